//! The render entry point shared by the CLI, examples and tests: settings in, image out.
//!
//! CONTRACT (kept stable for the CLI): `RenderSettings`, `IntegratorKind`, `Progress`,
//! `RenderOutput` and `render(scene, settings, progress, cancel)`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::UVec2;
use rayon::prelude::*;

use crate::error::RenderError;
use crate::film::{tiles, Film, FilmTile, Filter, PixelRect};
use crate::image::Image;
use crate::integrator::pt;
use crate::sampler::IndependentSampler;
use crate::scene::Scene;

/// Which light-transport algorithm renders the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum IntegratorKind {
    /// Unidirectional path tracing with next-event estimation and MIS.
    #[default]
    Pt,
}

/// How long to render: a sample count per pixel or a wall-clock budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Samples (or, for MCMC integrators, mutations) per pixel.
    SamplesPerPixel(u32),
    /// Wall-clock time; the image is not bit-reproducible under this budget.
    Time(Duration),
}

/// Everything a render needs besides the scene.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Image width in pixels (>= 1).
    pub width: u32,
    /// Image height in pixels (>= 1).
    pub height: u32,
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Sample or time budget.
    pub budget: Budget,
    /// Worker threads (>= 1). The image does not depend on it.
    pub threads: usize,
    /// Master seed; the same seed gives a bit-identical image under a sample budget.
    pub seed: u64,
    /// Maximum path depth (number of bounces).
    pub max_depth: u32,
}

/// Receives progress reports from a running render (e.g. an indicatif bar).
pub trait Progress: Sync {
    /// The total amount of work, in the unit of [`Progress::advance`], once it is known.
    fn set_total(&self, total: u64);
    /// `done` more units of work finished.
    fn advance(&self, done: u64);
}

/// A no-op [`Progress`].
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn set_total(&self, _total: u64) {}
    fn advance(&self, _done: u64) {}
}

/// The result of a render.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The rendered (possibly partial, if cancelled) image.
    pub image: Image,
    /// Number of samples (or mutations) evaluated.
    pub samples: u64,
    /// Samples whose radiance was NaN or infinite; they were dropped, not splatted.
    pub dropped_nonfinite: u64,
    /// True if the render stopped early because `cancel` was set.
    pub cancelled: bool,
    /// Wall-clock time spent.
    pub elapsed: Duration,
}

/// Edge length of the square tiles that are the work units of a render (and its merge order).
pub const TILE_SIZE: usize = 16;

/// Largest accepted image side.
pub const MAX_RESOLUTION: u32 = 1 << 16;

/// Largest accepted thread count.
pub const MAX_THREADS: usize = 1024;

/// Largest accepted path depth.
pub const MAX_DEPTH: u32 = 1 << 16;

/// Checks every setting against its allowed range.
///
/// # Errors
/// [`RenderError::InvalidSetting`] naming the first offending setting (by its CLI flag name)
/// and the allowed range.
pub fn validate(settings: &RenderSettings) -> Result<(), RenderError> {
    if !(1..=MAX_RESOLUTION).contains(&settings.width) {
        return Err(RenderError::setting("width", settings.width, "1..=65536"));
    }
    if !(1..=MAX_RESOLUTION).contains(&settings.height) {
        return Err(RenderError::setting("height", settings.height, "1..=65536"));
    }
    if u64::from(settings.width) * u64::from(settings.height) > 1 << 28 {
        return Err(RenderError::setting(
            "width",
            format!("{}x{}", settings.width, settings.height),
            "width * height <= 268435456 pixels",
        ));
    }
    if !(1..=MAX_THREADS).contains(&settings.threads) {
        return Err(RenderError::setting(
            "threads",
            settings.threads,
            "1..=1024",
        ));
    }
    if settings.max_depth > MAX_DEPTH {
        return Err(RenderError::setting(
            "max-depth",
            settings.max_depth,
            "0..=65536",
        ));
    }
    match settings.budget {
        Budget::SamplesPerPixel(0) => Err(RenderError::setting("spp", 0, ">= 1")),
        Budget::Time(d) if d.is_zero() => Err(RenderError::setting(
            "time",
            format!("{}s", d.as_secs_f64()),
            "> 0 seconds",
        )),
        _ => Ok(()),
    }
}

