//! The one MCMC driver of render: a builder over mcmc-core's generic render loop (targets,
//! settings, then optional estimator options, a given normalisation, round length or
//! independent states), run with a kernel factory and, optionally, per-chain controllers.
//!
//! ```no_run
//! # use std::sync::atomic::AtomicBool;
//! # use mcmc_core::{Mh, NoProgress};
//! # use pss::{KelemenParams, PssmltProposal, SmallMutation, SmallStep};
//! # use render::mlt::{LargeStepMode, MltBudget, MltDriver, MltEstimator, MltSettings, PssmltTarget, PATH_STREAMS};
//! # let scene = render::Scene::cornell_box(16, 16);
//! let targets = [PssmltTarget::new(&scene, render::bdpt::BdptParams::default(), 16, 16)];
//! let settings = MltSettings {
//!     width: 16, height: 16, chains: 16, bootstrap_samples: 10_000,
//!     budget: MltBudget::MutationsPerPixel(8.0), large_step: LargeStepMode::Fixed(0.3),
//!     seed: 1, streams: PATH_STREAMS, stage_map: false,
//!     shard: render::shard::Shard::WHOLE, normalization: Default::default(),
//! };
//! let small = SmallStep::new(SmallMutation::Kelemen(KelemenParams::kelemen2002()));
//! let out = MltDriver::new(&targets, &settings)
//!     .estimator(MltEstimator { large_step_mis: true, ..MltEstimator::plain() })
//!     .run(|p: f64| Mh::new(PssmltProposal::new(small, p).unwrap()), &NoProgress, &AtomicBool::new(false));
//! assert!(out.mutations > 0);
//! ```

use std::sync::atomic::AtomicBool;

use mcmc_core::controller::{LargeStepSchedule, LargeStepStats, LargeStepTunable};
use mcmc_core::render_loop::{
    Both, ChainSlot, IndependentStates, LargeStepMis, LoopBudget, LoopOutput, LoopSettings,
    RenderLoop, SharedController, SplatPayload,
};
use mcmc_core::{Controller, Kernel, McmcError, NoAdaptation, Progress, Target};
use pss::{FreshPss, PssState};

use super::estimation::{auto_large_step, set_up_estimation, warm_up_steps};
use super::run::finish;
use super::{
    LargeStepMode, MakeKernel, MltBudget, MltEstimator, MltOutput, MltSettings, MmltStrata,
    StagedSplats,
};

/// [`MltDriver`]'s states: fresh primary-sample-space points (or MMLT's strategy strata),
/// with large-step control.
#[derive(Clone, Copy, Debug, Default)]
pub struct PrimarySamples;

/// [`MltDriver`]'s states: the caller's independent states (e.g. path-space paths), no
/// large-step control.
#[derive(Clone, Copy, Debug)]
pub struct GivenStates<'s, St>(&'s St);

/// An MCMC render over `targets` (PSSMLT: one; MMLT: one per path depth), configured by its
/// builder methods and then run: bootstrap, chain starts resampled in proportion to `f`,
/// chains in fixed jobs, expected-value splats, the large-step controller of
/// [`MltSettings::large_step`].
///
/// Pixel estimate: `I_j = (b W H / N) sum_i sum_splats w_i rgb / f(u_i)` with `N` the total
/// number of mutations (Kelemen et al. 2002, eq. 5 with expected values).
#[derive(Clone, Copy, Debug)]
#[must_use]
pub struct MltDriver<'a, T, S = PrimarySamples> {
    targets: &'a [T],
    settings: MltSettings,
    estimator: MltEstimator,
    normalization: Option<&'a [f64]>,
    round_mutations: Option<u64>,
    first_depth: u32,
    states: S,
}

impl<'a, T> MltDriver<'a, T, PrimarySamples> {
    /// A render of `targets` with `settings` over fresh primary sample points, the plain
    /// estimator ([`MltEstimator::plain`]) and the bootstrap's normalisation.
    pub fn new(targets: &'a [T], settings: &MltSettings) -> Self {
        Self {
            targets,
            settings: *settings,
            estimator: MltEstimator::plain(),
            normalization: None,
            round_mutations: None,
            first_depth: 0,
            states: PrimarySamples,
        }
    }
}

