//! glTF materials and textures: metallic-roughness factors, the supported material
//! extensions, texture references with `KHR_texture_transform`, decoded images and samplers.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::uri::UriLimit;
use super::Loader;
use crate::error::RenderError;
use crate::scene::texture::{Texture, TextureFilter, WrapMode};
use crate::scene::{AlphaMode, Material, TextureRef};

/// Material extensions whose content the loader uses (any other in a material is named in
/// the unsupported-material-features warning).
const MATERIAL_EXTENSIONS: [&str; 3] = [
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
];

/// The textures loaded so far: each glTF texture decoded once per colour space.
#[derive(Default)]
struct TextureTable {
    textures: Vec<Texture>,
    /// `(glTF texture index, sRGB)` -> index in `textures`.
    index: HashMap<(usize, bool), u32>,
}

impl TextureTable {
    /// The index of glTF texture `tex` decoded as sRGB colour or linear data, loading it on
    /// first use.
    fn get(
        &mut self,
        loader: &mut Loader<'_>,
        doc: &gltf::Document,
        buffers: &[Vec<u8>],
        tex: &gltf::Texture<'_>,
        srgb: bool,
    ) -> Result<u32, RenderError> {
        if let Some(&id) = self.index.get(&(tex.index(), srgb)) {
            return Ok(id);
        }
        let t = loader.load_texture(doc, tex, buffers, srgb)?;
        self.textures.push(t);
        let id = self.textures.len() as u32 - 1;
        self.index.insert((tex.index(), srgb), id);
        Ok(id)
    }
}

/// Unsupported material features, each with the materials that use it, in first-seen order.
#[derive(Default)]
struct FeatureNotes(Vec<(String, Vec<String>)>);

impl FeatureNotes {
    fn add(&mut self, feature: String, material: &str) {
        let i = match self.0.iter().position(|(f, _)| *f == feature) {
            Some(i) => i,
            None => {
                self.0.push((feature, Vec::new()));
                self.0.len() - 1
            }
        };
        let names = &mut self.0[i].1;
        if !names.iter().any(|n| n == material) {
            names.push(material.to_owned());
        }
    }

    /// `feature (in 'a', 'b'); feature (in 'c')`, or `None` if nothing was noted.
    fn summary(&self) -> Option<String> {
        (!self.0.is_empty()).then(|| {
            self.0
                .iter()
                .map(|(f, names)| format!("{f} (in {})", name_list(names)))
                .collect::<Vec<_>>()
                .join("; ")
        })
    }
}

/// `'a', 'b', 'c' and 4 more`.
fn name_list(names: &[String]) -> String {
    const SHOWN: usize = 3;
    let mut s = names
        .iter()
        .take(SHOWN)
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        s.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    s
}

/// `base` with the UV set `tex_coord` and the `KHR_texture_transform` of the textureInfo
/// JSON `info` (offset, rotation, scale, texCoord override; defaults for missing or
/// malformed fields), or `None` if a value is not finite.
fn texture_transform(
    info: &gltf::json::Value,
    base: TextureRef,
    tex_coord: u32,
) -> Option<TextureRef> {
    let base = TextureRef { tex_coord, ..base };
    let tt = &info["extensions"]["KHR_texture_transform"];
    if !tt.is_object() {
        return Some(base);
    }
    let pair = |v: &gltf::json::Value, d: Vec2| match (v[0].as_f64(), v[1].as_f64()) {
        (Some(x), Some(y)) => Vec2::new(x as f32, y as f32),
        _ => d,
    };
    let offset = pair(&tt["offset"], Vec2::ZERO);
    let scale = pair(&tt["scale"], Vec2::ONE);
    let rotation = tt["rotation"].as_f64().map_or(0.0, |r| r as f32);
    if !(offset.is_finite() && scale.is_finite() && rotation.is_finite()) {
        return None;
    }
    let tex_coord = tt["texCoord"]
        .as_u64()
        .map_or(tex_coord, |t| u32::try_from(t).unwrap_or(u32::MAX));
    Some(TextureRef { tex_coord, ..base }.with_transform(offset, rotation, scale))
}

