//! Scene loading: valid glTF / GLB fixtures (tests/data, written by `make_fixtures.py`) and the
//! bundled scenes load with the expected content; malformed files, missing files and
//! out-of-range indices give errors naming the file; unsupported features give warnings.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3A};
use gltf::json::Value;
use render::error::RenderError;
use render::scene::Scene;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn tmp_dir(test: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("scene_load-{test}"));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The embedded fixture's JSON, to edit.
fn embedded_json() -> Value {
    let bytes = std::fs::read(data("tiny-embedded.gltf")).unwrap();
    gltf::json::deserialize::from_slice(&bytes).unwrap()
}

fn to_bytes(v: &Value) -> Vec<u8> {
    gltf::json::serialize::to_vec(v).unwrap()
}

/// Loads `v` from memory and returns the error message.
fn load_err(v: &Value) -> String {
    match Scene::from_gltf_slice(&to_bytes(v), None) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

fn check_fixture_scene(s: &Scene) {
    // Floor (2) + light (2) + glass (1) triangles; the light's two triangles are lights.
    assert_eq!(s.mesh().triangle_count(), 5);
    assert_eq!(s.lights().lights().len(), 2);
    assert_eq!(s.textures().len(), 1);
    let names: Vec<&str> = s.materials().iter().map(|m| m.name.as_str()).collect();
    assert_eq!(&names[..3], ["floor", "light", "glass"]);
    let glass = &s.materials()[2];
    assert_eq!((glass.transmission, glass.ior), (1.0, 1.5));
    let light = &s.materials()[1];
    assert!(
        (light.emission - glam::Vec3::new(10.0, 9.0, 8.0))
            .abs()
            .max_element()
            < 1e-5
    );
    // Node transforms: the group node moves everything down by 0.5.
    let (lo, hi) = s.bounds().unwrap();
    assert!(
        (lo.y + 0.5).abs() < 1e-6 && (hi.y - 1.0).abs() < 1e-6,
        "{lo} {hi}"
    );
    // The camera node (translation (0, 0.5, 3)) looks down -z; aspect 1.5 gives 512 x 341.
    let spec = s.camera_spec();
    assert!((spec.from - Vec3A::new(0.0, 0.5, 3.0)).length() < 1e-6);
    assert!((spec.to - spec.from).normalize().dot(-Vec3A::Z) > 0.9999);
    assert!((spec.vfov_deg - 0.8f32.to_degrees()).abs() < 1e-3);
    assert_eq!((s.camera().width(), s.camera().height()), (512, 341));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // A ray from the camera down to the floor hits the textured material.
    let ray = render::camera::Ray::new(spec.from, Vec3A::new(0.0, -1.0, -3.0).normalize(), 0.0);
    let si = s.intersect(&ray).expect("floor hit");
    assert_eq!(si.material, 0);
    assert!((si.ns - Vec3A::Y).length() < 1e-5);
    assert!(si.uv.min_element() >= 0.0 && si.uv.max_element() <= 1.0);
}

#[test]
fn gltf_with_external_buffer_and_image_loads() {
    let s = Scene::load(&data("tiny.gltf")).unwrap();
    check_fixture_scene(&s);
}

#[test]
fn embedded_gltf_loads_from_a_slice() {
    let bytes = std::fs::read(data("tiny-embedded.gltf")).unwrap();
    let s = Scene::from_gltf_slice(&bytes, None).unwrap();
    check_fixture_scene(&s);
}

#[test]
fn glb_loads_from_file_and_slice() {
    let s = Scene::load(&data("tiny.glb")).unwrap();
    check_fixture_scene(&s);
    let bytes = std::fs::read(data("tiny.glb")).unwrap();
    check_fixture_scene(&Scene::from_gltf_slice(&bytes, None).unwrap());
}

#[test]
fn set_resolution_changes_the_camera_only() {
    let mut s = Scene::load(&data("tiny.glb")).unwrap();
    s.set_resolution(64, 32);
    assert_eq!((s.camera().width(), s.camera().height()), (64, 32));
    let r = s
        .camera()
        .generate_ray(Vec2::new(32.0, 16.0), Vec2::ZERO, 0.0);
    assert!((r.dir - (-Vec3A::Z)).length() < 1e-4);
}

#[test]
fn missing_file_and_wrong_extension() {
    let missing = data("does-not-exist.gltf");
    let err = Scene::load(&missing).unwrap_err();
    assert!(matches!(err, RenderError::Io { .. }), "{err}");
    assert!(err.to_string().contains("does-not-exist.gltf"), "{err}");
    let err = Scene::load(&data("checker.png")).unwrap_err();
    assert!(
        matches!(err, RenderError::UnsupportedFormat { .. }),
        "{err}"
    );
    assert!(err.to_string().contains("checker.png"));
}

#[test]
fn malformed_json_names_the_file() {
    let dir = tmp_dir("malformed");
    let path = dir.join("broken.gltf");
    std::fs::write(
        &path,
        b"{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ ",
    )
    .unwrap();
    let err = Scene::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("broken.gltf") && err.contains("malformed JSON"),
        "{err}"
    );
    // Valid JSON but not glTF (no asset).
    std::fs::write(&path, b"[1, 2, 3]").unwrap();
    let err = Scene::load(&path).unwrap_err().to_string();
    assert!(err.contains("broken.gltf"), "{err}");
}