impl<'a, T, S> MltDriver<'a, T, S> {
    /// The estimator's options ([`MltEstimator`]: large-step MIS, chain allocation, MMLT's
    /// strategy strata). Two-stage kernels ignore large-step MIS.
    pub fn estimator(self, estimator: MltEstimator) -> Self {
        Self { estimator, ..self }
    }

    /// Each target's integral given (`normalization[d]`, one per target; MMLT:
    /// [`super::mmlt_depth_normalization`]) instead of the bootstrap's estimate: chains are
    /// allocated per target in proportion to it and each target's splats scaled by
    /// `normalization[d] / n_d` (the bootstrap then only picks the chain starts). A
    /// normalisation of the wrong length gives a black image with a message.
    pub fn normalized(self, normalization: &'a [f64]) -> Self {
        Self {
            normalization: Some(normalization),
            ..self
        }
    }

    /// MMLT targets that start at depth `depth` ([`super::MmltTarget::depths_from`], when a
    /// direct-lighting pass renders the shallower depths): target `i` has depth `depth + i`,
    /// which the strategy strata ([`MltEstimator::strategy_strata`]) need. Default 0.
    pub fn first_depth(self, depth: u32) -> Self {
        Self {
            first_depth: depth,
            ..self
        }
    }

    /// `n` mutations per chain between two synchronisation points of the loop (default
    /// 1000; controllers that share statistics through the round hook, such as regional
    /// adaptation, want small rounds). Automatic large-step control sets every round to the
    /// length of its estimation phase (`mlt::estimation`).
    pub fn round_mutations(self, n: u64) -> Self {
        Self {
            round_mutations: Some(n.max(1)),
            ..self
        }
    }

    /// The chains' independent states (bootstrap and chain starts) from `states`, whose
    /// weights `f / p` make the bootstrap estimate `b` (path-space MLT: paths of an
    /// independent path sampler). [`MltSettings::streams`] and [`MltSettings::large_step`]
    /// are then not used.
    pub fn states<St>(self, states: &'a St) -> MltDriver<'a, T, GivenStates<'a, St>> {
        MltDriver {
            targets: self.targets,
            settings: self.settings,
            estimator: self.estimator,
            normalization: self.normalization,
            round_mutations: self.round_mutations,
            first_depth: self.first_depth,
            states: GivenStates(states),
        }
    }

    /// The loop's settings: chains, bootstrap, budget, seed, the estimator's options, rounds.
    fn loop_settings(&self) -> LoopSettings {
        let pixels = (self.settings.width * self.settings.height) as f64;
        let defaults = LoopSettings::default();
        LoopSettings {
            chains: self.settings.chains.max(1),
            bootstrap_samples: self.settings.bootstrap_samples.max(1) as u64,
            budget: match self.settings.budget {
                MltBudget::MutationsPerPixel(m) => {
                    LoopBudget::Mutations((m * pixels).round().max(1.0) as u64)
                }
                MltBudget::Time(t) => LoopBudget::Time(t),
            },
            seed: self.settings.seed,
            large_step_mis: self.estimator.large_step_mis,
            chain_allocation: self.estimator.chain_allocation,
            round_mutations: self.round_mutations.unwrap_or(defaults.round_mutations),
            shard: self.settings.shard,
            normalization: self.settings.normalization,
            ..defaults
        }
    }

    /// The sink of every job: one shared set of layers (the splats and, with
    /// [`MltSettings::stage_map`], the DR stage map), handed to each job as a clone.
    fn sink(&self) -> impl Fn() -> StagedSplats + Sync {
        let staged = StagedSplats::new(
            self.settings.width,
            self.settings.height,
            self.settings.stage_map,
        );
        move || staged.clone()
    }

