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
mod gltf_lights;
mod gltf_load;
mod load_options;
/// Triangle meshes: a leaf module (the BVH and the lights use it), re-exported here.
pub use crate::mesh;
pub mod texture;

use std::path::Path;

use glam::{Affine2, Mat4, Vec2, Vec3, Vec3A};

use crate::bvh::{gamma, offset_ray_origin, Bvh};
use crate::camera::{Camera, Ray};
use crate::error::RenderError;
use crate::light::{
    collect_area_lights, Emission, EnvironmentLight, LeSample, LightSample, Lights, PunctualLight,
};
use crate::material::Bsdf;
pub use load_options::{LoadOptions, MAX_IMAGE_FILE_BYTES};
pub use mesh::Mesh;
pub use texture::{Texture, TextureFilter, WrapMode};

/// A material's reference to a texture (a glTF `textureInfo`): which texture, which UV set,
/// and the `KHR_texture_transform` applied to the UVs before the lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`Scene::textures`].
    pub texture: u32,
    /// UV set: 0 = `TEXCOORD_0`, 1 = `TEXCOORD_1` (the glTF `texCoord`, or the transform's
    /// override).
    pub tex_coord: u32,
    /// The UV transform (identity without `KHR_texture_transform`).
    pub transform: Affine2,
}

impl TextureRef {
    /// A reference to texture `texture` through `TEXCOORD_0` without a transform.
    #[must_use]
    pub fn new(texture: u32) -> Self {
        Self {
            texture,
            tex_coord: 0,
            transform: Affine2::IDENTITY,
        }
    }

    /// The reference with the `KHR_texture_transform` `offset`, `rotation` (radians) and
    /// `scale`: `uv' = T(offset) R(rotation) S(scale) uv`, where `R` rotates the UVs
    /// counter-clockwise, i.e. `u' = cos r u + sin r v`, `v' = -sin r u + cos r v` (the
    /// extension's text and examples; its GLSL snippet has the opposite sign in some
    /// revisions).
    #[must_use]
    pub fn with_transform(mut self, offset: Vec2, rotation: f32, scale: Vec2) -> Self {
        let (sin, cos) = rotation.sin_cos();
        self.transform = Affine2::from_cols(
            Vec2::new(cos * scale.x, -sin * scale.x),
            Vec2::new(sin * scale.y, cos * scale.y),
            offset,
        );
        self
    }

    /// The texture coordinates looked up for the mesh UVs `uvs` (`[TEXCOORD_0, TEXCOORD_1]`):
    /// the set this reference uses, transformed.
    #[inline]
    #[must_use]
    pub fn uv(&self, uvs: [Vec2; 2]) -> Vec2 {
        let uv = uvs[(self.tex_coord as usize).min(1)];
        self.transform.transform_point2(uv)
    }

    /// The texture value (RGB) at the mesh UVs `uvs`; white if the texture does not exist.
    #[inline]
    #[must_use]
    pub fn sample(&self, textures: &[Texture], uvs: [Vec2; 2]) -> Vec3 {
        textures
            .get(self.texture as usize)
            .map_or(Vec3::ONE, |t| t.sample(self.uv(uvs)))
    }
}

/// How a material's alpha (`baseColorFactor.a` x base-colour texture alpha x `COLOR_0.a`) is
/// used: glTF `alphaMode`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum AlphaMode {
    /// Alpha is ignored (glTF `OPAQUE`, the default).
    #[default]
    Opaque,
    /// Cut-out (glTF `MASK`): the surface exists where alpha `>= cutoff` (glTF `alphaCutoff`,
    /// default 0.5); elsewhere rays pass through it, camera and shadow rays alike. The loader
    /// also maps glTF `BLEND` to this with cutoff 0.5 (with a warning).
    Mask {
        /// The alpha threshold.
        cutoff: f32,
    },
}

