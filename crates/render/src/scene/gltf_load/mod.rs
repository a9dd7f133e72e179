//! glTF 2.0 (.gltf / .glb) loading: container, JSON and validation through the `gltf` crate;
//! buffers, accessors and images read here with every offset and index bounds-checked, so a
//! malformed file gives a [`RenderError`] naming the file and field, never a panic.

mod buffers;
mod camera;
mod document;
mod materials;
mod mesh;
mod uri;

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec3A};

use super::{CameraSpec, LoadOptions, Material, Mesh, Scene};
use crate::error::RenderError;
use document::split_glb;

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
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(
        &mut crate::files::open_regular(path).map_err(io_err)?,
        &mut bytes,
    )
    .map_err(io_err)?;
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

/// One glTF document being read: the file it came from (for errors), the folder its URIs
/// resolve in, the options, and the warnings gathered so far.
struct Loader<'a> {
    file: &'a str,
    base_dir: Option<&'a Path>,
    options: LoadOptions,
    warnings: Vec<String>,
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
}
