//! glTF 2.0 (.gltf / .glb) loading: container, JSON and validation through the `gltf` crate;
//! buffers, accessors and images read here with every offset and index bounds-checked, so a
//! malformed file gives a [`RenderError`] naming the file and field, never a panic.

use std::collections::HashMap;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use glam::{Mat4, Quat, Vec2, Vec3, Vec3A, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::Semantic;

use super::texture::{Texture, TextureFilter, WrapMode};
use super::{AlphaMode, TextureRef};
use super::{CameraSpec, LoadOptions, Material, Mesh, Scene, MAX_IMAGE_FILE_BYTES};
use crate::error::RenderError;

/// How much of a URI's target [`Loader::read_uri`] reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum UriLimit {
    /// A buffer: at most this many bytes (its `byteLength`; a shorter file is an error).
    UpTo(u64),
    /// An image: at most [`MAX_IMAGE_FILE_BYTES`]; a larger file is an error.
    Image,
}

/// Extensions whose content the loader uses.
const SUPPORTED_EXTENSIONS: [&str; 5] = [
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
];

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

/// Largest element count of an accessor without a buffer view (all zeros).
const MAX_VIEWLESS_COUNT: usize = 1 << 24;

/// Image size when the file does not say otherwise (the CLI sets the real one).
const DEFAULT_WIDTH: u32 = 512;

/// Loads a file by path. The file must be a regular file (a FIFO would block, a device
/// never end); its folder is the only place external buffers and images may come from unless
/// `options` allow others.
pub(super) fn load_path(path: &Path, options: &LoadOptions) -> Result<Scene, RenderError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("gltf" | "glb")) {
        return Err(RenderError::UnsupportedFormat {
            path: path.to_path_buf(),
        });
    }
    let io_err = |source| RenderError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io_err)?;
    if !meta.is_file() {
        return Err(io_err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("not a regular file ({})", file_kind(&meta)),
        )));
    }
    let bytes = std::fs::read(path).map_err(io_err)?;
    let base = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    load_slice(&bytes, Some(base), &path.display().to_string(), options)
}

/// Loads glTF or GLB bytes; `file` names the source in errors, `base_dir` is the folder
/// relative URIs resolve in.
pub(super) fn load_slice(
    bytes: &[u8],
    base_dir: Option<&Path>,
    file: &str,
    options: &LoadOptions,
) -> Result<Scene, RenderError> {
    Loader {
        file,
        base_dir,
        options: *options,
        warnings: Vec::new(),
    }
    .load(bytes)
}

/// What a file's metadata says it is, for error messages.
fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    let ty = meta.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ty.is_fifo() {
            return "a FIFO";
        }
        if ty.is_char_device() {
            return "a character device";
        }
        if ty.is_block_device() {
            return "a block device";
        }
        if ty.is_socket() {
            return "a socket";
        }
    }
    if ty.is_dir() {
        "a directory"
    } else {
        "a special file"
    }
}

