//! How to learn: adaptation controllers, which tune kernels through the interfaces of
//! [`crate::tunable`] (re-exported here).

mod global_scale;
mod large_step;
mod large_step_schedule;
mod region_table;
mod regional_params;
mod regional_pool;
mod regional_scale;
mod shared;

pub use global_scale::{AdaptState, GlobalScale, ScaleAdaptParams};
pub use large_step::{
    automatic_large_step_probability, AutoLargeStep, LargeStepEstimate, LargeStepStats,
    FLATNESS_THRESHOLD, NOT_FLAT_LARGE_STEP_PROBABILITY,
};
pub use large_step_schedule::LargeStepSchedule;
pub use regional_params::{
    RegionalScaleParams, RegionalUpdateRule, PIXELS_PER_LEAF, SPLIT_UPDATES,
};
pub use regional_pool::PooledRegionalScales;
pub use regional_scale::{RegionStats, RegionalScale, MAX_VISITS_PER_ROUND, RECENT_WINDOW};
pub use shared::{Both, SharedController};

/// The tunable interfaces, re-exported from [`crate::tunable`] where they live.
pub use crate::tunable::{
    HasSharedScales, LargeStepTunable, RegionalTunable, ScaleTunable, SharedRegionalScales,
    StateMove,
};

use crate::kernel::StepInfo;

/// An adaptation controller: sees each step's report and tunes the kernel between steps.
///
/// A controller either relies on *diminishing adaptation* (its step sizes go to zero, so the
/// chain still converges to the target; Roberts & Rosenthal 2007) or on *finite adaptation*
/// (it freezes after a while, after which the chain is a plain MH chain). Each implementation
/// documents which; [`Controller::is_frozen`] reports whether adaptation has stopped.
pub trait Controller<K: ?Sized, S> {
    /// Called before the kernel step with the current state (e.g. to find its region).
    fn before_step(&mut self, kernel: &K, x: &S) {
        let _ = (kernel, x);
    }
    /// Called after the kernel step with its report; may change the kernel's parameters.
    fn after_step(&mut self, kernel: &mut K, info: &StepInfo);
    /// True once the controller no longer changes the kernel.
    fn is_frozen(&self) -> bool;
}

/// No adaptation: the kernel is never changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoAdaptation;

impl<K: ?Sized, S> Controller<K, S> for NoAdaptation {
    fn after_step(&mut self, _kernel: &mut K, _info: &StepInfo) {}
    fn is_frozen(&self) -> bool {
        true
    }
}
