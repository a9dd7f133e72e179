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

/// Maximum number of entries in a k-d tree leaf.
const LEAF_SIZE: usize = 16;

/// Tail length (entries not yet in the tree) that triggers a rebuild.
const MAX_TAIL: usize = 256;

/// Marker for "no child": the node is a leaf.
const NO_CHILD: usize = usize::MAX;

/// One node of the k-d tree: the entries `perm[start..end]` and, for internal nodes, the
/// indices of both children in `GradientCache::nodes`.
#[derive(Clone, Copy, Debug)]
struct Node {
    start: usize,
    end: usize,
    left: usize,
    right: usize,
}

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

    /// Depth-first search of the subtree rooted at `node`, nearer child first.
    fn visit(&self, node: usize, v: &[f64], r2: f64, source: u32, out: &mut Neighbours) {
        let Node {
            start,
            end,
            left,
            right,
        } = self.nodes[node];
        if left == NO_CHILD {
            for &index in &self.perm[start..end] {
                self.offer(index, v, r2, source, out);
            }
            return;
        }
        let bound_left = self.box_bound(left, v);
        let bound_right = self.box_bound(right, v);
        let (near, bound_near, far, bound_far) = if bound_right < bound_left {
            (right, bound_right, left, bound_left)
        } else {
            (left, bound_left, right, bound_right)
        };
        if out.admits(bound_near, r2) {
            self.visit(near, v, r2, source, out);
        }
        if out.admits(bound_far, r2) {
            self.visit(far, v, r2, source, out);
        }
    }

    /// Lower bound on the squared distance from `v` to any entry of `node`.
    ///
    /// Computed term by term in the same order as [`squared_distance`], with each term no
    /// larger than the corresponding exact term (rounding is monotone), so it never exceeds
    /// the floating-point distance of any entry in the box.
    #[inline]
    fn box_bound(&self, node: usize, v: &[f64]) -> f64 {
        let b = &self.boxes[node * 2 * self.dim..(node + 1) * 2 * self.dim];
        let (lo, hi) = b.split_at(self.dim);
        let mut sum = 0.0;
        for ((&x, &l), &h) in v.iter().zip(lo).zip(hi) {
            let gap = if x < l {
                l - x
            } else if x > h {
                x - h
            } else {
                0.0
            };
            sum += gap * gap;
        }
        sum
    }

    /// Rebuilds the tree when the tail is long enough or the cache just became full.
    fn maybe_rebuild(&mut self) {
        let tail = self.len - self.n_tree;
        if tail >= MAX_TAIL || (tail > 0 && self.is_full()) {
            self.rebuild();
        }
    }

    /// Rebuilds the k-d tree over all entries, reusing the tree's allocations.
    fn rebuild(&mut self) {
        self.perm.clear();
        self.perm.extend(0..self.len);
        self.nodes.clear();
        self.boxes.clear();
        if self.len > 0 {
            let mut builder = Builder {
                dim: self.dim,
                points: &self.points,
                perm: &mut self.perm,
                nodes: &mut self.nodes,
                boxes: &mut self.boxes,
            };
            builder.build(0, self.len);
        }
        self.n_tree = self.len;
    }
}

/// Borrowed state for a recursive tree build.
struct Builder<'a> {
    dim: usize,
    points: &'a [f64],
    perm: &'a mut Vec<usize>,
    nodes: &'a mut Vec<Node>,
    boxes: &'a mut Vec<f64>,
}

