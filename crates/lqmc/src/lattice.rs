//! Rank-1 lattices `r_j = {j g / N}` (paper eq. 2) and the closest lattice point on the unit
//! torus (Alg. 1, line 3).

use crate::cbc::KorobovSpace;
use crate::error::LqmcError;
use crate::tables::CBC_TABLE;
use crate::torus::torus_difference;

/// The lattice sizes `N` with embedded CBC generator vectors (paper section 3.4).
pub const TABLE_SIZES: [u32; 4] = [7, 23, 97, 313];

/// The embedded generator vectors cover `s = 1..=TABLE_MAX_DIMS` (paper section 3.4).
pub const TABLE_MAX_DIMS: usize = 21;

/// A rank-1 lattice: `N` points `r_j = {j g / N}`, `j = 0..N`, in `[0, 1)^s` (paper eq. 2).
///
/// Its Voronoi cells on the unit torus are congruent (the lattice is a group under addition
/// mod 1), which is what makes the Cranley-Patterson shift found by the closest-point search
/// the same from every member of a shifted set (section 3, "A note on lattices"; see
/// [`crate::ShiftedLattice`]). The points are stored (`N s` numbers).
///
/// # Example
///
/// ```
/// use lqmc::Rank1Lattice;
///
/// // The lattice of the paper's Fig. 2.
/// let lattice = Rank1Lattice::new(128, vec![1, 12]).unwrap();
/// assert_eq!(lattice.point(3), &[3.0 / 128.0, 36.0 / 128.0]);
///
/// // An embedded CBC lattice (section 3.4): N = 23 in 5 dimensions.
/// let lattice = Rank1Lattice::from_table(23, 5).unwrap();
/// assert_eq!(lattice.len(), 23);
/// assert_eq!(lattice.dims(), 5);
///
/// // Closest point on the torus: (0.99, 0.99) is next to the origin.
/// let c = Rank1Lattice::new(7, vec![1, 3]).unwrap().closest_point(&[0.99, 0.99]);
/// assert_eq!(c.index, 0);
/// assert!((c.distance_squared - 2.0e-4).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Rank1Lattice {
    points: u32,
    generator: Vec<u32>,
    /// `coords[j * s + d] = {j g_d / N}`.
    coords: Vec<f64>,
}

/// The result of a closest-point search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    /// Index `j` of the closest lattice point `r_j`.
    pub index: u32,
    /// Its squared toroidal distance.
    pub distance_squared: f64,
}

impl Rank1Lattice {
    /// The lattice with `points` points and generator vector `generator` (components are
    /// reduced modulo `points`).
    ///
    /// # Errors
    ///
    /// [`LqmcError::InvalidParameter`] if `points == 0` or the generator is empty.
    pub fn new(points: u32, generator: Vec<u32>) -> Result<Self, LqmcError> {
        if points == 0 {
            return Err(LqmcError::invalid("points", points, ">= 1"));
        }
        if generator.is_empty() {
            return Err(LqmcError::invalid("generator.len()", 0, ">= 1"));
        }
        let generator: Vec<u32> = generator.into_iter().map(|g| g % points).collect();
        let n = u64::from(points);
        let mut coords = Vec::with_capacity(points as usize * generator.len());
        for j in 0..n {
            for &g in &generator {
                coords.push(((j * u64::from(g)) % n) as f64 / n as f64);
            }
        }
        Ok(Rank1Lattice {
            points,
            generator,
            coords,
        })
    }

    /// The embedded CBC lattice for `points` in [`TABLE_SIZES`] and `dims` in
    /// `1..=TABLE_MAX_DIMS` (weights: [`KorobovSpace::table`]).
    ///
    /// # Errors
    ///
    /// [`LqmcError::NotInTable`] for any other `(points, dims)`.
    pub fn from_table(points: u32, dims: usize) -> Result<Self, LqmcError> {
        let row = CBC_TABLE
            .iter()
            .find(|(n, _)| *n == points)
            .filter(|_| (1..=TABLE_MAX_DIMS).contains(&dims))
            .ok_or(LqmcError::NotInTable { points, dims })?;
        Rank1Lattice::new(points, row.1[..dims].to_vec())
    }

    /// The CBC lattice for any `points >= 2` in the `space.dims()` dimensions of `space`
    /// (see [`KorobovSpace::cbc`]).
    ///
    /// # Errors
    ///
    /// [`LqmcError::InvalidParameter`] if `points < 2`.
    pub fn cbc(points: u32, space: &KorobovSpace) -> Result<Self, LqmcError> {
        Rank1Lattice::new(points, space.cbc(points)?)
    }

