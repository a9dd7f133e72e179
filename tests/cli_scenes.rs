//! CLI tests of scene input: glTF files (bundled, missing, malformed, with external files),
//! non-finite emission through PSSMLT, and the environment flags.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{assert_fails_with, chainlight, path_str, stderr, stdout, temp_dir};
use render::image::Image;
use render::image_io::{read_exr, write_exr};

#[test]
fn missing_and_malformed_scene_files_name_the_file() {
    let dir = temp_dir("scenes");
    let missing = dir.join("missing.gltf");
    assert_fails_with(&["render", path_str(&missing)], &["missing.gltf"]);

    let malformed = dir.join("broken.gltf");
    std::fs::write(&malformed, b"{ \"asset\": { \"version\": ").unwrap();
    let out = dir.join("out.exr");
    assert_fails_with(
        &["render", path_str(&malformed), "-o", path_str(&out)],
        &["broken.gltf"],
    );

    let wrong_kind = dir.join("scene.obj");
    std::fs::write(&wrong_kind, b"v 0 0 0").unwrap();
    assert_fails_with(&["render", path_str(&wrong_kind)], &["scene.obj", ".gltf"]);
}

/// A bundled glTF scene renders through the CLI.
#[test]
fn renders_a_bundled_gltf_scene() {
    let dir = temp_dir("gltf");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.gltf");
    let out = dir.join("cornell.exr");
    let output = chainlight(&[
        "render",
        path_str(&scene),
        "--width",
        "8",
        "--height",
        "6",
        "--spp",
        "1",
        "-o",
        path_str(&out),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(read_exr(&out).unwrap().width, 8);
    assert!(stdout(&output).contains("cornell.gltf"));
}

#[test]
fn external_scene_files_need_the_flag() {
    let dir = temp_dir("external");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/render/tests/data");
    // The fixture with its buffer and image named by absolute paths outside `dir`.
    let text = std::fs::read_to_string(data.join("tiny.gltf")).unwrap();
    let mut edited = text.clone();
    for name in ["tiny.bin", "checker.png"] {
        let abs = path_str(&data.join(name)).to_owned();
        edited = edited.replace(
            &format!("\"uri\": \"{name}\""),
            &format!("\"uri\": \"{abs}\""),
        );
    }
    assert_eq!(edited.matches(path_str(&data)).count(), 2, "{edited}");
    let scene = dir.join("scene.gltf");
    std::fs::write(&scene, edited).unwrap();
    let out = dir.join("out.exr");
    let args = [
        "render",
        path_str(&scene),
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "1",
        "-o",
        path_str(&out),
    ];
    assert_fails_with(
        &args,
        &[
            "scene.gltf",
            "buffers[0].uri",
            "absolute path",
            "--allow-external-files",
        ],
    );
    let mut allowed = args.to_vec();
    allowed.push("--allow-external-files");
    let output = chainlight(&allowed);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(read_exr(&out).unwrap().width, 4);
}

/// Writes `dir/wall.gltf` (+ `wall.bin`): a 0.4 x 0.4 m emissive wall at z = 0 facing +z with
/// `emissiveStrength` `strength`, filling the view of a camera at z = 0.5 looking down -z
/// (small, so that its power, radiance x area x pi, stays finite in f32).
fn emissive_wall(dir: &Path, strength: &str) -> PathBuf {
    let mut bin = Vec::new();
    for p in [
        [-0.2f32, -0.2, 0.0],
        [0.2, -0.2, 0.0],
        [0.2, 0.2, 0.0],
        [-0.2, 0.2, 0.0],
    ] {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    std::fs::write(dir.join("wall.bin"), &bin).unwrap();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scenes": [{{"nodes": [0, 1]}}], "scene": 0,
        "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 0, 0.5]}}],
        "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.5, "znear": 0.01}}}}],
        "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0, 0, 0, 1]}},
            "emissiveFactor": [1, 1, 1],
            "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": {strength}}}}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
        "accessors": [
            {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [-0.2, -0.2, 0], "max": [0.2, 0.2, 0]}},
            {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 48}},
            {{"buffer": 0, "byteOffset": 48, "byteLength": 12}}],
        "buffers": [{{"byteLength": 60, "uri": "wall.bin"}}]}}"#
    );
    let path = dir.join("wall.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// Renders `scene` with PSSMLT at 8 x 8, 64 mutations per pixel (every pixel is visited); returns the image and the
/// summary's non-finite count. The direct-lighting pass is off: the emitter seen directly
/// (depth 0) must go through the chains' splats, the path under test.
fn pssmlt_render(scene: &Path, out: &Path) -> (Image, u64) {
    let output = chainlight(&[
        "render",
        path_str(scene),
        "--integrator",
        "pssmlt",
        "--direct-samples",
        "0",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "64",
        "--chains",
        "64",
        "--bootstrap-samples",
        "1000",
        "-o",
        path_str(out),
    ]);
    let err = stderr(&output);
    assert!(output.status.success(), "{err}");
    let summary = stdout(&output);
    let dropped: u64 = summary
        .lines()
        .find_map(|l| l.strip_prefix("non-finite"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no non-finite line in {summary}"));
    (read_exr(out).unwrap(), dropped)
}

/// An emitter of radiance 3e38 (finite in f32) through PSSMLT: the f64 pixel estimates
/// scatter around 3e38, and those above f32::MAX (3.4e38) would be inf in the f32 image.
/// They are dropped (black) and counted in the summary (before: inf pixels and "non-finite 0
/// samples dropped").
#[test]
fn huge_emission_through_pssmlt_gives_no_inf() {
    let dir = temp_dir("huge-emission");
    let (image, dropped) = pssmlt_render(&emissive_wall(&dir, "3e38"), &dir.join("hot.exr"));
    assert!(
        image.pixels.iter().flatten().all(|c| c.is_finite()),
        "the EXR has non-finite pixels"
    );
    // Every pixel sees the wall: a black pixel is a dropped one, and each is counted.
    let black = image.pixels.iter().filter(|p| **p == [0.0; 3]).count() as u64;
    assert!(
        black > 0,
        "no pixel overflowed: the test does not test anything"
    );
    assert_eq!(dropped, black, "dropped pixels and the summary disagree");
    assert!(image
        .pixels
        .iter()
        .flatten()
        .all(|c| *c == 0.0 || *c > 1e37));
    // Control: the same wall at 1e30 has no drop and no black pixel.
    let (image, dropped) = pssmlt_render(&emissive_wall(&dir, "1e30"), &dir.join("warm.exr"));
    assert_eq!(dropped, 0);
    assert!(image
        .pixels
        .iter()
        .flatten()
        .all(|c| *c > 1e29 && c.is_finite()));
}

/// `--env`: a lightless model renders under the default environment with a note; `--env none`
/// renders it black; a constant and a map environment light it; bad values name the flag.
#[test]
fn environment_flags() {
    let dir = temp_dir("env");
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/third-party/BoxVertexColors/BoxVertexColors.glb"
    );
    let render = |extra: &[&str], name: &str| -> (Output, Image) {
        let out = dir.join(name);
        let mut args = vec![
            "render",
            model,
            "--integrator",
            "pt",
            "--spp",
            "4",
            "--width",
            "16",
            "--height",
            "16",
            "-o",
            path_str(&out),
        ];
        args.extend_from_slice(extra);
        let output = chainlight(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        let image = read_exr(&out).unwrap();
        (output, image)
    };
    let mean = |im: &Image| im.pixels.iter().map(|p| p[1]).sum::<f32>() / im.pixels.len() as f32;
    let (output, default) = render(&[], "default.exr");
    let text = format!("{}{}", stdout(&output), stderr(&output));
    assert!(text.contains("default uniform white environment"), "{text}");
    assert!(mean(&default) > 0.1);
    let (_, none) = render(&["--env", "none"], "none.exr");
    assert_eq!(mean(&none), 0.0);
    let (_, dim) = render(&["--env", "0.5", "--env-strength", "0.5"], "dim.exr");
    // The background is exactly the environment's radiance.
    assert!(
        (dim.pixels[0][1] - 0.25).abs() < 1e-6,
        "{:?}",
        dim.pixels[0]
    );
    let mut map = Image::new(8, 4);
    for (i, p) in map.pixels.iter_mut().enumerate() {
        *p = [0.1 * (i % 8) as f32, 0.2, 0.3];
    }
    let map_path = dir.join("sky.exr");
    write_exr(&map_path, &map).unwrap();
    let (_, lit) = render(
        &["--env", path_str(&map_path), "--env-rotate", "45"],
        "map.exr",
    );
    assert!(mean(&lit) > 0.0 && lit.pixels.iter().flatten().all(|c| c.is_finite()));
    let out = dir.join("x.exr");
    for (args, needle) in [
        (vec!["--env", "1,2"], "--env"),
        (vec!["--env", "-1"], "0..=1000000"),
        (vec!["--env", "missing.hdr"], "no such file"),
        (vec!["--env", "1", "--env-rotate", "400"], "-360..=360"),
        (
            vec!["--env", "1", "--env-strength", "nan"],
            "--env-strength",
        ),
        (vec!["--env-strength", "2"], "--env"),
    ] {
        let mut full = vec!["render", "--spp", "1", "-o", path_str(&out)];
        full.extend(args);
        assert_fails_with(&full, &[needle]);
    }
}
