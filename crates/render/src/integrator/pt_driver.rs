//! The path-tracing driver: a whole image rendered with [`pt::sample_pixel`] over fixed tiles,
//! in passes, merged in tile order, and cancellable between two samples of a tile.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::UVec2;
use mcmc_core::render_loop::Shard;
use mcmc_core::Progress;
use rayon::prelude::*;

use super::pt;
use crate::budget::Budget;
use crate::film::{tiles, Film, FilmTile, Filter, PixelRect};
use crate::image::Image;
use crate::sampler::{IndependentSampler, PixelSampler, Sampler, SamplerKind, SobolSampler};
use crate::scene::Scene;

/// Edge length of the square tiles that are the work units of a render (and its merge order).
pub const TILE_SIZE: usize = 16;

/// A [`Budget::SamplesPerPixel`] render of `n` samples takes passes of at most
/// `ceil(n / PASSES)` samples per pixel.
const PASSES: u32 = 16;

/// What [`render_pt`] needs besides the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PtDriverSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Maximum path depth (bounces).
    pub max_depth: u32,
    /// Samples per pixel, or a wall-clock budget.
    pub budget: Budget,
    /// Master seed of every random number.
    pub seed: u64,
    /// The per-pixel sampler of [`render_pt`] (the Halton integrators bring their own).
    pub sampler: SamplerKind,
    /// Russian roulette of [`render_pt`] and [`render_pixel_samples`] from this bounce on
    /// ([`pt::li_with`]); `None` turns it off. The usual value is [`pt::ROULETTE_DEPTH`]. (LQMC
    /// builds its paths itself and ignores it.)
    pub roulette: Option<u32>,
    /// The part of the fixed tile list to render ([`Shard::WHOLE`]: all of it): shard `k`
    /// of `n` renders the tiles `i` with `i * n / tiles == k` ([`crate::shard`]).
    pub shard: Shard,
}

/// The result of [`render_pt`].
#[derive(Clone, Debug)]
pub struct PtOutput {
    /// The image: every pixel is the mean of its own samples (0 where none was taken).
    pub image: Image,
    /// Pixel samples taken.
    pub samples: u64,
    /// Samples whose radiance was NaN or infinite; they were dropped, not averaged.
    pub dropped_nonfinite: u64,
    /// True if `cancel` stopped the render early.
    pub cancelled: bool,
    /// Pixels without any sample (black): a cancel or the time budget stopped the first pass
    /// before their tile ([`PassesOutcome::unsampled_pixels`]).
    pub unsampled_pixels: u64,
    /// The pixel-sample sums the image was made from (a shard's part of a render).
    pub film: Film,
}