    /// The 2-D Fibonacci lattice `N = F_m`, `g = (1, F_{m-1})` (`F_1 = F_2 = 1`), for
    /// `3 <= m <= 47`.
    ///
    /// # Errors
    ///
    /// [`LqmcError::InvalidParameter`] if `m` is outside `3..=47`.
    pub fn fibonacci(m: u32) -> Result<Self, LqmcError> {
        if !(3..=47).contains(&m) {
            return Err(LqmcError::invalid("m", m, "3..=47"));
        }
        let (mut a, mut b) = (1u32, 1u32);
        for _ in 2..m {
            (a, b) = (b, a + b);
        }
        Rank1Lattice::new(b, vec![1, a])
    }

    /// Number of points `N`.
    #[must_use]
    #[allow(clippy::len_without_is_empty)] // never empty
    pub fn len(&self) -> u32 {
        self.points
    }

    /// Number of dimensions `s`.
    #[must_use]
    pub fn dims(&self) -> usize {
        self.generator.len()
    }

    /// The generator vector `g` (components in `0..N`).
    #[must_use]
    pub fn generator(&self) -> &[u32] {
        &self.generator
    }

    /// Lattice point `r_j = {j g / N}` (`j < N`).
    #[must_use]
    pub fn point(&self, j: u32) -> &[f64] {
        let s = self.dims();
        let j = j as usize;
        &self.coords[j * s..(j + 1) * s]
    }

    /// The lattice point closest to `t` on the unit torus (paper Alg. 1, line 3): brute force
    /// over the `N` points with the squared distance accumulated per dimension and abandoned
    /// as soon as it exceeds the best so far (section 3.4). Ties go to the smallest index.
    ///
    /// `t` must have [`Self::dims`] components; it need not lie in `[0, 1)`.
    #[must_use]
    pub fn closest_point(&self, t: &[f64]) -> ClosestPoint {
        assert_eq!(t.len(), self.dims(), "point and lattice dimensions differ");
        let s = self.dims();
        let mut best = ClosestPoint {
            index: 0,
            distance_squared: f64::INFINITY,
        };
        'points: for (j, r) in self.coords.chunks_exact(s).enumerate() {
            let mut d2 = 0.0;
            for (&x, &y) in r.iter().zip(t) {
                let d = torus_difference(x, y);
                d2 += d * d;
                if d2 >= best.distance_squared {
                    continue 'points;
                }
            }
            best = ClosestPoint {
                index: j as u32,
                distance_squared: d2,
            };
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constructors_validate() {
        assert!(Rank1Lattice::new(0, vec![1]).is_err());
        assert!(Rank1Lattice::new(5, vec![]).is_err());
        assert_eq!(Rank1Lattice::new(5, vec![7]).unwrap().generator(), &[2]);
        assert!(matches!(
            Rank1Lattice::from_table(24, 3),
            Err(LqmcError::NotInTable { .. })
        ));
        assert!(Rank1Lattice::from_table(23, 0).is_err());
        assert!(Rank1Lattice::from_table(23, 22).is_err());
        for n in TABLE_SIZES {
            for s in 1..=TABLE_MAX_DIMS {
                let l = Rank1Lattice::from_table(n, s).unwrap();
                assert_eq!((l.len(), l.dims()), (n, s));
                assert_eq!(l.generator()[0], 1);
            }
        }
        assert!(Rank1Lattice::fibonacci(2).is_err());
        let f = Rank1Lattice::fibonacci(11).unwrap();
        assert_eq!((f.len(), f.generator()), (89, &[1, 55][..]));
    }

    #[test]
    fn points_are_the_lattice_rule() {
        let l = Rank1Lattice::new(23, vec![1, 10, 4]).unwrap();
        assert_eq!(l.point(0), &[0.0, 0.0, 0.0]);
        assert_eq!(l.point(3), &[3.0 / 23.0, 7.0 / 23.0, 12.0 / 23.0]);
    }

    /// Early out must not change the answer: compare with a plain exhaustive search.
    #[test]
    fn closest_point_equals_exhaustive_search() {
        let l = Rank1Lattice::from_table(97, 6).unwrap();
        let mut state = 99u64;
        for _ in 0..500 {
            let t: Vec<f64> = (0..6)
                .map(|_| {
                    state = crate::hash::mix64(state + 1);
                    crate::hash::unit_f64(state) * 3.0 - 1.0
                })
                .collect();
            let c = l.closest_point(&t);
            let mut best = (f64::INFINITY, 0);
            for j in 0..l.len() {
                let d2: f64 = l
                    .point(j)
                    .iter()
                    .zip(&t)
                    .map(|(&x, &y)| torus_difference(x, y).powi(2))
                    .sum();
                if d2 < best.0 {
                    best = (d2, j);
                }
            }
            assert_eq!(c.index, best.1);
            assert_eq!(c.distance_squared, best.0);
        }
    }
}
