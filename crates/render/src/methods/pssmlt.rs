//! `pssmlt` and `pssmlt-pt`: primary-sample-space MLT (Kelemen et al. 2002) over BDPT (every
//! strategy of a BDPT sample weighted by MIS is one path contribution) or over the
//! unidirectional path tracer with next-event estimation; the chains move the primary sample
//! vector with Kelemen's small steps and independent large steps.

use super::direct_pass::{self, DirectRun};

use super::{
    bdpt_params, depth_note, emitter_notes, mcmc_output, remaining, ChainSettings, IntegratorKind,
    Method, PssKernel, RenderOutput, RenderSettings, Run,
};
use crate::bdpt::{BdptParams, Roulette};
use crate::error::RenderError;
use crate::mlt::direct::{self, DirectPass};
use crate::mlt::{
    LargeStepMode, MltDriver, MltEstimator, MltSettings, PssmltTarget, PtTarget, PATH_STREAMS,
};
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use mcmc_core::render_loop::ChainAllocation;
use pss::{RasterParams, SmallMutation};

/// Large-step probability of [`PssmltSettings::corona13_kmlt`] (corona-13 `kmlt.c`).
pub const CORONA13_LARGE_STEP: f64 = 0.2;
/// Half-width of [`PssmltSettings::corona13_kmlt`]'s uniform small step (corona-13's
/// direction mutation amount).
pub const CORONA13_SMALL_STEP: f64 = 0.01;
/// Bootstrap samples of [`PssmltSettings::corona13_kmlt`] (corona-13 estimates `b` over the
/// first 2^20 large steps).
pub const CORONA13_BOOTSTRAP: usize = 1 << 20;

/// The path sampler PSSMLT's chains run on: what one primary sample vector means.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathBase {
    /// BDPT, every strategy weighted by MIS ([`PssmltTarget`]; the `pssmlt` integrator).
    #[default]
    Bdpt,
    /// The unidirectional path tracer with next-event estimation ([`PtTarget`]; the
    /// `pssmlt-pt` integrator).
    Pt,
}

/// `pssmlt`'s and `pssmlt-pt`'s settings. [`Default`] is `pssmlt`'s command-line default: the
/// measured improvements on the paper's method (large-step MIS, raster steps, a balanced
/// direct-lighting pass over Sobol points); the presets are the papers' methods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PssmltSettings {
    /// The path sampler the chains run on (default BDPT; [`PathBase::Pt`] is `pssmlt-pt`).
    pub base: PathBase,
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
            base: PathBase::Bdpt,
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
            base: PathBase::Bdpt,
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

    /// The KMLT baseline of Tessari et al. 2020 as their renderer runs it (corona-13,
    /// `kmlt.c`), over the path tracer with next-event estimation ([`PathBase::Pt`], the
    /// unidirectional sampler LQMC's seeds come from): large steps with probability 0.2, the
    /// expected-value estimator (no large-step MIS), a uniform box small step
    /// `x + 0.01 (2u - 1)` on every coordinate (corona's amount for BSDF directions, which are
    /// most of a path's numbers; corona moves the image by 0.005 and light numbers by 0.005 and
    /// 0.001, one amount per kind of number, which [`PtTarget`]'s flat vector does not tell
    /// apart), `b` from 2^20 independent samples (corona: a running mean over the first 2^20
    /// large steps of each thread), no raster steps, no direct pass and no Russian roulette
    /// (LQMC's tracer has none; corona keeps the roulette numbers of a path fixed). Corona's
    /// forced accept after 40 000 rejections is not reproduced.
    #[must_use]
    pub const fn corona13_kmlt() -> Self {
        Self {
            base: PathBase::Pt,
            chain: ChainSettings {
                large_step: LargeStepMode::Fixed(CORONA13_LARGE_STEP),
                small_step: SmallMutation::Uniform {
                    amount: CORONA13_SMALL_STEP,
                },
                bootstrap_samples: CORONA13_BOOTSTRAP,
                ..ChainSettings::kelemen2002()
            },
            large_step_mis: false,
            raster: RasterParams::off(),
            direct: DirectPass::Off,
            direct_depth: direct::DIRECT_DEPTH_DEFAULT,
            sampler: SamplerKind::Independent,
            roulette: Roulette { start: None },
        }
    }

    /// These settings over `base`.
    #[must_use]
    pub const fn on(self, base: PathBase) -> Self {
        Self { base, ..self }
    }

    /// `pssmlt-pt`'s command-line default: [`Default`] over the path tracer.
    #[must_use]
    pub fn path_traced() -> Self {
        Self::default().on(PathBase::Pt)
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
        match self.base {
            PathBase::Bdpt => IntegratorKind::Pssmlt,
            PathBase::Pt => IntegratorKind::PssmltPt,
        }
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
        let direct: Option<DirectRun> = direct_pass::run(
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
        let direct = direct_pass::usable(direct, common, &mut notes);
        let min_depth =
            direct_pass::chain_min_depth(direct.as_ref(), self.direct, common, pass_depth);
        let mut mlt_settings = self
            .chain
            .mlt_settings(common, PATH_STREAMS, false, run.shard);
        if let Some(spent) = spent {
            mlt_settings.budget = remaining(mlt_settings.budget, spent);
        }
        direct_pass::given_normalization(&mut mlt_settings, direct.as_ref(), &mut notes)?;
        let estimator = MltEstimator {
            large_step_mis: self.large_step_mis,
            chain_allocation: ChainAllocation::Joint,
            strategy_strata: false,
        };
        push_estimator_notes(&mut notes, self.large_step_mis, &kernel, &self.raster);
        let (w, h) = (common.width, common.height);
        let out = match self.base {
            PathBase::Bdpt => run_chains(
                &[PssmltTarget::new(scene, params, w, h).with_min_depth(min_depth)],
                &mlt_settings,
                estimator,
                &kernel,
                run,
            ),
            PathBase::Pt => run_chains(
                &[
                    PtTarget::new(scene, w, h, common.max_depth, self.roulette.start)
                        .with_min_depth(min_depth),
                ],
                &mlt_settings,
                estimator,
                &kernel,
                run,
            ),
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

/// The chains of `targets` with `kernel` at the driver's large-step probability.
fn run_chains<T>(
    targets: &[T],
    settings: &MltSettings,
    estimator: MltEstimator,
    kernel: &PssKernel,
    run: &Run<'_>,
) -> crate::mlt::MltOutput
where
    T: mcmc_core::Target<State = pss::PssState, Payload = crate::mlt::PathPayload> + Sync,
{
    MltDriver::new(targets, settings).estimator(estimator).run(
        |p: f64| kernel.with_large_step(p),
        run.progress,
        run.cancel,
    )
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
