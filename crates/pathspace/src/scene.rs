//! The scene queries path-space MLT needs, as small traits a renderer implements.
//!
//! The crate never sees triangles, BVHs or textures: it reaches the scene only through
//! [`RayTracer`] (trace a ray, mutual visibility), [`Bsdfs`] (evaluate, pdf, sample, and the
//! deterministic continuation through a specular vertex), [`Emitters`] (emitted radiance and
//! the area density of light sampling) and [`Camera`] (a pinhole: raster <-> ray and
//! importance). [`PathScene`] is all four. Everything is f64; a single-precision renderer
//! converts at this boundary. All methods take uniform numbers, never an RNG (pbrt's
//! separation), and every direction is a unit vector pointing *away* from the surface point.

use crate::vec3::{Rgb, Vec3};

/// A point on a surface as the ray tracer reports it: what a path vertex stores about the
/// scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfacePoint {
    /// World-space position.
    pub position: Vec3,
    /// Unit shading normal (what the BSDF uses; may differ from the geometric normal on
    /// smooth-shaded meshes).
    pub shading_normal: Vec3,
    /// Unit geometric normal (what measure conversions use: `|cos|` in `G` and in the
    /// solid angle <-> area Jacobian).
    pub geometric_normal: Vec3,
    /// Opaque handle of the surface's material (BSDF and emission), interpreted only by the
    /// scene (e.g. a triangle-mesh renderer's material index, or primitive id).
    pub material: u32,
}

/// Which delta lobe a specular vertex uses: the path model's specular flag
/// (Veach 1997, section 8.2: a vertex is specular if its BSDF is a Dirac distribution).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SpecularLobe {
    /// Mirror reflection.
    Reflection,
    /// Refraction through a dielectric interface.
    Refraction,
}

/// A direction sampled by a BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled unit direction `wi` (away from the surface, toward the light side).
    pub wi: Vec3,
    /// For a non-specular sample: the solid-angle density of `wi`. For a specular sample: the
    /// discrete probability of choosing `lobe` (e.g. the Fresnel reflectance of a dielectric).
    pub pdf: f64,
    /// `Some(lobe)` if the sample is a delta lobe of a specular material.
    pub lobe: Option<SpecularLobe>,
}

/// Ray queries.
pub trait RayTracer {
    /// The closest surface hit by the ray `origin + t dir`, `t > 0` (the implementation
    /// avoids self-intersection at `origin`), or `None` if the ray leaves the scene.
    fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<SurfacePoint>;

    /// True if nothing blocks the open segment between `a` and `b` (two surface points).
    fn visible(&self, a: Vec3, b: Vec3) -> bool;
}

/// Scattering at surface points.
///
/// A material is either *specular* (only Dirac lobes: mirrors, smooth dielectrics) or
/// *non-specular* (an ordinary BSDF with a density): the path model treats the two kinds
/// differently (the vertex after a specular vertex is determined by the two before it).
/// `wo` is the direction toward the camera side of the path, `wi` toward the light side
/// (pbrt's naming); radiance flows from `wi` to `wo`.
pub trait Bsdfs {
    /// True if the material at `p` is specular (Dirac lobes only).
    fn is_specular(&self, p: &SurfacePoint) -> bool;

