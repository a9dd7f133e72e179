//! A gradient cache with exact, deterministic K-nearest-within-radius queries.
//!
//! Cache-driven adaptation for Langevin Monte Carlo (Luan et al. 2020, *Langevin Monte Carlo
//! Rendering with Gradient-based Adaptation*, sections 6–7, eq. 21–22) keeps a cache
//! `C = {(u, g)}` of visited points `u` and the gradients `g` evaluated there, and at every
//! step queries `Q(v; C, r)`: the entries within Euclidean distance `r` of the current point
//! `v`. The paper's implementation stops after `K` neighbours; this module returns the `K`
//! **nearest** entries within `r`, so the answer does not depend on traversal order.
//!
//! # Design
//!
//! [`GradientCache`] stores points and gradients in flat arrays. The first `n_tree` entries
//! are indexed by a static k-d tree (median split on the widest dimension of each node's
//! tight bounding box, leaf buckets of at most 16 entries); later entries form a linearly
//! scanned tail. The tree is rebuilt (reusing its allocations) when the tail reaches 256
//! entries and when the cache becomes full, so a push costs amortised `O(log n)` work and
//! never allocates beyond amortised `Vec` growth.
//!
//! [`Neighbours`] is a bounded, sorted result set: a query inserts candidates into it,
//! keeping the `K` smallest under the total order `(dist2, source, index)`, and prunes
//! subtrees whose bounding-box lower bound cannot beat the current `K`-th entry or the
//! radius. The lower bound is computed with the same per-dimension arithmetic, in the same
//! order, as the exact distance, so it never exceeds it in floating point: pruning is exact
//! and the result is bit-identical to a brute-force scan, whatever the insertion and rebuild
//! history. A query allocates nothing once the [`Neighbours`] has capacity for `K` entries.
//!
//! The `source` tag lets a caller query several caches (say a shared snapshot as source 0
//! and a chain-local cache as source 1) into one [`Neighbours`] and obtain the `K` nearest
//! entries of their union.

use std::cmp::Ordering;

#[cfg(test)]
mod exactness_tests;
mod kd_tree;
mod neighbours;

pub use neighbours::{Neighbour, Neighbours};

use kd_tree::Node;
use neighbours::squared_distance;

/// Tail length (entries not yet in the tree) that triggers a rebuild.
const MAX_TAIL: usize = 256;

/// A finite cache of `(point, gradient)` pairs with exact nearest-neighbour queries.
///
/// Entries are numbered `0..len()` in insertion order; that index is what [`Neighbour::index`]
/// refers to. The cache has a fixed capacity `H` (finite adaptation): once full, further
/// entries are refused.
///
/// Query results depend only on the stored entries (and their order), never on when the
/// internal k-d tree was rebuilt.
///
/// # Example
/// ```
/// use mcmc_core::langevin::{GradientCache, Neighbours};
///
/// let mut cache = GradientCache::new(2, 100);
/// assert!(cache.push(&[0.0, 0.0], &[1.0, 0.0]));
/// assert!(cache.push(&[0.5, 0.0], &[0.0, 1.0]));
/// assert!(cache.push(&[3.0, 3.0], &[1.0, 1.0]));
///
/// // The two nearest entries within distance 1 of (0.1, 0).
/// let mut out = Neighbours::new(2);
/// cache.query(&[0.1, 0.0], 1.0, 0, &mut out);
/// let found: Vec<usize> = out.iter().map(|n| n.index).collect();
/// assert_eq!(found, [0, 1]);
/// assert_eq!(cache.gradient(found[1]), &[0.0, 1.0]);
/// ```
#[derive(Clone, Debug)]
pub struct GradientCache {
    dim: usize,
    capacity: usize,
    len: usize,
    /// `len * dim` coordinates, entry-major.
    points: Vec<f64>,
    /// `len * dim` gradient components, entry-major.
    gradients: Vec<f64>,
    /// Number of leading entries indexed by the tree; `n_tree..len` is the scanned tail.
    n_tree: usize,
    /// Permutation of `0..n_tree`; every node covers a contiguous range of it.
    perm: Vec<usize>,
    /// Tree nodes; node 0 is the root (when `n_tree > 0`).
    nodes: Vec<Node>,
    /// Tight bounding box of each node: `2 * dim` values, `dim` lows then `dim` highs.
    boxes: Vec<f64>,
}

