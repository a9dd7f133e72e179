//! How the pairwise stages group coordinates (pairs and a lone coordinate) and measure
//! displacements (in the plane or on the unit torus).

use crate::torus::{displacement, wrap};

/// A group of coordinates a pairwise stage moves together: a pair (a point of the plane or
/// of the 2-torus) or a lone coordinate.
///
/// On a plain vector the groups are [`pairs`]`(n)`; primary sample space pairs the numbers
/// of each stream (`pss::PairLayout`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    /// Two coordinates (their indices), moved as a point of the plane.
    Pair(usize, usize),
    /// A coordinate without a partner (the last one of an odd dimension).
    Single(usize),
}

/// The groups of a vector of length `n`: pairs `(0, 1), (2, 3), ...` (the DR paper's Alg. 2),
/// then the lone last coordinate if `n` is odd.
///
/// # Example
/// ```
/// use mcmc_core::delayed_rejection::{pairs, Group};
/// let groups: Vec<Group> = pairs(5).collect();
/// assert_eq!(groups, [Group::Pair(0, 1), Group::Pair(2, 3), Group::Single(4)]);
/// ```
pub fn pairs(n: usize) -> impl Iterator<Item = Group> {
    (0..n.div_ceil(2)).map(move |j| {
        let k = 2 * j;
        if k + 1 < n {
            Group::Pair(k, k + 1)
        } else {
            Group::Single(k)
        }
    })
}

/// How a pairwise stage measures and applies displacements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Space {
    /// `R^n`.
    Plane,
    /// The unit torus `[0, 1)^n`: minimal-image displacements, wrapped positions.
    Torus,
}

impl Space {
    /// The displacement `to - from` (on the torus: the minimal image, in `[-1/2, 1/2]`).
    #[inline]
    pub(super) fn delta(self, from: f64, to: f64) -> f64 {
        match self {
            Space::Plane => to - from,
            Space::Torus => displacement(from, to),
        }
    }

    /// A position in the space (on the torus: wrapped into `[0, 1)`).
    #[inline]
    pub(super) fn place(self, v: f64) -> f64 {
        match self {
            Space::Plane => v,
            Space::Torus => wrap(v),
        }
    }
}
