//! Warps from the unit square to disks, hemispheres, spheres, cones and triangles, each with its
//! pdf and (where the map is a bijection) its inverse.
//!
//! Naming follows pbrt-v4 (`src/pbrt/util/sampling.h`): `sample_x(u)` maps uniform numbers
//! `u ∈ [0,1)^2` to a point, `x_pdf(..)` is the density of that point with respect to area
//! (disk, triangle) or solid angle (directions), and `invert_x(p)` returns the `u` that maps to
//! `p`. Inverses make the warps usable inside primary-sample-space Markov chains (mapping a path
//! back to random numbers). Functions take uniform numbers, never an RNG.

use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI, TAU};

/// `1 / (4 pi)`.
const INV_4PI: f32 = 0.25 * FRAC_1_PI;
/// `1 / (2 pi)`.
const INV_2PI: f32 = 0.5 * FRAC_1_PI;

/// Shirley and Chiu's concentric map from `[0,1)^2` to the unit disk (Shirley & Chiu 1997, "A
/// Low Distortion Map Between Disk and Square", JGT 2(3); pbrt-v4 `SampleUniformDiskConcentric`).
///
/// Area preserving up to the constant `pi`, so the density is [`concentric_disk_pdf`].
#[must_use]
#[inline]
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    let (sin, cos) = theta.sin_cos();
    r * Vec2::new(cos, sin)
}

/// Density of [`sample_concentric_disk`] with respect to area: `1 / pi` on the unit disk.
#[must_use]
#[inline]
pub fn concentric_disk_pdf() -> f32 {
    FRAC_1_PI
}

/// Inverse of [`sample_concentric_disk`]: the `u ∈ [0,1]^2` that maps to the disk point `p`.
///
/// Points outside the unit disk are mapped as if scaled onto its boundary radius `|p|`, so the
/// result may leave `[0,1]^2` for `|p| > 1`.
#[must_use]
pub fn invert_concentric_disk(p: Vec2) -> Vec2 {
    let r = p.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    // Angle in [-pi/4, 7pi/4): the four wedges of the forward map, in order.
    let mut phi = p.y.atan2(p.x);
    if phi < -FRAC_PI_4 {
        phi += TAU;
    }
    let o = if phi < FRAC_PI_4 {
        // Right wedge: o.x = r, theta = pi/4 * o.y / o.x.
        Vec2::new(r, r * phi / FRAC_PI_4)
    } else if phi < 3.0 * FRAC_PI_4 {
        // Top wedge: o.y = r, theta = pi/2 - pi/4 * o.x / o.y.
        Vec2::new(r * (FRAC_PI_2 - phi) / FRAC_PI_4, r)
    } else if phi < 5.0 * FRAC_PI_4 {
        // Left wedge: o.x = -r, direction angle = theta + pi.
        let theta = phi - PI;
        Vec2::new(-r, -r * theta / FRAC_PI_4)
    } else {
        // Bottom wedge: o.y = -r, direction angle = theta + pi.
        let theta = phi - PI;
        Vec2::new(-r * (FRAC_PI_2 - theta) / FRAC_PI_4, -r)
    };
    0.5 * (o + Vec2::ONE)
}

/// Cosine-weighted direction on the `+z` hemisphere by Malley's method: a concentric disk
/// sample lifted to the hemisphere (pbrt-v4 `SampleCosineHemisphere`, PBR 4th ed. §A.5.3).
///
/// Density [`cosine_hemisphere_pdf`]`(w.z) = cos theta / pi` per steradian.
#[must_use]
#[inline]
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

/// Density of [`sample_cosine_hemisphere`] per steradian: `max(cos theta, 0) / pi`.
#[must_use]
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Inverse of [`sample_cosine_hemisphere`] for a unit direction with `w.z >= 0`.
#[must_use]
#[inline]
pub fn invert_cosine_hemisphere(w: Vec3A) -> Vec2 {
    invert_concentric_disk(Vec2::new(w.x, w.y))
}

/// Uniform direction on the unit sphere: `z = 1 - 2 u0`, `phi = 2 pi u1` (Archimedes' hat-box
/// theorem; pbrt-v4 `SampleUniformSphere`). Density [`uniform_sphere_pdf`].
#[must_use]
#[inline]
pub fn sample_uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (TAU * u.y).sin_cos();
    Vec3A::new(r * cos, r * sin, z)
}

/// Density of [`sample_uniform_sphere`] per steradian: `1 / (4 pi)`.
#[must_use]
#[inline]
pub fn uniform_sphere_pdf() -> f32 {
    INV_4PI
}

