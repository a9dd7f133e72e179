//! Dielectrics (glass, water): a smooth Fresnel interface and the Walter et al. 2007 rough
//! GGX interface, each reflecting and transmitting, with adjoint handling of radiance vs
//! importance transport.
//!
//! Conventions: the local `+z` side is outside, `eta = n_inside / n_outside > 0`. A sample's
//! `eta` is `etap = n(wi side) / n(wo side)` for transmission and 1 for reflection. In
//! [`TransportMode::Radiance`] transmitted values are divided by `etap^2` (radiance is
//! compressed into a smaller solid angle on entering a denser medium; Veach 1997 §5.2), in
//! [`TransportMode::Importance`] they are not: `f_importance(wo, wi) = f_radiance(wi, wo)`, the
//! adjoint BSDF. The `tint` multiplies transmission only (glTF `KHR_materials_transmission`
//! tints transmitted light by the base colour); reflection is untinted.

use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::microfacet::Ggx;
use super::{sanitize_rgb, BsdfSample, TransportMode};
use glam::{Vec2, Vec3, Vec3A};

/// Sanitises a relative IOR: non-finite or non-positive values become 1.5 (glTF's default).
fn sanitize_eta(eta: f32) -> f32 {
    if eta.is_finite() && eta > 0.0 {
        eta
    } else {
        1.5
    }
}

/// The factor applied to transmitted values for `mode` when crossing relative IOR `etap`.
#[inline]
fn transmission_scale(mode: TransportMode, etap: f32) -> f32 {
    match mode {
        TransportMode::Radiance => 1.0 / (etap * etap),
        TransportMode::Importance => 1.0,
    }
}

/// A smooth dielectric interface: two delta lobes, mirror reflection with probability and
/// weight `R = F_dielectric(cos theta_o, eta)` and Snell transmission with `T = 1 - R`
/// (PBR 4th ed. §9.5.1). Two-sided (either side may face `wo`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothDielectric {
    eta: f32,
    tint: Vec3,
}

impl SmoothDielectric {
    /// A smooth interface with relative IOR `eta = n_inside / n_outside` (sanitised: positive
    /// and finite, else 1.5) and transmission tint (clamped to `[0, 1]`).
    #[must_use]
    pub fn new(eta: f32, tint: Vec3) -> Self {
        Self {
            eta: sanitize_eta(eta),
            tint: sanitize_rgb(tint),
        }
    }

    /// Relative index of refraction `n_inside / n_outside`.
    #[must_use]
    #[inline]
    pub fn eta(&self) -> f32 {
        self.eta
    }

    /// Transmission tint.
    #[must_use]
    #[inline]
    pub fn tint(&self) -> Vec3 {
        self.tint
    }

    /// Chooses reflection if `u < R`, else transmission; `pdf` is the lobe's discrete
    /// probability and `f = weight / |cos theta_i|` so that `f |cos| / pdf` is `1` (reflection)
    /// or `tint / etap^2` (radiance transmission).
    #[must_use]
    pub fn sample(&self, wo: Vec3A, u: f32, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let r = fresnel_dielectric(wo.z, self.eta);
        let t = 1.0 - r;
        if u < r || t <= 0.0 {
            let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample {
                wi,
                f: Vec3::splat(r / wi.z.abs()),
                pdf: r,
                is_specular: true,
                eta: 1.0,
            });
        }
        let (wi, etap) = refract(wo, Vec3A::Z, self.eta)?;
        if wi.z == 0.0 {
            return None;
        }
        let f = self.tint * (t * transmission_scale(mode, etap) / wi.z.abs());
        Some(BsdfSample {
            wi,
            f,
            pdf: t,
            is_specular: true,
            eta: etap,
        })
    }
}

/// A rough dielectric interface (Walter et al. 2007, "Microfacet Models for Refraction through
/// Rough Surfaces", eq. 15-21) with GGX normals and height-correlated Smith `G2`:
///
/// * reflection: `f_r = D F G2 / (4 |cos_o cos_i|)`, `wm = normalize(wo + wi)`;
/// * transmission: `f_t = D (1 - F) G2 |wi.wm| |wo.wm| / (|cos_o cos_i| (wi.wm + wo.wm /
///   etap)^2)` (eq. 21 with the IORs divided through; the importance form), divided by
///   `etap^2` for radiance, `wm = normalize(etap wi + wo)` (eq. 16), oriented to `+z`.
///
/// Microfacets back-facing either direction contribute nothing. Sampling draws a visible normal
/// (Heitz 2018), then reflection with probability `F(wo . wm)`; the pdf uses the half-vector
/// Jacobians `1 / (4 |wo.wm|)` (eq. 14) and `|wi.wm| / (wi.wm + wo.wm / etap)^2` (eq. 17).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    eta: f32,
    tint: Vec3,
    ggx: Ggx,
}

/// The microfacet configuration of a `(wo, wi)` pair of a rough dielectric.
struct HalfVector {
    wm: Vec3A,
    etap: f32,
    reflect: bool,
}

