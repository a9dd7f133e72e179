//! Scenes: a world-space triangle mesh with glTF metallic-roughness materials, textures, a
//! camera, area lights and a BVH, loaded from glTF 2.0 or built in (the Cornell box).
//!
//! # Example
//! ```
//! use render::scene::Scene;
//! let scene = Scene::cornell_box(64, 64);
//! let ray = scene.camera().generate_ray(glam::Vec2::new(32.0, 32.0), glam::Vec2::ZERO, 0.0);
//! let hit = scene.intersect(&ray).expect("the camera looks into the box");
//! assert!(hit.t > 0.0);
//! ```

mod builtin;
mod gltf_load;
/// Triangle meshes: a leaf module (the BVH and the lights use it), re-exported here.
pub use crate::mesh;
pub mod texture;

use std::path::Path;

use glam::{Mat4, Vec2, Vec3, Vec3A};

use crate::bvh::{gamma, offset_ray_origin, Bvh};
use crate::camera::{Camera, Ray};
use crate::error::RenderError;
use crate::light::Lights;
use crate::material::Bsdf;
pub use mesh::Mesh;
pub use texture::{Texture, TextureFilter, WrapMode};

/// A glTF metallic-roughness material (with the transmission, IOR and emissive-strength
/// extensions). The BSDF at a hit is [`Bsdf::from_gltf_params`] of these values, with the
/// base colour multiplied by the base-colour texture at the hit's UV.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the file (may be empty).
    pub name: String,
    /// Linear base colour (`pbrMetallicRoughness.baseColorFactor`, alpha dropped).
    pub base_color: Vec3,
    /// Index into [`Scene::textures`] of the base-colour texture, if any.
    pub base_color_texture: Option<u32>,
    /// `pbrMetallicRoughness.metallicFactor` in `[0, 1]`.
    pub metallic: f32,
    /// `pbrMetallicRoughness.roughnessFactor` in `[0, 1]` (perceptual; GGX alpha = roughness²).
    pub roughness: f32,
    /// `KHR_materials_transmission.transmissionFactor` in `[0, 1]`.
    pub transmission: f32,
    /// `KHR_materials_ior.ior` (default 1.5).
    pub ior: f32,
    /// Emitted radiance: `emissiveFactor × KHR_materials_emissive_strength.emissiveStrength`.
    pub emission: Vec3,
    /// glTF `doubleSided`: emitters with this flag emit from both sides.
    pub double_sided: bool,
}

impl Default for Material {
    /// glTF's default material: white, fully rough dielectric (`metallic` 1 in glTF, but a
    /// renderer's missing material is conventionally a grey diffuse; we use 0.8 Lambertian).
    fn default() -> Self {
        Self {
            name: String::new(),
            base_color: Vec3::splat(0.8),
            base_color_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            transmission: 0.0,
            ior: 1.5,
            emission: Vec3::ZERO,
            double_sided: false,
        }
    }
}

impl Material {
    /// A Lambertian material of albedo `albedo` emitting `emission`.
    #[must_use]
    pub fn diffuse(name: &str, albedo: Vec3, emission: Vec3) -> Self {
        Self {
            name: name.to_owned(),
            base_color: albedo,
            emission,
            ..Self::default()
        }
    }

    /// The BSDF for base colour `base_color` (the factor times the texture value).
    #[must_use]
    pub fn bsdf_with(&self, base_color: Vec3) -> Bsdf {
        Bsdf::from_gltf_params(
            base_color,
            self.metallic,
            self.roughness,
            self.transmission,
            self.ior,
        )
    }
}

/// Where a camera sits, before the image size is known: [`CameraSpec::build`] makes the
/// [`Camera`] for a resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    /// Eye point.
    pub from: Vec3A,
    /// Look-at point.
    pub to: Vec3A,
    /// Up vector.
    pub up: Vec3A,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
    /// Thin lens `(aperture_radius, focus_distance)`, or `None` for a pinhole.
    pub thin_lens: Option<(f32, f32)>,
    /// Linear motion `(end_from, end_to, shutter_open, shutter_close)`, if any.
    pub motion: Option<(Vec3A, Vec3A, f32, f32)>,
}

