//! The data of the splat-weight check: moments of each start's splat vector over pooled bins.

use nalgebra::{DMatrix, DVector};

/// The first, second and third moments of the splat vectors `c_i` of `N` starts over `B`
/// pooled bins, accumulated one start at a time.
/// [`SplatMoments::test`] runs the splat-weight check on them.
#[derive(Clone, Debug, PartialEq)]
pub struct SplatMoments {
    groups: Vec<Vec<usize>>,
    probabilities: DVector<f64>,
    sum: DVector<f64>,
    cross: DMatrix<f64>,
    cubes: DVector<f64>,
    starts: usize,
    total_weight: f64,
    impossible_weight: f64,
}

impl SplatMoments {
    /// No starts yet, over pooled bins `groups` (the original bins of each) with exact
    /// probabilities `probabilities`.
    ///
    /// # Panics
    /// If the two have different lengths.
    #[must_use]
    pub fn new(groups: Vec<Vec<usize>>, probabilities: Vec<f64>) -> Self {
        assert_eq!(
            groups.len(),
            probabilities.len(),
            "one probability per pooled bin"
        );
        let dim = groups.len();
        Self {
            groups,
            probabilities: DVector::from_vec(probabilities),
            sum: DVector::zeros(dim),
            cross: DMatrix::zeros(dim, dim),
            cubes: DVector::zeros(dim),
            starts: 0,
            total_weight: 0.0,
            impossible_weight: 0.0,
        }
    }

    /// Adds one start: `row` lists `(pooled bin, weight)` with distinct bins,
    /// `total_weight` is all the weight its step splatted (into any bin) and
    /// `impossible_weight` the absolute weight it splatted into bins of probability 0.
    ///
    /// # Panics
    /// If a bin index is out of range.
    pub fn push(&mut self, row: &[(usize, f64)], total_weight: f64, impossible_weight: f64) {
        for &(j, cj) in row {
            assert!(j < self.groups.len(), "pooled bin {j} out of range");
            self.sum[j] += cj;
            self.cubes[j] += cj * cj * cj;
            for &(k, ck) in row {
                self.cross[(j, k)] += cj * ck;
            }
        }
        self.starts += 1;
        self.total_weight += total_weight;
        self.impossible_weight += impossible_weight;
    }

    /// Number of starts `N`.
    #[must_use]
    pub fn starts(&self) -> usize {
        self.starts
    }

    /// The original bins of each pooled bin.
    #[must_use]
    pub fn groups(&self) -> &[Vec<usize>] {
        &self.groups
    }

    /// Exact probability `p_b` of each pooled bin.
    #[must_use]
    pub fn probabilities(&self) -> &DVector<f64> {
        &self.probabilities
    }

    /// `sum_i c_i`: the total weight splatted into each pooled bin.
    #[must_use]
    pub fn sum(&self) -> &DVector<f64> {
        &self.sum
    }

    /// `sum_i c_i c_i^T`.
    #[must_use]
    pub fn cross(&self) -> &DMatrix<f64> {
        &self.cross
    }

    /// `sum_i c_ib^3` for each pooled bin `b`.
    #[must_use]
    pub fn cubes(&self) -> &DVector<f64> {
        &self.cubes
    }

    /// Mean over starts of the total weight one step splatted (1 for MH).
    #[must_use]
    pub fn mean_total_weight(&self) -> f64 {
        self.total_weight / self.starts().max(1) as f64
    }

    /// Total absolute weight splatted into bins of probability 0.
    #[must_use]
    pub fn impossible_weight(&self) -> f64 {
        self.impossible_weight
    }

    /// The mean splat vector `m`.
    #[must_use]
    pub fn mean(&self) -> DVector<f64> {
        &self.sum / self.starts().max(1) as f64
    }

    /// The sample covariance `S = sum_i (c_i - m)(c_i - m)^T / (N - 1)`.
    #[must_use]
    pub fn sample_covariance(&self) -> DMatrix<f64> {
        let n = self.starts() as f64;
        let mean = self.mean();
        (&self.cross - &mean * mean.transpose() * n) / (n - 1.0).max(1.0)
    }

    /// The covariance under the hypothesis, `V = D R D - p p^T` ([`SplatMoments::test`]).
    #[must_use]
    pub fn null_covariance(&self) -> DMatrix<f64> {
        let n = self.starts().max(1) as f64;
        let p = &self.probabilities;
        // D R D = diag(sqrt(p / m)) M diag(sqrt(p / m)), without dividing by m_b <= 0.
        let scale = self
            .mean()
            .zip_map(p, |m, p| if m > 0.0 { (p / m).sqrt() } else { 1.0 });
        DMatrix::from_fn(p.len(), p.len(), |j, k| {
            scale[j] * scale[k] * self.cross[(j, k)] / n - p[j] * p[k]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_of_three_starts() {
        let mut m = SplatMoments::new(vec![vec![0], vec![1, 2]], vec![0.4, 0.6]);
        m.push(&[(0, 0.25), (1, 0.75)], 1.0, 0.0);
        m.push(&[], 0.5, 0.5);
        m.push(&[(1, 1.0)], 1.0, 0.0);
        assert_eq!(m.starts(), 3);
        assert_eq!(m.sum().as_slice(), &[0.25, 1.75]);
        assert_eq!(m.cross()[(0, 1)], 0.1875);
        assert_eq!(m.cross()[(1, 1)], 0.5625 + 1.0);
        assert_eq!(m.cubes()[1], 0.421_875 + 1.0);
        let cov = m.sample_covariance();
        // Bin 0: values (0.25, 0, 0), mean 1/12, variance (0.25^2 - 3 (1/12)^2) / 2.
        assert!((cov[(0, 0)] - (0.0625 - 3.0 / 144.0) / 2.0).abs() < 1e-15);
        assert!((m.mean_total_weight() - 2.5 / 3.0).abs() < 1e-15);
        assert_eq!(m.impossible_weight(), 0.5);
    }
}
