//! Materials of a scene: glTF metallic-roughness parameters with their texture references,
//! alpha modes and the BSDF, alpha and emission they give at a surface point.

use glam::{Affine2, Vec2, Vec3};

use super::texture::Texture;
use crate::material::Bsdf;

/// A material's reference to a texture (a glTF `textureInfo`): which texture, which UV set,
/// and the `KHR_texture_transform` applied to the UVs before the lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`Scene::textures`](super::Scene::textures).
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
    /// (`emissive_texture.tex_coord`, see [`Scene::tex_coord`](super::Scene::tex_coord)); the
    /// texture transform is applied here.
    #[must_use]
    pub fn emission_at(&self, textures: &[Texture], uv: Vec2) -> Vec3 {
        match &self.emissive_texture {
            Some(t) if self.emission != Vec3::ZERO => self.emission * t.sample(textures, [uv; 2]),
            _ => self.emission,
        }
    }

    /// The texture references of the material, mutably (for validation).
    pub(super) fn texture_refs_mut(&mut self) -> [(&'static str, &mut Option<TextureRef>); 4] {
        [
            ("base colour", &mut self.base_color_texture),
            ("metallic-roughness", &mut self.metallic_roughness_texture),
            ("normal", &mut self.normal_texture),
            ("emissive", &mut self.emissive_texture),
        ]
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::*;
    use crate::scene::TextureFilter;

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
}
