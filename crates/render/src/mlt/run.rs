//! The settings and the output of an MCMC render over mcmc-core's generic render loop, and
//! how the loop's sink becomes an image; the driver that runs it is [`super::MltDriver`].

use std::time::Duration;

use mcmc_core::controller::LargeStepEstimate;
use mcmc_core::render_loop::{ChainAllocation, ChainSlot, LoopOutput, NormalizationMode, Shard};
use mcmc_core::stats::AcceptanceStats;

use super::StagedSplats;
use crate::image::Image;
use crate::shard::Component;

/// How the large-step probability is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LargeStepMode {
    /// A fixed probability in `[0, 1]`.
    Fixed(f64),
    /// Automatic control (Zsolnai & Szirmay-Kalos 2013): every chain first runs an
    /// estimation phase with `initial` large-step probability, of `estimation_steps`
    /// mutations capped at a tenth of its budget (time budgets: at
    /// [`super::TIME_BUDGET_ESTIMATION_STEPS`], with the chains capped so that the loop plans
    /// ten times that per chain; `mlt::estimation`); `eta_s`, `eta_l`, `eta_0` are pooled over
    /// all chains (`mcmc_core::controller::AutoLargeStep::pooled`) and `p_l` is set for the
    /// rest of the render (finite adaptation: the kernel is fixed afterwards).
    Auto {
        /// Large-step probability during the estimation phase.
        initial: f64,
        /// Mutations per chain requested for the estimation phase (capped as above).
        estimation_steps: u64,
    },
    /// A warm-up schedule (the Langevin MLT authors' code, `largestepprob` and
    /// `largestepscale`): `initial` for the first tenth of every chain's mutations, then
    /// `then` (`mcmc_core::controller::LargeStepSchedule`; how long the warm-up is under a
    /// time budget: `mlt::estimation::set_up_warm_up`). Not adaptive: the switch depends only
    /// on the chain's step count.
    Schedule {
        /// Large-step probability during the warm-up.
        initial: f64,
        /// Large-step probability after it.
        then: f64,
    },
}

/// Budget of an MCMC render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MltBudget {
    /// Mutations per pixel (deterministic output).
    MutationsPerPixel(f64),
    /// Wall-clock time, bootstrap included (output depends on speed).
    Time(Duration),
}

/// Settings of an MCMC render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MltSettings {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// Number of Markov chains (default 256).
    pub chains: usize,
    /// Independent samples per target in the bootstrap (default 100 000, pbrt's value).
    pub bootstrap_samples: usize,
    /// Budget.
    pub budget: MltBudget,
    /// Large-step probability.
    pub large_step: LargeStepMode,
    /// Master seed.
    pub seed: u64,
    /// Number of PSS streams the target reads (1..=4).
    pub streams: usize,
    /// Also accumulate the delayed-rejection stage map ([`MltOutput::stage_map`]): one more
    /// splat layer per job (only meaningful with a two-stage kernel).
    pub stage_map: bool,
    /// The part of the fixed chain-job list to render ([`Shard::WHOLE`]: all of it); a
    /// sharded run returns its accumulators in [`MltOutput::component`] ([`crate::shard`]).
    pub shard: Shard,
    /// How the image's normalisation `b` is estimated (default [`NormalizationMode::Pooled`]:
    /// the bootstrap with every large-step candidate of the chains,
    /// `mcmc_core::render_loop::Normalization`), or the caller's `b`
    /// ([`NormalizationMode::Given`]: the chains' image then has that mean luminance; it
    /// also overrides the sum of [`super::MltDriver::normalized`]'s per-target values, which
    /// still allocate the chains).
    pub normalization: NormalizationMode,
}

