//! The statistics of regional scale adaptation pooled over all chains, and the work done on
//! them at a synchronisation point: the `lambda_k` updates of Alg. 1 and refinement.

use super::region_table::RegionTable;
use super::regional_params::{RegionalScaleParams, RegionalUpdateRule};
use super::regional_scale::RegionStats;
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
    regions: RegionTable,
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
    /// The round's visits of every chain, in job and chain order, replayed at the
    /// synchronisation point.
    pending: Vec<Visit>,
}

impl<Sc> Default for PooledRegionalScales<Sc> {
    fn default() -> Self {
        Self {
            sigmas: None,
            regions: RegionTable::default(),
            params: None,
            mutations: 0,
            next_refine: 0,
            refinements: 0,
            splits: 0,
            rounds: 0,
            frozen: false,
            updates_every: u64::MAX,
            due: Vec::new(),
            pending: Vec::new(),
        }
    }
}

impl<Sc: SharedRegionalScales> PooledRegionalScales<Sc> {
    /// The published scales (`None` before the first synchronisation point).
    #[must_use]
    pub fn sigmas(&self) -> Option<&Sc> {
        self.sigmas.as_ref()
    }

    /// Alg. 1's state of region `k` and its visits since the last refinement, as of the last
    /// synchronisation point.
    #[must_use]
    pub fn region_stats(&self, k: usize) -> Option<RegionStats> {
        self.regions.get(k)
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
        self.regions = RegionTable::new(sigmas.num_regions());
        self.sigmas = Some(sigmas.clone());
        self.params = Some(params);
        self.next_refine = params.refine_every;
        self.updates_every = params.adapt.updates_every;
        self.frozen = params.freeze_after_mutations == Some(0);
    }

    /// Adds one chain's visits of the round, in order, to the round's record; they are
    /// replayed at the synchronisation point ([`Self::end_round`]) in the order the chains
    /// contributed them.
    pub(super) fn apply(&mut self, visits: &[Visit], steps: u64) {
        self.mutations += steps;
        if self.sigmas.is_some() && self.params.is_some() && !self.frozen {
            self.pending.extend_from_slice(visits);
        }
    }

    /// Replays the round's visits, in order (Alg. 1 lines 11-18).
    ///
    /// With [`RegionalUpdateRule::EveryLVisits`] every `L`-th proposal from a region makes
    /// its sign step here, with the `lambda` left by the previous step: the pooled records,
    /// fed chain after chain in job order, go through exactly the sequential rule
    /// ([`super::AdaptState::record`]). With [`RegionalUpdateRule::OncePerRound`] the region
    /// is only marked due and steps once at [`Self::update_scales`].
    ///
    /// The visited regions' states are first read all at once
    /// ([`RegionTable::touch`]), so that a partition with many regions (the 4-D grid's 10^6,
    /// whose states do not stay in the cache) waits for their cache misses side by side
    /// rather than one visit after another; the updates then follow in order.
    fn replay(&mut self) {
        let visits = std::mem::take(&mut self.pending);
        let (Some(sigmas), Some(params)) = (self.sigmas.as_mut(), self.params.as_ref()) else {
            return;
        };
        self.regions.touch(visits.iter().map(|v| v.region as usize));
        let every_l = params.update_rule == RegionalUpdateRule::EveryLVisits;
        let updates_every = self.updates_every;
        for v in &visits {
            let k = v.region as usize;
            let due = self.regions.update(k, |state| {
                state.visits_since_refine += 1;
                if !v.perturbed {
                    return false;
                }
                state.note_proposal(v.accept);
                if every_l {
                    let lambda = sigmas.log_scale_of(k);
                    if let Some(new) = state.adapt.record(v.accept, lambda, &params.adapt) {
                        if new != lambda {
                            sigmas.set_log_scale_of(k, new);
                        }
                    }
                    false
                } else {
                    state.adapt.visits += 1;
                    state.adapt.accepted += v.accept;
                    state.adapt.visits == updates_every
                }
            });
            match due {
                Some(true) => self.due.push(v.region),
                Some(false) => {}
                None => debug_assert!(false, "visit to region {k} of {}", self.regions.len()),
            }
        }
        // Keep the buffer's capacity for the next round.
        self.pending = visits;
        self.pending.clear();
    }

