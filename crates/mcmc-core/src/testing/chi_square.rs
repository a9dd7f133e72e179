//! Pearson's chi-square goodness-of-fit test: statistic, bin pooling, survival function, report.
//!
//! Public so that other crates (e.g. the render crate's BSDF sampling tests, pbrt style) can
//! reuse it. The survival function is the regularised upper incomplete gamma
//! `Q(k/2, x/2)` of [`crate::special`], written from Numerical Recipes' series and
//! continued fraction (NR 3rd ed., section 6.2).

use std::fmt;

pub use crate::special::{chi_square_cdf, chi_square_sf as survival};

/// The significance level of one stationarity test (alpha = 0.01; Sidak-corrected over the
/// tests of a file by `ChiSquareReport::assert_passes`).
pub const ALPHA: f64 = 0.01;

/// The minimum expected count per bin after pooling (the usual rule of thumb for the
/// chi-square approximation to Pearson's statistic).
pub const MIN_EXPECTED: f64 = 5.0;

/// The Sidak-corrected per-test level `1 - (1 - alpha)^(1/m)` that keeps the probability of
/// *any* false failure among `m` independent tests at `alpha`.
#[must_use]
pub fn sidak_alpha(alpha: f64, m: usize) -> f64 {
    let m = m.max(1) as f64;
    // 1 - (1 - alpha)^(1/m) = -expm1(ln(1 - alpha) / m), without cancellation.
    -((-alpha).ln_1p() / m).exp_m1()
}

/// Pearson's statistic `sum_i (O_i - E_i)^2 / E_i` over bins with `E_i > 0`; `+inf` if any
/// bin with `E_i = 0` has `O_i > 0` (an impossible observation).
#[must_use]
pub fn statistic(observed: &[u64], expected: &[f64]) -> f64 {
    assert_eq!(observed.len(), expected.len(), "one expected count per bin");
    observed
        .iter()
        .zip(expected)
        .map(|(&o, &e)| {
            let o = o as f64;
            if e > 0.0 {
                (o - e) * (o - e) / e
            } else if o > 0.0 {
                f64::INFINITY
            } else {
                0.0
            }
        })
        .sum()
}

/// Bins after pooling: each pooled bin is a group of original bins.
#[derive(Clone, Debug, PartialEq)]
pub struct Pooled {
    /// Observed count per pooled bin.
    pub observed: Vec<u64>,
    /// Expected count per pooled bin.
    pub expected: Vec<f64>,
    /// The original bin indices of each pooled bin.
    pub groups: Vec<Vec<usize>>,
    /// Observations in bins of expected count 0 (impossible under the hypothesis).
    pub impossible: u64,
}

/// Pools bins so that every pooled bin has expected count `>= min_expected` (pbrt's
/// `Chi2Test` rule): bins with `E = 0` are dropped (their observations counted as
/// impossible); bins below `min_expected` are merged in increasing order of `E` until each
/// merged group reaches `min_expected`; a last group still below it joins the smallest
/// group or bin that is large enough.
#[must_use]
pub fn pool(observed: &[u64], expected: &[f64], min_expected: f64) -> Pooled {
    assert_eq!(observed.len(), expected.len(), "one expected count per bin");
    let mut impossible = 0;
    let mut large: Vec<usize> = Vec::new();
    let mut small: Vec<usize> = Vec::new();
    for (i, (&o, &e)) in observed.iter().zip(expected).enumerate() {
        if e <= 0.0 {
            impossible += o;
        } else if e >= min_expected {
            large.push(i);
        } else {
            small.push(i);
        }
    }
    small.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]).then(a.cmp(&b)));
    let mut groups: Vec<Vec<usize>> = large.into_iter().map(|i| vec![i]).collect();
    let mut current: Vec<usize> = Vec::new();
    let mut current_e = 0.0;
    for i in small {
        current.push(i);
        current_e += expected[i];
        if current_e >= min_expected {
            groups.push(std::mem::take(&mut current));
            current_e = 0.0;
        }
    }
    if !current.is_empty() {
        let sum = |g: &Vec<usize>| g.iter().map(|&i| expected[i]).sum::<f64>();
        match (0..groups.len()).min_by(|&a, &b| sum(&groups[a]).total_cmp(&sum(&groups[b]))) {
            Some(k) => groups[k].extend(current),
            None => groups.push(current),
        }
    }
    let observed_pooled = groups
        .iter()
        .map(|g| g.iter().map(|&i| observed[i]).sum())
        .collect();
    let expected_pooled = groups
        .iter()
        .map(|g| g.iter().map(|&i| expected[i]).sum())
        .collect();
    Pooled {
        observed: observed_pooled,
        expected: expected_pooled,
        groups,
        impossible,
    }
}

/// The outcome of a chi-square goodness-of-fit test.
#[derive(Clone, Debug, PartialEq)]
pub struct ChiSquareReport {
    /// Pearson's statistic after pooling (`+inf` with impossible observations).
    pub statistic: f64,
    /// Degrees of freedom: pooled bins minus one.
    pub degrees_of_freedom: usize,
    /// `P(chi^2_dof >= statistic)`: uniform on `[0, 1]` under the hypothesis.
    pub p_value: f64,
    /// Number of samples.
    pub samples: u64,
    /// Observations in bins of probability 0.
    pub impossible: u64,
    /// The pooled bin contributing most to the statistic: (original bins, observed, expected).
    pub worst_bin: Option<(Vec<usize>, u64, f64)>,
}

