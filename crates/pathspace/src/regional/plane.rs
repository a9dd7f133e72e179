//! Partitions of the unit square `[0, 1)^2`: an `N x N` grid and a refinable quadtree
//! (regional-adaptive paper, section 6.1-6.2, Fig. 4-5).

use std::ops::Range;

use crate::error::PathspaceError;

/// Largest accepted grid resolution per axis.
pub const MAX_GRID_CELLS: usize = 4096;

/// Deepest quadtree level accepted (`4^24` leaves would not fit the region ids anyway).
pub const MAX_QUADTREE_DEPTH: u8 = 24;

const NO_CHILD: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Node {
    /// Index of the first of four consecutive children, or `NO_CHILD` for a leaf.
    children: u32,
    /// The region id of a leaf (meaningless for inner nodes).
    region: u32,
    depth: u8,
}

/// A quadtree over `[0, 1)^2` whose leaves are the regions (section 6.1, Fig. 4 right).
///
/// It starts with the root as its only leaf (region 0). [`Quadtree::split`] turns a leaf into
/// four children (quadrants in the order `(x < 1/2, y < 1/2)`, `(x >= 1/2, y < 1/2)`,
/// `(x < 1/2, y >= 1/2)`, `(x >= 1/2, y >= 1/2)`): the first keeps the leaf's region id, the
/// others get the next three fresh ids, so ids stay dense (mcmc-core's
/// [`mcmc_core::Partition::split`] convention). Splitting is deterministic: the same sequence
/// of splits gives the same tree and the same ids.
///
/// # Example
/// ```
/// use pathspace::regional::Quadtree;
///
/// let mut tree = Quadtree::new(8).unwrap();
/// assert_eq!(tree.region([0.9, 0.1]), 0);
/// assert_eq!(tree.split(0), Some(1..4));
/// assert_eq!(tree.region([0.1, 0.1]), 0); // the first child keeps the id
/// assert_eq!(tree.region([0.9, 0.1]), 1);
/// assert_eq!(tree.bounds(3), [[0.5, 0.5], [1.0, 1.0]]);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Quadtree {
    nodes: Vec<Node>,
    /// Node index of each region's leaf.
    leaf_node: Vec<u32>,
    max_depth: u8,
}

impl Quadtree {
    /// A quadtree with only the root, whose leaves may be split down to depth `max_depth`
    /// (`1..=24`; the root has depth 0).
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for a depth outside `1..=24`.
    pub fn new(max_depth: u8) -> Result<Self, PathspaceError> {
        PathspaceError::check_range(
            "max_depth",
            f64::from(max_depth),
            1.0,
            f64::from(MAX_QUADTREE_DEPTH),
        )?;
        Ok(Self {
            nodes: vec![Node {
                children: NO_CHILD,
                region: 0,
                depth: 0,
            }],
            leaf_node: vec![0],
            max_depth,
        })
    }

    /// The deepest level a leaf may reach.
    #[must_use]
    pub fn max_depth(&self) -> u8 {
        self.max_depth
    }

    /// Number of leaves (regions).
    #[must_use]
    pub fn num_regions(&self) -> usize {
        self.leaf_node.len()
    }

    /// The region of the leaf containing `p` (coordinates are clamped into `[0, 1)`; NaN
    /// counts as 0).
    #[must_use]
    pub fn region(&self, p: [f64; 2]) -> usize {
        let (mut x, mut y) = (clamp_unit(p[0]), clamp_unit(p[1]));
        let mut node = self.nodes[0];
        while node.children != NO_CHILD {
            // Rescale to the child's square: exact in binary for the halvings.
            let right = x >= 0.5;
            let top = y >= 0.5;
            x = if right { 2.0 * x - 1.0 } else { 2.0 * x };
            y = if top { 2.0 * y - 1.0 } else { 2.0 * y };
            let q = usize::from(right) + 2 * usize::from(top);
            node = self.nodes[node.children as usize + q];
        }
        node.region as usize
    }

    /// Depth of a region's leaf (the root is 0).
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    #[must_use]
    pub fn depth(&self, region: usize) -> u8 {
        self.nodes[self.leaf_node[region] as usize].depth
    }

    /// The square `[lo, hi)` covered by a region's leaf.
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    #[must_use]
    pub fn bounds(&self, region: usize) -> [[f64; 2]; 2] {
        // Walk down from the root to the leaf, following the path that contains it.
        let target = self.leaf_node[region];
        let mut lo = [0.0, 0.0];
        let mut size = 1.0;
        let mut node = 0u32;
        while node != target {
            let n = self.nodes[node as usize];
            debug_assert_ne!(n.children, NO_CHILD);
            size *= 0.5;
            let q = (0..4u32)
                .find(|&q| self.contains(n.children + q, target))
                .expect("every leaf is below the root");
            lo[0] += size * f64::from(q & 1);
            lo[1] += size * f64::from(q >> 1);
            node = n.children + q;
        }
        [lo, [lo[0] + size, lo[1] + size]]
    }

    fn contains(&self, node: u32, target: u32) -> bool {
        if node == target {
            return true;
        }
        let n = self.nodes[node as usize];
        n.children != NO_CHILD && (0..4).any(|q| self.contains(n.children + q, target))
    }

