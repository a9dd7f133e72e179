//! A glTF document builder for the material tests (geometry in a base64 buffer, textures as
//! PNG data URIs), and the probes they share: rays straight down, albedos, path-traced means.
#![allow(dead_code, unreachable_pub)]

use std::io::Cursor;

use glam::{Vec3, Vec3A};
use gltf::json::Value;
use render::camera::Ray;
use render::integrator::pt;
use render::scene::{Scene, SurfaceInteraction};
use render::{IndependentSampler, Sampler, TransportMode};

/// Parses a JSON fragment.
pub fn j(s: &str) -> Value {
    gltf::json::deserialize::from_str(s).unwrap_or_else(|e| panic!("{e}: {s}"))
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 (RFC 4648, padded).
pub fn base64(data: &[u8]) -> String {
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                out.push(B64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// An RGBA8 image as a PNG data URI.
pub fn png_uri(width: u32, height: u32, rgba: &[u8]) -> String {
    let img = image::RgbaImage::from_raw(width, height, rgba.to_vec()).unwrap();
    let mut bytes = Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    format!("data:image/png;base64,{}", base64(bytes.get_ref()))
}

/// A glTF document under construction: JSON plus one binary buffer.
pub struct Doc {
    v: Value,
    bin: Vec<u8>,
}

/// Optional vertex attributes of a quad (4 vertices, in the order of [`Doc::quad`]).
#[derive(Default)]
pub struct Attrs {
    /// `COLOR_0` as floats (`VEC3` or `VEC4` by length 3 or 4).
    pub colors_f32: Option<Vec<Vec<f32>>>,
    /// `COLOR_0` as normalised integers: (component type, `VEC3`/`VEC4`, bytes).
    pub colors_norm: Option<(u32, &'static str, Vec<u8>)>,
    /// `TANGENT`s.
    pub tangents: Option<[[f32; 4]; 4]>,
    /// `TEXCOORD_1`.
    pub uv1: Option<[[f32; 2]; 4]>,
}

impl Doc {
    /// An empty document: one scene, two samplers (default and NEAREST).
    pub fn new() -> Self {
        let v = j(r#"{
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [], "meshes": [], "accessors": [], "bufferViews": [],
            "materials": [], "textures": [], "images": [], "samplers": [{}, {"magFilter": 9728}]
        }"#);
        Self { v, bin: Vec::new() }
    }

    fn push(&mut self, key: &str, item: Value) -> usize {
        let a = self.v[key].as_array_mut().unwrap();
        a.push(item);
        a.len() - 1
    }

    /// An accessor over `bytes` (one buffer view), `count` elements.
    pub fn accessor(
        &mut self,
        bytes: &[u8],
        component_type: u32,
        normalized: bool,
        ty: &str,
        count: usize,
        target_indices: bool,
    ) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let target = if target_indices { 34963 } else { 34962 };
        let view = self.push(
            "bufferViews",
            j(&format!(
                r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}, "target": {target}}}"#,
                bytes.len()
            )),
        );
        self.push(
            "accessors",
            j(&format!(
                r#"{{"bufferView": {view}, "componentType": {component_type}, "normalized": {normalized}, "type": "{ty}", "count": {count}}}"#
            )),
        )
    }

    /// A float accessor of `count` elements of type `ty`.
    pub fn floats(&mut self, data: &[f32], ty: &str, count: usize) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        self.accessor(&bytes, 5126, false, ty, count, false)
    }

    /// A `size`-wide square at height `z` facing +z, centred at `(cx, cy)`, as a new mesh and
    /// node (with `node_extra` merged into the node). Vertex order: (-,-), (+,-), (+,+), (-,+)
    /// with UVs (0,1), (1,1), (1,0), (0,0): `u` grows with x, `v` downwards (glTF), so the
    /// left half (x < cx) is u < 0.5. `facing_down` reverses the winding (normal -z).
    #[allow(clippy::too_many_arguments)]
    pub fn quad(
        &mut self,
        (cx, cy, z): (f32, f32, f32),
        size: f32,
        material: usize,
        attrs: &Attrs,
        facing_down: bool,
        node_extra: Option<Value>,
    ) {
        let h = size / 2.0;
        let xy = [(-h, -h), (h, -h), (h, h), (-h, h)];
        let pos: Vec<f32> = xy.iter().flat_map(|&(x, y)| [cx + x, cy + y, z]).collect();
        let nz = if facing_down { -1.0 } else { 1.0 };
        let nrm: Vec<f32> = (0..4).flat_map(|_| [0.0, 0.0, nz]).collect();
        let uv = [0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
        let p = self.floats(&pos, "VEC3", 4);
        // POSITION needs its bounds.
        self.v["accessors"][p]["min"] = j(&format!("[{}, {}, {z}]", cx - h, cy - h));
        self.v["accessors"][p]["max"] = j(&format!("[{}, {}, {z}]", cx + h, cy + h));
        let n = self.floats(&nrm, "VEC3", 4);
        let t = self.floats(&uv, "VEC2", 4);
        let idx: [u16; 6] = if facing_down {
            [0, 2, 1, 0, 3, 2]
        } else {
            [0, 1, 2, 0, 2, 3]
        };
        let ib: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let i = self.accessor(&ib, 5123, false, "SCALAR", 6, true);
        let mut attributes = j(&format!(
            r#"{{"POSITION": {p}, "NORMAL": {n}, "TEXCOORD_0": {t}}}"#
        ));
        if let Some(c) = &attrs.colors_f32 {
            let ty = if c[0].len() == 4 { "VEC4" } else { "VEC3" };
            let flat: Vec<f32> = c.iter().flatten().copied().collect();
            attributes["COLOR_0"] = Value::from(self.floats(&flat, ty, 4));
        }
        if let Some((component_type, ty, bytes)) = &attrs.colors_norm {
            let a = self.accessor(bytes, *component_type, true, ty, 4, false);
            attributes["COLOR_0"] = Value::from(a);
        }
        if let Some(tg) = &attrs.tangents {
            let flat: Vec<f32> = tg.iter().flatten().copied().collect();
            attributes["TANGENT"] = Value::from(self.floats(&flat, "VEC4", 4));
        }
        if let Some(uv1) = &attrs.uv1 {
            let flat: Vec<f32> = uv1.iter().flatten().copied().collect();
            attributes["TEXCOORD_1"] = Value::from(self.floats(&flat, "VEC2", 4));
        }
        let mut prim = j(&format!(r#"{{"indices": {i}, "material": {material}}}"#));
        prim["attributes"] = attributes;
        let mut mesh = j(r#"{"primitives": []}"#);
        mesh["primitives"].as_array_mut().unwrap().push(prim);
        let m = self.push("meshes", mesh);
        let mut node = j(&format!(r#"{{"mesh": {m}}}"#));
        if let Some(Value::Object(extra)) = node_extra {
            for (k, v) in extra {
                node[k.as_str()] = v;
            }
        }
        let node = self.push("nodes", node);
        self.v["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(Value::from(node));
    }

    /// A texture over an RGBA8 image; `nearest` selects the NEAREST sampler.
    pub fn texture(&mut self, width: u32, height: u32, rgba: &[u8], nearest: bool) -> usize {
        let img = self.push(
            "images",
            j(&format!(r#"{{"uri": "{}"}}"#, png_uri(width, height, rgba))),
        );
        self.push(
            "textures",
            j(&format!(
                r#"{{"source": {img}, "sampler": {}}}"#,
                usize::from(nearest)
            )),
        )
    }

    /// Adds a material from its JSON.
    pub fn material(&mut self, json: &str) -> usize {
        self.push("materials", j(json))
    }

    /// Lists `name` in `extensionsUsed`.
    pub fn use_extension(&mut self, name: &str) {
        let used = self.v["extensionsUsed"].take();
        let mut used = match used {
            Value::Array(a) => a,
            _ => Vec::new(),
        };
        used.push(Value::from(name));
        self.v["extensionsUsed"] = Value::from(used);
    }

    /// The document with its buffer embedded, loaded as a scene.
    pub fn scene(&self) -> Scene {
        let mut v = self.v.clone();
        v["buffers"] = j(&format!(
            r#"[{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}]"#,
            self.bin.len(),
            base64(&self.bin)
        ));
        let bytes = gltf::json::serialize::to_vec(&v).unwrap();
        Scene::from_gltf_slice(&bytes, None).unwrap_or_else(|e| panic!("{e}"))
    }
}

/// The hit of the ray from `(x, y, z0)` straight down.
pub fn hit_down(scene: &Scene, x: f32, y: f32, z0: f32) -> Option<SurfaceInteraction> {
    scene.intersect(&Ray::new(Vec3A::new(x, y, z0), -Vec3A::Z, 0.0))
}

/// The diffuse albedo of the BSDF at `si` (`pi f(n, n)`; zero for specular BSDFs).
pub fn albedo(scene: &Scene, si: &SurfaceInteraction) -> Vec3 {
    let b = scene.bsdf(si);
    b.eval(Vec3A::Z, Vec3A::Z, TransportMode::Radiance) * std::f32::consts::PI
}

/// A 2x1 texture: left texel `l`, right texel `r` (RGBA8).
pub fn two_texels(l: [u8; 4], r: [u8; 4]) -> Vec<u8> {
    l.iter().chain(&r).copied().collect()
}

/// A one-sided emitter of radiance 10 at height `z` over `x in [x0, x0 + 2]`, facing down.
pub fn add_emitter(doc: &mut Doc, x0: f32, z: f32) {
    let e = doc.material(
        r#"{"name": "light", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]},
            "emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}}}"#,
    );
    doc.use_extension("KHR_materials_emissive_strength");
    doc.quad((x0 + 1.0, 0.0, z), 2.0, e, &Attrs::default(), true, None);
}

/// Mean path-traced radiance (luminance-free: the mean of RGB) of `n` rays straight down from
/// height `z0` through a 0.2-wide square around `(x, 0)`.
pub fn render_down(scene: &Scene, x: f32, z0: f32, n: u64) -> f32 {
    let mut s = IndependentSampler::new(7);
    let mut sum = 0.0f64;
    for i in 0..n {
        s.start_pixel_sample(i, 0);
        let d = s.next_2d() - 0.5;
        let ray = Ray::new(Vec3A::new(x + 0.2 * d.x, 0.2 * d.y, z0), -Vec3A::Z, 0.0);
        let l = pt::li(scene, ray, &mut s, 4);
        assert!(l.is_finite(), "non-finite radiance {l}");
        sum += f64::from(l.element_sum() / 3.0);
    }
    (sum / n as f64) as f32
}

/// A normal texel encoding the unit tangent-space normal `n`.
pub fn encode_normal(n: Vec3) -> [u8; 4] {
    let c = (n * 0.5 + 0.5) * 255.0;
    [c.x.round() as u8, c.y.round() as u8, c.z.round() as u8, 255]
}
