//! The Gaussian a MALA step proposes from: `N(u + Sigma m / 2, Sigma)`, diagonal or full.

#[cfg(feature = "nalgebra")]
use nalgebra::{DMatrix, DVector};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use super::params::LangevinParams;

const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_7;

/// The proposal Gaussian of one MALA step, as an *offset* from the point it is formed at:
/// `offset ~ N(mu, Sigma)` with `Sigma = epsilon M` and `mu = Sigma m / 2` (Luan et al. 2020,
/// eq. 8-9, 18, 28). Diagonal `Sigma` (the paper's algorithms)
/// or full `Sigma` (its Fig. 2 comparison, section 5; feature `nalgebra`), stored with its
/// Cholesky factor.
///
/// Buffers are reused: forming a Gaussian of the same dimension again does not allocate
/// (the full form allocates its matrices; it exists for the 2-D comparison).
///
/// # Example
/// ```
/// use mcmc_core::langevin::{LangevinParams, ProposalGaussian};
///
/// let params = LangevinParams::luan2020();
/// let mut q = ProposalGaussian::default();
/// // Plain MALA (M = I) with gradient (1, -2): mean = epsilon g / 2.
/// q.set_diagonal(&params, &[1.0, 1.0], &[1.0, -2.0]);
/// assert!((q.mean()[0] - 0.005).abs() < 1e-15 && (q.mean()[1] + 0.01).abs() < 1e-15);
/// assert!((q.std()[0] - 0.1).abs() < 1e-15);
/// ```
#[derive(Clone, Debug, Default)]
pub struct ProposalGaussian {
    mean: Vec<f64>,
    std: Vec<f64>,
    /// Lower Cholesky factor of `Sigma` for the full form.
    #[cfg(feature = "nalgebra")]
    chol: Option<DMatrix<f64>>,
    /// `-sum ln std_i - d ln sqrt(2 pi)` (or the full form's `-ln det L - ...`).
    log_norm: f64,
}

impl ProposalGaussian {
    /// Forms the diagonal Gaussian from the preconditioner diagonal `m_diag` (`M_ii`, clamped
    /// to [`LangevinParams::preconditioner_range`]) and the drift `drift` (`m`, clamped to
    /// [`LangevinParams::drift_clamp`]):
    /// `Sigma_ii = 1 / (1 / S_ii + 1 / max_std^2)`, `mu_i = Sigma_ii m_i / 2`, with
    /// `S_ii = epsilon M_ii` or `epsilon^2 (M_ii + 1)` ([`super::Covariance`]).
    pub fn set_diagonal(&mut self, params: &LangevinParams, m_diag: &[f64], drift: &[f64]) {
        debug_assert_eq!(m_diag.len(), drift.len());
        #[cfg(feature = "nalgebra")]
        {
            self.chol = None;
        }
        self.mean.clear();
        self.std.clear();
        let [lo, hi] = params.preconditioner_range;
        let prior = 1.0 / (params.max_std * params.max_std);
        let mut log_norm = 0.0;
        let c = params.drift_clamp;
        for (&m, &d) in m_diag.iter().zip(drift) {
            let m = m.clamp(lo, hi);
            let s = match params.covariance {
                super::Covariance::EpsilonM => params.epsilon * m,
                super::Covariance::EpsilonSquaredMPlusOne => {
                    params.epsilon * params.epsilon * (m + 1.0)
                }
            };
            let var = 1.0 / (1.0 / s + prior);
            self.mean.push(0.5 * var * d.clamp(-c, c));
            let s = var.sqrt();
            self.std.push(s);
            log_norm -= s.ln() + LN_SQRT_2PI;
        }
        self.log_norm = log_norm;
    }

    /// Forms the full Gaussian from a symmetric positive definite preconditioner `m`
    /// (`d x d`) and the drift: `Sigma = (1 / (epsilon M) + I / max_std^2)^-1` in the
    /// matrix sense, `mu = Sigma m / 2`. Returns `false` (leaving an isotropic Gaussian of
    /// variance `epsilon`) if `Sigma` is not positive definite.
    #[cfg(feature = "nalgebra")]
    pub fn set_full(&mut self, params: &LangevinParams, m: &DMatrix<f64>, drift: &[f64]) -> bool {
        let d = drift.len();
        let mut sigma = match params.covariance {
            super::Covariance::EpsilonM => m * params.epsilon,
            super::Covariance::EpsilonSquaredMPlusOne => {
                (m + DMatrix::<f64>::identity(d, d)) * (params.epsilon * params.epsilon)
            }
        };
        if params.max_std.is_finite() {
            let prior = DMatrix::<f64>::identity(d, d) / (params.max_std * params.max_std);
            let precision = match sigma.clone().try_inverse() {
                Some(p) => p + prior,
                None => return self.isotropic_fallback(params, d),
            };
            sigma = match precision.try_inverse() {
                Some(s) => s,
                None => return self.isotropic_fallback(params, d),
            };
        }
        let Some(chol) = nalgebra::Cholesky::new(sigma.clone()) else {
            return self.isotropic_fallback(params, d);
        };
        let c = params.drift_clamp;
        let drift: Vec<f64> = drift.iter().map(|v| v.clamp(-c, c)).collect();
        let mean = &sigma * DVector::from_column_slice(&drift) * 0.5;
        self.mean.clear();
        self.mean.extend(mean.iter());
        let l = chol.l();
        self.std.clear();
        self.std.extend((0..d).map(|i| l[(i, i)]));
        self.log_norm = -self.std.iter().map(|s| s.ln()).sum::<f64>() - d as f64 * LN_SQRT_2PI;
        self.chol = Some(l);
        true
    }

