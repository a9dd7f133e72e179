//! Forward-mode dual numbers with `N` derivative lanes.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub};

use super::Real;

/// A value and its partial derivatives with respect to `N` independent variables (forward-mode
/// automatic differentiation: every operation applies the chain rule lane by lane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const N: usize> {
    /// The value.
    pub v: f64,
    /// The partial derivatives.
    pub d: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// The independent variable of lane `lane` with value `v` (derivative 1 in its lane; a
    /// lane `>= N` gives a constant).
    #[must_use]
    #[inline]
    pub fn variable(v: f64, lane: usize) -> Self {
        let mut d = [0.0; N];
        if let Some(x) = d.get_mut(lane) {
            *x = 1.0;
        }
        Self { v, d }
    }

    /// `f(v)` with derivative `df = f'(v)`: the chain rule.
    #[inline]
    fn chain(self, f: f64, df: f64) -> Self {
        let mut d = self.d;
        for x in &mut d {
            *x *= df;
        }
        Self { v: f, d }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for (a, b) in self.d.iter_mut().zip(o.d) {
            *a += b;
        }
        self
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for (a, b) in self.d.iter_mut().zip(o.d) {
            *a -= b;
        }
        self
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; N];
        for ((x, a), b) in d.iter_mut().zip(self.d).zip(o.d) {
            *x = a * o.v + b * self.v;
        }
        Self { v: self.v * o.v, d }
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.v;
        let q = self.v * inv;
        let mut d = [0.0; N];
        for ((x, a), b) in d.iter_mut().zip(self.d).zip(o.d) {
            *x = (a - q * b) * inv;
        }
        Self { v: q, d }
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.chain(-self.v, -1.0)
    }
}

impl<const N: usize> Add<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, c: f64) -> Self {
        self.v += c;
        self
    }
}

impl<const N: usize> Sub<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, c: f64) -> Self {
        self.v -= c;
        self
    }
}

impl<const N: usize> Mul<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, c: f64) -> Self {
        self.chain(self.v * c, c)
    }
}

impl<const N: usize> Div<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, c: f64) -> Self {
        let inv = 1.0 / c;
        self.chain(self.v * inv, inv)
    }
}

impl<const N: usize> AddAssign for Dual<N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<const N: usize> MulAssign for Dual<N> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}

impl<const N: usize> Real for Dual<N> {
    #[inline]
    fn cst(v: f64) -> Self {
        Self { v, d: [0.0; N] }
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
