//! The Halton QMC path tracer (`--integrator qmc`): the "Halton points" baseline of Tessari
//! et al. (Fig. 1, 7, 10): the path tracer of [`crate::integrator::pt`] driven by
//! per-pixel Cranley-Patterson-rotated Halton points instead of independent numbers.

use std::sync::atomic::AtomicBool;

use mcmc_core::Progress;

use super::halton_sampler::HaltonSampler;
use super::pt_driver::{render_pixel_samples, PtOutput, PtSettings};
use crate::scene::Scene;

/// Renders `scene` with Halton QMC path tracing: the PT driver ([`render_pixel_samples`]:
/// tiles, passes, budgets, progress, cancellation) with a [`HaltonSampler`]. Sample `i` of
/// a pixel is point `i` of the pixel's scrambled Halton sequence, so under a sample budget
/// the image is bit-identical for any thread count; the rotation keeps it unbiased.
pub fn render_qmc(
    scene: &Scene,
    settings: &PtSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> PtOutput {
    let seed = settings.seed;
    render_pixel_samples(
        scene,
        settings,
        progress,
        cancel,
        || HaltonSampler::new(seed),
        HaltonSampler::start_pixel_sample,
    )
}
