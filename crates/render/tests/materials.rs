//! glTF material features, each on a small glTF document built in memory (geometry in a base64
//! buffer, textures as PNG data URIs) and each with a negative control: the same document with
//! the feature removed fails the assertion the feature passes.
//!
//! - metallic-roughness texture: the halves of a quad become a mirror (black: it reflects the
//!   empty sky) and a lit diffuse surface in a path-traced render;
//! - normal map: the shading normal tilts by the encoded angle, towards +u (red) and image-up
//!   (green), with generated tangents, with `TANGENT`s, and under a mirroring node transform;
//!   extreme normal maps give valid normals and finite renders;
//! - `KHR_texture_transform`: an offset of half a texture swaps the halves of a checker; the
//!   transform's `texCoord` override and `TEXCOORD_1`;
//! - `COLOR_0` (float vec3, normalised u8 vec4, normalised u16 vec3) multiplies the base colour;
//! - alpha `MASK`: camera rays, shadow rays (both visibility queries) and a path-traced render
//!   pass through the cut-out half only; `alphaCutoff`, `baseColorFactor` alpha, `COLOR_0`
//!   alpha, `BLEND` (as MASK 0.5, with a warning);
//! - emissive texture and its transform through `Material::emission_at`;
//! - unsupported material features are named in one warning.

use std::io::Cursor;

use glam::{Vec3, Vec3A};
use gltf::json::Value;
use render::camera::Ray;
use render::integrator::pt;
use render::scene::{AlphaMode, Scene, SurfaceInteraction};
use render::{IndependentSampler, Sampler, TransportMode};