/// A glTF metallic-roughness material (with the transmission, IOR and emissive-strength
/// extensions, texture transforms and alpha cut-outs). The BSDF at a hit is
/// [`Bsdf::from_gltf_params`] of these values, with the base colour multiplied by the
/// base-colour texture and the vertex colour, and metallic and roughness by the
/// metallic-roughness texture, at the hit (see [`Material::bsdf_at`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the file (may be empty).
    pub name: String,
    /// Linear base colour (`pbrMetallicRoughness.baseColorFactor`, RGB).
    pub base_color: Vec3,
    /// `pbrMetallicRoughness.baseColorFactor` alpha in `[0, 1]`.
    pub alpha: f32,
    /// The base-colour texture (sRGB, with alpha), if any.
    pub base_color_texture: Option<TextureRef>,
    /// `pbrMetallicRoughness.metallicFactor` in `[0, 1]`.
    pub metallic: f32,
    /// `pbrMetallicRoughness.roughnessFactor` in `[0, 1]` (perceptual; GGX alpha = roughness²).
    pub roughness: f32,
    /// The metallic-roughness texture (linear; blue = metallic, green = roughness, each
    /// multiplying its factor), if any.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// The tangent-space normal map (linear; `normalTexture`), if any.
    pub normal_texture: Option<TextureRef>,
    /// `normalTexture.scale`: multiplies the X and Y of the decoded tangent-space normal.
    pub normal_scale: f32,
    /// The emissive texture (sRGB; multiplies [`Material::emission`]), if any.
    pub emissive_texture: Option<TextureRef>,
    /// glTF `alphaMode` / `alphaCutoff`.
    pub alpha_mode: AlphaMode,
    /// `KHR_materials_transmission.transmissionFactor` in `[0, 1]`.
    pub transmission: f32,
    /// `KHR_materials_ior.ior` (default 1.5).
    pub ior: f32,
    /// Emitted radiance: `emissiveFactor × KHR_materials_emissive_strength.emissiveStrength`
    /// (times the emissive texture at a point: [`Material::emission_at`]).
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
            alpha: 1.0,
            base_color_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
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

    /// The BSDF for base colour `base_color` (the factor times the texture value), with the
    /// metallic and roughness factors.
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

    /// True if the BSDF varies over the surface through a texture (base colour or
    /// metallic-roughness); vertex colours are a property of the mesh, not the material.
    #[must_use]
    pub fn is_textured(&self) -> bool {
        self.base_color_texture.is_some() || self.metallic_roughness_texture.is_some()
    }

    /// The BSDF at a point with mesh UVs `uvs` (`[TEXCOORD_0, TEXCOORD_1]`) and vertex colour
    /// `color` (RGB, white without `COLOR_0`): base colour = factor x texture x `color`,
    /// metallic = factor x texture blue, roughness = factor x texture green.
    #[must_use]
    pub fn bsdf_at(&self, textures: &[Texture], uvs: [Vec2; 2], color: Vec3) -> Bsdf {
        let mut base = self.base_color * color;
        if let Some(t) = &self.base_color_texture {
            base *= t.sample(textures, uvs);
        }
        let (mut metallic, mut roughness) = (self.metallic, self.roughness);
        if let Some(t) = &self.metallic_roughness_texture {
            let mr = t.sample(textures, uvs);
            metallic *= mr.z;
            roughness *= mr.y;
        }
        Bsdf::from_gltf_params(base, metallic, roughness, self.transmission, self.ior)
    }

    /// The alpha at a point with mesh UVs `uvs` and vertex-colour alpha `color_alpha`:
    /// `baseColorFactor.a x base-colour texture alpha x COLOR_0.a`.
    #[must_use]
    pub fn alpha_at(&self, textures: &[Texture], uvs: [Vec2; 2], color_alpha: f32) -> f32 {
        let tex = self.base_color_texture.as_ref().map_or(1.0, |t| {
            textures
                .get(t.texture as usize)
                .map_or(1.0, |tex| tex.sample_alpha(t.uv(uvs)))
        });
        self.alpha * tex * color_alpha
    }

    /// True if the surface exists at a point of alpha `alpha` (always for
    /// [`AlphaMode::Opaque`]).
    #[inline]
    #[must_use]
    pub fn is_opaque_at(&self, alpha: f32) -> bool {
        match self.alpha_mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask { cutoff } => alpha >= cutoff,
        }
    }

    /// Emitted radiance at texture coordinates `uv`: `emissiveFactor × emissiveStrength ×
    /// emissive texture(transform(uv))` (just [`Material::emission`] without a texture, or if
    /// its index is not in `textures`). `uv` must be the UV set the emissive texture uses
    /// (`emissive_texture.tex_coord`, see [`Scene::tex_coord`]); the texture transform is
    /// applied here.
    #[must_use]
    pub fn emission_at(&self, textures: &[Texture], uv: Vec2) -> Vec3 {
        match &self.emissive_texture {
            Some(t) if self.emission != Vec3::ZERO => self.emission * t.sample(textures, [uv; 2]),
            _ => self.emission,
        }
    }

    /// The texture references of the material, mutably (for validation).
    fn texture_refs_mut(&mut self) -> [(&'static str, &mut Option<TextureRef>); 4] {
        [
            ("base colour", &mut self.base_color_texture),
            ("metallic-roughness", &mut self.metallic_roughness_texture),
            ("normal", &mut self.normal_texture),
            ("emissive", &mut self.emissive_texture),
        ]
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
    ///
    /// `None` if the transform cannot place a camera: a singular or non-finite matrix (e.g. a
    /// node `scale` with a 0), a zero viewing direction or up vector, or an up vector parallel
    /// to the viewing direction. There is no fallback pose: the caller reports it.
    #[must_use]
    pub fn from_matrix(world_from_camera: Mat4, yfov_rad: f32) -> Option<Self> {
        let origin = Vec3A::from(world_from_camera.transform_point3(Vec3::ZERO));
        let forward = Vec3A::from(world_from_camera.transform_vector3(Vec3::NEG_Z));
        let up = Vec3A::from(world_from_camera.transform_vector3(Vec3::Y));
        let det = world_from_camera.determinant();
        if !(origin.is_finite() && det.is_finite() && det != 0.0) {
            return None;
        }
        let f = forward.try_normalize()?;
        let u = up.try_normalize()?;
        // A usable up vector is not (nearly) parallel to the viewing direction.
        if f.cross(u).length_squared() < 1e-12 {
            return None;
        }
        Some(Self::look_at(origin, origin + f, up, yfov_rad.to_degrees()))
    }

    /// A camera framing the box `(lo, hi)`: looking at its centre from the front (`+z`),
    /// raised by 25° and turned by 20° about `+y` so that flat models lying in any axis plane
    /// are not seen edge-on, from far enough that the bounding sphere fits a 45° vertical
    /// field of view.
    #[must_use]
    pub fn framing(lo: Vec3A, hi: Vec3A) -> Self {
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let vfov = 45.0f32;
        let dist = radius / (vfov.to_radians() * 0.5).sin() * 1.05;
        let (elevation, azimuth) = (25f32.to_radians(), 20f32.to_radians());
        let dir = Vec3A::new(
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
            elevation.cos() * azimuth.cos(),
        );
        Self::look_at(center + dir * dist, center, Vec3A::Y, vfov)
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
    /// Unit shading normal: the interpolated vertex normals (`ng` when the mesh has none) in
    /// the hemisphere of `ng`, perturbed by the material's normal map if it has one (then kept
    /// at least [`MIN_SHADING_COS`] inside the hemisphere of `ng`).
    pub ns: Vec3A,
    /// Interpolated texture coordinates (`TEXCOORD_0`; see [`Scene::tex_coord`] for set 1).
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
    /// BSDF of each material that is constant over its surface (no texture, no vertex
    /// colour), built once.
    bsdfs: Vec<Option<Bsdf>>,
    /// For each material: true if it can cut out parts of its surface (alpha mask), so ray
    /// queries must test the alpha of its hits.
    cutout: Vec<bool>,
    /// Some material cuts out: ray queries take the filtered path.
    has_cutouts: bool,
    /// Some material has a normal map.
    has_normal_maps: bool,
    camera_spec: CameraSpec,
    camera: Camera,
    lights: Lights,
    /// The punctual lights (`KHR_lights_punctual`).
    punctual: Vec<PunctualLight>,
    /// How the environment was chosen.
    environment: EnvironmentChoice,
    bvh: Bvh,
    /// Problems that did not prevent loading (unsupported glTF features, dropped triangles).
    pub warnings: Vec<String>,
    /// Things a user should know that are not problems (e.g. the default environment).
    pub notes: Vec<String>,
}

/// The radiance of the default environment that lights scenes without any light.
pub const DEFAULT_ENVIRONMENT_RADIANCE: f32 = 1.0;

/// How a scene's environment light was chosen.
#[derive(Clone, Debug)]
enum EnvironmentChoice {
    /// No light in the scene: a uniform environment of [`DEFAULT_ENVIRONMENT_RADIANCE`]
    /// (dropped as soon as the scene gets a light).
    Default,
    /// Set by [`Scene::set_environment`] (`None`: no environment, even without lights).
    Explicit(Option<EnvironmentLight>),
}

/// Relative shortening of shadow rays at their far end (the end point is on another surface
/// whose error bound is unknown).
const SHADOW_EPSILON: f32 = 1e-4;

/// The smallest cosine a normal-mapped shading normal keeps with the geometric normal: a
/// normal map tilting it further is pulled back towards the geometric normal.
pub const MIN_SHADING_COS: f32 = 0.01;

/// Keeps a perturbed unit shading normal `n` usable: pushed (towards `ng`) back to at least
/// [`MIN_SHADING_COS`] inside the hemisphere of the geometric normal `ng`. The result depends
/// on the surface point only, not on the direction it is seen from, so every integrator and
/// every strategy of a bidirectional one sees the same shading frame at a point. (A view
/// direction below a strongly tilted shading horizon then sees a dark surface, as in pbrt.)
/// `None` if the result is not finite.
#[inline]
fn valid_shading_normal(n: Vec3A, ng: Vec3A) -> Option<Vec3A> {
    let d = n.dot(ng);
    let n = if d < MIN_SHADING_COS {
        (n + ng * (MIN_SHADING_COS - d)).try_normalize()?
    } else {
        n
    };
    n.is_finite().then_some(n)
}

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
            let name = m.name.clone();
            for (kind, slot) in m.texture_refs_mut() {
                if slot.is_some_and(|t| t.texture as usize >= textures.len()) {
                    warnings.push(format!(
                        "material '{name}' refers to a missing {kind} texture; it is ignored"
                    ));
                    *slot = None;
                }
                if let Some(t) = slot {
                    if !t.transform.is_finite() {
                        t.transform = Affine2::IDENTITY;
                    }
                }
            }
            if !m.emission.is_finite() {
                m.emission = Vec3::ZERO;
            }
            m.alpha = if m.alpha.is_nan() {
                1.0
            } else {
                m.alpha.clamp(0.0, 1.0)
            };
            if !m.normal_scale.is_finite() {
                m.normal_scale = 1.0;
            }
            if let AlphaMode::Mask { cutoff } = &mut m.alpha_mode {
                if cutoff.is_nan() {
                    *cutoff = 0.5;
                }
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
        // Materials on vertices with a colour other than white, or an alpha below 1.
        let mut colored = vec![false; materials.len()];
        let mut color_alpha = vec![false; materials.len()];
        if !mesh.colors.is_empty() {
            for (t, &m) in mesh.triangles.iter().zip(&mesh.material_ids) {
                for &v in t {
                    let c = mesh.colors[v as usize];
                    colored[m as usize] |= c.truncate() != Vec3::ONE;
                    color_alpha[m as usize] |= c.w < 1.0;
                }
            }
        }
        let bsdfs = materials
            .iter()
            .zip(&colored)
            .map(|(m, &colored)| (!m.is_textured() && !colored).then(|| m.bsdf_with(m.base_color)))
            .collect();
        // A mask can cut something out only if the alpha can fall below the cutoff.
        let cutout: Vec<bool> = materials
            .iter()
            .zip(&color_alpha)
            .map(|(m, &color_alpha)| match m.alpha_mode {
                AlphaMode::Opaque => false,
                AlphaMode::Mask { cutoff } => {
                    let tex_alpha = m
                        .base_color_texture
                        .is_some_and(|t| textures[t.texture as usize].has_alpha());
                    cutoff > 0.0 && (m.alpha < cutoff || tex_alpha || color_alpha)
                }
            })
            .collect();
        let has_cutouts = cutout.contains(&true);
        let has_normal_maps = materials.iter().any(|m| m.normal_texture.is_some());
        let bvh = Bvh::build(&mesh);
        if mesh.triangle_count() == 0 {
            warnings.push("the scene has no triangles: the image will be black".to_owned());
        }
        let mut scene = Self {
            mesh,
            materials,
            textures,
            bsdfs,
            cutout,
            has_cutouts,
            has_normal_maps,
            camera_spec: camera,
            camera: camera.build(width, height),
            lights: Lights::default(),
            punctual: Vec::new(),
            environment: EnvironmentChoice::Default,
            bvh,
            warnings,
            notes: Vec::new(),
        };
        scene.rebuild_lights();
        scene
    }

    /// Rebuilds the light list from the emissive materials, the punctual lights and the
    /// environment choice, and updates the note about the default environment.
    fn rebuild_lights(&mut self) {
        let (area, light_of_triangle) = collect_area_lights(
            &self.mesh,
            |id| self.emission_of(id),
            |t| self.emission_texture_mean(t),
        );
        // A scene without geometry stays black: there is nothing for a default light to show.
        let own_lights =
            !area.is_empty() || !self.punctual.is_empty() || self.mesh.triangle_count() == 0;
        let environment = match &self.environment {
            EnvironmentChoice::Default if !own_lights => Some(EnvironmentLight::constant(
                Vec3::splat(DEFAULT_ENVIRONMENT_RADIANCE),
            )),
            EnvironmentChoice::Default => None,
            EnvironmentChoice::Explicit(e) => e.clone(),
        };
        let default_in_use = matches!(self.environment, EnvironmentChoice::Default) && !own_lights;
        const NOTE: &str = "the scene has no light: it is lit by a default uniform white environment of radiance 1 (`--env none` renders it without, `--env RGB|FILE` sets another)";
        self.notes.retain(|n| n != NOTE);
        if default_in_use {
            self.notes.push(NOTE.to_owned());
        }
        self.lights = Lights::new(
            area,
            light_of_triangle,
            self.punctual.clone(),
            environment,
            self.mesh.bounds(),
        );
    }

    /// What material `id` emits, for the area lights.
    fn emission_of(&self, id: u32) -> Emission {
        let m = &self.materials[id as usize];
        Emission {
            radiance: m.emission,
            two_sided: m.double_sided,
            textured: m.emissive_texture.is_some() || self.cutout[id as usize],
        }
    }

    /// Mean emissive-texture luminance factor over triangle `t` (for selection by power):
    /// the average over a fixed 6 x 6 stratified pattern of points.
    fn emission_texture_mean(&self, t: usize) -> f32 {
        let n = 6;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let [_, b1, b2] = crate::warp::sample_uniform_triangle(u);
                let f = self.emission_texture(t as u32, Vec2::new(b1, b2));
                sum += crate::image::luminance(f.to_array());
            }
        }
        sum / (n * n) as f32
    }

    /// Adds punctual lights (point, spot, directional) and rebuilds the light list. The
    /// default environment is dropped once the scene has a light of its own.
    pub fn add_punctual_lights(&mut self, lights: impl IntoIterator<Item = PunctualLight>) {
        self.punctual.extend(lights);
        self.rebuild_lights();
    }

    /// Sets the environment light (`None`: no environment; a scene without any other light
    /// then renders black), replacing the default one.
    pub fn set_environment(&mut self, environment: Option<EnvironmentLight>) {
        self.environment = EnvironmentChoice::Explicit(environment);
        self.rebuild_lights();
    }

    /// True if the scene is lit only by the default environment (it has no light of its own
    /// and none was set).
    #[must_use]
    pub fn uses_default_environment(&self) -> bool {
        matches!(self.environment, EnvironmentChoice::Default)
            && self.lights.environment().is_some()
    }

    /// Loads a `.gltf` (with external or embedded buffers and images) or `.glb` file.
    ///
    /// # Errors
    /// [`RenderError::Io`] if the file cannot be read, [`RenderError::UnsupportedFormat`] for
    /// other extensions, [`RenderError::Gltf`] naming the file and the reason for malformed
    /// content. Unsupported features only add to [`Scene::warnings`].
    ///
    /// Uses the default [`LoadOptions`]: buffers and images are read only from regular files
    /// inside the scene file's folder (see [`Scene::load_with`]).
    pub fn load(path: &Path) -> Result<Self, RenderError> {
        Self::load_with(path, &LoadOptions::default())
    }

    /// Loads a `.gltf` or `.glb` file with `options`.
    ///
    /// Loading safety (whatever the options): the scene file and every external buffer or
    /// image must be a regular file (a directory, FIFO or device is an error naming the file,
    /// the glTF field and why); a buffer file is read no further than its `byteLength` (a
    /// shorter file is an error); an image file may have at most [`MAX_IMAGE_FILE_BYTES`].
    /// Unless [`LoadOptions::allow_external_files`] is set, buffer and image URIs must resolve
    /// inside the scene file's folder: absolute paths, `..` leaving the folder, `file://` URIs
    /// and symbolic links that lead outside it are errors. glTF 1.0 files and files requiring
    /// Draco mesh compression are errors saying so; a UTF-8 byte-order mark is skipped with a
    /// warning.
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Self, RenderError> {
        gltf_load::load_path(path, options)
    }

    /// Loads glTF or GLB bytes; relative URIs are resolved against `base_dir` (none: only
    /// embedded data and the GLB binary chunk are available) and must stay inside it, with the
    /// safety rules of [`Scene::load_with`] under the default [`LoadOptions`].
    ///
    /// # Errors
    /// As [`Scene::load`], with the file named `<memory>`.
    pub fn from_gltf_slice(bytes: &[u8], base_dir: Option<&Path>) -> Result<Self, RenderError> {
        gltf_load::load_slice(bytes, base_dir, "<memory>", &LoadOptions::default())
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

    /// The lights (area, punctual, environment).
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
        let hit = if self.has_cutouts {
            self.bvh
                .intersect_filtered(ray.origin, ray.dir, f32::INFINITY, |tri, b| {
                    self.surface_exists(tri, b)
                })
        } else {
            self.bvh.intersect(ray.origin, ray.dir, f32::INFINITY)
        }?;
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
        let material = self.mesh.material_ids[tri];
        let ns = if self.has_normal_maps {
            match &self.materials[material as usize].normal_texture {
                Some(map) => self.normal_mapped(map, material, tri, hit.barycentrics, ng, ns),
                None => ns,
            }
        } else {
            ns
        };
        Some(SurfaceInteraction {
            p,
            p_error,
            t: hit.t,
            ng,
            ns,
            uv,
            barycentrics: hit.barycentrics,
            triangle: hit.triangle,
            material,
            wo: -ray.dir,
        })
    }

    /// False if triangle `tri` is cut out (alpha mask) at barycentrics `b`.
    #[inline]
    fn surface_exists(&self, tri: u32, b: Vec2) -> bool {
        let id = self.mesh.material_ids[tri as usize] as usize;
        if !self.cutout[id] {
            return true;
        }
        let m = &self.materials[id];
        let tri = tri as usize;
        let alpha = m.alpha_at(
            &self.textures,
            self.mesh.tex_coords(tri, b),
            self.mesh.color_at(tri, b).w,
        );
        m.is_opaque_at(alpha)
    }

    /// The shading normal `ns` of triangle `tri` at barycentrics `b` perturbed by the normal
    /// map `map` of material `material` (glTF: tangent-space normal `(2 rgb - 1) x (scale,
    /// scale, 1)`, +X along the tangent, +Y along the bitangent, +Z along `ns`), then kept
    /// valid by [`valid_shading_normal`]. `ns` unchanged when no tangent frame exists.
    #[allow(clippy::too_many_arguments)]
    fn normal_mapped(
        &self,
        map: &TextureRef,
        material: u32,
        tri: usize,
        b: Vec2,
        ng: Vec3A,
        ns: Vec3A,
    ) -> Vec3A {
        let Some(texture) = self.textures.get(map.texture as usize) else {
            return ns;
        };
        let c = texture.sample(map.uv(self.mesh.tex_coords(tri, b)));
        let scale = self.materials[material as usize].normal_scale;
        let local = Vec3A::new(
            (2.0 * c.x - 1.0) * scale,
            (2.0 * c.y - 1.0) * scale,
            2.0 * c.z - 1.0,
        );
        let Some((t, bt)) = self.tangent_frame(tri, b, ns, map.tex_coord) else {
            return ns;
        };
        match (t * local.x + bt * local.y + ns * local.z).try_normalize() {
            Some(n) => valid_shading_normal(n, ng).unwrap_or(ns),
            None => ns,
        }
    }

    /// Unit tangent and bitangent at barycentrics `b` of triangle `tri`, orthogonal to the
    /// unit shading normal `ns`: from the vertex `TANGENT`s if all three vertices have one
    /// (bitangent `= w (ns x tangent)`, glTF), otherwise generated for the triangle from the
    /// UV set `set` (tangent along increasing `u`, bitangent along decreasing `v`, i.e. up in
    /// the image, as glTF normal maps expect). `None` if the UVs are degenerate.
    fn tangent_frame(&self, tri: usize, b: Vec2, ns: Vec3A, set: u32) -> Option<(Vec3A, Vec3A)> {
        let [i0, i1, i2] = self.mesh.triangles[tri].map(|i| i as usize);
        let tangents = &self.mesh.tangents;
        if !tangents.is_empty()
            && [i0, i1, i2]
                .iter()
                .all(|&i| tangents[i].truncate() != Vec3::ZERO)
        {
            let b0 = (1.0 - b.x - b.y).max(0.0);
            let t4 = tangents[i0] * b0 + tangents[i1] * b.x + tangents[i2] * b.y;
            let t = Vec3A::from(t4.truncate());
            if let Some(t) = (t - ns * ns.dot(t)).try_normalize() {
                let w = if t4.w < 0.0 { -1.0 } else { 1.0 };
                return Some((t, ns.cross(t) * w));
            }
        }
        let uvs = if set == 1 && !self.mesh.uvs1.is_empty() {
            &self.mesh.uvs1
        } else {
            &self.mesh.uvs
        };
        let (d1, d2) = (uvs[i1] - uvs[i0], uvs[i2] - uvs[i0]);
        let det = d1.x * d2.y - d1.y * d2.x;
        let p = &self.mesh.positions;
        let (e1, e2) = (p[i1] - p[i0], p[i2] - p[i0]);
        let dpdu = (e1 * d2.y - e2 * d1.y) / det;
        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
        let t = (dpdu - ns * ns.dot(dpdu)).try_normalize()?;
        let bt = ns.cross(t);
        let w = if bt.dot(dpdv) > 0.0 { -1.0 } else { 1.0 };
        Some((t, bt * w))
    }

    /// The texture coordinates of UV set `set` at `si`: `si.uv` for 0, `TEXCOORD_1` for 1
    /// (`TEXCOORD_0` if the mesh has no second set). For [`Material::emission_at`] and other
    /// texture lookups by a [`TextureRef::tex_coord`].
    #[inline]
    #[must_use]
    pub fn tex_coord(&self, si: &SurfaceInteraction, set: u32) -> Vec2 {
        if set == 0 {
            si.uv
        } else {
            self.mesh.uv1_at(si.triangle as usize, si.barycentrics)
        }
    }

    /// True if a triangle that is not cut out intersects the segment `origin + t dir`,
    /// `0 <= t <= t_max`.
    #[inline]
    fn segment_blocked(&self, origin: Vec3A, dir: Vec3A, t_max: f32) -> bool {
        if self.has_cutouts {
            self.bvh
                .occluded_filtered(origin, dir, t_max, |tri, b| self.surface_exists(tri, b))
        } else {
            self.bvh.occluded(origin, dir, t_max)
        }
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
        !self.segment_blocked(origin, d / dist, dist * (1.0 - SHADOW_EPSILON))
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
        !self.segment_blocked(oa, d / dist, dist * (1.0 - SHADOW_EPSILON))
    }

    /// The BSDF at a surface point (in the local frame of its shading normal): the material's
    /// factors times its textures and the vertex colour ([`Material::bsdf_at`]).
    #[inline]
    #[must_use]
    pub fn bsdf(&self, si: &SurfaceInteraction) -> Bsdf {
        let id = si.material as usize;
        if let Some(b) = self.bsdfs[id] {
            return b;
        }
        let tri = si.triangle as usize;
        let uvs = [si.uv, self.tex_coord(si, 1)];
        let color = self.mesh.color_at(tri, si.barycentrics).truncate();
        self.materials[id].bsdf_at(&self.textures, uvs, color)
    }

    /// Radiance emitted by the surface at `si` towards `w` (zero for non-emitters and for the
    /// back of one-sided emitters).
    #[inline]
    #[must_use]
    pub fn emitted(&self, si: &SurfaceInteraction, w: Vec3A) -> Vec3 {
        match self.lights.light_of_triangle(si.triangle) {
            Some(l) => self.area_le(l, si.barycentrics, w),
            None => Vec3::ZERO,
        }
    }

    /// Radiance emitted by area light `light` at barycentrics `b` (`(b1, b2)`) towards `w`
    /// (zero towards the back of a one-sided emitter): the material's emission times its
    /// emissive texture, zero where an alpha mask cuts the surface out.
    #[inline]
    #[must_use]
    pub fn area_le(&self, light: u32, b: Vec2, w: Vec3A) -> Vec3 {
        let Some(l) = self.lights.lights().get(light as usize) else {
            return Vec3::ZERO;
        };
        let le = l.le(w);
        if l.textured && le != Vec3::ZERO {
            le * self.emission_texture(l.triangle, b)
        } else {
            le
        }
    }

    /// The factor of the emissive texture of triangle `tri` at barycentrics `b` (1 without a
    /// texture; 0 where an alpha mask cuts the surface out).
    #[inline]
    fn emission_texture(&self, tri: u32, b: Vec2) -> Vec3 {
        if !self.surface_exists(tri, b) {
            return Vec3::ZERO;
        }
        let m = &self.materials[self.mesh.material_ids[tri as usize] as usize];
        match &m.emissive_texture {
            Some(t) => t.sample(&self.textures, self.mesh.tex_coords(tri as usize, b)),
            None => Vec3::ONE,
        }
    }

    /// Samples incident light at `p_ref` ([`Lights::sample_li`]) with the emissive texture
    /// of area lights applied to the radiance.
    #[inline]
    #[must_use]
    pub fn sample_li(&self, p_ref: Vec3A, u_light: f32, u_pos: Vec2) -> Option<LightSample> {
        let mut ls = self.lights.sample_li(p_ref, u_light, u_pos)?;
        if let Some(l) = self.lights.lights().get(ls.light as usize) {
            if l.textured {
                ls.radiance *= self.emission_texture(l.triangle, ls.barycentrics);
            }
        }
        Some(ls)
    }

    /// Samples an emitted ray ([`Lights::sample_le`]) with the emissive texture of area
    /// lights applied to the radiance.
    #[inline]
    #[must_use]
    pub fn sample_le(&self, u_light: f32, u_pos: Vec2, u_dir: Vec2) -> Option<LeSample> {
        let mut le = self.lights.sample_le(u_light, u_pos, u_dir)?;
        if let Some(l) = self.lights.lights().get(le.light as usize) {
            if l.textured {
                le.radiance *= self.emission_texture(l.triangle, le.barycentrics);
                if le.radiance == Vec3::ZERO {
                    return None;
                }
            }
        }
        Some(le)
    }

    /// True if nothing blocks the ray from surface point `from` in direction `dir` to
    /// infinity (shadow rays towards infinite lights).
    #[inline]
    #[must_use]
    pub fn unoccluded_towards(&self, from: &SurfaceInteraction, dir: Vec3A) -> bool {
        let origin = offset_ray_origin(from.p, from.p_error, from.ng, dir);
        !self.segment_blocked(origin, dir, f32::INFINITY)
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

    /// The `KHR_texture_transform` example "the lower left quadrant of the source image,
    /// rotated clockwise 90°" (offset (0, 1), rotation pi/2, scale 0.5) maps the unit square
    /// into `[0, 0.5] x [0.5, 1]`, with the UV origin at the quadrant's bottom left.
    #[test]
    fn texture_transform_matches_the_extension_example() {
        let t = TextureRef::new(0).with_transform(
            Vec2::new(0.0, 1.0),
            std::f32::consts::FRAC_PI_2,
            Vec2::splat(0.5),
        );
        let map = |u: f32, v: f32| t.uv([Vec2::new(u, v), Vec2::splat(9.0)]);
        let close = |a: Vec2, b: Vec2| (a - b).length() < 1e-6;
        assert!(close(map(0.0, 0.0), Vec2::new(0.0, 1.0)));
        assert!(close(map(1.0, 0.0), Vec2::new(0.0, 0.5)));
        assert!(close(map(0.0, 1.0), Vec2::new(0.5, 1.0)));
        assert!(close(map(1.0, 1.0), Vec2::new(0.5, 0.5)));
        // The "bottom-left origin" example: offset (0, 1), scale (1, -1) flips v.
        let flip = TextureRef::new(0).with_transform(Vec2::Y, 0.0, Vec2::new(1.0, -1.0));
        assert!(close(
            flip.uv([Vec2::new(0.25, 0.1); 2]),
            Vec2::new(0.25, 0.9)
        ));
        // The UV set: texCoord 1 reads the second set.
        let set1 = TextureRef {
            tex_coord: 1,
            ..TextureRef::new(0)
        };
        assert_eq!(set1.uv([Vec2::ZERO, Vec2::ONE]), Vec2::ONE);
    }

    fn checker_texture() -> Texture {
        // Left texel black, right white (linear), nearest filtering.
        let mut t = Texture::new(2, 1, vec![Vec3::ZERO, Vec3::ONE]).unwrap();
        t.filter = TextureFilter::Nearest;
        t
    }

    #[test]
    fn emission_at_uses_factor_texture_and_transform() {
        let textures = [checker_texture()];
        let mut m = Material::diffuse("e", Vec3::ZERO, Vec3::new(2.0, 3.0, 4.0));
        let (left, right) = (Vec2::new(0.25, 0.5), Vec2::new(0.75, 0.5));
        assert_eq!(m.emission_at(&textures, left), m.emission);
        m.emissive_texture = Some(TextureRef::new(0));
        assert_eq!(m.emission_at(&textures, left), Vec3::ZERO);
        assert_eq!(m.emission_at(&textures, right), m.emission);
        // An offset of half the texture swaps the halves.
        m.emissive_texture = Some(TextureRef::new(0).with_transform(Vec2::X * 0.5, 0.0, Vec2::ONE));
        assert_eq!(m.emission_at(&textures, left), m.emission);
        assert_eq!(m.emission_at(&textures, right), Vec3::ZERO);
        // A missing texture leaves the factor.
        assert_eq!(m.emission_at(&[], left), m.emission);
    }

    #[test]
    fn bsdf_and_alpha_at_a_point() {
        use crate::material::TransportMode;
        let textures = [checker_texture()];
        let albedo =
            |b: Bsdf| b.eval(Vec3A::Z, Vec3A::Z, TransportMode::Radiance) * std::f32::consts::PI;
        let mut m = Material::diffuse("d", Vec3::new(0.5, 1.0, 1.0), Vec3::ZERO);
        let (left, right) = ([Vec2::new(0.25, 0.5); 2], [Vec2::new(0.75, 0.5); 2]);
        let c = Vec3::new(1.0, 0.5, 1.0);
        assert!((albedo(m.bsdf_at(&textures, left, c)) - Vec3::new(0.5, 0.5, 1.0)).length() < 1e-5);
        m.base_color_texture = Some(TextureRef::new(0));
        assert!(m.is_textured());
        assert_eq!(albedo(m.bsdf_at(&textures, left, c)), Vec3::ZERO);
        // Metallic-roughness: blue = metallic, green = roughness (black texel: diffuse, white:
        // a rough conductor since both factors are 1).
        let mut mr = Material {
            metallic: 1.0,
            metallic_roughness_texture: Some(TextureRef::new(0)),
            ..Material::default()
        };
        assert!(!mr.bsdf_at(&textures, left, Vec3::ONE).is_specular());
        assert!(matches!(
            mr.bsdf_at(&textures, left, Vec3::ONE),
            Bsdf::Lambertian(_)
        ));
        assert!(!matches!(
            mr.bsdf_at(&textures, right, Vec3::ONE),
            Bsdf::Lambertian(_)
        ));
        mr.metallic_roughness_texture = None;
        assert!(!matches!(
            mr.bsdf_at(&textures, left, Vec3::ONE),
            Bsdf::Lambertian(_)
        ));
        // Alpha: factor x texture alpha x vertex alpha, against the cutoff.
        let a = Texture::new(2, 1, vec![Vec3::ONE; 2])
            .unwrap()
            .with_alpha(vec![0.2, 1.0])
            .unwrap();
        let mut t = a;
        t.filter = TextureFilter::Nearest;
        let textures = [t];
        let mut m = Material {
            alpha: 0.8,
            base_color_texture: Some(TextureRef::new(0)),
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            ..Material::default()
        };
        assert!((m.alpha_at(&textures, left, 1.0) - 0.16).abs() < 1e-6);
        assert!((m.alpha_at(&textures, right, 0.5) - 0.4).abs() < 1e-6);
        assert!(!m.is_opaque_at(0.4) && m.is_opaque_at(0.5));
        m.alpha_mode = AlphaMode::Opaque;
        assert!(m.is_opaque_at(0.0));
    }

    /// Perturbed normals far outside the geometric hemisphere are pulled back into it; the
    /// result is unit and finite, and normals inside it are unchanged.
    #[test]
    fn shading_normals_stay_valid() {
        use crate::sampler::{IndependentSampler, Sampler};
        let ng = Vec3A::new(0.3, -0.4, 0.5).normalize();
        let mut s = IndependentSampler::new(9);
        for i in 0..20_000 {
            s.start_pixel_sample(i, 0);
            let u = s.next_2d();
            let z = 1.0 - 2.0 * u.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u.y;
            let n = Vec3A::new(r * phi.cos(), r * phi.sin(), z);
            let m = valid_shading_normal(n, ng).unwrap_or_else(|| panic!("{n}"));
            assert!((m.length() - 1.0).abs() < 1e-4);
            assert!(m.dot(ng) > 0.5 * MIN_SHADING_COS, "{n} -> {m}");
            if n.dot(ng) >= MIN_SHADING_COS {
                assert_eq!(m, n);
            }
        }
        // Exactly opposite the geometric normal.
        assert!(valid_shading_normal(-ng, ng).is_some());
    }

    #[test]
    fn framing_sees_the_whole_box() {
        let spec = CameraSpec::framing(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        assert!(spec.from.z > 1.0);
        assert_eq!(spec.to, Vec3A::ZERO);
    }
}
