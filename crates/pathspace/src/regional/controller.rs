//! Regional adaptation (regional-adaptive paper, Alg. 1, eq. 4-6) with statistics shared by
//! all chains through the render loop's round hook, and quadtree refinement (section 6.2) at
//! those synchronisation points.

use mcmc_core::controller::SharedController;
use mcmc_core::controller::{AdaptState, RegionStats, ScaleAdaptParams};
use mcmc_core::{Controller, Partition, StepInfo};

use super::sigmas::{HasSharedSigmas, SharedSigmas};
use crate::error::PathspaceError;
use crate::path::Path;

/// Most visits a chain's controller keeps between two synchronisation points; further visits
/// of the round are not used for adaptation (a chain driven without a render loop never
/// synchronises and would otherwise grow without bound).
pub const MAX_VISITS_PER_ROUND: usize = 1 << 20;

/// Parameters of shared regional adaptation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionalAdaptParams {
    /// The sign rule of Alg. 1 per region: target acceptance `alpha*`, `L`, `gamma_max`,
    /// `gamma_scale`, `lambda_0`, `lambda_min` (its `freeze_after_updates` is not used here;
    /// see `freeze_after_mutations`).
    pub adapt: ScaleAdaptParams,
    /// `M_split`: at a refinement, split every leaf visited at least this many times since the
    /// previous refinement (section 6.2); `None` never refines (grids, or a frozen tree).
    pub split_after_visits: Option<u64>,
    /// `M_refine`: refine at the first synchronisation point after every this many mutations
    /// over all chains (section 6.2, 7).
    pub refine_every: u64,
    /// The mixture component that is the regional perturbation (0 in
    /// [`crate::ra_mixture`]): only its proposals update `lambda` (Alg. 1 is about the
    /// perturbation); visits for refinement count every step. `None`: every step is a
    /// perturbation (a kernel that is only the perturbation).
    pub perturbation_component: Option<usize>,
    /// Finite adaptation: stop adapting and refining at the first synchronisation point after
    /// this many mutations over all chains; `None` adapts forever (diminishing adaptation).
    /// `Some(0)` never adapts (the FIXED variant with the same code path).
    pub freeze_after_mutations: Option<u64>,
}

impl RegionalAdaptParams {
    /// The paper's values (section 8.1): `L = 10`, `gamma_max = 1`, `gamma_scale = 5`,
    /// `lambda_0 = 1`, `lambda_min = -30`, target acceptance 0.5 (the default of section 8.1;
    /// 0.8 for the Necklace scene), `M_split = 5000`, `M_refine = 10^7`; the perturbation is
    /// component 0 of [`crate::ra_mixture`]; diminishing adaptation (no freeze).
    #[must_use]
    pub const fn otsu2018() -> Self {
        Self {
            adapt: ScaleAdaptParams::otsu2018(),
            split_after_visits: Some(5000),
            refine_every: 10_000_000,
            perturbation_component: Some(0),
            freeze_after_mutations: None,
        }
    }

    /// The paper's parameters with `M_refine` and `M_split` scaled to a render of
    /// `total_mutations` (over all chains): the paper's `M_refine = 10^7` and `M_split = 5000`
    /// are tuned for about 10^9-10^10 mutations (10 minutes on 32 threads); we keep about 100
    /// refinement passes per render, `M_refine = max(total / 100, 1000)`, and the paper's
    /// ratio `M_split / M_refine = 5 * 10^-4` (a leaf splits once it gets 1/2000 of a pass's
    /// visits), with `M_split >= 4 L` so that every child can still be updated. Our choice: the
    /// paper gives no rule.
    #[must_use]
    pub const fn otsu2018_for_budget(total_mutations: u64) -> Self {
        let p = Self::otsu2018();
        let refine = total_mutations / 100;
        let refine = if refine < 1000 { 1000 } else { refine };
        let split = refine / 2000;
        let min_split = 4 * p.adapt.updates_every;
        Self {
            split_after_visits: Some(if split < min_split { min_split } else { split }),
            refine_every: refine,
            ..p
        }
    }

    /// Checks every field's range.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<(), PathspaceError> {
        self.adapt
            .validate()
            .map_err(|e| PathspaceError::InvalidParameter {
                name: "adapt",
                value: f64::NAN,
                allowed: e.to_string(),
            })?;
        PathspaceError::check_range("refine_every", self.refine_every as f64, 1.0, f64::MAX)?;
        if let Some(m) = self.split_after_visits {
            PathspaceError::check_range("split_after_visits", m as f64, 1.0, f64::MAX)?;
        }
        Ok(())
    }
}

impl Default for RegionalAdaptParams {
    fn default() -> Self {
        Self::otsu2018()
    }
}

/// One visit of a chain's state to a region, recorded between synchronisation points.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Visit {
    region: u32,
    perturbed: bool,
    accept: f64,
}