    /// Runs the loop over `states`, with the given normalisation if any.
    fn run_loop<St, K, C>(
        &self,
        states: &St,
        kernel: impl Fn(ChainSlot) -> K + Sync,
        controller: impl Fn(ChainSlot) -> C + Sync,
        loop_settings: &LoopSettings,
        progress: &dyn Progress,
        cancel: &AtomicBool,
    ) -> Result<LoopOutput<StagedSplats, C::Shared>, McmcError>
    where
        T: Target,
        T::Payload: SplatPayload,
        St: IndependentStates<T::State> + ?Sized,
        K: Kernel<T> + Send,
        C: Controller<K, T::State> + SharedController<K> + Send,
    {
        let render_loop = RenderLoop {
            targets: self.targets,
            states,
            kernel,
            controller,
            sink: self.sink(),
        };
        match self.normalization {
            Some(nb) => render_loop.run_normalized(loop_settings, nb, progress, cancel),
            None => render_loop.run(loop_settings, progress, cancel),
        }
    }
}

impl<T> MltDriver<'_, T, PrimarySamples>
where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
{
    /// Runs with the same kind of kernel for every chain (from `make_kernel`, with the
    /// large-step probability; [`super::PerChain`] for one that depends on the chain's slot)
    /// and no adaptation besides automatic large-step control. With
    /// [`MltEstimator::large_step_mis`] every kernel (single-stage, or two-stage delayed
    /// rejection, whose splats keep the same contract) is wrapped in
    /// `mcmc_core::render_loop::LargeStepMis` (large-step density 1: primary sample space),
    /// weighting with its target's `b_d` and the large-step probability of each step.
    pub fn run<K>(
        self,
        make_kernel: impl MakeKernel<K>,
        progress: &dyn Progress,
        cancel: &AtomicBool,
    ) -> MltOutput
    where
        K: Kernel<T> + LargeStepTunable + Send,
    {
        // Primary sample space: the large step is uniform, density 1.
        let wrap = |slot: ChainSlot, kernel: K| LargeStepMis::for_slot(kernel, slot, 1.0);
        let fresh = self.fresh();
        let strata = self.strata();
        let states: &dyn IndependentStates<PssState> = match &strata {
            Some(s) => s,
            None => &fresh,
        };
        let mut loop_settings = self.loop_settings();
        match self.settings.large_step {
            LargeStepMode::Fixed(p) => {
                let out = self.run_loop(
                    states,
                    |slot| wrap(slot, make_kernel.make(slot, p)),
                    |_| NoAdaptation,
                    &loop_settings,
                    progress,
                    cancel,
                );
                finish(out, &self.settings, p, |_| None)
            }
            LargeStepMode::Auto {
                initial,
                estimation_steps,
            } => {
                set_up_estimation(&mut loop_settings, estimation_steps);
                let out = self.run_loop(
                    states,
                    |slot| wrap(slot, make_kernel.make(slot, initial)),
                    |_| auto_large_step(),
                    &loop_settings,
                    progress,
                    cancel,
                );
                finish(out, &self.settings, initial, |pooled: &LargeStepStats| {
                    (pooled.steps() > 0).then(|| pooled.estimate())
                })
            }
            LargeStepMode::Schedule { initial, then } => {
                let schedule = large_step_schedule(&loop_settings, then);
                let out = self.run_loop(
                    states,
                    |slot| wrap(slot, make_kernel.make(slot, initial)),
                    |_| schedule,
                    &loop_settings,
                    progress,
                    cancel,
                );
                finish(out, &self.settings, then, |_| None)
            }
        }
    }

    /// Runs with a kernel and a controller made per chain (from its [`ChainSlot`]: chain and
    /// target index, e.g. the MMLT depth): for integrators whose kernel depends on the
    /// chain's target (Langevin MLT: MALA on shallow depths, Kelemen on deep ones) or whose
    /// controllers share statistics through the loop's round hook (a gradient cache). With
    /// automatic large-step control the chains run
    /// [`mcmc_core::controller::AutoLargeStep::pooled`] beside the caller's controller
    /// ([`Both`]). The kernels are not wrapped for large-step MIS.
    pub fn run_with_controller<K, C>(
        self,
        make_kernel: impl MakeKernel<K>,
        make_controller: impl Fn(ChainSlot) -> C + Sync,
        progress: &dyn Progress,
        cancel: &AtomicBool,
    ) -> MltOutput
    where
        K: Kernel<T> + LargeStepTunable + Send,
        C: Controller<K, PssState> + SharedController<K> + Send,
    {
        let states = self.fresh();
        let mut loop_settings = self.loop_settings();
        match self.settings.large_step {
            LargeStepMode::Fixed(p) => {
                let out = self.run_loop(
                    &states,
                    |slot| make_kernel.make(slot, p),
                    make_controller,
                    &loop_settings,
                    progress,
                    cancel,
                );
                let summary = out.as_ref().ok().and_then(|o| C::summary(&o.shared));
                let mut output = finish(out, &self.settings, p, |_| None);
                output.notes.extend(summary);
                output
            }
            LargeStepMode::Auto {
                initial,
                estimation_steps,
            } => {
                set_up_estimation(&mut loop_settings, estimation_steps);
                let out = self.run_loop(
                    &states,
                    |slot| make_kernel.make(slot, initial),
                    |slot| Both(auto_large_step(), make_controller(slot)),
                    &loop_settings,
                    progress,
                    cancel,
                );
                let summary = out.as_ref().ok().and_then(|o| C::summary(&o.shared.1));
                let mut output = finish(
                    out,
                    &self.settings,
                    initial,
                    |pooled: &(LargeStepStats, C::Shared)| {
                        (pooled.0.steps() > 0).then(|| pooled.0.estimate())
                    },
                );
                output.notes.extend(summary);
                output
            }
            LargeStepMode::Schedule { initial, then } => {
                let schedule = large_step_schedule(&loop_settings, then);
                let out = self.run_loop(
                    &states,
                    |slot| make_kernel.make(slot, initial),
                    |slot| Both(schedule, make_controller(slot)),
                    &loop_settings,
                    progress,
                    cancel,
                );
                let summary = out.as_ref().ok().and_then(|o| C::summary(&o.shared.1));
                let mut output = finish(out, &self.settings, then, |_| None);
                output.notes.extend(summary);
                output
            }
        }
    }

    /// Fresh primary sample points of [`MltSettings::streams`] streams.
    fn fresh(&self) -> FreshPss {
        FreshPss::new(self.settings.streams.clamp(1, pss::MAX_STREAMS))
            .unwrap_or_else(|_| unreachable!("clamped to 1..=4"))
    }

    /// MMLT's strategy strata, with [`MltEstimator::strategy_strata`].
    fn strata(&self) -> Option<MmltStrata> {
        self.estimator.strategy_strata.then(|| {
            let targets: u32 = self.targets.len().try_into().unwrap_or(u32::MAX);
            MmltStrata::for_depths(
                self.settings.streams,
                self.first_depth,
                self.first_depth.saturating_add(targets.saturating_sub(1)),
            )
        })
    }
}