fn wrap_mode(m: gltf::texture::WrappingMode) -> WrapMode {
    match m {
        gltf::texture::WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
        gltf::texture::WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
    }
}

impl Loader<'_> {
    /// Reads every material and loads the textures they use (each glTF texture once per
    /// colour space: sRGB for base colour and emissive, linear for metallic-roughness and
    /// normal maps), with their `texCoord` and `KHR_texture_transform` (from `raw`, which
    /// gltf-json drops without its extension features). Unsupported material features are
    /// gathered into one warning naming them and their materials; `BLEND` gets its own.
    pub(super) fn load_materials(
        &mut self,
        doc: &gltf::Document,
        raw: &gltf::json::Value,
        buffers: &[Vec<u8>],
    ) -> Result<(Vec<Material>, Vec<Texture>), RenderError> {
        let mut materials = Vec::new();
        let mut textures = TextureTable::default();
        let mut notes = FeatureNotes::default();
        let mut blend = Vec::new();
        for mat in doc.materials() {
            let index = mat.index().unwrap_or(0);
            let name = mat
                .name()
                .map_or_else(|| format!("materials[{index}]"), str::to_owned);
            let json = &raw["materials"][index];
            let pbr = mat.pbr_metallic_roughness();
            let pbr_json = &json["pbrMetallicRoughness"];
            let [r, g, b, a] = pbr.base_color_factor();
            let mut slot = |loader: &mut Self,
                            info: Option<(gltf::Texture<'_>, u32)>,
                            json: &gltf::json::Value,
                            field: &str,
                            srgb: bool|
             -> Result<Option<TextureRef>, RenderError> {
                let Some((tex, tex_coord)) = info else {
                    return Ok(None);
                };
                let texture = textures.get(loader, doc, buffers, &tex, srgb)?;
                let t = texture_transform(json, TextureRef::new(texture), tex_coord);
                let t = t.unwrap_or_else(|| {
                    notes.add(
                        format!("{field}: non-finite KHR_texture_transform (not applied)"),
                        &name,
                    );
                    TextureRef {
                        tex_coord,
                        ..TextureRef::new(texture)
                    }
                });
                if t.tex_coord > 1 {
                    notes.add(
                        format!(
                            "{field}.texCoord {} (only TEXCOORD_0 and TEXCOORD_1 are read; TEXCOORD_0 is used)",
                            t.tex_coord
                        ),
                        &name,
                    );
                    return Ok(Some(TextureRef { tex_coord: 0, ..t }));
                }
                Ok(Some(t))
            };
            let base_color_texture = slot(
                self,
                pbr.base_color_texture()
                    .map(|i| (i.texture(), i.tex_coord())),
                &pbr_json["baseColorTexture"],
                "baseColorTexture",
                true,
            )?;
            let metallic_roughness_texture = slot(
                self,
                pbr.metallic_roughness_texture()
                    .map(|i| (i.texture(), i.tex_coord())),
                &pbr_json["metallicRoughnessTexture"],
                "metallicRoughnessTexture",
                false,
            )?;
            let normal = mat.normal_texture();
            let normal_scale = normal.as_ref().map_or(1.0, |n| n.scale());
            let normal_texture = slot(
                self,
                normal.map(|n| (n.texture(), n.tex_coord())),
                &json["normalTexture"],
                "normalTexture",
                false,
            )?;
            let emissive_texture = slot(
                self,
                mat.emissive_texture().map(|i| (i.texture(), i.tex_coord())),
                &json["emissiveTexture"],
                "emissiveTexture",
                true,
            )?;
            if mat.occlusion_texture().is_some() {
                notes.add(
                    "occlusionTexture (irrelevant to path tracing, which computes the occlusion itself)"
                        .to_owned(),
                    &name,
                );
            }
            if let Some(exts) = json["extensions"].as_object() {
                for ext in exts.keys() {
                    if !MATERIAL_EXTENSIONS.contains(&ext.as_str()) {
                        notes.add(ext.clone(), &name);
                    }
                }
            }
            if mat
                .transmission()
                .is_some_and(|t| t.transmission_texture().is_some())
            {
                notes.add(
                    "KHR_materials_transmission.transmissionTexture (the factor is used)"
                        .to_owned(),
                    &name,
                );
            }
            let alpha_mode = match mat.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                    cutoff: mat.alpha_cutoff().unwrap_or(0.5),
                },
                gltf::material::AlphaMode::Blend => {
                    blend.push(name.clone());
                    AlphaMode::Mask { cutoff: 0.5 }
                }
            };
            let strength = mat.emissive_strength().unwrap_or(1.0);
            let emission = Vec3::from(mat.emissive_factor()) * strength;
            let finite_or = |v: f32, d: f32| if v.is_finite() { v } else { d };
            materials.push(Material {
                name,
                base_color: Vec3::new(r, g, b),
                alpha: finite_or(a, 1.0).clamp(0.0, 1.0),
                base_color_texture,
                metallic: finite_or(pbr.metallic_factor(), 1.0).clamp(0.0, 1.0),
                roughness: finite_or(pbr.roughness_factor(), 1.0).clamp(0.0, 1.0),
                metallic_roughness_texture,
                normal_texture,
                normal_scale: finite_or(normal_scale, 1.0),
                emissive_texture,
                alpha_mode,
                transmission: mat.transmission().map_or(0.0, |t| {
                    finite_or(t.transmission_factor(), 0.0).clamp(0.0, 1.0)
                }),
                ior: mat.ior().map_or(1.5, |i| finite_or(i, 1.5)),
                emission: if emission.is_finite() {
                    emission.max(Vec3::ZERO)
                } else {
                    Vec3::ZERO
                },
                double_sided: mat.double_sided(),
            });
        }
        if let Some(list) = notes.summary() {
            self.warn(format!(
                "material features not supported and ignored: {list}"
            ));
        }
        if !blend.is_empty() {
            self.warn(format!(
                "alpha mode BLEND is rendered as MASK with alphaCutoff 0.5 (a cut-out, no partial transparency) in {}",
                name_list(&blend)
            ));
        }
        Ok((materials, textures.textures))
    }

    /// Decodes the image of texture `tex` with its sampler settings: RGB sRGB-decoded with the
    /// alpha channel kept if `srgb` (colour textures), linear without alpha otherwise (data
    /// textures). 8 bits per channel (16-bit images are rounded).
    fn load_texture(
        &mut self,
        doc: &gltf::Document,
        tex: &gltf::Texture<'_>,
        buffers: &[Vec<u8>],
        srgb: bool,
    ) -> Result<Texture, RenderError> {
        let image_index = tex.source().index();
        let what = format!("images[{image_index}]");
        let json = doc
            .as_json()
            .images
            .get(image_index)
            .ok_or_else(|| self.err(format!("{what} does not exist")))?;
        let encoded: Vec<u8> = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                let view = doc
                    .views()
                    .nth(view.value())
                    .ok_or_else(|| self.err(format!("{what}.bufferView out of range")))?;
                self.view_bytes(&view, buffers)?.to_vec()
            }
            (None, Some(uri)) => self.read_uri(uri, &what, UriLimit::Image)?,
            (None, None) => return Err(self.err(format!("{what} has neither uri nor bufferView"))),
        };
        let decoded = image::load_from_memory(&encoded)
            .map_err(|e| self.err(format!("{what}: cannot decode image: {e}")))?;
        let rgba = decoded.to_rgba8();
        let (w, h) = (rgba.width() as usize, rgba.height() as usize);
        let mut texture = Texture::from_rgba8(w, h, rgba.as_raw(), srgb, srgb)
            .ok_or_else(|| self.err(format!("{what}: image is empty")))?;
        let sampler = tex.sampler();
        texture.wrap_s = wrap_mode(sampler.wrap_s());
        texture.wrap_t = wrap_mode(sampler.wrap_t());
        if sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest) {
            texture.filter = TextureFilter::Nearest;
        }
        Ok(texture)
    }
}
