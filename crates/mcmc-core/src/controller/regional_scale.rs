//! Regional scale adaptation (regional-adaptive paper, Alg. 1, eq. 4-6) with statistics shared
//! by all chains at the synchronisation points of a render loop: the per-chain recorder.

use super::regional_params::RegionalScaleParams;
#[cfg(doc)]
use super::regional_params::RegionalUpdateRule;
use super::regional_pool::{PooledRegionalScales, Visit};
use super::{AdaptState, Controller, SharedController};
use crate::kernel::StepInfo;
use crate::partition::Partition;
use crate::tunable::{HasSharedScales, SharedRegionalScales, StateMove};
use crate::McmcError;

/// Most visits a chain's controller keeps between two synchronisation points; further visits
/// of the round are not used for adaptation (a chain driven without a render loop never
/// synchronises and would otherwise grow without bound).
pub const MAX_VISITS_PER_ROUND: usize = 1 << 20;

/// Regional adaptation of a proposal's scale with statistics shared by all chains
/// (regional-adaptive paper, Alg. 1 and section 7), deterministic for any thread count.
///
/// The kernel reads `lambda_k` per region from a [`SharedRegionalScales`] handle
/// ([`HasSharedScales`]). Each chain's controller only *records* `(region of the current
/// state, acceptance probability)` for every step. At the end of every round of a render loop
/// ([`SharedController`]), the records of all chains are added **in job and chain order** to
/// one pooled set of Alg. 1 statistics `(i_k, A_k, n_k)` ([`PooledRegionalScales`]); then, at
/// that synchronisation point ([`SharedController::end_round`]), the due `lambda_k` updates
/// and a due refinement run, and every chain receives the new scales (the handle, no copy per
/// chain). The paper shares the same statistics through atomics and a lock per update
/// instead, whose result depends on thread timing.
///
/// # Alg. 1 as implemented
/// Per region `k`, for each proposal of the scaled component from `k`: `A_k += alpha`,
/// `i_k += 1`; when `i_k = L`: `lambda_k += gamma_{n_k} sgn(A_k / i_k - alpha*)` (eq. 5: low
/// acceptance *shrinks* `lambda`; the prose's opposite reading is wrong), `gamma_n =
/// min(gamma_max, gamma_scale n^{-1/2})` (eq. 6; Alg. 1 line 15 is garbled), `lambda >=
/// lambda_min`, then `i_k = A_k = 0`, `n_k += 1`. The estimate divides by the visits counted
/// (Alg. 1's `i_k > L` would sum `L + 1` values and divide by `L`).
///
/// # Paper speed, deterministically
/// Chains record during a round and the pool replays the records at the synchronisation
/// point, chain after chain in job order, through the sequential rule
/// ([`RegionalUpdateRule::EveryLVisits`], the default): every block of `L` proposals makes one
/// step, so `n_k` counts blocks of `L` visits as in the paper, and the scales after a round
/// are a function of the pooled acceptance record alone (the same for any thread count).
/// The difference from a single sequential chain is staleness: a round's proposals from
/// region `k` were all made with the `lambda_k` published at its start. With `v_k` proposals
/// per round from `k`, the lag is `v_k / L` steps; keep rounds short (the render loop's
/// `round_mutations`) so that it stays a few steps. [`RegionalUpdateRule::OncePerRound`]
/// makes at most one step per region per round instead (`n_k` counts rounds). A round costs
/// O(visits + updated regions); each update writes one `lambda` through the handle.
///
/// # Refinement (section 6.2)
/// At the first synchronisation point after every `M_refine` mutations (all chains): every
/// region visited at least `M_split` times since the previous refinement (every step counts a
/// visit of its current state) splits ([`SharedRegionalScales::split_region`]), once per pass
/// (children are not considered in the same pass); children inherit `lambda` and get
/// `n = max(1, n_parent / 4)`, `i = A = 0`; then all visit counters restart at 0 (our
/// reading: the paper leaves it open).
///
/// # Validity
/// Between synchronisation points every chain runs a fixed Metropolis-Hastings kernel; with a
/// reverse density that uses the scale of the *proposed* state's region (eq. 2-3, as
/// [`crate::proposal::Regional`] does) each kernel leaves `pi` invariant. Adaptation is
/// *diminishing* (Roberts & Rosenthal 2007): `gamma_n -> 0` in every region that keeps being
/// visited; a split restarts its children at `n / 4` (`gamma` doubles), but a partition that
/// refines finitely often keeps `gamma -> 0`. With `freeze_after_mutations` it is *finite*
/// adaptation: after the freeze the chain is a plain MH chain with fixed scales
/// ([`Controller::is_frozen`]).
///
/// A state space adapts through this controller by implementing [`SharedRegionalScales`] for
/// its scale handle and [`HasSharedScales`] for its proposal (`Mh` and `Mixture` forward it);
/// a crate whose kernels expose the handle otherwise drives the same statistics through
/// [`RegionalScale::observe`], [`RegionalScale::record`], [`RegionalScale::contribute_scales`]
/// and [`RegionalScale::receive_scales`]. The method page is
/// `docs/methods/regional-adaptive.md`.
///
/// # Example
/// ```
/// use mcmc_core::controller::{RegionalScale, RegionalScaleParams};
///
/// let params = RegionalScaleParams {
///     split_after_visits: Some(200),
///     refine_every: 20_000,
///     ..RegionalScaleParams::otsu2018()
/// };
/// let controller = RegionalScale::new(params).unwrap();
/// assert_eq!(controller.params().adapt.updates_every, 10);
/// ```
#[derive(Clone, Debug)]
pub struct RegionalScale {
    params: RegionalScaleParams,
    visits: Vec<Visit>,
    /// The current step's region as [`Self::observe`] found it (`None`: the proposal looks
    /// it up and the handle records it).
    current_region: Option<usize>,
    steps: u64,
    dropped: u64,
    frozen: bool,
}

