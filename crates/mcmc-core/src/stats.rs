//! Chain statistics: acceptance per component and stage, autocorrelation time and ESS.

use crate::kernel::{StepInfo, MAX_STAGES};
use crate::proposal::MAX_COMPONENTS;

/// Acceptance counts per mixture component and per kernel stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AcceptanceStats {
    /// Steps taken.
    pub steps: u64,
    /// Steps whose first-stage proposal came from each component.
    pub proposed: [u64; MAX_COMPONENTS],
    /// Accepted steps per first-stage component (at any stage).
    pub accepted: [u64; MAX_COMPONENTS],
    /// Summed acceptance probability per component (first stage).
    pub accept_prob_sum: [f64; MAX_COMPONENTS],
    /// Candidates proposed at each stage.
    pub stage_tried: [u64; MAX_STAGES],
    /// Candidates accepted at each stage.
    pub stage_accepted: [u64; MAX_STAGES],
    /// Steps with a non-finite density or Hastings term.
    pub non_finite: u64,
    /// Summed acceptance probability per stage (over the steps that tried the stage): with
    /// [`AcceptanceStats::stage_tried`], the mean `a1` and the mean `a2` of a
    /// delayed-rejection kernel (its "DR stage map" statistics).
    pub stage_accept_prob_sum: [f64; MAX_STAGES],
    /// Summed [`move_probability`] per first-stage component: the mean over a component's
    /// steps estimates the probability that such a step moves the chain (for delayed
    /// rejection `E[a1 + (1 - a1) a2]`, the two-stage `eta_s` of automatic large-step
    /// control; for MH the same as [`AcceptanceStats::accept_prob_sum`]).
    pub move_prob_sum: [f64; MAX_COMPONENTS],
}

/// An unbiased one-step estimate of the probability that a step moves the chain:
/// `a1 + a2` from [`StepInfo::accept_prob`] (`a2 = 0` when no second stage ran).
///
/// For MH it is `a1`. For two-stage delayed rejection the second stage runs only after a
/// first-stage rejection (probability `1 - a1`), so `E[a1 + 1{second stage} a2] =
/// E[a1 + (1 - a1) a2]`, the probability of moving at either stage. A single value may
/// exceed 1 (a rejected `y` with large `a1` followed by an accepted `z`); its mean may not.
/// This is what `eta_s` means for a delayed-rejection small step (docs/methods/drmlt.md).
#[must_use]
pub fn move_probability(info: &StepInfo) -> f64 {
    info.accept_prob.iter().sum()
}

impl AcceptanceStats {
    /// Records one step.
    pub fn record(&mut self, info: &StepInfo) {
        self.steps += 1;
        let c = info.component.min(MAX_COMPONENTS - 1);
        self.proposed[c] += 1;
        self.accept_prob_sum[c] += info.accept_prob[0];
        if info.accepted() {
            self.accepted[c] += 1;
            self.stage_accepted[usize::from(info.accepted_stage) - 1] += 1;
        }
        for s in 0..usize::from(info.stages_tried).min(MAX_STAGES) {
            self.stage_tried[s] += 1;
            self.stage_accept_prob_sum[s] += info.accept_prob[s];
        }
        self.move_prob_sum[c] += move_probability(info);
        self.non_finite += u64::from(info.non_finite);
    }

    /// Overall acceptance rate (accepted steps / steps).
    #[must_use]
    pub fn acceptance_rate(&self) -> f64 {
        let acc: u64 = self.accepted.iter().sum();
        ratio(acc as f64, self.steps)
    }

    /// Acceptance rate of steps that started with component `j`.
    #[must_use]
    pub fn component_acceptance_rate(&self, j: usize) -> f64 {
        ratio(self.accepted[j] as f64, self.proposed[j])
    }

    /// Acceptance rate of candidates at stage `s` (0-based) among those tried there.
    #[must_use]
    pub fn stage_acceptance_rate(&self, s: usize) -> f64 {
        ratio(self.stage_accepted[s] as f64, self.stage_tried[s])
    }

    /// Mean acceptance probability at stage `s` (0-based) among the steps that tried it.
    #[must_use]
    pub fn stage_mean_accept_prob(&self, s: usize) -> f64 {
        ratio(self.stage_accept_prob_sum[s], self.stage_tried[s])
    }

    /// Mean [`move_probability`] of the steps that started with component `j`.
    #[must_use]
    pub fn component_move_probability(&self, j: usize) -> f64 {
        ratio(self.move_prob_sum[j], self.proposed[j])
    }

    /// The share of accepted moves made at the second stage, `accepted_2 / (accepted_1 +
    /// accepted_2)` (0 without accepted moves): the per-pixel quantity of the DR paper's
    /// stage maps (Fig. 1, 9).
    #[must_use]
    pub fn second_stage_share(&self) -> f64 {
        let total = self.stage_accepted.iter().sum::<u64>();
        ratio(self.stage_accepted[MAX_STAGES - 1] as f64, total)
    }

