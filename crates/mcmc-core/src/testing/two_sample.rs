//! Two-sample tests: do two samples come from the same distribution (chi-square, Kolmogorov-Smirnov)?
//!
//! Used where the reference distribution is known only through a second sampler, e.g. lazy
//! versus eager primary-sample-space mutation in the `pss` crate: both processes are run
//! independently many times and their outcomes compared. The one-sample Kolmogorov-Smirnov
//! test against a known CDF ([`ks_one_sample`]) shares the Kolmogorov law.

use std::fmt;

use super::chi_square::{pool, survival, ChiSquareReport};

/// Pearson's chi-square test of homogeneity for two histograms over the same bins
/// (Numerical Recipes 3rd ed., section 14.3.2, `chstwo`, for unequal sample sizes).
///
/// With `n_a = sum(a)`, `n_b = sum(b)` and bin totals `t_i = a_i + b_i`, the expected counts
/// under "same distribution" are `E^a_i = n_a t_i / (n_a + n_b)` and `E^b_i = n_b t_i /
/// (n_a + n_b)`, and `X^2 = sum_i (a_i - E^a_i)^2 / E^a_i + (b_i - E^b_i)^2 / E^b_i` is
/// asymptotically chi-square with (pooled bins - 1) degrees of freedom.
///
/// Bins are pooled (as in [`super::chi_square_test`]) until the smaller expected count of
/// each pooled bin is `>= min_expected`. Pooling looks only at the totals `t_i`, whose
/// distribution does not depend on which sample an observation came from under the null
/// hypothesis, so it does not bias the test. The report's `samples` is `n_a + n_b`; its
/// `worst_bin` gives the observed count of `a` and its expected count `E^a`.
///
/// # Panics
/// If the histograms have different lengths or either is empty of observations.
#[must_use]
pub fn chi_square_two_sample(a: &[u64], b: &[u64], min_expected: f64) -> ChiSquareReport {
    assert_eq!(a.len(), b.len(), "both histograms need the same bins");
    let (n_a, n_b) = (a.iter().sum::<u64>() as f64, b.iter().sum::<u64>() as f64);
    assert!(n_a > 0.0 && n_b > 0.0, "both samples must be non-empty");
    let totals: Vec<u64> = a.iter().zip(b).map(|(x, y)| x + y).collect();
    let smaller = n_a.min(n_b) / (n_a + n_b);
    let smaller_expected: Vec<f64> = totals.iter().map(|&t| t as f64 * smaller).collect();
    let pooled = pool(&totals, &smaller_expected, min_expected);
    let mut statistic = 0.0;
    let mut worst: Option<(usize, f64)> = None;
    let sum_over = |h: &[u64], g: &[usize]| g.iter().map(|&i| h[i]).sum::<u64>() as f64;
    for (k, group) in pooled.groups.iter().enumerate() {
        let (o_a, o_b) = (sum_over(a, group), sum_over(b, group));
        let t = o_a + o_b;
        let (e_a, e_b) = (n_a * t / (n_a + n_b), n_b * t / (n_a + n_b));
        let term = (o_a - e_a).powi(2) / e_a + (o_b - e_b).powi(2) / e_b;
        statistic += term;
        if worst.is_none_or(|(_, w)| term > w) {
            worst = Some((k, term));
        }
    }
    let degrees_of_freedom = pooled.groups.len().saturating_sub(1);
    let p_value = if degrees_of_freedom == 0 {
        1.0
    } else {
        survival(statistic, degrees_of_freedom as f64)
    };
    let worst_bin = worst.map(|(k, _)| {
        let group = pooled.groups[k].clone();
        let o_a = sum_over(a, &group);
        let t = o_a + sum_over(b, &group);
        (group, o_a as u64, n_a * t / (n_a + n_b))
    });
    ChiSquareReport {
        statistic,
        degrees_of_freedom,
        p_value,
        samples: (n_a + n_b) as u64,
        impossible: 0,
        worst_bin,
    }
}

/// The outcome of a two-sample Kolmogorov-Smirnov test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KsReport {
    /// `D = sup_x |F_a(x) - F_b(x)|` of the two empirical CDFs.
    pub statistic: f64,
    /// Asymptotic p-value `Q_KS((sqrt(n_e) + 0.12 + 0.11 / sqrt(n_e)) D)` with
    /// `n_e = n_a n_b / (n_a + n_b)` (Stephens' correction; Numerical Recipes 3rd ed.,
    /// section 14.3.3).
    pub p_value: f64,
    /// Sizes of the two samples.
    pub samples: (usize, usize),
}

impl fmt::Display for KsReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "KS D = {:.5}, p = {:.3e} ({} vs {} samples)",
            self.statistic, self.p_value, self.samples.0, self.samples.1
        )
    }
}

/// The Kolmogorov distribution's survival function `Q_KS(lambda) = 2 sum_{k >= 1} (-1)^(k-1)
/// exp(-2 k^2 lambda^2)`, monotone from 1 at 0 to 0 at infinity.
#[must_use]
pub fn kolmogorov_survival(lambda: f64) -> f64 {
    if lambda < 0.2 {
        // The alternating series converges slowly here, and Q_KS(0.2) = 1 - 3e-22 already.
        return 1.0;
    }
    let a = -2.0 * lambda * lambda;
    let mut sum = 0.0;
    let mut sign = 1.0;
    for k in 1..=100 {
        let k = f64::from(k);
        let term = sign * 2.0 * (a * k * k).exp();
        sum += term;
        if term.abs() <= 1e-16 * sum.abs() {
            break;
        }
        sign = -sign;
    }
    sum.clamp(0.0, 1.0)
}

