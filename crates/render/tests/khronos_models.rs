//! The Khronos glTF sample models bundled in `scenes/third-party/` (provenance, licences and
//! attribution in `scenes/third-party/README.md`): each one loads, and renders a tiny image
//! with the path tracer and with PSSMLT that has no NaN or infinite pixel and is not black,
//! under the model's own emitters or, for the models that ship no light, the default uniform
//! environment.
//!
//! The models were chosen to cover the material features people use: vertex colours
//! (`COLOR_0`), base-colour, normal (with `TANGENT`) and metallic-roughness textures,
//! `KHR_texture_transform`, alpha mask (cutout), emissive textures and
//! `KHR_materials_emissive_strength`, metallic-roughness factors; none has a camera, so every
//! one is auto-framed.
//!
//! Each model must also cover part of the image (camera rays through the pixel centres hit
//! it): a non-black image alone would pass for a model that the automatic framing misses or
//! sees edge-on, lit only by the environment behind it.
//!
//! Run with `cargo test -p render --release --test khronos_models -- --nocapture` to see each
//! model's load warnings and render notes.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use glam::Vec2;
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

/// Image side in pixels.
const SIZE: u32 = 32;
/// Samples per pixel of the path tracer.
const PT_SPP: u32 = 8;
/// Mutations per pixel of PSSMLT.
const MLT_MPP: u32 = 8;
/// Mean luminance below which an image counts as black. A uniform environment of radiance 1
/// (or the models' own emitters) gives means of order 0.1 to 1; an image with no light at all
/// gives exactly 0.
const BLACK: f64 = 1e-3;
/// Smallest fraction of the pixel centres whose camera ray must hit the model.
const MIN_COVERAGE: f64 = 0.02;

/// Every bundled model: (directory under `scenes/third-party/`, scene file).
const MODELS: [(&str, &str); 6] = [
    ("BoxVertexColors", "BoxVertexColors.glb"),
    ("TwoSidedPlane", "TwoSidedPlane.gltf"),
    ("TextureTransformTest", "TextureTransformTest.gltf"),
    ("TextureEncodingTest", "TextureEncodingTest.glb"),
    ("EmissiveStrengthTest", "EmissiveStrengthTest.glb"),
    (
        "MetalRoughSpheresNoTextures",
        "MetalRoughSpheresNoTextures.glb",
    ),
];

fn third_party() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/third-party")
}

fn settings(integrator: IntegratorKind) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        budget: Budget::SamplesPerPixel(if integrator.is_mcmc() {
            MLT_MPP
        } else {
            PT_SPP
        }),
        threads: 1,
        seed: 1,
        max_depth: 5,
        method: integrator.settings().with_chains(16, 4_000),
    }
}

/// Fraction of the `SIZE x SIZE` pixel centres whose camera ray hits the scene's geometry.
fn coverage(scene: &Scene) -> f64 {
    let camera = scene.camera();
    let mut hits = 0u32;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let ray = camera.generate_ray(p, Vec2::splat(0.5), 0.5);
            if scene.intersect(&ray).is_some() {
                hits += 1;
            }
        }
    }
    f64::from(hits) / f64::from(SIZE * SIZE)
}

/// Loads `dir/file`, prints its warnings, renders it with PT and PSSMLT and checks each image.
fn check(dir: &str, file: &str) {
    let path = third_party().join(dir).join(file);
    let start = Instant::now();
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{dir}: {e}"));
    println!(
        "{dir}: loaded in {:.2?}: {} triangles, {} materials, {} textures",
        start.elapsed(),
        scene.mesh().triangle_count(),
        scene.materials().len(),
        scene.textures().len(),
    );
    for w in &scene.warnings {
        println!("{dir}: warning: {w}");
    }
    let mut failures = Vec::new();
    scene.set_resolution(SIZE, SIZE);
    let covered = coverage(&scene);
    println!(
        "{dir}: the model covers {:.1} % of the pixel centres",
        100.0 * covered
    );
    if covered < MIN_COVERAGE {
        failures.push(format!(
            "{dir}: camera rays hit the model at only {:.1} % of the pixel centres (< {:.0} %): \
             the framing misses it or sees it edge-on",
            100.0 * covered,
            100.0 * MIN_COVERAGE
        ));
    }
    for integrator in [IntegratorKind::Pt, IntegratorKind::Pssmlt] {
        let name = integrator.name();
        let out = render(
            &scene,
            &settings(integrator),
            &NoProgress,
            &AtomicBool::new(false),
        )
        .unwrap_or_else(|e| panic!("{dir} {name}: {e}"));
        let image = &out.image;
        let mean = image.mean_luminance();
        println!(
            "{dir} {name}: {:.2?}, {} samples, {} dropped as non-finite, mean luminance {mean:.4}",
            out.elapsed, out.samples, out.dropped_nonfinite
        );
        for note in &out.notes {
            println!("{dir} {name}: note: {note}");
        }
        assert_eq!(
            (image.width, image.height),
            (SIZE as usize, SIZE as usize),
            "{dir} {name}: image size"
        );
        assert!(!out.cancelled, "{dir} {name}: cancelled");
        // Checked first: a NaN or an infinity is a bug whatever the lighting.
        assert_eq!(
            image.count_nonfinite(),
            0,
            "{dir} {name}: pixels with NaN or infinite values"
        );
        if mean <= BLACK {
            failures.push(format!(
                "{dir} {name}: the image is black (mean luminance {mean:e} <= {BLACK:e}); notes: {:?}",
                out.notes
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// One test per model, so that a failure names the model and the models run in parallel.
macro_rules! model_tests {
    ($($test:ident => $index:expr;)*) => {
        $(
            #[test]
            fn $test() {
                let (dir, file) = MODELS[$index];
                check(dir, file);
            }
        )*
    };
}

model_tests! {
    box_vertex_colors => 0;
    two_sided_plane => 1;
    texture_transform_test => 2;
    texture_encoding_test => 3;
    emissive_strength_test => 4;
    metal_rough_spheres_no_textures => 5;
}

/// Every model directory holds its scene file, and the attribution file names every model
/// with its licence, so that no model is bundled without attribution.
#[test]
fn every_model_is_present_and_attributed() {
    let root = third_party();
    let readme = std::fs::read_to_string(root.join("README.md"))
        .expect("scenes/third-party/README.md (the attribution file)");
    for (dir, file) in MODELS {
        let path = root.join(dir).join(file);
        assert!(path.is_file(), "missing {}", path.display());
        assert!(
            readme.contains(&format!("## {dir}")),
            "scenes/third-party/README.md has no section '## {dir}'"
        );
    }
    // ... and no model directory is left out of the test.
    let mut dirs: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().unwrap().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    dirs.sort();
    let mut listed: Vec<String> = MODELS.iter().map(|(d, _)| (*d).to_owned()).collect();
    listed.sort();
    assert_eq!(dirs, listed, "scenes/third-party/ and MODELS differ");
}
