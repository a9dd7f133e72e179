//! A piecewise-constant density on `[0, 1)` with zero-density holes.

use rand::{Rng, RngExt};

use super::{check_positive, impl_toy_target, uniform_edges, Bins, ToyTarget};
use crate::McmcError;

/// `pi(x) = n w_i / sum(w)` on the `i`-th of `n` equal cells of `[0, 1)`, zero outside
/// `[0, 1)` and on cells of weight 0 ("holes").
///
/// Holes are where kernels that mishandle zero densities go wrong (accepting a zero-density
/// candidate, dividing by a zero density when leaving one), and where a local proposal must
/// jump to stay ergodic. It is also the discretisation-friendly target of the exact
/// finite-state check ([`crate::testing::finite_state_check`]).
///
/// Bins: the CDF is piecewise linear, so bin probabilities are exact; holes give bins of
/// probability 0 (a sample there fails a chi-square test outright).
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant {
    /// Normalised density value per cell.
    density: Vec<f64>,
    /// CDF at the cell edges (`n + 1` values).
    cdf_at_edges: Vec<f64>,
}

impl PiecewiseConstant {
    /// From non-negative cell weights (at least one positive).
    pub fn new(weights: &[f64]) -> Result<Self, McmcError> {
        if weights.is_empty() {
            return Err(McmcError::InvalidParameter {
                name: "weights.len()",
                value: 0.0,
                allowed: ">= 1",
            });
        }
        for &w in weights {
            McmcError::check_range("weight", w, 0.0, f64::MAX, "[0, inf)")?;
        }
        let total: f64 = weights.iter().sum();
        check_positive("sum of weights", total)?;
        let n = weights.len() as f64;
        let density: Vec<f64> = weights.iter().map(|w| n * w / total).collect();
        let mut cdf_at_edges = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0;
        cdf_at_edges.push(0.0);
        for w in weights {
            acc += w / total;
            cdf_at_edges.push(acc);
        }
        *cdf_at_edges.last_mut().expect("non-empty") = 1.0;
        Ok(Self {
            density,
            cdf_at_edges,
        })
    }

    /// Sixteen cells with weights `1 3 0 0 2 5 0 1 4 0 0 0 2 1 0 3`: holes of one, two and
    /// three cells (widths 1/16 to 3/16), including a hole next to the densest cell.
    #[must_use]
    pub fn with_holes() -> Self {
        Self::new(&[
            1.0, 3.0, 0.0, 0.0, 2.0, 5.0, 0.0, 1.0, 4.0, 0.0, 0.0, 0.0, 2.0, 1.0, 0.0, 3.0,
        ])
        .expect("valid constants")
    }

    /// Number of cells.
    #[must_use]
    pub fn cells(&self) -> usize {
        self.density.len()
    }

    /// The normalised density of each cell.
    #[must_use]
    pub fn cell_densities(&self) -> &[f64] {
        &self.density
    }

    fn cell_of(&self, x: f64) -> Option<usize> {
        if (0.0..1.0).contains(&x) {
            Some(((x * self.cells() as f64) as usize).min(self.cells() - 1))
        } else {
            None
        }
    }

    /// The exact CDF.
    #[must_use]
    pub fn cdf(&self, x: f64) -> f64 {
        match self.cell_of(x) {
            None if x < 0.0 => 0.0,
            None => 1.0,
            Some(i) => {
                let n = self.cells() as f64;
                let within = x - i as f64 / n;
                (self.cdf_at_edges[i] + self.density[i] * within).min(1.0)
            }
        }
    }
}

impl ToyTarget for PiecewiseConstant {
    fn name(&self) -> &'static str {
        "piecewise constant with holes (1-D)"
    }

    fn dim(&self) -> usize {
        1
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        match self.cell_of(x[0]) {
            Some(i) => self.density[i].ln(),
            None => f64::NEG_INFINITY,
        }
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let u: f64 = rng.random();
        let i = self.cdf_at_edges[1..]
            .partition_point(|&c| c <= u)
            .min(self.cells() - 1);
        // A zero-weight cell has an empty CDF interval, so it is never chosen.
        debug_assert!(self.density[i] > 0.0);
        let v: f64 = rng.random();
        vec![(i as f64 + v) / self.cells() as f64]
    }

    /// Two bins per cell on `[0, 1)` and the two (empty) outer tails.
    fn bins(&self) -> Bins {
        let this = self.clone();
        Bins::from_cdf(
            uniform_edges(0.0, 1.0, 2 * self.cells()),
            move |x| this.cdf(x),
            |x| x[0],
        )
    }

    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![1.0])
    }
}

impl_toy_target!(PiecewiseConstant);

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    #[test]
    fn normalised_and_sampled_exactly() {
        let t = PiecewiseConstant::with_holes();
        check_normalised(&t, 1600, 1e-12);
        check_sampler_matches_bins(&t, 19);
        assert_eq!(t.log_density(&[2.5 / 16.0]), f64::NEG_INFINITY);
        assert_eq!(t.log_density(&[1.0]), f64::NEG_INFINITY);
        assert_eq!(t.log_density(&[-0.0001]), f64::NEG_INFINITY);
        assert!((t.cdf(0.5) - 12.0 / 22.0).abs() < 1e-15);
        assert!(PiecewiseConstant::new(&[0.0, 0.0]).is_err());
        assert!(PiecewiseConstant::new(&[1.0, -1.0]).is_err());
    }
}