/// Renders `scene` with `settings`: the film is split into [`TILE_SIZE`] tiles (the work
/// units), rendered in passes by a pool of `settings.threads` rayon threads and merged in tile
/// order, with a box filter of one pixel. Every random number is keyed by (seed, pixel,
/// sample index, dimension), so under [`Budget::SamplesPerPixel`] the image is bit-identical
/// for any thread count.
///
/// * `SamplesPerPixel(n)`: passes of `ceil(n / 16)` samples per pixel (fewer in the last).
/// * `Time(d)`: passes of one sample per pixel until `d` has elapsed; after the first pass,
///   tiles not started before the deadline are skipped.
/// * `cancel` is checked before each tile; a cancelled render returns the samples merged so
///   far (each pixel normalised by its own filter weight) with `cancelled: true`.
///
/// Progress is reported in pixel samples.
///
/// # Errors
/// [`RenderError::InvalidSetting`] for out-of-range settings, [`RenderError::ThreadPool`] if
/// the threads cannot be started, [`RenderError::UnsupportedIntegrator`] for integrators this
/// function does not run.
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<RenderOutput, RenderError> {
    let start = Instant::now();
    validate(settings)?;
    #[allow(unreachable_patterns)]
    match settings.integrator {
        IntegratorKind::Pt => {}
        other => return Err(RenderError::UnsupportedIntegrator(format!("{other:?}"))),
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| RenderError::ThreadPool {
            threads: settings.threads,
            reason: e.to_string(),
        })?;
    let (w, h) = (settings.width, settings.height);
    let camera = scene.camera_spec().build(w, h);
    let mut film = Film::new(w as usize, h as usize, Filter::BOX);
    let work = tiles(w as usize, h as usize, TILE_SIZE);
    let pixels = u64::from(w) * u64::from(h);

    let render_tile = |rect: PixelRect, first: u32, count: u32| -> FilmTile {
        let mut tile = FilmTile::new(w as usize, h as usize, Filter::BOX, rect);
        let mut sampler = IndependentSampler::new(settings.seed);
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                let pixel_index = y as u64 * u64::from(w) + x as u64;
                for s in first..first + count {
                    sampler.start_pixel_sample(pixel_index, u64::from(s));
                    let (p, l) = pt::sample_pixel(
                        scene,
                        &camera,
                        UVec2::new(x as u32, y as u32),
                        &mut sampler,
                        settings.max_depth,
                    );
                    tile.add_sample(p, l);
                }
            }
        }
        progress.advance(rect.area() as u64 * u64::from(count));
        tile
    };

    let mut cancelled = false;
    match settings.budget {
        Budget::SamplesPerPixel(spp) => {
            progress.set_total(pixels * u64::from(spp));
            let per_pass = spp.div_ceil(16).max(1);
            let mut first = 0;
            while first < spp && !cancelled {
                let count = per_pass.min(spp - first);
                let done: Vec<Option<FilmTile>> = pool.install(|| {
                    work.par_iter()
                        .map(|&rect| {
                            (!cancel.load(Ordering::Relaxed))
                                .then(|| render_tile(rect, first, count))
                        })
                        .collect()
                });
                for tile in &done {
                    match tile {
                        Some(t) => film.merge_tile(t),
                        None => cancelled = true,
                    }
                }
                first += count;
            }
        }
        Budget::Time(limit) => {
            let deadline = start + limit;
            let mut pass = 0u32;
            loop {
                let done: Vec<Option<FilmTile>> = pool.install(|| {
                    work.par_iter()
                        .map(|&rect| {
                            let late = pass > 0 && Instant::now() >= deadline;
                            (!cancel.load(Ordering::Relaxed) && !late)
                                .then(|| render_tile(rect, pass, 1))
                        })
                        .collect()
                });
                for t in done.iter().flatten() {
                    film.merge_tile(t);
                }
                pass += 1;
                if cancel.load(Ordering::Relaxed) {
                    cancelled = true;
                    break;
                }
                let elapsed = start.elapsed();
                if elapsed >= limit {
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
    Ok(RenderOutput {
        image: film.image(0.0),
        samples: film.samples,
        dropped_nonfinite: film.nonfinite,
        cancelled,
        elapsed: start.elapsed(),
    })
}

/// Renders the built-in Cornell box at `size x size` with `spp` samples per pixel on one
/// thread: a convenience for examples and doc tests.
///
/// # Errors
/// As [`render`].
pub fn render_cornell_box(size: u32, spp: u32, seed: u64) -> Result<Image, RenderError> {
    let scene = Scene::cornell_box(size, size);
    let settings = RenderSettings {
        width: size,
        height: size,
        integrator: IntegratorKind::Pt,
        budget: Budget::SamplesPerPixel(spp),
        threads: 1,
        seed,
        max_depth: 5,
    };
    Ok(render(&scene, &settings, &NoProgress, &AtomicBool::new(false))?.image)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> RenderSettings {
        RenderSettings {
            width: 8,
            height: 8,
            integrator: IntegratorKind::Pt,
            budget: Budget::SamplesPerPixel(2),
            threads: 1,
            seed: 0,
            max_depth: 3,
        }
    }

    #[test]
    fn settings_are_validated() {
        let scene = Scene::cornell_box(8, 8);
        let no = AtomicBool::new(false);
        type Edit = fn(&mut RenderSettings);
        let cases: [(Edit, &str); 5] = [
            (|s| s.width = 0, "width"),
            (|s| s.height = 70_000, "height"),
            (|s| s.threads = 0, "threads"),
            (|s| s.budget = Budget::SamplesPerPixel(0), "spp"),
            (|s| s.budget = Budget::Time(Duration::ZERO), "time"),
        ];
        for (edit, field) in cases {
            let mut s = settings();
            edit(&mut s);
            let err = render(&scene, &s, &NoProgress, &no).unwrap_err();
            assert!(
                matches!(err, RenderError::InvalidSetting { field: f, .. } if f == field),
                "{err}"
            );
        }
    }

    #[test]
    fn cancelled_before_start_gives_black_cancelled_image() {
        let scene = Scene::cornell_box(8, 8);
        let out = render(&scene, &settings(), &NoProgress, &AtomicBool::new(true)).unwrap();
        assert!(out.cancelled);
        assert_eq!(out.samples, 0);
        assert_eq!(out.image.mean(), [0.0; 3]);
    }

    #[test]
    fn time_budget_renders_at_least_one_pass() {
        let scene = Scene::cornell_box(8, 8);
        let mut s = settings();
        s.budget = Budget::Time(Duration::from_millis(1));
        let out = render(&scene, &s, &NoProgress, &AtomicBool::new(false)).unwrap();
        assert!(out.samples >= 64);
        assert!(!out.cancelled);
    }

    #[test]
    fn progress_reaches_total() {
        use std::sync::atomic::AtomicU64;
        #[derive(Default)]
        struct Count(AtomicU64, AtomicU64);
        impl Progress for Count {
            fn set_total(&self, total: u64) {
                self.0.store(total, Ordering::Relaxed);
            }
            fn advance(&self, done: u64) {
                self.1.fetch_add(done, Ordering::Relaxed);
            }
        }
        let scene = Scene::cornell_box(20, 20);
        let mut s = settings();
        s.width = 20;
        s.height = 20;
        let c = Count::default();
        let out = render(&scene, &s, &c, &AtomicBool::new(false)).unwrap();
        assert_eq!(c.0.load(Ordering::Relaxed), 800);
        assert_eq!(c.1.load(Ordering::Relaxed), 800);
        assert_eq!(out.samples, 800);
    }
}