impl RoughDielectric {
    /// A rough interface with relative IOR `eta` (sanitised as in [`SmoothDielectric::new`]),
    /// GGX roughness `alpha` (clamped by [`Ggx::new`]) and transmission tint.
    ///
    /// Callers wanting `eta == 1` or tiny `alpha` should use [`SmoothDielectric`]: an index-
    /// matched rough interface does not refract and its half vector is degenerate.
    #[must_use]
    pub fn new(eta: f32, alpha: f32, tint: Vec3) -> Self {
        Self {
            eta: sanitize_eta(eta),
            tint: sanitize_rgb(tint),
            ggx: Ggx::new(alpha),
        }
    }

    /// Relative index of refraction `n_inside / n_outside`.
    #[must_use]
    #[inline]
    pub fn eta(&self) -> f32 {
        self.eta
    }

    /// Transmission tint.
    #[must_use]
    #[inline]
    pub fn tint(&self) -> Vec3 {
        self.tint
    }

    /// The microfacet distribution.
    #[must_use]
    #[inline]
    pub fn distribution(&self) -> Ggx {
        self.ggx
    }

    /// The generalised half vector of `(wo, wi)` (Walter et al. 2007 eq. 13, 16), or `None` for
    /// grazing, degenerate or back-facing configurations.
    #[inline]
    fn half_vector(&self, wo: Vec3A, wi: Vec3A) -> Option<HalfVector> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o == 0.0 || cos_i == 0.0 {
            return None;
        }
        let reflect = cos_o * cos_i > 0.0;
        let etap = if reflect {
            1.0
        } else if cos_o > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let mut wm = (wi * etap + wo).try_normalize()?;
        if wm.z < 0.0 {
            wm = -wm;
        }
        // Discard back-facing microfacets.
        if wm.dot(wi) * cos_i <= 0.0 || wm.dot(wo) * cos_o <= 0.0 {
            return None;
        }
        Some(HalfVector { wm, etap, reflect })
    }

    /// BSDF value for a valid half-vector configuration.
    #[inline]
    fn f(&self, wo: Vec3A, wi: Vec3A, h: &HalfVector, mode: TransportMode) -> Vec3 {
        let d = self.ggx.d(h.wm);
        let g = self.ggx.g(wo, wi);
        let fr = fresnel_dielectric(wo.dot(h.wm), self.eta);
        if h.reflect {
            Vec3::splat(d * g * fr / (4.0 * wo.z * wi.z).abs())
        } else {
            let (dot_i, dot_o) = (wi.dot(h.wm), wo.dot(h.wm));
            let s = dot_i + dot_o / h.etap;
            let denom = s * s * wi.z * wo.z;
            let ft = d * (1.0 - fr) * g * (dot_i * dot_o / denom).abs();
            self.tint * (ft * transmission_scale(mode, h.etap))
        }
    }

    /// Solid-angle pdf of [`RoughDielectric::sample`] for a valid configuration.
    #[inline]
    fn pdf_h(&self, wo: Vec3A, wi: Vec3A, h: &HalfVector) -> f32 {
        let dot_o = wo.dot(h.wm);
        let r = fresnel_dielectric(dot_o, self.eta);
        let visible = self.ggx.pdf_visible(wo, h.wm);
        if h.reflect {
            visible / (4.0 * dot_o.abs()) * r
        } else {
            let dot_i = wi.dot(h.wm);
            let s = dot_i + dot_o / h.etap;
            visible * dot_i.abs() / (s * s) * (1.0 - r)
        }
    }

    /// The BSDF value (not multiplied by the cosine).
    #[must_use]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Vec3 {
        match self.half_vector(wo, wi) {
            Some(h) => self.f(wo, wi, &h, mode),
            None => Vec3::ZERO,
        }
    }

    /// The solid-angle density of [`RoughDielectric::sample`].
    #[must_use]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        match self.half_vector(wo, wi) {
            Some(h) => self.pdf_h(wo, wi, &h),
            None => 0.0,
        }
    }

    /// Samples a visible normal with `u2`, then reflection (if `u < F(wo . wm)`) or refraction
    /// about it. `None` if the resulting direction is on the wrong side (lost mass).
    #[must_use]
    pub fn sample(&self, wo: Vec3A, u: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.ggx.sample_visible(wo, u2);
        let dot_o = wo.dot(wm);
        if dot_o * wo.z <= 0.0 {
            return None;
        }
        let r = fresnel_dielectric(dot_o, self.eta);
        let (wi, h) = if u < r {
            let wi = reflect(wo, wm);
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            let h = HalfVector {
                wm,
                etap: 1.0,
                reflect: true,
            };
            (wi, h)
        } else {
            let (wi, etap) = refract(wo, wm, self.eta)?;
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            let h = HalfVector {
                wm,
                etap,
                reflect: false,
            };
            (wi, h)
        };
        if wi.dot(wm) * wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf_h(wo, wi, &h);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            f: self.f(wo, wi, &h, mode),
            pdf,
            is_specular: false,
            eta: h.etap,
        })
    }
}
