//! The isotropic GGX (Trowbridge-Reitz) microfacet distribution: normal distribution `D`, Smith
//! masking `G1` and height-correlated masking-shadowing `G`, and visible-normal sampling.
//!
//! All directions are in the local shading frame (`z` = macro-surface normal). Microfacet
//! normals `wm` always lie in the upper hemisphere. References: Walter et al. 2007,
//! "Microfacet Models for Refraction through Rough Surfaces" (EGSR), eq. 33-34; Heitz 2014,
//! "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs" (JCGT 3(2)),
//! eq. 72, 86, 99; Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)).

use glam::{Vec2, Vec3A};
use std::f32::consts::{PI, TAU};

/// Isotropic GGX distribution with roughness `alpha` (the slope-space width; glTF's perceptual
/// roughness `r` maps to `alpha = r^2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    alpha: f32,
}

impl Ggx {
    /// Smallest supported `alpha`; smaller values are clamped to it. Below this the lobe is a
    /// near-delta that `f32` cannot evaluate reliably: use the smooth BSDF variants instead.
    pub const MIN_ALPHA: f32 = 1e-3;
    /// Largest supported `alpha` (glTF roughness 1).
    pub const MAX_ALPHA: f32 = 1.0;

    /// A distribution with roughness `alpha`, clamped to `[MIN_ALPHA, MAX_ALPHA]`; a non-finite
    /// `alpha` becomes `MAX_ALPHA`.
    #[must_use]
    pub fn new(alpha: f32) -> Self {
        let alpha = if alpha.is_finite() {
            alpha.clamp(Self::MIN_ALPHA, Self::MAX_ALPHA)
        } else {
            Self::MAX_ALPHA
        };
        Self { alpha }
    }

    /// The roughness `alpha`.
    #[must_use]
    #[inline]
    pub fn alpha(&self) -> f32 {
        self.alpha
    }

    /// Normal distribution `D(wm)` per steradian of microfacet normals, normalised so that
    /// `∫ D(wm) cos(theta_m) dwm = 1` (Walter et al. 2007 eq. 33). Zero for `wm.z <= 0`.
    ///
    /// Evaluated as `alpha^2 / (pi (alpha^2 cos^2 + sin^2)^2)` with `sin^2 = x^2 + y^2`, which
    /// avoids the cancellation in `1 - cos^2` near the peak for small `alpha`. `wm` must be unit.
    #[must_use]
    #[inline]
    pub fn d(&self, wm: Vec3A) -> f32 {
        if wm.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = a2 * wm.z * wm.z + (wm.x * wm.x + wm.y * wm.y);
        a2 / (PI * t * t)
    }

    /// Smith's auxiliary function `Lambda(w) = (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2`
    /// (Heitz 2014 eq. 86). Infinite at grazing angles.
    #[must_use]
    #[inline]
    pub fn lambda(&self, w: Vec3A) -> f32 {
        let z2 = w.z * w.z;
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        let a2_tan2 = self.alpha * self.alpha * (w.x * w.x + w.y * w.y) / z2;
        // (sqrt(1 + x) - 1) / 2 = x / (2 (sqrt(1 + x) + 1)), stable for small x.
        a2_tan2 / (2.0 * ((1.0 + a2_tan2).sqrt() + 1.0))
    }

