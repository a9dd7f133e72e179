//! Toy targets with exact normalised densities, exact samplers and exact bin probabilities.
//!
//! They are the test bench of every kernel: small, cheap, and known in closed form, so a
//! chain's output can be compared with the truth (docs/architecture.md, "Using the
//! correctness harness from another crate").
//! All live on `Vec<f64>` states with no payload.
//!
//! | target | dim | what it stresses |
//! |---|---|---|
//! | [`UniformMixture`] | 1 | a narrow spike next to a wide plateau (DR paper, eq. 8) |
//! | [`Ridge`] | 2 | a thin rotated Gaussian ridge (anisotropy) |
//! | [`GaussianMixture2d`] | 2 | disconnected modes |
//! | [`TorusMixture`] | 2 | modes on the unit torus with mass across the seams (PSS) |
//! | [`Banana`] | 2 | the twisted Gaussian of Haario et al. (curvature) |
//! | [`CorrelatedGaussian`] | n | a general covariance (Cholesky) |
//! | [`PiecewiseConstant`] | 1 | zero-density holes in `[0, 1)` |
//!
//! # Example
//! ```
//! use mcmc_core::toy::{ToyTarget, UniformMixture};
//! use rand::SeedableRng;
//!
//! let target = UniformMixture::rioux_lavoie2020();
//! let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
//! let x = target.sample_exact(&mut rng);
//! assert!(target.log_density(&x).is_finite());
//! let bins = target.bins();
//! let total: f64 = bins.probabilities().iter().sum();
//! assert!((total - 1.0).abs() < 1e-12);
//! ```

mod banana;
mod bins;
mod correlated_gaussian;
mod gaussian_mixture;
mod piecewise;
mod ridge;
mod torus_mixture;
mod uniform_mixture;

/// Special functions, re-exported from [`crate::special`] where they live.
pub use crate::special;
/// Re-exported from [`crate::torus`], where they live.
pub use crate::torus::{wrap, wrapped_normal_pdf};
pub use banana::Banana;
pub use bins::{uniform_edges, Bins};
pub use correlated_gaussian::CorrelatedGaussian;
pub use gaussian_mixture::{DiagonalGaussian, GaussianMixture2d, MAX_MIXTURE_COMPONENTS};
pub use piecewise::PiecewiseConstant;
pub use ridge::Ridge;
pub use torus_mixture::TorusMixture;
pub use uniform_mixture::UniformMixture;

use rand::Rng;

use crate::target::Target;

/// A toy target: a [`Target`] over `Vec<f64>` whose normalised density, exact sampler and
/// exact bin probabilities are known.
pub trait ToyTarget: Target<State = Vec<f64>, Payload = ()> {
    /// A short name for tables and failure messages.
    fn name(&self) -> &'static str;

    /// Dimension of the state.
    fn dim(&self) -> usize;

    /// The *normalised* log density (`NEG_INFINITY` outside the support). The [`Target`]
    /// implementation returns exactly this.
    fn log_density(&self, x: &[f64]) -> f64;

    /// An exact, independent draw from the target (for stationarity tests from exact starts).
    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64>;

    /// The default bins for chi-square tests, with exact probabilities (each target documents
    /// how they are computed).
    fn bins(&self) -> Bins;

    /// An axis-aligned box `[lo, hi)` holding the interesting part of the mass: the domain of
    /// finite-state grids and of plots. For unbounded targets it holds all but a negligible
    /// fraction (documented per target).
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>);
}

/// Implements [`Target`] for a toy target by forwarding to [`ToyTarget::log_density`].
macro_rules! impl_toy_target {
    ($t:ty) => {
        impl $crate::target::Target for $t {
            type State = Vec<f64>;
            type Payload = ();
            fn evaluate(&self, x: &mut Vec<f64>, _payload: &mut ()) -> f64 {
                $crate::toy::ToyTarget::log_density(self, x)
            }
        }
    };
}
pub(crate) use impl_toy_target;

/// `ln(2 pi) / 2`.
pub(crate) const HALF_LN_2PI: f64 = 0.918_938_533_204_672_7;

/// One standard normal draw.
pub(crate) fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    use rand_distr::{Distribution, StandardNormal};
    StandardNormal.sample(rng)
}

/// Checks a user-supplied value is finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), crate::McmcError> {
    crate::McmcError::check_range(name, value, f64::MIN_POSITIVE, f64::MAX, "(0, inf)")
}

#[cfg(test)]
pub(crate) mod test_util {
    //! Checks shared by the toy targets' unit tests.

    use super::ToyTarget;
    use rand::SeedableRng;

    /// The bins' probabilities sum to 1 and the density integrates to 1 over the bounding box
    /// (by a midpoint rule on `cells^dim` cells, to `tol`).
    pub(crate) fn check_normalised<T: ToyTarget>(target: &T, cells: usize, tol: f64) {
        let total: f64 = target.bins().probabilities().iter().sum();
        assert!(
            (total - 1.0).abs() < 1e-12,
            "{}: bins sum to {total}",
            target.name()
        );
        let (lo, hi) = target.bounding_box();
        let h: Vec<f64> = lo
            .iter()
            .zip(&hi)
            .map(|(l, u)| (u - l) / cells as f64)
            .collect();
        let volume: f64 = h.iter().product();
        let dim = target.dim();
        let mut index = vec![0usize; dim];
        let mut integral = 0.0;
        let mut x = vec![0.0; dim];
        loop {
            for d in 0..dim {
                x[d] = lo[d] + (index[d] as f64 + 0.5) * h[d];
            }
            integral += target.log_density(&x).exp() * volume;
            let mut d = 0;
            loop {
                if d == dim {
                    assert!(
                        (integral - 1.0).abs() < tol,
                        "{}: density integrates to {integral}",
                        target.name()
                    );
                    return;
                }
                index[d] += 1;
                if index[d] < cells {
                    break;
                }
                index[d] = 0;
                d += 1;
            }
        }
    }

    /// Exact samples land in bins with frequencies matching the bin probabilities: a crude
    /// consistency check between `sample_exact` and `bins` (|freq - p| < 5 binomial sd + 1e-3,
    /// for 40_000 samples; a per-bin z of 5 has two-sided probability 6e-7).
    pub(crate) fn check_sampler_matches_bins<T: ToyTarget>(target: &T, seed: u64) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let bins = target.bins();
        let n = 40_000;
        let mut counts = vec![0u64; bins.len()];
        for _ in 0..n {
            let x = target.sample_exact(&mut rng);
            assert!(target.log_density(&x) > f64::NEG_INFINITY);
            counts[bins.bin_of(&x)] += 1;
        }
        for (i, (&c, &p)) in counts.iter().zip(bins.probabilities()).enumerate() {
            let freq = c as f64 / n as f64;
            let sd = (p * (1.0 - p) / n as f64).sqrt();
            assert!(
                (freq - p).abs() < 5.0 * sd + 1e-3,
                "{}: bin {i} freq {freq} vs p {p}",
                target.name()
            );
        }
    }
}