/// Renders `scene` with unidirectional path tracing at `settings.width x settings.height`,
/// on the current rayon pool.
///
/// The film is split into [`TILE_SIZE`] tiles (the work units), rendered in passes and merged
/// in tile order, with a box filter of one pixel. `settings.sampler` picks independent numbers
/// or Owen-scrambled Sobol points per pixel. Every random number is keyed by (seed,
/// pixel, sample index, dimension) and a tile takes its samples in sample-index order, so
/// under [`Budget::SamplesPerPixel`] the image is bit-identical for any thread count.
///
/// * `SamplesPerPixel(n)`: passes that double from one sample per pixel up to `ceil(n / 16)`
///   (fewer in the last): every pixel soon has samples, and a pass never adds more than the
///   pixels already had, so tiles a cancelled pass did not reach have at least half the
///   samples of the others.
/// * `Time(d)`: passes of one sample per pixel until `d` has elapsed; tiles not started
///   before the deadline are skipped, in the first pass too (except its first tile): a huge
///   image stops on time and reports its unsampled pixels ([`PtOutput::unsampled_pixels`]).
/// * `cancel` is checked before every sample index of every tile (one sample of each of the
///   tile's pixels, milliseconds of work), so a cancelled render returns promptly at any
///   sample count, with every pixel normalised by its own samples: the partial image is an
///   unbiased average of the samples taken, not darkened by the samples planned.
///
/// Progress is reported in pixel samples.
pub fn render_pt(
    scene: &Scene,
    settings: &PtDriverSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> PtOutput {
    let seed = settings.seed;
    match settings.sampler {
        SamplerKind::Independent => render_pixel_samples(
            scene,
            settings,
            progress,
            cancel,
            || IndependentSampler::new(seed),
            |s, pixel, sample| s.start_pixel_sample(pixel, sample),
        ),
        SamplerKind::Sobol => render_pixel_samples(
            scene,
            settings,
            progress,
            cancel,
            || SobolSampler::new(seed),
            |s, pixel, sample| s.start_pixel_sample(pixel, sample),
        ),
    }
}

/// [`render_pt`] with any per-pixel sampler: `new_sampler()` makes one sampler per work unit
/// and `start(sampler, pixel_index, sample_index)` positions it before each pixel sample
/// (the Halton QMC integrator, [`crate::integrator::qmc`], runs through here). The image is
/// bit-identical for any thread count if `start` is a pure function of its keys.
pub fn render_pixel_samples<S, N, B>(
    scene: &Scene,
    settings: &PtDriverSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
    new_sampler: N,
    start: B,
) -> PtOutput
where
    S: Sampler,
    N: Fn() -> S + Sync,
    B: Fn(&mut S, u64, u64) + Sync,
{
    let (w, h) = (settings.width as usize, settings.height as usize);
    let camera = scene.camera_spec().build(settings.width, settings.height);
    let mut film = Film::new(w, h, Filter::BOX);

    // Samples `first..first + count` of every pixel of `rect`, sample index by sample index;
    // stops (returning false with the samples taken so far) when `cancel` is set.
    let render_tile = |rect: PixelRect, first: u32, count: u32| -> (FilmTile, bool) {
        let mut tile = FilmTile::new(w, h, Filter::BOX, rect);
        let mut sampler = new_sampler();
        for s in first..first + count {
            if cancel.load(Ordering::Relaxed) {
                return (tile, false);
            }
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    start(&mut sampler, (y * w + x) as u64, u64::from(s));
                    let (p, l) = pt::sample_pixel_with(
                        scene,
                        &camera,
                        UVec2::new(x as u32, y as u32),
                        &mut sampler,
                        settings.max_depth,
                        settings.roulette,
                    );
                    tile.add_sample(p, l);
                }
            }
            progress.advance(rect.area() as u64);
        }
        (tile, true)
    };
    let outcome = render_passes(
        settings.width,
        settings.height,
        settings.budget,
        settings.shard,
        progress,
        cancel,
        render_tile,
        |_, _, done| {
            for (tile, _) in done.iter().flatten() {
                film.merge_tile(tile);
            }
        },
    );
    let (image, overflowed) = film.image_checked(0.0);
    PtOutput {
        image,
        samples: film.samples,
        dropped_nonfinite: film.nonfinite + overflowed,
        cancelled: outcome.cancelled,
        unsampled_pixels: outcome.unsampled_pixels,
        film,
    }
}

/// How [`render_passes`] ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassesOutcome {
    /// True if `cancel` stopped the render.
    pub cancelled: bool,
    /// Pixels of this shard's tiles that never completed a pass: they have no sample
    /// (black). Nonzero only if a cancel or the time budget stopped the first pass.
    pub unsampled_pixels: u64,
}

