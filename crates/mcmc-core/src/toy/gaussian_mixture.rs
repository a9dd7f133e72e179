//! A 2-D mixture of axis-aligned Gaussians with well separated (disconnected) modes.

use rand::{Rng, RngExt};

use super::{check_positive, impl_toy_target, standard_normal, uniform_edges, Bins, ToyTarget};
use crate::proposal::log_sum_exp;
use crate::special::normal_interval;
use crate::McmcError;

/// One weighted component `w N(mean, diag(sd^2))` of a 2-D mixture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiagonalGaussian {
    /// Mixture weight (normalised by the mixture's constructor).
    pub weight: f64,
    /// Mean.
    pub mean: [f64; 2],
    /// Standard deviation per axis.
    pub sd: [f64; 2],
}

impl DiagonalGaussian {
    pub(crate) fn validate(&self) -> Result<(), McmcError> {
        McmcError::check_range("weight", self.weight, 0.0, f64::MAX, "[0, inf)")?;
        for m in self.mean {
            McmcError::check_range("mean", m, f64::MIN, f64::MAX, "finite")?;
        }
        for s in self.sd {
            check_positive("sd", s)?;
        }
        Ok(())
    }

    /// Unweighted log density at `x` (2-D).
    pub(crate) fn log_pdf(&self, x0: f64, x1: f64) -> f64 {
        let a = (x0 - self.mean[0]) / self.sd[0];
        let b = (x1 - self.mean[1]) / self.sd[1];
        -0.5 * (a * a + b * b) - 2.0 * super::HALF_LN_2PI - (self.sd[0] * self.sd[1]).ln()
    }

    /// Probability (unweighted) of the box `[lo, hi)`.
    pub(crate) fn box_probability(&self, lo: [f64; 2], hi: [f64; 2]) -> f64 {
        let axis = |d: usize| {
            normal_interval(
                (lo[d] - self.mean[d]) / self.sd[d],
                (hi[d] - self.mean[d]) / self.sd[d],
            )
        };
        axis(0) * axis(1)
    }
}

/// Maximum number of components of the toy mixtures (their log densities live on the stack).
pub const MAX_MIXTURE_COMPONENTS: usize = 16;

/// Normalises the weights of `components` in place after validating them.
pub(crate) fn normalise_components(components: &mut [DiagonalGaussian]) -> Result<(), McmcError> {
    if components.is_empty() || components.len() > MAX_MIXTURE_COMPONENTS {
        return Err(McmcError::InvalidParameter {
            name: "components.len()",
            value: components.len() as f64,
            allowed: "1..=16",
        });
    }
    for c in components.iter() {
        c.validate()?;
    }
    let total: f64 = components.iter().map(|c| c.weight).sum();
    check_positive("sum of weights", total)?;
    for c in components.iter_mut() {
        c.weight /= total;
    }
    Ok(())
}

/// Picks a component index with probability proportional to its (normalised) weight.
pub(crate) fn pick_component<R: Rng + ?Sized>(
    components: &[DiagonalGaussian],
    rng: &mut R,
) -> usize {
    let u: f64 = rng.random();
    let mut cdf = 0.0;
    for (i, c) in components.iter().enumerate() {
        cdf += c.weight;
        if u < cdf {
            return i;
        }
    }
    components.len() - 1
}

/// A mixture of axis-aligned 2-D Gaussians, `pi(x) = sum_k w_k N(x; m_k, diag(s_k^2))`.
///
/// With modes many standard deviations apart it is effectively disconnected for a local
/// random walk: a chain started in one mode stays there, so only exact starts (which pick the
/// mode with the right probability) make a stationarity test meaningful.
///
/// Bins: a 12 x 12 grid on the bounding box plus overflow; a cell's probability is a
/// weighted sum of products of normal CDF differences (exact).
#[derive(Clone, Debug, PartialEq)]
pub struct GaussianMixture2d {
    components: Vec<DiagonalGaussian>,
}

impl GaussianMixture2d {
    /// A mixture of the given components (weights normalised; 1 to 16 components).
    pub fn new(mut components: Vec<DiagonalGaussian>) -> Result<Self, McmcError> {
        normalise_components(&mut components)?;
        Ok(Self { components })
    }

    /// Two modes, weights 0.3 and 0.7, about ten standard deviations apart:
    /// `N((-2, -1.5), diag(0.5^2, 0.3^2))` and `N((2, 1.5), diag(0.4^2, 0.6^2))`.
    #[must_use]
    pub fn disconnected() -> Self {
        Self::new(vec![
            DiagonalGaussian {
                weight: 0.3,
                mean: [-2.0, -1.5],
                sd: [0.5, 0.3],
            },
            DiagonalGaussian {
                weight: 0.7,
                mean: [2.0, 1.5],
                sd: [0.4, 0.6],
            },
        ])
        .expect("valid constants")
    }

    /// The components (normalised weights).
    #[must_use]
    pub fn components(&self) -> &[DiagonalGaussian] {
        &self.components
    }
}

impl ToyTarget for GaussianMixture2d {
    fn name(&self) -> &'static str {
        "disconnected mixture (2-D)"
    }

    fn dim(&self) -> usize {
        2
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        let mut terms = [f64::NEG_INFINITY; MAX_MIXTURE_COMPONENTS];
        for (t, c) in terms.iter_mut().zip(&self.components) {
            *t = c.weight.ln() + c.log_pdf(x[0], x[1]);
        }
        log_sum_exp(&terms[..self.components.len()])
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let c = &self.components[pick_component(&self.components, rng)];
        let z0 = standard_normal(rng);
        let z1 = standard_normal(rng);
        vec![c.mean[0] + c.sd[0] * z0, c.mean[1] + c.sd[1] * z1]
    }

    fn bins(&self) -> Bins {
        let (lo, hi) = self.bounding_box();
        let components = self.components.clone();
        Bins::grid_2d(
            uniform_edges(lo[0], hi[0], 12),
            uniform_edges(lo[1], hi[1], 12),
            move |lo, hi| {
                components
                    .iter()
                    .map(|c| c.weight * c.box_probability(lo, hi))
                    .sum()
            },
            |x| [x[0], x[1]],
        )
    }

    /// The smallest box holding every component's `mean +- 4 sd` (mass outside below
    /// `1.3e-4`).
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        let mut lo = vec![f64::INFINITY; 2];
        let mut hi = vec![f64::NEG_INFINITY; 2];
        for c in &self.components {
            for d in 0..2 {
                lo[d] = lo[d].min(c.mean[d] - 4.0 * c.sd[d]);
                hi[d] = hi[d].max(c.mean[d] + 4.0 * c.sd[d]);
            }
        }
        (lo, hi)
    }
}

impl_toy_target!(GaussianMixture2d);

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    #[test]
    fn normalised_and_sampled_exactly() {
        let t = GaussianMixture2d::disconnected();
        check_normalised(&t, 600, 2e-3);
        check_sampler_matches_bins(&t, 13);
        assert!(GaussianMixture2d::new(vec![]).is_err());
        let w: f64 = t.components().iter().map(|c| c.weight).sum();
        assert!((w - 1.0).abs() < 1e-15);
    }
}
