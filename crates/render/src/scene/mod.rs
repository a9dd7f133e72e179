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
mod camera_spec;
mod gltf_lights;
mod gltf_load;
mod intersect;
mod lights;
mod load_options;
mod material;
/// Triangle meshes: a leaf module (the BVH and the lights use it), re-exported here.
pub use crate::mesh;
pub mod texture;

use std::path::Path;

use glam::{Affine2, Vec3, Vec3A};

use crate::bvh::Bvh;
use crate::camera::Camera;
use crate::error::RenderError;
use crate::light::{Lights, PunctualLight};
use crate::material::Bsdf;
pub use camera_spec::CameraSpec;
pub use intersect::{SurfaceInteraction, MIN_SHADING_COS};
use lights::EnvironmentChoice;
pub use lights::DEFAULT_ENVIRONMENT_RADIANCE;
pub use load_options::{LoadOptions, MAX_IMAGE_FILE_BYTES};
pub use material::{AlphaMode, Material, TextureRef};
pub use mesh::Mesh;
pub use texture::{Texture, TextureFilter, WrapMode};

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
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

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
}