    /// Adds another chain's counts.
    pub fn merge(&mut self, other: &Self) {
        self.steps += other.steps;
        for j in 0..MAX_COMPONENTS {
            self.proposed[j] += other.proposed[j];
            self.accepted[j] += other.accepted[j];
            self.accept_prob_sum[j] += other.accept_prob_sum[j];
            self.move_prob_sum[j] += other.move_prob_sum[j];
        }
        for s in 0..MAX_STAGES {
            self.stage_tried[s] += other.stage_tried[s];
            self.stage_accepted[s] += other.stage_accepted[s];
            self.stage_accept_prob_sum[s] += other.stage_accept_prob_sum[s];
        }
        self.non_finite += other.non_finite;
    }
}

fn ratio(a: f64, n: u64) -> f64 {
    if n == 0 {
        0.0
    } else {
        a / n as f64
    }
}

/// Integrated autocorrelation time `tau = 1 + 2 sum_k rho_k` of a scalar series, with Geyer's
/// initial monotone sequence estimator (Geyer 1992): autocorrelations are summed in pairs
/// `Gamma_m = rho_{2m} + rho_{2m+1}` while positive, forced non-increasing. Returns 1 for
/// series shorter than 4 or with zero variance. O(n * lag) time, adequate for diagnostics.
#[must_use]
pub fn integrated_autocorrelation_time(series: &[f64]) -> f64 {
    let n = series.len();
    if n < 4 {
        return 1.0;
    }
    let mean = series.iter().sum::<f64>() / n as f64;
    let var = series.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
    if var <= 0.0 || !var.is_finite() {
        return 1.0;
    }
    let rho = |k: usize| -> f64 {
        let c: f64 = (0..n - k)
            .map(|i| (series[i] - mean) * (series[i + k] - mean))
            .sum();
        c / (n as f64 * var)
    };
    let mut tau = -1.0; // tau = -rho_0 + 2 sum_m Gamma_m
    let mut prev = f64::INFINITY;
    let mut m = 0;
    while 2 * m + 1 < n {
        let gamma = rho(2 * m) + rho(2 * m + 1);
        if gamma <= 0.0 {
            break;
        }
        let gamma = gamma.min(prev);
        tau += 2.0 * gamma;
        prev = gamma;
        m += 1;
    }
    tau.max(1.0)
}

/// Effective sample size `n / tau` of a scalar series.
#[must_use]
pub fn effective_sample_size(series: &[f64]) -> f64 {
    series.len() as f64 / integrated_autocorrelation_time(series)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Per-stage sums and the move probability of a two-stage step (`a1 + a2`), merged.
    #[test]
    fn records_stage_statistics() {
        let mut two = StepInfo::new(0);
        two.stages_tried = 2;
        two.accept_prob = [0.25, 0.5];
        two.accepted_stage = 2;
        let mut one = StepInfo::new(1);
        one.stages_tried = 1;
        one.accept_prob = [0.75, 0.0];
        one.accepted_stage = 1;
        let mut a = AcceptanceStats::default();
        a.record(&two);
        let mut b = AcceptanceStats::default();
        b.record(&one);
        a.merge(&b);
        assert_eq!(move_probability(&two), 0.75);
        assert_eq!(a.stage_accept_prob_sum, [1.0, 0.5]);
        assert_eq!(a.stage_mean_accept_prob(0), 0.5);
        assert_eq!(a.stage_mean_accept_prob(1), 0.5);
        assert_eq!(a.component_move_probability(0), 0.75);
        assert_eq!(a.component_move_probability(1), 0.75);
        assert_eq!(a.second_stage_share(), 0.5);
        assert_eq!(AcceptanceStats::default().second_stage_share(), 0.0);
    }

    #[test]
    fn iid_series_has_tau_near_one() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
        let s: Vec<f64> = (0..20_000).map(|_| rng.random::<f64>()).collect();
        let tau = integrated_autocorrelation_time(&s);
        assert!(tau < 1.1, "{tau}");
    }

    #[test]
    fn ar1_series_matches_theory() {
        // AR(1) with coefficient phi has tau = (1 + phi) / (1 - phi) = 19 for phi = 0.9.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(2);
        let phi = 0.9;
        let mut x = 0.0;
        let s: Vec<f64> = (0..100_000)
            .map(|_| {
                let e: f64 = rng.random::<f64>() - 0.5;
                x = phi * x + e;
                x
            })
            .collect();
        let tau = integrated_autocorrelation_time(&s);
        assert!((tau - 19.0).abs() < 3.0, "{tau}");
        assert!((effective_sample_size(&s) - 100_000.0 / tau).abs() < 1e-6);
    }
}
