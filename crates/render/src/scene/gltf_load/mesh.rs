//! glTF meshes: every triangle primitive (lists, strips and fans) with its positions,
//! normals, texture coordinates, vertex colours, tangents and indices.

use glam::{Vec2, Vec3A, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::Semantic;

use super::Loader;
use crate::error::RenderError;
use crate::scene::Mesh;

impl Loader<'_> {
    /// Reads every supported primitive of `m` in mesh-local space.
    pub(super) fn load_mesh(
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
