//! The interfaces through which controllers tune kernels and proposals: one global scale,
//! one scale per region, the large-step probability.
//!
//! They sit below both sides: proposals and kernels implement them, controllers
//! ([`crate::controller`]) act through them, and neither side depends on the other.

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
