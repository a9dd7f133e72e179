//! glTF 2.0 (.gltf / .glb) loading: container, JSON and validation through the `gltf` crate;
//! buffers, accessors and images read here with every offset and index bounds-checked, so a
//! malformed file gives a [`RenderError`] naming the file and field, never a panic.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec2, Vec3, Vec3A};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::Semantic;

use super::texture::{Texture, TextureFilter, WrapMode};
use super::{CameraSpec, Material, Mesh, Scene};
use crate::error::RenderError;

/// Extensions whose content the loader uses.
const SUPPORTED_EXTENSIONS: [&str; 3] = [
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
];

/// Largest element count of an accessor without a buffer view (all zeros).
const MAX_VIEWLESS_COUNT: usize = 1 << 24;

/// Image size when the file does not say otherwise (the CLI sets the real one).
const DEFAULT_WIDTH: u32 = 512;

/// Loads a file by path.
pub(super) fn load_path(path: &Path) -> Result<Scene, RenderError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("gltf" | "glb")) {
        return Err(RenderError::UnsupportedFormat {
            path: path.to_path_buf(),
        });
    }
    let bytes = std::fs::read(path).map_err(|source| RenderError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    load_slice(&bytes, Some(base), &path.display().to_string())
}

/// Loads glTF or GLB bytes; `file` names the source in errors.
pub(super) fn load_slice(
    bytes: &[u8],
    base_dir: Option<&Path>,
    file: &str,
) -> Result<Scene, RenderError> {
    Loader {
        file,
        base_dir,
        warnings: Vec::new(),
    }
    .load(bytes)
}

struct Loader<'a> {
    file: &'a str,
    base_dir: Option<&'a Path>,
    warnings: Vec<String>,
}

/// A bounds-checked view of an accessor's bytes.
struct AccessorData<'b> {
    bytes: &'b [u8],
    /// Byte offset of element 0 in `bytes`.
    offset: usize,
    stride: usize,
    count: usize,
    data_type: DataType,
    normalized: bool,
}

impl AccessorData<'_> {
    /// Component `c` of element `i` as f32 (normalised integers mapped to [0, 1] / [-1, 1]).
    fn get(&self, i: usize, c: usize) -> f32 {
        let size = self.data_type.size();
        let at = self.offset + i * self.stride + c * size;
        let b = &self.bytes[at..at + size];
        let n = self.normalized;
        match self.data_type {
            DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            DataType::U8 if n => f32::from(b[0]) / 255.0,
            DataType::U8 => f32::from(b[0]),
            DataType::I8 if n => (f32::from(b[0] as i8) / 127.0).max(-1.0),
            DataType::I8 => f32::from(b[0] as i8),
            DataType::U16 => {
                let v = f32::from(u16::from_le_bytes([b[0], b[1]]));
                if n {
                    v / 65535.0
                } else {
                    v
                }
            }
            DataType::I16 => {
                let v = f32::from(i16::from_le_bytes([b[0], b[1]]));
                if n {
                    (v / 32767.0).max(-1.0)
                } else {
                    v
                }
            }
            DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    }

    /// Element `i` as an unsigned integer (index buffers).
    fn get_u32(&self, i: usize) -> u32 {
        let size = self.data_type.size();
        let at = self.offset + i * self.stride;
        let b = &self.bytes[at..at + size];
        match self.data_type {
            DataType::U8 => u32::from(b[0]),
            DataType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk (glTF 2.0 spec, "GLB
/// File Format Specification"), checking every length against the data.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let u32_at = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = u32_at(4).ok_or("GLB header is truncated (12 bytes expected)")?;
    if version != 2 {
        return Err(format!(
            "GLB version {version} is not supported (expected 2)"
        ));
    }
    let length = u32_at(8).ok_or("GLB header is truncated (12 bytes expected)")? as usize;
    if length > bytes.len() || length < 12 {
        return Err(format!(
            "GLB header length {length} does not match the file size {}",
            bytes.len()
        ));
    }
    let bytes = &bytes[..length];
    // A chunk at byte `at`: (type, data, offset of the next chunk).
    type Chunk<'c> = Option<(u32, &'c [u8], usize)>;
    let chunk = |at: usize| -> Result<Chunk<'_>, String> {
        if at >= bytes.len() {
            return Ok(None);
        }
        let (len, ty) = match (u32_at(at), u32_at(at + 4)) {
            (Some(l), Some(t)) if at + 8 <= bytes.len() => (l as usize, t),
            _ => return Err(format!("GLB chunk header at byte {at} is truncated")),
        };
        let start = at + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| format!("GLB chunk at byte {at} (length {len}) exceeds the file"))?;
        Ok(Some((ty, &bytes[start..end], end.div_ceil(4) * 4)))
    };
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    let (ty, json, mut next) = chunk(12)?.ok_or("GLB file has no JSON chunk")?;
    if ty != JSON {
        return Err("the first GLB chunk is not JSON".to_owned());
    }
    let mut bin = None;
    while let Some((ty, data, after)) = chunk(next)? {
        if ty == BIN && bin.is_none() {
            bin = Some(data);
        }
        next = after;
    }
    Ok((json, bin))
}

