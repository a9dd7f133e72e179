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
    used.push(Value::from("KHR_texture_transform"));
    v["extensions"] = gltf::json::deserialize::from_str(
        r#"{"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 5.0}]}}"#,
    )
    .unwrap();
    v["materials"][0]["normalTexture"] =
        gltf::json::deserialize::from_str(r#"{"index": 0}"#).unwrap();
    v["materials"][0]["alphaMode"] = Value::from("BLEND");
    v["meshes"][1]["primitives"][0]["mode"] = Value::from(1); // lines
    let s = Scene::from_gltf_slice(&to_bytes(&v), None).unwrap();
    let all = s.warnings.join("\n");
    for needle in [
        "KHR_lights_punctual",
        "KHR_texture_transform",
        "normal textures",
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
