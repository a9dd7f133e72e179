//! The bundled scene set (`scenes/`, written by `scripts/make_scenes.py`).
//!
//! * every one of the ten scenes is present (so the other checks cannot pass vacuously);
//! * each loads with the `gltf` crate and follows the conventions of `docs/scenes.md`
//!   (one perspective camera, emitters via `KHR_materials_emissive_strength`, per-vertex normals
//!   that agree with the triangle winding, planar emitters facing into the scene, < 100k
//!   triangles, camera extras for `dof` and `motion-blur`, `cornell-glass` matching the peer);
//! * the Khronos glTF validator reports no error (skipped with a message when node/npm or the
//!   `gltf-validator` package is unavailable, e.g. offline);
//! * re-running the generator reproduces the committed files byte for byte (skipped with a
//!   message when `python3` is unavailable).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The scene set: one per phenomenon (see docs/scenes.md).
const SCENES: [&str; 10] = [
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
];

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("repository root")
}

fn scene_path(name: &str) -> PathBuf {
    repo_root().join("scenes").join(format!("{name}.gltf"))
}

#[test]
fn all_ten_scenes_are_present() {
    for name in SCENES {
        let gltf = scene_path(name);
        assert!(gltf.is_file(), "missing scene {}", gltf.display());
        let bin = gltf.with_extension("bin");
        assert!(bin.is_file(), "missing buffer {}", bin.display());
    }
}

