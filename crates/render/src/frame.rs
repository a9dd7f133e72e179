//! Orthonormal shading frames: the local coordinate system (z = shading normal) that BSDFs use.
//!
//! BSDFs in [`crate::material`] work in a local frame where the shading normal is `+z`, so that
//! `cos theta = w.z`. A [`Frame`] converts directions between that frame and world space.

use glam::Vec3A;

/// A right-handed orthonormal basis `(s, t, n)` with `s x t = n`.
///
/// `to_local` maps a world direction to `(v.s, v.t, v.n)`; `to_world` is its inverse (the
/// transpose, since the basis is orthonormal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3A,
    /// Second tangent (bitangent), `n x s`.
    pub t: Vec3A,
    /// Normal, the local `+z` axis.
    pub n: Vec3A,
}

impl Frame {
    /// A frame whose `n` is the unit vector `n`, with tangents chosen continuously except across
    /// `n.z = 0`.
    ///
    /// Implements the branchless construction of Duff et al. 2017, "Building an Orthonormal
    /// Basis, Revisited" (JCGT 6(1)), Listing 3. `n` must be unit length (not checked in release
    /// builds); a zero or non-finite `n` gives a non-finite frame.
    #[must_use]
    #[inline]
    pub fn from_normal(n: Vec3A) -> Self {
        debug_assert!(
            !n.is_finite() || (n.length_squared() - 1.0).abs() < 1e-3,
            "Frame::from_normal expects a unit normal, got {n:?}"
        );
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// A frame with normal `n` and first tangent as close as possible to `tangent`
    /// (Gram-Schmidt); falls back to [`Frame::from_normal`] when `tangent` is (nearly) parallel
    /// to `n` or not finite. `n` must be unit length.
    #[must_use]
    pub fn from_normal_tangent(n: Vec3A, tangent: Vec3A) -> Self {
        match (tangent - n * n.dot(tangent)).try_normalize() {
            Some(s) => Self {
                s,
                t: n.cross(s),
                n,
            },
            None => Self::from_normal(n),
        }
    }

    /// Expresses the world-space vector `v` in this frame: `(v.s, v.t, v.n)`.
    #[must_use]
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Maps the local vector `v` back to world space: `v.x s + v.y t + v.z n`.
    #[must_use]
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// True if the shading normal `ns` and the geometric normal `ng` agree on whether light going
/// from `wi` to `wo` is reflected (both on one side) or transmitted: the check pbrt-v3's
/// `BSDF::f` makes with the geometric normal. Where they disagree a BSDF evaluated in the
/// shading frame would let light through an opaque surface (or reflect it off a refractive
/// one): interpolated normals on a coarse sphere leak the environment into a closed room
/// without it. Integrators treat such directions as carrying no light.
#[inline]
#[must_use]
pub fn shading_consistent(
    wo: glam::Vec3A,
    wi: glam::Vec3A,
    ng: glam::Vec3A,
    ns: glam::Vec3A,
) -> bool {
    let geometric = wo.dot(ng) * wi.dot(ng);
    let shading = wo.dot(ns) * wi.dot(ns);
    geometric != 0.0 && (geometric > 0.0) == (shading > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::warp::sample_uniform_sphere;
    use glam::Vec2;

    fn normals() -> Vec<Vec3A> {
        let mut v = vec![
            Vec3A::Z,
            -Vec3A::Z,
            Vec3A::X,
            -Vec3A::Y,
            Vec3A::new(1e-8, 0.0, -1.0).normalize(),
            Vec3A::new(0.0, 1e-7, 1.0).normalize(),
        ];
        for i in 0..64 {
            let u = Vec2::new((i as f32 + 0.5) / 64.0, ((i * 37) % 64) as f32 / 64.0);
            v.push(sample_uniform_sphere(u));
        }
        v
    }

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        for n in normals() {
            let f = Frame::from_normal(n);
            for (a, name) in [(f.s, "s"), (f.t, "t"), (f.n, "n")] {
                assert!(
                    (a.length() - 1.0).abs() < 1e-5,
                    "|{name}| != 1 for n = {n:?}"
                );
            }
            assert!(f.s.dot(f.t).abs() < 1e-5);
            assert!(f.s.dot(f.n).abs() < 1e-5);
            assert!(f.t.dot(f.n).abs() < 1e-5);
            assert!(
                (f.s.cross(f.t) - f.n).length() < 1e-5,
                "left-handed for {n:?}"
            );
        }
    }

    #[test]
    fn local_world_round_trip() {
        let v = Vec3A::new(0.3, -0.7, 0.2);
        for n in normals() {
            let f = Frame::from_normal(n);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
            assert!((f.to_local(n) - Vec3A::Z).length() < 1e-5);
        }
    }

    #[test]
    fn tangent_frame_keeps_tangent_direction() {
        let n = Vec3A::new(0.0, 0.6, 0.8);
        let f = Frame::from_normal_tangent(n, Vec3A::new(1.0, 0.1, 0.0));
        assert!(f.s.dot(n).abs() < 1e-6);
        assert!(f.s.x > 0.99);
        assert!((f.s.cross(f.t) - f.n).length() < 1e-5);
        // Degenerate tangent falls back to the normal-only construction.
        assert_eq!(Frame::from_normal_tangent(n, n), Frame::from_normal(n));
    }
}