    /// Splits a region's leaf into four (section 6.2): the first child keeps `region`'s id,
    /// the other three get the fresh ids returned. `None` if the leaf is at `max_depth`.
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    pub fn split(&mut self, region: usize) -> Option<Range<usize>> {
        let leaf = self.leaf_node[region] as usize;
        let depth = self.nodes[leaf].depth;
        if depth >= self.max_depth {
            return None;
        }
        let first_child = self.nodes.len() as u32;
        let fresh = self.leaf_node.len();
        for q in 0..4u32 {
            let id = if q == 0 {
                region
            } else {
                fresh + q as usize - 1
            };
            self.nodes.push(Node {
                children: NO_CHILD,
                region: id as u32,
                depth: depth + 1,
            });
            if q == 0 {
                self.leaf_node[region] = first_child;
            } else {
                self.leaf_node.push(first_child + q);
            }
        }
        self.nodes[leaf].children = first_child;
        Some(fresh..fresh + 3)
    }
}

fn clamp_unit(v: f64) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0 - f64::EPSILON / 2.0)
    }
}

/// A partition of `[0, 1)^2`: a uniform grid (fixed) or a quadtree (refinable).
///
/// # Example
/// ```
/// use pathspace::regional::PlanePartition;
///
/// let grid = PlanePartition::grid(4).unwrap();
/// assert_eq!(grid.num_regions(), 16);
/// assert_eq!(grid.region([0.3, 0.8]), 3 * 4 + 1); // row-major: y cell * N + x cell
/// let tree = PlanePartition::quadtree(6).unwrap();
/// assert_eq!(tree.num_regions(), 1);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PlanePartition {
    /// `n x n` equal cells, ids `y_cell * n + x_cell` (section 6.1, Fig. 4 left).
    Grid {
        /// Cells per axis.
        n: usize,
    },
    /// An adaptive quadtree (section 6.1-6.2).
    Quadtree(Quadtree),
}

impl PlanePartition {
    /// An `n x n` grid (`1..=4096`).
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for `n` out of range.
    pub fn grid(n: usize) -> Result<Self, PathspaceError> {
        PathspaceError::check_range("grid cells", n as f64, 1.0, MAX_GRID_CELLS as f64)?;
        Ok(Self::Grid { n })
    }

    /// A quadtree with only the root, refinable to depth `max_depth` (`1..=24`).
    ///
    /// # Errors
    /// As [`Quadtree::new`].
    pub fn quadtree(max_depth: u8) -> Result<Self, PathspaceError> {
        Ok(Self::Quadtree(Quadtree::new(max_depth)?))
    }

    /// Number of regions.
    #[must_use]
    pub fn num_regions(&self) -> usize {
        match self {
            Self::Grid { n } => n * n,
            Self::Quadtree(t) => t.num_regions(),
        }
    }

    /// The region containing `p` (clamped into `[0, 1)^2`).
    #[must_use]
    pub fn region(&self, p: [f64; 2]) -> usize {
        match self {
            Self::Grid { n } => {
                let cell = |v: f64| ((clamp_unit(v) * *n as f64) as usize).min(n - 1);
                cell(p[1]) * n + cell(p[0])
            }
            Self::Quadtree(t) => t.region(p),
        }
    }

    /// The square `[lo, hi)` of a region.
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    #[must_use]
    pub fn bounds(&self, region: usize) -> [[f64; 2]; 2] {
        match self {
            Self::Grid { n } => {
                assert!(region < n * n, "region {region} of {}", n * n);
                let h = 1.0 / *n as f64;
                let (x, y) = ((region % n) as f64, (region / n) as f64);
                [[x * h, y * h], [(x + 1.0) * h, (y + 1.0) * h]]
            }
            Self::Quadtree(t) => t.bounds(region),
        }
    }

    /// Splits a region (quadtrees only; see [`Quadtree::split`]); `None` for a grid.
    pub fn split(&mut self, region: usize) -> Option<Range<usize>> {
        match self {
            Self::Grid { .. } => None,
            Self::Quadtree(t) => t.split(region),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadtree_split_keeps_ids_dense_and_respects_depth() {
        let mut t = Quadtree::new(2).unwrap();
        assert_eq!(t.split(0), Some(1..4));
        assert_eq!(t.split(2), Some(4..7));
        assert_eq!(t.num_regions(), 7);
        // Id 2 was the (x < 1/2, y >= 1/2) quadrant; its first child keeps the id.
        assert_eq!(t.bounds(2), [[0.0, 0.5], [0.25, 0.75]]);
        assert_eq!(t.region([0.3, 0.9]), 6);
        assert_eq!(t.depth(6), 2);
        assert_eq!(t.split(6), None, "max depth reached");
        assert!(Quadtree::new(0).is_err());
        assert!(Quadtree::new(25).is_err());
    }

    #[test]
    fn grid_ids_and_bounds() {
        let g = PlanePartition::grid(3).unwrap();
        assert_eq!(g.region([0.0, 0.0]), 0);
        assert_eq!(g.region([0.99, 0.5]), 5);
        assert_eq!(g.region([2.0, -1.0]), 2);
        let b = g.bounds(5);
        assert!((b[0][0] - 2.0 / 3.0).abs() < 1e-15 && (b[1][1] - 2.0 / 3.0).abs() < 1e-15);
        assert!(PlanePartition::grid(0).is_err());
        assert_eq!(PlanePartition::grid(3).unwrap().split(0), None);
    }
}
