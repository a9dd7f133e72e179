//! The 1-D mixture of two uniforms of the DR paper (eq. 8): a narrow spike next to a plateau.

use rand::{Rng, RngExt};

use super::{check_positive, impl_toy_target, uniform_edges, Bins, ToyTarget};
use crate::McmcError;

/// `pi(x) = 1/(2a) 1[-a, 0)(x) + 1/(2b) 1[0, b)(x)`: half the mass in a spike of width `a`,
/// half on a plateau of width `b` (DR paper, section 4.2, eq. 8, which writes alpha and beta).
///
/// With `a << b` a random walk tuned for one piece is badly tuned for the other: the DR
/// paper's motivating example for delayed rejection, and a natural test of regional
/// adaptation.
///
/// Bins: the CDF is piecewise linear, so bin probabilities are exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformMixture {
    a: f64,
    b: f64,
}

impl UniformMixture {
    /// The mixture with spike width `a > 0` and plateau width `b > 0`.
    pub fn new(a: f64, b: f64) -> Result<Self, McmcError> {
        check_positive("a", a)?;
        check_positive("b", b)?;
        Ok(Self { a, b })
    }

    /// The DR paper's values (section 4.2): `a = 1/10`, `b = 1`.
    #[must_use]
    pub const fn rioux_lavoie2020() -> Self {
        Self { a: 0.1, b: 1.0 }
    }

    /// Spike width `a`.
    #[must_use]
    pub fn a(&self) -> f64 {
        self.a
    }

    /// Plateau width `b`.
    #[must_use]
    pub fn b(&self) -> f64 {
        self.b
    }

    /// The exact CDF.
    #[must_use]
    pub fn cdf(&self, x: f64) -> f64 {
        if x < -self.a {
            0.0
        } else if x < 0.0 {
            0.5 * (x + self.a) / self.a
        } else if x < self.b {
            0.5 + 0.5 * x / self.b
        } else {
            1.0
        }
    }
}

impl ToyTarget for UniformMixture {
    fn name(&self) -> &'static str {
        "uniform mixture (1-D)"
    }

    fn dim(&self) -> usize {
        1
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        let x = x[0];
        if x >= -self.a && x < 0.0 {
            -(2.0 * self.a).ln()
        } else if (0.0..self.b).contains(&x) {
            -(2.0 * self.b).ln()
        } else {
            f64::NEG_INFINITY
        }
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let u: f64 = rng.random();
        if rng.random::<bool>() {
            vec![-self.a + self.a * u]
        } else {
            vec![self.b * u]
        }
    }

    /// 8 bins on the spike, 24 on the plateau, and the two (empty) tails.
    fn bins(&self) -> Bins {
        let mut edges = uniform_edges(-self.a, 0.0, 8);
        edges.pop();
        edges.extend(uniform_edges(0.0, self.b, 24));
        let this = *self;
        Bins::from_cdf(edges, move |x| this.cdf(x), |x| x[0])
    }

    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![-self.a], vec![self.b])
    }
}

impl_toy_target!(UniformMixture);

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    #[test]
    fn normalised_and_sampled_exactly() {
        let t = UniformMixture::rioux_lavoie2020();
        check_normalised(&t, 1100, 1e-12);
        check_sampler_matches_bins(&t, 11);
        assert!(UniformMixture::new(0.0, 1.0).is_err());
        assert_eq!(t.log_density(&[1.0]), f64::NEG_INFINITY);
        assert_eq!(t.log_density(&[-0.1]), -(0.2f64).ln());
        assert_eq!(t.cdf(0.0), 0.5);
    }
}
