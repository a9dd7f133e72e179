//! The scalar type of a dual number's derivative lanes: `f64` or `f32`.

use std::fmt::Debug;
use std::ops::{Add, Mul, Sub};

/// The scalar of [`super::Dual`]'s derivative lanes. The value of a dual number stays `f64`
/// (branches, scene queries and the density read it); only the derivatives use `Self`.
///
/// - `f64`: derivatives exact to `f64` rounding (the reference, and the default).
/// - `f32`: twice as many lanes per SIMD register, so about half the lane arithmetic and half
///   the bytes moved per dual number. Each operation rounds the derivatives to a relative
///   `2^-24` (about `6e-8`); the factors taken from the value (`f'(v)`, the other operand's
///   value) are rounded to `f32` once per operation. A result is still a deterministic
///   function of the inputs, which is all an exact MCMC kernel needs from its gradient.
pub trait Lane:
    Copy + Debug + PartialEq + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// `v` rounded to the lane type (identity for `f64`).
    fn from_f64(v: f64) -> Self;
    /// The lane as `f64` (exact).
    fn to_f64(self) -> f64;
}

impl Lane for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

impl Lane for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}
