//! BSDFs in the local shading frame: Lambertian, smooth/rough conductors and smooth/rough
//! dielectrics, behind one closed [`Bsdf`] enum with `eval` / `pdf` / `sample`.
//!
//! # Conventions
//!
//! * Directions are unit vectors in the **local shading frame** ([`crate::frame::Frame`]):
//!   `z` is the shading normal, `cos theta = w.z`. Both `wo` and `wi` point *away* from the
//!   surface. `wo` is the direction the path arrived from (towards the camera for camera
//!   paths, towards the light for light paths); `wi` is the next direction.
//! * RGB is linear `glam::Vec3` (Rec. 709 primaries), no newtype.
//! * [`Bsdf::eval`] returns `f(wo, wi)` **without** the cosine factor. A Monte Carlo weight is
//!   `f |cos theta_i| / pdf`.
//! * Randomness enters only as uniform numbers `u ∈ [0,1)`, `u2 ∈ [0,1)^2` (pbrt-v4's
//!   `BxDF::Sample_f(wo, uc, u2, mode)`): `u` picks a lobe (dielectrics), `u2` a direction.
//! * Delta lobes (smooth variants): `eval` and `pdf` are 0; `sample` returns
//!   `is_specular = true`, `pdf` = the discrete probability of the chosen lobe and
//!   `f = weight / |cos theta_i|`, so the usual `f |cos| / pdf` formula still applies.
//! * Reflection is two-sided (a `wo` below the surface is handled by symmetry), as in pbrt.
//! * [`TransportMode`] selects the adjoint BSDF: non-symmetric scattering (refraction)
//!   includes the `1 / etap^2` radiance factor only in [`TransportMode::Radiance`]. The
//!   shading-normal correction of Veach 1997 §5.3 is the integrator's job (it needs the
//!   geometric normal).

mod conductor;
mod dielectric;
mod fresnel;
mod lambertian;
mod microfacet;

pub use conductor::{RoughConductor, SmoothConductor};
pub use dielectric::{RoughDielectric, SmoothDielectric};
pub use fresnel::{fresnel_dielectric, fresnel_schlick, reflect, refract};
pub use lambertian::Lambertian;
pub use microfacet::Ggx;

use glam::{Vec2, Vec3, Vec3A};

/// Which quantity a path carries; selects the adjoint BSDF for non-symmetric scattering
/// (Veach 1997, "Robust Monte Carlo Methods for Light Transport Simulation", §5.2; pbrt-v4
/// `TransportMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum TransportMode {
    /// Camera (eye) subpaths: radiance flows from `wi` to `wo`.
    #[default]
    Radiance,
    /// Light subpaths: importance flows from `wi` to `wo`; the adjoint BSDF is used.
    Importance,
}

/// One direction sampled from a [`Bsdf`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled direction, local frame, unit length, pointing away from the surface.
    pub wi: Vec3A,
    /// BSDF value `f(wo, wi)`, NOT multiplied by `|cos theta_i|`.
    pub f: Vec3,
    /// Solid-angle density of `wi`; for delta lobes the discrete probability of the lobe.
    pub pdf: f32,
    /// True if `wi` came from a delta (specular) lobe.
    pub is_specular: bool,
    /// Relative IOR crossed, `n(wi side) / n(wo side)`; 1 for reflection. A path's radiance
    /// scale changes by `1 / eta^2` across the interface (used by Russian roulette, as pbrt-v4's
    /// `etaScale`).
    pub eta: f32,
}

impl BsdfSample {
    /// The Monte Carlo weight `f |cos theta_i| / pdf`.
    #[must_use]
    #[inline]
    pub fn weight(&self) -> Vec3 {
        self.f * (self.wi.z.abs() / self.pdf)
    }
}