impl Builder<'_> {
    /// Builds the node covering `perm[start..end]` and its subtree; returns its index.
    fn build(&mut self, start: usize, end: usize) -> usize {
        let dim = self.dim;
        let id = self.nodes.len();
        self.nodes.push(Node {
            start,
            end,
            left: NO_CHILD,
            right: NO_CHILD,
        });

        // Tight bounding box (NaN coordinates are ignored).
        let box_start = self.boxes.len();
        self.boxes.extend(std::iter::repeat_n(f64::INFINITY, dim));
        self.boxes
            .extend(std::iter::repeat_n(f64::NEG_INFINITY, dim));
        {
            let (lo, hi) = self.boxes[box_start..].split_at_mut(dim);
            for &i in &self.perm[start..end] {
                let p = &self.points[i * dim..(i + 1) * dim];
                for d in 0..dim {
                    if p[d] < lo[d] {
                        lo[d] = p[d];
                    }
                    if p[d] > hi[d] {
                        hi[d] = p[d];
                    }
                }
            }
        }
        if end - start <= LEAF_SIZE {
            return id;
        }

        // Widest dimension (first one on ties); no split if every extent is zero or NaN.
        let (lo, hi) = self.boxes[box_start..box_start + 2 * dim].split_at(dim);
        let mut split = None;
        let mut widest = 0.0;
        for d in 0..dim {
            let width = hi[d] - lo[d];
            if width > widest {
                widest = width;
                split = Some(d);
            }
        }
        let Some(split) = split else {
            return id;
        };

        let mid = start + (end - start) / 2;
        let points = self.points;
        self.perm[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            points[a * dim + split]
                .total_cmp(&points[b * dim + split])
                .then(a.cmp(&b))
        });
        let left = self.build(start, mid);
        let right = self.build(mid, end);
        self.nodes[id].left = left;
        self.nodes[id].right = right;
        id
    }
}

/// Squared Euclidean distance, summed in dimension order.
#[inline]
fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    let mut sum = 0.0;
    for (&x, &y) in a.iter().zip(b) {
        let diff = x - y;
        sum += diff * diff;
    }
    sum
}

/// One query result: an entry of the cache tagged `source`, at squared distance `dist2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    /// Squared Euclidean distance from the query point.
    pub dist2: f64,
    /// The `source` tag passed to [`GradientCache::query`].
    pub source: u32,
    /// Index of the entry in its cache ([`GradientCache::point`], [`GradientCache::gradient`]).
    pub index: usize,
}

impl Neighbour {
    /// Total order `(dist2, source, index)` used for selection and sorting.
    #[inline]
    fn key_cmp(&self, other: &Self) -> Ordering {
        self.dist2
            .total_cmp(&other.dist2)
            .then(self.source.cmp(&other.source))
            .then(self.index.cmp(&other.index))
    }
}

/// The `K` nearest neighbours found so far, sorted by `(dist2, source, index)`.
///
/// Reuse one value across queries with [`reset`](Self::reset): once its capacity reaches
/// `K`, neither resetting nor querying allocates. The default value has `K = 0` and accepts
/// nothing.
#[derive(Clone, Debug, Default)]
pub struct Neighbours {
    k: usize,
    items: Vec<Neighbour>,
}

impl Neighbours {
    /// An empty set keeping at most `k` neighbours.
    #[must_use]
    pub fn new(k: usize) -> Self {
        Self {
            k,
            items: Vec::with_capacity(k),
        }
    }

    /// Empties the set and sets its bound to `k`; allocates only if the capacity is below `k`.
    pub fn reset(&mut self, k: usize) {
        self.items.clear();
        self.items.reserve(k);
        self.k = k;
    }