/// The tiling, threading, pass, budget, progress and cancellation machinery of the PT driver,
/// for any per-tile work.
///
/// `render_tile(rect, first, count)` renders sample indices `first..first + count` of the
/// pixels of `rect` (a [`TILE_SIZE`] tile; tiles run in parallel on the current rayon pool)
/// and returns its result and whether it completed (false: it saw `cancel`).
/// `end_pass(first, count, results)` receives every tile's result of a pass, in tile order
/// (`None` for another shard's tile, or a tile not started because `cancel` was set or a
/// [`Budget::Time`] deadline had passed), so merging in that order gives the same bits for
/// any thread count. Passes are as in [`render_pt`]: doubling up to a sixteenth of a sample
/// budget, or one sample per pixel until the time budget is spent. The deadline is checked
/// before every tile, in the first pass too (whose first tile always runs), so a huge image
/// stops on time with part of it unsampled ([`PassesOutcome::unsampled_pixels`]). Progress
/// is in pixel samples; the tile reports its own progress.
#[allow(clippy::too_many_arguments)]
pub fn render_passes<R, F, M>(
    width: u32,
    height: u32,
    budget: Budget,
    shard: Shard,
    progress: &dyn Progress,
    cancel: &AtomicBool,
    render_tile: F,
    mut end_pass: M,
) -> PassesOutcome
where
    R: Send,
    F: Fn(PixelRect, u32, u32) -> (R, bool) + Sync,
    M: FnMut(u32, u32, Vec<Option<(R, bool)>>),
{
    let start = Instant::now();
    let (w, h) = (width as usize, height as usize);
    let all = tiles(w, h, TILE_SIZE);
    let units = all.len();
    // Another shard's tiles: `None` results, as tiles a time budget skipped.
    let mine: Vec<bool> = (0..units).map(|i| shard.owns(i, units)).collect();
    let work: Vec<(PixelRect, bool)> = all.into_iter().zip(mine).collect();
    let pixels = work
        .iter()
        .filter(|(_, mine)| *mine)
        .map(|(rect, _)| rect.area() as u64)
        .sum::<u64>();
    // The first pass always renders this shard's first tile.
    let first_tile = work.iter().position(|(_, mine)| *mine);
    let mut cancelled = false;
    // Per tile: has it completed a pass (so every pixel has a sample)?
    let mut sampled = vec![false; work.len()];
    // Records the tiles a pass completed; true if one of this shard's tiles did not complete.
    let mut record = |done: &[Option<(R, bool)>]| -> bool {
        let mut incomplete = false;
        for ((s, d), (_, mine)) in sampled.iter_mut().zip(done).zip(&work) {
            let complete = matches!(d, Some((_, true)));
            *s |= complete;
            incomplete |= *mine && !complete;
        }
        incomplete
    };
    match budget {
        Budget::SamplesPerPixel(spp) => {
            progress.set_total(pixels * u64::from(spp));
            for (first, count) in passes(spp) {
                let done: Vec<Option<(R, bool)>> = work
                    .par_iter()
                    .map(|&(rect, mine)| {
                        (mine && !cancel.load(Ordering::Relaxed))
                            .then(|| render_tile(rect, first, count))
                    })
                    .collect();
                cancelled |= record(&done);
                end_pass(first, count, done);
                if cancelled {
                    break;
                }
            }
        }
        Budget::Time(limit) => {
            let deadline = start + limit;
            let mut pass = 0u32;
            loop {
                let done: Vec<Option<(R, bool)>> = work
                    .par_iter()
                    .enumerate()
                    .map(|(i, &(rect, mine))| {
                        let free = pass == 0 && Some(i) == first_tile;
                        let late = !free && Instant::now() >= deadline;
                        (mine && !late && !cancel.load(Ordering::Relaxed))
                            .then(|| render_tile(rect, pass, 1))
                    })
                    .collect();
                record(&done);
                cancelled |= done.iter().flatten().any(|(_, complete)| !complete);
                end_pass(pass, 1, done);
                pass += 1;
                cancelled |= cancel.load(Ordering::Relaxed);
                let elapsed = start.elapsed();
                if cancelled || elapsed >= limit {
                    break;
                }
                // Estimated total work so a progress bar can show an ETA.
                let passes = (limit.as_secs_f64() / elapsed.as_secs_f64() * f64::from(pass))
                    .ceil()
                    .max(f64::from(pass + 1));
                progress.set_total(pixels * passes as u64);
            }
        }
    }
    let unsampled_pixels = work
        .iter()
        .zip(&sampled)
        .filter(|((_, mine), &s)| *mine && !s)
        .map(|((rect, _), _)| rect.area() as u64)
        .sum();
    PassesOutcome {
        cancelled,
        unsampled_pixels,
    }
}