/// What an MCMC render produced.
#[derive(Clone, Debug)]
pub struct MltOutput {
    /// The image (black if nothing carried light).
    pub image: Image,
    /// The normalisation `b` the image is scaled with: by default the bootstrap pooled with
    /// every large-step candidate (`mcmc_core::render_loop::Normalization`), or the one given.
    pub b: f64,
    /// Standard error of `b` (0 for a given `b`).
    pub b_standard_error: f64,
    /// The bootstrap's own estimate of `b` (or the sum of a per-target normalisation given).
    pub bootstrap_b: f64,
    /// The bootstrap's standard error.
    pub bootstrap_standard_error: f64,
    /// Large-step candidates pooled into `b`.
    pub large_step_samples: u64,
    /// True if `b` was given ([`MltSettings::normalization`] or
    /// [`super::MltDriver::normalized`]) rather than estimated.
    pub normalization_given: bool,
    /// Bootstrap samples evaluated.
    pub bootstrap_samples: u64,
    /// The bootstrap estimate `b_d` of each target (MMLT: depth); they sum to `b`.
    pub target_b: Vec<f64>,
    /// Chains started per target (MMLT: depth).
    pub target_chains: Vec<usize>,
    /// Mutations performed (all chains).
    pub mutations: u64,
    /// Acceptance statistics pooled over chains.
    pub stats: AcceptanceStats,
    /// The automatic large-step estimate, if automatic control ran (its
    /// [`LargeStepEstimate::steps`] are the estimation phase's mutations).
    pub large_step: Option<LargeStepEstimate>,
    /// The large-step probability used after the estimation phase.
    pub final_large_step_probability: f64,
    /// Splats dropped (non-finite, outside the image, or overflowing a pixel's sum) plus
    /// pixels dropped because their value does not fit a finite f32.
    pub dropped: u64,
    /// Non-finite target values met by chains (rejected candidates).
    pub non_finite: u64,
    /// True if cancelled before the budget was used.
    pub cancelled: bool,
    /// With [`MltSettings::stage_map`]: per pixel, the share of the estimate contributed by
    /// second-stage candidates of a delayed-rejection kernel ([`super::StagedSplats`]).
    pub stage_map: Option<Image>,
    /// Why the image is black, if it is ("no light-carrying path found").
    pub message: Option<String>,
    /// Other notes from the loop (chains capped, bootstrap stopped early by the time budget).
    pub notes: Vec<String>,
    /// Wall-clock time of the bootstrap.
    pub bootstrap_time: Duration,
    /// Wall-clock time of the chains' first round (with automatic large-step control: the
    /// estimation phase).
    pub estimation_time: Duration,
    /// Wall-clock time of all the chains' rounds.
    pub chains_time: Duration,
    /// A sharded run's accumulators ([`MltSettings::shard`]; `None` for the whole render).
    pub component: Option<Component>,
}

/// How [`super::MltDriver`] makes each chain's kernel: any `Fn(p_large) -> K` (the same kernel for
/// every chain), or [`PerChain`] for a kernel that depends on the chain's [`ChainSlot`] (e.g.
/// on its MMLT depth).
pub trait MakeKernel<K>: Sync {
    /// The kernel of the chain in `slot`, with large-step probability `p_large`.
    fn make(&self, slot: ChainSlot, p_large: f64) -> K;
}

impl<K, F: Fn(f64) -> K + Sync> MakeKernel<K> for F {
    fn make(&self, _slot: ChainSlot, p_large: f64) -> K {
        self(p_large)
    }
}

/// A kernel factory that sees the chain's slot (chain index, and target index: the MMLT depth
/// for [`super::MmltTarget::all_depths`]).
#[derive(Clone, Copy, Debug)]
pub struct PerChain<F>(pub F);

impl<K, F: Fn(ChainSlot, f64) -> K + Sync> MakeKernel<K> for PerChain<F> {
    fn make(&self, slot: ChainSlot, p_large: f64) -> K {
        (self.0)(slot, p_large)
    }
}

/// Options of an MCMC render's estimator, beside [`MltSettings`] (a separate struct, so that
/// existing `MltSettings` literals stay valid): see [`super::MltDriver::estimator`]. The
/// default is [`MltEstimator::plain`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MltEstimator {
    /// Combine the large-step samples with the Metropolis estimator by multiple importance
    /// sampling (Kelemen et al. 2002, section 4; LuxCore's METROPOLIS sampler;
    /// `mcmc_core::render_loop::LargeStepMis`): a large step's candidate is splatted with
    /// weight `(a + 1) / (f/b_d + p)`, every other splat with its expected-value weight
    /// over `f/b_d + p` (in the loop's units: times `f / (f + b_d p)`), `b_d` the bootstrap
    /// estimate of the chain's target (MMLT: of its depth), `p` the large-step probability
    /// of that step. Default off here; the session turns it on for PSSMLT
    /// ([`crate::methods::PssmltSettings`]; docs/methods/large-step-mis.md has the
    /// measurement); for delayed rejection [`crate::methods::DrmltSettings`] turns it on
    /// when asked (its splats keep the same contract, so the weights are the same).
    pub large_step_mis: bool,
    /// How chains are spread over the targets (MMLT: depths): pbrt's joint resampling
    /// (default) or a fixed count per depth with splats scaled by `b_d / n_d`
    /// (`mcmc_core::render_loop::ChainAllocation`; docs/methods/pssmlt-mmlt.md).
    pub chain_allocation: ChainAllocation,
    /// MMLT only (targets in [`super::MmltTarget::all_depths`] order): stratify the
    /// bootstrap over the strategy choice, so every primary point of depth `d` is evaluated
    /// under all `d + 2` strategies ([`super::MmltStrata`]; Hachisuka et al. 2014, section
    /// 4). Default off.
    pub strategy_strata: bool,
}

