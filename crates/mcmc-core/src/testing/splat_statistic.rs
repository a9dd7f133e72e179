//! The splat-weight statistic: a chi-square for a weighted histogram at the hypothesis' scale.
//!
//! [`SplatMoments::test`] derives the statistic; [`SplatWeightReport`] carries its outcome.

use std::fmt;

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::chi_square::{sidak_alpha, survival, ALPHA};
use super::splat_moments::SplatMoments;

/// Largest deviation of the mean splat from `p` tolerated along a direction in which every
/// start contributed exactly the same (see [`SplatMoments::test`]): far above rounding (`1e-15`
/// per operation) and the accuracy of exact bin probabilities (`1e-12`), far below any real
/// bias.
pub const DETERMINISTIC_TOLERANCE: f64 = 1e-9;

/// Relative eigenvalue below which a direction of the sample covariance counts as having
/// zero variance.
const RELATIVE_EIGEN_FLOOR: f64 = 1e-10;

/// The outcome of a splat-weight test.
#[derive(Clone, Debug, PartialEq)]
pub struct SplatWeightReport {
    /// The Bartlett-corrected statistic `T r / (r + e)` ([`SplatMoments::test`]; `+inf` for
    /// weight in impossible bins or a deviation along a direction without variance).
    pub statistic: f64,
    /// Degrees of freedom `r`: the free directions of the per-start vectors.
    pub degrees_of_freedom: usize,
    /// The Bartlett factor `r / (r + e)` (1 for equal weights).
    pub bartlett_factor: f64,
    /// `P(chi^2_r >= statistic)`: uniform on `[0, 1]` under the hypothesis (asymptotically).
    pub p_value: f64,
    /// Number of starts `N`.
    pub starts: usize,
    /// Mean over starts of the total weight one step splatted (1 for MH).
    pub mean_total_weight: f64,
    /// Total absolute weight splatted into bins of probability 0.
    pub impossible_weight: f64,
    /// The pooled bin whose mean weight deviates most (in standard errors under the
    /// hypothesis) from its probability: (original bins, total weight splatted there,
    /// expected `N p`, z-score).
    pub worst_bin: Option<(Vec<usize>, f64, f64, f64)>,
}

impl fmt::Display for SplatWeightReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "T = {:.3} with {} dof (Bartlett factor {:.4}), p = {:.3e} ({} starts, mean total \
             weight {:.5}, {:.3} weight in zero-probability bins",
            self.statistic,
            self.degrees_of_freedom,
            self.bartlett_factor,
            self.p_value,
            self.starts,
            self.mean_total_weight,
            self.impossible_weight
        )?;
        if let Some((bins, w, e, z)) = &self.worst_bin {
            write!(
                f,
                "; worst bin(s) {bins:?}: weight {w:.1}, expected {e:.1}, z = {z:.2}"
            )?;
        }
        write!(f, ")")
    }
}

impl SplatWeightReport {
    /// True if the test rejects at level `alpha` (also when it has no degree of freedom or
    /// could not be evaluated).
    #[must_use]
    pub fn rejects(&self, alpha: f64) -> bool {
        self.degrees_of_freedom == 0 || self.p_value.is_nan() || self.p_value < alpha
    }

    /// Panics unless the test passes at the Sidak-corrected level for `tests_in_file` tests
    /// sharing the overall level [`ALPHA`].
    #[track_caller]
    pub fn assert_passes(&self, what: &str, tests_in_file: usize) {
        let level = sidak_alpha(ALPHA, tests_in_file);
        assert!(
            !self.rejects(level),
            "{what}: splat-weight test rejects at level {level:.2e} (alpha = {ALPHA}, Sidak \
             over {tests_in_file} tests): {self}"
        );
    }
}

