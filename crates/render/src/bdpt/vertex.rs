//! Path vertices of bidirectional path tracing and the densities MIS needs (Veach 1997,
//! chapter 10; pbrt-v3 section 16.3).

use glam::{Vec2, Vec3, Vec3A};

use super::scene_api::{self, SceneRef};
use crate::camera::Ray;
use crate::frame::{shading_consistent, Frame};
use crate::material::{Bsdf, TransportMode};

/// Maximum number of vertices of a subpath (max depth 62 + 2 endpoints).
pub const MAX_VERTICES: usize = 64;

/// The deepest path BDPT and the Markov chain methods over it render (bounces): a larger
/// `max_depth` is clamped to it.
pub const MAX_PATH_DEPTH: u32 = MAX_VERTICES as u32 - 2;

/// What a vertex is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// The camera (lens) endpoint.
    Camera,
    /// A light endpoint: a point sampled on an emitter (or at a punctual light) as the light
    /// subpath's origin, a light sampled for a connection, or the point at infinity a camera
    /// ray escaped to (environment).
    Light,
    /// A scattering point on a surface (possibly on an emitter).
    Surface,
}

/// One vertex of a camera or light subpath.
#[derive(Clone, Copy, Debug)]
pub struct Vertex {
    /// What the vertex is.
    pub kind: VertexKind,
    /// Position.
    pub p: Vec3A,
    /// Conservative floating-point error bound of `p` (for ray offsets).
    pub p_error: Vec3A,
    /// Geometric normal (zero for the camera).
    pub ng: Vec3A,
    /// Shading frame (z = shading normal); for lights the frame of the geometric normal.
    pub frame: Frame,
    /// Direction towards the previous vertex of the subpath (surfaces only).
    pub wo: Vec3A,
    /// The BSDF at a surface vertex.
    pub bsdf: Option<Bsdf>,
    /// Emitter id if the point lies on an emitter (or is a light endpoint).
    pub light: Option<u32>,
    /// Barycentrics `(b1, b2)` on the triangle (emissive textures of area lights).
    pub barycentrics: Vec2,
    /// A light endpoint at infinity (environment, directional light): `p` stands `2 R` away
    /// and densities towards it stay in solid angle (pbrt-v3 `IsInfiniteLight`).
    pub infinite: bool,
    /// A light endpoint of a delta light (point, spot, directional; pbrt-v3 `IsDeltaLight`).
    pub delta_light: bool,
    /// Subpath throughput up to and including this vertex (divided by its pdf).
    pub beta: Vec3,
    /// Area density of sampling this vertex from its predecessor (forward).
    pub pdf_fwd: f32,
    /// Area density of sampling this vertex from its successor (reverse).
    pub pdf_rev: f32,
    /// True if the vertex was sampled from a delta distribution (specular scattering).
    pub delta: bool,
    /// Time of the path (motion blur).
    pub time: f32,
}

impl Vertex {
    /// A camera vertex at lens point `p` with forward direction `forward`.
    pub fn camera(p: Vec3A, forward: Vec3A, beta: Vec3, time: f32) -> Self {
        Self {
            kind: VertexKind::Camera,
            p,
            p_error: Vec3A::ZERO,
            ng: Vec3A::ZERO,
            frame: Frame::from_normal(forward),
            wo: Vec3A::ZERO,
            bsdf: None,
            light: None,
            barycentrics: Vec2::ZERO,
            infinite: false,
            delta_light: false,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            time,
        }
    }

    /// A light vertex at `p` with geometric normal `n` (zero for lights not on a surface:
    /// punctual and infinite lights).
    pub fn light(p: Vec3A, n: Vec3A, light: u32, beta: Vec3, pdf_fwd: f32, time: f32) -> Self {
        Self {
            kind: VertexKind::Light,
            p,
            p_error: p.abs() * 1e-6,
            ng: n,
            frame: Frame::from_normal(if n == Vec3A::ZERO { Vec3A::Z } else { n }),
            wo: Vec3A::ZERO,
            bsdf: None,
            light: Some(light),
            barycentrics: Vec2::ZERO,
            infinite: false,
            delta_light: false,
            beta,
            pdf_fwd,
            pdf_rev: 0.0,
            delta: false,
            time,
        }
    }

