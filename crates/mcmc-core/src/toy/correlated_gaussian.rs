//! An n-D Gaussian with a given mean and covariance (Cholesky factorised).

use rand::Rng;

use super::{impl_toy_target, standard_normal, Bins, ToyTarget};
use crate::special::{bisect_quantile, chi_square_cdf};
use crate::target::DifferentiableTarget;
use crate::McmcError;

/// Number of equal-probability bins of the whitened squared radius.
const RADIUS_BINS: usize = 8;

/// `N(mean, covariance)` on `R^n`, with the covariance factorised `Sigma = L L^T` (Cholesky).
///
/// Log density `-|z|^2 / 2 - sum_i ln L_ii - n ln(2 pi) / 2` with the whitened coordinates
/// `z = L^-1 (x - mean)`; gradient `-Sigma^-1 (x - mean) = -L^-T z`; exact draws
/// `mean + L z`, `z ~ N(0, I)`.
///
/// Bins: the squared whitened radius `|z|^2 ~ chi^2_n` cut into 8 equal-probability bins
/// (edges from the chi-square CDF, itself the regularised incomplete gamma), times the 4
/// quadrants of `(sign z_0, sign z_1)` (2 half-lines in 1-D). For a standard normal `z` the
/// radius is independent of the direction and every quadrant has probability 1/4 by
/// symmetry, so each of the 32 bins has probability exactly 1/32 (up to rounding of the
/// edges, which are recomputed from the CDF). A kernel that distorts the covariance changes
/// the radius distribution; one that drifts or skews changes the quadrant balance.
#[derive(Clone, Debug, PartialEq)]
pub struct CorrelatedGaussian {
    mean: Vec<f64>,
    /// Lower-triangular Cholesky factor, row-major `n x n`.
    chol: Vec<f64>,
    log_det_chol: f64,
}

impl CorrelatedGaussian {
    /// `N(mean, covariance)`; `covariance` is row-major `n x n` with `n = mean.len() >= 1`,
    /// symmetric (to `1e-12` relative) and positive definite.
    pub fn new(mean: Vec<f64>, covariance: &[f64]) -> Result<Self, McmcError> {
        let n = mean.len();
        if n == 0 || covariance.len() != n * n {
            return Err(McmcError::InvalidParameter {
                name: "covariance.len()",
                value: covariance.len() as f64,
                allowed: "mean.len()^2 with mean.len() >= 1",
            });
        }
        for &m in &mean {
            McmcError::check_range("mean", m, f64::MIN, f64::MAX, "finite")?;
        }
        for i in 0..n {
            for j in 0..i {
                let (a, b) = (covariance[i * n + j], covariance[j * n + i]);
                if !a.is_finite() || (a - b).abs() > 1e-12 * a.abs().max(b.abs()) {
                    return Err(McmcError::InvalidParameter {
                        name: "covariance[i][j] - covariance[j][i]",
                        value: a - b,
                        allowed: "a finite symmetric matrix",
                    });
                }
            }
        }
        let chol = cholesky(covariance, n).ok_or(McmcError::InvalidParameter {
            name: "covariance",
            value: f64::NAN,
            allowed: "a positive definite matrix",
        })?;
        let log_det_chol = (0..n).map(|i| chol[i * n + i].ln()).sum();
        Ok(Self {
            mean,
            chol,
            log_det_chol,
        })
    }

    /// Zero mean and the "AR(1)" covariance `Sigma_ij = s_i s_j rho^|i-j|` with scales
    /// `s_i` growing geometrically from `1/2` to `2` (anisotropic and strongly correlated for
    /// `rho` near 1). `n >= 1`, `|rho| < 1`.
    pub fn ar1(n: usize, rho: f64) -> Result<Self, McmcError> {
        McmcError::check_range("n", n as f64, 1.0, 1e4, "1..=10000")?;
        McmcError::check_range("rho", rho, -1.0 + 1e-12, 1.0 - 1e-12, "(-1, 1)")?;
        let scale = |i: usize| {
            if n == 1 {
                1.0
            } else {
                0.5 * 4f64.powf(i as f64 / (n - 1) as f64)
            }
        };
        let mut cov = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                cov[i * n + j] = scale(i) * scale(j) * rho.powi(i.abs_diff(j) as i32);
            }
        }
        Self::new(vec![0.0; n], &cov)
    }

    /// The mean.
    #[must_use]
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// The covariance `L L^T`, row-major.
    #[must_use]
    pub fn covariance(&self) -> Vec<f64> {
        let n = self.mean.len();
        let mut c = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                c[i * n + j] = (0..=i.min(j))
                    .map(|k| self.chol[i * n + k] * self.chol[j * n + k])
                    .sum();
            }
        }
        c
    }

    /// The whitened coordinates `z = L^-1 (x - mean)` (forward substitution).
    #[must_use]
    pub fn whiten(&self, x: &[f64]) -> Vec<f64> {
        let n = self.mean.len();
        let mut z = vec![0.0; n];
        for i in 0..n {
            let row = &self.chol[i * n..i * n + i];
            let s = x[i] - self.mean[i] - row.iter().zip(&z[..i]).map(|(l, v)| l * v).sum::<f64>();
            z[i] = s / self.chol[i * n + i];
        }
        z
    }
}

