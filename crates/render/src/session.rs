//! The render entry point shared by the CLI, examples and tests: settings in, image out.
//!
//! CONTRACT (kept stable for the CLI): `RenderSettings`, `IntegratorKind`, `Progress`,
//! `RenderOutput` and `render(scene, settings, progress, cancel)`.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::image::Image;

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
