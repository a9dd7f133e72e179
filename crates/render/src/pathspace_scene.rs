//! render's [`Scene`] seen through `pathspace`'s scene traits (f32 geometry, BVH and
//! materials; f64 at the boundary), for path-space MLT (`--integrator pathmlt`).
//!
//! # What pathmlt supports
//! `pathspace`'s model (Veach 1997, section 8.2; docs/methods/pathspace-mlt.md) is a pinhole
//! camera, emissive surfaces (area lights), and materials that are either purely specular
//! (Dirac lobes only) or purely non-specular. [`PathSpaceScene::new`] maps render's scene onto
//! it and refuses, with an error naming the feature, what it cannot represent:
//!
//! - a thin-lens camera (the camera node's `aperture_radius` extra) or a moving camera (the lens perturbation of RA 3.3
//!   needs a fixed pinhole vertex `x_1`);
//! - punctual lights (`KHR_lights_punctual`: point, spot, directional) and environment lights
//!   (including the default environment of a scene without lights: pass `--env none`), which
//!   are not surfaces a path can end on.
//!
//! render's BSDFs are each one closed family (`Bsdf::from_gltf_params` never mixes a specular
//! coat with a diffuse base), so the specular/non-specular split is exact: smooth conductors
//! and smooth dielectrics are specular (their lobes, directions, weights and probabilities
//! come from the same `Bsdf::sample` the other integrators use), Lambertian, rough conductors
//! and rough dielectrics are non-specular. Textures, vertex colours, alpha masks, normal maps
//! and textured emission are supported (the BSDF is looked up at the vertex).
//!
//! # Conventions
//! - The opaque material handle of a [`SurfacePoint`] is render's triangle index; barycentrics
//!   (for textures and emission) are recomputed from the position.
//! - Shading normals: `eval` returns `f_s(wo, wi) |n_s . wi| / |n_g . wi|` and zero where the
//!   shading and geometric hemispheres disagree ([`crate::frame::shading_consistent`]), so that
//!   `pathspace`'s `f(x)` (which converts measures with geometric normals) equals the
//!   radiance-transport contribution render's path tracer and BDPT estimate (Veach 1997,
//!   section 5.3: camera subpaths use the shading cosine at the scattering vertex). With flat
//!   shading the factor is 1.
//! - Rays leave surface points offset by a scene-relative epsilon along their direction (the
//!   traits give positions, not error bounds): surfaces closer than that to a vertex are
//!   missed, a bias of the order of f32 resolution.
//! - Radiance is carried in TransportMode::Radiance (the `1 / eta^2` of refraction included),
//!   as in render's camera subpaths.

use glam::{Vec2, Vec3 as GVec3, Vec3A};
use pathspace::{
    BsdfSample, Bsdfs, Camera, Emitters, RayTracer, Rgb, SpecularLobe, SurfacePoint, Vec3,
};

use crate::camera::Ray;
use crate::error::RenderError;
use crate::frame::{shading_consistent, Frame};
use crate::material::{Bsdf, TransportMode};
use crate::scene::{Scene, SurfaceInteraction};

/// Relative epsilon (of the scene's largest coordinate) by which rays leave surface points.
const RAY_EPSILON: f64 = 2e-5;

/// render's [`Scene`] implementing `pathspace`'s [`RayTracer`], [`Bsdfs`], [`Emitters`] and
/// [`Camera`] (a pinhole), i.e. a `pathspace::PathScene`. See the module docs for what it
/// supports.
#[derive(Clone, Copy, Debug)]
pub struct PathSpaceScene<'a> {
    scene: &'a Scene,
    origin: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    /// Half extents of the film at distance 1.
    half: [f64; 2],
    /// Film area at distance 1 (`We = 1 / (A cos^4)`, render's camera module).
    film_area: f64,
    /// Absolute ray offset.
    epsilon: f64,
}