type V3 = [f32; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn len(a: V3) -> f32 {
    dot(a, a).sqrt()
}

/// Raw JSON of a scene (the `gltf` crate is built without its `extras` feature).
fn raw_json(name: &str) -> gltf::json::Value {
    let bytes = std::fs::read(scene_path(name)).expect("read scene");
    gltf::json::deserialize::from_slice(&bytes).expect("scene is JSON")
}

fn camera_node_json(name: &str) -> gltf::json::Value {
    let doc = raw_json(name);
    let nodes = doc["nodes"].as_array().expect("nodes");
    nodes
        .iter()
        .find(|n| n.get("camera").is_some())
        .cloned()
        .unwrap_or_else(|| panic!("{name}: no camera node"))
}

struct EmitterInfo {
    /// Area-weighted geometric normal sum and centroid of a planar emitter primitive.
    normal: V3,
    centroid: V3,
    planar: bool,
}

#[test]
fn scenes_follow_the_conventions() {
    for name in SCENES {
        let path = scene_path(name);
        let (doc, buffers, images) =
            gltf::import(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));

        // exactly one camera node: perspective, square, sensible fov, unit rotation
        let cameras: Vec<_> = doc.nodes().filter(|n| n.camera().is_some()).collect();
        assert_eq!(cameras.len(), 1, "{name}: expected one camera node");
        let cam = cameras[0].camera().unwrap();
        let gltf::camera::Projection::Perspective(p) = cam.projection() else {
            panic!("{name}: camera is not perspective");
        };
        assert_eq!(p.aspect_ratio(), Some(1.0), "{name}: aspectRatio");
        assert!(
            p.yfov() > 0.1 && p.yfov() < 2.0,
            "{name}: yfov {}",
            p.yfov()
        );
        let (_, rot, scale) = cameras[0].transform().decomposed();
        let qn = rot.iter().map(|c| c * c).sum::<f32>().sqrt();
        assert!((qn - 1.0).abs() < 1e-5, "{name}: camera rotation not unit");
        assert_eq!(scale, [1.0; 3], "{name}: camera node is scaled");

        // geometry: normals present, unit, agreeing with the winding; triangle budget
        let mut triangles = 0usize;
        let mut emitters = Vec::new();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for node in doc.nodes() {
            let Some(mesh) = node.mesh() else { continue };
            let (t, r, s) = node.transform().decomposed();
            assert!(
                t == [0.0; 3] && r == [0.0, 0.0, 0.0, 1.0] && s == [1.0; 3],
                "{name}: mesh node {:?} has a transform (geometry is baked in world space)",
                node.name()
            );
            for prim in mesh.primitives() {
                assert_eq!(
                    prim.mode(),
                    gltf::mesh::Mode::Triangles,
                    "{name}: not triangles"
                );
                let reader = prim.reader(|b| Some(&buffers[b.index()]));
                let pos: Vec<V3> = reader.read_positions().expect("POSITION").collect();
                let nrm: Vec<V3> = reader
                    .read_normals()
                    .unwrap_or_else(|| panic!("{name}: mesh {:?} has no NORMAL", mesh.name()))
                    .collect();
                let idx: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
                assert_eq!(pos.len(), nrm.len());
                assert_eq!(idx.len() % 3, 0);
                for n in &nrm {
                    assert!(
                        (len(*n) - 1.0).abs() < 1e-3,
                        "{name}: non-unit normal {n:?}"
                    );
                }
                let mat = prim.material();
                let emissive = mat.emissive_strength().unwrap_or(1.0) > 0.0
                    && mat.emissive_factor().iter().any(|&c| c > 0.0);
                let mut nsum = [0.0f32; 3];
                let mut csum = [0.0f32; 3];
                let mut area = 0.0f32;
                let mut first_n: Option<V3> = None;
                let mut planar = true;
                for tri in idx.chunks_exact(3) {
                    let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| pos[i as usize]);
                    let g = cross(sub(b, a), sub(c, a));
                    let ga = len(g);
                    assert!(ga > 0.0, "{name}: degenerate triangle in {:?}", mesh.name());
                    for &i in tri {
                        assert!(
                            dot(g, nrm[i as usize]) > 0.0,
                            "{name}: vertex normal disagrees with winding in {:?}",
                            mesh.name()
                        );
                    }
                    for p in [a, b, c] {
                        for k in 0..3 {
                            lo[k] = lo[k].min(p[k]);
                            hi[k] = hi[k].max(p[k]);
                        }
                    }
                    if emissive {
                        let gn = g.map(|x| x / ga);
                        match first_n {
                            None => first_n = Some(gn),
                            Some(f) => planar &= dot(f, gn) > 0.9999,
                        }
                        for k in 0..3 {
                            nsum[k] += g[k];
                            csum[k] += ga * (a[k] + b[k] + c[k]) / 3.0;
                        }
                        area += ga;
                    }
                }
                triangles += idx.len() / 3;
                if emissive {
                    emitters.push(EmitterInfo {
                        normal: nsum,
                        centroid: csum.map(|x| x / area),
                        planar,
                    });
                }
            }
        }
        assert!(triangles < 100_000, "{name}: {triangles} triangles");
        assert!(!emitters.is_empty(), "{name}: no emitter");
        // planar emitters face the middle of the scene's bounding box, except the lamp of
        // thin-highlight and thin-bar, which faces the strip it lights from 35 cm (up and away
        // from the camera)
        let centre = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let aimed =
            |e: &&EmitterInfo| matches!(name, "thin-highlight" | "thin-bar") && e.normal[2] < 0.0;
        for e in emitters.iter().filter(|e| e.planar).filter(|e| !aimed(e)) {
            assert!(
                dot(e.normal, sub(centre, e.centroid)) > 0.0,
                "{name}: planar emitter at {:?} faces away from the scene",
                e.centroid
            );
        }

        // materials: emitters normalised (max component 1) with a strength; glass has an ior
        for mat in doc.materials() {
            let ef = mat.emissive_factor();
            if ef.iter().any(|&c| c > 0.0) {
                let m = ef.iter().cloned().fold(0.0f32, f32::max);
                assert!(
                    (m - 1.0).abs() < 1e-6,
                    "{name}: emissiveFactor {ef:?} not normalised"
                );
                assert!(
                    mat.emissive_strength().is_some_and(|s| s > 0.0),
                    "{name}: emitter {:?} without KHR_materials_emissive_strength",
                    mat.name()
                );
            }
            if let Some(t) = mat.transmission() {
                assert_eq!(t.transmission_factor(), 1.0);
                assert!(
                    mat.ior().is_some(),
                    "{name}: glass without KHR_materials_ior"
                );
            }
        }
        for img in &images {
            assert!(img.width > 0 && img.height > 0, "{name}: empty texture");
        }
    }
}