/// A BSDF with all parameters resolved (texture lookups already done), in the LOCAL shading
/// frame (`z` = shading normal).
///
/// Variants wrap one small struct per family (see their docs for the formulas); construct with
/// the validating constructors below, which clamp user values into range instead of failing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Ideal diffuse reflection.
    Lambertian(Lambertian),
    /// Perfect mirror with Schlick Fresnel.
    SmoothConductor(SmoothConductor),
    /// GGX microfacet metal with Schlick Fresnel.
    RoughConductor(RoughConductor),
    /// Smooth glass-like interface (reflection + refraction, delta lobes).
    SmoothDielectric(SmoothDielectric),
    /// Rough glass-like interface (Walter et al. 2007).
    RoughDielectric(RoughDielectric),
}

/// glTF perceptual roughness below which [`Bsdf::from_gltf_params`] uses the smooth variants
/// (`alpha = 0.02^2 = 4e-4` is already below [`Ggx::MIN_ALPHA`]).
pub const SMOOTH_ROUGHNESS_THRESHOLD: f32 = 0.02;

impl Bsdf {
    /// Lambertian reflection with the given albedo (clamped to `[0, 1]`).
    #[must_use]
    pub fn lambertian(albedo: Vec3) -> Self {
        Self::Lambertian(Lambertian::new(albedo))
    }

    /// A perfect mirror with normal-incidence reflectance `f0` (Schlick Fresnel).
    #[must_use]
    pub fn smooth_conductor(f0: Vec3) -> Self {
        Self::SmoothConductor(SmoothConductor::new(f0))
    }

    /// A GGX metal with normal-incidence reflectance `f0` and **GGX `alpha`** (not glTF's
    /// perceptual roughness: pass `roughness^2`), clamped to `[Ggx::MIN_ALPHA, 1]`.
    #[must_use]
    pub fn rough_conductor(f0: Vec3, alpha: f32) -> Self {
        Self::RoughConductor(RoughConductor::new(f0, alpha))
    }

    /// A smooth dielectric with relative IOR `ior = n_inside / n_outside` and a transmission
    /// tint.
    #[must_use]
    pub fn smooth_dielectric(ior: f32, tint: Vec3) -> Self {
        Self::SmoothDielectric(SmoothDielectric::new(ior, tint))
    }

    /// A rough dielectric with relative IOR `ior`, **GGX `alpha`** and a transmission tint.
    /// An index-matched interface (`|ior - 1| < 1e-3`) becomes a [`SmoothDielectric`] (it does
    /// not refract, and its generalised half vector is undefined), as in pbrt-v4.
    #[must_use]
    pub fn rough_dielectric(ior: f32, alpha: f32, tint: Vec3) -> Self {
        if (ior - 1.0).abs() < 1e-3 {
            return Self::smooth_dielectric(ior, tint);
        }
        Self::RoughDielectric(RoughDielectric::new(ior, alpha, tint))
    }

    /// Maps glTF 2.0 metallic-roughness parameters (with `KHR_materials_transmission` and
    /// `KHR_materials_ior`) to one BSDF family. The mapping, in order:
    ///
    /// 1. inputs are sanitised: `base_color`, `metallic`, `roughness`, `transmission` clamped to
    ///    `[0, 1]` (NaN -> 0, roughness NaN -> 1); `ior` not finite or `< 1` -> 1.5;
    /// 2. `alpha = roughness^2` (glTF spec, Appendix B); `roughness <`
    ///    [`SMOOTH_ROUGHNESS_THRESHOLD`] selects the smooth variant;
    /// 3. `transmission > 0.5` -> dielectric with IOR `ior`, tint `base_color`;
    /// 4. else `metallic >= 0.5` -> conductor with Schlick `F0 = base_color`;
    /// 5. else Lambertian with albedo `base_color` (the glTF dielectric specular layer is
    ///    dropped).
    ///
    /// A binary choice keeps each BSDF a single closed family, which the MCMC perturbations and
    /// the chi-square tests rely on.
    #[must_use]
    pub fn from_gltf_params(
        base_color: Vec3,
        metallic: f32,
        roughness: f32,
        transmission: f32,
        ior: f32,
    ) -> Self {
        let unit = |x: f32, nan: f32| if x.is_nan() { nan } else { x.clamp(0.0, 1.0) };
        let base_color = sanitize_rgb(base_color);
        let metallic = unit(metallic, 0.0);
        let roughness = unit(roughness, 1.0);
        let transmission = unit(transmission, 0.0);
        let ior = if ior.is_finite() && ior >= 1.0 {
            ior
        } else {
            1.5
        };
        let smooth = roughness < SMOOTH_ROUGHNESS_THRESHOLD;
        let alpha = roughness * roughness;
        if transmission > 0.5 {
            if smooth {
                Self::smooth_dielectric(ior, base_color)
            } else {
                Self::rough_dielectric(ior, alpha, base_color)
            }
        } else if metallic >= 0.5 {
            if smooth {
                Self::smooth_conductor(base_color)
            } else {
                Self::rough_conductor(base_color, alpha)
            }
        } else {
            Self::lambertian(base_color)
        }
    }

