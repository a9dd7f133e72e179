//! Statistics that the controllers of all chains share: merged in job order at every round
//! boundary of a render loop and handed back, so shared adaptation is deterministic.

use super::{AutoLargeStep, Controller, GlobalScale, LargeStepStats, NoAdaptation};
use crate::kernel::StepInfo;
use crate::tunable::LargeStepTunable;

/// A controller whose statistics are pooled over all chains of a render loop.
///
/// At the end of every round the loop calls [`SharedController::contribute`] on every chain's
/// controller (with its kernel), in job order and chain order, into one pooled value (cumulative over the whole
/// run), then [`SharedController::receive`] on every controller with the pooled value. Under a
/// mutation budget rounds are fixed, so the result does not depend on the thread count (the
/// paper implementations use atomics and locks instead, which are not reproducible).
///
/// Controllers that adapt per chain use `Shared = ()` and do nothing here.
pub trait SharedController<K: ?Sized> {
    /// The pooled statistics.
    type Shared: Clone + Default + Send + Sync + std::fmt::Debug;
    /// Adds this chain's statistics gathered since the last call to `pooled` (the kernel is
    /// passed for statistics it holds itself, such as a gradient cache).
    fn contribute(&mut self, kernel: &mut K, pooled: &mut Self::Shared);
    /// Receives the statistics pooled over all chains since the start; may tune `kernel`.
    fn receive(&mut self, kernel: &mut K, pooled: &Self::Shared);
    /// Called once per round, after every chain's [`SharedController::contribute`] and before
    /// any [`SharedController::receive`]: work on the pooled statistics as a whole at the
    /// synchronisation point (e.g. refining a shared partition). The default does nothing.
    fn end_round(pooled: &mut Self::Shared) {
        let _ = pooled;
    }
    /// One line on the pooled statistics at the end of a run, for the render notes (the
    /// default: none).
    fn summary(pooled: &Self::Shared) -> Option<String> {
        let _ = pooled;
        None
    }
    /// True if the pooled statistics make a chain's moves depend on other chains (the
    /// default): a render split into shards ([`crate::render_loop::Shard`]) must then run
    /// every chain in every shard and keep only its own chains' splats. False for
    /// controllers whose chains are independent (nothing is pooled), so a shard runs only
    /// its own chains.
    const COUPLES_CHAINS: bool = true;
}

impl<K: ?Sized> SharedController<K> for NoAdaptation {
    type Shared = ();
    const COUPLES_CHAINS: bool = false;
    fn contribute(&mut self, _kernel: &mut K, _pooled: &mut ()) {}
    fn receive(&mut self, _kernel: &mut K, _pooled: &()) {}
}

/// Global scale adaptation is per chain (each chain follows its own sign rule).
impl<K: ?Sized> SharedController<K> for GlobalScale {
    type Shared = ();
    const COUPLES_CHAINS: bool = false;
    fn contribute(&mut self, _kernel: &mut K, _pooled: &mut ()) {}
    fn receive(&mut self, _kernel: &mut K, _pooled: &()) {}
}

/// Automatic large-step control pooled over chains: a controller made with
/// [`AutoLargeStep::pooled`] only records during its estimation phase; once the pooled
/// statistics of all chains hold its `estimation_steps`, every chain sets the same `p_l` from
/// them and freezes. A controller made with [`AutoLargeStep::new`] decides alone, from its own
/// statistics, and shares nothing.
impl<K: LargeStepTunable + ?Sized> SharedController<K> for AutoLargeStep {
    type Shared = LargeStepStats;
    fn contribute(&mut self, _kernel: &mut K, pooled: &mut LargeStepStats) {
        pooled.merge(&self.take_unshared());
    }
    fn receive(&mut self, kernel: &mut K, pooled: &LargeStepStats) {
        self.receive_pooled(kernel, pooled);
    }
}

/// Two controllers run side by side on one kernel (e.g. automatic large-step control and a
/// shared gradient cache): both see every step, both contribute to and receive their own part
/// of the pooled statistics `(A::Shared, B::Shared)`. Frozen when both are.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Both<A, B>(pub A, pub B);

impl<K: ?Sized, S, A: Controller<K, S>, B: Controller<K, S>> Controller<K, S> for Both<A, B> {
    fn before_step(&mut self, kernel: &K, x: &S) {
        self.0.before_step(kernel, x);
        self.1.before_step(kernel, x);
    }
    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        self.0.after_step(kernel, info);
        self.1.after_step(kernel, info);
    }
    fn is_frozen(&self) -> bool {
        self.0.is_frozen() && self.1.is_frozen()
    }
}

impl<K: ?Sized, A: SharedController<K>, B: SharedController<K>> SharedController<K> for Both<A, B> {
    type Shared = (A::Shared, B::Shared);
    fn contribute(&mut self, kernel: &mut K, pooled: &mut Self::Shared) {
        self.0.contribute(kernel, &mut pooled.0);
        self.1.contribute(kernel, &mut pooled.1);
    }
    fn receive(&mut self, kernel: &mut K, pooled: &Self::Shared) {
        self.0.receive(kernel, &pooled.0);
        self.1.receive(kernel, &pooled.1);
    }
    fn end_round(pooled: &mut Self::Shared) {
        A::end_round(&mut pooled.0);
        B::end_round(&mut pooled.1);
    }
    fn summary(pooled: &Self::Shared) -> Option<String> {
        match (A::summary(&pooled.0), B::summary(&pooled.1)) {
            (Some(a), Some(b)) => Some(format!("{a}; {b}")),
            (a, b) => a.or(b),
        }
    }
    const COUPLES_CHAINS: bool = A::COUPLES_CHAINS || B::COUPLES_CHAINS;
}