impl GradientCache {
    /// Creates an empty cache for points of dimension `dim` holding at most `capacity`
    /// entries.
    ///
    /// Only the point and gradient storage for the first entries is reserved up front
    /// (at most 1024 entries); storage grows as entries are pushed.
    ///
    /// # Panics
    /// If `dim == 0`.
    #[must_use]
    pub fn new(dim: usize, capacity: usize) -> Self {
        assert!(dim > 0, "GradientCache: dimension must be positive");
        let reserve = capacity.min(1024).saturating_mul(dim);
        Self {
            dim,
            capacity,
            len: 0,
            points: Vec::with_capacity(reserve),
            gradients: Vec::with_capacity(reserve),
            n_tree: 0,
            perm: Vec::new(),
            nodes: Vec::new(),
            boxes: Vec::new(),
        }
    }

    /// Dimension of the points (and gradients).
    #[must_use]
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of stored entries.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the cache holds no entry.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Maximum number of entries (`H`).
    #[must_use]
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Whether the cache holds `capacity()` entries and refuses further ones.
    #[must_use]
    pub fn is_full(&self) -> bool {
        self.len >= self.capacity
    }

    /// Appends the entry `(point, gradient)` and returns `true`, or returns `false` and
    /// stores nothing when the cache is full.
    ///
    /// Entries with non-finite coordinates are stored but never returned by
    /// [`query`](Self::query) (their distance is not finite, or NaN).
    ///
    /// # Panics
    /// If `point.len()` or `gradient.len()` differs from [`dim`](Self::dim) (checked even
    /// when the cache is full).
    pub fn push(&mut self, point: &[f64], gradient: &[f64]) -> bool {
        assert_eq!(
            point.len(),
            self.dim,
            "GradientCache::push: point has the wrong dimension"
        );
        assert_eq!(
            gradient.len(),
            self.dim,
            "GradientCache::push: gradient has the wrong dimension"
        );
        if self.is_full() {
            return false;
        }
        self.points.extend_from_slice(point);
        self.gradients.extend_from_slice(gradient);
        self.len += 1;
        self.maybe_rebuild();
        true
    }

    /// Appends `other`'s entries, in order, until this cache is full; returns how many were
    /// appended.
    ///
    /// # Panics
    /// If `other.dim() != self.dim()`.
    pub fn extend_from(&mut self, other: &GradientCache) -> usize {
        assert_eq!(
            other.dim, self.dim,
            "GradientCache::extend_from: dimensions differ"
        );
        let count = other.len.min(self.capacity.saturating_sub(self.len));
        if count == 0 {
            return 0;
        }
        let values = count * self.dim;
        self.points.extend_from_slice(&other.points[..values]);
        self.gradients.extend_from_slice(&other.gradients[..values]);
        self.len += count;
        self.maybe_rebuild();
        count
    }

    /// Removes every entry, keeping all allocations.
    pub fn clear(&mut self) {
        self.len = 0;
        self.points.clear();
        self.gradients.clear();
        self.n_tree = 0;
        self.perm.clear();
        self.nodes.clear();
        self.boxes.clear();
    }

    /// The point of entry `i`.
    ///
    /// # Panics
    /// If `i >= len()`.
    #[must_use]
    pub fn point(&self, i: usize) -> &[f64] {
        assert!(i < self.len, "GradientCache::point: index {i} out of range");
        &self.points[i * self.dim..(i + 1) * self.dim]
    }

    /// The gradient of entry `i`.
    ///
    /// # Panics
    /// If `i >= len()`.
    #[must_use]
    pub fn gradient(&self, i: usize) -> &[f64] {
        assert!(
            i < self.len,
            "GradientCache::gradient: index {i} out of range"
        );
        &self.gradients[i * self.dim..(i + 1) * self.dim]
    }

    /// Adds to `out` the entries within Euclidean distance `radius` of `v`, tagged with
    /// `source`, keeping only `out`'s `K` nearest overall.
    ///
    /// An entry qualifies when its squared distance `dist2`, computed as the in-order sum of
    /// `(v[d] - point[d])²`, satisfies `dist2 < radius * radius` (strict). Entries already
    /// in `out` (from earlier queries, e.g. of another cache with another `source`) compete
    /// with the new ones under the order `(dist2, source, index)`; querying the same cache
    /// twice with the same `source` would insert duplicates. A `radius` that is zero,
    /// negative or NaN adds nothing; an infinite radius admits every finite entry.
    ///
    /// The result is exact (identical to a brute-force scan) and does not allocate once
    /// `out` has capacity for its `K` entries.
    ///
    /// # Panics
    /// If `v.len() != dim()`.
    pub fn query(&self, v: &[f64], radius: f64, source: u32, out: &mut Neighbours) {
        assert_eq!(
            v.len(),
            self.dim,
            "GradientCache::query: point has the wrong dimension"
        );
        // Rejects zero, negative and NaN radii.
        if out.k == 0 || radius.partial_cmp(&0.0) != Some(Ordering::Greater) {
            return;
        }
        let r2 = radius * radius;
        if self.n_tree > 0 && out.admits(self.box_bound(0, v), r2) {
            self.visit(0, v, r2, source, out);
        }
        for index in self.n_tree..self.len {
            self.offer(index, v, r2, source, out);
        }
    }