impl<T, St> MltDriver<'_, T, GivenStates<'_, St>>
where
    T: Target,
    T::Payload: SplatPayload,
    St: IndependentStates<T::State>,
{
    /// Runs over the given states with a kernel and a controller made per chain; also
    /// returns the controllers' pooled statistics at the end of the run (`None` if the
    /// loop's settings were invalid). The image is `b W H / N` times the expected-value
    /// splat sums (splat rasters in pixels).
    pub fn run<K, C>(
        self,
        make_kernel: impl Fn(ChainSlot) -> K + Sync,
        make_controller: impl Fn(ChainSlot) -> C + Sync,
        progress: &dyn Progress,
        cancel: &AtomicBool,
    ) -> (MltOutput, Option<C::Shared>)
    where
        K: Kernel<T> + Send,
        C: Controller<K, T::State> + SharedController<K> + Send,
        C::Shared: Clone,
    {
        let loop_settings = self.loop_settings();
        let out = self.run_loop(
            self.states.0,
            make_kernel,
            make_controller,
            &loop_settings,
            progress,
            cancel,
        );
        let shared = out.as_ref().ok().map(|o| o.shared.clone());
        (finish(out, &self.settings, 0.0, |_| None), shared)
    }
}

/// Every chain's [`LargeStepSchedule`]: `then` after the warm-up of
/// [`super::estimation::warm_up_steps`].
fn large_step_schedule(loop_settings: &LoopSettings, then: f64) -> LargeStepSchedule {
    LargeStepSchedule::new(warm_up_steps(loop_settings), then.clamp(0.0, 1.0))
        .unwrap_or_else(|_| unreachable!("clamped to [0, 1]"))
}