/// Parses a JSON fragment.
fn j(s: &str) -> Value {
    gltf::json::deserialize::from_str(s).unwrap_or_else(|e| panic!("{e}: {s}"))
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

fn base64(data: &[u8]) -> String {
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
fn png_uri(width: u32, height: u32, rgba: &[u8]) -> String {
    let img = image::RgbaImage::from_raw(width, height, rgba.to_vec()).unwrap();
    let mut bytes = Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    format!("data:image/png;base64,{}", base64(bytes.get_ref()))
}

/// A glTF document under construction: JSON plus one binary buffer.
struct Doc {
    v: Value,
    bin: Vec<u8>,
}

/// Optional vertex attributes of a quad (4 vertices, in the order of [`Doc::quad`]).
#[derive(Default)]
struct Attrs {
    /// `COLOR_0` as floats (`VEC3` or `VEC4` by length 3 or 4).
    colors_f32: Option<Vec<Vec<f32>>>,
    /// `COLOR_0` as normalised integers: (component type, `VEC3`/`VEC4`, bytes).
    colors_norm: Option<(u32, &'static str, Vec<u8>)>,
    /// `TANGENT`s.
    tangents: Option<[[f32; 4]; 4]>,
    /// `TEXCOORD_1`.
    uv1: Option<[[f32; 2]; 4]>,
}

impl Doc {
    fn new() -> Self {
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
    fn accessor(
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

    fn floats(&mut self, data: &[f32], ty: &str, count: usize) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        self.accessor(&bytes, 5126, false, ty, count, false)
    }

    /// A `size`-wide square at height `z` facing +z, centred at `(cx, cy)`, as a new mesh and
    /// node (with `node_extra` merged into the node). Vertex order: (-,-), (+,-), (+,+), (-,+)
    /// with UVs (0,1), (1,1), (1,0), (0,0): `u` grows with x, `v` downwards (glTF), so the
    /// left half (x < cx) is u < 0.5. `facing_down` reverses the winding (normal -z).
    #[allow(clippy::too_many_arguments)]
    fn quad(
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
    fn texture(&mut self, width: u32, height: u32, rgba: &[u8], nearest: bool) -> usize {
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

    fn material(&mut self, json: &str) -> usize {
        self.push("materials", j(json))
    }

    fn use_extension(&mut self, name: &str) {
        let used = self.v["extensionsUsed"].take();
        let mut used = match used {
            Value::Array(a) => a,
            _ => Vec::new(),
        };
        used.push(Value::from(name));
        self.v["extensionsUsed"] = Value::from(used);
    }

    fn scene(&self) -> Scene {
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
fn hit_down(scene: &Scene, x: f32, y: f32, z0: f32) -> Option<SurfaceInteraction> {
    scene.intersect(&Ray::new(Vec3A::new(x, y, z0), -Vec3A::Z, 0.0))
}

/// The diffuse albedo of the BSDF at `si` (`pi f(n, n)`; zero for specular BSDFs).
fn albedo(scene: &Scene, si: &SurfaceInteraction) -> Vec3 {
    let b = scene.bsdf(si);
    b.eval(Vec3A::Z, Vec3A::Z, TransportMode::Radiance) * std::f32::consts::PI
}

/// A 2x1 texture: left texel `l`, right texel `r` (RGBA8).
fn two_texels(l: [u8; 4], r: [u8; 4]) -> Vec<u8> {
    l.iter().chain(&r).copied().collect()
}

/// A one-sided emitter of radiance 10 at height `z` over `x in [x0, x0 + 2]`, facing down.
fn add_emitter(doc: &mut Doc, x0: f32, z: f32) {
    let e = doc.material(
        r#"{"name": "light", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]},
            "emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}}}"#,
    );
    doc.use_extension("KHR_materials_emissive_strength");
    doc.quad((x0 + 1.0, 0.0, z), 2.0, e, &Attrs::default(), true, None);
}

/// Mean path-traced radiance (luminance-free: the mean of RGB) of `n` rays straight down from
/// height `z0` through a 0.2-wide square around `(x, 0)`.
fn render_down(scene: &Scene, x: f32, z0: f32, n: u64) -> f32 {
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

// ---------------------------------------------------------------------------------------
// Metallic-roughness texture
// ---------------------------------------------------------------------------------------

/// Left texel: metallic (blue 255), roughness 0 (green 0): a mirror. Right texel: roughness 1,
/// metallic 0: diffuse. Both factors are 1, so without the texture the whole quad is a rough
/// metal.
fn mr_scene(with_texture: bool) -> Scene {
    let mut doc = Doc::new();
    let tex = doc.texture(2, 1, &two_texels([0, 0, 255, 255], [0, 255, 0, 255]), true);
    let mr = if with_texture {
        format!(r#", "metallicRoughnessTexture": {{"index": {tex}}}"#)
    } else {
        String::new()
    };
    let m = doc.material(&format!(
        r#"{{"name": "mr", "pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.8, 0.8, 1],
            "metallicFactor": 1, "roughnessFactor": 1{mr}}}}}"#
    ));
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    // The light is off to the side: the mirror half reflects the camera rays into the empty
    // sky, the diffuse half is lit.
    add_emitter(&mut doc, 1.5, 2.0);
    doc.scene()
}

/// The mirror half renders black and the diffuse half bright.
fn mr_halves_differ(scene: &Scene) -> bool {
    let left = render_down(scene, -0.5, 3.0, 4000);
    let right = render_down(scene, 0.5, 3.0, 4000);
    println!("metallic-roughness halves: left {left}, right {right}");
    left < 1e-6 && right > 0.05
}

#[test]
fn metallic_roughness_texture_switches_halves() {
    let s = mr_scene(true);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let l = hit_down(&s, -0.5, 0.0, 3.0).unwrap();
    let r = hit_down(&s, 0.5, 0.0, 3.0).unwrap();
    assert!(s.bsdf(&l).is_specular(), "left half: smooth metal");
    assert!(
        (albedo(&s, &r) - Vec3::splat(0.8)).length() < 1e-4,
        "right half: diffuse"
    );
    assert!(mr_halves_differ(&s));
    // Negative control: without the texture both halves are the same rough metal.
    let control = mr_scene(false);
    assert!(!mr_halves_differ(&control));
}

// ---------------------------------------------------------------------------------------
// Normal maps
// ---------------------------------------------------------------------------------------

/// A normal texel encoding the unit tangent-space normal `n`.
fn encode_normal(n: Vec3) -> [u8; 4] {
    let c = (n * 0.5 + 0.5) * 255.0;
    [c.x.round() as u8, c.y.round() as u8, c.z.round() as u8, 255]
}

/// A quad with a constant normal map encoding `tangent_normal`, optionally with `TANGENT`s and
/// a node transform; `scale` is `normalTexture.scale`.
fn normal_scene(
    tangent_normal: Option<Vec3>,
    scale: f32,
    tangents: Option<[f32; 4]>,
    node_extra: Option<Value>,
) -> Scene {
    let mut doc = Doc::new();
    let nt = match tangent_normal {
        Some(n) => {
            let tex = doc.texture(1, 1, &encode_normal(n), false);
            format!(r#", "normalTexture": {{"index": {tex}, "scale": {scale}}}"#)
        }
        None => String::new(),
    };
    let m = doc.material(&format!(
        r#"{{"name": "bumpy", "pbrMetallicRoughness": {{"metallicFactor": 0}}{nt}}}"#
    ));
    let attrs = Attrs {
        tangents: tangents.map(|t| [t; 4]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &attrs, false, node_extra);
    doc.scene()
}

/// The shading normal seen by a ray straight down onto the quad.
fn shading_normal(s: &Scene) -> Vec3A {
    let si = hit_down(s, 0.3, 0.2, 3.0).expect("the quad");
    assert!((si.ng - Vec3A::Z).length() < 1e-6);
    si.ns
}

/// True if `ns` is tilted by `deg` degrees (within 0.5 degrees) from +z towards `towards`.
fn tilted(ns: Vec3A, deg: f32, towards: Vec3A) -> bool {
    let angle = ns.dot(Vec3A::Z).clamp(-1.0, 1.0).acos().to_degrees();
    let lateral = (ns - Vec3A::Z * ns.dot(Vec3A::Z)).normalize_or_zero();
    println!("ns {ns}: {angle} degrees towards {lateral}");
    (angle - deg).abs() < 0.5 && (deg == 0.0 || lateral.dot(towards) > 0.999)
}

#[test]
fn normal_map_tilts_the_shading_normal_by_a_known_angle() {
    let theta = 30f32.to_radians();
    let (s, c) = theta.sin_cos();
    // Red = +u = +x here; green = image up = decreasing v = +y here.
    let red = Vec3::new(s, 0.0, c);
    let green = Vec3::new(0.0, s, c);
    let scene = normal_scene(Some(red), 1.0, None, None);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(tilted(shading_normal(&scene), 30.0, Vec3A::X));
    assert!(tilted(
        shading_normal(&normal_scene(Some(green), 1.0, None, None)),
        30.0,
        Vec3A::Y
    ));
    // scale multiplies X and Y: 0 removes the tilt.
    assert!(tilted(
        shading_normal(&normal_scene(Some(red), 0.0, None, None)),
        0.0,
        Vec3A::X
    ));
    // Negative control: the same quad without the normal map is not tilted.
    assert!(!tilted(
        shading_normal(&normal_scene(None, 1.0, None, None)),
        30.0,
        Vec3A::X
    ));
}

#[test]
fn normal_map_uses_vertex_tangents_and_handedness() {
    let theta = 30f32.to_radians();
    let (s, c) = theta.sin_cos();
    let red = Vec3::new(s, 0.0, c);
    let green = Vec3::new(0.0, s, c);
    // Tangent +y: red tilts towards +y; bitangent = w (n x t) = w (-x).
    let t = Some([0.0, 1.0, 0.0, 1.0]);
    assert!(tilted(
        shading_normal(&normal_scene(Some(red), 1.0, t, None)),
        30.0,
        Vec3A::Y
    ));
    assert!(tilted(
        shading_normal(&normal_scene(Some(green), 1.0, t, None)),
        30.0,
        -Vec3A::X
    ));
    let t = Some([0.0, 1.0, 0.0, -1.0]);
    assert!(tilted(
        shading_normal(&normal_scene(Some(green), 1.0, t, None)),
        30.0,
        Vec3A::X
    ));
    // Negative control: the tangent is used, not the UVs (which would tilt red towards +x).
    let t = Some([0.0, 1.0, 0.0, 1.0]);
    assert!(!tilted(
        shading_normal(&normal_scene(Some(red), 1.0, t, None)),
        30.0,
        Vec3A::X
    ));
}

/// Under a mirroring node transform (x -> -x) the generated and the given tangents agree:
/// red (+u) now tilts towards -x, green (image up) still towards +y.
#[test]
fn normal_map_follows_a_mirroring_node() {
    let theta = 30f32.to_radians();
    let (s, c) = theta.sin_cos();
    let mirror = || Some(j(r#"{"scale": [-1, 1, 1]}"#));
    for tangents in [None, Some([1.0, 0.0, 0.0, 1.0])] {
        let red = normal_scene(Some(Vec3::new(s, 0.0, c)), 1.0, tangents, mirror());
        assert!(
            tilted(shading_normal(&red), 30.0, -Vec3A::X),
            "{tangents:?}"
        );
        let green = normal_scene(Some(Vec3::new(0.0, s, c)), 1.0, tangents, mirror());
        assert!(
            tilted(shading_normal(&green), 30.0, Vec3A::Y),
            "{tangents:?}"
        );
    }
    // Negative control: without the mirror red tilts towards +x.
    let plain = normal_scene(Some(Vec3::new(s, 0.0, c)), 1.0, None, None);
    assert!(!tilted(shading_normal(&plain), 30.0, -Vec3A::X));
}

/// Normal maps pointing below the surface (or along it) still give unit shading normals
/// inside the geometric hemisphere and finite renders.
#[test]
fn extreme_normal_maps_stay_valid() {
    for texel in [
        Vec3::new(1.0, 0.0, -1.0).normalize(),
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(0.7, 0.7, 0.1).normalize(),
    ] {
        let mut doc = Doc::new();
        let tex = doc.texture(1, 1, &encode_normal(texel), false);
        let m = doc.material(&format!(
            r#"{{"pbrMetallicRoughness": {{"metallicFactor": 0}}, "doubleSided": true,
                "normalTexture": {{"index": {tex}, "scale": 3}}}}"#
        ));
        doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
        add_emitter(&mut doc, -1.0, 2.0);
        let scene = doc.scene();
        let mut s = IndependentSampler::new(3);
        for i in 0..2000 {
            s.start_pixel_sample(i, 0);
            let u = s.next_2d();
            let target = Vec3A::new(u.x * 1.6 - 0.8, u.y * 1.6 - 0.8, 0.0);
            let v = s.next_2d();
            // Directions from both sides, down to grazing.
            let dir =
                Vec3A::new(v.x - 0.5, v.y - 0.5, if i % 2 == 0 { -0.05 } else { 0.05 }).normalize();
            let ray = Ray::new(target - dir * 0.5, dir, 0.0);
            let si = scene.intersect(&ray).expect("the quad");
            assert!((si.ns.length() - 1.0).abs() < 1e-4, "{}", si.ns);
            assert!(si.ns.dot(si.ng) > 0.005, "{} vs {}", si.ns, si.ng);
        }
        assert!(render_down(&scene, 0.0, 1.0, 2000).is_finite());
    }
}

// ---------------------------------------------------------------------------------------
// KHR_texture_transform, TEXCOORD_1
// ---------------------------------------------------------------------------------------

/// A quad with a black | white base-colour texture referenced through `info_extra` (extra
/// textureInfo JSON members), with `TEXCOORD_1 = (1 - u, v)` (mirrored).
fn checker_scene(info_extra: &str) -> Scene {
    let mut doc = Doc::new();
    let tex = doc.texture(
        2,
        1,
        &two_texels([0, 0, 0, 255], [255, 255, 255, 255]),
        true,
    );
    let m = doc.material(&format!(
        r#"{{"pbrMetallicRoughness": {{"metallicFactor": 0,
            "baseColorTexture": {{"index": {tex}{info_extra}}}}}}}"#
    ));
    let attrs = Attrs {
        uv1: Some([[1.0, 1.0], [0.0, 1.0], [0.0, 0.0], [1.0, 0.0]]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &attrs, false, None);
    doc.scene()
}

/// The albedo (red channel) of the left and right halves.
fn checker_halves(s: &Scene) -> (f32, f32) {
    let l = albedo(s, &hit_down(s, -0.5, 0.0, 3.0).unwrap()).x;
    let r = albedo(s, &hit_down(s, 0.5, 0.0, 3.0).unwrap()).x;
    (l, r)
}

#[test]
fn texture_transform_offset_shifts_a_checker() {
    let plain = checker_scene("");
    assert_eq!(checker_halves(&plain), (0.0, 1.0));
    let shifted =
        checker_scene(r#", "extensions": {"KHR_texture_transform": {"offset": [0.5, 0]}}"#);
    assert!(shifted.warnings.is_empty(), "{:?}", shifted.warnings);
    assert_eq!(checker_halves(&shifted), (1.0, 0.0));
    // Scale 2 repeats the checker twice across the quad: u in [0.25, 0.5) reads white.
    let scaled = checker_scene(r#", "extensions": {"KHR_texture_transform": {"scale": [2, 1]}}"#);
    let at = |x: f32| albedo(&scaled, &hit_down(&scaled, x, 0.0, 3.0).unwrap()).x;
    assert_eq!(
        (at(-0.75), at(-0.25), at(0.25), at(0.75)),
        (0.0, 1.0, 0.0, 1.0)
    );
}

#[test]
fn texcoord_1_and_the_transform_override() {
    // texCoord 1 reads the mirrored set: the halves swap.
    assert_eq!(
        checker_halves(&checker_scene(r#", "texCoord": 1"#)),
        (1.0, 0.0)
    );
    // The transform's texCoord overrides the textureInfo's.
    let over = checker_scene(r#", "extensions": {"KHR_texture_transform": {"texCoord": 1}}"#);
    assert_eq!(checker_halves(&over), (1.0, 0.0));
    // Negative control: texCoord 0.
    assert_eq!(
        checker_halves(&checker_scene(r#", "texCoord": 0"#)),
        (0.0, 1.0)
    );
}

// ---------------------------------------------------------------------------------------
// COLOR_0
// ---------------------------------------------------------------------------------------

fn colored_scene(attrs: &Attrs) -> Scene {
    let mut doc = Doc::new();
    let m = doc.material(
        r#"{"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0}}"#,
    );
    doc.quad((0.0, 0.0, 0.0), 2.0, m, attrs, false, None);
    doc.scene()
}

fn centre_albedo(s: &Scene) -> Vec3 {
    albedo(s, &hit_down(s, 0.1, 0.1, 3.0).unwrap())
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    let red = Attrs {
        colors_f32: Some(vec![vec![1.0, 0.0, 0.0]; 4]),
        ..Attrs::default()
    };
    let a = centre_albedo(&colored_scene(&red));
    assert!((a - Vec3::X).length() < 1e-5, "{a}");
    // Normalised unsigned bytes, VEC4 (alpha ignored without a mask).
    let bytes = [255u8, 0, 0, 128].repeat(4);
    let u8s = Attrs {
        colors_norm: Some((5121, "VEC4", bytes)),
        ..Attrs::default()
    };
    let a = centre_albedo(&colored_scene(&u8s));
    assert!((a - Vec3::X).length() < 1e-5, "{a}");
    // Normalised unsigned shorts, VEC3: half green.
    let shorts: Vec<u8> = [0u16, 32768, 0]
        .repeat(4)
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let u16s = Attrs {
        colors_norm: Some((5123, "VEC3", shorts)),
        ..Attrs::default()
    };
    let a = centre_albedo(&colored_scene(&u16s));
    assert!((a - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-4, "{a}");
    // Interpolated across the quad: red on the left vertices, blue on the right.
    let ramp = Attrs {
        colors_f32: Some(vec![
            vec![1.0, 0.0, 0.0],
            vec![0.0, 0.0, 1.0],
            vec![0.0, 0.0, 1.0],
            vec![1.0, 0.0, 0.0],
        ]),
        ..Attrs::default()
    };
    let s = colored_scene(&ramp);
    let a = albedo(&s, &hit_down(&s, -0.5, 0.3, 3.0).unwrap());
    assert!((a - Vec3::new(0.75, 0.0, 0.25)).length() < 1e-4, "{a}");
    // Negative control: no COLOR_0, white.
    let a = centre_albedo(&colored_scene(&Attrs::default()));
    assert!((a - Vec3::ONE).length() < 1e-5, "{a}");
}

// ---------------------------------------------------------------------------------------
// Alpha mask
// ---------------------------------------------------------------------------------------

/// A black quad at z = 0 whose base-colour texture is transparent on the left half (alpha 0)
/// and opaque on the right, with alpha mode `mode`; a white floor at z = -1; a light at
/// z = 2 covering the quad.
fn mask_scene(mode: &str) -> Scene {
    let mut doc = Doc::new();
    let tex = doc.texture(2, 1, &two_texels([0, 0, 0, 0], [0, 0, 0, 255]), true);
    let m = doc.material(&format!(
        r#"{{"name": "leaf", "alphaMode": "{mode}", "doubleSided": true,
            "pbrMetallicRoughness": {{"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0,
            "baseColorTexture": {{"index": {tex}}}}}}}"#
    ));
    let floor = doc.material(
        r#"{"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0}}"#,
    );
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    doc.quad((0.0, 0.0, -1.0), 4.0, floor, &Attrs::default(), false, None);
    add_emitter(&mut doc, -1.0, 2.0);
    doc.scene()
}

/// Camera and shadow rays pass the left (cut-out) half and are stopped by the right half.
fn cutout_works(s: &Scene) -> bool {
    let name = |si: &SurfaceInteraction| s.materials()[si.material as usize].name.clone();
    // Camera rays.
    let left = hit_down(s, -0.5, 0.0, 3.0 - 1.5).unwrap();
    let right = hit_down(s, 0.5, 0.0, 1.5).unwrap();
    let camera_ok = name(&left) == "floor" && name(&right) == "leaf";
    // Shadow rays between free points (BDPT's query) ...
    let free = |x: f32| {
        s.unoccluded_between(
            Vec3A::new(x, 0.0, 1.0),
            Vec3A::ZERO,
            Vec3A::new(x, 0.0, -0.5),
            Vec3A::ZERO,
        )
    };
    // ... and from a surface point on the floor up to the light (PT's query).
    let floor_at = |x: f32| hit_down(s, x, 0.0, -0.5).unwrap();
    let lit = |x: f32| s.unoccluded(&floor_at(x), Vec3A::new(x, 0.0, 2.0));
    println!(
        "camera {} {}, free {} {}, lit {} {}",
        name(&left),
        name(&right),
        free(-0.5),
        free(0.5),
        lit(-0.5),
        lit(0.5)
    );
    camera_ok && free(-0.5) && !free(0.5) && lit(-0.5) && !lit(0.5)
}

#[test]
fn alpha_mask_cuts_out_camera_and_shadow_rays() {
    let s = mask_scene("MASK");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.materials()[0].alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    assert!(cutout_works(&s));
    // Path traced from between the quad and the light: the floor under the cut-out half is
    // lit (camera ray and shadow rays pass), the opaque half is black.
    let left = render_down(&s, -0.5, 1.0, 2000);
    let right = render_down(&s, 0.5, 1.0, 2000);
    println!("mask render: left {left}, right {right}");
    assert!(left > 0.1 && right < 1e-6);
    // Negative control: the same texture and material, opaque.
    let opaque = mask_scene("OPAQUE");
    assert!(!cutout_works(&opaque));
    assert!(render_down(&opaque, -0.5, 1.0, 500) < 1e-6);
}

#[test]
fn blend_is_a_mask_with_a_warning() {
    let s = mask_scene("BLEND");
    let w: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("alpha mode BLEND"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    assert!(w[0].contains("'leaf'"), "{}", w[0]);
    assert!(cutout_works(&s));
}

/// `alpha = baseColorFactor.a x texture alpha x COLOR_0.a`, compared with `alphaCutoff`.
#[test]
fn alpha_sources_and_cutoff() {
    let quad_with = |factor_alpha: f32, cutoff: Option<f32>, color_alpha: Option<f32>| {
        let mut doc = Doc::new();
        // Texture alpha 0.8 everywhere.
        let tex = doc.texture(1, 1, &[255, 255, 255, 204], true);
        let cutoff = cutoff.map_or(String::new(), |c| format!(r#", "alphaCutoff": {c}"#));
        let m = doc.material(&format!(
            r#"{{"alphaMode": "MASK"{cutoff}, "pbrMetallicRoughness": {{
                "baseColorFactor": [1, 1, 1, {factor_alpha}], "baseColorTexture": {{"index": {tex}}}}}}}"#
        ));
        let attrs = Attrs {
            colors_f32: color_alpha.map(|a| vec![vec![1.0, 1.0, 1.0, a]; 4]),
            ..Attrs::default()
        };
        doc.quad((0.0, 0.0, 0.0), 2.0, m, &attrs, false, None);
        let s = doc.scene();
        hit_down(&s, 0.1, 0.1, 3.0).is_some()
    };
    assert!(quad_with(1.0, None, None)); // 0.8 >= 0.5
    assert!(!quad_with(1.0, Some(0.85), None)); // 0.8 < 0.85
    assert!(!quad_with(0.5, None, None)); // 0.4 < 0.5
    assert!(quad_with(0.7, Some(0.55), None)); // 0.56 >= 0.55
    assert!(!quad_with(1.0, None, Some(0.5))); // 0.4 < 0.5
    assert!(quad_with(1.0, None, Some(0.7))); // 0.56 >= 0.5
}

// ---------------------------------------------------------------------------------------
// Emissive texture
// ---------------------------------------------------------------------------------------

#[test]
fn emissive_texture_is_loaded_with_its_transform() {
    let mut doc = Doc::new();
    // sRGB: 188 decodes to about 0.5.
    let tex = doc.texture(
        2,
        1,
        &two_texels([0, 0, 0, 255], [188, 255, 255, 255]),
        true,
    );
    let m = doc.material(&format!(
        r#"{{"name": "screen", "emissiveFactor": [1, 1, 1],
            "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": 4}}}},
            "emissiveTexture": {{"index": {tex},
                "extensions": {{"KHR_texture_transform": {{"offset": [0.5, 0]}}}}}}}}"#
    ));
    doc.use_extension("KHR_materials_emissive_strength");
    doc.use_extension("KHR_texture_transform");
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    let s = doc.scene();
    let mat = &s.materials()[0];
    let et = mat.emissive_texture.expect("emissive texture loaded");
    assert_eq!(et.tex_coord, 0);
    let left = hit_down(&s, -0.5, 0.0, 3.0).unwrap();
    let right = hit_down(&s, 0.5, 0.0, 3.0).unwrap();
    let e = |si: &SurfaceInteraction| mat.emission_at(s.textures(), s.tex_coord(si, et.tex_coord));
    // The offset swaps the halves: the left half reads the right texel.
    let l = e(&left);
    assert!((l.x - 2.0).abs() < 0.05 && (l.y - 4.0).abs() < 1e-4, "{l}");
    assert_eq!(e(&right), Vec3::ZERO);
    // Negative control: the factor alone is uniform.
    assert_eq!(mat.emission, Vec3::splat(4.0));
}

// ---------------------------------------------------------------------------------------
// Unsupported features
// ---------------------------------------------------------------------------------------

#[test]
fn unsupported_material_features_are_one_warning() {
    let mut doc = Doc::new();
    let tex = doc.texture(1, 1, &[255, 255, 255, 255], false);
    doc.material(&format!(
        r#"{{"name": "car paint", "occlusionTexture": {{"index": {tex}}},
            "extensions": {{"KHR_materials_clearcoat": {{"clearcoatFactor": 1}},
                           "KHR_materials_sheen": {{"sheenColorFactor": [1, 1, 1]}}}}}}"#
    ));
    let m = doc.material(&format!(
        r#"{{"name": "velvet", "emissiveFactor": [1, 1, 1],
            "emissiveTexture": {{"index": {tex}, "texCoord": 2}},
            "extensions": {{"KHR_materials_sheen": {{"sheenColorFactor": [1, 0, 0]}}}}}}"#
    ));
    doc.use_extension("KHR_materials_clearcoat");
    doc.use_extension("KHR_materials_sheen");
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    let s = doc.scene();
    let material_warnings: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("material features"))
        .collect();
    assert_eq!(material_warnings.len(), 1, "{:?}", s.warnings);
    let w = material_warnings[0];
    for needle in [
        "occlusionTexture",
        "KHR_materials_clearcoat (in 'car paint')",
        "KHR_materials_sheen (in 'car paint', 'velvet')",
        "emissiveTexture.texCoord 2",
    ] {
        assert!(w.contains(needle), "missing {needle}: {w}");
    }
    // The extensions are not named again, one warning each.
    let others = s
        .warnings
        .iter()
        .filter(|w| !w.contains("material features") && w.contains("KHR_materials_"))
        .count();
    assert_eq!(others, 0, "{:?}", s.warnings);
    // TEXCOORD_0 is used instead of set 2.
    assert_eq!(s.materials()[1].emissive_texture.unwrap().tex_coord, 0);
}

