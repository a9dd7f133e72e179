//! Regional scale adaptation (regional-adaptive paper, Alg. 1, eq. 4-6) with statistics shared
//! by all chains at the synchronisation points of a render loop: the per-chain recorder.

use super::regional_pool::{PooledRegionalScales, Visit};
use super::{AdaptState, Controller, ScaleAdaptParams, SharedController};
use crate::kernel::StepInfo;
use crate::partition::Partition;
use crate::tunable::{HasSharedScales, SharedRegionalScales};
use crate::McmcError;

/// Most visits a chain's controller keeps between two synchronisation points; further visits
/// of the round are not used for adaptation (a chain driven without a render loop never
/// synchronises and would otherwise grow without bound).
pub const MAX_VISITS_PER_ROUND: usize = 1 << 20;

/// Parameters of shared regional adaptation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionalScaleParams {
    /// The sign rule of Alg. 1 per region: target acceptance `alpha*`, `L`, `gamma_max`,
    /// `gamma_scale`, `lambda_0`, `lambda_min` (its `freeze_after_updates` is not used here;
    /// see `freeze_after_mutations`).
    pub adapt: ScaleAdaptParams,
    /// `M_split`: at a refinement, split every region visited at least this many times since
    /// the previous refinement (section 6.2); `None` never refines (grids, or a frozen tree).
    pub split_after_visits: Option<u64>,
    /// `M_refine`: refine at the first synchronisation point after every this many mutations
    /// over all chains (section 6.2, 7).
    pub refine_every: u64,
    /// The mixture component that is the regionally scaled proposal: only its proposals
    /// update `lambda` (Alg. 1 is about that proposal); visits for refinement count every
    /// step. `None`: every step is one (a kernel that is only the scaled proposal).
    pub perturbation_component: Option<usize>,
    /// Finite adaptation: stop adapting and refining at the first synchronisation point after
    /// this many mutations over all chains; `None` adapts forever (diminishing adaptation).
    /// `Some(0)` never adapts (the FIXED variant with the same code path).
    pub freeze_after_mutations: Option<u64>,
}

impl RegionalScaleParams {
    /// The paper's values (section 8.1): `L = 10`, `gamma_max = 1`, `gamma_scale = 5`,
    /// `lambda_0 = 1`, `lambda_min = -30`, target acceptance 0.5 (the default of section 8.1;
    /// 0.8 for the Necklace scene), `M_split = 5000`, `M_refine = 10^7`; the scaled proposal is
    /// mixture component 0; diminishing adaptation (no freeze).
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
    /// are tuned for about 10^9-10^10 mutations (section 8); we keep about 100 refinement
    /// passes per render, `M_refine = max(total / 100, 1000)`, and the paper's ratio
    /// `M_split / M_refine = 5 * 10^-4` (a leaf splits once it gets 1/2000 of a pass's
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
    /// [`McmcError::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<(), McmcError> {
        self.adapt.validate()?;
        McmcError::check_range(
            "refine_every",
            self.refine_every as f64,
            1.0,
            f64::MAX,
            ">= 1",
        )?;
        if let Some(m) = self.split_after_visits {
            McmcError::check_range("split_after_visits", m as f64, 1.0, f64::MAX, ">= 1")?;
        }
        Ok(())
    }
}

impl Default for RegionalScaleParams {
    fn default() -> Self {
        Self::otsu2018()
    }
}

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
/// `i_k += 1`. At a synchronisation point, every region with `i_k >= L` updates once:
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
/// had been observed after each other, overshoots and makes the scales oscillate.) The price
/// is speed: `n_k` counts synchronisation points, not blocks of `L` visits, so scales settle
/// after a few hundred rounds (`gamma_n` reaches 0.3 after 250 updates); choose the render
/// loop's `round_mutations` so that rounds are frequent but regions still collect `L` visits
/// per round or two. A round costs O(visits + updated regions) plus, if any `lambda` changed,
/// the handle's copy-on-write of the scales. A refinement likewise happens at the first
/// synchronisation point after the `M_refine`-th mutation.
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
    current_region: usize,
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
            current_region: 0,
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
    pub fn observe<S, Sc>(&mut self, scales: Option<&Sc>, x: &S)
    where
        Sc: SharedRegionalScales,
        Sc::Partition: Partition<S>,
    {
        if self.frozen {
            return;
        }
        if let Some(s) = scales {
            self.current_region = s.partition().region(x);
        }
    }

    /// After a step: records its visit and acceptance. What [`Controller::after_step`] does.
    pub fn record(&mut self, info: &StepInfo) {
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
        if let (Some(s), Some(mine)) = (pooled.sigmas(), scales) {
            if !mine.same_as(s) {
                *mine = s.clone();
            }
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

    fn after_step(&mut self, _kernel: &mut K, info: &StepInfo) {
        self.record(info);
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

/// The state `(i_k, A_k, n_k)` of one region: an [`AdaptState`] and the visits counted for
/// refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionStats {
    /// Sign-rule state.
    pub adapt: AdaptState,
    /// Visits since the last refinement pass.
    pub visits_since_refine: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_scaling_keeps_the_papers_ratio() {
        let p = RegionalScaleParams::otsu2018_for_budget(1_000_000_000);
        assert_eq!(p.refine_every, 10_000_000);
        assert_eq!(p.split_after_visits, Some(5000));
        let small = RegionalScaleParams::otsu2018_for_budget(10_000);
        assert_eq!(small.refine_every, 1000);
        assert_eq!(small.split_after_visits, Some(40));
        assert!(small.validate().is_ok());
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