    /// Offers entry `index` to `out` if it lies strictly within the radius.
    #[inline]
    fn offer(&self, index: usize, v: &[f64], r2: f64, source: u32, out: &mut Neighbours) {
        let p = &self.points[index * self.dim..(index + 1) * self.dim];
        let dist2 = squared_distance(v, p);
        if dist2 < r2 {
            out.offer(Neighbour {
                dist2,
                source,
                index,
            });
        }
    }

    /// Rebuilds the tree when the tail is long enough or the cache just became full.
    fn maybe_rebuild(&mut self) {
        let tail = self.len - self.n_tree;
        if tail >= MAX_TAIL || (tail > 0 && self.is_full()) {
            self.rebuild();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capacity_stops_pushes_and_truncates_extend() {
        let mut cache = GradientCache::new(2, 5);
        assert_eq!(cache.capacity(), 5);
        for i in 0..5 {
            assert!(!cache.is_full());
            assert!(cache.push(&[f64::from(i), 0.0], &[0.0, f64::from(i)]));
        }
        assert!(cache.is_full());
        assert!(!cache.push(&[9.0, 9.0], &[9.0, 9.0]));
        assert_eq!(cache.len(), 5);
        assert_eq!(cache.point(4), &[4.0, 0.0]);

        let mut other = GradientCache::new(2, 10);
        for i in 0..10 {
            other.push(&[f64::from(i), 1.0], &[f64::from(i), 2.0]);
        }
        let mut small = GradientCache::new(2, 7);
        small.push(&[-1.0, -1.0], &[-1.0, -1.0]);
        assert_eq!(small.extend_from(&other), 6);
        assert_eq!(small.len(), 7);
        assert!(small.is_full());
        for i in 0..6 {
            assert_eq!(small.point(i + 1), other.point(i));
            assert_eq!(small.gradient(i + 1), other.gradient(i));
        }
        assert_eq!(small.extend_from(&other), 0);
        assert_eq!(small.len(), 7);

        let mut zero = GradientCache::new(3, 0);
        assert!(zero.is_full() && zero.is_empty());
        assert!(!zero.push(&[0.0; 3], &[0.0; 3]));
        assert_eq!(zero.len(), 0);
    }

    #[test]
    fn empty_cache_adds_nothing_and_keeps_previous_results() {
        let empty = GradientCache::new(2, 10);
        let mut out = Neighbours::new(3);
        empty.query(&[0.0, 0.0], f64::INFINITY, 0, &mut out);
        assert!(out.is_empty());

        let mut full = GradientCache::new(2, 10);
        full.push(&[0.0, 0.0], &[1.0, 1.0]);
        full.query(&[0.0, 0.0], 1.0, 1, &mut out);
        empty.query(&[0.0, 0.0], 1.0, 0, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(
            out.iter().next(),
            Some(Neighbour {
                dist2: 0.0,
                source: 1,
                index: 0
            })
        );
    }

    #[test]
    #[should_panic(expected = "wrong dimension")]
    fn push_wrong_point_length_panics() {
        GradientCache::new(3, 10).push(&[0.0; 2], &[0.0; 3]);
    }

    #[test]
    #[should_panic(expected = "wrong dimension")]
    fn push_wrong_gradient_length_panics() {
        GradientCache::new(3, 10).push(&[0.0; 3], &[0.0; 4]);
    }

    #[test]
    #[should_panic(expected = "wrong dimension")]
    fn query_wrong_length_panics() {
        GradientCache::new(3, 10).query(&[0.0; 2], 1.0, 0, &mut Neighbours::new(1));
    }

    #[test]
    #[should_panic(expected = "dimensions differ")]
    fn extend_from_other_dimension_panics() {
        GradientCache::new(3, 10).extend_from(&GradientCache::new(2, 10));
    }
}
