//! `drmlt`: delayed-rejection MLT (Rioux-Lavoie et al. 2020): a bold first stage and, after
//! its rejection, a timid second stage under the Tierney-Mira, Green-Mira or pairwise
//! orbital rule, over PSSMLT or MMLT ([`crate::mlt::dr`]); or cheap-then-expensive (section
//! 5.2) with MALA as the expensive stage.

use std::sync::atomic::AtomicBool;

use mcmc_core::render_loop::{ChainSlot, SplatPayload};
use mcmc_core::{Progress, Target};

use super::direct_pass::{self, DirectSettings};
use super::mala::mala_note;
use super::{
    bdpt_params, depth_note, emitter_notes, mcmc_output, remaining, ChainSettings, IntegratorKind,
    Method, RenderOutput, RenderSettings, Run,
};
use crate::bdpt::Roulette;
use crate::error::RenderError;
use crate::mlt::direct::DirectPass;
use crate::mlt::dr::{self, DrBase, DrVariant};
use crate::mlt::mala::{self, MalaConfig};
use crate::mlt::{
    self, MltDriver, MltEstimator, MltOutput, MltSettings, MmltTarget, PssmltTarget, PtTarget,
    PATH_STREAMS,
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
    /// The path sampler (default PSSMLT over BDPT; [`DrBase::PssmltPt`]: over the path
    /// tracer; cheap-then-expensive always runs on MMLT).
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
    /// A separate direct-lighting pass ([`crate::mlt::direct`], shared with `pssmlt`, `mmlt`
    /// and `mala*`): BDPT renders depths `0..=direct.depth`, the chains only the deeper
    /// ones (the authors' runs: `directSamples` 16). Default off. Not with
    /// cheap-then-expensive.
    pub direct: DirectSettings,
    /// On MMLT, keep the strategy along the chain in both stages (the paper's chain, section
    /// 5.1.2; large steps still draw it afresh): [`dr::lazy_orbital_kernel`]. Orbital rule
    /// only. Default off (the first stage then moves the strategy number too).
    pub fixed_strategy: bool,
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
            direct: DirectSettings::OFF,
            fixed_strategy: false,
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
        let direct_on = !matches!(self.direct.pass, DirectPass::Off | DirectPass::Fixed(0));
        if direct_on && self.variant == DrVariant::CheapThenExpensive {
            return Err(RenderError::setting(
                "direct-samples/direct-share",
                "a direct pass with --dr-variant cheap-then-expensive",
                "no direct pass for cheap-then-expensive (any for the other drmlt variants)",
            ));
        }
        if self.fixed_strategy && (self.variant != DrVariant::Orbital || self.on != DrBase::Mmlt) {
            return Err(RenderError::setting(
                "dr-fixed-strategy",
                "on without --dr-variant orbital --dr-on mmlt",
                "on only with the orbital rule on MMLT",
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
        let mut notes = emitter_notes(scene);
        notes.extend(depth_note(common));
        if self.variant != DrVariant::CheapThenExpensive {
            return self.render_two_stage(scene, common, run, notes);
        }
        let params = bdpt_params(common, self.roulette);
        let mlt_settings = self
            .chain
            .mlt_settings(common, PATH_STREAMS, true, run.shard);
        notes.push(format!(
            "delayed rejection: cheap-then-expensive (Gaussian sigma {} then MALA, Green-Mira) on MMLT{}; {}",
            self.mala.cheap_sigma,
            if self.on == DrBase::Mmlt { "" } else { " (it needs one strategy per sample: --dr-on is ignored)" },
            mala_note(&self.mala)
        ));
        let out = mala::render(
            scene,
            params,
            &self.mala,
            true,
            &mlt_settings,
            self.chain.small_step,
            run.progress,
            run.cancel,
        );
        Ok(mcmc_output(out, notes, run.start.elapsed()))
    }
}

impl DrmltSettings {
    /// The two-stage rules over PSSMLT (BDPT or the path tracer) or MMLT, after the direct
    /// pass if one is set.
    fn render_two_stage(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
        mut notes: Vec<String>,
    ) -> Result<RenderOutput, RenderError> {
        let params = bdpt_params(common, self.roulette);
        let (w, h) = (common.width, common.height);
        let (direct, direct_spent, min_depth) =
            self.direct.run(scene, &params, common, run, &mut notes);
        let mut mlt_settings = self
            .chain
            .mlt_settings(common, PATH_STREAMS, true, run.shard);
        if let Some(spent) = direct_spent {
            mlt_settings.budget = remaining(mlt_settings.budget, spent);
        }
        direct_pass::given_normalization(&mut mlt_settings, direct.as_ref(), &mut notes)?;
        notes.push(format!(
            "delayed rejection: {} second stage on {}{}",
            self.variant.name(),
            match self.on {
                DrBase::Pssmlt => "PSSMLT",
                DrBase::PssmltPt => "PSSMLT over the path tracer",
                DrBase::Mmlt if self.fixed_strategy => {
                    "MMLT (camera subpath only; strategy fixed along the chain)"
                }
                DrBase::Mmlt => "MMLT (camera subpath only)",
            },
            if self.large_step_mis {
                "; large-step MIS (Kelemen et al. 2002)"
            } else {
                ""
            }
        ));
        let rule = DrRun {
            variant: self.variant,
            base: self.on,
            max_depth: common.max_depth,
            first_depth: 0,
            fixed_strategy: self.fixed_strategy,
        };
        let settings = (&mlt_settings, self.large_step_mis);
        let out = match self.on {
            DrBase::Mmlt => {
                let targets = MmltTarget::depths_from(scene, params, w, h, min_depth);
                let rule = DrRun {
                    first_depth: min_depth,
                    ..rule
                };
                render_dr(&targets, rule, settings, run.progress, run.cancel)
            }
            DrBase::Pssmlt => {
                let targets = [PssmltTarget::new(scene, params, w, h).with_min_depth(min_depth)];
                render_dr(&targets, rule, settings, run.progress, run.cancel)
            }
            DrBase::PssmltPt => {
                let target = PtTarget::new(scene, w, h, common.max_depth, self.roulette.start);
                let targets = [target.with_min_depth(min_depth)];
                render_dr(&targets, rule, settings, run.progress, run.cancel)
            }
        };
        let chains_ran = out.mutations > 0;
        let mut output = mcmc_output(out, notes, run.start.elapsed());
        if let Some(d) = direct {
            direct_pass::merge_into(d, &mut output, common, run, chains_ran);
        }
        output.elapsed = run.start.elapsed();
        Ok(output)
    }
}

/// What [`render_dr`] runs: the rule, the path sampler, the maximum depth (the layouts) and
/// the depth of the first target (MMLT after a direct pass).
#[derive(Clone, Copy, Debug)]
struct DrRun {
    variant: DrVariant,
    base: DrBase,
    max_depth: u32,
    first_depth: u32,
    fixed_strategy: bool,
}

/// Delayed-rejection MLT over `targets` with the kernel of `variant` ([`crate::mlt::dr`]).
fn render_dr<T>(
    targets: &[T],
    DrRun {
        variant,
        base,
        max_depth,
        first_depth,
        fixed_strategy,
    }: DrRun,
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
                .first_depth(first_depth)
                .run(
                    mlt::PerChain(|slot: ChainSlot, p| {
                        let depth = first_depth + slot.target as u32;
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
            .first_depth(first_depth)
            .run(
                mlt::PerChain(|slot: ChainSlot, p| {
                    dr::lazy_orbital_kernel(
                        base,
                        p,
                        first_depth + slot.target as u32,
                        fixed_strategy,
                    )
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
