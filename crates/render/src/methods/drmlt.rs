//! `drmlt`: delayed-rejection MLT (Rioux-Lavoie et al. 2020): a bold first stage and, after
//! its rejection, a timid second stage under the Tierney-Mira, Green-Mira or pairwise
//! orbital rule, over PSSMLT or MMLT ([`crate::mlt::dr`]); or cheap-then-expensive (section
//! 5.2) with MALA as the expensive stage.

use std::sync::atomic::AtomicBool;

use mcmc_core::render_loop::{ChainSlot, SplatPayload};
use mcmc_core::{Progress, Target};

use super::mala::mala_note;
use super::{
    bdpt_params, depth_note, emitter_notes, mcmc_output, ChainSettings, IntegratorKind, Method,
    RenderOutput, RenderSettings, Run,
};
use crate::bdpt::Roulette;
use crate::error::RenderError;
use crate::mlt::dr::{self, DrBase, DrVariant};
use crate::mlt::mala::{self, MalaConfig};
use crate::mlt::{
    self, MltDriver, MltEstimator, MltOutput, MltSettings, MmltTarget, PssmltTarget, PATH_STREAMS,
};
use crate::scene::Scene;

/// `drmlt`'s settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrmltSettings {
    /// Chains, bootstrap, large steps (and the small step of the Kelemen chains of
    /// cheap-then-expensive beyond MALA's depth).
    pub chain: ChainSettings,
    /// The second-stage rule (default the pairwise orbital rule, the paper's recommendation).
    pub variant: DrVariant,
    /// The path sampler (default PSSMLT; cheap-then-expensive always runs on MMLT).
    pub on: DrBase,
    /// Cheap-then-expensive: the MALA stage's parameters, depth rule and gradient.
    pub mala: MalaConfig,
    /// Russian roulette of the BDPT subpaths on PSSMLT (default from 3 bounces on).
    pub roulette: Roulette,
    /// Combine the large-step samples with the two-stage estimator by multiple importance
    /// sampling (Kelemen et al. 2002, section 4; [`MltEstimator::large_step_mis`]; the
    /// weights of `mcmc_core::render_loop::LargeStepMis`, unbiased for delayed rejection's
    /// splats). Default off, as in the authors' DRMLT (expected-value weights only). Not
    /// with cheap-then-expensive.
    pub large_step_mis: bool,
}

impl Default for DrmltSettings {
    fn default() -> Self {
        Self::rioux_lavoie2020()
    }
}

impl DrmltSettings {
    /// Rioux-Lavoie et al. 2020 as this crate implements it: the pairwise orbital rule
    /// (section 4.3, eq. 11; the paper's recommendation) on PSSMLT over BDPT (section 5.1.1),
    /// large steps with probability 0.3 and 100 000 bootstrap samples (the authors' pLarge
    /// and luminanceSamples), pairwise Kelemen first stage (docs/methods/drmlt.md lists where
    /// the authors' kernels differ).
    #[must_use]
    pub const fn rioux_lavoie2020() -> Self {
        Self::rioux_lavoie2020_with(DrVariant::Orbital, DrBase::Pssmlt)
    }

    /// [`DrmltSettings::rioux_lavoie2020`] with another rule and path sampler (the paper's
    /// Fig. 7 compares the rules on both samplers).
    #[must_use]
    pub const fn rioux_lavoie2020_with(variant: DrVariant, on: DrBase) -> Self {
        Self {
            chain: ChainSettings::kelemen2002(),
            variant,
            on,
            mala: super::MalaSettings::luan2020().config,
            roulette: Roulette { start: Some(3) },
            large_step_mis: false,
        }
    }
}

impl Method for DrmltSettings {
    fn kind(&self) -> IntegratorKind {
        IntegratorKind::Drmlt
    }

