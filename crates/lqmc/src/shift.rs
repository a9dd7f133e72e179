//! The Cranley-Patterson shift of a seed point relative to its closest lattice point, and the
//! shifted lattice set it defines (paper eq. 3 and Alg. 1, lines 3 and 7).

use crate::lattice::Rank1Lattice;
use crate::torus::{torus_difference, wrap_unit};

/// A rank-1 lattice shifted so that one of its points lands on a seed: the set
/// `R = { {r_j + Delta} : j = 0..N }` with `Delta = t_s - r_i`, `r_i` the lattice point
/// closest to the seed `t_s` on the torus (paper eq. 3, Alg. 1 lines 3 and 7).
///
/// `Delta` is stored as the shortest toroidal difference, so it lies in the Voronoi cell of
/// the origin. The Voronoi cells of a lattice are congruent, hence `{r_j + Delta}` lies in the
/// cell of `r_j`: starting from any member `j` instead of the seed finds `r_j` and the same
/// `Delta` (section 3, "A note on lattices", Fig. 3), i.e. all members of a set agree on the
/// set. This is tested with proptest in `tests/voronoi.rs`.
///
/// # Example
///
/// ```
/// use lqmc::{Rank1Lattice, ShiftedLattice};
///
/// let lattice = Rank1Lattice::from_table(23, 3).unwrap();
/// let set = ShiftedLattice::through(&lattice, &[0.31, 0.72, 0.05]);
/// let mut member = [0.0; 3];
/// set.member(&lattice, 5, &mut member);
/// // From member 5 the search recovers the same set, with member 5 as its seed.
/// let again = ShiftedLattice::through(&lattice, &member);
/// assert_eq!(again.seed_index(), 5);
/// for (a, b) in again.shift().iter().zip(set.shift()) {
///     assert!((a - b).abs() < 1e-12);
/// }
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ShiftedLattice {
    seed_index: u32,
    shift: Vec<f64>,
}

impl ShiftedLattice {
    /// The set through seed `t` (tile coordinates, `lattice.dims()` components).
    #[must_use]
    pub fn through(lattice: &Rank1Lattice, t: &[f64]) -> Self {
        let closest = lattice.closest_point(t);
        let r = lattice.point(closest.index);
        let shift = t
            .iter()
            .zip(r)
            .map(|(&x, &y)| torus_difference(x, y))
            .collect();
        ShiftedLattice {
            seed_index: closest.index,
            shift,
        }
    }

    /// Index `i` of the lattice point closest to the seed: the seed is member `i`.
    #[must_use]
    pub fn seed_index(&self) -> u32 {
        self.seed_index
    }

    /// The Cranley-Patterson shift `Delta = t_s - r_i` (each component in `[-0.5, 0.5]`).
    #[must_use]
    pub fn shift(&self) -> &[f64] {
        &self.shift
    }

    /// Member `j`: `{r_j + Delta}` in `[0, 1)^s` (Alg. 1 line 7, before `T^{-1}`).
    pub fn member(&self, lattice: &Rank1Lattice, j: u32, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.shift.len());
        for ((o, &r), &d) in out.iter_mut().zip(lattice.point(j)).zip(&self.shift) {
            *o = wrap_unit(r + d);
        }
    }
}