#[test]
fn cornell_glass_matches_the_peer_scene() {
    // The pbrt-v3 scene of the peer comparison (`docs/performance.md`, "Against the peer"):
    // LookAt 0 1 3.5 -> 0 1 0, fov 39 (square film), light L = (17, 12, 4), glass ior 1.5
    for name in ["cornell", "cornell-glass"] {
        let (doc, _, _) = gltf::import(scene_path(name)).unwrap();
        let node = doc.nodes().find(|n| n.camera().is_some()).unwrap();
        let (t, r, _) = node.transform().decomposed();
        assert_eq!(t, [0.0, 1.0, 3.5], "{name}: camera position");
        assert!(
            (r[3].abs() - 1.0).abs() < 1e-6,
            "{name}: camera must look down -Z"
        );
        let cam = node.camera().unwrap();
        let gltf::camera::Projection::Perspective(p) = cam.projection() else {
            panic!("{name}: camera is not perspective")
        };
        assert!((p.yfov() - 39f32.to_radians()).abs() < 1e-6, "{name}: yfov");
        let light = doc
            .materials()
            .find(|m| m.name() == Some("light"))
            .expect("light");
        let s = light.emissive_strength().unwrap();
        let l = light.emissive_factor().map(|c| c * s);
        for (got, want) in l.iter().zip([17.0, 12.0, 4.0]) {
            assert!((got - want).abs() < 1e-4, "{name}: light radiance {l:?}");
        }
    }
    let (doc, _, _) = gltf::import(scene_path("cornell-glass")).unwrap();
    let glass = doc
        .materials()
        .find(|m| m.transmission().is_some())
        .expect("glass material");
    assert_eq!(glass.ior(), Some(1.5));
}

#[test]
fn camera_extras_for_thin_lens_and_motion_blur() {
    let dof = camera_node_json("dof");
    let ar = dof["extras"]["aperture_radius"]
        .as_f64()
        .expect("aperture_radius");
    let fd = dof["extras"]["focus_distance"]
        .as_f64()
        .expect("focus_distance");
    assert!(ar > 0.0 && fd > 0.0, "dof: aperture {ar}, focus {fd}");
    let mb = camera_node_json("motion-blur");
    let ex = &mb["extras"];
    let open = ex["shutter_open"].as_f64().expect("shutter_open");
    let close = ex["shutter_close"].as_f64().expect("shutter_close");
    assert!(open < close);
    let end = ex["motion_end_translation"]
        .as_array()
        .expect("motion_end_translation");
    let start = mb["translation"].as_array().expect("translation");
    assert_eq!(end.len(), 3);
    let moved: f64 = (0..3)
        .map(|k| (end[k].as_f64().unwrap() - start[k].as_f64().unwrap()).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(moved > 0.01, "motion-blur: the camera does not move");
}

/// Runs `scripts/validate_scenes.sh` (installs gltf-validator into scripts/node_modules if
/// needed). Exit code 77 means "unavailable": the test is skipped with a message.
#[test]
fn khronos_validator_reports_no_errors() {
    let root = repo_root();
    let script = root.join("scripts/validate_scenes.sh");
    let out = match Command::new("bash")
        .arg(&script)
        .arg(root.join("scenes"))
        .output()
    {
        Ok(out) => out,
        Err(e) => {
            eprintln!("SKIPPED khronos_validator_reports_no_errors: cannot run bash: {e}");
            return;
        }
    };
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    match out.status.code() {
        Some(77) => {
            eprintln!(
                "SKIPPED khronos_validator_reports_no_errors: glTF validator unavailable\n{stderr}"
            );
        }
        Some(0) => {
            print!("{stdout}");
            for name in SCENES {
                assert!(
                    stdout.contains(&format!("{name}.gltf: 0 errors")),
                    "validator did not report on {name}:\n{stdout}"
                );
            }
        }
        _ => panic!(
            "glTF validator found errors ({:?}):\n{stdout}\n{stderr}",
            out.status
        ),
    }
}

/// The committed scenes are exactly what the generator writes now.
#[test]
fn generator_reproduces_the_committed_scenes() {
    let root = repo_root();
    let out_dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("scenes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out_dir);
    let run = Command::new("python3")
        .arg(root.join("scripts/make_scenes.py"))
        .arg(&out_dir)
        .output();
    let out = match run {
        Ok(out) => out,
        Err(e) => {
            eprintln!("SKIPPED generator_reproduces_the_committed_scenes: cannot run python3: {e}");
            return;
        }
    };
    assert!(
        out.status.success(),
        "make_scenes.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut files = Vec::new();
    for name in SCENES {
        files.push(format!("{name}.gltf"));
        files.push(format!("{name}.bin"));
    }
    files.push("textures/pool-tiles.png".into());
    files.push("textures/checker.png".into());
    for f in &files {
        let fresh = std::fs::read(out_dir.join(f)).unwrap_or_else(|e| panic!("generated {f}: {e}"));
        let committed = std::fs::read(root.join("scenes").join(f))
            .unwrap_or_else(|e| panic!("scenes/{f}: {e}"));
        assert!(
            fresh == committed,
            "scenes/{f} differs from what scripts/make_scenes.py writes: re-run the generator"
        );
    }
    let _ = std::fs::remove_dir_all(&out_dir);
}
