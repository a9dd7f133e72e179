//! Automatic large-step probability (Zsolnai & Szirmay-Kalos 2013, "Automatic Parameter
//! Control for Metropolis Light Transport").

use super::Controller;
use crate::kernel::StepInfo;
use crate::tunable::LargeStepTunable;
use crate::McmcError;

/// Threshold on `eta_l / eta_0` below which the integrand is considered not flattened by the
/// path-building strategy (paper section 2.2) and `p_l = 0.25` is used.
pub const FLATNESS_THRESHOLD: f64 = 0.1;

/// The large-step probability used when the integrand is not flattened (paper section 2.2).
pub const NOT_FLAT_LARGE_STEP_PROBABILITY: f64 = 0.25;

/// The automatic large-step probability from the three statistics of the paper (section 2):
///
/// - if `eta_l / eta_0 < 0.1` (or `eta_0 == 0`: no large step found a nonzero sample),
///   the integrand is not flattened and `p_l = 0.25` (section 2.2);
/// - otherwise `p_l = eta_s / (2 (eta_s - eta_l))` (section 2.1, the argmax of `E[D]`),
///   clamped to `(0, 1]`. When `eta_l >= eta_s` the formula's maximiser is unbounded, i.e.
///   large steps are at least as successful as small ones, and we return 1 (the paper's
///   "should be set to 1").
///
/// Inputs are clamped to `[0, 1]`; NaN inputs give the fallback 0.25.
#[must_use]
pub fn automatic_large_step_probability(eta_s: f64, eta_l: f64, eta_0: f64) -> f64 {
    let (eta_s, eta_l, eta_0) = (
        eta_s.clamp(0.0, 1.0),
        eta_l.clamp(0.0, 1.0),
        eta_0.clamp(0.0, 1.0),
    );
    if eta_s.is_nan()
        || eta_l.is_nan()
        || eta_0.is_nan()
        || eta_0 == 0.0
        || eta_l / eta_0 < FLATNESS_THRESHOLD
    {
        return NOT_FLAT_LARGE_STEP_PROBABILITY;
    }
    if eta_s <= eta_l {
        return 1.0;
    }
    let p = eta_s / (2.0 * (eta_s - eta_l));
    p.clamp(f64::MIN_POSITIVE, 1.0)
}

/// The statistics measured in the estimation phase and the resulting `p_l`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LargeStepEstimate {
    /// Mean acceptance probability of small steps.
    pub eta_s: f64,
    /// Mean acceptance probability of large steps.
    pub eta_l: f64,
    /// Fraction of large steps whose candidate had nonzero density.
    pub eta_0: f64,
    /// Small steps measured.
    pub small_steps: u64,
    /// Large steps measured.
    pub large_steps: u64,
    /// The chosen large-step probability.
    pub large_step_probability: f64,
}

impl LargeStepEstimate {
    /// The steps the estimate was measured on: the estimation phase's mutations.
    #[must_use]
    pub const fn steps(&self) -> u64 {
        self.small_steps + self.large_steps
    }
}

/// Running sums for the three statistics; mergeable across chains (estimate in parallel,
/// then combine with [`LargeStepStats::merge`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LargeStepStats {
    small: u64,
    small_accept: f64,
    large: u64,
    large_accept: f64,
    large_nonzero: u64,
}

impl LargeStepStats {
    /// Records one step's report; `is_large` says whether its component was the large step.
    pub fn record(&mut self, info: &StepInfo, is_large: bool) {
        if is_large {
            self.large += 1;
            self.large_accept += info.accept_prob[0];
            if info.candidate_log_density[0] > f64::NEG_INFINITY {
                self.large_nonzero += 1;
            }
        } else {
            // eta_s of a delayed-rejection small step is its probability of moving at either
            // stage, E[a1 + (1 - a1) a2] (`stats::move_probability`; docs/methods/drmlt.md);
            // for a one-stage kernel that is a1.
            self.small += 1;
            self.small_accept += crate::stats::move_probability(info);
        }
    }

    /// Adds another set of sums (e.g. from another chain).
    pub fn merge(&mut self, other: &Self) {
        self.small += other.small;
        self.small_accept += other.small_accept;
        self.large += other.large;
        self.large_accept += other.large_accept;
        self.large_nonzero += other.large_nonzero;
    }

    /// Total steps recorded.
    #[must_use]
    pub fn steps(&self) -> u64 {
        self.small + self.large
    }

    /// The estimates and the automatic `p_l`. With no small (large) steps, `eta_s` (`eta_l`,
    /// `eta_0`) is 0.
    #[must_use]
    pub fn estimate(&self) -> LargeStepEstimate {
        let ratio = |a: f64, n: u64| if n == 0 { 0.0 } else { a / n as f64 };
        let eta_s = ratio(self.small_accept, self.small);
        let eta_l = ratio(self.large_accept, self.large);
        let eta_0 = ratio(self.large_nonzero as f64, self.large);
        LargeStepEstimate {
            eta_s,
            eta_l,
            eta_0,
            small_steps: self.small,
            large_steps: self.large,
            large_step_probability: automatic_large_step_probability(eta_s, eta_l, eta_0),
        }
    }
}