    /// Number of neighbours held (at most `K`).
    #[must_use]
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether no neighbour is held.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The neighbours in ascending `(dist2, source, index)` order.
    pub fn iter(&self) -> impl Iterator<Item = Neighbour> + '_ {
        self.items.iter().copied()
    }

    /// Whether a subtree whose entries are at squared distance `>= bound` may still
    /// contribute: it must beat the radius and, when full, not be worse than the `K`-th entry
    /// (equal distances may still win on `(source, index)`).
    #[inline]
    fn admits(&self, bound: f64, r2: f64) -> bool {
        bound < r2
            && (self.items.len() < self.k
                || self.items.last().is_some_and(|worst| bound <= worst.dist2))
    }

    /// Inserts `candidate` if it is among the `K` smallest, evicting the largest if needed.
    #[inline]
    fn offer(&mut self, candidate: Neighbour) {
        if self.items.len() >= self.k {
            match self.items.last() {
                Some(worst) if candidate.key_cmp(worst) == Ordering::Less => {
                    self.items.pop();
                }
                _ => return,
            }
        }
        let pos = self
            .items
            .partition_point(|n| n.key_cmp(&candidate) == Ordering::Less);
        self.items.insert(pos, candidate);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64;

    /// Brute-force reference: the `k` smallest `(dist2, source, index)` over all sources.
    fn brute(caches: &[(&GradientCache, u32)], v: &[f64], radius: f64, k: usize) -> Vec<Neighbour> {
        let mut all = Vec::new();
        if radius > 0.0 {
            let r2 = radius * radius;
            for &(cache, source) in caches {
                for index in 0..cache.len() {
                    let dist2 = squared_distance(v, cache.point(index));
                    if dist2 < r2 {
                        all.push(Neighbour {
                            dist2,
                            source,
                            index,
                        });
                    }
                }
            }
        }
        all.sort_by(Neighbour::key_cmp);
        all.truncate(k);
        all
    }

    /// Bit-exact comparison of two result lists.
    fn assert_same(got: &[Neighbour], want: &[Neighbour], context: &str) {
        assert_eq!(
            got.len(),
            want.len(),
            "{context}: lengths differ\n got {got:?}\nwant {want:?}"
        );
        for (g, w) in got.iter().zip(want) {
            assert!(
                g.dist2.to_bits() == w.dist2.to_bits()
                    && g.source == w.source
                    && g.index == w.index,
                "{context}: {g:?} != {w:?}\n got {got:?}\nwant {want:?}"
            );
        }
    }

    fn collect(out: &Neighbours) -> Vec<Neighbour> {
        out.iter().collect()
    }

    /// A random point: uniform, clustered, or on a coarse grid (many exact ties).
    fn random_point(rng: &mut Pcg64, dim: usize, kind: u32, centres: &[Vec<f64>]) -> Vec<f64> {
        match kind {
            0 => (0..dim).map(|_| rng.random::<f64>()).collect(),
            1 => {
                let c = &centres[rng.random_range(0..centres.len())];
                c.iter()
                    .map(|&x| x + 0.02 * (rng.random::<f64>() - 0.5))
                    .collect()
            }
            _ => (0..dim)
                .map(|_| f64::from(rng.random_range(0..5u32)) * 0.25)
                .collect(),
        }
    }

    fn random_cache(rng: &mut Pcg64, dim: usize, n: usize, kind: u32) -> GradientCache {
        let centres: Vec<Vec<f64>> = (0..4)
            .map(|_| (0..dim).map(|_| rng.random::<f64>()).collect())
            .collect();
        let mut cache = GradientCache::new(dim, n);
        for _ in 0..n {
            let p = random_point(rng, dim, kind, &centres);
            let g: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
            assert!(cache.push(&p, &g));
        }
        cache
    }

    #[test]
    fn query_matches_brute_force() {
        let mut rng = Pcg64::seed_from_u64(1);
        let mut out = Neighbours::default();
        for &dim in &[1usize, 2, 3, 5, 8, 16, 32] {
            for &n in &[0usize, 1, 7, 16, 17, 100, 255, 256, 257, 700, 2000] {
                for kind in 0..3 {
                    let cache = random_cache(&mut rng, dim, n, kind);
                    let centres = vec![vec![0.5; dim]];
                    for _ in 0..6 {
                        let v = random_point(&mut rng, dim, kind, &centres);
                        let radius = [0.05, 0.2, 0.5, 1.0, f64::INFINITY][rng.random_range(0..5)]
                            * (dim as f64).sqrt();
                        let k = [1usize, 3, 10, 30][rng.random_range(0..4)];
                        out.reset(k);
                        cache.query(&v, radius, 0, &mut out);
                        let want = brute(&[(&cache, 0)], &v, radius, k);
                        assert_same(
                            &collect(&out),
                            &want,
                            &format!("dim {dim} n {n} kind {kind} r {radius} k {k}"),
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn interleaved_push_and_query_across_rebuilds() {
        let mut rng = Pcg64::seed_from_u64(2);
        for &(dim, capacity) in &[(1usize, 600usize), (3, 1100), (12, 800)] {
            let mut cache = GradientCache::new(dim, capacity);
            let mut out = Neighbours::new(30);
            let mut step = 0usize;
            while !cache.is_full() {
                // Occasionally push several at once, through `extend_from`.
                if step.is_multiple_of(97) {
                    let size = rng.random_range(1..40);
                    let batch = random_cache(&mut rng, dim, size, 0);
                    cache.extend_from(&batch);
                } else {
                    let p: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
                    assert!(cache.push(&p, &p));
                }
                step += 1;
                let v: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
                let radius = 0.3 * (dim as f64).sqrt();
                let k = 1 + step % 30;
                out.reset(k);
                cache.query(&v, radius, 0, &mut out);
                let want = brute(&[(&cache, 0)], &v, radius, k);
                assert_same(
                    &collect(&out),
                    &want,
                    &format!("dim {dim} len {}", cache.len()),
                );
            }
            assert_eq!(cache.len(), capacity);
            assert_eq!(
                cache.n_tree, capacity,
                "a full cache is entirely in the tree"
            );
        }
    }

    #[test]
    fn two_sources_merge_to_union() {
        let mut rng = Pcg64::seed_from_u64(3);
        for &dim in &[2usize, 6] {
            for kind in 0..3 {
                let shared = random_cache(&mut rng, dim, 900, kind);
                let local = random_cache(&mut rng, dim, 130, kind);
                for _ in 0..20 {
                    let v: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
                    let radius = 0.4;
                    let k = rng.random_range(1..31);
                    let want = brute(&[(&shared, 0), (&local, 1)], &v, radius, k);
                    let mut a = Neighbours::new(k);
                    shared.query(&v, radius, 0, &mut a);
                    local.query(&v, radius, 1, &mut a);
                    assert_same(&collect(&a), &want, "shared then local");
                    let mut b = Neighbours::new(k);
                    local.query(&v, radius, 1, &mut b);
                    shared.query(&v, radius, 0, &mut b);
                    assert_same(&collect(&b), &want, "local then shared");
                }
            }
        }
    }

    #[test]
    fn ties_across_sources_break_by_source_then_index() {
        let mut a = GradientCache::new(1, 10);
        let mut b = GradientCache::new(1, 10);
        for _ in 0..3 {
            a.push(&[1.0], &[0.0]);
            b.push(&[1.0], &[0.0]);
        }
        let mut out = Neighbours::new(4);
        b.query(&[0.0], 2.0, 1, &mut out);
        a.query(&[0.0], 2.0, 0, &mut out);
        let keys: Vec<(u32, usize)> = out.iter().map(|n| (n.source, n.index)).collect();
        assert_eq!(keys, [(0, 0), (0, 1), (0, 2), (1, 0)]);
    }

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
    fn duplicates_resolve_by_lowest_index() {
        let mut cache = GradientCache::new(3, 2000);
        for i in 0..1000 {
            // Alternate between two locations; the one at the origin is nearest.
            let p = if i % 2 == 0 {
                [0.0; 3]
            } else {
                [0.1, 0.0, 0.0]
            };
            cache.push(&p, &p);
        }
        let mut out = Neighbours::new(5);
        cache.query(&[0.0; 3], 1.0, 0, &mut out);
        let idx: Vec<usize> = out.iter().map(|n| n.index).collect();
        assert_eq!(idx, [0, 2, 4, 6, 8]);
        out.reset(30);
        cache.query(&[0.1, 0.0, 0.0], 1.0, 0, &mut out);
        let want: Vec<usize> = (0..30).map(|i| 2 * i + 1).collect();
        assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), want);
        assert_same(
            &collect(&out),
            &brute(&[(&cache, 0)], &[0.1, 0.0, 0.0], 1.0, 30),
            "dups",
        );
    }

    #[test]
    fn results_independent_of_history() {
        let mut rng = Pcg64::seed_from_u64(4);
        let dim = 4;
        let source = random_cache(&mut rng, dim, 1500, 2);
        // History 1: one push at a time.
        let mut one = GradientCache::new(dim, 2000);
        for i in 0..source.len() {
            one.push(source.point(i), source.gradient(i));
        }
        // History 2: chunks through `extend_from`, after filling and clearing with junk.
        let mut two = GradientCache::new(dim, 2000);
        let junk = random_cache(&mut rng, dim, 777, 0);
        two.extend_from(&junk);
        two.clear();
        assert!(two.is_empty());
        let mut chunk = GradientCache::new(dim, 300);
        for i in 0..source.len() {
            chunk.push(source.point(i), source.gradient(i));
            if chunk.is_full() || i + 1 == source.len() {
                two.extend_from(&chunk);
                chunk.clear();
            }
        }
        // History 3: a clone, then everything full (rebuilt once at capacity).
        let mut three = GradientCache::new(dim, source.len());
        three.extend_from(&source);
        let three = three.clone();
        assert_ne!(
            one.n_tree, three.n_tree,
            "histories should differ in tree layout"
        );
        for _ in 0..50 {
            let v: Vec<f64> = (0..dim)
                .map(|_| f64::from(rng.random_range(0..5u32)) * 0.25)
                .collect();
            let k = rng.random_range(1..31);
            let mut results = Vec::new();
            for cache in [&one, &two, &three] {
                let mut out = Neighbours::new(k);
                cache.query(&v, 0.6, 0, &mut out);
                results.push(collect(&out));
            }
            assert_same(&results[0], &results[1], "one vs two");
            assert_same(&results[0], &results[2], "one vs three");
            assert_same(
                &results[0],
                &brute(&[(&source, 0)], &v, 0.6, k),
                "one vs brute",
            );
        }
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
    fn degenerate_radius_and_k_add_nothing() {
        let mut rng = Pcg64::seed_from_u64(5);
        let cache = random_cache(&mut rng, 3, 500, 2);
        let v = cache.point(0).to_vec();
        let mut out = Neighbours::new(10);
        for radius in [0.0, -0.0, -1.0, f64::NAN, f64::NEG_INFINITY] {
            cache.query(&v, radius, 0, &mut out);
            assert!(out.is_empty(), "radius {radius}");
        }
        // Strict inequality: an entry at exactly the radius is excluded.
        let mut line = GradientCache::new(1, 4);
        line.push(&[1.0], &[0.0]);
        line.push(&[0.5], &[0.0]);
        line.query(&[0.0], 1.0, 0, &mut out);
        assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), [1]);
        // K = 0 accepts nothing.
        let mut none = Neighbours::new(0);
        cache.query(&v, f64::INFINITY, 0, &mut none);
        assert!(none.is_empty());
        let mut default = Neighbours::default();
        cache.query(&v, f64::INFINITY, 0, &mut default);
        assert!(default.is_empty());
    }

    #[test]
    fn non_finite_entries_are_never_returned() {
        let mut cache = GradientCache::new(2, 400);
        for i in 0..300 {
            let x = f64::from(i) / 300.0;
            let p = match i % 3 {
                0 => [f64::NAN, x],
                1 => [x, f64::INFINITY],
                _ => [x, x],
            };
            cache.push(&p, &[0.0, 0.0]);
        }
        let mut out = Neighbours::new(30);
        cache.query(&[0.5, 0.5], f64::INFINITY, 0, &mut out);
        assert_eq!(out.len(), 30);
        assert!(out.iter().all(|n| n.index % 3 == 2 && n.dist2.is_finite()));
        assert_same(
            &collect(&out),
            &brute(&[(&cache, 0)], &[0.5, 0.5], f64::INFINITY, 30),
            "nan",
        );
        out.reset(30);
        cache.query(&[f64::NAN, 0.5], f64::INFINITY, 0, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn neighbours_reuse_does_not_reallocate() {
        let mut rng = Pcg64::seed_from_u64(6);
        let cache = random_cache(&mut rng, 5, 3000, 1);
        let mut out = Neighbours::new(30);
        let ptr = out.items.as_ptr();
        for _ in 0..100 {
            out.reset(rng.random_range(0..31));
            let v: Vec<f64> = (0..5).map(|_| rng.random::<f64>()).collect();
            cache.query(&v, 2.0, 0, &mut out);
            assert!(out.items.capacity() >= 30);
            assert_eq!(out.items.as_ptr(), ptr);
        }
    }

    #[test]
    fn clear_keeps_allocations_and_works_again() {
        let mut rng = Pcg64::seed_from_u64(7);
        let mut cache = random_cache(&mut rng, 2, 1000, 0);
        let (pc, nc) = (cache.points.capacity(), cache.nodes.capacity());
        cache.clear();
        assert!(cache.is_empty() && !cache.is_full());
        assert_eq!(cache.points.capacity(), pc);
        assert_eq!(cache.nodes.capacity(), nc);
        let mut out = Neighbours::new(5);
        cache.query(&[0.5, 0.5], 10.0, 0, &mut out);
        assert!(out.is_empty());
        assert!(cache.push(&[0.25, 0.5], &[1.0, 2.0]));
        cache.query(&[0.5, 0.5], 10.0, 0, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(cache.gradient(0), &[1.0, 2.0]);
        assert_eq!(cache.dim(), 2);
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