/// Regional adaptation of the perturbation's scale with statistics shared by all chains
/// (regional-adaptive paper, Alg. 1 and section 7), deterministic for any thread count.
///
/// Each chain's controller only *records* `(region of the current state, acceptance
/// probability)` for every step. At the end of every round of mcmc-core's render loop
/// ([`SharedController`]), the records of all chains are added **in job and chain order** to
/// one pooled set of Alg. 1 statistics `(i_k, A_k, n_k)` ([`PooledRegionalStats`]); then, at
/// that synchronisation point ([`SharedController::end_round`]), the due `lambda_k` updates
/// and a due quadtree refinement run, and every chain receives the new scales (an
/// [`std::sync::Arc`], no copy per chain). The paper shares the same statistics through
/// atomics and a lock per update instead, whose result depends on thread timing.
///
/// # Alg. 1 as implemented
/// Per region `k`, for each perturbation proposal from `k`: `A_k += alpha`, `i_k += 1`. At a
/// synchronisation point, every region with `i_k >= L` updates once:
/// `lambda_k += gamma_{n_k} sgn(A_k / i_k - alpha*)` (eq. 5: low acceptance *shrinks*
/// `lambda`; the prose's opposite reading is wrong), `gamma_n = min(gamma_max, gamma_scale
/// n^{-1/2})` (eq. 6; Alg. 1 line 15 is garbled), `lambda >= lambda_min`, then `i_k = A_k =
/// 0`, `n_k += 1`. The estimate divides by the visits counted (Alg. 1's `i_k > L` would sum
/// `L + 1` values and divide by `L`); fewer than `L` visits carry over to the next round
/// (they were observed at the same `lambda_k`, which only changes at an update).
///
/// # Staleness, and why one update per region per round
/// Within a round every chain proposes with the scales published at the round's start, so
/// all of a round's acceptances from region `k` were observed at the *same* `lambda_k`: they
/// are one estimate of the acceptance at that scale, and the controller makes one sign step
/// from it. (Applying a step for every `L` of them at the synchronisation point, as if they
/// had been observed after each other, overshoots: on the two-material test scene the scales
/// oscillated between 0.008 and 7 rad.) The price is speed: `n_k` counts synchronisation
/// points, not blocks of `L` visits, so scales settle after a few hundred rounds (`gamma_n`
/// reaches 0.3 after 250 updates); choose the render loop's `round_mutations` so that rounds
/// are frequent but regions still collect `L` visits per round or two. A round costs
/// O(visits + updated regions) plus, if any `lambda` changed, one copy of the `lambda` array
/// (8 bytes per region; the partition is copied only when refined). A refinement likewise
/// happens at the first synchronisation point after the `M_refine`-th mutation.
///
/// # Refinement (section 6.2)
/// At the first synchronisation point after every `M_refine` mutations (all chains): every
/// leaf visited at least `M_split` times since the previous refinement (every step counts a
/// visit of its current state) splits into four, once per pass (children are not considered
/// in the same pass); children inherit `lambda` and get `n = max(1, n_parent / 4)`,
/// `i = A = 0`; then all visit counters restart at 0 (our reading: the paper leaves it open,
/// practical path guiding resets per pass).
///
/// # Validity
/// Between synchronisation points every chain runs a fixed Metropolis-Hastings kernel whose
/// reverse density uses the scale of the *proposed* state's region (eq. 2-3), so each kernel
/// leaves `pi` invariant. Adaptation is *diminishing* (Roberts & Rosenthal 2007): `gamma_n ->
/// 0` in every region that keeps being visited; a split restarts its children at `n / 4`
/// (`gamma` doubles), but a quadtree of bounded depth splits finitely often, so `gamma` still
/// goes to 0. With `freeze_after_mutations` it is *finite* adaptation: after the freeze the
/// chain is a plain MH chain with fixed scales ([`Controller::is_frozen`]). `lambda` is bounded
/// below by `lambda_min`; above it is unbounded, but the kernel is continuous in `lambda` and
/// tends to the uniform-azimuth, truncated-normal kernel with `sigma -> inf` (almost uniform
/// `theta`), so large `lambda` is harmless.
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
pub struct SharedRegionalAdaptation {
    params: RegionalAdaptParams,
    visits: Vec<Visit>,
    current_region: usize,
    steps: u64,
    dropped: u64,
    frozen: bool,
}

