//! A mixture of wrapped Gaussians on the unit torus `[0,1)^2`, with mass across the seams.

use rand::Rng;

use super::gaussian_mixture::{normalise_components, pick_component, DiagonalGaussian};
use super::{impl_toy_target, standard_normal, uniform_edges, Bins, ToyTarget};
use crate::proposal::log_sum_exp;
use crate::special::normal_interval;
use crate::torus::{wrap, wrapped_normal_pdf, WRAPPED_NORMAL_IMAGES};
use crate::McmcError;

/// Largest standard deviation accepted (see [`WRAPPED_NORMAL_IMAGES`]).
const MAX_SD: f64 = 0.25;

/// A mixture of *wrapped* axis-aligned Gaussians on the unit torus:
/// `pi(x) = sum_k w_k prod_d sum_{m in Z} N(x_d + m; mu_kd, s_kd^2)` for `x in [0, 1)^2`,
/// and 0 outside the unit square.
///
/// States are points of `[0, 1)^2`, as in primary sample space. A proposal that wraps around
/// (PSS mutations) sees each mode whole across the seam; a walk that does not wrap is still a
/// correct kernel (candidates outside the square have zero density and are rejected), it
/// just sees the modes cut in two. Components centred near 0 or 1 put mass across the seams,
/// where a proposal that wraps without the matching density (or that does not return to the
/// square) goes wrong.
///
/// Bins: a 12 x 12 grid on `[0, 1)^2` plus an overflow bin of probability 0 (a state outside
/// the square fails the test outright); a cell's probability sums the normal CDF differences
/// of the 7 nearest periodic images per axis (exact to `1e-23`).
#[derive(Clone, Debug, PartialEq)]
pub struct TorusMixture {
    components: Vec<DiagonalGaussian>,
}

impl TorusMixture {
    /// A mixture of wrapped components: means in `[0, 1)`, standard deviations in
    /// `(0, 0.25]`, weights normalised, 1 to 16 components.
    pub fn new(mut components: Vec<DiagonalGaussian>) -> Result<Self, McmcError> {
        normalise_components(&mut components)?;
        for c in &components {
            for d in 0..2 {
                McmcError::check_range("mean", c.mean[d], 0.0, 1.0 - f64::EPSILON, "[0, 1)")?;
                McmcError::check_range("sd", c.sd[d], f64::MIN_POSITIVE, MAX_SD, "(0, 0.25]")?;
            }
        }
        Ok(Self { components })
    }

    /// Two modes that straddle the seams: weight 0.6 at `(0.95, 0.5)` with
    /// `sd = (0.07, 0.1)` (crosses `x0 = 1 ~ 0`), weight 0.4 at `(0.3, 0.02)` with
    /// `sd = (0.1, 0.05)` (crosses `x1 = 0 ~ 1`).
    #[must_use]
    pub fn across_seam() -> Self {
        Self::new(vec![
            DiagonalGaussian {
                weight: 0.6,
                mean: [0.95, 0.5],
                sd: [0.07, 0.1],
            },
            DiagonalGaussian {
                weight: 0.4,
                mean: [0.3, 0.02],
                sd: [0.1, 0.05],
            },
        ])
        .expect("valid constants")
    }

    /// The components (normalised weights).
    #[must_use]
    pub fn components(&self) -> &[DiagonalGaussian] {
        &self.components
    }

    /// Probability that the wrapped normal of one axis falls in `[lo, hi) subset [0, 1)`.
    fn wrapped_interval(lo: f64, hi: f64, mean: f64, sd: f64) -> f64 {
        (-WRAPPED_NORMAL_IMAGES..=WRAPPED_NORMAL_IMAGES)
            .map(|m| {
                let m = f64::from(m);
                normal_interval((lo + m - mean) / sd, (hi + m - mean) / sd)
            })
            .sum()
    }
}

impl ToyTarget for TorusMixture {
    fn name(&self) -> &'static str {
        "torus mixture (2-D)"
    }

    fn dim(&self) -> usize {
        2
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        let (t0, t1) = (x[0], x[1]);
        if !((0.0..1.0).contains(&t0) && (0.0..1.0).contains(&t1)) {
            return f64::NEG_INFINITY;
        }
        let mut terms = [f64::NEG_INFINITY; super::MAX_MIXTURE_COMPONENTS];
        for (t, c) in terms.iter_mut().zip(&self.components) {
            // Each wrapped factor is a sum of positive terms; take logs per axis.
            *t = c.weight.ln()
                + wrapped_normal_pdf(t0, c.mean[0], c.sd[0]).ln()
                + wrapped_normal_pdf(t1, c.mean[1], c.sd[1]).ln();
        }
        log_sum_exp(&terms[..self.components.len()])
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let c = &self.components[pick_component(&self.components, rng)];
        let z0 = standard_normal(rng);
        let z1 = standard_normal(rng);
        vec![
            wrap(c.mean[0] + c.sd[0] * z0),
            wrap(c.mean[1] + c.sd[1] * z1),
        ]
    }

    fn bins(&self) -> Bins {
        let components = self.components.clone();
        Bins::grid_2d(
            uniform_edges(0.0, 1.0, 12),
            uniform_edges(0.0, 1.0, 12),
            move |lo, hi| {
                components
                    .iter()
                    .map(|c| {
                        c.weight
                            * Self::wrapped_interval(lo[0], hi[0], c.mean[0], c.sd[0])
                            * Self::wrapped_interval(lo[1], hi[1], c.mean[1], c.sd[1])
                    })
                    .sum()
            },
            |x| [x[0], x[1]],
        )
    }

    /// The unit square (the whole torus).
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0, 0.0], vec![1.0, 1.0])
    }
}

impl_toy_target!(TorusMixture);

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    #[test]
    fn normalised_and_sampled_exactly() {
        let t = TorusMixture::across_seam();
        check_normalised(&t, 400, 1e-9);
        check_sampler_matches_bins(&t, 14);
        // The overflow bin (outside the square) has probability 0.
        assert!(*t.bins().probabilities().last().unwrap() < 1e-12);
        assert!(TorusMixture::new(vec![DiagonalGaussian {
            weight: 1.0,
            mean: [0.5, 0.5],
            sd: [0.3, 0.1]
        }])
        .is_err());
    }

    #[test]
    fn mass_across_the_seam_and_zero_outside() {
        let t = TorusMixture::across_seam();
        // The first mode (mean 0.95) has more density just past the seam (distance 0.06)
        // than at 0.8 (distance 0.15).
        assert!(t.log_density(&[0.01, 0.5]) > t.log_density(&[0.8, 0.5]));
        assert_eq!(t.log_density(&[1.01, 0.5]), f64::NEG_INFINITY);
        assert_eq!(t.log_density(&[0.5, -0.01]), f64::NEG_INFINITY);
    }
}