/// One-sample Kolmogorov-Smirnov test of `samples` (NaN-free) against a continuous `cdf`:
/// `(D, p)` with `D = sup_x |F_n(x) - cdf(x)|` and the asymptotic p-value
/// `Q_KS((sqrt(n) + 0.12 + 0.11 / sqrt(n)) D)` (Stephens' correction, as [`ks_two_sample`]).
/// E.g. the p-values of independent tests against the uniform law (`cdf` the identity).
///
/// # Panics
/// If `samples` is empty.
#[must_use]
pub fn ks_one_sample(samples: &[f64], cdf: impl Fn(f64) -> f64) -> (f64, f64) {
    assert!(!samples.is_empty(), "the sample must be non-empty");
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len() as f64;
    let d = sorted
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let f = cdf(x);
            ((i + 1) as f64 / n - f).max(f - i as f64 / n)
        })
        .fold(0.0, f64::max);
    let en = n.sqrt();
    (d, kolmogorov_survival((en + 0.12 + 0.11 / en) * d))
}

/// Two-sample Kolmogorov-Smirnov test of two samples of reals (NaN-free).
///
/// # Panics
/// If either sample is empty.
#[must_use]
pub fn ks_two_sample(a: &[f64], b: &[f64]) -> KsReport {
    assert!(
        !a.is_empty() && !b.is_empty(),
        "both samples must be non-empty"
    );
    let mut a = a.to_vec();
    let mut b = b.to_vec();
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (n, m) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0usize, 0usize, 0.0f64);
    while i < a.len() && j < b.len() {
        // Step past every copy of the smaller value in both samples before comparing, so
        // that ties do not create a spurious gap.
        let x = a[i].min(b[j]);
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / n - j as f64 / m).abs());
    }
    let en = (n * m / (n + m)).sqrt();
    KsReport {
        statistic: d,
        p_value: kolmogorov_survival((en + 0.12 + 0.11 / en) * d),
        samples: (a.len(), b.len()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kolmogorov_survival_matches_tables() {
        // Critical values of the Kolmogorov distribution: 1.3581 at 0.05, 1.6276 at 0.01.
        assert!((kolmogorov_survival(1.358_1) - 0.05).abs() < 1e-4);
        assert!((kolmogorov_survival(1.627_6) - 0.01).abs() < 1e-4);
        assert_eq!(kolmogorov_survival(0.0), 1.0);
        assert!(kolmogorov_survival(5.0) < 1e-20);
    }

    #[test]
    fn ks_sees_a_shift_and_not_a_copy() {
        let a: Vec<f64> = (0..1000).map(|i| f64::from(i) / 1000.0).collect();
        let same = ks_two_sample(&a, &a);
        assert_eq!(same.statistic, 0.0);
        assert_eq!(same.p_value, 1.0);
        let b: Vec<f64> = a.iter().map(|x| x + 0.2).collect();
        let shifted = ks_two_sample(&a, &b);
        assert!((shifted.statistic - 0.2).abs() < 2e-3, "{shifted}");
        // lambda = (sqrt(500) + 0.12 + 0.11 / sqrt(500)) D = 4.50: Q ~ 2 exp(-2 lambda^2).
        let lambda = (500f64.sqrt() + 0.12 + 0.11 / 500f64.sqrt()) * shifted.statistic;
        let leading = 2.0 * (-2.0 * lambda * lambda).exp();
        assert!((shifted.p_value / leading - 1.0).abs() < 1e-6, "{shifted}");
        assert!(shifted.p_value < 1e-15, "{shifted}");
    }

    #[test]
    fn ks_one_sample_sees_a_uniform_grid_and_a_squeeze() {
        // The midpoints (i + 1/2) / n of [0, 1): D = 1 / (2n), p = 1.
        let grid: Vec<f64> = (0..1000).map(|i| (f64::from(i) + 0.5) / 1000.0).collect();
        let (d, p) = ks_one_sample(&grid, |u| u);
        assert!((d - 0.0005).abs() < 1e-12 && p == 1.0, "{d} {p}");
        // Squeezed into [0, 0.9): D = 1 - 0.9 (1 - 1 / (2n)) at the last point, far in the
        // tail.
        let squeezed: Vec<f64> = grid.iter().map(|u| u * 0.9).collect();
        let (d, p) = ks_one_sample(&squeezed, |u| u);
        assert!((d - 0.10045).abs() < 1e-9 && p < 1e-6, "{d} {p}");
    }

    #[test]
    fn two_sample_chi_square_pools_and_detects() {
        let a = [100, 100, 100, 100, 1, 0];
        let b = [200, 200, 200, 200, 1, 1];
        let r = chi_square_two_sample(&a, &b, 5.0);
        assert!(r.p_value > 0.5, "{r}");
        assert_eq!(r.samples, 1203);
        let c = [300, 100, 200, 200, 1, 1];
        let r = chi_square_two_sample(&a, &c, 5.0);
        assert!(r.p_value < 1e-6, "{r}");
    }
}
