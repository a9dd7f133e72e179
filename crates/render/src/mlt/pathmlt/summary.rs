//! What pathmlt's regional adaptation did in one render: regions, rounds, refinements, the
//! learned scales and how close each region's acceptance came to the target.

use pathspace::regional::{PooledRegionalStats, RegionalAdaptParams};

use super::adapt::{AdaptPartition, PathAdapt};

/// A region counts as *visited* in [`AdaptSummary`] once it made at least this many
/// perturbation proposals (20 sign steps of `L = 10`): enough for its recent acceptance
/// (mcmc-core's `RegionStats::recent_acceptance`, a mean over about 200 proposals) to be
/// measured to about 0.03.
pub const VISITED_PROPOSALS: u64 = 200;

/// Half-width of the band around the target acceptance counted by
/// [`AdaptSummary::near_target`].
pub const ACCEPTANCE_TOLERANCE: f64 = 0.1;

/// What regional adaptation did in one render (Otsu et al. 2018, section 6): its regions,
/// rounds, refinements, the learned `sigma_1` over the regions that were updated, and the
/// regions whose recent acceptance is near the target.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdaptSummary {
    /// The adaptation variant.
    pub adapt: PathAdapt,
    /// False if no synchronisation point was reached (nothing was learned).
    pub synchronised: bool,
    /// Regions of the final partition.
    pub regions: usize,
    /// Regions whose scale was updated more than once.
    pub updated: usize,
    /// Synchronisation rounds.
    pub rounds: u64,
    /// Refinement passes (RA-QUADTREE, section 6.2).
    pub refinements: u64,
    /// Leaves split over all refinements.
    pub splits: u64,
    /// The learned `sigma_1` (radians) over the updated regions: minimum, median (the
    /// nearest-rank one) and maximum; NaN when no region was updated.
    pub sigma_min: f64,
    /// See [`AdaptSummary::sigma_min`].
    pub sigma_median: f64,
    /// See [`AdaptSummary::sigma_min`].
    pub sigma_max: f64,
    /// The initial scale (radians).
    pub sigma_initial: f64,
    /// The target acceptance `alpha*`.
    pub target_acceptance: f64,
    /// Regions with at least [`VISITED_PROPOSALS`] perturbation proposals.
    pub visited: usize,
    /// Visited regions whose recent acceptance is within [`ACCEPTANCE_TOLERANCE`] of the
    /// target.
    pub near_target: usize,
}

impl AdaptSummary {
    /// The summary of the pooled statistics of `adapt` run with `params`.
    pub(super) fn of(
        adapt: PathAdapt,
        params: &RegionalAdaptParams,
        pooled: &PooledRegionalStats<AdaptPartition<'_>>,
    ) -> Self {
        let mut summary = Self {
            adapt,
            synchronised: false,
            regions: pooled.num_regions(),
            updated: 0,
            rounds: pooled.rounds(),
            refinements: pooled.refinements(),
            splits: pooled.splits(),
            sigma_min: f64::NAN,
            sigma_median: f64::NAN,
            sigma_max: f64::NAN,
            sigma_initial: (0.5 * params.adapt.lambda_initial).exp(),
            target_acceptance: params.adapt.target_acceptance,
            visited: 0,
            near_target: 0,
        };
        let Some(sigmas) = pooled.sigmas() else {
            return summary;
        };
        let mut updated: Vec<f64> = (0..pooled.num_regions())
            .filter(|&k| pooled.region_stats(k).is_some_and(|r| r.adapt.updates > 1))
            .map(|k| sigmas.get().sigmas_of_region(k)[0])
            .collect();
        updated.sort_by(f64::total_cmp);
        let q = |f: f64| {
            updated
                .get(((updated.len().max(1) - 1) as f64 * f).round() as usize)
                .copied()
                .unwrap_or(f64::NAN)
        };
        for k in 0..pooled.num_regions() {
            let Some(r) = pooled.region_stats(k) else {
                continue;
            };
            if r.proposals >= VISITED_PROPOSALS {
                summary.visited += 1;
                if (r.recent_acceptance - summary.target_acceptance).abs() <= ACCEPTANCE_TOLERANCE {
                    summary.near_target += 1;
                }
            }
        }
        summary.synchronised = true;
        summary.updated = updated.len();
        (summary.sigma_min, summary.sigma_median, summary.sigma_max) = (q(0.0), q(0.5), q(1.0));
        summary
    }

    /// The share of visited regions whose recent acceptance is within
    /// [`ACCEPTANCE_TOLERANCE`] of the target (NaN if none was visited).
    #[must_use]
    pub fn near_target_share(&self) -> f64 {
        if self.visited == 0 {
            f64::NAN
        } else {
            self.near_target as f64 / self.visited as f64
        }
    }

    /// One line for people on the learned scales: regions, refinements, `sigma` over the
    /// regions that were updated at least once, and the acceptance diagnostic (the render's
    /// note).
    #[must_use]
    pub fn note(&self) -> String {
        let name = self.adapt.name();
        if !self.synchronised {
            return format!("--adapt {name}: no synchronisation point reached");
        }
        if self.updated == 0 {
            return format!(
                "--adapt {name}: {} regions, none updated in {} rounds (sigma stays {:.4} rad)",
                self.regions, self.rounds, self.sigma_initial
            );
        }
        format!(
            "--adapt {name}: {} regions ({} updated), {} rounds, {} refinements, {} splits; learned sigma (rad) min {:.3e}, median {:.3e}, max {:.3e} (from {:.4}); acceptance within {} +- {} in {} of {} regions with >= {} proposals",
            self.regions,
            self.updated,
            self.rounds,
            self.refinements,
            self.splits,
            self.sigma_min,
            self.sigma_median,
            self.sigma_max,
            self.sigma_initial,
            self.target_acceptance,
            ACCEPTANCE_TOLERANCE,
            self.near_target,
            self.visited,
            VISITED_PROPOSALS
        )
    }
}