#[test]
fn missing_buffer_file_names_both_files() {
    let dir = tmp_dir("missing-buffer");
    let mut v: Value =
        gltf::json::deserialize::from_slice(&std::fs::read(data("tiny.gltf")).unwrap()).unwrap();
    v["buffers"][0]["uri"] = Value::from("gone.bin");
    let path = dir.join("needs-gone.gltf");
    std::fs::write(&path, to_bytes(&v)).unwrap();
    let err = Scene::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("needs-gone.gltf") && err.contains("buffers[0]") && err.contains("gone.bin"),
        "{err}"
    );
    // From memory without a base directory, external files cannot be resolved.
    let err = Scene::from_gltf_slice(&to_bytes(&v), None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("<memory>") && err.contains("base directory"),
        "{err}"
    );
}

#[test]
fn missing_image_file_is_an_error() {
    let dir = tmp_dir("missing-image");
    std::fs::copy(data("tiny.bin"), dir.join("tiny.bin")).unwrap();
    let mut v: Value =
        gltf::json::deserialize::from_slice(&std::fs::read(data("tiny.gltf")).unwrap()).unwrap();
    v["images"][0]["uri"] = Value::from("nope.png");
    let path = dir.join("no-image.gltf");
    std::fs::write(&path, to_bytes(&v)).unwrap();
    let err = Scene::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("images[0]") && err.contains("nope.png"),
        "{err}"
    );
}