    /// A ray leaving this vertex in direction `dir`, offset off its surface.
    #[inline]
    pub(crate) fn spawn_ray(&self, dir: Vec3A) -> Ray {
        let origin = if self.on_surface() {
            crate::bvh::offset_ray_origin(self.p, self.p_error, self.ng, dir)
        } else {
            self.p
        };
        Ray {
            origin,
            dir,
            time: self.time,
        }
    }

    /// The geometric normal for shadow-ray offsets: zero off surfaces (the camera).
    #[inline]
    fn offset_normal(&self) -> Vec3A {
        if self.on_surface() {
            self.ng
        } else {
            Vec3A::ZERO
        }
    }

    /// True for surface vertices (the only ones with a normal that converts densities):
    /// not the camera, nor punctual or infinite light endpoints.
    #[inline]
    pub fn on_surface(&self) -> bool {
        self.kind != VertexKind::Camera && self.ng != Vec3A::ZERO
    }

    /// Shading normal.
    #[inline]
    pub fn ns(&self) -> Vec3A {
        self.frame.n
    }

    /// True if the vertex can be connected to (non-delta scattering, or an endpoint).
    #[inline]
    pub fn is_connectible(&self) -> bool {
        match self.kind {
            VertexKind::Camera => true,
            // Directional lights are delta in direction: nothing connects to them.
            VertexKind::Light => !(self.infinite && self.delta_light),
            VertexKind::Surface => self.bsdf.is_some_and(|b| !b.is_specular()),
        }
    }

    /// True if the point lies on an emitter.
    #[inline]
    pub fn is_emissive(&self) -> bool {
        self.light.is_some()
    }

    /// BSDF value for light arriving from `next` and leaving towards `wo` (surfaces only). In
    /// importance transport (light subpaths) it includes Veach's shading-normal correction,
    /// as the random walk's throughput does (pbrt-v3 `Vertex::f` with `CorrectShadingNormal`):
    /// without it, connections through a light-subpath vertex whose shading normal differs
    /// from its geometric one (interpolated normals, normal maps) are biased.
    #[inline]
    pub fn f(&self, next: &Vertex, mode: TransportMode) -> Vec3 {
        let Some(bsdf) = self.bsdf else {
            return Vec3::ZERO;
        };
        let wi = (next.p - self.p).normalize_or_zero();
        if !shading_consistent(self.wo, wi, self.ng, self.ns()) {
            return Vec3::ZERO;
        }
        let f = bsdf.eval(self.frame.to_local(self.wo), self.frame.to_local(wi), mode);
        if mode == TransportMode::Importance && f != Vec3::ZERO {
            f * shading_normal_correction(self.wo, wi, self.ng, self.ns())
        } else {
            f
        }
    }

    /// Emitted radiance leaving this point towards the point `towards`.
    #[inline]
    pub fn emitted_towards(&self, scene: SceneRef<'_>, towards: Vec3A) -> Vec3 {
        match self.light {
            Some(_) if self.infinite && !self.delta_light => {
                scene_api::environment_le(scene, (self.p - towards).normalize_or_zero())
            }
            Some(l) if !self.delta_light => scene_api::area_le(
                scene,
                l,
                self.barycentrics,
                (towards - self.p).normalize_or_zero(),
            ),
            _ => Vec3::ZERO,
        }
    }

    /// Converts a solid-angle density at this vertex towards `next` into an area density at
    /// `next` (pbrt-v3 `Vertex::ConvertDensity`).
    #[inline]
    pub fn convert_density(&self, pdf: f32, next: &Vertex) -> f32 {
        if next.infinite {
            return pdf;
        }
        let w = next.p - self.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let inv_d2 = 1.0 / d2;
        let mut pdf = pdf;
        if next.on_surface() {
            pdf *= next.ng.dot(w * inv_d2.sqrt()).abs();
        }
        pdf * inv_d2
    }

