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

/// A kernel or proposal with one scale per region of a partition, held by the kernel itself
/// (e.g. [`crate::proposal::Regional`]): how fixed regional kernels are set up. Adaptive
/// regional control shares one set of scales among all chains instead
/// ([`SharedRegionalScales`]).
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

/// Per-region scales `lambda_k = log sigma_k^2` over a refinable partition, published to every
/// chain behind one cheaply cloned handle: what a shared regional controller
/// ([`crate::controller::RegionalScale`]) reads regions from, updates at synchronisation points
/// and hands back to every chain.
///
/// The controller writes only at synchronisation points, when no chain is stepping, and hands
/// the written handle to every chain before the next round. An implementation may copy on
/// write (a chain still holding the previous handle keeps the previous scales, e.g. an `Arc`
/// and `Arc::make_mut`) or write in place to scales all handles share (no copy per round).
pub trait SharedRegionalScales: Clone {
    /// The partition the scales are over (a [`crate::Partition`] of the state space).
    type Partition;
    /// The partition.
    fn partition(&self) -> &Self::Partition;
    /// Number of regions.
    fn num_regions(&self) -> usize;
    /// `lambda` of a region.
    fn log_scale_of(&self, region: usize) -> f64;
    /// Sets `lambda` of a region (in place, or copying the scales first if another handle
    /// shares them).
    fn set_log_scale_of(&mut self, region: usize, lambda: f64);
    /// Splits a region, its children inheriting its scale (copying first if shared); returns
    /// the fresh ids of the children other than `region` itself (see
    /// [`crate::Partition::split`]), or `None` if the partition cannot refine it.
    fn split_region(&mut self, region: usize) -> Option<std::ops::Range<usize>>;
    /// True if both handles share the same scales (handing them over again is a no-op).
    fn same_as(&self, other: &Self) -> bool;
    /// Starts recording the region of the first state this handle is asked about (the
    /// proposal's current state) until the next call; returns false if the handle does not
    /// record it (the default). Lets a controller that needs only the perturbation steps'
    /// regions skip its own lookup ([`crate::controller::RegionalScale`]).
    fn clear_region_hint(&self) -> bool {
        false
    }
    /// The region recorded since [`Self::clear_region_hint`], if any.
    fn region_hint(&self) -> Option<usize> {
        None
    }
}

/// A kernel or proposal whose scales come from a [`SharedRegionalScales`] handle: how a shared
/// regional controller finds the handle to read regions from and to replace at
/// synchronisation points. [`crate::Mh`] forwards it from its proposal, a
/// [`crate::Mixture`] from its first component that has one.
pub trait HasSharedScales {
    /// The handle type.
    type Scales: SharedRegionalScales;
    /// The handle, if this kernel has one.
    fn shared_scales(&self) -> Option<&Self::Scales>;
    /// Mutable access to the handle, if this kernel has one.
    fn shared_scales_mut(&mut self) -> Option<&mut Self::Scales>;
}
