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
        }
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

    /// Adds another chain's counts.
    pub fn merge(&mut self, other: &Self) {
        self.steps += other.steps;
        for j in 0..MAX_COMPONENTS {
            self.proposed[j] += other.proposed[j];
            self.accepted[j] += other.accepted[j];
            self.accept_prob_sum[j] += other.accept_prob_sum[j];
        }
        for s in 0..MAX_STAGES {
            self.stage_tried[s] += other.stage_tried[s];
            self.stage_accepted[s] += other.stage_accepted[s];
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