    #[cfg(feature = "nalgebra")]
    fn isotropic_fallback(&mut self, params: &LangevinParams, d: usize) -> bool {
        let ones = vec![1.0; d];
        let zeros = vec![0.0; d];
        self.set_diagonal(
            &LangevinParams {
                preconditioner_range: [0.0, f64::INFINITY],
                ..*params
            },
            &ones,
            &zeros,
        );
        false
    }

    /// Dimension.
    #[must_use]
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// The mean offset `mu`.
    #[must_use]
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Per-dimension standard deviations (the diagonal of the Cholesky factor for the full
    /// form).
    #[must_use]
    pub fn std(&self) -> &[f64] {
        &self.std
    }

    /// True for the full (non-diagonal) form.
    #[must_use]
    pub fn is_full(&self) -> bool {
        #[cfg(feature = "nalgebra")]
        {
            self.chol.is_some()
        }
        #[cfg(not(feature = "nalgebra"))]
        {
            false
        }
    }

    /// Draws an offset into `out` (resized to the dimension).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut Vec<f64>) {
        out.clear();
        #[cfg(feature = "nalgebra")]
        if let Some(l) = &self.chol {
            let d = self.mean.len();
            let w: Vec<f64> = (0..d).map(|_| StandardNormal.sample(rng)).collect();
            for i in 0..d {
                let lw: f64 = (0..=i).map(|j| l[(i, j)] * w[j]).sum();
                out.push(self.mean[i] + lw);
            }
            return;
        }
        for (&m, &s) in self.mean.iter().zip(&self.std) {
            let w: f64 = StandardNormal.sample(rng);
            out.push(m + s * w);
        }
    }

    /// Log density of the offset `offset` on `R^d`.
    #[must_use]
    pub fn log_density(&self, offset: &[f64]) -> f64 {
        debug_assert_eq!(offset.len(), self.mean.len());
        #[cfg(feature = "nalgebra")]
        if let Some(l) = &self.chol {
            // Solve L z = offset - mu by forward substitution.
            let d = self.mean.len();
            let mut q = 0.0;
            let mut z = [0.0f64; 64];
            let mut zv = Vec::new();
            let z: &mut [f64] = if d <= 64 {
                &mut z[..d]
            } else {
                zv.resize(d, 0.0);
                &mut zv
            };
            for i in 0..d {
                let s: f64 = (0..i).map(|j| l[(i, j)] * z[j]).sum();
                z[i] = (offset[i] - self.mean[i] - s) / l[(i, i)];
                q += z[i] * z[i];
            }
            return self.log_norm - 0.5 * q;
        }
        let q: f64 = offset
            .iter()
            .zip(&self.mean)
            .zip(&self.std)
            .map(|((&o, &m), &s)| {
                let z = (o - m) / s;
                z * z
            })
            .sum();
        self.log_norm - 0.5 * q
    }