impl SharedRegionalAdaptation {
    /// A chain's controller (every chain gets one with the same parameters).
    ///
    /// # Errors
    /// As [`RegionalAdaptParams::validate`].
    pub fn new(params: RegionalAdaptParams) -> Result<Self, PathspaceError> {
        params.validate()?;
        Ok(Self {
            params,
            visits: Vec::new(),
            current_region: 0,
            steps: 0,
            dropped: 0,
            frozen: params.freeze_after_mutations == Some(0),
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &RegionalAdaptParams {
        &self.params
    }

    /// Visits dropped because a round exceeded [`MAX_VISITS_PER_ROUND`].
    #[must_use]
    pub fn dropped_visits(&self) -> u64 {
        self.dropped
    }
}

impl<K> Controller<K, Path> for SharedRegionalAdaptation
where
    K: HasSharedSigmas,
    K::Partition: Partition<Path>,
{
    fn before_step(&mut self, kernel: &K, x: &Path) {
        if self.frozen {
            return;
        }
        if let Some(s) = kernel.shared_sigmas() {
            self.current_region = s.get().partition().region(x);
        }
    }

    fn after_step(&mut self, _kernel: &mut K, info: &StepInfo) {
        self.steps += 1;
        if self.frozen {
            return;
        }
        if self.visits.len() >= MAX_VISITS_PER_ROUND {
            self.dropped += 1;
            return;
        }
        let perturbed = self
            .params
            .perturbation_component
            .is_none_or(|c| c == info.component);
        self.visits.push(Visit {
            region: self.current_region as u32,
            perturbed,
            accept: info.accept_prob[0],
        });
    }

    fn is_frozen(&self) -> bool {
        self.frozen
    }
}

/// The statistics of [`SharedRegionalAdaptation`] pooled over all chains: the published
/// scales (partition and `lambda_k`) and Alg. 1's per-region state. It is the render loop's
/// `LoopOutput::shared` at the end of a run (the learned scales, e.g. for a heat map).
#[derive(Clone, Debug)]
pub struct PooledRegionalStats<P> {
    sigmas: Option<SharedSigmas<P>>,
    regions: Vec<RegionStats>,
    params: Option<RegionalAdaptParams>,
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

impl<P> Default for PooledRegionalStats<P> {
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

impl<P: Partition<Path> + Clone> PooledRegionalStats<P> {
    /// The published scales (`None` before the first synchronisation point).
    #[must_use]
    pub fn sigmas(&self) -> Option<&SharedSigmas<P>> {
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

    /// Leaves split over all passes.
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

    /// Starts pooling from the scales of the first chain (all chains must share them).
    fn init(&mut self, sigmas: &SharedSigmas<P>, params: RegionalAdaptParams) {
        self.regions = vec![
            RegionStats {
                adapt: AdaptState::new(),
                visits_since_refine: 0,
            };
            sigmas.get().num_regions()
        ];
        self.sigmas = Some(sigmas.clone());
        self.params = Some(params);
        self.next_refine = params.refine_every;
        self.updates_every = params.adapt.updates_every;
        self.frozen = params.freeze_after_mutations == Some(0);
    }

    /// Adds one chain's visits of the round, in order (Alg. 1 lines 11-12).
    fn apply(&mut self, visits: &[Visit], steps: u64) {
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
        let scales = sigmas.make_mut();
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
            let lambda = (scales.lambdas()[k] + p.gamma(a.updates) * sign).max(p.lambda_min);
            scales.set_lambda(k, lambda);
            a.visits = 0;
            a.accepted = 0.0;
            a.updates += 1;
        }
        self.due.clear();
    }

    /// The synchronisation point, after every chain contributed its round (what
    /// [`SharedController::end_round`] runs): freeze if due, else refine if due (section 6.2).
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
        if self.regions[..before]
            .iter()
            .any(|r| r.visits_since_refine >= threshold)
        {
            let scales = sigmas.make_mut();
            // Only the leaves that existed before the pass are candidates (section 6.2).
            for k in 0..before {
                let parent = self.regions[k];
                if parent.visits_since_refine < threshold || scales.split(k).is_none() {
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
                self.regions.resize(scales.num_regions(), child);
                self.splits += 1;
            }
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

impl<K> SharedController<K> for SharedRegionalAdaptation
where
    K: HasSharedSigmas,
    K::Partition: Partition<Path> + Clone + Send + Sync + std::fmt::Debug,
{
    type Shared = PooledRegionalStats<K::Partition>;

    fn contribute(&mut self, kernel: &mut K, pooled: &mut Self::Shared) {
        if pooled.sigmas.is_none() {
            if let Some(s) = kernel.shared_sigmas() {
                pooled.init(s, self.params);
            }
        }
        pooled.apply(&self.visits, self.steps);
        self.visits.clear();
        self.steps = 0;
    }

    fn receive(&mut self, kernel: &mut K, pooled: &Self::Shared) {
        if let (Some(s), Some(mine)) = (&pooled.sigmas, kernel.shared_sigmas_mut()) {
            if !mine.ptr_eq(s) {
                *mine = s.clone();
            }
        }
        self.frozen = pooled.frozen;
    }

    fn end_round(pooled: &mut Self::Shared) {
        pooled.end_round();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_scaling_keeps_the_papers_ratio() {
        let p = RegionalAdaptParams::otsu2018_for_budget(1_000_000_000);
        assert_eq!(p.refine_every, 10_000_000);
        assert_eq!(p.split_after_visits, Some(5000));
        let small = RegionalAdaptParams::otsu2018_for_budget(10_000);
        assert_eq!(small.refine_every, 1000);
        assert_eq!(small.split_after_visits, Some(40));
        assert!(small.validate().is_ok());
        let bad = RegionalAdaptParams {
            refine_every: 0,
            ..RegionalAdaptParams::otsu2018()
        };
        assert!(SharedRegionalAdaptation::new(bad).is_err());
    }
}
