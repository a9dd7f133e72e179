//! Tiling of the explored primary-sample-space dimensions, `T(u) = (u - o) / k` (paper eq. 12),
//! with a jittered global offset re-drawn every progression (section 3.4), and its inverse.

use crate::error::LqmcError;
use crate::halton::ONE_MINUS_EPSILON;

/// A tiling of `[0, 1)^s` into `k_1 x .. x k_s` tiles, shifted by a global jitter offset.
///
/// In dimension `d`, tile `m` (in `0..k_d`) is the interval `[(m + c_d) / k_d, (m + 1 + c_d) / k_d)`
/// taken modulo one, where `c_d` in `[0, 1)` is the jitter in tile units (the paper's offset
/// `o` in `[0, 1/k)`, section 3.4 "Jittered tiling"). With `c_d > 0` the last tile wraps
/// around 1. [`Tiling::to_tile`] is `T` of eq. 12: the tile containing `u` and the position in
/// it, `t = (u - o) k` in `[0, 1)^s`; [`Tiling::invert`] is `T^{-1}`, and always returns a
/// point that `to_tile` puts back in the same tile (rounding is corrected there), so every
/// member of a lattice set lies in the seed's tile.
///
/// The jitter must be the same for all seeds whose sets may overlap; the paper re-draws it
/// after every progression (one sample per pixel): call [`Tiling::set_jitter`] with fresh
/// uniform numbers between progressions, never within one.
///
/// # Example
///
/// ```
/// use lqmc::Tiling;
///
/// let mut tiling = Tiling::new(vec![4, 1]).unwrap();
/// tiling.set_jitter(&[0.5, 0.0]).unwrap(); // tiles [0.125, 0.375), [0.375, 0.625), ...
/// let (mut tile, mut t) = ([0u32; 2], [0.0; 2]);
/// tiling.to_tile(&[0.4, 0.3], &mut tile, &mut t);
/// assert_eq!(tile, [1, 0]);
/// assert!((t[0] - 0.1).abs() < 1e-12 && (t[1] - 0.3).abs() < 1e-12);
///
/// // The wrapped tile: [0.875, 1) + [0, 0.125).
/// tiling.to_tile(&[0.05, 0.3], &mut tile, &mut t);
/// assert_eq!(tile[0], 3);
/// assert!((t[0] - 0.7).abs() < 1e-12);
///
/// let mut u = [0.0; 2];
/// tiling.invert(&tile, &t, &mut u);
/// assert!((u[0] - 0.05).abs() < 1e-12 && (u[1] - 0.3).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Tiling {
    tiles: Vec<u32>,
    jitter: Vec<f64>,
}

impl Tiling {
    /// `tiles[d]` tiles in dimension `d` (each `>= 1`), without jitter.
    ///
    /// # Errors
    ///
    /// [`LqmcError::InvalidParameter`] if `tiles` is empty or has a zero.
    pub fn new(tiles: Vec<u32>) -> Result<Self, LqmcError> {
        if tiles.is_empty() {
            return Err(LqmcError::invalid("tiles.len()", 0, ">= 1"));
        }
        if tiles.contains(&0) {
            return Err(LqmcError::invalid("tiles[d]", 0, ">= 1"));
        }
        let jitter = vec![0.0; tiles.len()];
        Ok(Tiling { tiles, jitter })
    }

    /// Sets the global jitter offset from uniform numbers `c_d` in `[0, 1)` (one per dimension,
    /// in tile units: the offset is `c_d / k_d`). Section 3.4: re-draw after every progression.
    ///
    /// # Errors
    ///
    /// [`LqmcError::DimensionMismatch`] or [`LqmcError::InvalidParameter`] (a `c_d` outside
    /// `[0, 1)`).
    pub fn set_jitter(&mut self, uniforms: &[f64]) -> Result<(), LqmcError> {
        if uniforms.len() != self.dims() {
            return Err(LqmcError::DimensionMismatch {
                what: "jitter",
                found: uniforms.len(),
                expected: self.dims(),
            });
        }
        if let Some(&c) = uniforms.iter().find(|c| !(0.0..1.0).contains(*c)) {
            return Err(LqmcError::invalid("jitter", c, "[0, 1)"));
        }
        self.jitter.copy_from_slice(uniforms);
        Ok(())
    }

    /// Builder form of [`Tiling::set_jitter`].
    ///
    /// # Errors
    ///
    /// As [`Tiling::set_jitter`].
    pub fn with_jitter(mut self, uniforms: &[f64]) -> Result<Self, LqmcError> {
        self.set_jitter(uniforms)?;
        Ok(self)
    }

    /// Number of dimensions `s`.
    #[must_use]
    pub fn dims(&self) -> usize {
        self.tiles.len()
    }

    /// Tiles per dimension, `k`.
    #[must_use]
    pub fn tiles(&self) -> &[u32] {
        &self.tiles
    }

    /// The jitter in tile units, `c` (the offset is `c / k`).
    #[must_use]
    pub fn jitter(&self) -> &[f64] {
        &self.jitter
    }