    /// Log density of landing at displacement `offset` (each component in `[-1/2, 1/2]`)
    /// on the unit torus: a *wrapped* Gaussian, summed over the periodic images
    /// `offset_i + k` within `9 std_i + 1` of the mean (omitted images below `1e-17`
    /// relative).
    /// Diagonal form only (the images of a full Gaussian do not factorise): `NaN` for the
    /// full form.
    #[must_use]
    pub fn log_density_wrapped(&self, offset: &[f64]) -> f64 {
        if self.is_full() {
            return f64::NAN;
        }
        let mut total = 0.0;
        for ((&o, &m), &s) in offset.iter().zip(&self.mean).zip(&self.std) {
            // Images k with |o + k - m| <= 9 s (+1 on each side).
            let kmin = ((m - o) - 9.0 * s).floor() as i64 - 1;
            let kmax = ((m - o) + 9.0 * s).ceil() as i64 + 1;
            // log-sum-exp over images, anchored at the largest term.
            let best = (kmin..=kmax)
                .map(|k| {
                    let z = (o + k as f64 - m) / s;
                    -0.5 * z * z
                })
                .fold(f64::NEG_INFINITY, f64::max);
            let sum: f64 = (kmin..=kmax)
                .map(|k| {
                    let z = (o + k as f64 - m) / s;
                    (-0.5 * z * z - best).exp()
                })
                .sum();
            total += best + sum.ln() - s.ln() - LN_SQRT_2PI;
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn the_code_semantics_floor_the_step_and_clamp_the_drift() {
        // The paper's text: Sigma = epsilon M, no clamp.
        let text = LangevinParams::luan2020();
        let mut q = ProposalGaussian::default();
        q.set_diagonal(&text, &[0.0001, 100.0], &[40.0, -40.0]);
        assert!((q.std[0] - (0.01f64 * 0.0001).sqrt()).abs() < 1e-15);
        assert!((q.mean[0] - 0.5 * 0.01 * 0.0001 * 40.0).abs() < 1e-15);
        // The paper's values with the code's semantics: Sigma = epsilon^2 (M + 1), M clamped
        // to [0.01, 100], drift clamped to +-5: sigma from 0.01 to about 0.1.
        let values = LangevinParams::luan2020_values();
        q.set_diagonal(&values, &[0.0001, 1e6], &[40.0, -40.0]);
        let var: [f64; 2] = [1e-4 * 1.01, 1e-4 * 101.0];
        for (i, v) in var.iter().enumerate() {
            assert!((q.std[i] - v.sqrt()).abs() < 1e-15, "{i}");
        }
        assert!((q.mean[0] - 0.5 * var[0] * 5.0).abs() < 1e-15);
        assert!((q.mean[1] + 0.5 * var[1] * 5.0).abs() < 1e-15);
        // The code: the shrink prior's precision is added.
        let code = LangevinParams::luan2020_code();
        q.set_diagonal(&code, &[1.0], &[0.0]);
        let var = 1.0 / (1.0 / (0.005f64 * 0.005 * 2.0) + 1.0 / (0.005f64 * 0.005));
        assert!((q.std[0] - var.sqrt()).abs() < 1e-15);
        // Radius per dimension.
        assert_eq!(text.query_radius(16), 0.01);
        assert!((values.query_radius(16) - 0.04).abs() < 1e-15);
        let mut bad = values;
        bad.drift_clamp = 0.0;
        assert!(bad.validate().is_err());
    }

    #[cfg(feature = "nalgebra")]
    #[test]
    fn diagonal_and_full_agree_for_a_diagonal_matrix() {
        let p = LangevinParams::luan2020();
        let mut a = ProposalGaussian::default();
        let mut b = ProposalGaussian::default();
        a.set_diagonal(&p, &[2.0, 0.5], &[3.0, -1.0]);
        let m = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 0.5]);
        assert!(b.set_full(&p, &m, &[3.0, -1.0]));
        for o in [[0.0, 0.0], [0.1, -0.2], [-0.3, 0.05]] {
            assert!((a.log_density(&o) - b.log_density(&o)).abs() < 1e-12);
        }
        assert!((a.mean()[0] - b.mean()[0]).abs() < 1e-15);
    }

    #[test]
    fn wrapped_density_integrates_to_one() {
        let p = LangevinParams {
            epsilon: 0.09,
            ..LangevinParams::luan2020()
        };
        let mut q = ProposalGaussian::default();
        q.set_diagonal(&p, &[1.0], &[4.0]); // std 0.3, mean 0.18
        let n = 20_000;
        let sum: f64 = (0..n)
            .map(|i| {
                let o = -0.5 + (i as f64 + 0.5) / n as f64;
                q.log_density_wrapped(&[o]).exp() / n as f64
            })
            .sum();
        assert!((sum - 1.0).abs() < 1e-9, "{sum}");
    }

    #[cfg(feature = "nalgebra")]
    #[test]
    fn samples_match_the_moments() {
        let p = LangevinParams::luan2020();
        let mut q = ProposalGaussian::default();
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.8, 0.8, 1.0]);
        q.set_full(&p, &m, &[10.0, 0.0]);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
        let mut out = Vec::new();
        let (mut s0, mut s01) = (0.0, 0.0);
        let n = 200_000;
        for _ in 0..n {
            q.sample(&mut rng, &mut out);
            s0 += out[0];
            s01 += (out[0] - q.mean()[0]) * (out[1] - q.mean()[1]);
        }
        // mean = eps M m / 2 = 0.01 * (10, 8) / 2; cov_01 = 0.008.
        assert!((s0 / n as f64 - 0.05).abs() < 1e-3);
        assert!((s01 / n as f64 - 0.008).abs() < 3e-4);
    }
}
