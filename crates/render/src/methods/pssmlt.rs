//! `pssmlt`: primary-sample-space MLT over BDPT (Kelemen et al. 2002): every strategy of a
//! BDPT sample weighted by MIS is one path contribution, the chains move the primary sample
//! vector with Kelemen's small steps and independent large steps.

use super::direct_pass::{self, DirectRun};
use std::sync::atomic::Ordering;

use super::{
    bdpt_params, depth_note, emitter_notes, mcmc_output, relative_error, remaining, unsampled_note,
    ChainSettings, IntegratorKind, Method, PssKernel, RenderOutput, RenderSettings, Run, Unsampled,
};
use crate::bdpt::{BdptParams, Roulette};
use crate::error::RenderError;
use crate::mlt::direct::{self, DirectPass};
use crate::mlt::{MltDriver, MltEstimator, PssmltTarget, PATH_STREAMS};
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use mcmc_core::render_loop::{ChainAllocation, NormalizationMode};
use pss::RasterParams;

/// `pssmlt`'s settings. [`Default`] is the command line's default: the measured improvements
/// on the paper's method (large-step MIS, raster steps, a balanced direct-lighting pass over
/// Sobol points); the presets are the papers' methods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PssmltSettings {
    /// Chains, bootstrap, large and small steps.
    pub chain: ChainSettings,
    /// Combine the large-step samples with the Metropolis estimator by multiple importance
    /// sampling (Kelemen et al. 2002, section 4; [`MltEstimator::large_step_mis`]). Default
    /// on (docs/methods/large-step-mis.md).
    pub large_step_mis: bool,
    /// Raster (image-plane) mutation: with probability `raster.probability` a small step
    /// moves only the two raster numbers ([`pss::RasterStep`]; LuxCore's image mutation read
    /// as a separate move). Default: in half the small steps
    /// ([`pss::RASTER_DEFAULT_PROBABILITY`]).
    pub raster: RasterParams,
    /// A separate direct-lighting pass ([`crate::mlt::direct`]): BDPT renders depths
    /// `0..=direct_depth`, the chains the deeper ones. Default
    /// [`DirectPass::PSSMLT_DEFAULT`] (a share of the budget balanced against the chains).
    pub direct: DirectPass,
    /// The direct pass's depth `K` (at least 1; no pass if `K` >= the maximum depth).
    /// Default [`direct::DIRECT_DEPTH_DEFAULT`].
    pub direct_depth: u32,
    /// The direct pass's per-pixel sampler (default Owen-scrambled Sobol points).
    pub sampler: SamplerKind,
    /// Russian roulette of the BDPT subpaths (default from 3 bounces on).
    pub roulette: Roulette,
}

impl Default for PssmltSettings {
    fn default() -> Self {
        Self {
            chain: ChainSettings::kelemen2002(),
            large_step_mis: true,
            raster: RasterParams::with_probability(pss::RASTER_DEFAULT_PROBABILITY),
            direct: DirectPass::PSSMLT_DEFAULT,
            direct_depth: direct::DIRECT_DEPTH_DEFAULT,
            sampler: SamplerKind::Sobol,
            roulette: BdptParams::default().roulette,
        }
    }
}

impl PssmltSettings {
    /// Kelemen et al. 2002 with the expected-value estimator (eq. 5 with the rejected and
    /// accepted candidates weighted by `1 - a` and `a`, section 3's mutations: small steps
    /// with s1 = 1/1024, s2 = 1/64, large steps with probability 0.3), no raster steps and no
    /// direct pass: the base PSSMLT every paper example compares against.
    #[must_use]
    pub const fn kelemen2002() -> Self {
        Self {
            chain: ChainSettings::kelemen2002(),
            large_step_mis: false,
            raster: RasterParams::off(),
            direct: DirectPass::Off,
            direct_depth: direct::DIRECT_DEPTH_DEFAULT,
            sampler: SamplerKind::Independent,
            roulette: Roulette { start: Some(3) },
        }
    }

    /// [`PssmltSettings::kelemen2002`] with its large steps also weighted as independent
    /// samples by multiple importance sampling (Kelemen et al. 2002, section 4; LuxRender's
    /// and LuxCore's Metropolis samplers run this estimator).
    #[must_use]
    pub const fn kelemen2002_mis() -> Self {
        Self {
            large_step_mis: true,
            ..Self::kelemen2002()
        }
    }

    /// Automatic large-step control (Zsolnai & Szirmay-Kalos 2013, section 2) on
    /// [`PssmltSettings::kelemen2002`]: every chain runs 1000 mutations at probability 0.5,
    /// the pooled `eta_s`, `eta_l`, `eta_0` give `p_l = eta_s / (2 (eta_s - eta_l))` (0.25 if
    /// `eta_l / eta_0 <= 0.1`), fixed for the rest of the render.
    #[must_use]
    pub const fn zsolnai2013() -> Self {
        Self {
            chain: ChainSettings::kelemen2002().with_auto_large_step(0.5),
            ..Self::kelemen2002()
        }
    }

    /// [`PssmltSettings::zsolnai2013`] inside LuxRender's Metropolis estimator, where the
    /// paper's measurements ran: large steps weighted by Kelemen's MIS
    /// ([`PssmltSettings::kelemen2002_mis`]).
    #[must_use]
    pub const fn zsolnai2013_luxrender() -> Self {
        Self {
            large_step_mis: true,
            ..Self::zsolnai2013()
        }
    }

    /// The direct pass's depth as used (at least 1).
    #[must_use]
    pub const fn pass_depth(&self) -> u32 {
        if self.direct_depth == 0 {
            1
        } else {
            self.direct_depth
        }
    }
}