struct Loader<'a> {
    file: &'a str,
    base_dir: Option<&'a Path>,
    options: LoadOptions,
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
        let json_bytes = match json_bytes.strip_prefix(b"\xEF\xBB\xBF") {
            Some(rest) => {
                self.warn(
                    "the JSON starts with a UTF-8 byte-order mark, which glTF does not allow; it was skipped"
                        .to_owned(),
                );
                rest
            }
            None => json_bytes,
        };
        // Raw JSON: for what gltf-json cannot represent (other glTF versions, Draco) and for
        // node extras (thin lens, motion blur), which gltf-json drops.
        let raw: gltf::json::Value = gltf::json::deserialize::from_slice(json_bytes)
            .map_err(|e| self.err(format!("malformed JSON: {e}")))?;
        self.precheck_raw(&raw)?;
        let root: gltf::json::Root = gltf::json::deserialize::from_slice(json_bytes)
            .map_err(|e| self.err(format!("malformed JSON: {e}")))?;
        self.precheck(&root)?;
        let doc = self.validate(root)?;

        self.check_features(&doc);
        let buffers = self.load_buffers(&doc, bin)?;
        let (materials, textures) = self.load_materials(&doc, &raw, &buffers)?;
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
        let mut punctual = Vec::new();
        for (node_index, world) in self.node_world_transforms(&doc, &nodes)? {
            punctual.extend(super::gltf_lights::node_light(
                &raw,
                node_index,
                world,
                &mut self.warnings,
            ));
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
                    camera = self.camera(&doc, &raw, c.index(), node_index, world)?;
                }
            }
        }
        // Cleaned here rather than only in Scene::new, so that the automatic framing sees
        // just the triangles that are rendered: one stray zero-area triangle far away must not
        // make the camera frame a huge empty box.
        let removed = mesh.remove_invalid();
        if removed > 0 {
            self.warn(format!(
                "{removed} degenerate or non-finite triangle(s) were skipped"
            ));
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
        if !punctual.is_empty() {
            scene.add_punctual_lights(punctual);
        }
        let mut warnings = self.warnings;
        warnings.append(&mut scene.warnings);
        scene.warnings = warnings;
        Ok(scene)
    }

    /// Checks, before gltf-json reads the document, what it cannot represent: a glTF version
    /// other than 2 (`asset.version`, or the top-level `version` of glTF 1.0 drafts) is an
    /// error; Draco mesh compression (`KHR_draco_mesh_compression`) is an error if the file
    /// requires it, else a warning per compressed primitive (its uncompressed fallback is
    /// used; without one it is not rendered).
    fn precheck_raw(&mut self, raw: &gltf::json::Value) -> Result<(), RenderError> {
        const DRACO: &str = "KHR_draco_mesh_compression";
        let convert = "only glTF 2.0 is supported (convert the file to glTF 2.0 first)";
        match &raw["asset"]["version"] {
            gltf::json::Value::String(v) if v.split('.').next() != Some("2") => {
                return Err(self.err(format!(
                    "asset.version is \"{v}\": glTF {v} is not supported; {convert}"
                )));
            }
            gltf::json::Value::String(_) => {}
            _ if !raw["version"].is_null() => {
                return Err(self.err(format!(
                    "a top-level \"version\" ({}) and no asset.version: this is a glTF 1.0 (or older) file, which is not supported; {convert}",
                    raw["version"]
                )))
            }
            _ => {}
        }
        let required = raw["extensionsRequired"]
            .as_array()
            .is_some_and(|r| r.iter().any(|e| e.as_str() == Some(DRACO)));
        if required {
            return Err(self.err(format!(
                "extensionsRequired lists {DRACO}: Draco-compressed meshes are not supported (save the file without Draco compression)"
            )));
        }
        let meshes = raw["meshes"].as_array().map_or(&[][..], Vec::as_slice);
        for (mi, m) in meshes.iter().enumerate() {
            let prims = m["primitives"].as_array().map_or(&[][..], Vec::as_slice);
            for (pi, p) in prims.iter().enumerate() {
                if p["extensions"][DRACO].is_null() {
                    continue;
                }
                let position = p["attributes"]["POSITION"].as_u64();
                let has_data = position.is_some_and(|a| {
                    usize::try_from(a).is_ok_and(|a| !raw["accessors"][a]["bufferView"].is_null())
                });
                self.warn(if has_data {
                    format!(
                        "meshes[{mi}].primitives[{pi}] is Draco-compressed ({DRACO}), which is not supported: its uncompressed fallback data is used"
                    )
                } else {
                    format!(
                        "meshes[{mi}].primitives[{pi}] is Draco-compressed ({DRACO}), which is not supported, and has no uncompressed fallback (POSITION has no bufferView): it is not rendered"
                    )
                });
            }
        }
        Ok(())
    }

    /// gltf-json's validation of `root`, except that an accessor without `bufferView` is
    /// accepted: glTF 2.0 (section 3.6.2.3) allows it (the accessor is all zeros), while
    /// gltf-json 1.4.1 reports it as missing data.
    fn validate(&self, root: gltf::json::Root) -> Result<gltf::Document, RenderError> {
        use gltf::json::validation::{Error, Validate};
        let mut errors = Vec::new();
        root.validate(&root, gltf::json::Path::new, &mut |path, error| {
            errors.push((path().to_string(), error));
        });
        errors.retain(|(path, error)| {
            let viewless = path
                .strip_prefix("accessors[")
                .and_then(|p| p.strip_suffix("].bufferView"))
                .is_some_and(|i| i.bytes().all(|b| b.is_ascii_digit()));
            !(viewless && *error == Error::Missing)
        });
        if !errors.is_empty() {
            let list: String = errors.iter().map(|(p, e)| format!(" {p}: {e};")).collect();
            return Err(self.err(format!("invalid glTF:{list}")));
        }
        Ok(gltf::Document::from_json_without_validation(root))
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
            // Material extensions are named by load_materials, with their materials.
            let is_required = required.iter().any(|r| r == ext);
            if ext.contains("_materials_") && !is_required {
                continue;
            }
            if !SUPPORTED_EXTENSIONS.contains(&ext) {
                let how = if is_required {
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

    /// Reads the bytes of the URI of `what` (`buffers[i]` or `images[i]`; errors name its
    /// `.uri` field and say why): a base64 data URI, or a regular file found by
    /// [`Loader::resolve`], read no further than `limit` allows.
    fn read_uri(&self, uri: &str, what: &str, limit: UriLimit) -> Result<Vec<u8>, RenderError> {
        let field = format!("{what}.uri");
        let too_big = |len: u64| {
            self.err(format!(
                "{field}: the image has {len} bytes, more than the {} MiB allowed for an image",
                MAX_IMAGE_FILE_BYTES >> 20
            ))
        };
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, data) = rest
                .split_once(";base64,")
                .ok_or_else(|| self.err(format!("{field}: only base64 data URIs are supported")))?;
            let bytes = decode_base64(data)
                .ok_or_else(|| self.err(format!("{field}: invalid base64 in data URI")))?;
            if limit == UriLimit::Image && bytes.len() as u64 > MAX_IMAGE_FILE_BYTES {
                return Err(too_big(bytes.len() as u64));
            }
            return Ok(bytes);
        }
        let path = self.resolve(uri, &field)?;
        let cannot =
            |e: std::io::Error| self.err(format!("{field}: cannot read '{}': {e}", path.display()));
        let not_regular = |meta: &std::fs::Metadata| {
            self.err(format!(
                "{field}: '{}' is {}, not a regular file; only regular files are read",
                path.display(),
                file_kind(meta)
            ))
        };
        // Checked before opening: opening a FIFO blocks until someone writes to it.
        let meta = std::fs::metadata(&path).map_err(cannot)?;
        if !meta.is_file() {
            return Err(not_regular(&meta));
        }
        let max = match limit {
            UriLimit::UpTo(n) => n,
            UriLimit::Image if meta.len() > MAX_IMAGE_FILE_BYTES => {
                return Err(too_big(meta.len()))
            }
            UriLimit::Image => MAX_IMAGE_FILE_BYTES + 1,
        };
        let file = std::fs::File::open(&path).map_err(cannot)?;
        // What was opened is what counts (the path may have been replaced meanwhile).
        let meta = file.metadata().map_err(cannot)?;
        if !meta.is_file() {
            return Err(not_regular(&meta));
        }
        let mut out = Vec::with_capacity(usize::try_from(meta.len().min(max)).unwrap_or(0));
        file.take(max).read_to_end(&mut out).map_err(cannot)?;
        if limit == UriLimit::Image && out.len() as u64 > MAX_IMAGE_FILE_BYTES {
            return Err(too_big(out.len() as u64));
        }
        Ok(out)
    }

    /// The file a (non-data) URI names, for `field`. Relative references (percent-decoded)
    /// resolve in the scene's folder. Unless [`LoadOptions::allow_external_files`] is set, the
    /// file must be inside that folder: absolute paths are refused, `..` may not leave it, and
    /// the path with every symbolic link resolved (a relative path or a `file://` URI) must
    /// still lie inside the folder with its links resolved. Other URI schemes are refused.
    fn resolve(&self, uri: &str, field: &str) -> Result<PathBuf, RenderError> {
        const HINT: &str =
            "(LoadOptions::allow_external_files or `--allow-external-files` allows other files)";
        let allow = self.options.allow_external_files;
        let decode = |s: &str| {
            percent_decode(s).ok_or_else(|| {
                self.err(format!(
                    "{field}: '{uri}' is not valid UTF-8 after percent-decoding"
                ))
            })
        };
        let colon = uri.find(':');
        let drive_letter = colon == Some(1) && uri.as_bytes()[0].is_ascii_alphabetic();
        let scheme = colon.filter(|&i| {
            i > 1
                && uri[..i]
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'+' | b'-' | b'.'))
        });
        let (path, relative) = if let Some(rest) = uri.strip_prefix("file://") {
            let decoded = decode(rest)?;
            let local = decoded.strip_prefix("localhost").unwrap_or(&decoded);
            if !local.starts_with('/') {
                return Err(self.err(format!(
                    "{field}: '{uri}' names a host; only local file URIs are supported"
                )));
            }
            (PathBuf::from(local), false)
        } else if scheme.is_some() {
            return Err(self.err(format!(
                "{field}: unsupported URI scheme in '{uri}' (only relative paths and data URIs are read)"
            )));
        } else {
            let rel = decode(uri)?;
            let rel_path = PathBuf::from(&rel);
            if rel_path.is_absolute() || rel.starts_with(['/', '\\']) || drive_letter {
                if !allow {
                    return Err(self.err(format!(
                        "{field}: '{uri}' is an absolute path; only files inside the scene folder are read {HINT}"
                    )));
                }
                (rel_path, false)
            } else {
                let base = self.base_dir.ok_or_else(|| {
                    self.err(format!(
                        "{field}: external file '{rel}' cannot be resolved without a base directory"
                    ))
                })?;
                if !allow {
                    let mut depth = 0usize;
                    for c in rel_path.components() {
                        match c {
                            Component::Normal(_) => depth += 1,
                            Component::CurDir => {}
                            Component::ParentDir if depth > 0 => depth -= 1,
                            _ => {
                                return Err(self.err(format!(
                                    "{field}: '{uri}' leaves the scene folder through '..'; only files inside it are read {HINT}"
                                )))
                            }
                        }
                    }
                }
                (base.join(rel_path), true)
            }
        };
        if allow {
            return Ok(path);
        }
        let base = self.base_dir.ok_or_else(|| {
            self.err(format!(
                "{field}: '{uri}' is outside the scene folder (the scene has none) {HINT}"
            ))
        })?;
        let canonical_base = base.canonicalize().map_err(|e| {
            self.err(format!(
                "{field}: cannot resolve the scene folder '{}': {e}",
                base.display()
            ))
        })?;
        let real = path
            .canonicalize()
            .map_err(|e| self.err(format!("{field}: cannot read '{}': {e}", path.display())))?;
        if !real.starts_with(&canonical_base) {
            return Err(self.err(format!(
                "{field}: '{uri}' resolves{} to '{}', outside the scene folder '{}'; only files inside it are read {HINT}",
                if relative { " through a symbolic link" } else { "" },
                real.display(),
                canonical_base.display()
            )));
        }
        Ok(real)
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
                gltf::buffer::Source::Uri(uri) => {
                    self.read_uri(uri, &what, UriLimit::UpTo(buffer.length() as u64))?
                }
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

    /// Reads every material and loads the textures they use (each glTF texture once per
    /// colour space: sRGB for base colour and emissive, linear for metallic-roughness and
    /// normal maps), with their `texCoord` and `KHR_texture_transform` (from `raw`, which
    /// gltf-json drops without its extension features). Unsupported material features are
    /// gathered into one warning naming them and their materials; `BLEND` gets its own.
    fn load_materials(
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
    ///
    /// Nothing falls back silently: a world transform that cannot place a camera (a scale of
    /// 0, non-finite values) and invalid thin-lens or motion extras (non-numeric or
    /// non-finite values, a negative aperture radius, a focus distance <= 0, a shutter that
    /// closes before it opens, an end translation that is not 3 finite numbers) are errors
    /// naming the node and field; an incomplete set of extras (one of `aperture_radius` /
    /// `focus_distance`, or motion without all of `shutter_open`, `shutter_close` and
    /// `motion_end_translation`), a `yfov` outside (0, pi) and an `aspectRatio` outside
    /// [0.01, 100] are warnings saying what is used instead.
    fn camera(
        &mut self,
        doc: &gltf::Document,
        raw: &gltf::json::Value,
        camera_index: usize,
        node_index: usize,
        world: Mat4,
    ) -> Result<Option<(CameraSpec, f32)>, RenderError> {
        let Some(json) = doc.as_json().cameras.get(camera_index) else {
            return Ok(None);
        };
        let Some(p) = json.perspective.as_ref() else {
            self.warn(format!(
                "cameras[{camera_index}] is not a perspective camera and is ignored"
            ));
            return Ok(None);
        };
        let yfov = if p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI {
            p.yfov
        } else {
            self.warn(format!(
                "cameras[{camera_index}].perspective.yfov {} (used by nodes[{node_index}]) is outside (0, pi); 0.8 is used",
                p.yfov
            ));
            0.8
        };
        let aspect = match p.aspect_ratio {
            Some(a) if !(a.is_finite() && (0.01..=100.0).contains(&a)) => {
                self.warn(format!(
                    "cameras[{camera_index}].perspective.aspectRatio {a} is outside [0.01, 100]; 1 is used"
                ));
                1.0
            }
            a => a.unwrap_or(1.0),
        };
        let mut spec = CameraSpec::from_matrix(world, yfov).ok_or_else(|| {
            self.err(format!(
                "nodes[{node_index}] (camera cameras[{camera_index}]): its world transform cannot place a camera (a scale of 0, non-finite values or a degenerate matrix)"
            ))
        })?;
        let extras = &raw["nodes"][node_index]["extras"];
        let field = |key: &str| format!("nodes[{node_index}].extras.{key}");
        // A present extras number as a finite f32 (absent or null: None).
        let file = self.file;
        let num = |key: &str| -> Result<Option<f32>, RenderError> {
            match &extras[key] {
                gltf::json::Value::Null => Ok(None),
                v => match v.as_f64().map(|x| x as f32) {
                    Some(x) if x.is_finite() => Ok(Some(x)),
                    _ => Err(RenderError::gltf(
                        file,
                        format!("{} = {v} is not a finite number", field(key)),
                    )),
                },
            }
        };
        match (num("aperture_radius")?, num("focus_distance")?) {
            (Some(radius), Some(focus)) => {
                if radius < 0.0 {
                    return Err(self.err(format!(
                        "{} = {radius} is negative (the lens radius in metres, >= 0)",
                        field("aperture_radius")
                    )));
                }
                if focus <= 0.0 {
                    return Err(self.err(format!(
                        "{} = {focus} must be > 0 (metres along the view direction)",
                        field("focus_distance")
                    )));
                }
                spec.thin_lens = Some((radius, focus));
            }
            (None, None) => {}
            (r, _) => {
                let (given, missing) = if r.is_some() {
                    ("aperture_radius", "focus_distance")
                } else {
                    ("focus_distance", "aperture_radius")
                };
                self.warn(format!(
                    "nodes[{node_index}].extras has {given} but no {missing}: the camera is a pinhole"
                ));
            }
        }
        let open = num("shutter_open")?;
        let close = num("shutter_close")?;
        let end = &extras["motion_end_translation"];
        let end = if end.is_null() {
            None
        } else {
            let t = end.as_array().filter(|a| a.len() == 3).map(|a| {
                a.iter()
                    .map(|v| v.as_f64().map(|x| x as f32).filter(|x| x.is_finite()))
                    .collect::<Option<Vec<f32>>>()
            });
            match t {
                Some(Some(t)) => Some(Vec3::new(t[0], t[1], t[2])),
                _ => {
                    return Err(self.err(format!(
                        "{} = {end} is not an array of 3 finite numbers",
                        field("motion_end_translation")
                    )))
                }
            }
        };
        match (open, close, end) {
            (None, None, None) => {}
            (Some(open), Some(close), Some(end)) => {
                if close < open {
                    return Err(self.err(format!(
                        "{} = {close} is before {} = {open}",
                        field("shutter_close"),
                        field("shutter_open")
                    )));
                }
                // The end pose: the node's rotation and scale with the end translation.
                let node = doc
                    .nodes()
                    .nth(node_index)
                    .ok_or_else(|| self.err(format!("nodes[{node_index}] does not exist")))?;
                let (_, r, s) = node.transform().decomposed();
                let local0 = Mat4::from_cols_array_2d(&node.transform().matrix());
                // Invertible: from_matrix accepted world = parent * local0.
                let parent = world * local0.inverse();
                let q = Quat::from_array(r);
                if !(q.is_finite() && q.length() > 1e-6) {
                    return Err(self.err(format!(
                        "nodes[{node_index}].rotation {r:?} is not a rotation quaternion: the motion end pose cannot be built"
                    )));
                }
                let local1 =
                    Mat4::from_scale_rotation_translation(Vec3::from(s), q.normalize(), end);
                let end_spec = CameraSpec::from_matrix(parent * local1, yfov).ok_or_else(|| {
                    self.err(format!(
                        "{}: the camera's end pose is degenerate (non-finite or singular transform)",
                        field("motion_end_translation")
                    ))
                })?;
                spec.motion = Some((end_spec.from, end_spec.to, open, close));
            }
            (o, c, e) => {
                let missing: Vec<&str> = [
                    ("shutter_open", o.is_none()),
                    ("shutter_close", c.is_none()),
                    ("motion_end_translation", e.is_none()),
                ]
                .iter()
                .filter(|m| m.1)
                .map(|m| m.0)
                .collect();
                self.warn(format!(
                    "nodes[{node_index}].extras: camera motion needs shutter_open, shutter_close and motion_end_translation; {} missing: the camera is static",
                    missing.join(", ")
                ));
            }
        }
        Ok(Some((spec, aspect)))
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
            let uvs1 = match prim.get(&Semantic::TexCoords(1)) {
                Some(a) => Some(self.accessor(&a, buffers, &[Dimensions::Vec2], "TEXCOORD_1")?),
                None => None,
            };
            // COLOR_0: vec3 or vec4 (float, or normalised unsigned byte / short).
            let (colors, color_alpha) = match prim.get(&Semantic::Colors(0)) {
                Some(a) => {
                    let has_alpha = a.dimensions() == Dimensions::Vec4;
                    let d = self.accessor(
                        &a,
                        buffers,
                        &[Dimensions::Vec3, Dimensions::Vec4],
                        "COLOR_0",
                    )?;
                    (Some(d), has_alpha)
                }
                None => (None, false),
            };
            let tangents = match prim.get(&Semantic::Tangents) {
                Some(a) => Some(self.accessor(&a, buffers, &[Dimensions::Vec4], "TANGENT")?),
                None => None,
            };
            for (name, acc) in [
                ("NORMAL", &normals),
                ("TEXCOORD_0", &uvs),
                ("TEXCOORD_1", &uvs1),
                ("COLOR_0", &colors),
                ("TANGENT", &tangents),
            ] {
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
                let v = out.add_vertex(p, nrm, uv);
                if let Some(a) = &uvs1 {
                    out.set_uv1(v, Vec2::new(a.get(i, 0), a.get(i, 1)));
                }
                if let Some(a) = &colors {
                    let alpha = if color_alpha { a.get(i, 3) } else { 1.0 };
                    out.set_color(v, Vec4::new(a.get(i, 0), a.get(i, 1), a.get(i, 2), alpha));
                }
                if let Some(a) = &tangents {
                    let t = Vec4::new(a.get(i, 0), a.get(i, 1), a.get(i, 2), a.get(i, 3));
                    out.set_tangent(v, t);
                }
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