impl SplatMoments {
    /// The splat-weight test: the statistic, its p-value and diagnostics.
    ///
    /// # Hypothesis
    /// Start `i` of `N` contributes `c_i`, the weight its step splatted into each of the `B`
    /// pooled bins; the `c_i` are i.i.d. with covariance `Sigma`, and the hypothesis is that
    /// their mean is `p`. With `d = m - p` (`m` the mean of the `c_i`),
    /// `sqrt(N) d -> Normal(0, Sigma)`, so `N d^T Sigma^-1 d` is asymptotically chi-square;
    /// the estimate of `Sigma` decides how close to chi-square it is at harness sizes.
    ///
    /// # Why not the sample covariance `S`
    /// A bin of expected weight `N p_b = 20` gets its weight from a few dozen starts, and its
    /// sample variance, like its mean, is a sum over those starts. For unit weights (a
    /// Poisson count `k` of mean `l`) the bin's term of Hotelling's `N d^T S^-1 d` is
    /// Neyman's `(k - l)^2 / k`, of mean `1 + 2 / l + O(l^-2)`: ten percent too large at
    /// `l = 20`, and over a hundred bins the p-values are far from uniform
    /// (`tests/splat_weight_calibration.rs` measures it). Pearson's cure: take the scale of
    /// the variance from the hypothesis (`p_b`), not from the data (`m_b`).
    ///
    /// # The covariance under the hypothesis
    /// The data give the *shape* of the weights, `R_jk = M_jk / sqrt(m_j m_k)` with
    /// `M = sum_i c_i c_i^T / N` (`R_bb = sum_i c_ib^2 / sum_i c_ib`, the mean squared weight
    /// per unit of weight, which does not grow with the number of starts in the bin); the
    /// hypothesis gives the scale, `E[c c^T] ~ D R D` with `D = diag(sqrt(p))`:
    /// `V = D R D - p p^T`. For unit weights `V = diag(p) - p p^T` and the test below is
    /// Pearson's. (Rescaling `S` to `S_jk sqrt(p_j p_k / (m_j m_k))` instead would misstate
    /// aggregate directions such as the total weight at first order in `d`, which `p p^T`
    /// cancels.) A bin with `m_b <= 0` keeps its raw second moment.
    ///
    /// # The statistic
    /// Directions in which every start contributes the same (e.g. the total weight when
    /// weights sum to 1) are the eigen-directions of `S` with eigenvalue at most `1e-10`
    /// times the largest; along them `d` must vanish to within [`DETERMINISTIC_TOLERANCE`],
    /// else the statistic is infinite. With `U` the other eigenvectors and `y = U^T d`,
    /// `T = N y^T (U^T V U)^+ y` with `r = rank(U^T V U)` degrees of freedom (pseudo-inverse
    /// over eigenvalues above `1e-10` times the largest). Under the hypothesis `U^T V U` is
    /// positive definite; far from it `V` may not be, and a deviation along a direction
    /// without positive variance makes the statistic infinite, as does weight in a bin of
    /// probability 0.
    ///
    /// # Bartlett correction
    /// `R_bb` still moves with the bin's weights (a start splatting a large weight raises both
    /// `d_b` and `R_bb`), so `E[T] = r + e`. For one sparse bin, with `S_j = sum_i c_ib^j`,
    /// the delta method to second order in the fluctuations of `(m_b, M_bb)` gives
    ///
    /// ```text
    /// E[N d_b^2 / V_bb] = 1 + 2 g / (S_1^2 S_2) + 2 g^2 / (S_1^2 S_2^3),  g = S_1 S_3 - S_2^2
    /// ```
    ///
    /// (the first term from the ratio's covariance with `d_b^2` and its variance, the second
    /// from its squared covariance with `d_b`; `O(1 / k)` for `k` contributing starts;
    /// `g >= 0` by Cauchy-Schwarz, `g = 0` for equal weights). In `T` a bin enters with its
    /// leverage `f_b = (V^+)_bb V_bb` (1 for a diagonal `V`), which scales the first term by
    /// `f_b^2` and the second by `f_b^3`; `e` sums the bins' terms (each at least 0). The
    /// report gives `T r / (r + e)` and `P(chi^2_r >= T r / (r + e))`. The same correlation
    /// widens the law of `T` a little, uncorrected; it matters most with many sparse bins and
    /// unequal weights, the setting of the calibration sweep.
    #[must_use]
    pub fn test(&self) -> SplatWeightReport {
        let n = self.starts() as f64;
        let p = self.probabilities();
        let deviation = self.mean() - p;
        let (free, deterministic_bias) = free_directions(&self.sample_covariance(), &deviation);
        let null = self.null_covariance();
        let restricted = SymmetricEigen::new(free.transpose() * &null * &free);
        let largest = restricted.eigenvalues.iter().copied().fold(0.0, f64::max);
        // Whitened coordinates of the deviation and the columns of U E Lambda^-1/2, over the
        // eigenvalues kept by the pseudo-inverse; a deviation along any other direction
        // contradicts the hypothesis.
        let mut whitened = Vec::new();
        let mut columns = Vec::new();
        let mut without_variance = false;
        for (k, &lambda) in restricted.eigenvalues.iter().enumerate() {
            let direction = &free * restricted.eigenvectors.column(k);
            let along = direction.dot(&deviation);
            if largest > 0.0 && lambda > RELATIVE_EIGEN_FLOOR * largest {
                whitened.push(along / lambda.sqrt());
                columns.push(direction / lambda.sqrt());
            } else if along.abs() > DETERMINISTIC_TOLERANCE {
                without_variance = true;
            }
        }
        let r = columns.len();
        let bartlett_factor = if r == 0 {
            1.0
        } else {
            // The diagonal of V^+ = sum_k u_k u_k^T / lambda_k.
            let inverse_diagonal = columns
                .iter()
                .fold(DVector::zeros(p.len()), |acc, c| acc + c.component_mul(c));
            r as f64 / (r as f64 + self.bartlett_excess(&inverse_diagonal, &null))
        };
        let statistic = if deterministic_bias || without_variance || self.impossible_weight() > 0.0
        {
            f64::INFINITY
        } else {
            n * whitened.iter().map(|z| z * z).sum::<f64>() * bartlett_factor
        };
        let p_value = if r == 0 {
            1.0
        } else {
            survival(statistic, r as f64)
        };
        let worst_bin = (0..deviation.len())
            .map(|k| {
                let se = (null[(k, k)] / n).max(0.0).sqrt();
                let z = if se > 0.0 {
                    deviation[k] / se
                } else if deviation[k].abs() > DETERMINISTIC_TOLERANCE {
                    f64::INFINITY.copysign(deviation[k])
                } else {
                    0.0
                };
                (k, z)
            })
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map(|(k, z)| (self.groups()[k].clone(), self.sum()[k], n * p[k], z));
        SplatWeightReport {
            statistic,
            degrees_of_freedom: r,
            bartlett_factor,
            p_value,
            starts: self.starts(),
            mean_total_weight: self.mean_total_weight(),
            impossible_weight: self.impossible_weight(),
            worst_bin,
        }
    }

