//! How render runs its path samplers through mcmc-core's generic render loop: settings in,
//! image out. No bootstrap, resampling or chain scheduling lives here (see
//! `mcmc_core::render_loop`); this file maps render's settings onto the loop, picks the
//! controller for the large-step mode and turns the loop's sink into an image.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use mcmc_core::controller::{AutoLargeStep, LargeStepEstimate, LargeStepStats, LargeStepTunable};
use mcmc_core::render_loop::{
    Both, ChainAllocation, ChainSlot, IndependentStates, LargeStepMis, LoopBudget, LoopOutput,
    LoopSettings, RenderLoop, SharedController, SplatPayload,
};
use mcmc_core::stats::AcceptanceStats;
use mcmc_core::{Controller, Kernel, NoAdaptation, Progress, Target};
use pss::{FreshPss, PssState};

use super::StagedSplats;
use crate::image::Image;

/// How the large-step probability is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LargeStepMode {
    /// A fixed probability in `[0, 1]`.
    Fixed(f64),
    /// Automatic control (Zsolnai & Szirmay-Kalos 2013): every chain first runs
    /// `estimation_steps` mutations with `initial` large-step probability; `eta_s`, `eta_l`,
    /// `eta_0` are pooled over all chains (`mcmc_core::controller::AutoLargeStep::pooled`) and
    /// `p_l` is set for the rest of the render (finite adaptation: the kernel is fixed
    /// afterwards).
    Auto {
        /// Large-step probability during the estimation phase.
        initial: f64,
        /// Mutations per chain in the estimation phase.
        estimation_steps: u64,
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
}

/// What an MCMC render produced.
#[derive(Clone, Debug)]
pub struct MltOutput {
    /// The image (black if nothing carried light).
    pub image: Image,
    /// The normalisation `b` from the bootstrap.
    pub b: f64,
    /// Standard error of `b`.
    pub b_standard_error: f64,
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
    /// The automatic large-step estimate, if automatic control ran to the end of its phase.
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
}

/// How [`render_mlt`] makes each chain's kernel: any `Fn(p_large) -> K` (the same kernel for
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
/// existing `MltSettings` literals stay valid): see [`render_mlt_with_estimator`]. The
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
    /// measurement). Two-stage (delayed-rejection) kernels
    /// ignore it.
    pub large_step_mis: bool,
    /// How chains are spread over the targets (MMLT: depths): pbrt's joint resampling
    /// (default) or a fixed count per depth with splats scaled by `b_d / n_d`
    /// (`mcmc_core::render_loop::ChainAllocation`; docs/performance.md, "MMLT robustness").
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

