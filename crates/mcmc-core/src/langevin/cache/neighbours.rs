//! The bounded, sorted result set of a gradient-cache query: the `K` nearest entries under the
//! total order `(dist2, source, index)`.

use std::cmp::Ordering;

/// Squared Euclidean distance, summed in dimension order.
#[inline]
pub(super) fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
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
    /// The `source` tag passed to [`super::GradientCache::query`].
    pub source: u32,
    /// Index of the entry in its cache ([`super::GradientCache::point`],
    /// [`super::GradientCache::gradient`]).
    pub index: usize,
}

impl Neighbour {
    /// Total order `(dist2, source, index)` used for selection and sorting.
    #[inline]
    pub(super) fn key_cmp(&self, other: &Self) -> Ordering {
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
    pub(super) k: usize,
    pub(super) items: Vec<Neighbour>,
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
    pub(super) fn admits(&self, bound: f64, r2: f64) -> bool {
        bound < r2
            && (self.items.len() < self.k
                || self.items.last().is_some_and(|worst| bound <= worst.dist2))
    }

    /// Inserts `candidate` if it is among the `K` smallest, evicting the largest if needed.
    #[inline]
    pub(super) fn offer(&mut self, candidate: Neighbour) {
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