fn to_vec3(v: Vec3A) -> Vec3 {
    Vec3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

fn to_vec3a(v: Vec3) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

fn to_rgb(c: GVec3) -> Rgb {
    Rgb([f64::from(c.x), f64::from(c.y), f64::from(c.z)])
}

impl<'a> PathSpaceScene<'a> {
    /// The pathspace view of `scene` (its camera at its current resolution).
    ///
    /// # Errors
    /// [`RenderError::InvalidSetting`] naming the feature pathmlt does not support: a thin-lens
    /// or moving camera, punctual lights, an environment light (module docs).
    pub fn new(scene: &'a Scene) -> Result<Self, RenderError> {
        let camera = scene.camera();
        if camera.lens_radius() > 0.0 {
            return Err(RenderError::setting(
                "integrator",
                "pathmlt",
                "a pinhole camera (pathmlt supports a pinhole only: remove the camera node's \
                 `aperture_radius` / `focus_distance` extras from the scene, set \
                 `aperture_radius` to 0, or pick another --integrator)",
            ));
        }
        let (open, close) = camera.shutter();
        let pose = camera.pose_at(open);
        if pose != camera.pose_at(close) {
            return Err(RenderError::setting(
                "integrator",
                "pathmlt",
                "a static camera (pathmlt does not support camera motion)",
            ));
        }
        if !scene.lights().punctual().is_empty() {
            return Err(RenderError::setting(
                "integrator",
                "pathmlt",
                "area lights only (pathmlt does not support punctual point, spot or directional lights)",
            ));
        }
        if scene.lights().environment().is_some() {
            return Err(RenderError::setting(
                "integrator",
                "pathmlt",
                "area lights only (pathmlt does not support environment lights; a scene without lights gets a default environment: pass --env none)",
            ));
        }
        let (w, h) = (f64::from(camera.width()), f64::from(camera.height()));
        let film_area = f64::from(camera.film_area());
        // A = 4 hw hh and hw / hh = w / h (render's camera module).
        let hh = (film_area * h / w).sqrt() / 2.0;
        let hw = hh * w / h;
        let extent = scene.bounds().map_or(1.0, |(lo, hi)| {
            f64::from(lo.abs().max(hi.abs()).max_element()).max(1e-3)
        });
        Ok(Self {
            scene,
            origin: to_vec3(pose.origin),
            right: to_vec3(pose.right),
            up: to_vec3(pose.up),
            forward: to_vec3(pose.forward),
            half: [hw, hh],
            film_area,
            epsilon: RAY_EPSILON * extent,
        })
    }

    /// The wrapped scene.
    #[must_use]
    pub fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// The absolute distance by which rays leave surface points.
    #[must_use]
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// Barycentrics `(b1, b2)` of `p` in triangle `tri` (projected onto its plane).
    fn barycentrics(&self, tri: usize, p: Vec3A) -> Vec2 {
        let [a, b, c] = self.scene.mesh().vertices(tri);
        let (e1, e2, d) = (b - a, c - a, p - a);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1, d2) = (d.dot(e1), d.dot(e2));
        let det = d11 * d22 - d12 * d12;
        if det == 0.0 || !det.is_finite() {
            return Vec2::splat(1.0 / 3.0);
        }
        let b1 = (d22 * d1 - d12 * d2) / det;
        let b2 = (d11 * d2 - d12 * d1) / det;
        Vec2::new(b1.clamp(0.0, 1.0), b2.clamp(0.0, 1.0))
    }

    /// The surface interaction of a path vertex (what render's BSDF lookup needs).
    fn interaction(&self, p: &SurfacePoint) -> Option<SurfaceInteraction> {
        let tri = p.material as usize;
        let mesh = self.scene.mesh();
        if tri >= mesh.triangle_count() {
            return None;
        }
        let position = to_vec3a(p.position);
        let b = self.barycentrics(tri, position);
        Some(SurfaceInteraction {
            p: position,
            p_error: Vec3A::ZERO,
            t: 0.0,
            ng: to_vec3a(p.geometric_normal),
            ns: to_vec3a(p.shading_normal),
            uv: mesh.uv_at(tri, b),
            barycentrics: b,
            triangle: tri as u32,
            material: mesh.material_ids[tri],
            wo: Vec3A::ZERO,
        })
    }

    /// The BSDF and shading frame at a vertex.
    fn bsdf(&self, p: &SurfacePoint) -> Option<(Bsdf, Frame)> {
        let si = self.interaction(p)?;
        Some((self.scene.bsdf(&si), Frame::from_normal(si.ns)))
    }

    /// The surface point of triangle `tri` at position `p` and barycentrics `b` as the ray
    /// tracer would report it (for sampled emitter points).
    fn surface_point(&self, tri: u32, p: Vec3A, b: Vec2) -> SurfacePoint {
        let mesh = self.scene.mesh();
        let t = tri as usize;
        let [p0, p1, p2] = mesh.vertices(t);
        let ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let [i0, i1, i2] = mesh.triangles[t].map(|i| i as usize);
        let b0 = (1.0 - b.x - b.y).max(0.0);
        let n = &mesh.normals;
        let ns = match (n[i0] * b0 + n[i1] * b.x + n[i2] * b.y).try_normalize() {
            Some(ns) if ns.dot(ng) < 0.0 => -ns,
            Some(ns) => ns,
            None => ng,
        };
        SurfacePoint {
            position: to_vec3(p),
            shading_normal: to_vec3(ns),
            geometric_normal: to_vec3(ng),
            material: tri,
        }
    }

    /// The specular sample of `lobe` at `p` from `wo`: render's `Bsdf::sample` with the lobe
    /// forced through its uniform number (`u = 0` picks reflection, `u -> 1` refraction, see
    /// `SmoothDielectric::sample`); `None` if the sample is the other lobe (the forced one
    /// does not exist: no reflectance, total internal reflection, or a conductor asked to
    /// refract). Returns the world direction, the weight `f |cos|` and the lobe probability.
    fn specular_sample(
        &self,
        p: &SurfacePoint,
        wo: Vec3,
        lobe: SpecularLobe,
    ) -> Option<(Vec3, Rgb, f64)> {
        let (bsdf, frame) = self.bsdf(p)?;
        if !bsdf.is_specular() {
            return None;
        }
        let wo_l = frame.to_local(to_vec3a(wo));
        let u = match lobe {
            SpecularLobe::Reflection => 0.0,
            SpecularLobe::Refraction => 1.0f32.next_down(),
        };
        let s = bsdf.sample(wo_l, u, Vec2::ZERO, TransportMode::Radiance)?;
        let reflects = s.wi.z * wo_l.z > 0.0;
        if reflects != (lobe == SpecularLobe::Reflection) || s.pdf.is_nan() || s.pdf <= 0.0 {
            return None;
        }
        let wi = to_vec3(frame.to_world(s.wi)).try_normalize()?;
        Some((wi, to_rgb(s.f * s.wi.z.abs()), f64::from(s.pdf)))
    }

    /// Camera-space coordinates of a world direction.
    fn camera_coordinates(&self, dir: Vec3) -> Vec3 {
        Vec3::new(dir.dot(self.right), dir.dot(self.up), dir.dot(self.forward))
    }
}