/// Runs an MCMC render over one or more targets (PSSMLT: one; MMLT: one per path depth)
/// through `mcmc_core::render_loop`: bootstrap of fresh PSS points (`pss::FreshPss`), chain
/// starts resampled in proportion to `f`, chains in 32 fixed jobs, expected-value splats, the
/// large-step controller of `settings.large_step`.
///
/// Pixel estimate: `I_j = (b W H / N) sum_i sum_splats w_i rgb / f(u_i)` with `N` the total
/// number of mutations (Kelemen et al. 2002, eq. 5 with expected values). The same as
/// [`render_mlt_with_estimator`] with the default [`MltEstimator`].
pub fn render_mlt<T, K>(
    targets: &[T],
    make_kernel: impl MakeKernel<K>,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
    K: Kernel<T> + LargeStepTunable + Send,
{
    render_mlt_with_estimator(
        targets,
        make_kernel,
        settings,
        MltEstimator::default(),
        progress,
        cancel,
    )
}

/// As [`render_mlt`], with the estimator's options: with
/// [`MltEstimator::large_step_mis`] every single-stage chain kernel is wrapped in
/// `mcmc_core::render_loop::LargeStepMis` (large-step density 1: primary sample space),
/// weighting with its target's bootstrap `b_d` and the large-step probability of each step
/// (under automatic control: the initial one during the estimation phase, the estimate
/// afterwards).
pub fn render_mlt_with_estimator<T, K>(
    targets: &[T],
    make_kernel: impl MakeKernel<K>,
    settings: &MltSettings,
    estimator: MltEstimator,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
    K: Kernel<T> + LargeStepTunable + Send,
{
    render_mlt_inner(
        targets,
        make_kernel,
        settings,
        estimator,
        None,
        progress,
        cancel,
    )
}

/// As [`render_mlt_with_estimator`] with each target's integral given (`normalization[d]`,
/// one per target; MMLT: [`super::mmlt_depth_normalization`], all-strategy BDPT samples)
/// instead of the bootstrap's estimate: chains are allocated per target in proportion to it
/// and each target's splats scaled by `normalization[d] / n_d`
/// (`mcmc_core::render_loop::RenderLoop::run_normalized`: consistent, the bootstrap then only
/// picks the chain starts). A `normalization` of the wrong length gives a black image with a
/// message.
pub fn render_mlt_normalized<T, K>(
    targets: &[T],
    make_kernel: impl MakeKernel<K>,
    settings: &MltSettings,
    estimator: MltEstimator,
    normalization: &[f64],
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
    K: Kernel<T> + LargeStepTunable + Send,
{
    render_mlt_inner(
        targets,
        make_kernel,
        settings,
        estimator,
        Some(normalization),
        progress,
        cancel,
    )
}

fn render_mlt_inner<T, K>(
    targets: &[T],
    make_kernel: impl MakeKernel<K>,
    settings: &MltSettings,
    estimator: MltEstimator,
    normalization: Option<&[f64]>,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
    K: Kernel<T> + LargeStepTunable + Send,
{
    let pixels = (settings.width * settings.height) as f64;
    let chains = settings.chains.max(1);
    let budget = match settings.budget {
        MltBudget::MutationsPerPixel(m) => {
            LoopBudget::Mutations((m * pixels).round().max(1.0) as u64)
        }
        MltBudget::Time(t) => LoopBudget::Time(t),
    };
    let mut loop_settings = LoopSettings {
        chains,
        bootstrap_samples: settings.bootstrap_samples.max(1) as u64,
        budget,
        seed: settings.seed,
        large_step_mis: estimator.large_step_mis,
        chain_allocation: estimator.chain_allocation,
        ..LoopSettings::default()
    };
    let fresh = FreshPss::new(settings.streams.clamp(1, pss::MAX_STREAMS))
        .unwrap_or_else(|_| unreachable!("clamped to 1..=4"));
    let strata = estimator.strategy_strata.then(|| {
        super::MmltStrata::new(
            settings.streams,
            targets
                .len()
                .saturating_sub(1)
                .try_into()
                .unwrap_or(u32::MAX),
        )
    });
    let states: &dyn IndependentStates<PssState> = match &strata {
        Some(s) => s,
        None => &fresh,
    };
    let (w, h) = (settings.width, settings.height);
    let stage_map = settings.stage_map;
    let sink = || StagedSplats::new(w, h, stage_map);
    // Primary sample space: the large step is uniform, density 1.
    let wrap = |slot: ChainSlot, kernel: K| {
        if Kernel::<T>::stages(&kernel) == 1 {
            LargeStepMis::for_slot(kernel, slot, 1.0)
        } else {
            LargeStepMis::disabled(kernel)
        }
    };
    match settings.large_step {
        LargeStepMode::Fixed(p) => {
            let render_loop = RenderLoop {
                targets,
                states,
                kernel: |slot| wrap(slot, make_kernel.make(slot, p)),
                controller: |_| NoAdaptation,
                sink,
            };
            let out = match normalization {
                Some(nb) => render_loop.run_normalized(&loop_settings, nb, progress, cancel),
                None => render_loop.run(&loop_settings, progress, cancel),
            };
            finish(out, settings, p, |_| None)
        }
        LargeStepMode::Auto {
            initial,
            estimation_steps,
        } => {
            // At most a tenth of each chain's budget goes to estimation.
            let steps = match budget {
                LoopBudget::Mutations(n) => estimation_steps.min(n / chains as u64 / 10),
                LoopBudget::Time(_) => estimation_steps,
            }
            .max(1);
            // The first round ends exactly when every chain has run its estimation phase.
            loop_settings.round_mutations = steps;
            let total = steps.saturating_mul(chains as u64);
            let render_loop = RenderLoop {
                targets,
                states,
                kernel: |slot| wrap(slot, make_kernel.make(slot, initial)),
                controller: |_| {
                    AutoLargeStep::pooled(total).unwrap_or_else(|_| unreachable!("total >= 1"))
                },
                sink,
            };
            let out = match normalization {
                Some(nb) => render_loop.run_normalized(&loop_settings, nb, progress, cancel),
                None => render_loop.run(&loop_settings, progress, cancel),
            };
            finish(out, settings, initial, |pooled: &LargeStepStats| {
                (pooled.steps() >= total).then(|| pooled.estimate())
            })
        }
    }
}

/// As [`render_mlt`] with a kernel and a controller made per chain (from its
/// [`ChainSlot`]: chain index and target index, e.g. the MMLT depth): for integrators whose
/// kernel depends on the chain's target (Langevin MLT: MALA on shallow depths, Kelemen on deep
/// ones) or whose controllers share statistics through the loop's round hook (a gradient
/// cache). `make_kernel` receives the large-step probability; with automatic control
/// (`LargeStepMode::Auto`) the chains run [`AutoLargeStep::pooled`] *beside* the caller's
/// controller ([`Both`]), as [`render_mlt`] does.
pub fn render_mlt_per_chain<T, K, C>(
    targets: &[T],
    make_kernel: impl Fn(ChainSlot, f64) -> K + Sync,
    make_controller: impl Fn(ChainSlot) -> C + Sync,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
    K: Kernel<T> + LargeStepTunable + Send,
    C: Controller<K, PssState> + SharedController<K> + Send,
{
    let states = FreshPss::new(settings.streams.clamp(1, pss::MAX_STREAMS))
        .unwrap_or_else(|_| unreachable!("clamped to 1..=4"));
    match settings.large_step {
        LargeStepMode::Fixed(p) => {
            let mut result = render_mlt_with_states(
                targets,
                &states,
                |slot: ChainSlot| make_kernel(slot, p),
                make_controller,
                settings,
                progress,
                cancel,
            );
            result.final_large_step_probability = p;
            result
        }
        LargeStepMode::Auto {
            initial,
            estimation_steps,
        } => {
            let mut loop_settings = loop_settings(settings);
            let chains = loop_settings.chains;
            // As render_mlt: at most a tenth of each chain's budget goes to estimation, and
            // the first round ends when every chain has run its estimation phase.
            let steps = match loop_settings.budget {
                LoopBudget::Mutations(n) => estimation_steps.min(n / chains as u64 / 10),
                LoopBudget::Time(_) => estimation_steps,
            }
            .max(1);
            loop_settings.round_mutations = steps;
            let total = steps.saturating_mul(chains as u64);
            let (w, h) = (settings.width, settings.height);
            let stage_map = settings.stage_map;
            let out = RenderLoop {
                targets,
                states: &states,
                kernel: |slot: ChainSlot| make_kernel(slot, initial),
                controller: |slot: ChainSlot| {
                    Both(
                        AutoLargeStep::pooled(total).unwrap_or_else(|_| unreachable!("total >= 1")),
                        make_controller(slot),
                    )
                },
                sink: || StagedSplats::new(w, h, stage_map),
            }
            .run(&loop_settings, progress, cancel);
            finish(
                out,
                settings,
                initial,
                |pooled: &(LargeStepStats, C::Shared)| {
                    (pooled.0.steps() >= total).then(|| pooled.0.estimate())
                },
            )
        }
    }
}

/// The loop settings of an MCMC render.
fn loop_settings(settings: &MltSettings) -> LoopSettings {
    let pixels = (settings.width * settings.height) as f64;
    LoopSettings {
        chains: settings.chains.max(1),
        bootstrap_samples: settings.bootstrap_samples.max(1) as u64,
        budget: match settings.budget {
            MltBudget::MutationsPerPixel(m) => {
                LoopBudget::Mutations((m * pixels).round().max(1.0) as u64)
            }
            MltBudget::Time(t) => LoopBudget::Time(t),
        },
        seed: settings.seed,
        ..LoopSettings::default()
    }
}

/// As [`render_mlt_per_chain`] over any state type: the chains' independent states (the
/// bootstrap and the chain starts) come from `states`, whose weights `f / p` make the
/// bootstrap estimate `b` (path-space MLT: `pathspace::Path` drawn by an independent path
/// sampler, [`super::pathmlt`]). `settings.streams` and `settings.large_step` are not used.
/// The image is `b W H / N` times the expected-value splat sums (splat rasters in pixels).
pub fn render_mlt_with_states<T, St, K, C>(
    targets: &[T],
    states: &St,
    make_kernel: impl Fn(ChainSlot) -> K + Sync,
    make_controller: impl Fn(ChainSlot) -> C + Sync,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target,
    T::Payload: SplatPayload,
    St: IndependentStates<T::State>,
    K: Kernel<T> + Send,
    C: Controller<K, T::State> + SharedController<K> + Send,
{
    let (w, h) = (settings.width, settings.height);
    let stage_map = settings.stage_map;
    let out = RenderLoop {
        targets,
        states,
        kernel: &make_kernel,
        controller: &make_controller,
        sink: || StagedSplats::new(w, h, stage_map),
    }
    .run(&loop_settings(settings), progress, cancel);
    finish(out, settings, 0.0, |_| None)
}

/// As [`render_mlt_with_states`] with `round_mutations` mutations per chain between two
/// synchronisation points of the loop (instead of the loop's default 1000: controllers that
/// share statistics through the round hook, such as regional adaptation, want small rounds),
/// also returning the controllers' pooled statistics at the end of the run (`None` if the
/// loop's settings were invalid).
#[allow(clippy::too_many_arguments)]
pub fn render_mlt_with_states_rounds<T, St, K, C>(
    targets: &[T],
    states: &St,
    make_kernel: impl Fn(ChainSlot) -> K + Sync,
    make_controller: impl Fn(ChainSlot) -> C + Sync,
    settings: &MltSettings,
    round_mutations: u64,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> (MltOutput, Option<C::Shared>)
where
    T: Target,
    T::Payload: SplatPayload,
    St: IndependentStates<T::State>,
    K: Kernel<T> + Send,
    C: Controller<K, T::State> + SharedController<K> + Send,
    C::Shared: Clone,
{
    let (w, h) = (settings.width, settings.height);
    let stage_map = settings.stage_map;
    let loop_settings = LoopSettings {
        round_mutations: round_mutations.max(1),
        ..loop_settings(settings)
    };
    let out = RenderLoop {
        targets,
        states,
        kernel: &make_kernel,
        controller: &make_controller,
        sink: || StagedSplats::new(w, h, stage_map),
    }
    .run(&loop_settings, progress, cancel);
    let shared = out.as_ref().ok().map(|o| o.shared.clone());
    (finish(out, settings, 0.0, |_| None), shared)
}

/// Turns the loop's output into an [`MltOutput`].
fn finish<Sh>(
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
    }
}
