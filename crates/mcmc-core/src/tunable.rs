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
    /// Asks this handle to track the region of its chain's current state from now on and
    /// returns true, or returns false if it cannot (the default). A tracking handle records
    /// the regions its proposal looks up for the current state and for the candidate
    /// ([`Self::current_region`]), and [`Self::end_step`] keeps the record valid: the region
    /// of a state is then looked up once, when it is first proposed, instead of again on
    /// every step it stays the current state ([`crate::controller::RegionalScale`]).
    fn track_current_region(&self) -> bool {
        false
    }
    /// The region of the chain's current state, if the handle tracks it and knows it.
    fn current_region(&self) -> Option<usize> {
        None
    }
    /// Records `region` as the current state's region (the controller looked it up), if the
    /// handle tracks it.
    fn set_current_region(&self, region: usize) {
        let _ = region;
    }
    /// After every step of the chain while tracking: how the current state changed. After
    /// [`StateMove::ByScaledProposal`] the candidate's region (looked up for the reverse
    /// density) becomes the current state's; after [`StateMove::ByOtherProposal`] it is
    /// unknown until looked up again.
    fn end_step(&self, moved: StateMove) {
        let _ = moved;
    }
    /// Called on every chain's handle after every synchronisation point, once the chain has
    /// received the scales: the scales may have changed, so a tracking handle forgets any
    /// scale it kept for the current state (its region stays valid).
    fn scales_published(&self) {}
}

/// How a step changed the chain's current state, for [`SharedRegionalScales::end_step`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateMove {
    /// The candidate was rejected (or invalid): the state is unchanged.
    Stayed,
    /// The state is now the first-stage candidate of the proposal with the shared scales.
    ByScaledProposal,
    /// The state is now a candidate of another proposal (or of a later stage).
    ByOtherProposal,
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