impl CameraSpec {
    /// A pinhole camera at `from` looking at `to`.
    #[must_use]
    pub fn look_at(from: Vec3A, to: Vec3A, up: Vec3A, vfov_deg: f32) -> Self {
        Self {
            from,
            to,
            up,
            vfov_deg,
            thin_lens: None,
            motion: None,
        }
    }

    /// A pinhole camera from a glTF camera node's world transform (looking down local `-z`,
    /// `+y` up) and vertical field of view in radians.
    #[must_use]
    pub fn from_matrix(world_from_camera: Mat4, yfov_rad: f32) -> Self {
        let origin = Vec3A::from(world_from_camera.transform_point3(Vec3::ZERO));
        let forward = Vec3A::from(world_from_camera.transform_vector3(Vec3::NEG_Z));
        let up = Vec3A::from(world_from_camera.transform_vector3(Vec3::Y));
        match forward.try_normalize() {
            Some(f) if origin.is_finite() && up.is_finite() => {
                Self::look_at(origin, origin + f, up, yfov_rad.to_degrees())
            }
            _ => Self::look_at(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, yfov_rad.to_degrees()),
        }
    }

    /// A camera framing the box `(lo, hi)`: looking along `-z` at its centre from far enough
    /// that the bounding sphere fits a 45° vertical field of view.
    #[must_use]
    pub fn framing(lo: Vec3A, hi: Vec3A) -> Self {
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let vfov = 45.0f32;
        let dist = radius / (vfov.to_radians() * 0.5).sin() * 1.05;
        Self::look_at(center + Vec3A::Z * dist, center, Vec3A::Y, vfov)
    }

    /// The camera for a `width x height` image.
    #[must_use]
    pub fn build(&self, width: u32, height: u32) -> Camera {
        let mut c = Camera::perspective(self.from, self.to, self.up, self.vfov_deg, width, height);
        if let Some((radius, focus)) = self.thin_lens {
            c = c.with_thin_lens(radius, focus);
        }
        if let Some((end_from, end_to, open, close)) = self.motion {
            c = c.with_motion(end_from, end_to, open, close);
        }
        c
    }
}

/// A ray-surface intersection with everything shading needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceInteraction {
    /// Hit point.
    pub p: Vec3A,
    /// Conservative absolute error bound of `p` per axis (for ray offsetting).
    pub p_error: Vec3A,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Unit geometric normal of the triangle's front side (glTF counter-clockwise winding).
    pub ng: Vec3A,
    /// Unit shading normal (interpolated vertex normals, in the hemisphere of `ng`; `ng` when
    /// the mesh has none).
    pub ns: Vec3A,
    /// Interpolated texture coordinates.
    pub uv: Vec2,
    /// Barycentrics `(b1, b2)` of the hit.
    pub barycentrics: Vec2,
    /// Mesh triangle index.
    pub triangle: u32,
    /// Material index into [`Scene::materials`].
    pub material: u32,
    /// Unit direction back along the incoming ray (`-ray.dir`).
    pub wo: Vec3A,
}

impl SurfaceInteraction {
    /// A ray leaving the surface in direction `dir`, its origin offset to the side of `dir` so
    /// it cannot re-hit this surface.
    #[inline]
    #[must_use]
    pub fn spawn_ray(&self, dir: Vec3A, time: f32) -> Ray {
        Ray {
            origin: offset_ray_origin(self.p, self.p_error, self.ng, dir),
            dir,
            time,
        }
    }
}

/// A renderable scene: mesh, materials, textures, camera, lights and BVH.
#[derive(Clone, Debug)]
pub struct Scene {
    mesh: Mesh,
    materials: Vec<Material>,
    textures: Vec<Texture>,
    /// BSDF of each untextured material, built once.
    bsdfs: Vec<Option<Bsdf>>,
    camera_spec: CameraSpec,
    camera: Camera,
    lights: Lights,
    bvh: Bvh,
    /// Problems that did not prevent loading (unsupported glTF features, dropped triangles).
    pub warnings: Vec<String>,
}

/// Relative shortening of shadow rays at their far end (the end point is on another surface
/// whose error bound is unknown).
const SHADOW_EPSILON: f32 = 1e-4;