/// Decodes standard base64 (RFC 4648, with optional `=` padding).
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let text = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for &c in text {
        acc = (acc << 6) | value(c)?;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// Decodes `%XX` escapes of a relative URI into a UTF-8 path.
fn percent_decode(uri: &str) -> Option<String> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok();
            if let Some(v) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).ok()
}

fn wrap_mode(m: gltf::texture::WrappingMode) -> WrapMode {
    match m {
        gltf::texture::WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
        gltf::texture::WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
    }
}

impl Loader<'_> {
    fn err(&self, reason: impl Into<String>) -> RenderError {
        RenderError::gltf(self.file, reason)
    }

    fn warn(&mut self, message: String) {
        if !self.warnings.contains(&message) {
            self.warnings.push(message);
        }
    }

    fn load(mut self, bytes: &[u8]) -> Result<Scene, RenderError> {
        let (json_bytes, bin) = if bytes.starts_with(b"glTF") {
            split_glb(bytes).map_err(|e| self.err(e))?
        } else {
            (bytes, None)
        };
        let root: gltf::json::Root = gltf::json::deserialize::from_slice(json_bytes)
            .map_err(|e| self.err(format!("malformed JSON: {e}")))?;
        self.precheck(&root)?;
        let doc = gltf::Document::from_json(root).map_err(|e| self.err(e.to_string()))?;
        // Raw JSON for node extras (thin lens, motion blur), which gltf-json drops.
        let raw: gltf::json::Value =
            gltf::json::deserialize::from_slice(json_bytes).unwrap_or_default();

        self.check_features(&doc);
        let buffers = self.load_buffers(&doc, bin)?;
        let (materials, textures) = self.load_materials(&doc, &buffers)?;
        let default_material = materials.len() as u32;
        let mut materials = materials;
        materials.push(Material {
            name: "default".to_owned(),
            ..Material::default()
        });

        let mut mesh = Mesh::new();
        let mut camera: Option<(CameraSpec, f32)> = None;
        let mut mesh_cache: HashMap<usize, Mesh> = HashMap::new();
        let nodes: Vec<gltf::Node<'_>> = doc.nodes().collect();
        for (node_index, world) in self.node_world_transforms(&doc, &nodes)? {
            let node = nodes
                .get(node_index)
                .ok_or_else(|| self.err(format!("nodes[{node_index}] does not exist")))?;
            if node.skin().is_some() {
                self.warn(
                    "skins are not supported: skinned meshes are rendered in their bind pose"
                        .to_owned(),
                );
            }
            if let Some(m) = node.mesh() {
                if let std::collections::hash_map::Entry::Vacant(e) = mesh_cache.entry(m.index()) {
                    e.insert(self.load_mesh(&m, &buffers, default_material)?);
                }
                mesh.append_transformed(&mesh_cache[&m.index()], world, 0);
            }
            if camera.is_none() {
                if let Some(c) = node.camera() {
                    camera = self.camera(&doc, &raw, c.index(), node_index, world);
                }
            }
        }
        // The default material is only kept if something uses it (Scene::new would add one
        // for out-of-range ids anyway).
        let (camera, aspect) = match camera {
            Some(c) => c,
            None => {
                let spec = match mesh.bounds() {
                    Some((lo, hi)) => CameraSpec::framing(lo, hi),
                    None => CameraSpec::look_at(Vec3A::Z, Vec3A::ZERO, Vec3A::Y, 45.0),
                };
                (spec, 1.0)
            }
        };
        let height = ((DEFAULT_WIDTH as f32 / aspect).round() as u32).clamp(1, 8 * DEFAULT_WIDTH);
        let mut scene = Scene::new(mesh, materials, textures, camera, DEFAULT_WIDTH, height);
        let mut warnings = self.warnings;
        warnings.append(&mut scene.warnings);
        scene.warnings = warnings;
        Ok(scene)
    }

    /// Checks what gltf-json 1.4.1's validation indexes without a bounds check (it panics on
    /// an out-of-range `POSITION` accessor index).
    fn precheck(&self, root: &gltf::json::Root) -> Result<(), RenderError> {
        use gltf::json::mesh::Semantic as JsonSemantic;
        use gltf::json::validation::Checked;
        for (mi, m) in root.meshes.iter().enumerate() {
            for (pi, p) in m.primitives.iter().enumerate() {
                if let Some(index) = p.attributes.get(&Checked::Valid(JsonSemantic::Positions)) {
                    if index.value() >= root.accessors.len() {
                        return Err(self.err(format!(
                            "meshes[{mi}].primitives[{pi}].attributes.POSITION: accessor {} out of range ({} accessors)",
                            index.value(),
                            root.accessors.len()
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// Warns about features the renderer ignores.
    fn check_features(&mut self, doc: &gltf::Document) {
        let required: Vec<String> = doc.extensions_required().map(str::to_owned).collect();
        for ext in doc.extensions_used() {
            if !SUPPORTED_EXTENSIONS.contains(&ext) {
                let how = if required.iter().any(|r| r == ext) {
                    "required by the file but not supported: the scene may render incorrectly"
                } else {
                    "not supported and ignored"
                };
                self.warn(format!("glTF extension {ext} is {how}"));
            }
        }
        for ext in &required {
            if !SUPPORTED_EXTENSIONS.contains(&ext.as_str())
                && !doc.extensions_used().any(|u| u == ext)
            {
                self.warn(format!(
                    "glTF extension {ext} is required by the file but not supported"
                ));
            }
        }
        if doc.animations().next().is_some() {
            self.warn("animations are not supported: the scene is rendered at rest".to_owned());
        }
        if doc.skins().next().is_some() {
            self.warn(
                "skins are not supported: skinned meshes are rendered in their bind pose"
                    .to_owned(),
            );
        }
    }

    /// Reads the bytes of a URI (data URI or file relative to the base directory).
    fn read_uri(&self, uri: &str, what: &str) -> Result<Vec<u8>, RenderError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, data) = rest
                .split_once(";base64,")
                .ok_or_else(|| self.err(format!("{what}: only base64 data URIs are supported")))?;
            return decode_base64(data)
                .ok_or_else(|| self.err(format!("{what}: invalid base64 in data URI")));
        }
        let path = if let Some(p) = uri.strip_prefix("file://") {
            PathBuf::from(
                percent_decode(p).ok_or_else(|| self.err(format!("{what}: invalid URI")))?,
            )
        } else if uri.contains(':') && !uri.starts_with('/') && uri.find(':') != Some(1) {
            return Err(self.err(format!("{what}: unsupported URI scheme in '{uri}'")));
        } else {
            let rel = percent_decode(uri)
                .ok_or_else(|| self.err(format!("{what}: URI '{uri}' is not valid UTF-8")))?;
            let base = self.base_dir.ok_or_else(|| {
                self.err(format!(
                    "{what}: external file '{rel}' cannot be resolved without a base directory"
                ))
            })?;
            base.join(rel)
        };
        std::fs::read(&path)
            .map_err(|e| self.err(format!("{what}: cannot read '{}': {e}", path.display())))
    }

    fn load_buffers(
        &self,
        doc: &gltf::Document,
        mut bin: Option<&[u8]>,
    ) -> Result<Vec<Vec<u8>>, RenderError> {
        let mut out = Vec::new();
        for buffer in doc.buffers() {
            let what = format!("buffers[{}]", buffer.index());
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => bin
                    .take()
                    .ok_or_else(|| {
                        self.err(format!(
                            "{what} refers to the GLB binary chunk, which is missing"
                        ))
                    })?
                    .to_vec(),
                gltf::buffer::Source::Uri(uri) => self.read_uri(uri, &what)?,
            };
            if data.len() < buffer.length() {
                return Err(self.err(format!(
                    "{what}.byteLength is {} but the data has only {} bytes",
                    buffer.length(),
                    data.len()
                )));
            }
            out.push(data);
        }
        Ok(out)
    }

    /// The bytes of buffer view `view`, bounds-checked.
    fn view_bytes<'b>(
        &self,
        view: &gltf::buffer::View<'_>,
        buffers: &'b [Vec<u8>],
    ) -> Result<&'b [u8], RenderError> {
        let data = buffers.get(view.buffer().index()).ok_or_else(|| {
            self.err(format!("bufferViews[{}].buffer out of range", view.index()))
        })?;
        let start = view.offset();
        start
            .checked_add(view.length())
            .and_then(|end| data.get(start..end))
            .ok_or_else(|| {
                self.err(format!(
                    "bufferViews[{}]: bytes {}..{}+{} exceed buffers[{}] ({} bytes)",
                    view.index(),
                    start,
                    start,
                    view.length(),
                    view.buffer().index(),
                    data.len()
                ))
            })
    }

    /// A bounds-checked reader for accessor `acc`; `allowed` lists acceptable dimensions.
    fn accessor<'b>(
        &mut self,
        acc: &gltf::Accessor<'_>,
        buffers: &'b [Vec<u8>],
        allowed: &[Dimensions],
        what: &str,
    ) -> Result<AccessorData<'b>, RenderError> {
        let i = acc.index();
        if !allowed.contains(&acc.dimensions()) {
            return Err(self.err(format!(
                "accessors[{i}] ({what}) has type {:?}, expected one of {allowed:?}",
                acc.dimensions()
            )));
        }
        if acc.sparse().is_some() {
            return Err(self.err(format!(
                "accessors[{i}] ({what}) is sparse, which is not supported"
            )));
        }
        let elem = acc.data_type().size() * acc.dimensions().multiplicity();
        let count = acc.count();
        let Some(view) = acc.view() else {
            // No buffer view: all zeros (glTF 2.0, 3.6.2.3). Bound the count, since no data
            // bounds it.
            if count > MAX_VIEWLESS_COUNT {
                return Err(self.err(format!(
                    "accessors[{i}] ({what}).count {count} exceeds {MAX_VIEWLESS_COUNT} for an accessor without bufferView"
                )));
            }
            static ZEROS: [u8; 16] = [0; 16];
            return Ok(AccessorData {
                bytes: &ZEROS,
                offset: 0,
                stride: 0,
                count,
                data_type: acc.data_type(),
                normalized: acc.normalized(),
            });
        };
        let bytes = self.view_bytes(&view, buffers)?;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(self.err(format!(
                "bufferViews[{}].byteStride {stride} is smaller than the {elem}-byte elements of accessors[{i}]",
                view.index()
            )));
        }
        let offset = acc.offset();
        let needed = if count == 0 {
            Some(0)
        } else {
            (count - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(elem))
                .and_then(|v| v.checked_add(offset))
        };
        match needed {
            Some(n) if n <= bytes.len() => {}
            _ => {
                return Err(self.err(format!(
                    "accessors[{i}] ({what}): {count} elements of {elem} bytes at byteOffset {offset} with stride {stride} exceed bufferViews[{}] ({} bytes)",
                    view.index(),
                    bytes.len()
                )))
            }
        }
        Ok(AccessorData {
            bytes,
            offset,
            stride,
            count,
            data_type: acc.data_type(),
            normalized: acc.normalized(),
        })
    }

    fn load_materials(
        &mut self,
        doc: &gltf::Document,
        buffers: &[Vec<u8>],
    ) -> Result<(Vec<Material>, Vec<Texture>), RenderError> {
        let mut materials = Vec::new();
        let mut textures = Vec::new();
        let mut texture_of: HashMap<usize, u32> = HashMap::new();
        for mat in doc.materials() {
            let name = mat.name().map_or_else(
                || format!("materials[{}]", mat.index().unwrap_or(0)),
                str::to_owned,
            );
            let pbr = mat.pbr_metallic_roughness();
            let [r, g, b, _] = pbr.base_color_factor();
            let mut base_color_texture = None;
            if let Some(info) = pbr.base_color_texture() {
                if info.tex_coord() != 0 {
                    self.warn(format!(
                        "material '{name}': base colour texture uses TEXCOORD_{}; TEXCOORD_0 is used instead",
                        info.tex_coord()
                    ));
                }
                let tex = info.texture();
                let id = match texture_of.get(&tex.index()) {
                    Some(&id) => id,
                    None => {
                        let t = self.load_texture(doc, &tex, buffers)?;
                        textures.push(t);
                        let id = textures.len() as u32 - 1;
                        texture_of.insert(tex.index(), id);
                        id
                    }
                };
                base_color_texture = Some(id);
            }
            let ignored = [
                (
                    "metallic-roughness",
                    pbr.metallic_roughness_texture().is_some(),
                ),
                ("normal", mat.normal_texture().is_some()),
                ("occlusion", mat.occlusion_texture().is_some()),
                ("emissive", mat.emissive_texture().is_some()),
                (
                    "transmission",
                    mat.transmission()
                        .is_some_and(|t| t.transmission_texture().is_some()),
                ),
            ];
            for (kind, present) in ignored {
                if present {
                    self.warn(format!(
                        "material '{name}': {kind} textures are not supported and ignored"
                    ));
                }
            }
            if mat.alpha_mode() != gltf::material::AlphaMode::Opaque {
                self.warn(format!(
                    "material '{name}': alpha mode {:?} is not supported; rendered opaque",
                    mat.alpha_mode()
                ));
            }
            let strength = mat.emissive_strength().unwrap_or(1.0);
            let emission = Vec3::from(mat.emissive_factor()) * strength;
            let finite_or = |v: f32, d: f32| if v.is_finite() { v } else { d };
            materials.push(Material {
                name,
                base_color: Vec3::new(r, g, b),
                base_color_texture,
                metallic: finite_or(pbr.metallic_factor(), 1.0).clamp(0.0, 1.0),
                roughness: finite_or(pbr.roughness_factor(), 1.0).clamp(0.0, 1.0),
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
        Ok((materials, textures))
    }

    /// Decodes the image of texture `tex` (sRGB base colour) with its sampler settings.
    fn load_texture(
        &mut self,
        doc: &gltf::Document,
        tex: &gltf::Texture<'_>,
        buffers: &[Vec<u8>],
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
            (None, Some(uri)) => self.read_uri(uri, &what)?,
            (None, None) => return Err(self.err(format!("{what} has neither uri nor bufferView"))),
        };
        let decoded = image::load_from_memory(&encoded)
            .map_err(|e| self.err(format!("{what}: cannot decode image: {e}")))?;
        let rgb = decoded.to_rgb8();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        let mut texture = Texture::from_srgb8(w, h, rgb.as_raw())
            .ok_or_else(|| self.err(format!("{what}: image is empty")))?;
        let sampler = tex.sampler();
        texture.wrap_s = wrap_mode(sampler.wrap_s());
        texture.wrap_t = wrap_mode(sampler.wrap_t());
        if sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest) {
            texture.filter = TextureFilter::Nearest;
        }
        Ok(texture)
    }

    /// Every node of the default scene (or of all root nodes if there is no scene) with its
    /// world transform, parents before children. A node reached twice is an error (the glTF
    /// node hierarchy must be a forest), which also rules out cycles.
    fn node_world_transforms(
        &self,
        doc: &gltf::Document,
        nodes: &[gltf::Node<'_>],
    ) -> Result<Vec<(usize, Mat4)>, RenderError> {
        let node_count = nodes.len();
        let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => scene.nodes().map(|n| n.index()).collect(),
            None => {
                let mut is_child = vec![false; node_count];
                for n in nodes {
                    for c in n.children() {
                        if let Some(flag) = is_child.get_mut(c.index()) {
                            *flag = true;
                        }
                    }
                }
                (0..node_count).filter(|&i| !is_child[i]).collect()
            }
        };
        let mut visited = vec![false; node_count];
        let mut out = Vec::new();
        let mut stack: Vec<(usize, Mat4)> = roots
            .into_iter()
            .rev()
            .map(|i| (i, Mat4::IDENTITY))
            .collect();
        while let Some((index, parent)) = stack.pop() {
            let seen = visited
                .get_mut(index)
                .ok_or_else(|| self.err(format!("nodes[{index}] does not exist")))?;
            if *seen {
                return Err(self.err(format!(
                    "nodes[{index}] is reached twice (the node hierarchy must be a tree without cycles)"
                )));
            }
            *seen = true;
            let Some(node) = nodes.get(index) else {
                continue;
            };
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let world = parent * local;
            out.push((index, world));
            let children: Vec<usize> = node.children().map(|c| c.index()).collect();
            for c in children.into_iter().rev() {
                stack.push((c, world));
            }
        }
        Ok(out)
    }

    /// The camera of node `node_index` if it is perspective: its spec and aspect ratio.
    fn camera(
        &mut self,
        doc: &gltf::Document,
        raw: &gltf::json::Value,
        camera_index: usize,
        node_index: usize,
        world: Mat4,
    ) -> Option<(CameraSpec, f32)> {
        let json = doc.as_json().cameras.get(camera_index)?;
        let Some(p) = json.perspective.as_ref() else {
            self.warn(format!(
                "cameras[{camera_index}] is not a perspective camera and is ignored"
            ));
            return None;
        };
        let yfov = if p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI {
            p.yfov
        } else {
            self.warn(format!(
                "cameras[{camera_index}].perspective.yfov {} is outside (0, pi); 0.8 is used",
                p.yfov
            ));
            0.8
        };
        let aspect = p
            .aspect_ratio
            .filter(|a| a.is_finite() && (0.01..=100.0).contains(a))
            .unwrap_or(1.0);
        let mut spec = CameraSpec::from_matrix(world, yfov);
        let extras = &raw["nodes"][node_index]["extras"];
        let num = |key: &str| extras[key].as_f64().map(|v| v as f32);
        if let (Some(radius), Some(focus)) = (num("aperture_radius"), num("focus_distance")) {
            spec.thin_lens = Some((radius, focus));
        }
        if let (Some(open), Some(close)) = (num("shutter_open"), num("shutter_close")) {
            let end = &extras["motion_end_translation"];
            let t = [0, 1, 2].map(|k| end[k].as_f64().map(|v| v as f32));
            if let [Some(x), Some(y), Some(z)] = t {
                // The end pose: the node's rotation and scale with the end translation.
                let node = doc.nodes().nth(node_index)?;
                let (_, r, s) = node.transform().decomposed();
                let local0 = Mat4::from_cols_array_2d(&node.transform().matrix());
                let parent = world * local0.inverse();
                let q = Quat::from_array(r);
                if !(q.is_finite() && q.length() > 1e-6) {
                    return Some((spec, aspect));
                }
                let local1 = Mat4::from_scale_rotation_translation(
                    Vec3::from(s),
                    q.normalize(),
                    Vec3::new(x, y, z),
                );
                let end_spec = CameraSpec::from_matrix(parent * local1, yfov);
                if end_spec.from.is_finite() && end_spec.to.is_finite() {
                    spec.motion = Some((end_spec.from, end_spec.to, open, close));
                }
            }
        }
        Some((spec, aspect))
    }

    /// Reads every supported primitive of `m` in mesh-local space.
    fn load_mesh(
        &mut self,
        m: &gltf::Mesh<'_>,
        buffers: &[Vec<u8>],
        default_material: u32,
    ) -> Result<Mesh, RenderError> {
        let mut out = Mesh::new();
        for prim in m.primitives() {
            let what = format!("meshes[{}].primitives[{}]", m.index(), prim.index());
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.warn(format!(
                    "{what}: primitive mode {mode:?} is not supported and skipped"
                ));
                continue;
            }
            if prim.morph_targets().next().is_some() {
                self.warn(format!(
                    "{what}: morph targets are not supported; the base shape is rendered"
                ));
            }
            let Some(pos_acc) = prim.get(&Semantic::Positions) else {
                self.warn(format!("{what} has no POSITION attribute and is skipped"));
                continue;
            };
            let positions = self.accessor(&pos_acc, buffers, &[Dimensions::Vec3], "POSITION")?;
            if positions.data_type != DataType::F32 {
                self.warn(format!(
                    "{what}: quantized POSITION is read without dequantization"
                ));
            }
            let n = positions.count;
            let normals = match prim.get(&Semantic::Normals) {
                Some(a) => Some(self.accessor(&a, buffers, &[Dimensions::Vec3], "NORMAL")?),
                None => None,
            };
            let uvs = match prim.get(&Semantic::TexCoords(0)) {
                Some(a) => Some(self.accessor(&a, buffers, &[Dimensions::Vec2], "TEXCOORD_0")?),
                None => None,
            };
            for (name, acc) in [("NORMAL", &normals), ("TEXCOORD_0", &uvs)] {
                if let Some(a) = acc {
                    if a.count != n {
                        return Err(self.err(format!(
                            "{what}: {name} has {} elements but POSITION has {n}",
                            a.count
                        )));
                    }
                }
            }
            let base = out.positions.len() as u32;
            if u32::try_from(n)
                .ok()
                .and_then(|n| n.checked_add(base))
                .is_none()
            {
                return Err(self.err(format!("{what}: too many vertices ({n})")));
            }
            for i in 0..n {
                let p = Vec3A::new(
                    positions.get(i, 0),
                    positions.get(i, 1),
                    positions.get(i, 2),
                );
                let nrm = normals.as_ref().map_or(Vec3A::ZERO, |a| {
                    Vec3A::new(a.get(i, 0), a.get(i, 1), a.get(i, 2))
                });
                let uv = uvs
                    .as_ref()
                    .map_or(Vec2::ZERO, |a| Vec2::new(a.get(i, 0), a.get(i, 1)));
                out.add_vertex(p, nrm, uv);
            }
            let indices: Vec<u32> = match prim.indices() {
                Some(a) => {
                    let acc = self.accessor(&a, buffers, &[Dimensions::Scalar], "indices")?;
                    if !matches!(acc.data_type, DataType::U8 | DataType::U16 | DataType::U32) {
                        return Err(self.err(format!(
                            "{what}: indices accessors[{}] must be unsigned integers",
                            a.index()
                        )));
                    }
                    let mut v = Vec::with_capacity(acc.count);
                    for i in 0..acc.count {
                        let idx = acc.get_u32(i);
                        if idx as usize >= n {
                            return Err(self.err(format!(
                                "{what}: index {idx} (element {i} of accessors[{}]) is out of range for {n} vertices",
                                a.index()
                            )));
                        }
                        v.push(idx);
                    }
                    v
                }
                None => (0..n as u32).collect(),
            };
            let material = prim
                .material()
                .index()
                .map_or(default_material, |i| i as u32);
            let mut push =
                |a: u32, b: u32, c: u32| out.add_triangle([base + a, base + b, base + c], material);
            match mode {
                Mode::Triangles => {
                    for t in indices.chunks_exact(3) {
                        push(t[0], t[1], t[2]);
                    }
                }
                Mode::TriangleStrip => {
                    for i in 2..indices.len() {
                        let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                        if i % 2 == 0 {
                            push(a, b, c);
                        } else {
                            push(b, a, c);
                        }
                    }
                }
                _ => {
                    for i in 2..indices.len() {
                        push(indices[0], indices[i - 1], indices[i]);
                    }
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("a$b").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("100%").unwrap(), "100%");
        assert_eq!(percent_decode("%zz").unwrap(), "%zz");
        assert!(percent_decode("%FF").is_none());
    }

    #[test]
    fn glb_container_errors() {
        assert!(split_glb(b"glTF").is_err());
        let mut v = b"glTF".to_vec();
        v.extend(2u32.to_le_bytes());
        v.extend(5u32.to_le_bytes()); // length < 12
        assert!(split_glb(&v).is_err());
        let mut v = b"glTF".to_vec();
        v.extend(2u32.to_le_bytes());
        v.extend(28u32.to_le_bytes());
        v.extend(100u32.to_le_bytes()); // chunk longer than file
        v.extend(0x4E4F_534Au32.to_le_bytes());
        v.extend(b"{}  ");
        assert!(split_glb(&v).is_err());
    }
}