/// The passes `(first sample index, samples per pixel)` of a render of `spp` samples per
/// pixel: sizes double from 1 up to `ceil(spp / PASSES)`, so a pass never adds more samples
/// than the pixels already have (after the first).
fn passes(spp: u32) -> impl Iterator<Item = (u32, u32)> {
    let max_pass = spp.div_ceil(PASSES).max(1);
    let mut first = 0u32;
    std::iter::from_fn(move || {
        if first >= spp {
            return None;
        }
        let count = max_pass.min(first.max(1)).min(spp - first);
        let pass = (first, count);
        first += count;
        Some(pass)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::CancelAfter;

    fn settings(spp: u32) -> PtDriverSettings {
        PtDriverSettings {
            width: 32,
            height: 16,
            max_depth: 3,
            budget: Budget::SamplesPerPixel(spp),
            seed: 1,
            sampler: SamplerKind::Independent,
            roulette: Some(pt::ROULETTE_DEPTH),
            shard: Shard::WHOLE,
        }
    }

    #[test]
    fn cancel_stops_between_two_samples_of_a_tile() {
        let scene = Scene::cornell_box(32, 16);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let flag = AtomicBool::new(false);
        // One report per sample index of a 16 x 16 tile: the flag is set after the 5th.
        let progress = CancelAfter::new(&flag, 5);
        let out = pool.install(|| render_pt(&scene, &settings(1_000_000), &progress, &flag));
        assert!(out.cancelled);
        assert_eq!(out.samples, 5 * 256);
        assert_eq!(out.image.count_nonfinite(), 0);
    }

    #[test]
    fn passes_double_up_to_a_sixteenth_of_the_budget() {
        let sizes: Vec<u32> = passes(100).map(|(_, count)| count).collect();
        assert_eq!(sizes[..5], [1, 1, 2, 4, 7]);
        assert!(sizes[4..sizes.len() - 1].iter().all(|&c| c == 7));
        assert_eq!(sizes.iter().sum::<u32>(), 100);
        let mut next = 0;
        for (first, count) in passes(1_000_000) {
            assert_eq!(first, next);
            assert!(count <= first.max(1) && count <= 62_500);
            next += count;
        }
        assert_eq!(next, 1_000_000);
        assert_eq!(passes(16).count(), 16);
        assert_eq!(passes(1).collect::<Vec<_>>(), [(0, 1)]);
    }

    #[test]
    fn a_deadline_inside_the_first_pass_leaves_counted_unsampled_pixels() {
        // 64 x 32: eight tiles. The deadline has passed when the render starts: only the
        // first tile (which always runs) is sampled.
        let scene = Scene::cornell_box(64, 32);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let mut s = settings(1);
        (s.width, s.height) = (64, 32);
        s.budget = Budget::Time(std::time::Duration::from_nanos(1));
        let no = AtomicBool::new(false);
        let out = pool.install(|| render_pt(&scene, &s, &mcmc_core::NoProgress, &no));
        assert!(!out.cancelled);
        assert_eq!(out.samples, 256);
        assert_eq!(out.unsampled_pixels, 64 * 32 - 256);
        // Control: a sample budget reaches every pixel.
        s.budget = Budget::SamplesPerPixel(1);
        let out = pool.install(|| render_pt(&scene, &s, &mcmc_core::NoProgress, &no));
        assert_eq!((out.samples, out.unsampled_pixels), (64 * 32, 0));
    }
}