impl RegionalScale {
    /// A chain's controller (every chain gets one with the same parameters).
    ///
    /// # Errors
    /// As [`RegionalScaleParams::validate`].
    pub fn new(params: RegionalScaleParams) -> Result<Self, McmcError> {
        params.validate()?;
        Ok(Self {
            params,
            visits: Vec::new(),
            current_region: None,
            steps: 0,
            dropped: 0,
            frozen: params.freeze_after_mutations == Some(0),
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &RegionalScaleParams {
        &self.params
    }

    /// Visits dropped because a round exceeded [`MAX_VISITS_PER_ROUND`].
    #[must_use]
    pub fn dropped_visits(&self) -> u64 {
        self.dropped
    }

    /// True once the pooled statistics froze adaptation.
    #[must_use]
    pub fn is_frozen(&self) -> bool {
        self.frozen
    }

    /// Before a step: notes the region of the current state `x` under `scales` (the kernel's
    /// handle, if it has one). What [`Controller::before_step`] does.
    ///
    /// A handle that tracks its chain's current region
    /// ([`SharedRegionalScales::track_current_region`]) knows it whenever the state was
    /// reached by the scaled proposal (whose reverse density looked up the candidate's
    /// region) or stayed; otherwise the lookup is left to the scaled proposal, which makes it
    /// anyway, unless refinement needs the region of every step. Only an unknown region that
    /// refinement needs, or a handle that does not track, costs a lookup here, and it is
    /// handed to the handle so that the proposal does not repeat it.
    pub fn observe<S, Sc>(&mut self, scales: Option<&Sc>, x: &S)
    where
        Sc: SharedRegionalScales,
        Sc::Partition: Partition<S>,
    {
        let Some(s) = scales else {
            return;
        };
        let tracked = s.track_current_region();
        if self.frozen {
            return;
        }
        self.current_region = s.current_region();
        if self.current_region.is_none() && (self.refines() || !tracked) {
            let region = s.partition().region(x);
            s.set_current_region(region);
            self.current_region = Some(region);
        }
    }

    /// True if refinement counts the visits of every step.
    fn refines(&self) -> bool {
        self.params.split_after_visits.is_some()
    }

    /// After a step: records its visit and acceptance, the region as [`Self::observe`] found
    /// it or, when it left the lookup to the proposal, as the handle `scales` recorded it;
    /// then tells the handle how the step moved the state
    /// ([`SharedRegionalScales::end_step`], also once adaptation froze). Steps of other
    /// proposals are only counted unless refinement needs their visits. What
    /// [`Controller::after_step`] does; pass the handle given to [`Self::observe`].
    pub fn record<Sc: SharedRegionalScales>(&mut self, scales: Option<&Sc>, info: &StepInfo) {
        let perturbed = self
            .params
            .perturbation_component
            .is_none_or(|c| c == info.component);
        self.steps += 1;
        if !self.frozen {
            self.push_visit(scales, info, perturbed);
        }
        if let Some(s) = scales {
            s.end_step(match info.accepted_stage {
                0 => StateMove::Stayed,
                1 if perturbed => StateMove::ByScaledProposal,
                _ => StateMove::ByOtherProposal,
            });
        }
    }

    /// Keeps the step's visit for the pool.
    fn push_visit<Sc: SharedRegionalScales>(
        &mut self,
        scales: Option<&Sc>,
        info: &StepInfo,
        perturbed: bool,
    ) {
        if !perturbed && !self.refines() {
            return;
        }
        let Some(region) = self
            .current_region
            .or_else(|| scales.and_then(SharedRegionalScales::current_region))
        else {
            return;
        };
        if self.visits.len() >= MAX_VISITS_PER_ROUND {
            self.dropped += 1;
            return;
        }
        self.visits.push(Visit {
            region: region as u32,
            perturbed,
            accept: info.accept_prob[0],
        });
    }

    /// Adds this chain's visits of the round to `pooled` (starting the pool from `scales`,
    /// the kernel's handle, the first time). What [`SharedController::contribute`] does.
    pub fn contribute_scales<Sc: SharedRegionalScales>(
        &mut self,
        scales: Option<&Sc>,
        pooled: &mut PooledRegionalScales<Sc>,
    ) {
        if !pooled.is_started() {
            if let Some(s) = scales {
                pooled.init(s, self.params);
            }
        }
        pooled.apply(&self.visits, self.steps);
        self.visits.clear();
        self.steps = 0;
    }

    /// Hands the pooled scales to the kernel's handle `scales` (unless it already holds them)
    /// and takes over the pool's freeze. What [`SharedController::receive`] does.
    pub fn receive_scales<Sc: SharedRegionalScales>(
        &mut self,
        scales: Option<&mut Sc>,
        pooled: &PooledRegionalScales<Sc>,
    ) {
        if let Some(mine) = scales {
            if let Some(s) = pooled.sigmas() {
                if !mine.same_as(s) {
                    *mine = s.clone();
                }
            }
            mine.scales_published();
        }
        self.frozen = pooled.is_frozen();
    }
}

impl<K, S> Controller<K, S> for RegionalScale
where
    K: HasSharedScales,
    <K::Scales as SharedRegionalScales>::Partition: Partition<S>,
{
    fn before_step(&mut self, kernel: &K, x: &S) {
        self.observe(kernel.shared_scales(), x);
    }

    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        self.record(kernel.shared_scales(), info);
    }

    fn is_frozen(&self) -> bool {
        self.frozen
    }
}

impl<K> SharedController<K> for RegionalScale
where
    K: HasSharedScales,
    K::Scales: Send + Sync + std::fmt::Debug,
{
    type Shared = PooledRegionalScales<K::Scales>;

    fn contribute(&mut self, kernel: &mut K, pooled: &mut Self::Shared) {
        self.contribute_scales(kernel.shared_scales(), pooled);
    }

    fn receive(&mut self, kernel: &mut K, pooled: &Self::Shared) {
        self.receive_scales(kernel.shared_scales_mut(), pooled);
    }

    fn end_round(pooled: &mut Self::Shared) {
        pooled.end_round();
    }
}

/// The state `(i_k, A_k, n_k)` of one region: an [`AdaptState`], the visits counted for
/// refinement, and a diagnostic of its recent acceptance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionStats {
    /// Sign-rule state.
    pub adapt: AdaptState,
    /// Visits since the last refinement pass.
    pub visits_since_refine: u64,
    /// Proposals of the scaled component made from this region since it was created.
    pub proposals: u64,
    /// The acceptance probability of the region's recent proposals: the running mean over
    /// its first [`RECENT_WINDOW`] proposals, then an exponential moving average with weight
    /// `1 / RECENT_WINDOW` (NaN before the first proposal). A diagnostic only; the sign rule
    /// uses `adapt`.
    pub recent_acceptance: f64,
}

/// The window (in proposals) of [`RegionStats::recent_acceptance`].
pub const RECENT_WINDOW: u64 = 200;

impl RegionStats {
    /// A fresh region (`n = 1`, nothing seen).
    #[must_use]
    pub const fn new() -> Self {
        Self {
            adapt: AdaptState::new(),
            visits_since_refine: 0,
            proposals: 0,
            recent_acceptance: f64::NAN,
        }
    }

    /// Adds one proposal's acceptance probability to the diagnostic.
    pub(super) fn note_proposal(&mut self, accept: f64) {
        self.proposals += 1;
        if self.recent_acceptance.is_nan() {
            self.recent_acceptance = accept;
            return;
        }
        let w = self.proposals.min(RECENT_WINDOW) as f64;
        self.recent_acceptance += (accept - self.recent_acceptance) / w;
    }
}

impl Default for RegionStats {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_parameters_are_refused() {
        let bad = RegionalScaleParams {
            refine_every: 0,
            ..RegionalScaleParams::otsu2018()
        };
        assert!(RegionalScale::new(bad).is_err());
        let bad = RegionalScaleParams {
            split_after_visits: Some(0),
            ..RegionalScaleParams::otsu2018()
        };
        assert!(RegionalScale::new(bad).is_err());
    }
}