    /// [`RegionalUpdateRule::OncePerRound`]: Alg. 1 lines 13-18 at the synchronisation point,
    /// once per region that has at least `L` visits: `lambda_k += gamma_{n_k} sgn(A_k / i_k -
    /// alpha*)` (eq. 5, 6), clamped to `lambda_min`; `i_k = A_k = 0`, `n_k += 1`.
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
            self.regions.update(k, |state| {
                let lambda = state.adapt.update(sigmas.log_scale_of(k), p);
                sigmas.set_log_scale_of(k, lambda);
            });
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
            self.pending.clear();
            return;
        }
        self.replay();
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
        let cap = params.max_regions.unwrap_or(usize::MAX);
        for k in 0..before {
            let Some(parent) = self.regions.get(k) else {
                continue;
            };
            if parent.visits_since_refine < threshold
                || sigmas.num_regions().saturating_add(3) > cap
                || sigmas.split_region(k).is_none()
            {
                continue;
            }
            let mut child = RegionStats::new();
            child.adapt.updates = (parent.adapt.updates / 4).max(1);
            child.recent_acceptance = parent.recent_acceptance;
            let fresh = self.regions.len();
            self.regions.set(k, child);
            self.regions.grow(sigmas.num_regions());
            for id in fresh..self.regions.len() {
                self.regions.set(id, child);
            }
            self.splits += 1;
        }
        self.regions.clear_refinement_visits();
        self.refinements += 1;
        while self.next_refine <= self.mutations {
            self.next_refine += params.refine_every;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::{AdaptState, RegionalScaleParams, RegionalUpdateRule};
    use rand::{RngExt, SeedableRng};
    use std::sync::Arc;

    /// Per-region scales behind an `Arc`, copy-on-write.
    #[derive(Clone, Debug)]
    struct Scales(Arc<Vec<f64>>);

    impl SharedRegionalScales for Scales {
        type Partition = ();
        fn partition(&self) -> &() {
            &()
        }
        fn num_regions(&self) -> usize {
            self.0.len()
        }
        fn log_scale_of(&self, region: usize) -> f64 {
            self.0[region]
        }
        fn set_log_scale_of(&mut self, region: usize, lambda: f64) {
            Arc::make_mut(&mut self.0)[region] = lambda;
        }
        fn split_region(&mut self, _region: usize) -> Option<std::ops::Range<usize>> {
            None
        }
        fn same_as(&self, other: &Self) -> bool {
            Arc::ptr_eq(&self.0, &other.0)
        }
    }

    const REGIONS: usize = 5;

    /// A recorded acceptance sequence: `rounds x chains` blocks of visits; region 0 is visited
    /// far more often than the others (as GLOBAL's single region is), acceptance depends on
    /// the region.
    fn record(rounds: usize, chains: usize, per_chain: usize) -> Vec<Vec<Vec<Visit>>> {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        (0..rounds)
            .map(|_| {
                (0..chains)
                    .map(|_| {
                        (0..per_chain)
                            .map(|_| {
                                let u: f64 = rng.random();
                                let region = if u < 0.6 { 0 } else { (u * 10.0) as u32 % 5 };
                                Visit {
                                    region,
                                    perturbed: rng.random::<f64>() < 0.5,
                                    accept: rng.random::<f64>().powf(1.0 + f64::from(region)),
                                }
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect()
    }

    /// The pool's scales after feeding `rec` round by round, chain by chain.
    fn pooled(rec: &[Vec<Vec<Visit>>], rule: RegionalUpdateRule) -> (Vec<f64>, Vec<u64>) {
        let params = RegionalScaleParams {
            split_after_visits: None,
            update_rule: rule,
            ..RegionalScaleParams::otsu2018()
        };
        let mut pool = PooledRegionalScales::default();
        pool.init(&Scales(Arc::new(vec![1.0; REGIONS])), params);
        for round in rec {
            for chain in round {
                pool.apply(chain, chain.len() as u64);
            }
            pool.end_round();
        }
        let s = pool.sigmas().unwrap();
        (
            (0..REGIONS).map(|k| s.log_scale_of(k)).collect(),
            (0..REGIONS)
                .map(|k| pool.region_stats(k).unwrap().adapt.updates)
                .collect(),
        )
    }

    /// Alg. 1 run sequentially over the concatenated record: one `AdaptState` and one
    /// `lambda` per region, a step every `L` proposals from the region.
    fn sequential(rec: &[Vec<Vec<Visit>>]) -> (Vec<f64>, Vec<u64>) {
        let p = RegionalScaleParams::otsu2018().adapt;
        let mut lambda = vec![1.0; REGIONS];
        let mut state = [AdaptState::new(); REGIONS];
        for v in rec.iter().flatten().flatten().filter(|v| v.perturbed) {
            let k = v.region as usize;
            if let Some(new) = state[k].record(v.accept, lambda[k], &p) {
                lambda[k] = new;
            }
        }
        (lambda, state.iter().map(|s| s.updates).collect())
    }

    #[test]
    fn pooled_steps_equal_the_sequential_rule_on_the_same_record() {
        let rec = record(30, 8, 25);
        let (seq_lambda, seq_n) = sequential(&rec);
        let (lambda, n) = pooled(&rec, RegionalUpdateRule::EveryLVisits);
        assert_eq!(n, seq_n);
        for (a, b) in lambda.iter().zip(&seq_lambda) {
            assert_eq!(a.to_bits(), b.to_bits(), "{lambda:?} vs {seq_lambda:?}");
        }
        // The same concatenated record cut into other rounds and chains: the same scales
        // (what makes them independent of the thread count).
        let flat: Vec<Visit> = rec.iter().flatten().flatten().copied().collect();
        let recut: Vec<Vec<Vec<Visit>>> = flat
            .chunks(120)
            .map(|round| round.chunks(7).map(<[Visit]>::to_vec).collect())
            .collect();
        assert_eq!(pooled(&recut, RegionalUpdateRule::EveryLVisits).0, lambda);
        // Region 0 makes about 0.6 * 0.5 * 6000 / L = 180 steps.
        assert!(seq_n[0] > 150, "{seq_n:?}");
    }

    #[test]
    fn once_per_round_rule_is_not_the_sequential_rule() {
        // Negative control: the rule of one step per region per round fails the same check.
        let rec = record(30, 8, 25);
        let (seq_lambda, seq_n) = sequential(&rec);
        let (lambda, n) = pooled(&rec, RegionalUpdateRule::OncePerRound);
        assert_ne!(n, seq_n);
        assert_ne!(lambda, seq_lambda);
        // It makes at most one step per round: n_0 <= rounds + 1.
        assert!(n[0] <= 31, "{n:?}");
    }
}
