//! Independent BDPT rendering of a whole image: fixed row bands, counter-based samples,
//! light-tracing splats, optional per-strategy images.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::Vec2;
use rayon::prelude::*;

use super::{sample, BdptParams, BdptScratch, SceneRef};
use crate::image::Image;
use crate::mlt::SplatBuffer;
use crate::sampler::IndependentSampler;
use crate::session::Progress;

/// Number of fixed row bands (work units): the image does not depend on the thread count.
const BANDS: usize = 8;

/// The result of a BDPT render.
#[derive(Clone, Debug)]
pub struct BdptOutput {
    /// The image.
    pub image: Image,
    /// Samples per pixel actually rendered.
    pub spp: u32,
    /// Non-finite contributions dropped.
    pub dropped: u64,
    /// True if cancelled early.
    pub cancelled: bool,
    /// MIS-weighted image of each strategy `(s, t)` (only if requested); they sum to `image`.
    pub strategy_images: Vec<((u8, u8), Image)>,
}

struct Band {
    rows: std::ops::Range<usize>,
    buffer: SplatBuffer,
    strategies: Vec<SplatBuffer>,
    dropped: u64,
    scratch: BdptScratch,
}

/// Renders `scene` with BDPT at its camera's resolution: `spp` samples per pixel (or until
/// `time` has passed, in passes of one sample per pixel), `seed` keys every random number by
/// (pixel, sample index), so the image is independent of the thread count. Every contribution
/// (light tracing included) is box-filtered into the pixel it lands in and the sum is divided
/// by the number of samples per pixel (pbrt-v3's splat normalisation).
#[allow(clippy::too_many_arguments)]
pub fn render_bdpt(
    scene: SceneRef<'_>,
    params: &BdptParams,
    spp: Option<u32>,
    time: Option<Duration>,
    seed: u64,
    strategy_images: bool,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> BdptOutput {
    let (w, h) = (
        scene.camera().width() as usize,
        scene.camera().height() as usize,
    );
    let n_strategies = (params.max_depth as usize + 3) * (params.max_depth as usize + 3);
    let mut bands: Vec<Band> = (0..BANDS)
        .map(|b| Band {
            rows: (b * h / BANDS)..((b + 1) * h / BANDS),
            buffer: SplatBuffer::new(w, h),
            strategies: if strategy_images {
                vec![SplatBuffer::new(w, h); n_strategies]
            } else {
                Vec::new()
            },
            dropped: 0,
            scratch: BdptScratch::default(),
        })
        .collect();
    let total_spp = spp.unwrap_or(u32::MAX);
    if let Some(n) = spp {
        progress.set_total(u64::from(n) * (w * h) as u64);
    }
    let start = Instant::now();
    let mut done = 0u32;
    let mut cancelled = false;
    let stride = params.max_depth as usize + 3;
    while done < total_spp {
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        if time.is_some_and(|t| start.elapsed() >= t) {
            break;
        }
        let pass = done;
        bands.par_iter_mut().for_each(|band| {
            let mut sampler = IndependentSampler::new(seed);
            let Band {
                rows,
                buffer,
                strategies,
                dropped,
                scratch,
            } = band;
            for y in rows.clone() {
                for x in 0..w {
                    let pixel = (y * w + x) as u64;
                    sampler.start_pixel_sample(pixel, u64::from(pass));
                    let jitter = crate::sampler::Sampler::next_2d(&mut sampler);
                    let p_raster = Vec2::new(x as f32, y as f32) + jitter;
                    sample(scene, &mut sampler, p_raster, params, true, scratch, |sp| {
                        let rgb = sp.l.to_array();
                        if !buffer.add(sp.p_raster.to_array(), rgb, 1.0) {
                            *dropped += 1;
                        } else if !strategies.is_empty() {
                            strategies[sp.s as usize * stride + sp.t as usize].add(
                                sp.p_raster.to_array(),
                                rgb,
                                1.0,
                            );
                        }
                    });
                }
                progress.advance(w as u64);
            }
        });
        done += 1;
    }
    let mut total = SplatBuffer::new(w, h);
    let mut per_strategy =
        vec![SplatBuffer::new(w, h); if strategy_images { n_strategies } else { 0 }];
    let mut dropped = 0;
    for band in &bands {
        total.merge(&band.buffer);
        dropped += band.dropped;
        for (acc, b) in per_strategy.iter_mut().zip(&band.strategies) {
            acc.merge(b);
        }
    }
    let scale = if done == 0 {
        0.0
    } else {
        1.0 / f64::from(done)
    };
    let strategy_images = per_strategy
        .iter()
        .enumerate()
        .filter(|(i, _)| (i / stride) + (i % stride) >= 2 && i % stride >= 1)
        .map(|(i, b)| (((i / stride) as u8, (i % stride) as u8), b.to_image(scale)))
        .filter(|(_, img)| img.pixels.iter().any(|p| p.iter().any(|&c| c != 0.0)))
        .collect();
    BdptOutput {
        image: total.to_image(scale),
        spp: done,
        dropped,
        cancelled,
        strategy_images,
    }
}
