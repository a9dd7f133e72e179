//! The Halton QMC path tracer (`--integrator qmc`): the "Halton points" baseline of Tessari
//! et al. (Fig. 1, 7, 10): the path tracer of [`crate::integrator::pt`] driven by
//! per-pixel Cranley-Patterson-rotated Halton points instead of independent numbers.

use std::sync::atomic::AtomicBool;

use lqmc::Scrambling;
use mcmc_core::Progress;

use super::halton_sampler::HaltonSampler;
use super::pt_driver::{render_pixel_samples, PtDriverSettings, PtOutput};
use crate::scene::Scene;

/// Renders `scene` with Halton QMC path tracing: the PT driver ([`render_pixel_samples`]:
/// tiles, passes, budgets, progress, cancellation) with a [`HaltonSampler`]. Sample `i` of
/// a pixel is point `i` of the pixel's scrambled Halton sequence, so under a sample budget
/// the image is bit-identical for any thread count; the rotation keeps it unbiased.
pub fn render_qmc(
    scene: &Scene,
    settings: &PtDriverSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> PtOutput {
    render_qmc_with(scene, settings, Scrambling::None, progress, cancel)
}

/// [`render_qmc`] over a Halton sequence with digit scrambling `scrambling` (`--integrator
/// qmc-faure`: [`Scrambling::Faure`]). Plain Halton points of a pixel cluster in every
/// dimension whose prime base exceeds the pixel's sample count (`i / b` for `i < b` covers
/// `[0, n / b)`, and the rotation only moves that arc); Faure's permutations spread the
/// leading digit over the whole interval while keeping every stratification property.
pub fn render_qmc_with(
    scene: &Scene,
    settings: &PtDriverSettings,
    scrambling: Scrambling,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> PtOutput {
    let seed = settings.seed;
    render_pixel_samples(
        scene,
        settings,
        progress,
        cancel,
        || HaltonSampler::with_scrambling(seed, scrambling),
        HaltonSampler::start_pixel_sample,
    )
}