    /// Smith masking `G1(w) = 1 / (1 + Lambda(w))` (Heitz 2014 eq. 43), ignoring the
    /// back-facing test, which callers perform.
    #[must_use]
    #[inline]
    pub fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated Smith masking-shadowing `G2(wo, wi) = 1 / (1 + Lambda(wo) +
    /// Lambda(wi))` (Heitz 2014 eq. 99). Symmetric in its arguments.
    #[must_use]
    #[inline]
    pub fn g(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of visible normals `D_w(wm) = G1(w) max(0, w . wm) D(wm) / |cos theta_w|`
    /// (Heitz 2018 eq. 1) per steradian of `wm`. A `w` below the surface is mirrored to the
    /// upper hemisphere first, matching [`Ggx::sample_visible`].
    #[must_use]
    #[inline]
    pub fn pdf_visible(&self, w: Vec3A, wm: Vec3A) -> f32 {
        let w = if w.z < 0.0 { -w } else { w };
        if w.z == 0.0 {
            return 0.0;
        }
        self.g1(w) * w.dot(wm).max(0.0) * self.d(wm) / w.z
    }

    /// Samples a microfacet normal from the distribution of normals visible from `w`
    /// (Heitz 2018, Listing 1). `w` below the surface is mirrored to the upper hemisphere; the
    /// result is a unit vector with `wm.z > 0` and density [`Ggx::pdf_visible`]`(w, wm)`.
    ///
    /// Steps: stretch `w` to the hemisphere configuration (`alpha = 1`), build a frame around
    /// it, sample a disk point by the polar map, warp it to the projected visible hemisphere,
    /// lift it to the hemisphere and unstretch.
    #[must_use]
    pub fn sample_visible(&self, w: Vec3A, u2: Vec2) -> Vec3A {
        let w = if w.z < 0.0 { -w } else { w };
        // Section 3.2: transform the view direction to the hemisphere configuration.
        let vh = Vec3A::new(self.alpha * w.x, self.alpha * w.y, w.z)
            .try_normalize()
            .unwrap_or(Vec3A::Z);
        // Section 4.1: orthonormal basis (with the special case at normal incidence).
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3A::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3A::X
        };
        let t2 = vh.cross(t1);
        // Section 4.2: parameterisation of the projected area.
        let r = u2.x.sqrt();
        let (sin_phi, cos_phi) = (TAU * u2.y).sin_cos();
        let p1 = r * cos_phi;
        let mut p2 = r * sin_phi;
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        // Section 4.3: reprojection onto the hemisphere.
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        // Section 3.4: transform the normal back to the ellipsoid configuration.
        Vec3A::new(self.alpha * nh.x, self.alpha * nh.y, nh.z.max(1e-6))
            .try_normalize()
            .unwrap_or(Vec3A::Z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::warp::sample_uniform_sphere;

    /// Midpoint rule over the upper hemisphere in (cos theta, phi).
    fn integrate_hemisphere(n: usize, f: impl Fn(Vec3A) -> f64) -> f64 {
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let z = ((i as f64 + 0.5) / n as f64) as f32;
                let phi = TAU * (j as f32 + 0.5) / n as f32;
                let r = (1.0 - z * z).sqrt();
                sum += f(Vec3A::new(r * phi.cos(), r * phi.sin(), z));
            }
        }
        sum * std::f64::consts::TAU / (n * n) as f64
    }

    #[test]
    fn projected_area_of_microfacets_is_one() {
        for alpha in [0.2, 0.5, 1.0] {
            let ggx = Ggx::new(alpha);
            let v = integrate_hemisphere(800, |wm| f64::from(ggx.d(wm) * wm.z));
            assert!((v - 1.0).abs() < 2e-3, "alpha {alpha}: {v}");
        }
    }

    #[test]
    fn visible_normals_are_normalised() {
        // ∫ G1(w) max(0, w.wm) D(wm) dwm = cos theta_w (Heitz 2014 eq. 18).
        let ggx = Ggx::new(0.4);
        for w in [
            Vec3A::Z,
            Vec3A::new(0.6, 0.0, 0.8),
            Vec3A::new(-0.3, 0.9, 0.316_227_8).normalize(),
        ] {
            let v = integrate_hemisphere(800, |wm| f64::from(ggx.pdf_visible(w, wm)));
            assert!((v - 1.0).abs() < 3e-3, "w {w:?}: {v}");
        }
    }

    #[test]
    fn sampled_normals_face_the_viewer() {
        let ggx = Ggx::new(0.3);
        for i in 0..200 {
            let u = Vec2::new((i as f32 + 0.5) / 200.0, ((i * 71) % 200) as f32 / 200.0);
            let w = sample_uniform_sphere(u);
            let wm = ggx.sample_visible(w, Vec2::new(u.y, u.x));
            assert!(wm.z > 0.0 && (wm.length() - 1.0).abs() < 1e-5);
            assert!(wm.dot(if w.z < 0.0 { -w } else { w }) >= -1e-5);
        }
    }

    #[test]
    fn lambda_and_masking_limits() {
        let ggx = Ggx::new(0.5);
        assert_eq!(ggx.lambda(Vec3A::Z), 0.0);
        assert_eq!(ggx.g1(Vec3A::Z), 1.0);
        assert_eq!(ggx.lambda(Vec3A::X), f32::INFINITY);
        assert_eq!(ggx.g1(Vec3A::X), 0.0);
        let (a, b) = (Vec3A::new(0.6, 0.0, 0.8), Vec3A::new(0.0, -0.8, 0.6));
        assert_eq!(ggx.g(a, b), ggx.g(b, a));
        assert!(ggx.g(a, b) <= ggx.g1(a).min(ggx.g1(b)));
        assert_eq!(Ggx::new(f32::NAN).alpha(), Ggx::MAX_ALPHA);
        assert_eq!(Ggx::new(0.0).alpha(), Ggx::MIN_ALPHA);
    }
}