/// Inverse of [`sample_uniform_sphere`] for a unit direction.
#[must_use]
#[inline]
pub fn invert_uniform_sphere(w: Vec3A) -> Vec2 {
    Vec2::new(0.5 * (1.0 - w.z), azimuth_fraction(w))
}

/// Uniform direction on the `+z` hemisphere: `z = u0`, `phi = 2 pi u1`. Density
/// [`uniform_hemisphere_pdf`].
#[must_use]
#[inline]
pub fn sample_uniform_hemisphere(u: Vec2) -> Vec3A {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (TAU * u.y).sin_cos();
    Vec3A::new(r * cos, r * sin, z)
}

/// Density of [`sample_uniform_hemisphere`] per steradian: `1 / (2 pi)`.
#[must_use]
#[inline]
pub fn uniform_hemisphere_pdf() -> f32 {
    INV_2PI
}

/// Inverse of [`sample_uniform_hemisphere`] for a unit direction with `w.z >= 0`.
#[must_use]
#[inline]
pub fn invert_uniform_hemisphere(w: Vec3A) -> Vec2 {
    Vec2::new(w.z, azimuth_fraction(w))
}

/// Uniform direction in the cone of half-angle `acos(cos_theta_max)` around `+z`
/// (pbrt-v4 `SampleUniformCone`): `cos theta = 1 - u0 (1 - cos_theta_max)`, `phi = 2 pi u1`.
/// Density [`uniform_cone_pdf`]. Used for sampling spheres by solid angle.
#[must_use]
#[inline]
pub fn sample_uniform_cone(u: Vec2, cos_theta_max: f32) -> Vec3A {
    let cos_theta = (1.0 - u.x) + u.x * cos_theta_max;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (sin, cos) = (TAU * u.y).sin_cos();
    Vec3A::new(sin_theta * cos, sin_theta * sin, cos_theta)
}

/// Density of [`sample_uniform_cone`] per steradian: `1 / (2 pi (1 - cos_theta_max))`.
#[must_use]
#[inline]
pub fn uniform_cone_pdf(cos_theta_max: f32) -> f32 {
    INV_2PI / (1.0 - cos_theta_max)
}

/// Inverse of [`sample_uniform_cone`] for a unit direction inside the cone.
#[must_use]
#[inline]
pub fn invert_uniform_cone(w: Vec3A, cos_theta_max: f32) -> Vec2 {
    Vec2::new((1.0 - w.z) / (1.0 - cos_theta_max), azimuth_fraction(w))
}

