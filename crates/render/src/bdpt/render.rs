//! The BDPT driver: a whole image rendered with independent BDPT samples in fixed row bands,
//! with light-tracing splats and optional per-strategy images, cancellable between two pixel
//! samples.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::{UVec2, Vec2, Vec3};
use mcmc_core::render_loop::{ExactSplatGrid, Shard};
use mcmc_core::Progress;
use rayon::prelude::*;

use super::{sample, BdptParams, BdptScratch, SceneRef, StrategySplat, MAX_VERTICES};
use crate::film::{exact_splat_grid, pixel_sample_position, Film, FilmTile, Filter, PixelRect};
use crate::image::Image;
use crate::sampler::{IndependentSampler, PixelSampler, Sampler, SamplerKind, SobolSampler};
use crate::shard::Component;

/// Number of fixed row bands (work units): the image does not depend on the thread count.
const BANDS: usize = 8;

/// The result of a BDPT render.
#[derive(Clone, Debug)]
pub struct BdptOutput {
    /// The image.
    pub image: Image,
    /// Complete passes: samples per pixel that every pixel received.
    pub spp: u32,
    /// Camera samples taken (pixel samples; more than `spp` per pixel if a pass was cut short).
    pub samples: u64,
    /// Non-finite contributions dropped.
    pub dropped: u64,
    /// True if cancelled early.
    pub cancelled: bool,
    /// Pixels without a camera sample (only light-tracing splats reach them): a cancel or
    /// the time budget stopped the first pass before their row.
    pub unsampled_pixels: u64,
    /// MIS-weighted image of each strategy `(s, t)` (only if requested); they sum to `image`.
    pub strategy_images: Vec<((u8, u8), Image)>,
    /// A shard's accumulators ([`render_bdpt_shard`]; `None` for the whole image).
    pub component: Option<Component>,
}

/// The strategies `(s, t)` that can contribute at a maximum depth, split by where their
/// contributions land: camera-side strategies (`t >= 2`) in the sampled pixel, light tracing
/// (`t = 1`) anywhere on the image.
struct Strategies {
    /// `s * stride + t` indexes `slot`.
    stride: usize,
    /// The strategy's index in `camera` or `light` (by `t`), `usize::MAX` if it cannot occur.
    slot: Vec<usize>,
    camera: Vec<(u8, u8)>,
    light: Vec<(u8, u8)>,
}

impl Strategies {
    fn new(max_depth: u32) -> Self {
        let depth = (max_depth as usize).min(MAX_VERTICES - 2);
        let stride = depth + 3;
        let mut slot = vec![usize::MAX; stride * stride];
        let (mut camera, mut light) = (Vec::new(), Vec::new());
        for s in 0..stride {
            for t in 1..stride {
                if (s == 1 && t == 1) || s + t < 2 || s + t - 2 > depth {
                    continue;
                }
                let list = if t == 1 { &mut light } else { &mut camera };
                slot[s * stride + t] = list.len();
                list.push((s as u8, t as u8));
            }
        }
        Self {
            stride,
            slot,
            camera,
            light,
        }
    }

    fn slot(&self, s: u8, t: u8) -> usize {
        self.slot[s as usize * self.stride + t as usize]
    }
}

/// The strategies `(s, t)` whose images [`render_bdpt`] returns with `strategy_images` at
/// maximum depth `max_depth` (camera-side strategies first, then light tracing): what a caller
/// writing them can check up front.
#[must_use]
pub fn strategy_list(max_depth: u32) -> Vec<(u8, u8)> {
    let strategies = Strategies::new(max_depth);
    strategies
        .camera
        .into_iter()
        .chain(strategies.light)
        .collect()
}

/// What one band accumulates. Camera-side contributions of a sample are summed and added as
/// one pixel sample (the pixel's mean over its own samples); light-tracing splats are summed
/// over the whole image and scaled by pixels / samples at the end (pbrt-v3's splat scale).
struct Band<'g> {
    rows: std::ops::Range<usize>,
    camera: FilmTile,
    /// The light-tracing splats of every band: one shared exact grid (sums independent of
    /// the order of the splats, so of the thread count).
    light: &'g ExactSplatGrid,
    /// Per camera-side strategy (only with strategy images).
    strategy_camera: Vec<FilmTile>,
    /// Per light-tracing strategy (only with strategy images), shared like `light`.
    strategy_light: &'g [ExactSplatGrid],
    /// The current sample's contribution of each camera-side strategy.
    strategy_sums: Vec<Vec3>,
    samples: u64,
    dropped: u64,
    scratch: BdptScratch,
}