    /// `f_s(p, wo, wi)` of a non-specular material, per unit solid angle (no cosine).
    fn eval(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> Rgb;

    /// Solid-angle density with which [`Bsdfs::sample`] produces `wi` given `wo` at a
    /// non-specular point.
    fn pdf(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> f64;

    /// Samples `wi` given `wo` from three uniform numbers in `[0, 1)`, or `None` if the
    /// sample is absorbed (e.g. below the surface). At a specular point the sample is a lobe,
    /// chosen with the probability returned in [`BsdfSample::pdf`].
    fn sample(&self, p: &SurfacePoint, wo: Vec3, u: [f64; 3]) -> Option<BsdfSample>;

    /// Continues through a specular point in `lobe`: the unique outgoing direction, or
    /// `None` if the lobe does not exist for `wo` (total internal reflection for refraction,
    /// or the material has no such lobe).
    fn specular_direction(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Option<Vec3>;

    /// The coefficient of the Dirac lobe with respect to projected solid angle (e.g. Fresnel
    /// `F` for reflection and `1 - F` for refraction, times a tint): what a specular vertex
    /// contributes to `f(x)`.
    fn specular_weight(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Rgb;

    /// The probability with which [`Bsdfs::sample`] chooses `lobe` given `wo`.
    fn specular_pdf(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> f64;

    /// The solid-angle Jacobian `dω_i / dω_o` of the specular map `wo -> wi =
    /// specular_direction(p, wo, lobe)` at the fixed point `p`: 1 for reflection,
    /// `(η_o / η_i)^2 cos θ_o / cos θ_i` for refraction (Snell's law in projected solid angle,
    /// Veach 1997, section 5.2; cosines about the shading normal). Light-side sampling needs it
    /// to convert densities across specular vertices into [`crate::Path`]'s measure.
    ///
    /// The default derives the index ratio from Snell's law on the directions themselves
    /// (`η_o / η_i = sin θ_i / sin θ_o`, probing a tilted direction near normal incidence); a
    /// scene that knows its indices should override it. 0 if the lobe does not exist.
    fn specular_jacobian(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> f64 {
        crate::lightside::snell_jacobian(self, p, wo, lobe)
    }
}

/// Light sources: emissive surfaces.
pub trait Emitters {
    /// Radiance emitted from `p` in direction `w` (toward the camera side of the path).
    fn emitted(&self, p: &SurfacePoint, w: Vec3) -> Rgb;

    /// True if `p` lies on an emitter, i.e. can end a path (a light vertex).
    fn is_emitter(&self, p: &SurfacePoint) -> bool;

    /// Samples a point on the emitters from three uniform numbers; returns it with its area
    /// density.
    fn sample_emitter(&self, u: [f64; 3]) -> Option<(SurfacePoint, f64)>;

    /// Area density with which [`Emitters::sample_emitter`] produces `p` (0 off the emitters).
    fn emitter_pdf(&self, p: &SurfacePoint) -> f64;

    /// Samples a direction of emission at the emitter point `p` from two uniform numbers:
    /// the first edge of a light subpath (Veach 1997, section 10.2). Returns the unit direction
    /// and its solid-angle density, or `None` if `p` emits nowhere.
    ///
    /// The default is cosine-weighted about the geometric normal on each side that emits
    /// (probed with [`Emitters::emitted`] along `±n_g`; both sides equally likely when both
    /// emit).
    fn sample_emission_direction(&self, p: &SurfacePoint, u: [f64; 2]) -> Option<(Vec3, f64)> {
        crate::lightside::cosine_emission_sample(self, p, u)
    }

    /// Solid-angle density with which [`Emitters::sample_emission_direction`] produces `w`
    /// at `p`.
    fn emission_direction_pdf(&self, p: &SurfacePoint, w: Vec3) -> f64 {
        crate::lightside::cosine_emission_pdf(self, p, w)
    }
}

/// A pinhole camera: the first path vertex, fixed (its area measure is a Dirac at
/// [`Camera::origin`]).
///
/// The raster is the unit square `[0, 1)^2`; the measurement of a raster region `R` is the
/// integral over `R` of the radiance arriving through it (so the whole image measures the
/// mean radiance over the raster).
pub trait Camera {
    /// The pinhole position.
    fn origin(&self) -> Vec3;

    /// The unit direction of the primary ray through raster point `raster`.
    fn direction(&self, raster: [f64; 2]) -> Vec3;

    /// The raster point of a direction from the origin, or `None` outside the image.
    fn raster(&self, dir: Vec3) -> Option<[f64; 2]>;

    /// Importance times the cosine at the lens, `W_e(w) cos(theta_1)`, per unit solid angle
    /// (0 outside the image). For raster measurement this equals [`Camera::direction_pdf`].
    fn importance(&self, dir: Vec3) -> f64;

    /// Solid-angle density of [`Camera::direction`] for a uniform raster point.
    fn direction_pdf(&self, dir: Vec3) -> f64;
}

/// Everything path-space MLT asks of a scene.
pub trait PathScene: RayTracer + Bsdfs + Emitters + Camera + Sync {}

impl<T: RayTracer + Bsdfs + Emitters + Camera + Sync> PathScene for T {}