impl Scene {
    /// Builds a scene: cleans the mesh ([`Mesh::remove_invalid`], warning about what was
    /// dropped), replaces out-of-range material and texture indices by a default material,
    /// then builds the BVH and the light list. The camera renders `width x height` until
    /// [`Scene::set_resolution`].
    #[must_use]
    pub fn new(
        mut mesh: Mesh,
        mut materials: Vec<Material>,
        textures: Vec<Texture>,
        camera: CameraSpec,
        width: u32,
        height: u32,
    ) -> Self {
        let mut warnings = Vec::new();
        let removed = mesh.remove_invalid();
        if removed > 0 {
            warnings.push(format!(
                "{removed} degenerate or non-finite triangle(s) were skipped"
            ));
        }
        for m in &mut materials {
            if m.base_color_texture
                .is_some_and(|t| t as usize >= textures.len())
            {
                warnings.push(format!(
                    "material '{}' refers to a missing texture; it is ignored",
                    m.name
                ));
                m.base_color_texture = None;
            }
            if !m.emission.is_finite() {
                m.emission = Vec3::ZERO;
            }
        }
        if mesh
            .material_ids
            .iter()
            .any(|&m| m as usize >= materials.len())
        {
            let fallback = materials.len() as u32;
            materials.push(Material {
                name: "default".to_owned(),
                ..Material::default()
            });
            for m in &mut mesh.material_ids {
                if *m >= fallback {
                    *m = fallback;
                }
            }
        }
        let bsdfs = materials
            .iter()
            .map(|m| {
                m.base_color_texture
                    .is_none()
                    .then(|| m.bsdf_with(m.base_color))
            })
            .collect();
        let lights = Lights::build(&mesh, |id| {
            let m = &materials[id as usize];
            (m.emission, m.double_sided)
        });
        let bvh = Bvh::build(&mesh);
        if mesh.triangle_count() == 0 {
            warnings.push("the scene has no triangles: the image will be black".to_owned());
        } else if lights.is_empty() {
            warnings.push("the scene has no emissive triangle: the image will be black".to_owned());
        }
        Self {
            mesh,
            materials,
            textures,
            bsdfs,
            camera_spec: camera,
            camera: camera.build(width, height),
            lights,
            bvh,
            warnings,
        }
    }

    /// Loads a `.gltf` (with external or embedded buffers and images) or `.glb` file.
    ///
    /// # Errors
    /// [`RenderError::Io`] if the file cannot be read, [`RenderError::UnsupportedFormat`] for
    /// other extensions, [`RenderError::Gltf`] naming the file and the reason for malformed
    /// content. Unsupported features only add to [`Scene::warnings`].
    pub fn load(path: &Path) -> Result<Self, RenderError> {
        gltf_load::load_path(path)
    }

    /// Loads glTF or GLB bytes; relative URIs are resolved against `base_dir` (none: only
    /// embedded data and the GLB binary chunk are available).
    ///
    /// # Errors
    /// As [`Scene::load`], with the file named `<memory>`.
    pub fn from_gltf_slice(bytes: &[u8], base_dir: Option<&Path>) -> Result<Self, RenderError> {
        gltf_load::load_slice(bytes, base_dir, "<memory>")
    }

    /// The built-in Cornell box (the default scene): white, red and green diffuse walls, a
    /// tall and a short white box, one area light below the ceiling. Dimensions are the
    /// classic Cornell data (555 units) scaled to metres.
    #[must_use]
    pub fn cornell_box(width: u32, height: u32) -> Self {
        builtin::cornell_box(width, height)
    }

    /// Sets the image size the camera renders.
    pub fn set_resolution(&mut self, width: u32, height: u32) {
        self.camera = self.camera_spec.build(width, height);
    }

    /// The camera at the current resolution.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The camera description (pose, lens, motion) independent of the resolution.
    #[must_use]
    pub fn camera_spec(&self) -> &CameraSpec {
        &self.camera_spec
    }

    /// The mesh.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The materials.
    #[must_use]
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The textures.
    #[must_use]
    pub fn textures(&self) -> &[Texture] {
        &self.textures
    }

