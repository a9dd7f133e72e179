//! A thin rotated Gaussian ridge in 2-D: the anisotropic target of the toy set.

use rand::Rng;

use super::{check_positive, impl_toy_target, standard_normal, uniform_edges, Bins, ToyTarget};
use crate::special::normal_interval;
use crate::target::DifferentiableTarget;
use crate::McmcError;

/// A zero-mean 2-D Gaussian elongated along the direction at `angle` (radians from the first
/// axis): standard deviation `sd_long` along the ridge and `sd_across` across it.
///
/// In the ridge frame `u = c x0 + s x1`, `v = -s x0 + c x1` (`c = cos angle`, `s = sin angle`)
/// the coordinates are independent, `u ~ N(0, sd_long^2)`, `v ~ N(0, sd_across^2)`.
/// With `sd_across << sd_long` an isotropic random walk must take tiny steps: the classic
/// case for adaptive or anisotropic proposals.
///
/// Bins: a grid in the standardised ridge frame `(u / sd_long, v / sd_across)`; a cell's
/// probability is a product of two normal CDF differences (exact).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ridge {
    cos: f64,
    sin: f64,
    sd_long: f64,
    sd_across: f64,
}

impl Ridge {
    /// A ridge along `angle` with the given standard deviations (both `> 0`).
    pub fn new(angle: f64, sd_long: f64, sd_across: f64) -> Result<Self, McmcError> {
        McmcError::check_range("angle", angle, f64::MIN, f64::MAX, "finite")?;
        check_positive("sd_long", sd_long)?;
        check_positive("sd_across", sd_across)?;
        Ok(Self {
            cos: angle.cos(),
            sin: angle.sin(),
            sd_long,
            sd_across,
        })
    }

    /// The ridge used by the tests and the demo: 30 degrees, `sd_long = 1`,
    /// `sd_across = 0.05` (aspect ratio 20).
    #[must_use]
    pub fn thin() -> Self {
        Self::new(std::f64::consts::FRAC_PI_6, 1.0, 0.05).expect("valid constants")
    }

    /// The standardised ridge-frame coordinates `(u / sd_long, v / sd_across)` of `x`.
    #[must_use]
    pub fn standardise(&self, x: &[f64]) -> [f64; 2] {
        let u = self.cos * x[0] + self.sin * x[1];
        let v = -self.sin * x[0] + self.cos * x[1];
        [u / self.sd_long, v / self.sd_across]
    }
}

impl ToyTarget for Ridge {
    fn name(&self) -> &'static str {
        "ridge (2-D)"
    }

    fn dim(&self) -> usize {
        2
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        let [a, b] = self.standardise(x);
        -0.5 * (a * a + b * b) - 2.0 * super::HALF_LN_2PI - (self.sd_long * self.sd_across).ln()
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let u = self.sd_long * standard_normal(rng);
        let v = self.sd_across * standard_normal(rng);
        vec![self.cos * u - self.sin * v, self.sin * u + self.cos * v]
    }

    /// 8 x 8 cells on `[-2.5, 2.5]^2` in the standardised ridge frame, plus overflow.
    fn bins(&self) -> Bins {
        let edges = uniform_edges(-2.5, 2.5, 8);
        let this = *self;
        Bins::grid_2d(
            edges.clone(),
            edges,
            |lo, hi| normal_interval(lo[0], hi[0]) * normal_interval(lo[1], hi[1]),
            move |x| this.standardise(x),
        )
    }

    /// The box containing the ellipse `|u| <= 4 sd_long`, `|v| <= 4 sd_across` (mass outside
    /// below `1.3e-4`).
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        let e0 = 4.0 * (self.cos.abs() * self.sd_long + self.sin.abs() * self.sd_across);
        let e1 = 4.0 * (self.sin.abs() * self.sd_long + self.cos.abs() * self.sd_across);
        (vec![-e0, -e1], vec![e0, e1])
    }
}

impl_toy_target!(Ridge);

impl DifferentiableTarget for Ridge {
    fn evaluate_with_grad(&self, x: &mut Vec<f64>, _payload: &mut (), grad: &mut Vec<f64>) -> f64 {
        let [a, b] = self.standardise(x);
        // d/dx of -(a^2 + b^2)/2 with a = u/sl, b = v/sa.
        let (ga, gb) = (-a / self.sd_long, -b / self.sd_across);
        grad.clear();
        grad.push(ga * self.cos - gb * self.sin);
        grad.push(ga * self.sin + gb * self.cos);
        self.log_density(x)
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
        let t = Ridge::thin();
        check_normalised(&t, 1200, 2e-3);
        check_sampler_matches_bins(&t, 12);
        assert!(Ridge::new(0.0, 1.0, 0.0).is_err());
    }

    proptest! {
        #[test]
        fn gradient_matches_finite_differences(x0 in -3.0..3.0f64, x1 in -3.0..3.0f64) {
            let t = Ridge::thin();
            let mut g = Vec::new();
            let mut fd = Vec::new();
            t.evaluate_with_grad(&mut vec![x0, x1], &mut (), &mut g);
            finite_difference_gradient(&t, &[x0, x1], 1e-5, &mut fd);
            for (a, b) in g.iter().zip(&fd) {
                prop_assert!((a - b).abs() <= 1e-5 * (1.0 + a.abs()), "{g:?} vs {fd:?}");
            }
        }
    }
}
