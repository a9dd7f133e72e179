//! The 2-D "banana": the twisted Gaussian of Haario, Saksman & Tamminen (1999, 2001).

use rand::Rng;

use super::{check_positive, impl_toy_target, standard_normal, uniform_edges, Bins, ToyTarget};
use crate::special::normal_interval;
use crate::target::DifferentiableTarget;
use crate::McmcError;

/// The twisted Gaussian `pi(y) = N(u1; 0, scale^2) N(u2; 0, 1)` with the untwisted coordinates
/// `u1 = y0`, `u2 = y1 + b y0^2 - b scale^2` (Haario et al. 1999, section 4; "f_b = f o phi_b").
///
/// The map `y -> u` has unit Jacobian, so the density is normalised. Haario et al. use
/// `scale = 10` with `b = 0.03` (moderately) or `b = 0.1` (strongly twisted).
///
/// Bins: a grid in the standardised untwisted frame `(u1 / scale, u2)` (curved cells in `y`);
/// a cell's probability is a product of normal CDF differences (exact).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Banana {
    scale: f64,
    twist: f64,
}

impl Banana {
    /// A banana with `scale > 0` (standard deviation along the first axis) and twist `b >= 0`.
    pub fn new(scale: f64, twist: f64) -> Result<Self, McmcError> {
        check_positive("scale", scale)?;
        McmcError::check_range("twist", twist, 0.0, f64::MAX, "[0, inf)")?;
        Ok(Self { scale, twist })
    }

    /// Haario et al.'s 2-D twisted Gaussian: `scale = 10` and the given twist (0.03 or 0.1).
    pub fn haario(twist: f64) -> Result<Self, McmcError> {
        Self::new(10.0, twist)
    }

    /// The banana used by the tests and the demo: `scale = 3`, `b = 0.3` (a strongly curved
    /// ridge of unit width spanning about 18 units).
    #[must_use]
    pub const fn curved() -> Self {
        Self {
            scale: 3.0,
            twist: 0.3,
        }
    }

    /// The untwisted coordinates `(u1, u2)` of `y`.
    #[must_use]
    pub fn untwist(&self, y: &[f64]) -> [f64; 2] {
        let b = self.twist;
        [y[0], y[1] + b * y[0] * y[0] - b * self.scale * self.scale]
    }
}

impl ToyTarget for Banana {
    fn name(&self) -> &'static str {
        "banana (2-D)"
    }

    fn dim(&self) -> usize {
        2
    }

    fn log_density(&self, y: &[f64]) -> f64 {
        let [u1, u2] = self.untwist(y);
        let a = u1 / self.scale;
        -0.5 * (a * a + u2 * u2) - 2.0 * super::HALF_LN_2PI - self.scale.ln()
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let u1 = self.scale * standard_normal(rng);
        let u2 = standard_normal(rng);
        let b = self.twist;
        vec![u1, u2 - b * u1 * u1 + b * self.scale * self.scale]
    }

    /// 10 x 10 cells on `[-2.5, 2.5]^2` in `(u1 / scale, u2)`, plus overflow.
    fn bins(&self) -> Bins {
        let edges = uniform_edges(-2.5, 2.5, 10);
        let this = *self;
        Bins::grid_2d(
            edges.clone(),
            edges,
            |lo, hi| normal_interval(lo[0], hi[0]) * normal_interval(lo[1], hi[1]),
            move |y| {
                let [u1, u2] = this.untwist(y);
                [u1 / this.scale, u2]
            },
        )
    }

    /// `|u1| <= 4 scale`, `|u2| <= 4` mapped back to `y` (mass outside below `1.3e-4`).
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        let s = self.scale;
        let b = self.twist;
        // y1 = u2 - b u1^2 + b s^2 ranges over [-4 - 15 b s^2, 4 + b s^2].
        (
            vec![-4.0 * s, -4.0 - 15.0 * b * s * s],
            vec![4.0 * s, 4.0 + b * s * s],
        )
    }
}

impl_toy_target!(Banana);

impl DifferentiableTarget for Banana {
    fn evaluate_with_grad(&self, y: &mut Vec<f64>, _payload: &mut (), grad: &mut Vec<f64>) -> f64 {
        let [u1, u2] = self.untwist(y);
        grad.clear();
        // d/dy0 [-(u1/s)^2/2 - u2^2/2] = -u1/s^2 - u2 * 2 b y0;  d/dy1 = -u2.
        grad.push(-u1 / (self.scale * self.scale) - u2 * 2.0 * self.twist * y[0]);
        grad.push(-u2);
        self.log_density(y)
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
        let t = Banana::curved();
        check_normalised(&t, 1500, 2e-3);
        check_sampler_matches_bins(&t, 15);
        assert!(Banana::new(1.0, -0.1).is_err());
        assert!(Banana::haario(0.1).is_ok());
    }

    proptest! {
        #[test]
        fn gradient_matches_finite_differences(y0 in -10.0..10.0f64, y1 in -30.0..5.0f64) {
            let t = Banana::curved();
            let mut g = Vec::new();
            let mut fd = Vec::new();
            t.evaluate_with_grad(&mut vec![y0, y1], &mut (), &mut g);
            finite_difference_gradient(&t, &[y0, y1], 1e-5, &mut fd);
            for (a, b) in g.iter().zip(&fd) {
                prop_assert!((a - b).abs() <= 1e-4 * (1.0 + a.abs()), "{g:?} vs {fd:?}");
            }
        }
    }
}
