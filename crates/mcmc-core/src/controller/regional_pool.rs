//! The statistics of regional scale adaptation pooled over all chains, and the work done on
//! them at a synchronisation point: the `lambda_k` updates of Alg. 1 and refinement.

use super::regional_scale::{RegionStats, RegionalScaleParams};
use super::AdaptState;
use crate::tunable::SharedRegionalScales;

/// One visit of a chain's state to a region, recorded between synchronisation points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Visit {
    pub(super) region: u32,
    pub(super) perturbed: bool,
    pub(super) accept: f64,
}

/// The statistics of [`super::RegionalScale`] pooled over all chains: the published scales
/// (a [`SharedRegionalScales`] handle) and Alg. 1's per-region state. It is the render loop's
/// pooled output at the end of a run (the learned scales, e.g. for a heat map).
#[derive(Clone, Debug)]
pub struct PooledRegionalScales<Sc> {
    sigmas: Option<Sc>,
    regions: Vec<RegionStats>,
    params: Option<RegionalScaleParams>,
    mutations: u64,
    next_refine: u64,
    refinements: u64,
    splits: u64,
    rounds: u64,
    frozen: bool,
    /// `L` (copied from the parameters).
    updates_every: u64,
    /// Regions whose visit count reached `L` this round (updated at the synchronisation
    /// point, so a round costs O(visited regions), not O(regions)).
    due: Vec<u32>,
}

impl<Sc> Default for PooledRegionalScales<Sc> {
    fn default() -> Self {
        Self {
            sigmas: None,
            regions: Vec::new(),
            params: None,
            mutations: 0,
            next_refine: 0,
            refinements: 0,
            splits: 0,
            rounds: 0,
            frozen: false,
            updates_every: u64::MAX,
            due: Vec::new(),
        }
    }
}

impl<Sc: SharedRegionalScales> PooledRegionalScales<Sc> {
    /// The published scales (`None` before the first synchronisation point).
    #[must_use]
    pub fn sigmas(&self) -> Option<&Sc> {
        self.sigmas.as_ref()
    }

    /// Alg. 1's state of region `k` and its visits since the last refinement.
    #[must_use]
    pub fn region_stats(&self, k: usize) -> Option<RegionStats> {
        self.regions.get(k).copied()
    }

    /// Number of regions.
    #[must_use]
    pub fn num_regions(&self) -> usize {
        self.regions.len()
    }

    /// Mutations of all chains pooled so far.
    #[must_use]
    pub fn mutations(&self) -> u64 {
        self.mutations
    }

    /// Refinement passes run.
    #[must_use]
    pub fn refinements(&self) -> u64 {
        self.refinements
    }

    /// Regions split over all passes.
    #[must_use]
    pub fn splits(&self) -> u64 {
        self.splits
    }

    /// Synchronisation points seen.
    #[must_use]
    pub fn rounds(&self) -> u64 {
        self.rounds
    }

    /// True once adaptation has stopped (`freeze_after_mutations`).
    #[must_use]
    pub fn is_frozen(&self) -> bool {
        self.frozen
    }

    /// True once the pool holds scales (after the first contribution of a chain with them).
    pub(super) fn is_started(&self) -> bool {
        self.sigmas.is_some()
    }

    /// Starts pooling from the scales of the first chain (all chains must share them).
    pub(super) fn init(&mut self, sigmas: &Sc, params: RegionalScaleParams) {
        self.regions = vec![
            RegionStats {
                adapt: AdaptState::new(),
                visits_since_refine: 0,
            };
            sigmas.num_regions()
        ];
        self.sigmas = Some(sigmas.clone());
        self.params = Some(params);
        self.next_refine = params.refine_every;
        self.updates_every = params.adapt.updates_every;
        self.frozen = params.freeze_after_mutations == Some(0);
    }

    /// Adds one chain's visits of the round, in order (Alg. 1 lines 11-12).
    pub(super) fn apply(&mut self, visits: &[Visit], steps: u64) {
        self.mutations += steps;
        if self.sigmas.is_none() || self.frozen {
            return;
        }
        for v in visits {
            let k = v.region as usize;
            let Some(state) = self.regions.get_mut(k) else {
                debug_assert!(false, "visit to region {k} of {}", self.regions.len());
                continue;
            };
            state.visits_since_refine += 1;
            if v.perturbed {
                state.adapt.visits += 1;
                state.adapt.accepted += v.accept;
                if state.adapt.visits == self.updates_every {
                    self.due.push(v.region);
                }
            }
        }
    }

    /// Alg. 1 lines 13-18 at the synchronisation point, once per region that has at least `L`
    /// visits: `lambda_k += gamma_{n_k} sgn(A_k / i_k - alpha*)` (eq. 5, 6), clamped to
    /// `lambda_min`; `i_k = A_k = 0`, `n_k += 1`.
    fn update_scales(&mut self) {
        let (Some(sigmas), Some(params)) = (self.sigmas.as_mut(), self.params) else {
            return;
        };
        let p = &params.adapt;
        if self.due.is_empty() {
            return;
        }
        // Regions are independent: the order of `due` does not matter.
        for &k in &self.due {
            let k = k as usize;
            let a = &mut self.regions[k].adapt;
            let rate = a.accepted / a.visits as f64;
            let sign = if rate > p.target_acceptance {
                1.0
            } else if rate < p.target_acceptance {
                -1.0
            } else {
                0.0
            };
            let lambda = (sigmas.log_scale_of(k) + p.gamma(a.updates) * sign).max(p.lambda_min);
            sigmas.set_log_scale_of(k, lambda);
            a.visits = 0;
            a.accepted = 0.0;
            a.updates += 1;
        }
        self.due.clear();
    }

    /// The synchronisation point, after every chain contributed its round (what
    /// [`super::SharedController::end_round`] runs): the due scale updates, then freeze if
    /// due, else refine if due (section 6.2).
    pub fn end_round(&mut self) {
        self.rounds += 1;
        let (true, Some(params)) = (self.sigmas.is_some(), self.params) else {
            return;
        };
        if self.frozen {
            return;
        }
        self.update_scales();
        let Some(sigmas) = self.sigmas.as_mut() else {
            return;
        };
        if params
            .freeze_after_mutations
            .is_some_and(|f| self.mutations >= f)
        {
            self.frozen = true;
            return;
        }
        let Some(threshold) = params.split_after_visits else {
            return;
        };
        if self.mutations < self.next_refine {
            return;
        }
        let before = self.regions.len();
        // Only the regions that existed before the pass are candidates (section 6.2).
        for k in 0..before {
            let parent = self.regions[k];
            if parent.visits_since_refine < threshold || sigmas.split_region(k).is_none() {
                continue;
            }
            let child = RegionStats {
                adapt: AdaptState {
                    visits: 0,
                    accepted: 0.0,
                    updates: (parent.adapt.updates / 4).max(1),
                },
                visits_since_refine: 0,
            };
            self.regions[k] = child;
            self.regions.resize(sigmas.num_regions(), child);
            self.splits += 1;
        }
        for r in &mut self.regions {
            r.visits_since_refine = 0;
        }
        self.refinements += 1;
        while self.next_refine <= self.mutations {
            self.next_refine += params.refine_every;
        }
    }
}