/// Automatic large-step control: measures `eta_s`, `eta_l`, `eta_0` during an estimation phase
/// of `estimation_steps` steps (run with the kernel's initial large-step probability), then
/// sets `p_l` by [`automatic_large_step_probability`] and freezes (finite adaptation: after
/// the phase the chain is a fixed MH mixture, so stationarity is untouched).
///
/// Two modes: [`AutoLargeStep::new`] decides from this chain's own statistics;
/// [`AutoLargeStep::pooled`] decides from the statistics of all chains of a render loop,
/// pooled at round boundaries (`render_loop::SharedController`), which is what a renderer with
/// many short chains wants (the paper estimates once per image).
#[derive(Clone, Debug)]
pub struct AutoLargeStep {
    estimation_steps: u64,
    pooled: bool,
    stats: LargeStepStats,
    unshared: LargeStepStats,
    estimate: Option<LargeStepEstimate>,
}

impl AutoLargeStep {
    /// A controller whose estimation phase lasts `estimation_steps >= 1` steps of this chain.
    pub fn new(estimation_steps: u64) -> Result<Self, McmcError> {
        McmcError::check_range(
            "estimation_steps",
            estimation_steps as f64,
            1.0,
            f64::MAX,
            ">= 1",
        )?;
        Ok(Self {
            estimation_steps,
            pooled: false,
            stats: LargeStepStats::default(),
            unshared: LargeStepStats::default(),
            estimate: None,
        })
    }

    /// A controller whose estimation phase ends once the statistics pooled over all chains
    /// of a render loop hold `total_estimation_steps >= 1` steps (checked at round
    /// boundaries). Outside a render loop it never freezes by itself.
    pub fn pooled(total_estimation_steps: u64) -> Result<Self, McmcError> {
        let mut c = Self::new(total_estimation_steps)?;
        c.pooled = true;
        Ok(c)
    }

    /// The estimate, once the estimation phase is over.
    #[must_use]
    pub fn estimate(&self) -> Option<LargeStepEstimate> {
        self.estimate
    }

    /// This chain's running statistics.
    #[must_use]
    pub fn stats(&self) -> &LargeStepStats {
        &self.stats
    }

    /// The statistics recorded since the last call (for pooling), reset.
    pub fn take_unshared(&mut self) -> LargeStepStats {
        std::mem::take(&mut self.unshared)
    }

    /// Pooled mode: freezes with the pooled estimate once `pooled` holds the estimation steps.
    pub fn receive_pooled<K: LargeStepTunable + ?Sized>(
        &mut self,
        kernel: &mut K,
        pooled: &LargeStepStats,
    ) {
        if self.pooled && self.estimate.is_none() && pooled.steps() >= self.estimation_steps {
            let e = pooled.estimate();
            kernel.set_large_step_probability(e.large_step_probability);
            self.estimate = Some(e);
        }
    }
}

impl<K: LargeStepTunable + ?Sized, S> Controller<K, S> for AutoLargeStep {
    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        if self.estimate.is_some() {
            return;
        }
        let is_large = kernel.is_large_step(info.component);
        self.stats.record(info, is_large);
        if self.pooled {
            self.unshared.record(info, is_large);
        } else if self.stats.steps() >= self.estimation_steps {
            let e = self.stats.estimate();
            kernel.set_large_step_probability(e.large_step_probability);
            self.estimate = Some(e);
        }
    }

    fn is_frozen(&self) -> bool {
        self.estimate.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table 1 of the paper, from its (eta_l, eta_s, eta_0) values. The paper prints 0.95 for
    /// LuxTime, but its own formula gives 0.783 / (2 (0.783 - 0.377)) = 0.9643, which rounds to
    /// 0.96: we believe the table entry was rounded down or computed from unrounded statistics.
    #[test]
    fn reproduces_table_1() {
        let rows = [
            ("LuxTime", 0.377, 0.783, 0.985, 0.96),
            ("Spheres", 0.005, 0.394, 0.487, 0.25),
            ("Chess Day", 0.061, 0.641, 0.886, 0.25),
            ("Cherry", 0.126, 0.487, 0.911, 0.67),
            ("Cornell", 0.004, 0.438, 0.022, 0.50),
            ("Glass Ball", 0.088, 0.489, 0.87, 0.61),
        ];
        for (name, eta_l, eta_s, eta_0, expected) in rows {
            let p = automatic_large_step_probability(eta_s, eta_l, eta_0);
            assert!(
                (p - expected).abs() < 0.005,
                "{name}: got {p:.4}, table {expected}"
            );
        }
    }

    #[test]
    fn edge_cases() {
        assert_eq!(automatic_large_step_probability(0.5, 0.0, 0.0), 0.25);
        assert_eq!(automatic_large_step_probability(0.5, 0.6, 0.9), 1.0);
        assert_eq!(automatic_large_step_probability(f64::NAN, 0.3, 0.9), 0.25);
        let p = automatic_large_step_probability(0.9, 0.3, 0.5);
        assert!(p > 0.0 && p <= 1.0);
    }
}