/// Uniform barycentric coordinates `[b0, b1, b2]` on a triangle by Heitz's low-distortion
/// square-to-triangle map (Heitz 2019, "A Low-Distortion Map Between Triangle and Square",
/// Algorithm 1; pbrt-v4 `SampleUniformTriangle`). The point is `b0 p0 + b1 p1 + b2 p2`;
/// its density is [`uniform_triangle_pdf`]`(area)`.
#[must_use]
#[inline]
pub fn sample_uniform_triangle(u: Vec2) -> [f32; 3] {
    let (b0, b1) = if u.x < u.y {
        let b0 = 0.5 * u.x;
        (b0, u.y - b0)
    } else {
        let b1 = 0.5 * u.y;
        (u.x - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

/// Density of [`sample_uniform_triangle`] with respect to area on a triangle of area `area`.
#[must_use]
#[inline]
pub fn uniform_triangle_pdf(area: f32) -> f32 {
    1.0 / area
}

/// Inverse of [`sample_uniform_triangle`]: the `u` whose barycentrics are `b`.
#[must_use]
#[inline]
pub fn invert_uniform_triangle(b: [f32; 3]) -> Vec2 {
    if b[0] > b[1] {
        // Came from u.x >= u.y: b1 = u.y / 2, b0 = u.x - b1.
        Vec2::new(b[0] + b[1], 2.0 * b[1])
    } else {
        // Came from u.x < u.y: b0 = u.x / 2, b1 = u.y - b0.
        Vec2::new(2.0 * b[0], b[1] + b[0])
    }
}

/// `phi / (2 pi)` in `[0, 1)` for the azimuth of `w` around `+z`.
#[inline]
fn azimuth_fraction(w: Vec3A) -> f32 {
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += TAU;
    }
    (phi * INV_2PI).min(1.0 - f32::EPSILON / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic stratified grid of points strictly inside `[0,1)^2`.
    fn grid(n: usize) -> impl Iterator<Item = Vec2> {
        (0..n * n).map(move |k| {
            Vec2::new(
                ((k % n) as f32 + 0.37) / n as f32,
                ((k / n) as f32 + 0.61) / n as f32,
            )
        })
    }

    fn close2(a: Vec2, b: Vec2, tol: f32) -> bool {
        (a - b).abs().max_element() < tol
    }

    #[test]
    fn concentric_disk_round_trip_and_range() {
        for u in grid(41) {
            let p = sample_concentric_disk(u);
            assert!(p.length() <= 1.0 + 1e-6);
            let back = invert_concentric_disk(p);
            assert!(close2(back, u, 2e-5), "u = {u:?}, back = {back:?}");
        }
        assert_eq!(sample_concentric_disk(Vec2::splat(0.5)), Vec2::ZERO);
    }

    #[test]
    fn concentric_disk_is_area_preserving() {
        // Jacobian determinant of the map times pi must be 1 (so the pdf is 1/pi).
        let h = 1e-3;
        for u in grid(13) {
            let u = u.clamp(Vec2::splat(0.01), Vec2::splat(0.99));
            let dx = (sample_concentric_disk(u + Vec2::new(h, 0.0))
                - sample_concentric_disk(u - Vec2::new(h, 0.0)))
                / (2.0 * h);
            let dy = (sample_concentric_disk(u + Vec2::new(0.0, h))
                - sample_concentric_disk(u - Vec2::new(0.0, h)))
                / (2.0 * h);
            let det = (dx.x * dy.y - dx.y * dy.x).abs();
            assert!(
                (det * concentric_disk_pdf() - 1.0).abs() < 2e-2,
                "u {u:?} det {det}"
            );
        }
    }

    #[test]
    fn hemisphere_and_sphere_round_trips() {
        for u in grid(37) {
            let w = sample_cosine_hemisphere(u);
            assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0);
            assert!(close2(invert_cosine_hemisphere(w), u, 5e-4), "cos {u:?}");

            let w = sample_uniform_sphere(u);
            assert!((w.length() - 1.0).abs() < 1e-5);
            assert!(close2(invert_uniform_sphere(w), u, 1e-4), "sphere {u:?}");

            let w = sample_uniform_hemisphere(u);
            assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0);
            assert!(close2(invert_uniform_hemisphere(w), u, 1e-4), "hemi {u:?}");

            let w = sample_uniform_cone(u, 0.8);
            assert!(w.z >= 0.8 - 1e-6 && (w.length() - 1.0).abs() < 1e-5);
            assert!(close2(invert_uniform_cone(w, 0.8), u, 1e-3), "cone {u:?}");
        }
    }

    #[test]
    fn triangle_round_trip_and_uniformity() {
        for u in grid(31) {
            let b = sample_uniform_triangle(u);
            assert!(b.iter().all(|&x| (-1e-6..=1.0 + 1e-6).contains(&x)));
            assert!((b[0] + b[1] + b[2] - 1.0).abs() < 1e-6);
            assert!(close2(invert_uniform_triangle(b), u, 1e-5), "u {u:?}");
        }
        // A uniform grid in the square gives equal mass to the four sub-triangles obtained by
        // joining the edge midpoints.
        let mut counts = [0usize; 4];
        for u in grid(200) {
            let [b0, b1, b2] = sample_uniform_triangle(u);
            let k = if b0 > 0.5 {
                0
            } else if b1 > 0.5 {
                1
            } else if b2 > 0.5 {
                2
            } else {
                3
            };
            counts[k] += 1;
        }
        for c in counts {
            assert!((c as f32 / 40_000.0 - 0.25).abs() < 5e-3, "{counts:?}");
        }
        assert_eq!(uniform_triangle_pdf(0.5), 2.0);
    }

    #[test]
    fn direction_pdfs_integrate_to_one() {
        // Riemann sums over the sphere in (cos theta, phi), where d omega = d cos d phi.
        let n = 400;
        let (mut cosine, mut sphere, mut hemi, mut cone) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for i in 0..n {
            let z = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
            let d_omega = (2.0 / n as f64) * std::f64::consts::TAU;
            cosine += f64::from(cosine_hemisphere_pdf(z)) * d_omega;
            sphere += f64::from(uniform_sphere_pdf()) * d_omega;
            if z > 0.0 {
                hemi += f64::from(uniform_hemisphere_pdf()) * d_omega;
            }
            if z > 0.5 {
                cone += f64::from(uniform_cone_pdf(0.5)) * d_omega;
            }
        }
        for (name, v) in [
            ("cos", cosine),
            ("sphere", sphere),
            ("hemi", hemi),
            ("cone", cone),
        ] {
            assert!((v - 1.0).abs() < 1e-3, "{name}: {v}");
        }
    }
}
