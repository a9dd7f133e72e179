//! The render entry point shared by the CLI, examples and tests: settings in, image out. The
//! session checks the settings every method shares, looks the method up and runs its render
//! function ([`crate::methods::Method::render`]) on a pool of `threads` threads.
//!
//! CONTRACT (kept stable for the CLI): `RenderSettings`, `IntegratorKind`, `Progress`,
//! `RenderOutput` and `render(scene, settings, progress, cancel)`.

use crate::shard::Shard;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use crate::error::RenderError;
use crate::image::Image;
use crate::methods::{MethodSettings, Run};
use crate::scene::Scene;

/// How long to render: defined in its own leaf module, shared with the drivers.
pub use crate::budget::Budget;
/// Which integrator renders the image, the settings and the output: defined with the methods.
pub use crate::methods::{
    ChainSettings, IntegratorKind, McmcStats, RenderOutput, RenderSettings,
    AUTO_LARGE_STEP_ESTIMATION,
};
/// Progress reports of a running render: mcmc-core's trait (one copy across the crates).
pub use mcmc_core::{NoProgress, Progress};

/// Edge length of PT's square tiles: defined with the PT driver.
pub use crate::integrator::pt_driver::TILE_SIZE;

/// Largest accepted image side.
pub const MAX_RESOLUTION: u32 = 1 << 16;

/// Largest accepted thread count.
pub const MAX_THREADS: usize = 1024;

/// Largest accepted path depth.
pub const MAX_DEPTH: u32 = 1 << 16;

/// Checks every setting against its allowed range: the common ones here, the method's own by
/// [`crate::methods::Method::validate`].
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
        Budget::SamplesPerPixel(0) => return Err(RenderError::setting("spp", 0, ">= 1")),
        Budget::Time(d) if d.is_zero() => {
            return Err(RenderError::setting(
                "time",
                format!("{}s", d.as_secs_f64()),
                "> 0 seconds",
            ))
        }
        _ => {}
    }
    settings.method.method().validate(settings)
}

/// Renders `scene` with `settings` on a pool of `settings.threads` rayon threads: validates
/// the settings and runs the method's render function ([`MethodSettings::method`]).
///
/// Under [`Budget::SamplesPerPixel`] the image is bit-identical for any thread count. Setting
/// `cancel` stops the render within a fraction of a second and returns the samples taken so
/// far, each pixel normalised by its own samples, with `cancelled: true`.
///
/// Before any work the render's peak memory is estimated
/// ([`crate::methods::memory::estimate`]) and a render that does not fit in the available
/// memory is refused.
///
/// # Errors
/// [`RenderError::InvalidSetting`] for out-of-range settings, [`RenderError::OutOfMemory`]
/// for a render estimated not to fit, [`RenderError::ThreadPool`] if the threads cannot be
/// started, and the method's own refusals (e.g. a scene it cannot render).
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<RenderOutput, RenderError> {
    render_shard(scene, settings, Shard::WHOLE, progress, cancel)
}

/// As [`render`], rendering only shard `shard.index` of `shard.count` of the method's fixed
/// work list ([`crate::shard`]): the output's [`RenderOutput::partial`] holds the shard's
/// accumulators, which add up with the other shards' (see [`crate::shard::Partial::add`]) to
/// exactly the accumulators of the whole render; its `image` is the shard's own (not a
/// useful picture by itself).
///
/// # Errors
/// As [`render`]; [`RenderError::InvalidSetting`] for a shard index not below the count.
pub fn render_shard(
    scene: &Scene,
    settings: &RenderSettings,
    shard: Shard,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<RenderOutput, RenderError> {
    let start = Instant::now();
    validate(settings)?;
    if shard.count == 0 || shard.index >= shard.count {
        return Err(RenderError::setting(
            "shard",
            format!("{}/{}", shard.index, shard.count),
            "K/N with 0 <= K < N",
        ));
    }
    crate::methods::memory::check(settings, scene)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| RenderError::ThreadPool {
            threads: settings.threads,
            reason: e.to_string(),
        })?;
    let method = settings.method.method();
    // BDPT and the MCMC targets use the scene's camera: set it to the image size.
    let mut sized;
    let scene = if !method.sized_camera()
        || (scene.camera().width(), scene.camera().height()) == (settings.width, settings.height)
    {
        scene
    } else {
        sized = scene.clone();
        sized.set_resolution(settings.width, settings.height);
        &sized
    };
    let run = Run {
        start,
        progress,
        cancel,
        shard,
    };
    pool.install(|| method.render(scene, settings, &run))
}

/// Renders the built-in Cornell box at `size x size` with `spp` samples per pixel on one
/// thread with PT: a convenience for examples and doc tests.
///
/// # Errors
/// As [`render`].
pub fn render_cornell_box(size: u32, spp: u32, seed: u64) -> Result<Image, RenderError> {
    let scene = Scene::cornell_box(size, size);
    let settings = RenderSettings {
        width: size,
        height: size,
        method: MethodSettings::default(),
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
    use std::sync::atomic::Ordering;
    use std::time::Duration;

    fn settings() -> RenderSettings {
        RenderSettings {
            width: 8,
            height: 8,
            budget: Budget::SamplesPerPixel(2),
            threads: 1,
            seed: 0,
            max_depth: 3,
            ..RenderSettings::default()
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
    fn cancel_mid_render_returns_the_partial_image() {
        let scene = Scene::cornell_box(48, 48);
        let mut s = settings();
        (s.width, s.height, s.threads) = (48, 48, 2);
        s.budget = Budget::SamplesPerPixel(64);
        let full = render(&scene, &s, &NoProgress, &AtomicBool::new(false)).unwrap();
        let flag = AtomicBool::new(false);
        let progress = crate::test_util::CancelAfter::new(&flag, 12);
        let out = render(&scene, &s, &progress, &flag).unwrap();
        assert!(out.cancelled);
        assert!(
            out.samples > 0 && out.samples < full.samples,
            "{}",
            out.samples
        );
        // Every pixel is normalised by its own samples: the partial image has the full
        // image's brightness where it was rendered (loosely: fewer samples, more noise).
        let lit = out.image.pixels.iter().filter(|p| p[0] > 0.0).count();
        assert!(lit > 0);
        let partial_mean: f64 = out
            .image
            .pixels
            .iter()
            .map(|p| f64::from(p[0]))
            .sum::<f64>()
            / lit as f64;
        let full_lit: Vec<f64> = full
            .image
            .pixels
            .iter()
            .zip(&out.image.pixels)
            .filter(|(_, q)| q[0] > 0.0)
            .map(|(p, _)| f64::from(p[0]))
            .collect();
        let full_mean = full_lit.iter().sum::<f64>() / full_lit.len() as f64;
        assert!(
            (partial_mean - full_mean).abs() < 0.25 * full_mean,
            "{partial_mean} vs {full_mean}"
        );
        assert_eq!(out.image.count_nonfinite(), 0);
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