    /// Area density at `next` of continuing the subpath from this vertex, having arrived from
    /// `prev` (pbrt-v3 `Vertex::Pdf`).
    pub fn pdf(&self, scene: SceneRef<'_>, prev: Option<&Vertex>, next: &Vertex) -> f32 {
        if self.kind == VertexKind::Light {
            return self.pdf_light(scene, next);
        }
        let wn = next.p - self.p;
        if wn.length_squared() == 0.0 {
            return 0.0;
        }
        let wn = wn.normalize();
        let pdf = match self.kind {
            VertexKind::Camera => {
                let ray = Ray {
                    origin: self.p,
                    dir: wn,
                    time: self.time,
                };
                scene_api::camera_pdf_dir(scene, &ray)
            }
            _ => {
                let (Some(bsdf), Some(prev)) = (self.bsdf, prev) else {
                    return 0.0;
                };
                let wp = (prev.p - self.p).normalize_or_zero();
                bsdf.pdf(
                    self.frame.to_local(wp),
                    self.frame.to_local(wn),
                    TransportMode::Radiance,
                )
            }
        };
        self.convert_density(pdf, next)
    }

    /// Area density at `next` of emitting from this light endpoint towards it, selection
    /// excluded (pbrt-v3 `Vertex::PdfLight`): the light's directional density over `d^2`
    /// times the cosine at `next`; for infinite lights the density `1 / (pi R^2)` of the
    /// emission disc times the cosine at `next`.
    pub fn pdf_light(&self, scene: SceneRef<'_>, next: &Vertex) -> f32 {
        let Some(light) = self.light else { return 0.0 };
        let w = next.p - self.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let w = w / d2.sqrt();
        let mut pdf = if self.infinite {
            scene_api::infinite_disc_pdf(scene)
        } else {
            scene_api::light_pdf_dir(scene, light, w) / d2
        };
        if next.on_surface() {
            pdf *= next.ng.dot(w).abs();
        }
        pdf
    }

    /// Density of sampling this light endpoint as a light-subpath origin emitting towards
    /// `next` (pbrt-v3 `PdfLightOrigin`): selection probability times the area density for
    /// area lights (times 1 for point and spot lights); for infinite lights the density of
    /// the emission direction (`InfiniteLightDensity`).
    pub fn pdf_light_origin(&self, scene: SceneRef<'_>, next: &Vertex) -> f32 {
        let Some(light) = self.light else { return 0.0 };
        if self.infinite {
            let dir = (next.p - self.p).normalize_or_zero();
            scene_api::infinite_origin_pdf(scene, light, dir)
        } else {
            scene_api::light_pdf_pos(scene, light)
        }
    }
}

/// Mutual visibility of two vertices.
#[inline]
pub(crate) fn visible(scene: SceneRef<'_>, a: &Vertex, b: &Vertex) -> bool {
    scene_api::visible(scene, a.p, a.offset_normal(), b.p, b.offset_normal())
}

/// Geometry term `G = |cos_0| |cos_1| / d^2` between two vertices, times visibility (pbrt-v3
/// `G`, using shading normals at surfaces).
pub fn geometry_term(scene: SceneRef<'_>, v0: &Vertex, v1: &Vertex) -> f32 {
    let d = v0.p - v1.p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    let dn = d / d2.sqrt();
    let mut g = 1.0 / d2;
    if v0.on_surface() {
        g *= v0.ns().dot(dn).abs();
    }
    if v1.on_surface() {
        g *= v1.ns().dot(dn).abs();
    }
    if g == 0.0 || !visible(scene, v0, v1) {
        return 0.0;
    }
    g
}

/// Veach's correction for shading normals in adjoint (importance) transport:
/// `|wo.ns| |wi.ng| / (|wo.ng| |wi.ns|)` (Veach 1997, eq. 5.19; pbrt-v3 section 16.1.3).
#[inline]
pub(crate) fn shading_normal_correction(wo: Vec3A, wi: Vec3A, ng: Vec3A, ns: Vec3A) -> f32 {
    let denom = wo.dot(ng).abs() * wi.dot(ns).abs();
    if denom == 0.0 {
        return 0.0;
    }
    wo.dot(ns).abs() * wi.dot(ng).abs() / denom
}
