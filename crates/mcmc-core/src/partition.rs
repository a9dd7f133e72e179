//! Partitions of a state space into regions, for regional adaptation.

use std::ops::Range;

/// Maps a state to the id of the region containing it (`0..num_regions()`).
///
/// Refinable partitions (quadtrees) can split a region: the split region's id is reused by
/// the first child, the other children get fresh ids at the end, so ids stay dense and callers
/// keep per-region arrays by resizing.
pub trait Partition<S> {
    /// The region containing `x`.
    fn region(&self, x: &S) -> usize;
    /// Number of regions (region ids are `0..num_regions()`).
    fn num_regions(&self) -> usize;
    /// Splits `region`, returning the fresh ids of its other children (appended at the end:
    /// `num_regions()` before the split `..` after), or `None` if the partition cannot refine
    /// it. `region` itself is reused by the first child, so it is a child too.
    fn split(&mut self, region: usize) -> Option<Range<usize>> {
        let _ = region;
        None
    }
}

/// The trivial partition: one region.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SingleRegion;

impl<S> Partition<S> for SingleRegion {
    fn region(&self, _x: &S) -> usize {
        0
    }
    fn num_regions(&self) -> usize {
        1
    }
}

/// A uniform grid over the first `dims` (1 or 2) coordinates of a `Vec<f64>` state, covering
/// the box `[lo, hi)` per coordinate with `cells` cells per axis; coordinates outside the box
/// are clamped into the border cells.
#[derive(Clone, Debug, PartialEq)]
pub struct UniformGrid {
    dims: usize,
    cells: usize,
    lo: f64,
    hi: f64,
}

impl UniformGrid {
    /// A grid over the first `dims` (1 or 2) coordinates with `cells >= 1` cells per axis on
    /// `[lo, hi)`.
    pub fn new(dims: usize, cells: usize, lo: f64, hi: f64) -> Result<Self, crate::McmcError> {
        crate::McmcError::check_range("dims", dims as f64, 1.0, 2.0, "1 or 2")?;
        crate::McmcError::check_range("cells", cells as f64, 1.0, 1e6, "1..=1000000")?;
        if lo >= hi || !lo.is_finite() || !hi.is_finite() {
            return Err(crate::McmcError::InvalidParameter {
                name: "hi - lo",
                value: hi - lo,
                allowed: "finite lo < hi",
            });
        }
        Ok(Self {
            dims,
            cells,
            lo,
            hi,
        })
    }

    fn cell(&self, v: f64) -> usize {
        let t = ((v - self.lo) / (self.hi - self.lo) * self.cells as f64).floor();
        if t.is_nan() {
            0
        } else {
            (t.max(0.0) as usize).min(self.cells - 1)
        }
    }
}

impl<S: AsRef<[f64]>> Partition<S> for UniformGrid {
    fn region(&self, x: &S) -> usize {
        let x = x.as_ref();
        let mut id = 0;
        for d in 0..self.dims {
            id = id * self.cells + self.cell(x.get(d).copied().unwrap_or(0.0));
        }
        id
    }
    fn num_regions(&self) -> usize {
        self.cells.pow(self.dims as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_regions_cover_and_clamp() {
        let g = UniformGrid::new(2, 4, 0.0, 1.0).unwrap();
        assert_eq!(Partition::<Vec<f64>>::num_regions(&g), 16);
        assert_eq!(g.region(&vec![0.0, 0.0]), 0);
        assert_eq!(g.region(&vec![0.99, 0.99]), 15);
        assert_eq!(g.region(&vec![-5.0, 7.0]), 3);
        assert!(UniformGrid::new(3, 4, 0.0, 1.0).is_err());
        assert!(UniformGrid::new(1, 4, 1.0, 1.0).is_err());
    }
}