/// The per-pass inputs every band shares.
struct Pass<'a> {
    scene: SceneRef<'a>,
    params: &'a BdptParams,
    strategies: &'a Strategies,
    seed: u64,
    sampler: SamplerKind,
    index: u32,
    /// Rows not started by then are skipped (time budgets; in the first pass every row but
    /// `free_row`).
    deadline: Option<Instant>,
    /// The first row of the shard's first band: the first pass always renders it.
    free_row: Option<usize>,
    progress: &'a dyn Progress,
    cancel: &'a AtomicBool,
}

impl Band<'_> {
    /// Takes sample `pass.index` of every pixel of the band in row-major order; returns false
    /// if `cancel` (checked before every pixel) or the deadline (before every row) stopped it.
    fn render(&mut self, pass: &Pass<'_>) -> bool {
        match pass.sampler {
            SamplerKind::Independent => self.render_with(pass, IndependentSampler::new(pass.seed)),
            SamplerKind::Sobol => self.render_with(pass, SobolSampler::new(pass.seed)),
        }
    }

    /// [`Band::render`] with `sampler`.
    fn render_with<S: PixelSampler>(&mut self, pass: &Pass<'_>, mut sampler: S) -> bool {
        let w = self.light.width();
        for y in self.rows.clone() {
            let first = pass.index == 0 && Some(y) == pass.free_row;
            if !first && pass.deadline.is_some_and(|d| Instant::now() >= d) {
                return false;
            }
            for x in 0..w {
                if pass.cancel.load(Ordering::Relaxed) {
                    pass.progress.advance(x as u64);
                    return false;
                }
                sampler.start_pixel_sample((y * w + x) as u64, u64::from(pass.index));
                let pixel = UVec2::new(x as u32, y as u32);
                let p_raster = pixel_sample_position(pixel, sampler.next_2d());
                self.sample(pass, &mut sampler, p_raster);
            }
            pass.progress.advance(w as u64);
        }
        true
    }

    /// One BDPT sample through `p_raster`.
    fn sample<S: Sampler>(&mut self, pass: &Pass<'_>, sampler: &mut S, p_raster: Vec2) {
        let Band {
            camera,
            light,
            strategy_camera,
            strategy_light,
            strategy_sums,
            samples,
            dropped,
            scratch,
            ..
        } = self;
        let per_strategy = !strategy_sums.is_empty();
        strategy_sums.fill(Vec3::ZERO);
        let mut l_camera = Vec3::ZERO;
        let sink = |sp: StrategySplat| {
            let slot = || pass.strategies.slot(sp.s, sp.t);
            if !sp.l.is_finite() {
                *dropped += 1;
            } else if sp.t == 1 {
                let (raster, rgb) = (sp.p_raster.to_array(), sp.l.to_array());
                if !light.add_rgb(raster, rgb, 1.0) {
                    *dropped += 1;
                } else if per_strategy {
                    strategy_light[slot()].add_rgb(raster, rgb, 1.0);
                }
            } else {
                l_camera += sp.l;
                if per_strategy {
                    strategy_sums[slot()] += sp.l;
                }
            }
        };
        sample(
            pass.scene,
            sampler,
            p_raster,
            pass.params,
            true,
            scratch,
            sink,
        );
        camera.add_sample(p_raster, l_camera);
        for (tile, &l) in strategy_camera.iter_mut().zip(strategy_sums.iter()) {
            tile.add_sample(p_raster, l);
        }
        *samples += 1;
    }
}

/// Renders `scene` with BDPT at its camera's resolution: `spp` samples per pixel (or until
/// `time` has passed, or until cancelled if neither is given), in passes of one sample per
/// pixel over fixed row bands. `seed` keys every random number by (pixel, sample index), so
/// the image is independent of the thread count.
///
/// Camera-side contributions (`t >= 2`) are box-filtered into the sampled pixel and every
/// pixel is the mean over its own samples; light-tracing contributions (`t = 1`) land where
/// they project and are scaled by pixels / camera samples (pbrt-v3's splat normalisation, one
/// light subpath per camera sample). Both are unbiased for any per-pixel sample counts, so
/// the image stays a correct average when a pass is cut short: `cancel` is checked before
/// every pixel sample (a cancelled render returns within a fraction of a second at any
/// `spp`), and under a time budget rows not started by the deadline are skipped, in the
/// first pass too (all but the image's first row), so a huge image stops on time with the
/// pixels it did not reach counted in [`BdptOutput::unsampled_pixels`]. Progress is reported
/// in pixel samples.
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
    render_bdpt_sampled(
        scene,
        params,
        SamplerKind::Independent,
        spp,
        time,
        seed,
        strategy_images,
        progress,
        cancel,
    )
}

