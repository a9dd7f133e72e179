//! Determinism: under a sample budget the same seed gives a bit-identical image with 1, 2 and
//! 3 threads (tiles are fixed work units merged in a fixed order, random numbers are keyed by
//! seed, pixel, sample and dimension); a different seed gives a different image.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use render::image::Image;
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

fn settings(width: u32, height: u32, threads: usize, seed: u64) -> RenderSettings {
    RenderSettings {
        width,
        height,
        integrator: IntegratorKind::Pt,
        budget: Budget::SamplesPerPixel(3),
        threads,
        seed,
        max_depth: 6,
        ..RenderSettings::default()
    }
}

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn run(scene: &Scene, s: &RenderSettings) -> Image {
    let out = render(scene, s, &NoProgress, &AtomicBool::new(false)).unwrap();
    assert!(!out.cancelled);
    assert_eq!(out.samples, u64::from(s.width * s.height) * 3);
    out.image
}

#[test]
fn same_seed_any_thread_count_is_bit_identical() {
    // 40 x 20 is not a multiple of the 16-pixel tile size.
    let scene = Scene::cornell_box(40, 20);
    let reference = run(&scene, &settings(40, 20, 1, 7));
    assert!(reference.mean_luminance() > 0.0);
    for threads in [2, 3] {
        let image = run(&scene, &settings(40, 20, threads, 7));
        assert!(
            bits(&image) == bits(&reference),
            "{threads} threads differ from 1"
        );
    }
}

#[test]
fn different_seed_gives_a_different_image() {
    let scene = Scene::cornell_box(16, 16);
    let a = run(&scene, &settings(16, 16, 2, 1));
    let b = run(&scene, &settings(16, 16, 2, 2));
    assert!(bits(&a) != bits(&b));
    // ... but the same expected brightness (a loose sanity check).
    let (la, lb) = (a.mean_luminance(), b.mean_luminance());
    assert!((la - lb).abs() < 0.5 * la.max(lb), "{la} vs {lb}");
}

#[test]
fn gltf_scene_with_glass_is_deterministic() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-glass.gltf");
    let scene = Scene::load(&path).unwrap();
    let a = run(&scene, &settings(16, 16, 1, 3));
    let b = run(&scene, &settings(16, 16, 3, 3));
    assert!(bits(&a) == bits(&b));
}
