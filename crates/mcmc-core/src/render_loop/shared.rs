//! Statistics that the controllers of all chains share: merged in job order at every round
//! boundary of the render loop and handed back, so shared adaptation is deterministic.

use crate::controller::{
    AutoLargeStep, GlobalScale, LargeStepStats, LargeStepTunable, NoAdaptation, RegionalScale,
};

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
}

impl<K: ?Sized> SharedController<K> for NoAdaptation {
    type Shared = ();
    fn contribute(&mut self, _kernel: &mut K, _pooled: &mut ()) {}
    fn receive(&mut self, _kernel: &mut K, _pooled: &()) {}
}

/// Global scale adaptation is per chain (each chain follows its own sign rule).
impl<K: ?Sized> SharedController<K> for GlobalScale {
    type Shared = ();
    fn contribute(&mut self, _kernel: &mut K, _pooled: &mut ()) {}
    fn receive(&mut self, _kernel: &mut K, _pooled: &()) {}
}

/// `RegionalScale` adapts per chain; `pathspace::regional::SharedRegionalAdaptation` is the
/// regional controller whose statistics are shared through this hook.
impl<K: ?Sized> SharedController<K> for RegionalScale {
    type Shared = ();
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