    fn validate(&self, _common: &RenderSettings) -> Result<(), RenderError> {
        if self.large_step_mis && self.variant == DrVariant::CheapThenExpensive {
            return Err(RenderError::setting(
                "large-step-mis",
                "on with --dr-variant cheap-then-expensive",
                "off for cheap-then-expensive (on for the other drmlt variants)",
            ));
        }
        self.chain.validate()
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let params = bdpt_params(common, self.roulette);
        let (w, h) = (common.width, common.height);
        let mut notes = emitter_notes(scene);
        notes.extend(depth_note(common));
        let mlt_settings = self
            .chain
            .mlt_settings(common, PATH_STREAMS, true, run.shard);
        let out = if self.variant == DrVariant::CheapThenExpensive {
            notes.push(format!(
                "delayed rejection: cheap-then-expensive (Gaussian sigma {} then MALA, Green-Mira) on MMLT{}; {}",
                self.mala.cheap_sigma,
                if self.on == DrBase::Pssmlt { " (it needs one strategy per sample: --dr-on pssmlt is ignored)" } else { "" },
                mala_note(&self.mala)
            ));
            mala::render(
                scene,
                params,
                &self.mala,
                true,
                &mlt_settings,
                self.chain.small_step,
                run.progress,
                run.cancel,
            )
        } else {
            let max_depth = common.max_depth;
            notes.push(format!(
                "delayed rejection: {} second stage on {}{}",
                self.variant.name(),
                match self.on {
                    DrBase::Pssmlt => "PSSMLT",
                    DrBase::Mmlt => "MMLT (camera subpath only)",
                },
                if self.large_step_mis {
                    "; large-step MIS (Kelemen et al. 2002)"
                } else {
                    ""
                }
            ));
            match self.on {
                DrBase::Mmlt => {
                    let targets = MmltTarget::all_depths(scene, params, w, h);
                    render_dr(
                        &targets,
                        self.variant,
                        max_depth,
                        self.on,
                        (&mlt_settings, self.large_step_mis),
                        run.progress,
                        run.cancel,
                    )
                }
                DrBase::Pssmlt => {
                    let targets = [PssmltTarget::new(scene, params, w, h)];
                    render_dr(
                        &targets,
                        self.variant,
                        max_depth,
                        self.on,
                        (&mlt_settings, self.large_step_mis),
                        run.progress,
                        run.cancel,
                    )
                }
            }
        };
        Ok(mcmc_output(out, notes, run.start.elapsed()))
    }
}

/// Delayed-rejection MLT over `targets` with the kernel of `variant` ([`crate::mlt::dr`]).
fn render_dr<T>(
    targets: &[T],
    variant: DrVariant,
    max_depth: u32,
    base: DrBase,
    (mlt_settings, large_step_mis): (&MltSettings, bool),
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target<State = pss::PssState>,
    T::Payload: SplatPayload,
{
    let estimator = MltEstimator {
        large_step_mis,
        ..MltEstimator::plain()
    };
    // Each rule's kernel is its own type: one driver call per rule.
    macro_rules! run_rule {
        ($kernel:path) => {
            MltDriver::new(targets, mlt_settings)
                .estimator(estimator)
                .run(
                    mlt::PerChain(|slot: ChainSlot, p| {
                        let depth = slot.target as u32;
                        let layout = dr::chain_layout(base, max_depth, depth);
                        $kernel(layout, base, p, depth)
                    }),
                    progress,
                    cancel,
                )
        };
    }
    match variant {
        DrVariant::Orbital => MltDriver::new(targets, mlt_settings)
            .estimator(estimator)
            .run(
                mlt::PerChain(|slot: ChainSlot, p| {
                    dr::lazy_orbital_kernel(base, p, slot.target as u32)
                }),
                progress,
                cancel,
            ),
        DrVariant::TierneyMira => run_rule!(dr::tierney_mira_kernel),
        DrVariant::GreenMira => run_rule!(dr::green_mira_kernel),
        DrVariant::TierneyMiraPairwise => run_rule!(dr::pairwise_tierney_mira_kernel),
        DrVariant::GreenMiraPairwise => run_rule!(dr::pairwise_green_mira_kernel),
        DrVariant::CheapThenExpensive => {
            unreachable!("cheap-then-expensive runs through the Langevin driver")
        }
    }
}