    /// `T(u)` (eq. 12): writes the tile containing `u` (`u` in `[0, 1)^s`) and the position
    /// `t = (u - o) k` in `[0, 1)^s` inside it.
    pub fn to_tile(&self, u: &[f64], tile: &mut [u32], t: &mut [f64]) {
        debug_assert!(
            u.len() == self.dims() && tile.len() == self.dims() && t.len() == self.dims()
        );
        for d in 0..self.dims() {
            let (m, x) = self.to_tile_1d(d, u[d]);
            tile[d] = m;
            t[d] = x;
        }
    }

    /// `T^{-1}`: the point `u` in `[0, 1)^s` at position `t` (in `[0, 1)^s`) of `tile`.
    ///
    /// Guarantees `to_tile(invert(tile, t)).tile == tile` (a result that rounding put in a
    /// neighbouring tile is moved back by a few ulps).
    pub fn invert(&self, tile: &[u32], t: &[f64], u: &mut [f64]) {
        debug_assert!(
            u.len() == self.dims() && tile.len() == self.dims() && t.len() == self.dims()
        );
        for d in 0..self.dims() {
            u[d] = self.invert_1d(d, tile[d], t[d]);
        }
    }

    fn to_tile_1d(&self, d: usize, u: f64) -> (u32, f64) {
        let k = self.tiles[d];
        if k == 1 && self.jitter[d] == 0.0 {
            return (0, u);
        }
        let x = u * f64::from(k) - self.jitter[d];
        let f = x.floor();
        let t = (x - f).min(ONE_MINUS_EPSILON);
        let m = (f as i64).rem_euclid(i64::from(k)) as u32;
        (m, t)
    }

    fn invert_1d(&self, d: usize, m: u32, t: f64) -> f64 {
        let k = self.tiles[d];
        if k == 1 && self.jitter[d] == 0.0 {
            return t;
        }
        let mut u = (f64::from(m) + self.jitter[d] + t) / f64::from(k);
        if u >= 1.0 {
            u -= 1.0;
        }
        u = u.clamp(0.0, ONE_MINUS_EPSILON);
        // Rounding (cancellation in the wrapped tile) may put u just across a tile boundary:
        // step back with doubling steps, starting at one ulp.
        let mut step = u.max(f64::MIN_POSITIVE) * f64::EPSILON;
        for _ in 0..128 {
            let (found, _) = self.to_tile_1d(d, u);
            if found == m {
                return u;
            }
            // Rounding only matters at the ends of the tile: near its start u fell into the
            // previous tile (step up), near its end into the next one (step down).
            u = wrap_ulp(if t < 0.5 { u + step } else { u - step });
            step *= 2.0;
        }
        debug_assert!(false, "invert did not converge");
        u
    }
}

fn wrap_ulp(u: f64) -> f64 {
    if u >= 1.0 {
        0.0
    } else if u < 0.0 {
        ONE_MINUS_EPSILON
    } else {
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hash::{mix64, unit_f64};

    #[test]
    fn constructor_validates() {
        assert!(Tiling::new(vec![]).is_err());
        assert!(Tiling::new(vec![2, 0]).is_err());
        let t = Tiling::new(vec![2, 3]).unwrap();
        assert!(t.clone().with_jitter(&[0.5]).is_err());
        assert!(t.clone().with_jitter(&[0.5, 1.0]).is_err());
        assert!(t.clone().with_jitter(&[0.5, -0.1]).is_err());
        assert!(t.with_jitter(&[0.5, 0.0]).is_ok());
    }

    /// Round trips both ways, on random tilings, including points right at tile boundaries.
    #[test]
    fn round_trips() {
        let mut state = 1u64;
        let mut next = || {
            state = mix64(state + 1);
            unit_f64(state)
        };
        for _ in 0..2000 {
            let k = 1 + (next() * 200.0) as u32;
            let c = if next() < 0.2 { 0.0 } else { next() };
            let tiling = Tiling::new(vec![k]).unwrap().with_jitter(&[c]).unwrap();
            let u = match (next() * 3.0) as u32 {
                0 => next(),
                // On a boundary, or an ulp off one.
                1 => {
                    crate::torus::wrap_unit((f64::from((next() * k as f64) as u32) + c) / k as f64)
                }
                _ => {
                    crate::torus::wrap_unit((f64::from((next() * k as f64) as u32) + c) / k as f64)
                        .next_down()
                        .max(0.0)
                }
            };
            let (mut m, mut t, mut back) = ([0], [0.0], [0.0]);
            tiling.to_tile(&[u], &mut m, &mut t);
            assert!(m[0] < k && (0.0..1.0).contains(&t[0]));
            tiling.invert(&m, &t, &mut back);
            assert!(
                (back[0] - u).abs() < 1e-12,
                "k {k} c {c} u {u} back {}",
                back[0]
            );
            // T^{-1} then T: same tile always, same position up to rounding.
            let t2 = if next() < 0.3 {
                ONE_MINUS_EPSILON
            } else {
                next()
            };
            tiling.invert(&m, &[t2], &mut back);
            let (mut m2, mut t3) = ([0], [0.0]);
            tiling.to_tile(&back, &mut m2, &mut t3);
            assert_eq!(m2, m, "k {k} c {c} t2 {t2} back {back:?}");
            assert!(crate::torus::torus_difference(t3[0], t2).abs() < 1e-9);
        }
    }
}
