//! A 3-vector over [`Real`] (positions, directions, RGB).

use std::ops::{Add, Mul, Neg, Sub};

use glam::{Vec3, Vec3A};

use super::Real;

/// A 3-vector of [`Real`] scalars.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<T> {
    /// x
    pub x: T,
    /// y
    pub y: T,
    /// z
    pub z: T,
}

impl<T: Real> V3<T> {
    /// From components.
    #[inline]
    pub fn new(x: T, y: T, z: T) -> Self {
        Self { x, y, z }
    }
    /// A constant vector from `f32` components.
    #[inline]
    pub fn from_a(v: Vec3A) -> Self {
        Self::new(
            T::cst(f64::from(v.x)),
            T::cst(f64::from(v.y)),
            T::cst(f64::from(v.z)),
        )
    }
    /// A constant vector (RGB) from `f32` components.
    #[inline]
    pub fn from_rgb(v: Vec3) -> Self {
        Self::from_a(Vec3A::from(v))
    }
    /// All components `c`.
    #[inline]
    pub fn splat(c: f64) -> Self {
        Self::new(T::cst(c), T::cst(c), T::cst(c))
    }
    /// The zero vector.
    #[inline]
    pub fn zero() -> Self {
        Self::splat(0.0)
    }
    /// The values, rounded to `f32` (for the f32 scene queries).
    #[inline]
    pub fn to_a(self) -> Vec3A {
        Vec3A::new(
            self.x.value() as f32,
            self.y.value() as f32,
            self.z.value() as f32,
        )
    }
    /// Dot product.
    #[inline]
    pub fn dot(self, o: Self) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product.
    #[inline]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// Squared length.
    #[inline]
    pub fn length_squared(self) -> T {
        self.dot(self)
    }
    /// Length.
    #[inline]
    pub fn length(self) -> T {
        self.length_squared().sqrt()
    }
    /// Unit vector, or `None` for a zero or non-finite vector.
    #[inline]
    pub fn try_normalize(self) -> Option<Self> {
        let l2 = self.length_squared();
        let v = l2.value();
        (v > 0.0 && v.is_finite()).then(|| self * l2.sqrt().recip())
    }
    /// Unit vector, or zero.
    #[inline]
    pub fn normalize_or_zero(self) -> Self {
        self.try_normalize().unwrap_or_else(Self::zero)
    }
    /// Component-wise product.
    #[inline]
    pub fn mul_v(self, o: Self) -> Self {
        Self::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
    /// Scaled by a constant.
    #[inline]
    pub fn scale(self, c: f64) -> Self {
        Self::new(self.x * c, self.y * c, self.z * c)
    }
    /// True if every value is zero.
    #[inline]
    pub fn is_zero(self) -> bool {
        self.x.value() == 0.0 && self.y.value() == 0.0 && self.z.value() == 0.0
    }
    /// True if every value is finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
    /// Largest component (by value).
    #[inline]
    pub fn max_element(self) -> T {
        self.x.max(self.y).max(self.z)
    }

    /// The constant vector `c` (zero derivatives).
    #[inline]
    pub fn cst(c: V3<f64>) -> Self {
        Self::new(T::cst(c.x), T::cst(c.y), T::cst(c.z))
    }
    /// Dot product with a constant vector: `self.dot(V3::cst(c))` with every product taken as
    /// `T * f64`, which scales the derivatives instead of applying the product rule to a
    /// constant's zero derivatives (same value; the same derivatives where every value is
    /// finite, up to the sign of a zero).
    #[inline]
    pub fn dot_c(self, c: V3<f64>) -> T {
        self.x * c.x + self.y * c.y + self.z * c.z
    }
    /// Cross product with a constant vector, `self x c` ([`V3::dot_c`]'s mixed products).
    #[inline]
    pub fn cross_c(self, c: V3<f64>) -> Self {
        Self::new(
            self.y * c.z - self.z * c.y,
            self.z * c.x - self.x * c.z,
            self.x * c.y - self.y * c.x,
        )
    }
    /// Component-wise product with a constant vector ([`V3::dot_c`]'s mixed products).
    #[inline]
    pub fn mul_c(self, c: V3<f64>) -> Self {
        Self::new(self.x * c.x, self.y * c.y, self.z * c.z)
    }
    /// Sum with a constant vector (the derivatives pass unchanged).
    #[inline]
    pub fn add_c(self, c: V3<f64>) -> Self {
        Self::new(self.x + c.x, self.y + c.y, self.z + c.z)
    }
    /// Difference with a constant vector, `self - c` (the derivatives pass unchanged).
    #[inline]
    pub fn sub_c(self, c: V3<f64>) -> Self {
        Self::new(self.x - c.x, self.y - c.y, self.z - c.z)
    }
}

impl V3<f64> {
    /// This constant vector times the scalar `s`: `V3::cst(self) * s` with the products taken
    /// as `T * f64` ([`V3::dot_c`]).
    #[inline]
    pub fn times<T: Real>(self, s: T) -> V3<T> {
        V3::new(s * self.x, s * self.y, s * self.z)
    }
}

impl<T: Real> Add for V3<T> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<T: Real> Sub for V3<T> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<T: Real> Neg for V3<T> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

impl<T: Real> Mul<T> for V3<T> {
    type Output = Self;
    #[inline]
    fn mul(self, s: T) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}