impl MltEstimator {
    /// The plain expected-value estimator of Kelemen et al. 2002 (eq. 5) with pbrt's
    /// bootstrap: every option off (the [`Default`]).
    #[must_use]
    pub const fn plain() -> Self {
        Self {
            large_step_mis: false,
            chain_allocation: ChainAllocation::Joint,
            strategy_strata: false,
        }
    }
}

/// Turns the loop's output into an [`MltOutput`].
pub(super) fn finish<Sh>(
    out: Result<LoopOutput<StagedSplats, Sh>, mcmc_core::McmcError>,
    settings: &MltSettings,
    initial_p: f64,
    estimate: impl Fn(&Sh) -> Option<LargeStepEstimate>,
) -> MltOutput {
    let (w, h) = (settings.width, settings.height);
    let out = match out {
        Ok(out) => out,
        Err(e) => {
            return MltOutput {
                image: Image::new(w, h),
                b: 0.0,
                b_standard_error: 0.0,
                bootstrap_b: 0.0,
                bootstrap_standard_error: 0.0,
                large_step_samples: 0,
                normalization_given: false,
                bootstrap_samples: 0,
                target_b: Vec::new(),
                target_chains: Vec::new(),
                mutations: 0,
                stats: AcceptanceStats::default(),
                large_step: None,
                final_large_step_probability: initial_p,
                dropped: 0,
                non_finite: 0,
                cancelled: false,
                stage_map: None,
                message: Some(format!("invalid MCMC settings: {e}")),
                notes: Vec::new(),
                bootstrap_time: Duration::ZERO,
                estimation_time: Duration::ZERO,
                chains_time: Duration::ZERO,
                component: None,
            }
        }
    };
    let large_step = estimate(&out.shared);
    let scale = out.splat_scale * (w * h) as f64;
    let mut notes = out.notes;
    let message = if out.found_nothing { notes.pop() } else { None };
    // The splat sums are finite f64; a pixel above f32::MAX would still become infinite in
    // the f32 image: such pixels are dropped (black) and counted, never written as inf.
    let (pixels, overflowed) = out.sink.image.to_rgb32_checked(scale);
    if overflowed > 0 {
        notes.push(format!(
            "{overflowed} pixel(s) exceed the largest f32 value (3.4e38) and were dropped (black): the scene's radiance is too large to store; scale its emission down"
        ));
    }
    MltOutput {
        image: Image {
            width: w,
            height: h,
            pixels,
        },
        b: out.b,
        b_standard_error: out.b_standard_error,
        bootstrap_b: out.bootstrap_b,
        bootstrap_standard_error: out.bootstrap_standard_error,
        large_step_samples: out.large_step_samples,
        normalization_given: matches!(out.normalization.mode, NormalizationMode::Given(_)),
        bootstrap_samples: out.bootstrap_samples,
        target_b: out.target_b,
        target_chains: out.target_chains,
        mutations: out.mutations,
        stats: out.stats,
        final_large_step_probability: large_step.map_or(initial_p, |e| e.large_step_probability),
        large_step,
        dropped: out.dropped_splats + overflowed,
        non_finite: out.non_finite,
        cancelled: out.cancelled,
        stage_map: out.sink.stage_map(),
        message,
        notes,
        bootstrap_time: out.bootstrap_time,
        estimation_time: out.first_round_time,
        chains_time: out.chains_time,
        component: (!settings.shard.is_whole()).then(|| Component::Chains {
            grid: (*out.sink.image).clone(),
            normalization: out.normalization,
            mutations: out.mutations,
        }),
    }
}
