//! The scalar trait of code written once for `f64` and dual numbers.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub};

/// A real scalar: `f64` or a forward-mode dual number. Comparisons and branches use
/// [`Real::value`]; the arithmetic carries derivatives.
pub trait Real:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + AddAssign
    + MulAssign
{
    /// A constant (zero derivative).
    fn cst(v: f64) -> Self;
    /// The value.
    fn value(self) -> f64;
    /// Square root (derivative 0 at 0, where the true one is infinite).
    fn sqrt(self) -> Self;
    /// Sine and cosine.
    fn sin_cos(self) -> (Self, Self);
    /// Natural logarithm.
    fn ln(self) -> Self;

    /// Sine.
    #[inline]
    fn sin(self) -> Self {
        self.sin_cos().0
    }
    /// Cosine.
    #[inline]
    fn cos(self) -> Self {
        self.sin_cos().1
    }
    /// Absolute value (by the sign of the value).
    #[inline]
    fn abs(self) -> Self {
        if self.value() < 0.0 {
            -self
        } else {
            self
        }
    }
    /// `1 / self`.
    #[inline]
    fn recip(self) -> Self {
        Self::cst(1.0) / self
    }
    /// The larger of the two (by value; `self` on ties).
    #[inline]
    fn max(self, other: Self) -> Self {
        if other.value() > self.value() {
            other
        } else {
            self
        }
    }
    /// The smaller of the two (by value; `self` on ties).
    #[inline]
    fn min(self, other: Self) -> Self {
        if other.value() < self.value() {
            other
        } else {
            self
        }
    }
    /// `max(self, c)` for a constant `c`.
    #[inline]
    fn max_c(self, c: f64) -> Self {
        if self.value() < c {
            Self::cst(c)
        } else {
            self
        }
    }
    /// `min(self, c)` for a constant `c`.
    #[inline]
    fn min_c(self, c: f64) -> Self {
        if self.value() > c {
            Self::cst(c)
        } else {
            self
        }
    }
    /// `self` clamped to `[lo, hi]`.
    #[inline]
    fn clamp_c(self, lo: f64, hi: f64) -> Self {
        self.max_c(lo).min_c(hi)
    }
    /// True if the value is finite.
    #[inline]
    fn is_finite(self) -> bool {
        self.value().is_finite()
    }
}

impl Real for f64 {
    #[inline]
    fn cst(v: f64) -> Self {
        v
    }
    #[inline]
    fn value(self) -> f64 {
        self
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        f64::sin_cos(self)
    }
    #[inline]
    fn ln(self) -> Self {
        f64::ln(self)
    }
}