#[test]
fn out_of_range_indices_are_errors() {
    // An attribute pointing at a non-existent accessor (caught by glTF validation).
    let mut v = embedded_json();
    v["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = Value::from(99);
    let err = load_err(&v);
    assert!(
        err.contains("<memory>") && err.contains("POSITION"),
        "{err}"
    );

    // An accessor whose elements run past its buffer view.
    let mut v = embedded_json();
    v["accessors"][0]["count"] = Value::from(1000);
    let err = load_err(&v);
    assert!(
        err.contains("accessors[0]") && err.contains("exceed"),
        "{err}"
    );

    // A buffer view past the end of its buffer.
    let mut v = embedded_json();
    v["bufferViews"][1]["byteOffset"] = Value::from(1_000_000);
    let err = load_err(&v);
    assert!(err.contains("bufferViews[1]"), "{err}");

    // A vertex index past the vertex count.
    let mut v = embedded_json();
    let index_view = v["accessors"][3]["bufferView"].as_u64().unwrap() as usize;
    let offset = v["bufferViews"][index_view]["byteOffset"].as_u64().unwrap() as usize;
    let uri = v["buffers"][0]["uri"].as_str().unwrap().to_owned();
    let (head, b64) = uri.split_once(";base64,").unwrap();
    let mut buf = decode_b64(b64);
    buf[offset..offset + 2].copy_from_slice(&500u16.to_le_bytes());
    v["buffers"][0]["uri"] = Value::from(format!("{head};base64,{}", encode_b64(&buf)));
    let err = load_err(&v);
    assert!(
        err.contains("index 500") && err.contains("out of range"),
        "{err}"
    );

    // A declared buffer length larger than the data.
    let mut v = embedded_json();
    v["buffers"][0]["byteLength"] = Value::from(100_000);
    let err = load_err(&v);
    assert!(err.contains("buffers[0].byteLength"), "{err}");

    // A node hierarchy with a cycle.
    let mut v = embedded_json();
    v["nodes"][1]["children"] = Value::from(vec![0]);
    let err = load_err(&v);
    assert!(err.contains("nodes["), "{err}");
}

#[test]
fn truncated_and_corrupt_glb_are_errors() {
    let bytes = std::fs::read(data("tiny.glb")).unwrap();
    for len in [4, 11, 12, 19, 20, 100, bytes.len() - 1] {
        let err = Scene::from_gltf_slice(&bytes[..len], None).unwrap_err();
        assert!(matches!(err, RenderError::Gltf { .. }), "{len}: {err}");
    }
    let mut v2 = bytes.clone();
    v2[4] = 1; // version 1
    assert!(Scene::from_gltf_slice(&v2, None)
        .unwrap_err()
        .to_string()
        .contains("version"));
}

#[test]
fn unsupported_features_are_warnings() {
    let mut v = embedded_json();
    let used = v["extensionsUsed"].as_array_mut().unwrap();
    used.push(Value::from("KHR_lights_punctual"));
    // Supported: KHR_texture_transform and normal maps; unsupported:
    // clearcoat and occlusion textures (named in the one material warning).
    used.push(Value::from("KHR_materials_clearcoat"));
    v["materials"][0]["extensions"]["KHR_materials_clearcoat"] =
        gltf::json::deserialize::from_str(r#"{"clearcoatFactor": 1}"#).unwrap();
    v["extensions"] = gltf::json::deserialize::from_str(
        r#"{"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 5.0}]}}"#,
    )
    .unwrap();
    v["materials"][0]["occlusionTexture"] =
        gltf::json::deserialize::from_str(r#"{"index": 0}"#).unwrap();
    v["materials"][0]["alphaMode"] = Value::from("BLEND");
    v["meshes"][1]["primitives"][0]["mode"] = Value::from(1); // lines
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    let all = s.warnings.join("\n");
    // (KHR_lights_punctual is supported: no warning needed.)
    for needle in [
        "KHR_materials_clearcoat",
        "occlusionTexture",
        "alpha mode",
        "mode Lines",
    ] {
        assert!(
            all.contains(needle),
            "missing warning about {needle}: {all}"
        );
    }
    // The line primitive was skipped: only floor and light remain.
    assert_eq!(s.mesh().triangle_count(), 4);
}

#[test]
fn no_camera_frames_the_scene_and_no_geometry_is_a_warning() {
    let mut v = embedded_json();
    v["scenes"][0]["nodes"] = Value::from(vec![0]);
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    let (lo, hi) = s.bounds().unwrap();
    let c = s.camera_spec();
    assert!((c.to - (lo + hi) * 0.5).length() < 1e-5);
    assert!(c.from.z > hi.z);

    let mut v = embedded_json();
    v["scenes"][0]["nodes"] = Value::from(Vec::<u32>::new());
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    assert_eq!(s.mesh().triangle_count(), 0);
    assert!(
        s.warnings.iter().any(|w| w.contains("no triangles")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn bundled_scenes_load_with_camera_extras() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    for name in [
        "cornell",
        "cornell-glass",
        "caustic-pool",
        "ajar-door",
        "glossy-highlight",
        "glossy-diffuse",
        "dof",
        "motion-blur",
        "thin-highlight",
        "thin-bar",
    ] {
        let s = Scene::load(&scenes.join(format!("{name}.gltf")))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        assert!(!s.lights().is_empty(), "{name} has lights");
        assert!(s.mesh().triangle_count() > 0);
        let spec = s.camera_spec();
        assert_eq!(spec.thin_lens.is_some(), name == "dof", "{name}");
        assert_eq!(spec.motion.is_some(), name == "motion-blur", "{name}");
        // The centre ray hits something.
        let c = s.camera();
        let ray = c.generate_ray(
            Vec2::new(c.width() as f32 / 2.0, c.height() as f32 / 2.0),
            Vec2::splat(0.5),
            0.5,
        );
        assert!(s.intersect(&ray).is_some(), "{name}");
    }
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

fn encode_b64(data: &[u8]) -> String {
    let mut out = String::new();
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

fn decode_b64(s: &str) -> Vec<u8> {
    let mut out = Vec::new();
    let (mut acc, mut bits) = (0u32, 0);
    for c in s.bytes().filter(|&c| c != b'=') {
        acc = (acc << 6) | B64.iter().position(|&b| b == c).unwrap() as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    out
}

/// A glTF with one mesh of `positions` and `indices` (u32), no camera, no material, the buffer
/// as a data URI.
fn mesh_gltf(positions: &[[f32; 3]], indices: &[u32]) -> Value {
    let mut buf = Vec::new();
    for p in positions {
        for c in p {
            buf.extend(c.to_le_bytes());
        }
    }
    let pos_len = buf.len();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in positions {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    for i in indices {
        buf.extend(i.to_le_bytes());
    }
    let json = format!(
        r#"{{
        "asset": {{"version": "2.0"}},
        "scenes": [{{"nodes": [0]}}], "scene": 0,
        "nodes": [{{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
        "accessors": [
            {{"bufferView": 0, "componentType": 5126, "count": {}, "type": "VEC3",
             "min": {lo:?}, "max": {hi:?}}},
            {{"bufferView": 1, "componentType": 5125, "count": {}, "type": "SCALAR"}}],
        "bufferViews": [
            {{"buffer": 0, "byteOffset": 0, "byteLength": {pos_len}}},
            {{"buffer": 0, "byteOffset": {pos_len}, "byteLength": {}}}],
        "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}]
    }}"#,
        positions.len(),
        indices.len(),
        buf.len() - pos_len,
        buf.len(),
        encode_b64(&buf)
    );
    gltf::json::deserialize::from_str(&json).unwrap()
}

/// The 8 corners and 12 outward triangles of the box `[-h, h]^3`.
fn box_mesh(h: f32) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut p = Vec::new();
    for i in 0..8 {
        let s = |bit: u32| if i >> bit & 1 == 1 { h } else { -h };
        p.push([s(0), s(1), s(2)]);
    }
    #[rustfmt::skip]
    let idx = vec![
        0, 2, 1, 1, 2, 3, // z = -h
        4, 5, 6, 5, 7, 6, // z = +h
        0, 1, 4, 1, 5, 4, // y = -h
        2, 6, 3, 3, 6, 7, // y = +h
        0, 4, 2, 2, 4, 6, // x = -h
        1, 3, 5, 3, 7, 5, // x = +h
    ];
    (p, idx)
}

/// The ray through the image centre hits the scene.
fn centre_ray_hits(s: &Scene) -> bool {
    let c = s.camera();
    let ray = c.generate_ray(
        Vec2::new(c.width() as f32 / 2.0, c.height() as f32 / 2.0),
        Vec2::splat(0.5),
        0.5,
    );
    s.intersect(&ray).is_some()
}

#[test]
fn framing_ignores_a_stray_degenerate_triangle() {
    let (mut p, mut idx) = box_mesh(0.25);
    // One zero-area (collinear) triangle 1000 m away.
    let base = p.len() as u32;
    p.extend([[1000.0, 0.0, 0.0], [1001.0, 0.0, 0.0], [1002.0, 0.0, 0.0]]);
    idx.extend([base, base + 1, base + 2]);
    let s = Scene::from_gltf_slice(&to_bytes(&mesh_gltf(&p, &idx)), None).unwrap();
    assert_eq!(s.mesh().triangle_count(), 12);
    assert!(
        s.warnings.iter().any(|w| w.contains("1 degenerate")),
        "{:?}",
        s.warnings
    );
    let spec = s.camera_spec();
    assert!(spec.to.length() < 1e-5, "framed {:?}", spec.to);
    assert!(spec.from.length() < 2.0, "camera at {:?}", spec.from);
    assert!(centre_ray_hits(&s));
    // Control: framing the bounds with the stray triangle (what the loader did before)
    // misses the box.
    let lo = Vec3A::splat(-0.25);
    let hi = Vec3A::new(1002.0, 0.25, 0.25);
    let wrong = Scene::new(
        s.mesh().clone(),
        s.materials().to_vec(),
        s.textures().to_vec(),
        render::scene::CameraSpec::framing(lo, hi),
        64,
        64,
    );
    assert!(!centre_ray_hits(&wrong));
    // A valid far triangle still counts (it is rendered), so the framing includes it.
    let (mut p, mut idx) = box_mesh(0.25);
    let base = p.len() as u32;
    p.extend([[1000.0, 0.0, 0.0], [1001.0, 0.0, 0.0], [1000.0, 1.0, 0.0]]);
    idx.extend([base, base + 1, base + 2]);
    let s = Scene::from_gltf_slice(&to_bytes(&mesh_gltf(&p, &idx)), None).unwrap();
    assert_eq!(s.mesh().triangle_count(), 13);
    assert!(s.camera_spec().to.x > 400.0);
}

/// Loads the embedded fixture with its camera node (nodes[3]) edited by `edit`.
fn with_camera_node(edit: impl FnOnce(&mut Value)) -> Result<Scene, String> {
    let mut v = embedded_json();
    assert_eq!(v["nodes"][3]["camera"], Value::from(0));
    edit(&mut v["nodes"][3]);
    Scene::from_gltf_slice(&to_bytes(&v), None).map_err(|e| e.to_string())
}

fn json(text: &str) -> Value {
    gltf::json::deserialize::from_str(text).unwrap()
}

#[test]
fn invalid_camera_nodes_are_errors_naming_node_and_field() {
    // Control: the unedited camera and valid extras load without warnings.
    let s = with_camera_node(|n| {
        n["extras"] = json(
            r#"{"aperture_radius": 0.05, "focus_distance": 3, "shutter_open": 0,
                "shutter_close": 1, "motion_end_translation": [0.1, 0.5, 3]}"#,
        );
    })
    .unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.camera_spec().thin_lens, Some((0.05, 3.0)));
    assert!(s.camera_spec().motion.is_some());

    let cases: [(&str, &[&str]); 12] = [
        (
            r#"{"scale": [0, 0, 0]}"#,
            &["nodes[3]", "cannot place a camera"],
        ),
        (
            r#"{"scale": [1, 0, 1]}"#,
            &["nodes[3]", "cannot place a camera"],
        ),
        (
            r#"{"translation": [0, 1e39, 3]}"#,
            &["nodes[3]", "cannot place a camera"],
        ),
        (
            r#"{"extras": {"aperture_radius": -0.1, "focus_distance": 2}}"#,
            &["nodes[3].extras.aperture_radius", "negative"],
        ),
        (
            r#"{"extras": {"aperture_radius": 0.1, "focus_distance": 0}}"#,
            &["nodes[3].extras.focus_distance", "> 0"],
        ),
        (
            r#"{"extras": {"aperture_radius": "wide", "focus_distance": 2}}"#,
            &["nodes[3].extras.aperture_radius", "not a finite number"],
        ),
        (
            r#"{"extras": {"aperture_radius": 1e300, "focus_distance": 2}}"#,
            &["nodes[3].extras.aperture_radius", "not a finite number"],
        ),
        (
            r#"{"extras": {"shutter_open": 1, "shutter_close": 0.5, "motion_end_translation": [0, 0, 0]}}"#,
            &["nodes[3].extras.shutter_close", "before", "shutter_open"],
        ),
        (
            r#"{"extras": {"shutter_open": 0, "shutter_close": 1, "motion_end_translation": [0, "x", 0]}}"#,
            &["nodes[3].extras.motion_end_translation", "3 finite numbers"],
        ),
        (
            r#"{"extras": {"shutter_open": 0, "shutter_close": 1, "motion_end_translation": [0, 1]}}"#,
            &["nodes[3].extras.motion_end_translation", "3 finite numbers"],
        ),
        (
            r#"{"extras": {"shutter_open": 0, "shutter_close": 1e40, "motion_end_translation": [0, 0, 1]}}"#,
            &["nodes[3].extras.shutter_close", "not a finite number"],
        ),
        (
            r#"{"extras": {"shutter_open": 0, "shutter_close": 1, "motion_end_translation": [0, 0, 1e39]}}"#,
            &["nodes[3].extras.motion_end_translation"],
        ),
    ];
    for (edit, needles) in cases {
        let e = with_camera_node(|n| {
            for (k, v) in json(edit).as_object().unwrap() {
                n[k.as_str()] = v.clone();
            }
        })
        .map(|_| ())
        .unwrap_err();
        for needle in needles {
            assert!(e.contains(needle), "{edit}: '{needle}' missing from {e}");
        }
    }

    // Incomplete extras are named warnings; the camera stays where the node puts it.
    let s = with_camera_node(|n| {
        n["extras"] = json(r#"{"aperture_radius": 0.1, "shutter_open": 0, "shutter_close": 1}"#);
    })
    .unwrap();
    let all = s.warnings.join("\n");
    assert!(
        all.contains("nodes[3].extras has aperture_radius but no focus_distance"),
        "{all}"
    );
    assert!(
        all.contains("nodes[3].extras") && all.contains("motion_end_translation missing"),
        "{all}"
    );
    assert_eq!(s.camera_spec().thin_lens, None);
    assert_eq!(s.camera_spec().motion, None);
    assert!((s.camera_spec().from - Vec3A::new(0.0, 0.5, 3.0)).length() < 1e-6);
}

#[test]
fn camera_parameters_out_of_range_are_named_warnings() {
    let mut v = embedded_json();
    v["cameras"][0]["perspective"]["yfov"] = Value::from(4.0);
    v["cameras"][0]["perspective"]["aspectRatio"] = Value::from(1000.0);
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    let all = s.warnings.join("\n");
    assert!(
        all.contains("cameras[0].perspective.yfov 4") && all.contains("0.8 is used"),
        "{all}"
    );
    assert!(
        all.contains("cameras[0].perspective.aspectRatio 1000") && all.contains("1 is used"),
        "{all}"
    );
    assert_eq!(s.camera().height(), s.camera().width());
}

#[test]
fn gltf_1_0_is_named_as_unsupported() {
    // A glTF 1.0 document (objects keyed by id, not arrays).
    let v1 = json(
        r#"{"asset": {"version": "1.0"}, "meshes": {"m": {"primitives": []}},
            "scene": "s", "scenes": {"s": {"nodes": []}}}"#,
    );
    let e = load_err(&v1);
    assert!(
        e.contains("asset.version") && e.contains("glTF 1.0 is not supported"),
        "{e}"
    );
    // Pre-1.0 drafts: a top-level version and no asset.
    let v0 = json(r#"{"version": "0.8", "meshes": {}}"#);
    let e = load_err(&v0);
    assert!(
        e.contains("top-level \"version\"") && e.contains("glTF 1.0"),
        "{e}"
    );
    let mut v3 = embedded_json();
    v3["asset"]["version"] = Value::from("3.0");
    assert!(load_err(&v3).contains("glTF 3.0 is not supported"));
    // Control: 2.x loads.
    let mut v21 = embedded_json();
    v21["asset"]["version"] = Value::from("2.1");
    assert!(Scene::from_gltf_slice(&to_bytes(&v21), None).is_ok());
}

#[test]
fn a_utf8_bom_is_skipped_with_a_warning() {
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend(std::fs::read(data("tiny-embedded.gltf")).unwrap());
    let s = Scene::from_gltf_slice(&bytes, None).unwrap();
    assert_eq!(s.mesh().triangle_count(), 5);
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(
        s.warnings[0].contains("byte-order mark"),
        "{:?}",
        s.warnings
    );
    // From a file too.
    let path = tmp_dir("bom").join("bom.gltf");
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(Scene::load(&path).unwrap().mesh().triangle_count(), 5);
}

#[test]
fn draco_compression_is_named() {
    let draco =
        r#"{"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}"#;
    // Required: an error.
    let mut v = embedded_json();
    v["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push(Value::from("KHR_draco_mesh_compression"));
    v["extensionsRequired"] = Value::from(vec!["KHR_draco_mesh_compression"]);
    v["meshes"][1]["primitives"][0]["extensions"] = json(draco);
    let e = load_err(&v);
    assert!(
        e.contains("KHR_draco_mesh_compression") && e.contains("not supported"),
        "{e}"
    );
    // Used, with the uncompressed fallback: a warning naming the primitive; it is rendered.
    v.as_object_mut().unwrap().remove("extensionsRequired");
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    let all = s.warnings.join("\n");
    assert!(
        all.contains("meshes[1].primitives[0] is Draco-compressed")
            && all.contains("fallback data is used"),
        "{all}"
    );
    assert_eq!(s.mesh().triangle_count(), 5);
    // Used, without a fallback (as Draco encoders write it: accessors without bufferView).
    for a in [8, 9, 10, 11] {
        v["accessors"][a]
            .as_object_mut()
            .unwrap()
            .remove("bufferView");
    }
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    let all = s.warnings.join("\n");
    assert!(
        all.contains("meshes[1].primitives[0]") && all.contains("no uncompressed fallback"),
        "{all}"
    );
    assert_eq!(s.mesh().triangle_count(), 4);
}

#[test]
fn accessors_without_buffer_view_are_zero_filled() {
    // TEXCOORD_0 of the floor (accessors[2]) without a bufferView: all UVs are (0, 0).
    let mut v = embedded_json();
    v["accessors"][2]
        .as_object_mut()
        .unwrap()
        .remove("bufferView");
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    assert_eq!(s.mesh().triangle_count(), 5);
    assert!(s.mesh().uvs[..4].iter().all(|uv| *uv == Vec2::ZERO));
    // Control: with the view, the UVs are not all zero.
    let s = Scene::from_gltf_slice(&to_bytes(&embedded_json()), None).unwrap();
    assert!(s.mesh().uvs[..4].iter().any(|uv| *uv != Vec2::ZERO));
    // POSITION without a bufferView: every vertex at the origin, so the primitive has no
    // area and is dropped with a warning.
    let mut v = embedded_json();
    v["accessors"][8]
        .as_object_mut()
        .unwrap()
        .remove("bufferView");
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    assert_eq!(s.mesh().triangle_count(), 4);
    assert!(
        s.warnings.iter().any(|w| w.contains("1 degenerate")),
        "{:?}",
        s.warnings
    );
    // A huge count without data is refused rather than allocated.
    v["accessors"][8]["count"] = Value::from(1u64 << 40);
    let e = load_err(&v);
    assert!(e.contains("accessors[8]") && e.contains("count"), "{e}");
}

#[test]
fn sparse_accessors_are_an_error_naming_the_accessor() {
    let mut v = embedded_json();
    v["accessors"][0]["sparse"] = json(
        r#"{"count": 1, "indices": {"bufferView": 3, "componentType": 5123},
            "values": {"bufferView": 0}}"#,
    );
    let e = load_err(&v);
    assert!(
        e.contains("accessors[0]") && e.contains("sparse") && e.contains("not supported"),
        "{e}"
    );
}
