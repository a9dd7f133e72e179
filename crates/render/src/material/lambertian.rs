//! The Lambertian (ideal diffuse) BRDF `f = albedo / pi`, two-sided, cosine-weighted sampling.

use super::{same_hemisphere, BsdfSample};
use crate::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// Ideal diffuse reflection: `f(wo, wi) = albedo / pi` when `wo` and `wi` lie on the same side
/// of the surface, zero otherwise (PBR 4th ed. §9.2). Two-sided, like pbrt's `DiffuseBxDF`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambertian {
    albedo: Vec3,
}

impl Lambertian {
    /// A Lambertian BRDF with directional-hemispherical reflectance `albedo`, clamped per
    /// channel to `[0, 1]` (non-finite channels become 0) so that energy is conserved.
    #[must_use]
    pub fn new(albedo: Vec3) -> Self {
        Self {
            albedo: super::sanitize_rgb(albedo),
        }
    }

    /// The reflectance (albedo) in `[0, 1]^3`.
    #[must_use]
    #[inline]
    pub fn albedo(&self) -> Vec3 {
        self.albedo
    }

    /// `albedo / pi` on the same side, 0 otherwise.
    #[must_use]
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3 {
        if same_hemisphere(wo, wi) {
            self.albedo * FRAC_1_PI
        } else {
            Vec3::ZERO
        }
    }

    /// `|cos theta_i| / pi` on the same side, 0 otherwise.
    #[must_use]
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if same_hemisphere(wo, wi) {
            cosine_hemisphere_pdf(wi.z.abs())
        } else {
            0.0
        }
    }

    /// Cosine-weighted sampling (Malley's method) on `wo`'s side of the surface.
    #[must_use]
    pub fn sample(&self, wo: Vec3A, u2: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let mut wi = sample_cosine_hemisphere(u2);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf = cosine_hemisphere_pdf(wi.z.abs());
        (pdf > 0.0).then_some(BsdfSample {
            wi,
            f: self.albedo * FRAC_1_PI,
            pdf,
            is_specular: false,
            eta: 1.0,
        })
    }
}
