//! The glTF document before and around parsing: the GLB container, the checks of what
//! gltf-json cannot represent (other glTF versions, Draco, out-of-range indices), validation,
//! and the warnings about unsupported extensions, animations and skins.

use super::Loader;
use crate::error::RenderError;

/// Extensions whose content the loader uses.
const SUPPORTED_EXTENSIONS: [&str; 5] = [
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
];

/// Splits a GLB container into its JSON chunk and optional BIN chunk (glTF 2.0 spec, "GLB
/// File Format Specification"), checking every length against the data.
pub(super) fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
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

impl Loader<'_> {
    /// Checks, before gltf-json reads the document, what it cannot represent: a glTF version
    /// other than 2 (`asset.version`, or the top-level `version` of glTF 1.0 drafts) is an
    /// error; Draco mesh compression (`KHR_draco_mesh_compression`) is an error if the file
    /// requires it, else a warning per compressed primitive (its uncompressed fallback is
    /// used; without one it is not rendered).
    pub(super) fn precheck_raw(&mut self, raw: &gltf::json::Value) -> Result<(), RenderError> {
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
    pub(super) fn validate(&self, root: gltf::json::Root) -> Result<gltf::Document, RenderError> {
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
    pub(super) fn precheck(&self, root: &gltf::json::Root) -> Result<(), RenderError> {
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
    pub(super) fn check_features(&mut self, doc: &gltf::Document) {
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
}

#[cfg(test)]
mod tests {
    use super::*;

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