/// [`render_bdpt`] drawing every pixel sample's numbers from the per-pixel sampler `sampler`
/// (e.g. [`SamplerKind::Sobol`]: the camera, light and connection streams of a pixel's
/// samples are each stratified draw by draw; light-tracing splats land anywhere, and stay
/// unbiased because every sample is uniform on its own).
#[allow(clippy::too_many_arguments)]
pub fn render_bdpt_sampled(
    scene: SceneRef<'_>,
    params: &BdptParams,
    sampler: SamplerKind,
    spp: Option<u32>,
    time: Option<Duration>,
    seed: u64,
    strategy_images: bool,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> BdptOutput {
    render_bdpt_shard(
        scene,
        params,
        sampler,
        (spp, time),
        seed,
        strategy_images,
        Shard::WHOLE,
        progress,
        cancel,
    )
}

/// [`render_bdpt_sampled`] rendering only the row bands of shard `shard` (`budget` is
/// `(spp, time)`); the output's [`BdptOutput::component`] holds the shard's accumulators when
/// the shard is not the whole image ([`crate::shard`]).
#[allow(clippy::too_many_arguments)]
pub fn render_bdpt_shard(
    scene: SceneRef<'_>,
    params: &BdptParams,
    sampler: SamplerKind,
    budget: (Option<u32>, Option<Duration>),
    seed: u64,
    strategy_images: bool,
    shard: Shard,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> BdptOutput {
    let (spp, time) = budget;
    let start = Instant::now();
    let (w, h) = (
        scene.camera().width() as usize,
        scene.camera().height() as usize,
    );
    let strategies = Strategies::new(params.max_depth);
    let bound = scene.lights().emission_bound();
    let light_grid = exact_splat_grid(w, h, bound);
    let n_light = if strategy_images {
        strategies.light.len()
    } else {
        0
    };
    let strategy_light_grids: Vec<ExactSplatGrid> = (0..n_light)
        .map(|_| exact_splat_grid(w, h, bound))
        .collect();
    let mut bands: Vec<Band> = (0..BANDS)
        .map(|b| {
            let rows = (b * h / BANDS)..((b + 1) * h / BANDS);
            let rect = PixelRect {
                x0: 0,
                y0: rows.start,
                x1: w,
                y1: rows.end,
            };
            let tile = || FilmTile::new(w, h, Filter::BOX, rect);
            let n_camera = if strategy_images {
                strategies.camera.len()
            } else {
                0
            };
            Band {
                rows,
                camera: tile(),
                light: &light_grid,
                strategy_camera: (0..n_camera).map(|_| tile()).collect(),
                strategy_light: &strategy_light_grids,
                strategy_sums: vec![Vec3::ZERO; n_camera],
                samples: 0,
                dropped: 0,
                scratch: BdptScratch::default(),
            }
        })
        .collect();
    let total_spp = spp.unwrap_or(u32::MAX);
    if let Some(n) = spp {
        progress.set_total(u64::from(n) * (w * h) as u64);
    }
    let owned = |i: usize| shard.owns(i, BANDS);
    let free_row = (0..BANDS).find(|&i| owned(i)).map(|i| i * h / BANDS);
    let mut done = 0u32;
    let mut stopped = false;
    while done < total_spp && !stopped {
        let pass = Pass {
            scene,
            params,
            strategies: &strategies,
            seed,
            sampler,
            index: done,
            deadline: time.map(|t| start + t),
            free_row,
            progress,
            cancel,
        };
        if done > 0 && pass.deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        let complete: Vec<bool> = bands
            .par_iter_mut()
            .enumerate()
            .map(|(i, b)| !shard.owns(i, BANDS) || b.render(&pass))
            .collect();
        stopped = complete.contains(&false) || cancel.load(Ordering::Relaxed);
        if complete.iter().all(|&c| c) {
            done += 1;
        }
    }
    let cancelled = cancel.load(Ordering::Relaxed) && done < total_spp;

    let samples: u64 = bands.iter().map(|b| b.samples).sum();
    // An incomplete first pass took at most one sample per pixel of the shard's bands: the
    // others have none.
    let unsampled_pixels = if done == 0 {
        let shard_pixels: usize = bands
            .iter()
            .enumerate()
            .filter(|&(i, _)| owned(i))
            .map(|(_, b)| b.rows.len() * w)
            .sum();
        (shard_pixels as u64).saturating_sub(samples)
    } else {
        0
    };
    let light_scale = if samples == 0 {
        0.0
    } else {
        (w * h) as f64 / samples as f64
    };
    let tiles = bands.iter().map(|b| &b.camera);
    let (image, overflowed) = merge_layers(w, h, light_scale, tiles, Some(&light_grid));
    let component = (!shard.is_whole()).then(|| {
        let mut film = Film::new(w, h, Filter::BOX);
        for band in &bands {
            film.merge_tile(&band.camera);
        }
        let (sum, weight) = film.sums();
        Component::Film {
            sum: sum.to_vec(),
            weight: weight.to_vec(),
            light: Some(light_grid.clone()),
            light_samples: samples,
        }
    });
    let strategy_images = if strategy_images {
        let camera = strategies.camera.iter().enumerate().map(|(i, &st)| {
            let tiles = bands.iter().map(|b| &b.strategy_camera[i]);
            (st, merge_layers(w, h, light_scale, tiles, None).0)
        });
        let light = strategies.light.iter().enumerate().map(|(i, &st)| {
            let tiles = std::iter::empty();
            let grid = Some(&strategy_light_grids[i]);
            (st, merge_layers(w, h, light_scale, tiles, grid).0)
        });
        let mut all: Vec<((u8, u8), Image)> = camera
            .chain(light)
            .filter(|(_, img)| img.pixels.iter().any(|p| p.iter().any(|&c| c != 0.0)))
            .collect();
        all.sort_by_key(|&(st, _)| st);
        all
    } else {
        Vec::new()
    };
    BdptOutput {
        image,
        spp: done,
        samples,
        dropped: bands.iter().map(|b| b.dropped).sum::<u64>() + overflowed,
        cancelled,
        unsampled_pixels,
        strategy_images,
        component,
    }
}

/// The image of the bands' camera tiles, merged in band order (the mean of the pixel
/// samples), plus `light_scale` times the shared light grid's sums; with the number of pixels
/// dropped because they overflow f32 ([`Film::image_checked`]).
fn merge_layers<'a>(
    w: usize,
    h: usize,
    light_scale: f64,
    tiles: impl Iterator<Item = &'a FilmTile>,
    light: Option<&ExactSplatGrid>,
) -> (Image, u64) {
    let mut film = Film::new(w, h, Filter::BOX);
    for tile in tiles {
        film.merge_tile(tile);
    }
    if let Some(grid) = light {
        film.merge_exact_splats(grid);
    }
    film.image_checked(light_scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::test_util::CancelAfter;

    #[test]
    fn cancel_stops_within_a_pass() {
        let scene = Scene::cornell_box(16, 16);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let flag = AtomicBool::new(false);
        // One report per band row; a pass is 16 rows: stop after the 4th row of the second.
        let progress = CancelAfter::new(&flag, 20);
        let params = BdptParams::default();
        let out = pool.install(|| {
            render_bdpt(
                &scene,
                &params,
                Some(1_000_000),
                None,
                3,
                false,
                &progress,
                &flag,
            )
        });
        assert!(out.cancelled);
        assert_eq!(out.spp, 1);
        assert_eq!(out.samples, 20 * 16);
        assert_eq!(out.image.count_nonfinite(), 0);
    }

    #[test]
    fn strategy_images_sum_to_the_image_after_a_cut_pass() {
        let scene = Scene::cornell_box(16, 16);
        let flag = AtomicBool::new(false);
        let progress = CancelAfter::new(&flag, 40);
        let params = BdptParams {
            max_depth: 3,
            ..BdptParams::default()
        };
        let out = render_bdpt(&scene, &params, Some(1000), None, 5, true, &progress, &flag);
        assert!(out.cancelled && out.samples > 16 * 16 * 2 && out.samples < 16 * 16 * 3);
        assert!(out.strategy_images.iter().any(|((_, t), _)| *t == 1));
        assert!(out.strategy_images.iter().any(|((_, t), _)| *t >= 2));
        for (i, px) in out.image.pixels.iter().enumerate() {
            for (c, &value) in px.iter().enumerate() {
                let sum: f32 = out
                    .strategy_images
                    .iter()
                    .map(|(_, img)| img.pixels[i][c])
                    .sum();
                assert!(
                    (sum - value).abs() <= 1e-4 * value.abs().max(1.0),
                    "pixel {i}: {sum} vs {value}"
                );
            }
        }
    }

    #[test]
    fn a_deadline_inside_the_first_pass_leaves_counted_unsampled_pixels() {
        // The deadline has passed when the render starts: only the image's first row (which
        // always runs) gets camera samples.
        let scene = Scene::cornell_box(16, 16);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let params = BdptParams::default();
        let no = AtomicBool::new(false);
        let render = |spp, time| {
            pool.install(|| {
                render_bdpt(
                    &scene,
                    &params,
                    spp,
                    time,
                    3,
                    false,
                    &mcmc_core::NoProgress,
                    &no,
                )
            })
        };
        let out = render(None, Some(Duration::from_nanos(1)));
        assert!(!out.cancelled);
        assert_eq!((out.spp, out.samples), (0, 16));
        assert_eq!(out.unsampled_pixels, 16 * 16 - 16);
        // Control: a sample budget reaches every pixel.
        let out = render(Some(1), None);
        assert_eq!((out.samples, out.unsampled_pixels), (256, 0));
    }
}