impl fmt::Display for ChiSquareReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "chi2 = {:.3} with {} dof, p = {:.3e} ({} samples, {} in zero-probability bins",
            self.statistic, self.degrees_of_freedom, self.p_value, self.samples, self.impossible
        )?;
        if let Some((bins, o, e)) = &self.worst_bin {
            write!(f, "; worst bin(s) {bins:?}: observed {o}, expected {e:.1}")?;
        }
        write!(f, ")")
    }
}

impl ChiSquareReport {
    /// True if the test rejects at level `alpha` (also when it has no degree of freedom, i.e.
    /// could not have failed: such a test is a defect, not a pass).
    #[must_use]
    pub fn rejects(&self, alpha: f64) -> bool {
        self.degrees_of_freedom == 0 || self.p_value.is_nan() || self.p_value < alpha
    }

    /// Panics unless the test passes at the Sidak-corrected level for `tests_in_file` tests
    /// sharing the overall level [`ALPHA`]. The message carries the full report.
    #[track_caller]
    pub fn assert_passes(&self, what: &str, tests_in_file: usize) {
        let level = sidak_alpha(ALPHA, tests_in_file);
        assert!(
            !self.rejects(level),
            "{what}: chi-square test rejects at level {level:.2e} (alpha = {ALPHA}, Sidak over \
             {tests_in_file} tests): {self}"
        );
    }
}

/// Pearson's chi-square test of `observed` counts against bin `probabilities` (which should
/// sum to 1), pooling bins to expected count `>= min_expected`.
#[must_use]
pub fn chi_square_test(
    observed: &[u64],
    probabilities: &[f64],
    min_expected: f64,
) -> ChiSquareReport {
    let n: u64 = observed.iter().sum();
    let expected: Vec<f64> = probabilities.iter().map(|p| p * n as f64).collect();
    let pooled = pool(observed, &expected, min_expected);
    let degrees_of_freedom = pooled.observed.len().saturating_sub(1);
    let statistic = if pooled.impossible > 0 {
        f64::INFINITY
    } else {
        statistic(&pooled.observed, &pooled.expected)
    };
    let p_value = if degrees_of_freedom == 0 {
        1.0
    } else {
        survival(statistic, degrees_of_freedom as f64)
    };
    let worst_bin = (0..pooled.observed.len())
        .map(|k| {
            let (o, e) = (pooled.observed[k] as f64, pooled.expected[k]);
            (k, (o - e) * (o - e) / e)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| {
            (
                pooled.groups[k].clone(),
                pooled.observed[k],
                pooled.expected[k],
            )
        });
    ChiSquareReport {
        statistic,
        degrees_of_freedom,
        p_value,
        samples: n,
        impossible: pooled.impossible,
        worst_bin,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn survival_matches_tables() {
        assert!((survival(3.841_458_820_694_124, 1.0) - 0.05).abs() < 1e-12);
        assert!((survival(18.307_038_053_275_146, 10.0) - 0.05).abs() < 1e-12);
        assert!((survival(6.634_896_601_021_214, 1.0) - 0.01).abs() < 1e-12);
    }

    #[test]
    fn sidak_level() {
        assert!((sidak_alpha(0.01, 1) - 0.01).abs() < 1e-15);
        let a = sidak_alpha(0.01, 10);
        assert!(((1.0 - a).powi(10) - 0.99).abs() < 1e-14);
    }

    #[test]
    fn pooling_reaches_the_minimum() {
        let observed = [10, 1, 0, 2, 3, 7, 0];
        let expected = [9.0, 1.5, 0.5, 2.0, 2.5, 8.0, 0.0];
        let p = pool(&observed, &expected, 5.0);
        assert!(p.expected.iter().all(|&e| e >= 5.0));
        assert_eq!(p.observed.iter().sum::<u64>(), 23);
        assert!((p.expected.iter().sum::<f64>() - 23.5).abs() < 1e-12);
        assert_eq!(p.impossible, 0);
        let mut all: Vec<usize> = p.groups.concat();
        all.sort_unstable();
        assert_eq!(all, vec![0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn exact_counts_pass_and_skewed_counts_fail() {
        let probs = [0.25; 4];
        let ok = chi_square_test(&[250, 250, 250, 250], &probs, 5.0);
        assert_eq!(ok.statistic, 0.0);
        assert_eq!(ok.p_value, 1.0);
        assert_eq!(ok.degrees_of_freedom, 3);
        let bad = chi_square_test(&[400, 200, 200, 200], &probs, 5.0);
        // (150^2 + 3 * 50^2) / 250 = 120 with 3 dof: p ~ 7e-26.
        assert!((bad.statistic - 120.0).abs() < 1e-12);
        assert!(bad.p_value < 1e-20);
        assert!(bad.rejects(0.01));
        let impossible = chi_square_test(&[5, 5, 1], &[0.5, 0.5, 0.0], 5.0);
        assert_eq!(impossible.impossible, 1);
        assert_eq!(impossible.p_value, 0.0);
        // A test without degrees of freedom cannot fail, so it counts as a rejection.
        assert!(chi_square_test(&[3], &[1.0], 5.0).rejects(0.01));
    }
}
