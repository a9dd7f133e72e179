//! The isotropic Gaussian random walk on R^n, the reference proposal for adaptive scaling.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use super::{Proposal, Proposed, ScaledProposal};
use crate::McmcError;

/// Isotropic Gaussian random walk `y = x + sigma * N(0, I)` on `R^n` (`Vec<f64>` states).
/// Symmetric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianRandomWalk {
    sigma: f64,
}

impl GaussianRandomWalk {
    /// A random walk with standard deviation `sigma > 0` per coordinate.
    pub fn new(sigma: f64) -> Result<Self, McmcError> {
        McmcError::check_range("sigma", sigma, f64::MIN_POSITIVE, f64::MAX, "(0, inf)")?;
        Ok(Self { sigma })
    }

    /// The standard deviation per coordinate.
    #[must_use]
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    fn log_q_sigma(sigma: f64, from: &[f64], to: &[f64]) -> f64 {
        if from.len() != to.len() {
            return f64::NEG_INFINITY;
        }
        let d2: f64 = from.iter().zip(to).map(|(a, b)| (a - b) * (a - b)).sum();
        let n = from.len() as f64;
        -0.5 * d2 / (sigma * sigma) - n * (sigma.ln() + 0.5 * (2.0 * std::f64::consts::PI).ln())
    }

    fn propose_sigma<R: Rng + ?Sized>(sigma: f64, x: &[f64], y: &mut Vec<f64>, rng: &mut R) {
        y.clear();
        y.extend(x.iter().map(|&xi| {
            let z: f64 = StandardNormal.sample(rng);
            xi + sigma * z
        }));
    }
}

impl Proposal<Vec<f64>> for GaussianRandomWalk {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        Self::propose_sigma(self.sigma, x, y, rng);
        Proposed::symmetric()
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        Self::log_q_sigma(self.sigma, from, to)
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

/// `lambda = log sigma^2` (regional-adaptive paper, eq. 4).
impl ScaledProposal<Vec<f64>> for GaussianRandomWalk {
    fn propose_at_scale<R: Rng + ?Sized>(
        &self,
        lambda: f64,
        x: &Vec<f64>,
        y: &mut Vec<f64>,
        rng: &mut R,
    ) -> Proposed {
        Self::propose_sigma((0.5 * lambda).exp(), x, y, rng);
        Proposed::symmetric()
    }

    fn log_q_at_scale(&self, lambda: f64, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        Self::log_q_sigma((0.5 * lambda).exp(), from, to)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_sigma() {
        assert!(GaussianRandomWalk::new(0.0).is_err());
        assert!(GaussianRandomWalk::new(f64::NAN).is_err());
        assert!(GaussianRandomWalk::new(-1.0).is_err());
    }

    #[test]
    fn density_is_normalised_in_1d() {
        let q = GaussianRandomWalk::new(0.3).unwrap();
        let h = 1e-3;
        let total: f64 = (-3000..3000)
            .map(|i| q.log_q(&vec![0.0], &vec![i as f64 * h]).exp() * h)
            .sum();
        assert!((total - 1.0).abs() < 1e-6, "{total}");
    }
}
