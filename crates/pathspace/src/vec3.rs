//! A tiny f64 3-vector for positions, normals and directions, and an RGB triple.

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

/// A 3-vector of `f64`: positions, normals and unit directions.
///
/// Converts from and to `[f64; 3]`, so a renderer with its own vector type (e.g. glam's
/// `Vec3A` in f32) converts at the trait boundary with `Vec3::from([x as f64, ..])`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3 {
    /// x coordinate.
    pub x: f64,
    /// y coordinate.
    pub y: f64,
    /// z coordinate.
    pub z: f64,
}

impl Vec3 {
    /// The zero vector.
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0);

    /// A vector from its coordinates.
    #[must_use]
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }

    /// Dot product.
    #[must_use]
    pub fn dot(self, o: Self) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product.
    #[must_use]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Squared Euclidean length.
    #[must_use]
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }

    /// Euclidean length.
    #[must_use]
    pub fn length(self) -> f64 {
        self.length_squared().sqrt()
    }

    /// The unit vector in the same direction, or `None` for a zero or non-finite vector.
    #[must_use]
    pub fn try_normalize(self) -> Option<Self> {
        let l = self.length();
        if l > 0.0 && l.is_finite() {
            Some(self / l)
        } else {
            None
        }
    }

    /// The unit vector in the same direction (NaN for the zero vector).
    #[must_use]
    pub fn normalize(self) -> Self {
        self / self.length()
    }

    /// True if every coordinate is finite.
    #[must_use]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// An orthonormal basis `(t, b)` completing the unit vector `n` to a right-handed frame
    /// `(t, b, n)` (Duff et al. 2017, "Building an orthonormal basis, revisited").
    #[must_use]
    pub fn orthonormal_basis(self) -> (Self, Self) {
        let n = self;
        let sign = 1.0f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        (
            Self::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            Self::new(b, sign + n.y * n.y * a, -n.y),
        )
    }

    /// Mirror reflection of the direction `w` (pointing away from the surface) about the
    /// unit normal `n`: `2 (w.n) n - w`.
    #[must_use]
    pub fn reflect(w: Self, n: Self) -> Self {
        n * (2.0 * w.dot(n)) - w
    }
}

impl From<[f64; 3]> for Vec3 {
    fn from(a: [f64; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }
}

impl From<Vec3> for [f64; 3] {
    fn from(v: Vec3) -> Self {
        [v.x, v.y, v.z]
    }
}

impl Add for Vec3 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl AddAssign for Vec3 {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl Sub for Vec3 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Neg for Vec3 {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

impl Mul<f64> for Vec3 {
    type Output = Self;
    fn mul(self, s: f64) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Div<f64> for Vec3 {
    type Output = Self;
    fn div(self, s: f64) -> Self {
        Self::new(self.x / s, self.y / s, self.z / s)
    }
}

/// Linear RGB radiance, importance or reflectance (f64; the renderer's f32 RGB converts at
/// the trait boundary).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rgb(pub [f64; 3]);

impl Rgb {
    /// Black.
    pub const BLACK: Self = Self([0.0; 3]);

    /// The same value in all three channels.
    #[must_use]
    pub const fn gray(v: f64) -> Self {
        Self([v; 3])
    }

    /// Rec. 709 luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B`.
    #[must_use]
    pub fn luminance(self) -> f64 {
        0.2126 * self.0[0] + 0.7152 * self.0[1] + 0.0722 * self.0[2]
    }

    /// True if every channel is zero.
    #[must_use]
    pub fn is_black(self) -> bool {
        self.0 == [0.0; 3]
    }

    /// The largest channel.
    #[must_use]
    pub fn max_channel(self) -> f64 {
        self.0[0].max(self.0[1]).max(self.0[2])
    }
}

impl Mul for Rgb {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self([self.0[0] * o.0[0], self.0[1] * o.0[1], self.0[2] * o.0[2]])
    }
}

impl Mul<f64> for Rgb {
    type Output = Self;
    fn mul(self, s: f64) -> Self {
        Self([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
}

impl Add for Rgb {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal() {
        for n in [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.3, -0.4, 0.2).normalize(),
        ] {
            let (t, b) = n.orthonormal_basis();
            assert!((t.length() - 1.0).abs() < 1e-12);
            assert!((b.length() - 1.0).abs() < 1e-12);
            assert!(t.dot(b).abs() < 1e-12 && t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12);
        }
    }
}