// ---------------------------------------------------------------------------------------
// Every integrator
// ---------------------------------------------------------------------------------------

/// A scene using every supported material feature at once (a tilted normal map with its own
/// tangents, a metallic-roughness texture, a cut-out mask, vertex colours, a texture
/// transform) renders through PT, BDPT, PSSMLT and MMLT without a non-finite sample and not
/// black.
#[test]
fn every_integrator_renders_the_features_finitely() {
    use render::{Budget, IntegratorKind, NoProgress, RenderSettings};
    let mut doc = Doc::new();
    let normal = doc.texture(
        2,
        1,
        &[
            encode_normal(Vec3::new(0.7, 0.0, 0.7).normalize()),
            encode_normal(Vec3::new(0.0, -0.9, 0.1).normalize()),
        ]
        .concat(),
        false,
    );
    let mr = doc.texture(
        2,
        1,
        &two_texels([0, 40, 255, 255], [0, 200, 0, 255]),
        false,
    );
    let base = doc.texture(
        2,
        1,
        &two_texels([200, 90, 30, 0], [90, 200, 90, 255]),
        true,
    );
    let leaf = doc.material(&format!(
        r#"{{"name": "leaf", "alphaMode": "MASK", "doubleSided": true,
            "normalTexture": {{"index": {normal}, "scale": 1.5}},
            "pbrMetallicRoughness": {{"metallicFactor": 1, "roughnessFactor": 1,
                "metallicRoughnessTexture": {{"index": {mr},
                    "extensions": {{"KHR_texture_transform": {{"scale": [3, 3], "rotation": 0.4}}}}}},
                "baseColorTexture": {{"index": {base},
                    "extensions": {{"KHR_texture_transform": {{"scale": [4, 4]}}}}}}}}}}"#
    ));
    let floor = doc.material(
        r#"{"name": "floor", "pbrMetallicRoughness": {"metallicFactor": 0},
            "normalTexture": {"index": 0}}"#,
    );
    doc.use_extension("KHR_texture_transform");
    let tangents = Attrs {
        tangents: Some([[0.6, 0.8, 0.0, -1.0]; 4]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, 0.0), 2.0, leaf, &tangents, false, None);
    let colours = Attrs {
        colors_f32: Some(vec![
            vec![1.0, 0.2, 0.2],
            vec![0.2, 1.0, 0.2],
            vec![0.2, 0.2, 1.0],
            vec![1.0, 1.0, 1.0],
        ]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, -0.7), 4.0, floor, &colours, false, None);
    add_emitter(&mut doc, 1.2, 1.5);
    let scene = doc.scene();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    for integrator in [
        IntegratorKind::Pt,
        IntegratorKind::Bdpt,
        IntegratorKind::Pssmlt,
        IntegratorKind::Mmlt,
    ] {
        let settings = RenderSettings {
            method: integrator.settings(),
            width: 24,
            height: 24,
            budget: Budget::SamplesPerPixel(32),
            threads: 2,
            seed: 3,
            max_depth: 5,
        };
        let out = render::render(
            &scene,
            &settings,
            &NoProgress,
            &std::sync::atomic::AtomicBool::new(false),
        )
        .unwrap();
        let mean = out.image.mean_luminance();
        println!(
            "{integrator:?}: mean {mean}, {} samples, {} non-finite",
            out.samples, out.dropped_nonfinite
        );
        assert_eq!(out.dropped_nonfinite, 0, "{integrator:?}");
        assert!(mean.is_finite() && mean > 1e-3, "{integrator:?}: {mean}");
    }
}
