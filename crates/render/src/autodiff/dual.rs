//! Forward-mode dual numbers with `N` derivative lanes of `f64` or `f32`.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub};

use super::{Lane, Real};

/// A value and its partial derivatives with respect to `N` independent variables (forward-mode
/// automatic differentiation: every operation applies the chain rule lane by lane).
///
/// The value is always `f64`; the derivative lanes are `L`: `f64` (the default) or `f32`, which
/// fits twice as many lanes in a SIMD register and halves the lane arithmetic, at a relative
/// rounding of about `6e-8` per operation in the derivatives only (see [`Lane`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const N: usize, L: Lane = f64> {
    /// The value.
    pub v: f64,
    /// The partial derivatives.
    pub d: [L; N],
}

impl<const N: usize, L: Lane> Dual<N, L> {
    /// The independent variable of lane `lane` with value `v` (derivative 1 in its lane; a
    /// lane `>= N` gives a constant).
    #[must_use]
    #[inline]
    pub fn variable(v: f64, lane: usize) -> Self {
        let mut d = [L::ZERO; N];
        if let Some(x) = d.get_mut(lane) {
            *x = L::ONE;
        }
        Self { v, d }
    }

    /// `f(v)` with derivative `df = f'(v)`: the chain rule.
    #[inline]
    fn chain(self, f: f64, df: f64) -> Self {
        let df = L::from_f64(df);
        let mut d = self.d;
        for x in &mut d {
            *x = *x * df;
        }
        Self { v: f, d }
    }
}

impl<const N: usize, L: Lane> Add for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for (a, b) in self.d.iter_mut().zip(o.d) {
            *a = *a + b;
        }
        self
    }
}

impl<const N: usize, L: Lane> Sub for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for (a, b) in self.d.iter_mut().zip(o.d) {
            *a = *a - b;
        }
        self
    }
}

impl<const N: usize, L: Lane> Mul for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let (ov, sv) = (L::from_f64(o.v), L::from_f64(self.v));
        let mut d = [L::ZERO; N];
        for ((x, a), b) in d.iter_mut().zip(self.d).zip(o.d) {
            *x = a * ov + b * sv;
        }
        Self { v: self.v * o.v, d }
    }
}

impl<const N: usize, L: Lane> Div for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.v;
        let q = self.v * inv;
        let (lq, linv) = (L::from_f64(q), L::from_f64(inv));
        let mut d = [L::ZERO; N];
        for ((x, a), b) in d.iter_mut().zip(self.d).zip(o.d) {
            *x = (a - lq * b) * linv;
        }
        Self { v: q, d }
    }
}

impl<const N: usize, L: Lane> Neg for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.chain(-self.v, -1.0)
    }
}

impl<const N: usize, L: Lane> Add<f64> for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn add(mut self, c: f64) -> Self {
        self.v += c;
        self
    }
}

impl<const N: usize, L: Lane> Sub<f64> for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn sub(mut self, c: f64) -> Self {
        self.v -= c;
        self
    }
}

impl<const N: usize, L: Lane> Mul<f64> for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn mul(self, c: f64) -> Self {
        self.chain(self.v * c, c)
    }
}

impl<const N: usize, L: Lane> Div<f64> for Dual<N, L> {
    type Output = Self;
    #[inline]
    fn div(self, c: f64) -> Self {
        let inv = 1.0 / c;
        self.chain(self.v * inv, inv)
    }
}

impl<const N: usize, L: Lane> AddAssign for Dual<N, L> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<const N: usize, L: Lane> MulAssign for Dual<N, L> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}

impl<const N: usize, L: Lane> Real for Dual<N, L> {
    #[inline]
    fn cst(v: f64) -> Self {
        Self { v, d: [L::ZERO; N] }
    }
    #[inline]
    fn value(self) -> f64 {
        self.v
    }
    #[inline]
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, if s > 0.0 { 0.5 / s } else { 0.0 })
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.v.sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }
    #[inline]
    fn ln(self) -> Self {
        self.chain(self.v.ln(), 1.0 / self.v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A function exercising every operation, written once over `Real`.
    fn f<T: Real>(x: T, y: T) -> T {
        let a = (x * y + x / y - y * 2.0 + 1.0) / 3.0;
        let (s, c) = (x - y).sin_cos();
        let b = (x * x + y * y).sqrt().ln() * s - c * (-x).abs();
        a * b + (x / 4.0 - 0.5).max(y.min(x)).recip()
    }

    #[test]
    fn derivatives_match_central_differences() {
        for (x, y) in [(0.3, 1.7), (-1.2, 0.4), (2.5, -0.8), (0.9, 1.1)] {
            let g = f(Dual::<2>::variable(x, 0), Dual::<2>::variable(y, 1));
            assert!((g.v - f(x, y)).abs() < 1e-14);
            let h = 1e-6;
            let dx = (f(x + h, y) - f(x - h, y)) / (2.0 * h);
            let dy = (f(x, y + h) - f(x, y - h)) / (2.0 * h);
            assert!((g.d[0] - dx).abs() < 1e-6 * (1.0 + dx.abs()), "{g:?} {dx}");
            assert!((g.d[1] - dy).abs() < 1e-6 * (1.0 + dy.abs()), "{g:?} {dy}");
        }
    }

    #[test]
    fn f32_lanes_match_f64_lanes_to_f32_rounding() {
        // Same function, same values: only the lanes' rounding differs (2^-24 relative per
        // operation, a few dozen operations here), so 1e-5 relative is a wide bound; a lane
        // computed with the wrong operand (the control) is off by O(1).
        for (x, y) in [(0.3, 1.7), (-1.2, 0.4), (2.5, -0.8), (0.9, 1.1)] {
            let g64 = f(Dual::<2>::variable(x, 0), Dual::<2>::variable(y, 1));
            let g32 = f(
                Dual::<2, f32>::variable(x, 0),
                Dual::<2, f32>::variable(y, 1),
            );
            assert_eq!(g32.v, g64.v, "the value does not depend on the lanes");
            for k in 0..2 {
                let (a, b) = (f64::from(g32.d[k]), g64.d[k]);
                assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "{a} {b}");
                let wrong = f64::from(g32.d[1 - k]);
                assert!((wrong - b).abs() > 1e-2, "control: lane {k} vs {}", 1 - k);
            }
        }
    }

    #[test]
    fn wrong_derivative_is_detected() {
        // Negative control: a dual number whose sine had the wrong derivative would fail the
        // comparison above.
        let x = Dual::<1>::variable(0.7, 0);
        let wrong = x.chain(0.7f64.sin(), -0.7f64.cos());
        let h = 1e-6;
        let fd = ((0.7f64 + h).sin() - (0.7f64 - h).sin()) / (2.0 * h);
        assert!((wrong.d[0] - fd).abs() > 1.0);
        assert!((x.sin().d[0] - fd).abs() < 1e-9);
    }

    #[test]
    fn lanes_beyond_n_are_constants() {
        let x = Dual::<2>::variable(1.0, 5);
        assert_eq!(x.d, [0.0, 0.0]);
    }
}