    /// The excess `e` of the mean of `T` over `r` ([`SplatMoments::test`]), from the
    /// diagonal of `V^+`.
    fn bartlett_excess(&self, inverse_diagonal: &DVector<f64>, null: &DMatrix<f64>) -> f64 {
        (0..inverse_diagonal.len())
            .map(|b| {
                let leverage = inverse_diagonal[b] * null[(b, b)];
                let (s1, s2, s3) = (self.sum()[b], self.cross()[(b, b)], self.cubes()[b]);
                bartlett_term(s1, s2, s3, leverage)
            })
            .sum()
    }
}

/// The eigen-directions of the sample covariance with variance (as the columns of `U`), and
/// whether the deviation exceeds [`DETERMINISTIC_TOLERANCE`] along one without.
fn free_directions(sample: &DMatrix<f64>, deviation: &DVector<f64>) -> (DMatrix<f64>, bool) {
    let eigen = SymmetricEigen::new(sample.clone());
    let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut deterministic_bias = false;
    let mut free = Vec::new();
    for (k, &lambda) in eigen.eigenvalues.iter().enumerate() {
        let direction = eigen.eigenvectors.column(k);
        if largest > 0.0 && lambda > RELATIVE_EIGEN_FLOOR * largest {
            free.push(direction.into_owned());
        } else if direction.dot(deviation).abs() > DETERMINISTIC_TOLERANCE {
            deterministic_bias = true;
        }
    }
    let free = if free.is_empty() {
        DMatrix::zeros(deviation.len(), 0)
    } else {
        DMatrix::from_columns(&free)
    };
    (free, deterministic_bias)
}