/// Cholesky factor of a row-major symmetric matrix, or `None` if it is not positive definite.
fn cholesky(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if s <= 0.0 || !s.is_finite() {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    Some(l)
}

impl ToyTarget for CorrelatedGaussian {
    fn name(&self) -> &'static str {
        "correlated Gaussian (n-D)"
    }

    fn dim(&self) -> usize {
        self.mean.len()
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        let z = self.whiten(x);
        let r2: f64 = z.iter().map(|v| v * v).sum();
        -0.5 * r2 - self.log_det_chol - self.mean.len() as f64 * super::HALF_LN_2PI
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let n = self.mean.len();
        let z: Vec<f64> = (0..n).map(|_| standard_normal(rng)).collect();
        (0..n)
            .map(|i| self.mean[i] + (0..=i).map(|k| self.chol[i * n + k] * z[k]).sum::<f64>())
            .collect()
    }

    fn bins(&self) -> Bins {
        let n = self.mean.len();
        let k = n as f64;
        let cdf = move |r2: f64| chi_square_cdf(r2, k);
        let hi = k + 40.0 * (2.0 * k).sqrt() + 100.0;
        let edges: Vec<f64> = (1..RADIUS_BINS)
            .map(|i| bisect_quantile(cdf, i as f64 / RADIUS_BINS as f64, 0.0, hi))
            .collect();
        let mut radius_probs = Vec::with_capacity(RADIUS_BINS);
        let mut prev = 0.0;
        for &e in &edges {
            let c = cdf(e);
            radius_probs.push(c - prev);
            prev = c;
        }
        radius_probs.push(1.0 - prev);
        let directions = if n >= 2 { 4 } else { 2 };
        let probabilities: Vec<f64> = radius_probs
            .iter()
            .flat_map(|&p| std::iter::repeat_n(p / directions as f64, directions))
            .collect();
        let this = self.clone();
        Bins::new(probabilities, move |x| {
            let z = this.whiten(x);
            let r2: f64 = z.iter().map(|v| v * v).sum();
            let radius = edges.partition_point(|&e| e <= r2);
            let mut direction = usize::from(z[0] >= 0.0);
            if n >= 2 {
                direction += 2 * usize::from(z[1] >= 0.0);
            }
            radius * directions + direction
        })
    }

    /// `mean_i +- 4 sqrt(Sigma_ii)` per coordinate (each marginal has mass `6.3e-5`
    /// outside).
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        let n = self.mean.len();
        let cov = self.covariance();
        let sd: Vec<f64> = (0..n).map(|i| cov[i * n + i].sqrt()).collect();
        (
            (0..n).map(|i| self.mean[i] - 4.0 * sd[i]).collect(),
            (0..n).map(|i| self.mean[i] + 4.0 * sd[i]).collect(),
        )
    }
}

impl_toy_target!(CorrelatedGaussian);

impl DifferentiableTarget for CorrelatedGaussian {
    fn evaluate_with_grad(&self, x: &mut Vec<f64>, _payload: &mut (), grad: &mut Vec<f64>) -> f64 {
        let n = self.mean.len();
        let z = self.whiten(x);
        // grad = -L^-T z (backward substitution).
        grad.clear();
        grad.resize(n, 0.0);
        for i in (0..n).rev() {
            let s = z[i]
                - (i + 1..n)
                    .map(|k| self.chol[k * n + i] * grad[k])
                    .sum::<f64>();
            grad[i] = s / self.chol[i * n + i];
        }
        for g in grad.iter_mut() {
            *g = -*g;
        }
        let r2: f64 = z.iter().map(|v| v * v).sum();
        -0.5 * r2 - self.log_det_chol - n as f64 * super::HALF_LN_2PI
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::target::finite_difference_gradient;
    use proptest::prelude::*;

    #[test]
    fn normalised_and_sampled_exactly() {
        let t2 = CorrelatedGaussian::new(vec![0.5, -1.0], &[1.0, 0.8, 0.8, 2.0]).unwrap();
        check_normalised(&t2, 800, 2e-3);
        check_sampler_matches_bins(&t2, 16);
        let t10 = CorrelatedGaussian::ar1(10, 0.9).unwrap();
        check_sampler_matches_bins(&t10, 17);
        let t1 = CorrelatedGaussian::ar1(1, 0.0).unwrap();
        check_normalised(&t1, 4000, 2e-4);
        check_sampler_matches_bins(&t1, 18);
        for p in t10.bins().probabilities() {
            assert!((p - 1.0 / 32.0).abs() < 1e-12);
        }
    }

    #[test]
    fn rejects_bad_covariances() {
        assert!(CorrelatedGaussian::new(vec![0.0; 2], &[1.0, 2.0, 2.0, 1.0]).is_err());
        assert!(CorrelatedGaussian::new(vec![0.0; 2], &[1.0, 0.5, 0.4, 1.0]).is_err());
        assert!(CorrelatedGaussian::new(vec![0.0; 2], &[1.0]).is_err());
        assert!(CorrelatedGaussian::ar1(3, 1.0).is_err());
    }

    #[test]
    fn covariance_round_trips() {
        let cov = [4.0, 1.0, 0.5, 1.0, 3.0, -0.2, 0.5, -0.2, 1.0];
        let t = CorrelatedGaussian::new(vec![0.0; 3], &cov).unwrap();
        for (a, b) in t.covariance().iter().zip(&cov) {
            assert!((a - b).abs() < 1e-14);
        }
    }

    proptest! {
        #[test]
        fn gradient_matches_finite_differences(x in prop::collection::vec(-4.0..4.0f64, 10)) {
            let t = CorrelatedGaussian::ar1(10, 0.9).unwrap();
            let mut g = Vec::new();
            let mut fd = Vec::new();
            let ld = t.evaluate_with_grad(&mut x.clone(), &mut (), &mut g);
            prop_assert!((ld - t.log_density(&x)).abs() < 1e-12);
            finite_difference_gradient(&t, &x, 1e-5, &mut fd);
            for (a, b) in g.iter().zip(&fd) {
                prop_assert!((a - b).abs() <= 1e-4 * (1.0 + a.abs()), "{g:?} vs {fd:?}");
            }
        }
    }
}
