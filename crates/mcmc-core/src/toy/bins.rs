//! Histogram bins over a toy target's state space with their exact probabilities.

use std::sync::Arc;

/// A partition of the state space (`Vec<f64>` states) into bins, each with its exact
/// probability under a toy target's normalised density.
///
/// Bins are defined by an assignment function, so they may live in any coordinates: the
/// ridge bins in its rotated frame, the banana in its untwisted frame, the n-D Gaussian by
/// whitened radius and quadrant. Probabilities sum to 1 (up to rounding); bins that cannot
/// hold mass (outside the support) have probability 0, so a sample landing there fails a
/// chi-square test outright.
#[derive(Clone)]
pub struct Bins {
    probabilities: Vec<f64>,
    assign: Arc<AssignFn>,
}

/// The bin assignment function of [`Bins`].
type AssignFn = dyn Fn(&[f64]) -> usize + Send + Sync;

impl std::fmt::Debug for Bins {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bins")
            .field("probabilities", &self.probabilities)
            .finish_non_exhaustive()
    }
}

impl Bins {
    /// Bins from their exact probabilities and an assignment `x -> bin index`
    /// (`< probabilities.len()`).
    pub fn new(
        probabilities: Vec<f64>,
        assign: impl Fn(&[f64]) -> usize + Send + Sync + 'static,
    ) -> Self {
        debug_assert!(probabilities.iter().all(|p| *p >= 0.0 && p.is_finite()));
        Self {
            probabilities,
            assign: Arc::new(assign),
        }
    }

    /// Bins on a scalar coordinate `coordinate(x)` with the given increasing `edges`
    /// `e_0 < ... < e_m` and the exact `cdf` of that coordinate: bins `(-inf, e_0)`,
    /// `[e_0, e_1)`, ..., `[e_m, inf)` (`m + 2` bins).
    pub fn from_cdf(
        edges: Vec<f64>,
        cdf: impl Fn(f64) -> f64,
        coordinate: impl Fn(&[f64]) -> f64 + Send + Sync + 'static,
    ) -> Self {
        debug_assert!(edges.windows(2).all(|w| w[0] < w[1]));
        let cdfs: Vec<f64> = edges.iter().map(|&e| cdf(e).clamp(0.0, 1.0)).collect();
        let mut probabilities = Vec::with_capacity(edges.len() + 1);
        probabilities.push(cdfs[0]);
        probabilities.extend(cdfs.windows(2).map(|w| (w[1] - w[0]).max(0.0)));
        probabilities.push((1.0 - cdfs[cdfs.len() - 1]).max(0.0));
        Self::new(probabilities, move |x| {
            edges.partition_point(|&e| e <= coordinate(x))
        })
    }

    /// A product grid in two coordinates `coordinates(x) = (u, v)`: cells
    /// `[edges_u[i], edges_u[i+1]) x [edges_v[j], edges_v[j+1])` with probabilities from
    /// `box_probability(lo, hi)`, plus one overflow bin (index `cells`, probability
    /// `1 - sum`) for everything outside the grid.
    pub fn grid_2d(
        edges_u: Vec<f64>,
        edges_v: Vec<f64>,
        box_probability: impl Fn([f64; 2], [f64; 2]) -> f64,
        coordinates: impl Fn(&[f64]) -> [f64; 2] + Send + Sync + 'static,
    ) -> Self {
        let (nu, nv) = (edges_u.len() - 1, edges_v.len() - 1);
        let mut probabilities = Vec::with_capacity(nu * nv + 1);
        for i in 0..nu {
            for j in 0..nv {
                let p = box_probability([edges_u[i], edges_v[j]], [edges_u[i + 1], edges_v[j + 1]]);
                probabilities.push(p.max(0.0));
            }
        }
        let inside: f64 = probabilities.iter().sum();
        probabilities.push((1.0 - inside).max(0.0));
        let overflow = nu * nv;
        Self::new(probabilities, move |x| {
            let [u, v] = coordinates(x);
            let i = edges_u.partition_point(|&e| e <= u);
            let j = edges_v.partition_point(|&e| e <= v);
            if i == 0 || i > nu || j == 0 || j > nv {
                overflow
            } else {
                (i - 1) * nv + (j - 1)
            }
        })
    }

    /// The exact probability of each bin.
    #[must_use]
    pub fn probabilities(&self) -> &[f64] {
        &self.probabilities
    }

    /// Number of bins.
    #[must_use]
    pub fn len(&self) -> usize {
        self.probabilities.len()
    }

    /// True if there are no bins.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.probabilities.is_empty()
    }

    /// The bin containing `x`.
    #[must_use]
    pub fn bin_of(&self, x: &[f64]) -> usize {
        (self.assign)(x)
    }
}

/// `n + 1` equally spaced edges from `lo` to `hi`.
#[must_use]
pub fn uniform_edges(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..=n)
        .map(|i| lo + (hi - lo) * i as f64 / n as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdf_bins_cover_the_line() {
        let b = Bins::from_cdf(uniform_edges(0.0, 1.0, 4), |x| x.clamp(0.0, 1.0), |x| x[0]);
        assert_eq!(b.len(), 6);
        assert_eq!(b.probabilities(), &[0.0, 0.25, 0.25, 0.25, 0.25, 0.0]);
        assert_eq!(b.bin_of(&[-0.1]), 0);
        assert_eq!(b.bin_of(&[0.0]), 1);
        assert_eq!(b.bin_of(&[0.3]), 2);
        assert_eq!(b.bin_of(&[0.999]), 4);
        assert_eq!(b.bin_of(&[1.0]), 5);
    }

    #[test]
    fn grid_bins_have_an_overflow_cell() {
        let b = Bins::grid_2d(
            uniform_edges(0.0, 1.0, 2),
            uniform_edges(0.0, 1.0, 2),
            |lo, hi| 0.2 * (hi[0] - lo[0]) * (hi[1] - lo[1]),
            |x| [x[0], x[1]],
        );
        assert_eq!(b.len(), 5);
        assert!((b.probabilities()[4] - 0.8).abs() < 1e-15);
        assert_eq!(b.bin_of(&[0.1, 0.1]), 0);
        assert_eq!(b.bin_of(&[0.1, 0.6]), 1);
        assert_eq!(b.bin_of(&[0.6, 0.1]), 2);
        assert_eq!(b.bin_of(&[1.5, 0.1]), 4);
        assert_eq!(b.bin_of(&[0.5, -0.1]), 4);
    }
}
