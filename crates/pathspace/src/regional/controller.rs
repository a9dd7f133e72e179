//! Regional adaptation of path perturbations (regional-adaptive paper, Alg. 1, eq. 4-6, section
//! 6.2 refinement, section 7 sharing): mcmc-core's shared regional controller
//! ([`mcmc_core::controller::RegionalScale`]) on the scales of [`SharedSigmas`].
//!
//! The statistics, the pooled updates and refinement live in mcmc-core; this file only connects
//! them to path-space kernels ([`HasSharedSigmas`]) and keeps this crate's names and error type.

use mcmc_core::controller::{
    PooledRegionalScales, RegionStats, RegionalScale, RegionalScaleParams, SharedController,
};
use mcmc_core::{Controller, McmcError, Partition, StepInfo};

use super::sigmas::{HasSharedSigmas, SharedSigmas};
use crate::error::PathspaceError;
use crate::path::Path;

pub use mcmc_core::controller::{RegionalUpdateRule, MAX_VISITS_PER_ROUND};

/// Parameters of shared regional adaptation: mcmc-core's [`RegionalScaleParams`] (the paper's
/// values are [`RegionalScaleParams::otsu2018`]; the scaled proposal is component 0 of
/// [`crate::ra_mixture`]).
pub type RegionalAdaptParams = RegionalScaleParams;

/// Regional adaptation of the perturbation's scale with statistics shared by all chains
/// (regional-adaptive paper, Alg. 1 and section 7), deterministic for any thread count:
/// mcmc-core's [`RegionalScale`] (see there for Alg. 1 as implemented, staleness, refinement
/// and validity) reading regions from and publishing scales to the [`SharedSigmas`] of the
/// kernel's perturbation.
///
/// # Example
/// ```
/// use pathspace::regional::{RegionalAdaptParams, SharedRegionalAdaptation};
///
/// let params = RegionalAdaptParams {
///     split_after_visits: Some(200),
///     refine_every: 20_000,
///     ..RegionalAdaptParams::otsu2018()
/// };
/// let controller = SharedRegionalAdaptation::new(params).unwrap();
/// assert_eq!(controller.params().adapt.updates_every, 10);
/// ```
/// The module documentation synchronises a chain by hand; `tests/regional_loop.rs` runs the
/// controller through mcmc-core's `RenderLoop`.
#[derive(Clone, Debug)]
pub struct SharedRegionalAdaptation(RegionalScale);

impl SharedRegionalAdaptation {
    /// A chain's controller (every chain gets one with the same parameters).
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] naming the first field out of range
    /// ([`RegionalScaleParams::validate`]).
    pub fn new(params: RegionalAdaptParams) -> Result<Self, PathspaceError> {
        RegionalScale::new(params).map(Self).map_err(|e| match e {
            McmcError::InvalidParameter {
                name,
                value,
                allowed,
            } => PathspaceError::InvalidParameter {
                name,
                value,
                allowed: allowed.to_string(),
            },
            other => PathspaceError::InvalidParameter {
                name: "adapt",
                value: f64::NAN,
                allowed: other.to_string(),
            },
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &RegionalAdaptParams {
        self.0.params()
    }

    /// Visits dropped because a round exceeded [`MAX_VISITS_PER_ROUND`].
    #[must_use]
    pub fn dropped_visits(&self) -> u64 {
        self.0.dropped_visits()
    }
}

impl<K> Controller<K, Path> for SharedRegionalAdaptation
where
    K: HasSharedSigmas,
    K::Partition: Partition<Path> + Clone,
{
    fn before_step(&mut self, kernel: &K, x: &Path) {
        self.0.observe(kernel.shared_sigmas(), x);
    }

    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        self.0.record(kernel.shared_sigmas(), info);
    }

    fn is_frozen(&self) -> bool {
        self.0.is_frozen()
    }
}

/// The statistics of [`SharedRegionalAdaptation`] pooled over all chains: the published
/// scales (partition and `lambda_k`) and Alg. 1's per-region state (mcmc-core's
/// [`PooledRegionalScales`] over [`SharedSigmas`]). It is the render loop's
/// `LoopOutput::shared` at the end of a run (the learned scales, e.g. for a heat map).
#[derive(Clone, Debug)]
pub struct PooledRegionalStats<P>(PooledRegionalScales<SharedSigmas<P>>);

impl<P> Default for PooledRegionalStats<P> {
    fn default() -> Self {
        Self(PooledRegionalScales::default())
    }
}

impl<P: Partition<Path> + Clone> PooledRegionalStats<P> {
    /// The published scales (`None` before the first synchronisation point).
    #[must_use]
    pub fn sigmas(&self) -> Option<&SharedSigmas<P>> {
        self.0.sigmas()
    }

    /// Alg. 1's state of region `k` and its visits since the last refinement.
    #[must_use]
    pub fn region_stats(&self, k: usize) -> Option<RegionStats> {
        self.0.region_stats(k)
    }

    /// Number of regions.
    #[must_use]
    pub fn num_regions(&self) -> usize {
        self.0.num_regions()
    }

    /// Mutations of all chains pooled so far.
    #[must_use]
    pub fn mutations(&self) -> u64 {
        self.0.mutations()
    }

    /// Refinement passes run.
    #[must_use]
    pub fn refinements(&self) -> u64 {
        self.0.refinements()
    }

    /// Leaves split over all passes.
    #[must_use]
    pub fn splits(&self) -> u64 {
        self.0.splits()
    }

    /// Synchronisation points seen.
    #[must_use]
    pub fn rounds(&self) -> u64 {
        self.0.rounds()
    }

    /// True once adaptation has stopped (`freeze_after_mutations`).
    #[must_use]
    pub fn is_frozen(&self) -> bool {
        self.0.is_frozen()
    }

    /// The synchronisation point, after every chain contributed its round (what
    /// [`SharedController::end_round`] runs): the due scale updates, then freeze if due, else
    /// refine if due (section 6.2).
    pub fn end_round(&mut self) {
        self.0.end_round();
    }
}

impl<K> SharedController<K> for SharedRegionalAdaptation
where
    K: HasSharedSigmas,
    K::Partition: Partition<Path> + Clone + Send + Sync + std::fmt::Debug,
{
    type Shared = PooledRegionalStats<K::Partition>;

    fn contribute(&mut self, kernel: &mut K, pooled: &mut Self::Shared) {
        self.0
            .contribute_scales(kernel.shared_sigmas(), &mut pooled.0);
    }

    fn receive(&mut self, kernel: &mut K, pooled: &Self::Shared) {
        self.0.receive_scales(kernel.shared_sigmas_mut(), &pooled.0);
    }

    fn end_round(pooled: &mut Self::Shared) {
        pooled.end_round();
    }
}
