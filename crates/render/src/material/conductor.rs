//! Conductors (metals): a perfect mirror and a GGX microfacet BRDF, both with Schlick Fresnel.

use super::fresnel::{fresnel_schlick, reflect};
use super::microfacet::Ggx;
use super::{sanitize_rgb, BsdfSample};
use glam::{Vec2, Vec3, Vec3A};

/// A perfectly smooth conductor: a delta lobe in the mirror direction with reflectance
/// `F_schlick(f0, |cos theta_o|)` (PBR 4th ed. §9.4.2, with Schlick's Fresnel instead of the
/// complex-IOR one). Two-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothConductor {
    f0: Vec3,
}

impl SmoothConductor {
    /// A mirror with normal-incidence reflectance `f0`, clamped per channel to `[0, 1]`.
    #[must_use]
    pub fn new(f0: Vec3) -> Self {
        Self {
            f0: sanitize_rgb(f0),
        }
    }

    /// Normal-incidence reflectance.
    #[must_use]
    #[inline]
    pub fn f0(&self) -> Vec3 {
        self.f0
    }

    /// Samples the mirror direction: `f = F / |cos theta_i|`, `pdf = 1` (discrete).
    #[must_use]
    pub fn sample(&self, wo: Vec3A) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
        let cos = wi.z.abs();
        Some(BsdfSample {
            wi,
            f: fresnel_schlick(self.f0, cos) / cos,
            pdf: 1.0,
            is_specular: true,
            eta: 1.0,
        })
    }
}

/// A rough conductor: the Cook-Torrance / Walter et al. 2007 microfacet BRDF (eq. 20)
/// `f = D(wm) F(wo . wm) G2(wo, wi) / (4 |cos theta_o| |cos theta_i|)`, `wm = normalize(wo +
/// wi)`, with GGX `D`, height-correlated Smith `G2` and Schlick `F`. Sampled by visible normals
/// (Heitz 2018), `pdf = D_wo(wm) / (4 |wo . wm|)`. Two-sided. Being single-scattering, it loses
/// energy as `alpha` grows (Kulla & Conty 2017, "Revisiting Physically Based Shading at
/// Imageworks").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    f0: Vec3,
    ggx: Ggx,
}

impl RoughConductor {
    /// A rough metal with normal-incidence reflectance `f0` (clamped to `[0, 1]`) and GGX
    /// roughness `alpha` (clamped by [`Ggx::new`]).
    #[must_use]
    pub fn new(f0: Vec3, alpha: f32) -> Self {
        Self {
            f0: sanitize_rgb(f0),
            ggx: Ggx::new(alpha),
        }
    }

    /// Normal-incidence reflectance.
    #[must_use]
    #[inline]
    pub fn f0(&self) -> Vec3 {
        self.f0
    }

    /// The microfacet distribution.
    #[must_use]
    #[inline]
    pub fn distribution(&self) -> Ggx {
        self.ggx
    }

    /// Flips `wo` and `wi` to the upper hemisphere; `None` unless both are on the same side.
    #[inline]
    fn upper(wo: Vec3A, wi: Vec3A) -> Option<(Vec3A, Vec3A, Vec3A)> {
        if wo.z * wi.z <= 0.0 {
            return None;
        }
        let (wo, wi) = if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) };
        let wm = (wo + wi).try_normalize()?;
        Some((wo, wi, wm))
    }

    /// The BRDF value for upper-hemisphere `wo`, `wi` and their half vector `wm`.
    #[inline]
    fn f(&self, wo: Vec3A, wi: Vec3A, wm: Vec3A) -> Vec3 {
        let d = self.ggx.d(wm);
        let g = self.ggx.g(wo, wi);
        let f = fresnel_schlick(self.f0, wo.dot(wm));
        f * (d * g / (4.0 * wo.z * wi.z))
    }

    /// The BRDF value (not multiplied by the cosine).
    #[must_use]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3 {
        match Self::upper(wo, wi) {
            Some((wo, wi, wm)) => self.f(wo, wi, wm),
            None => Vec3::ZERO,
        }
    }

    /// The solid-angle density of [`RoughConductor::sample`].
    #[must_use]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        match Self::upper(wo, wi) {
            Some((wo, _, wm)) => self.ggx.pdf_visible(wo, wm) / (4.0 * wo.dot(wm)),
            None => 0.0,
        }
    }

    /// Visible-normal sampling followed by mirror reflection about the sampled normal; `None`
    /// when the reflected direction falls below the surface (its mass is the sampling's
    /// deficit, consistent with [`RoughConductor::pdf`] being 0 there).
    #[must_use]
    pub fn sample(&self, wo: Vec3A, u2: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let flip = wo.z < 0.0;
        let wo_up = if flip { -wo } else { wo };
        let wm = self.ggx.sample_visible(wo_up, u2);
        let wi_up = reflect(wo_up, wm);
        let cos_om = wo_up.dot(wm);
        if wi_up.z <= 0.0 || cos_om <= 0.0 {
            return None;
        }
        let pdf = self.ggx.pdf_visible(wo_up, wm) / (4.0 * cos_om);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let f = self.f(wo_up, wi_up, wm);
        Some(BsdfSample {
            wi: if flip { -wi_up } else { wi_up },
            f,
            pdf,
            is_specular: false,
            eta: 1.0,
        })
    }
}
