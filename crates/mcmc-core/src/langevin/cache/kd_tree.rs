//! The static k-d tree over a gradient cache's entries: nodes and the recursive median-split
//! build (widest dimension of each node's tight bounding box, leaf buckets of at most 16),
//! the rebuild and the pruned depth-first search of a query.

use super::neighbours::Neighbours;
use super::GradientCache;

/// Maximum number of entries in a k-d tree leaf.
const LEAF_SIZE: usize = 16;

/// Marker for "no child": the node is a leaf.
pub(super) const NO_CHILD: usize = usize::MAX;

/// One node of the k-d tree: the entries `perm[start..end]` and, for internal nodes, the
/// indices of both children in `GradientCache::nodes`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    pub(super) start: usize,
    pub(super) end: usize,
    pub(super) left: usize,
    pub(super) right: usize,
}

/// Borrowed state for a recursive tree build.
pub(super) struct Builder<'a> {
    pub(super) dim: usize,
    pub(super) points: &'a [f64],
    pub(super) perm: &'a mut Vec<usize>,
    pub(super) nodes: &'a mut Vec<Node>,
    pub(super) boxes: &'a mut Vec<f64>,
}

impl Builder<'_> {
    /// Builds the node covering `perm[start..end]` and its subtree; returns its index.
    pub(super) fn build(&mut self, start: usize, end: usize) -> usize {
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

/// The tree side of [`GradientCache`]: rebuild and search.
impl GradientCache {
    /// Rebuilds the k-d tree over all entries, reusing the tree's allocations.
    pub(super) fn rebuild(&mut self) {
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

    /// Depth-first search of the subtree rooted at `node`, nearer child first.
    pub(super) fn visit(&self, node: usize, v: &[f64], r2: f64, source: u32, out: &mut Neighbours) {
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
    pub(super) fn box_bound(&self, node: usize, v: &[f64]) -> f64 {
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
}