/// One bin's share of the Bartlett excess `e` ([`SplatMoments::test`]) from its sample moments
/// `S_1, S_2, S_3` and its leverage `f`: `f^2 2 g / (S_1^2 S_2) + f^3 2 g^2 / (S_1^2 S_2^3)`,
/// `g = S_1 S_3 - S_2^2`; 0 without positive weight, and never negative.
fn bartlett_term(s1: f64, s2: f64, s3: f64, leverage: f64) -> f64 {
    if !(s1 > 0.0 && s2 > 0.0) {
        return 0.0;
    }
    let g = s1 * s3 - s2 * s2;
    let f = leverage;
    let term =
        f * f * 2.0 * g / (s1 * s1 * s2) + f * f * f * 2.0 * g * g / (s1 * s1 * s2 * s2 * s2);
    if term.is_finite() {
        term.max(0.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `counts[b]` starts each splatting weight 1 into bin `b`.
    fn multinomial(counts: &[usize], p: &[f64]) -> SplatMoments {
        let mut moments = SplatMoments::new((0..p.len()).map(|b| vec![b]).collect(), p.to_vec());
        for (b, &count) in counts.iter().enumerate() {
            for _ in 0..count {
                moments.push(&[(b, 1.0)], 1.0, 0.0);
            }
        }
        moments
    }

    #[test]
    fn bartlett_term_vanishes_for_equal_weights_only() {
        // k starts of weight 1: no correction, whatever the leverage.
        assert_eq!(bartlett_term(40.0, 40.0, 40.0, 1.3), 0.0);
        // k = 100 starts, half with weight 1/2 and half with weight 1: S_1 = 75,
        // S_2 = 62.5, S_3 = 56.25, g = 312.5; the two terms are 0.17778 / k and
        // 0.014222 / k at leverage 1.
        let e = bartlett_term(75.0, 62.5, 56.25, 1.0);
        let expected = 2.0 * 312.5 / (75.0 * 75.0 * 62.5)
            + 2.0 * 312.5 * 312.5 / (75.0 * 75.0 * 62.5 * 62.5 * 62.5);
        assert!(
            (e - expected).abs() < 1e-15 && (e - 0.0019200).abs() < 1e-6,
            "{e}"
        );
        // Leverage multiplies the terms by f^2 and f^3.
        let f = 1.5;
        let scaled = bartlett_term(75.0, 62.5, 56.25, f);
        let first = 2.0 * 312.5 / (75.0 * 75.0 * 62.5);
        assert!((scaled - (f * f * first + f * f * f * (expected - first))).abs() < 1e-15);
        // No weight: no correction; a negative total (signed weights, g < 0) is clamped.
        assert_eq!(bartlett_term(0.0, 0.0, 0.0, 1.0), 0.0);
        assert_eq!(bartlett_term(10.0, 20.0, 10.0, 1.0), 0.0);
    }

    #[test]
    fn unit_weights_give_pearsons_test() {
        let report = multinomial(&[520, 290, 190], &[0.5, 0.3, 0.2]).test();
        // 20^2 / 500 + 10^2 / 300 + 10^2 / 200 with two degrees of freedom.
        let pearson = 0.8 + 1.0 / 3.0 + 0.5;
        assert!((report.statistic - pearson).abs() < 1e-9, "{report}");
        assert_eq!(report.degrees_of_freedom, 2);
        assert_eq!(report.bartlett_factor, 1.0, "{report}");
        let p = (-pearson / 2.0).exp();
        assert!((report.p_value - p).abs() < 1e-9, "{report}");
        // At the hypothesis itself, exactly 0.
        let exact = multinomial(&[500, 300, 200], &[0.5, 0.3, 0.2]).test();
        assert!(
            exact.statistic.abs() < 1e-20 && exact.p_value == 1.0,
            "{exact}"
        );
    }

    #[test]
    fn deterministic_and_impossible_deviations_are_infinite() {
        // Every start splats weight 1, but the bins hold only 0.9 of the probability: the
        // deviation of the total weight has no variance.
        let report = multinomial(&[520, 290, 190], &[0.45, 0.27, 0.18]).test();
        assert_eq!(report.statistic, f64::INFINITY, "{report}");
        assert_eq!(report.p_value, 0.0);
        assert!(report.rejects(1e-12));
        let mut moments = multinomial(&[520, 290, 190], &[0.5, 0.3, 0.2]);
        moments.push(&[], 1.0, 1.0);
        assert_eq!(moments.test().p_value, 0.0);
    }

    #[test]
    fn a_deviation_without_variance_under_the_hypothesis_is_infinite() {
        // 3000 starts: a third splat 0.2 into bin 0, a third 0.2 into bin 1, a third nothing,
        // against p = (1/2, 1/2): V = diag(0.1, 0.1) - p p^T has variance -0.4 along (1, 1),
        // where the mean falls short by 0.43 per bin. The direction must not be dropped.
        let mut moments = SplatMoments::new(vec![vec![0], vec![1]], vec![0.5, 0.5]);
        for _ in 0..1000 {
            moments.push(&[(0, 0.2)], 0.2, 0.0);
            moments.push(&[(1, 0.2)], 0.2, 0.0);
            moments.push(&[], 0.0, 0.0);
        }
        let report = moments.test();
        assert_eq!(report.statistic, f64::INFINITY, "{report}");
        assert!(report.rejects(1e-12));
    }
}
