//! How to learn: adaptation controllers and the tunable interfaces they act through.

mod global_scale;
mod large_step;
mod regional_scale;

pub use global_scale::{AdaptState, GlobalScale, ScaleAdaptParams};
pub use large_step::{
    automatic_large_step_probability, AutoLargeStep, LargeStepEstimate, LargeStepStats,
    FLATNESS_THRESHOLD, NOT_FLAT_LARGE_STEP_PROBABILITY,
};
pub use regional_scale::{RegionStats, RegionalScale, RegionalScaleParams};

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

/// A kernel or proposal with one global scale `lambda = log sigma^2`.
pub trait ScaleTunable {
    /// The current `lambda`.
    fn log_scale(&self) -> f64;
    /// Sets `lambda`.
    fn set_log_scale(&mut self, lambda: f64);
}

/// A kernel or proposal with one scale per region of a partition.
pub trait RegionalTunable<S> {
    /// The region containing `x`.
    fn region_of(&self, x: &S) -> usize;
    /// Number of regions.
    fn num_regions(&self) -> usize;
    /// `lambda` of a region.
    fn log_scale_of(&self, region: usize) -> f64;
    /// Sets `lambda` of a region.
    fn set_log_scale_of(&mut self, region: usize, lambda: f64);
    /// Splits a region (children inherit its scale); returns the fresh ids of the children
    /// other than `region` itself (see [`crate::Partition::split`]), or `None` if the
    /// partition cannot refine.
    fn split_region(&mut self, region: usize) -> Option<std::ops::Range<usize>> {
        let _ = region;
        None
    }
}

/// A kernel or proposal mixing small steps with large (independent) steps.
pub trait LargeStepTunable {
    /// The probability of a large step.
    fn large_step_probability(&self) -> f64;
    /// Sets the probability of a large step (in `(0, 1]`).
    fn set_large_step_probability(&mut self, p: f64);
    /// True if mixture component `component` is the large step.
    fn is_large_step(&self, component: usize) -> bool;
}