impl RayTracer for PathSpaceScene<'_> {
    fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<SurfacePoint> {
        let o = origin + dir * self.epsilon;
        let ray = Ray::new(to_vec3a(o), to_vec3a(dir), self.scene.camera().shutter().0);
        let si = self.scene.intersect(&ray)?;
        Some(SurfacePoint {
            position: to_vec3(si.p),
            shading_normal: to_vec3(si.ns),
            geometric_normal: to_vec3(si.ng),
            material: si.triangle,
        })
    }

    fn visible(&self, a: Vec3, b: Vec3) -> bool {
        let d = b - a;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return false;
        }
        if dist <= 2.0 * self.epsilon {
            return true;
        }
        let dir = d / dist;
        let (oa, ob) = (a + dir * self.epsilon, b - dir * self.epsilon);
        self.scene
            .unoccluded_between(to_vec3a(oa), Vec3A::ZERO, to_vec3a(ob), Vec3A::ZERO)
    }
}

impl Bsdfs for PathSpaceScene<'_> {
    fn is_specular(&self, p: &SurfacePoint) -> bool {
        self.bsdf(p).is_some_and(|(b, _)| b.is_specular())
    }

    fn eval(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> Rgb {
        let Some((bsdf, frame)) = self.bsdf(p) else {
            return Rgb::BLACK;
        };
        let (wo_w, wi_w) = (to_vec3a(wo), to_vec3a(wi));
        let ng = to_vec3a(p.geometric_normal);
        if !shading_consistent(wo_w, wi_w, ng, frame.n) {
            return Rgb::BLACK;
        }
        let cos_g = wi.dot(p.geometric_normal).abs();
        if cos_g.is_nan() || cos_g <= 0.0 {
            return Rgb::BLACK;
        }
        let f = bsdf.eval(
            frame.to_local(wo_w),
            frame.to_local(wi_w),
            TransportMode::Radiance,
        );
        let shading = wi.dot(p.shading_normal).abs() / cos_g;
        let c = to_rgb(f);
        Rgb([c.0[0] * shading, c.0[1] * shading, c.0[2] * shading])
    }

    fn pdf(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> f64 {
        let Some((bsdf, frame)) = self.bsdf(p) else {
            return 0.0;
        };
        f64::from(bsdf.pdf(
            frame.to_local(to_vec3a(wo)),
            frame.to_local(to_vec3a(wi)),
            TransportMode::Radiance,
        ))
    }

    fn sample(&self, p: &SurfacePoint, wo: Vec3, u: [f64; 3]) -> Option<BsdfSample> {
        let (bsdf, frame) = self.bsdf(p)?;
        let wo_l = frame.to_local(to_vec3a(wo));
        let uf = u.map(|x| (x as f32).min(1.0f32.next_down()));
        let s = bsdf.sample(
            wo_l,
            uf[0],
            Vec2::new(uf[1], uf[2]),
            TransportMode::Radiance,
        )?;
        if s.pdf.is_nan() || s.pdf <= 0.0 {
            return None;
        }
        let wi = to_vec3(frame.to_world(s.wi)).try_normalize()?;
        let lobe = s.is_specular.then(|| {
            if s.wi.z * wo_l.z > 0.0 {
                SpecularLobe::Reflection
            } else {
                SpecularLobe::Refraction
            }
        });
        let pdf = if s.is_specular {
            f64::from(s.pdf)
        } else {
            // The density pathspace will evaluate for this direction (f64 round trip).
            self.pdf(p, wo, wi)
        };
        (pdf > 0.0).then_some(BsdfSample { wi, pdf, lobe })
    }

    fn specular_direction(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Option<Vec3> {
        self.specular_sample(p, wo, lobe).map(|s| s.0)
    }

    fn specular_weight(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Rgb {
        self.specular_sample(p, wo, lobe)
            .map_or(Rgb::BLACK, |s| s.1)
    }

    fn specular_pdf(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> f64 {
        self.specular_sample(p, wo, lobe).map_or(0.0, |s| s.2)
    }
}

impl Emitters for PathSpaceScene<'_> {
    fn emitted(&self, p: &SurfacePoint, w: Vec3) -> Rgb {
        let Some(light) = self.scene.lights().light_of_triangle(p.material) else {
            return Rgb::BLACK;
        };
        let b = self.barycentrics(p.material as usize, to_vec3a(p.position));
        to_rgb(self.scene.area_le(light, b, to_vec3a(w)))
    }

    fn is_emitter(&self, p: &SurfacePoint) -> bool {
        self.scene.lights().light_of_triangle(p.material).is_some()
    }

    fn sample_emitter(&self, u: [f64; 3]) -> Option<(SurfacePoint, f64)> {
        let lights = self.scene.lights();
        let (index, pmf) = lights.select((u[0] as f32).min(1.0f32.next_down()))?;
        let light = lights.lights().get(index as usize)?;
        if light.area.is_nan() || light.area <= 0.0 {
            return None;
        }
        let (p, b) = light.sample_point_bary(Vec2::new(u[1] as f32, u[2] as f32));
        let point = self.surface_point(light.triangle, p, b);
        Some((point, f64::from(pmf) / f64::from(light.area)))
    }

    fn emitter_pdf(&self, p: &SurfacePoint) -> f64 {
        let lights = self.scene.lights();
        let Some(index) = lights.light_of_triangle(p.material) else {
            return 0.0;
        };
        match lights.lights().get(index as usize) {
            Some(light) if light.area > 0.0 => {
                f64::from(lights.selection_pmf(index)) / f64::from(light.area)
            }
            _ => 0.0,
        }
    }
}

impl Camera for PathSpaceScene<'_> {
    fn origin(&self) -> Vec3 {
        self.origin
    }

    fn direction(&self, raster: [f64; 2]) -> Vec3 {
        let x = (2.0 * raster[0] - 1.0) * self.half[0];
        let y = (1.0 - 2.0 * raster[1]) * self.half[1];
        (self.right * x + self.up * y + self.forward).normalize()
    }

    fn raster(&self, dir: Vec3) -> Option<[f64; 2]> {
        let c = self.camera_coordinates(dir);
        if c.z.is_nan() || c.z <= 0.0 {
            return None;
        }
        let u = 0.5 * (c.x / (c.z * self.half[0]) + 1.0);
        let v = 0.5 * (1.0 - c.y / (c.z * self.half[1]));
        ((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)).then_some([u, v])
    }

    fn importance(&self, dir: Vec3) -> f64 {
        self.direction_pdf(dir)
    }

    fn direction_pdf(&self, dir: Vec3) -> f64 {
        if self.raster(dir).is_none() {
            return 0.0;
        }
        let cos = self.camera_coordinates(dir).z / dir.length();
        1.0 / (self.film_area * cos * cos * cos)
    }
}