    /// The area lights.
    #[must_use]
    pub fn lights(&self) -> &Lights {
        &self.lights
    }

    /// The bounding box of the geometry, if any.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3A, Vec3A)> {
        self.mesh.bounds()
    }

    /// The closest surface hit by `ray` (any `t > 0`).
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let hit = self.bvh.intersect(ray.origin, ray.dir, f32::INFINITY)?;
        let tri = hit.triangle as usize;
        let [i0, i1, i2] = self.mesh.triangles[tri].map(|i| i as usize);
        let [p0, p1, p2] = [
            self.mesh.positions[i0],
            self.mesh.positions[i1],
            self.mesh.positions[i2],
        ];
        let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
        let b0 = (1.0 - b1 - b2).max(0.0);
        let p = p0 * b0 + p1 * b1 + p2 * b2;
        let p_error = ((p0 * b0).abs() + (p1 * b1).abs() + (p2 * b2).abs()) * gamma(7);
        let ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let n = &self.mesh.normals;
        let ns = n[i0] * b0 + n[i1] * b1 + n[i2] * b2;
        let ns = match ns.try_normalize() {
            Some(ns) if ns.dot(ng) < 0.0 => -ns,
            Some(ns) => ns,
            None => ng,
        };
        let uv = self.mesh.uvs[i0] * b0 + self.mesh.uvs[i1] * b1 + self.mesh.uvs[i2] * b2;
        Some(SurfaceInteraction {
            p,
            p_error,
            t: hit.t,
            ng,
            ns,
            uv,
            barycentrics: hit.barycentrics,
            triangle: hit.triangle,
            material: self.mesh.material_ids[tri],
            wo: -ray.dir,
        })
    }

    /// True if nothing blocks the segment from surface point `from` to the point `to` (which
    /// is assumed to lie on a surface: the far end is shortened by a relative epsilon).
    #[inline]
    #[must_use]
    pub fn unoccluded(&self, from: &SurfaceInteraction, to: Vec3A) -> bool {
        let dir = to - from.p;
        let origin = offset_ray_origin(from.p, from.p_error, from.ng, dir);
        let d = to - origin;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return false;
        }
        !self
            .bvh
            .occluded(origin, d / dist, dist * (1.0 - SHADOW_EPSILON))
    }

    /// True if nothing blocks the segment between two points on surfaces, both ends offset
    /// along their geometric normals (`n_a`, `n_b`; zero for points not on a surface, e.g. a
    /// camera lens).
    #[inline]
    #[must_use]
    pub fn unoccluded_between(&self, a: Vec3A, n_a: Vec3A, b: Vec3A, n_b: Vec3A) -> bool {
        let err = |p: Vec3A| p.abs() * gamma(7) + Vec3A::splat(1e-6);
        let oa = offset_ray_origin(a, err(a), n_a, b - a);
        let ob = offset_ray_origin(b, err(b), n_b, a - b);
        let d = ob - oa;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return false;
        }
        !self
            .bvh
            .occluded(oa, d / dist, dist * (1.0 - SHADOW_EPSILON))
    }

    /// The BSDF at a surface point (in the local frame of its shading normal).
    #[inline]
    #[must_use]
    pub fn bsdf(&self, si: &SurfaceInteraction) -> Bsdf {
        let id = si.material as usize;
        if let Some(b) = self.bsdfs[id] {
            return b;
        }
        let m = &self.materials[id];
        let tex = m
            .base_color_texture
            .map_or(Vec3::ONE, |t| self.textures[t as usize].sample(si.uv));
        m.bsdf_with(m.base_color * tex)
    }

    /// Radiance emitted by the surface at `si` towards `w` (zero for non-emitters and for the
    /// back of one-sided emitters).
    #[inline]
    #[must_use]
    pub fn emitted(&self, si: &SurfaceInteraction, w: Vec3A) -> Vec3 {
        match self.lights.light_of_triangle(si.triangle) {
            Some(l) => self.lights.lights()[l as usize].le(w),
            None => Vec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_scene_is_black_not_broken() {
        let s = Scene::new(
            Mesh::new(),
            vec![],
            vec![],
            CameraSpec::look_at(Vec3A::Z, Vec3A::ZERO, Vec3A::Y, 40.0),
            8,
            8,
        );
        assert!(s.lights().is_empty());
        assert!(s.warnings.iter().any(|w| w.contains("no triangles")));
        let ray = s.camera().generate_ray(Vec2::splat(4.0), Vec2::ZERO, 0.0);
        assert!(s.intersect(&ray).is_none());
    }

    #[test]
    fn out_of_range_material_gets_default() {
        let mut m = Mesh::new();
        m.add_quad(
            [
                Vec3A::new(-1.0, -1.0, 0.0),
                Vec3A::new(1.0, -1.0, 0.0),
                Vec3A::new(1.0, 1.0, 0.0),
                Vec3A::new(-1.0, 1.0, 0.0),
            ],
            7,
        );
        let s = Scene::new(
            m,
            vec![Material::default()],
            vec![],
            CameraSpec::look_at(Vec3A::Z * 3.0, Vec3A::ZERO, Vec3A::Y, 40.0),
            8,
            8,
        );
        assert_eq!(s.materials().len(), 2);
        let ray = s.camera().generate_ray(Vec2::splat(4.0), Vec2::ZERO, 0.0);
        let si = s.intersect(&ray).unwrap();
        assert_eq!(si.material, 1);
        assert!((si.ng - Vec3A::Z).length() < 1e-6);
        assert!((si.t - 3.0).abs() < 1e-5);
        let _ = s.bsdf(&si);
    }

    /// Shadow rays from surface points to an unblocked light are never occluded by the surface
    /// they start on (Cornell-box scale, where offsets are ~1e-7), nor rays leaving it.
    #[test]
    fn no_self_shadowing() {
        use crate::sampler::{IndependentSampler, Sampler};
        let mut m = Mesh::new();
        let q = |y: f32, s: f32| {
            [
                Vec3A::new(0.0, y, 0.0),
                Vec3A::new(0.0, y, s),
                Vec3A::new(s, y, s),
                Vec3A::new(s, y, 0.0),
            ]
        };
        m.add_quad(q(0.0, 0.5559), 0); // floor, facing +y
        let mut light = q(0.5487, 0.5559);
        light.reverse(); // facing -y
        m.add_quad(light, 1);
        let scene = Scene::new(
            m,
            vec![
                Material::default(),
                Material::diffuse("light", Vec3::ZERO, Vec3::ONE),
            ],
            vec![],
            CameraSpec::look_at(
                Vec3A::new(0.278, 0.45, 0.278),
                Vec3A::new(0.278, 0.0, 0.279),
                Vec3A::Z,
                60.0,
            ),
            64,
            64,
        );
        let mut s = IndependentSampler::new(4);
        let (mut tested, mut blocked, mut rehit) = (0, 0, 0);
        for i in 0..20_000u64 {
            s.start_pixel_sample(i, 0);
            let p = s.next_2d() * 64.0;
            let ray = scene.camera().generate_ray(p, Vec2::ZERO, 0.0);
            let Some(si) = scene.intersect(&ray) else {
                continue;
            };
            if si.material != 0 {
                continue;
            }
            let ls = scene
                .lights()
                .sample_li(si.p, s.next_1d(), s.next_2d())
                .unwrap();
            tested += 1;
            if !scene.unoccluded(&si, ls.p) {
                blocked += 1;
            }
            // A grazing ray leaving the floor must not hit the floor again.
            let d = s.next_2d();
            let dir = Vec3A::new(d.x - 0.5, 1e-3 + 0.01 * d.y, 0.5 - d.y).normalize();
            if let Some(h) = scene.intersect(&si.spawn_ray(dir, 0.0)) {
                if h.material == 0 {
                    rehit += 1;
                }
            }
        }
        assert!(tested > 10_000, "{tested}");
        assert_eq!((blocked, rehit), (0, 0), "of {tested} shadow rays");
    }

    #[test]
    fn framing_sees_the_whole_box() {
        let spec = CameraSpec::framing(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        assert!(spec.from.z > 1.0);
        assert_eq!(spec.to, Vec3A::ZERO);
    }
}