    /// `f(wo, wi)` without the cosine; 0 for delta lobes.
    #[must_use]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Vec3 {
        match self {
            Self::Lambertian(b) => b.eval(wo, wi),
            Self::RoughConductor(b) => b.eval(wo, wi),
            Self::RoughDielectric(b) => b.eval(wo, wi, mode),
            Self::SmoothConductor(_) | Self::SmoothDielectric(_) => Vec3::ZERO,
        }
    }

    /// Solid-angle density with which [`Bsdf::sample`] produces `wi` from `wo`; 0 for delta
    /// lobes. Independent of `mode` for the current families (kept for the adjoint API).
    #[must_use]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> f32 {
        let _ = mode;
        match self {
            Self::Lambertian(b) => b.pdf(wo, wi),
            Self::RoughConductor(b) => b.pdf(wo, wi),
            Self::RoughDielectric(b) => b.pdf(wo, wi),
            Self::SmoothConductor(_) | Self::SmoothDielectric(_) => 0.0,
        }
    }

    /// Samples `wi` given `wo` from uniform numbers (`u` for the lobe choice, `u2` for the
    /// direction). `None` when no direction is produced (grazing `wo`, or a microfacet sample
    /// that left the valid hemisphere — that mass is missing from `pdf` as well).
    #[must_use]
    pub fn sample(&self, wo: Vec3A, u: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        match self {
            Self::Lambertian(b) => b.sample(wo, u2),
            Self::SmoothConductor(b) => b.sample(wo),
            Self::RoughConductor(b) => b.sample(wo, u2),
            Self::SmoothDielectric(b) => b.sample(wo, u, mode),
            Self::RoughDielectric(b) => b.sample(wo, u, u2, mode),
        }
    }

    /// True if all lobes are delta distributions (smooth conductor / dielectric): such a
    /// vertex cannot be connected to in BDPT or next-event estimation.
    #[must_use]
    pub fn is_specular(&self) -> bool {
        matches!(self, Self::SmoothConductor(_) | Self::SmoothDielectric(_))
    }

    /// The GGX `alpha`: 0 for the smooth variants, 1 for Lambertian (a proxy used by
    /// integrators and mutation heuristics).
    #[must_use]
    pub fn roughness(&self) -> f32 {
        match self {
            Self::Lambertian(_) => 1.0,
            Self::SmoothConductor(_) | Self::SmoothDielectric(_) => 0.0,
            Self::RoughConductor(b) => b.distribution().alpha(),
            Self::RoughDielectric(b) => b.distribution().alpha(),
        }
    }

    /// True if the BSDF transmits light (dielectrics).
    #[must_use]
    pub fn has_transmission(&self) -> bool {
        matches!(self, Self::SmoothDielectric(_) | Self::RoughDielectric(_))
    }
}

/// True if `a` and `b` are strictly on the same side of the local surface.
#[inline]
pub(crate) fn same_hemisphere(a: Vec3A, b: Vec3A) -> bool {
    a.z * b.z > 0.0
}

/// Clamps each channel to `[0, 1]`, mapping NaN to 0.
pub(crate) fn sanitize_rgb(c: Vec3) -> Vec3 {
    let f = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    Vec3::new(f(c.x), f(c.y), f(c.z))
}

#[cfg(test)]
mod tests;