impl Method for PssmltSettings {
    fn kind(&self) -> IntegratorKind {
        IntegratorKind::Pssmlt
    }

    fn validate(&self, _common: &RenderSettings) -> Result<(), RenderError> {
        self.chain.validate()
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let params = bdpt_params(common, self.roulette);
        let mut notes = emitter_notes(scene);
        notes.extend(depth_note(common));
        let kernel = PssKernel::new(
            self.chain.small_step,
            &self.raster,
            common.width,
            common.height,
        );
        // The separate direct-lighting pass, rendered first; under a time budget the chains
        // get what is left.
        let pass_depth = self.pass_depth();
        let mut direct: Option<DirectRun> = direct_pass::run(
            scene,
            &params,
            common,
            self.direct,
            pass_depth,
            self.sampler,
            run,
            &mut notes,
        );
        let spent = direct.as_ref().map(|d| d.elapsed);
        // A pass whose share of a time budget did not reach every pixel (a huge image) would
        // leave those pixels without their direct light: drop it, the chains take every depth.
        if let Some(d) = direct
            .as_ref()
            .filter(|d| d.pass.unsampled_pixels > 0 && !d.pass.cancelled)
        {
            let pixels = u64::from(common.width) * u64::from(common.height);
            notes.push(format!(
                "the direct-lighting pass reached only {:.1} % of the pixels in its share of the time budget: it is dropped and the chains render every depth",
                100.0 * (pixels - d.pass.unsampled_pixels.min(pixels)) as f64 / pixels as f64
            ));
            direct = None;
        }
        let min_depth = if direct.is_some() {
            self.direct.chain_min_depth(common.max_depth, pass_depth)
        } else {
            0
        };
        let mut mlt_settings = self
            .chain
            .mlt_settings(common, PATH_STREAMS, false, run.shard);
        if let Some(spent) = spent {
            mlt_settings.budget = remaining(mlt_settings.budget, spent);
        }
        // A given `b` is the whole image's mean luminance: the chains render what the direct
        // pass does not.
        if let (NormalizationMode::Given(b), Some(d)) = (mlt_settings.normalization, &direct) {
            let pass = d.pass.image.mean_luminance();
            if b - pass <= 0.0 || pass.is_nan() {
                return Err(RenderError::setting(
                    "normalization",
                    b,
                    "above the direct-lighting pass's mean luminance (the chains render the rest of the light)",
                ));
            }
            notes.push(format!(
                "normalisation given: b = {b:.6} for the image, {:.6} for the chains after the direct pass's {pass:.6}",
                b - pass
            ));
            mlt_settings.normalization = NormalizationMode::Given(b - pass);
        }
        let estimator = MltEstimator {
            large_step_mis: self.large_step_mis,
            chain_allocation: ChainAllocation::Joint,
            strategy_strata: false,
        };
        push_estimator_notes(&mut notes, self.large_step_mis, &kernel, &self.raster);
        let targets = [
            PssmltTarget::new(scene, params, common.width, common.height).with_min_depth(min_depth),
        ];
        let out = MltDriver::new(&targets, &mlt_settings)
            .estimator(estimator)
            .run(|p: f64| kernel.with_large_step(p), run.progress, run.cancel);
        let chains_ran = out.mutations > 0;
        let mut output = mcmc_output(out, notes, run.start.elapsed());
        if let Some(d) = direct {
            let depths = format!("path depths 0-{pass_depth}");
            if output.mcmc.as_ref().is_some_and(|m| m.found_nothing) {
                output.notes.push(format!(
                    "the bootstrap found no light on deeper paths: the direct-lighting pass ({depths}) is the whole image"
                ));
            } else if !chains_ran {
                output.notes.push(format!(
                    "{} before the chains ran: the image holds only the direct-lighting pass ({depths}); the light of deeper paths is missing",
                    if output.cancelled || run.cancel.load(Ordering::Relaxed) {
                        "cancelled"
                    } else {
                        "stopped"
                    }
                ));
            }
            output.notes.extend(unsampled_note(
                d.pass.unsampled_pixels,
                u64::from(common.width) * u64::from(common.height),
                d.pass.cancelled,
                Unsampled::CameraSamples,
            ));
            output.unsampled_pixels = d.pass.unsampled_pixels;
            direct::add_into(&mut output.image, &d.pass.image);
            if let (Some(partial), Some(c)) = (output.partial.as_mut(), d.pass.component) {
                partial.components.push(c);
            }
            output.dropped_nonfinite += d.pass.dropped;
            output.cancelled |= d.pass.cancelled;
            if let Some(stats) = output.mcmc.as_mut() {
                stats.direct_pass = Some(d.stats);
                // The pass's light is not scaled by `b`: the brightness error is relative to
                // the whole image.
                stats.brightness_standard_error = relative_error(
                    stats.b_standard_error,
                    stats.b + d.pass.image.mean_luminance(),
                );
                stats.times.direct_pass = d.elapsed;
            }
        }
        output.elapsed = run.start.elapsed();
        Ok(output)
    }
}

/// The notes on the large-step MIS estimator and the raster mutation (PSSMLT and MMLT).
pub(super) fn push_estimator_notes(
    notes: &mut Vec<String>,
    large_step_mis: bool,
    kernel: &PssKernel,
    raster: &RasterParams,
) {
    if large_step_mis {
        notes.push(
            "large-step MIS (Kelemen et al. 2002, section 4): large steps also weighted as independent samples"
                .to_owned(),
        );
    }
    if kernel.raster_probability() > 0.0 {
        notes.push(format!(
            "raster mutation: {} of the small steps move only the raster position ({} px to {} of the image; LuxCore's image mutation)",
            kernel.raster_probability(),
            raster.min_pixels,
            raster.max_fraction
        ));
    }
}
