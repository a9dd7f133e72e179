//! pathmlt on light that only specular vertices deliver: a room lit only through mirrors
//! (`L S S D E`, `L S D E`, and the light seen in a mirror, `E S L`) and a caustic of a small
//! light through a glass ball onto a diffuse floor (`L S S D E`). pathmlt's bootstrap and
//! global mutation sample every strategy of a bidirectional path tracer, so it converges to
//! BDPT (image mean and block means over independent replicates, `mlt_convergence.rs`'s
//! statistics). Negative control: the eye-side sampler pathmlt used before finds no
//! light-carrying path in the mirror room, and pathmlt at max depth 1 misses the reference.

mod common;

use std::sync::atomic::AtomicBool;

use common::bdpt_replicates;
use common::stats::{against_reference, assert_finite_non_negative, block_t, t_critical};
use glam::{Vec3, Vec3A};
use mcmc_core::render_loop::{bootstrap_key, IndependentStates};
use mcmc_core::Target;
use pathspace::{Path, PerturbationKind};
use render::bdpt::BdptParams;
use render::image::Image;
use render::mlt::pathmlt::{self, IndependentPaths, PathMltTarget};
use render::mlt::{LargeStepMode, MltBudget, MltSettings};
use render::pathspace_scene::PathSpaceScene;
use render::scene::{CameraSpec, Material, Mesh, Scene};
use render::session::NoProgress;

/// Image side, max depth, replicates (pathmlt and BDPT), blocks per side.
const SIZE: u32 = 16;
const DEPTH: u32 = 5;
const R: usize = 10;
const BLOCKS: usize = 2;
/// Comparisons: image mean and blocks on two scenes.
const N_COMPARISONS: usize = 2 * (1 + BLOCKS * BLOCKS);

fn critical() -> f64 {
    t_critical(0.001 / N_COMPARISONS as f64, (R - 1) as u32)
}

/// The quad of centre `c` spanned by `±u`, `±v`, facing `u x v`.
fn quad(mesh: &mut Mesh, c: Vec3A, u: Vec3A, v: Vec3A, material: u32) {
    mesh.add_quad([c - u - v, c + u - v, c + u + v, c - u + v], material);
}

fn mirror() -> Material {
    Material {
        name: "mirror".into(),
        base_color: Vec3::splat(0.95),
        metallic: 1.0,
        roughness: 0.0,
        ..Material::default()
    }
}

/// A diffuse floor lit only through mirrors: a small one-sided lamp facing up (nothing below
/// its plane sees it), a mirror above it turning its light sideways, a second mirror turning
/// it down onto the floor; the camera sees the lit floor and the second mirror's edge.
fn mirror_room() -> Scene {
    let mut mesh = Mesh::new();
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.7), Vec3::ZERO),
        Material::diffuse("lamp", Vec3::ZERO, Vec3::splat(400.0)),
        mirror(),
    ];
    let s = std::f32::consts::FRAC_1_SQRT_2;
    quad(
        &mut mesh,
        Vec3A::new(1.5, 0.0, -1.0),
        Vec3A::new(0.0, 0.0, 2.0),
        Vec3A::new(2.5, 0.0, 0.0),
        0,
    );
    quad(
        &mut mesh,
        Vec3A::new(0.0, 1.0, -1.0),
        Vec3A::new(0.0, 0.0, 0.05),
        Vec3A::new(0.05, 0.0, 0.0),
        1,
    );
    quad(
        &mut mesh,
        Vec3A::new(0.0, 2.0, -1.0),
        Vec3A::new(0.0, 0.0, 0.3),
        Vec3A::new(-s, -s, 0.0) * 0.3,
        2,
    );
    quad(
        &mut mesh,
        Vec3A::new(2.0, 2.0, -1.0),
        Vec3A::new(0.0, 0.0, 0.5),
        Vec3A::new(-s, s, 0.0) * 0.5,
        2,
    );
    let camera = CameraSpec::look_at(
        Vec3A::new(1.6, 2.2, 1.5),
        Vec3A::new(1.9, 0.0, -1.0),
        Vec3A::Y,
        50.0,
    );
    Scene::new(mesh, materials, vec![], camera, SIZE, SIZE)
}

/// A small bright lamp above a glass ball (ior 1.5) over a diffuse floor: the caustic.
fn caustic() -> Scene {
    let mut mesh = Mesh::new();
    let glass = Material {
        name: "glass".into(),
        base_color: Vec3::ONE,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.5,
        ..Material::default()
    };
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.7), Vec3::ZERO),
        Material::diffuse("lamp", Vec3::ZERO, Vec3::splat(75.0)),
        glass,
    ];
    quad(
        &mut mesh,
        Vec3A::new(0.0, 0.0, -1.0),
        Vec3A::new(0.0, 0.0, 2.0),
        Vec3A::new(2.0, 0.0, 0.0),
        0,
    );
    // Facing down: u x v = -y.
    quad(
        &mut mesh,
        Vec3A::new(0.0, 2.0, -1.0),
        Vec3A::new(0.1, 0.0, 0.0),
        Vec3A::new(0.0, 0.0, 0.1),
        1,
    );
    mesh.add_sphere(Vec3A::new(0.0, 0.6, -1.0), 0.4, 24, 48, 2, false);
    let camera = CameraSpec::look_at(
        Vec3A::new(0.0, 1.6, 1.2),
        Vec3A::new(0.0, 0.2, -1.0),
        Vec3A::Y,
        50.0,
    );
    Scene::new(mesh, materials, vec![], camera, SIZE, SIZE)
}

fn settings(seed: u64, depth_budget: f64) -> MltSettings {
    MltSettings {
        width: SIZE as usize,
        height: SIZE as usize,
        chains: 64,
        bootstrap_samples: 200_000,
        budget: MltBudget::MutationsPerPixel(depth_budget),
        large_step: LargeStepMode::Fixed(0.0),
        seed,
        streams: 1,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    }
}

fn replicates(scene: &Scene, depth: u32, seed0: u64) -> Vec<Image> {
    (0..R as u64)
        .map(|r| {
            let s = settings(seed0 + r, 512.0);
            let out = pathmlt::render(
                scene,
                PerturbationKind::Lens,
                depth,
                &s,
                &NoProgress,
                &AtomicBool::new(false),
            )
            .unwrap();
            assert!(out.message.is_none(), "replicate {r}: {:?}", out.message);
            assert_eq!(out.non_finite, 0);
            assert_finite_non_negative(&out.image, "pathmlt");
            out.image
        })
        .collect()
}

fn reference(scene: &Scene, seed0: u64) -> Vec<Image> {
    let params = BdptParams {
        max_depth: DEPTH,
        ..BdptParams::default()
    };
    bdpt_replicates(scene, &params, 2048, R, seed0)
}

#[test]
fn pathmlt_converges_to_bdpt_in_the_mirror_room() {
    let scene = mirror_room();
    let reference = reference(&scene, 80_000);
    let images = replicates(&scene, DEPTH, 1000);
    against_reference("mirror room", &images, &reference, BLOCKS, critical());
    // Negative control: at max depth 1 (direct light only) the floor is black.
    let shallow = replicates(&scene, 2, 2000);
    let worst = block_t(&shallow, &reference, BLOCKS)
        .iter()
        .map(|b| b[0].abs())
        .fold(0.0, f64::max);
    eprintln!("mirror room at max depth 2: worst block |t| {worst:.1}");
    assert!(worst > critical(), "depth 2 not detected: {worst}");
}

#[test]
fn pathmlt_converges_to_bdpt_on_a_caustic() {
    let scene = caustic();
    let reference = reference(&scene, 81_000);
    let images = replicates(&scene, DEPTH, 3000);
    against_reference("caustic", &images, &reference, BLOCKS, critical());
}

/// The eye-side sampler pathmlt bootstrapped from before finds (almost) nothing in the mirror
/// room, where the bidirectional sampler finds plenty: the reason for the change.
#[test]
fn the_eye_side_sampler_misses_the_mirror_room() {
    let scene = mirror_room();
    let view = PathSpaceScene::new(&scene).unwrap();
    let target = PathMltTarget::new(&view, SIZE as usize, SIZE as usize);
    let count = |states: &dyn Fn(u64, &mut Path), n: u64| {
        let (mut path, mut payload) = (Path::new(), None);
        (0..n)
            .filter(|&i| {
                states(bootstrap_key(7, 0, i), &mut path);
                target.evaluate(&mut path, &mut payload).is_finite()
            })
            .count()
    };
    let bidir = IndependentPaths {
        sampler: pathmlt::independent_sampler(&view, DEPTH).unwrap(),
    };
    let eye = IndependentPaths {
        sampler: pathmlt::unidirectional_sampler(&view, DEPTH).unwrap(),
    };
    let n = 100_000;
    let found_bidir = count(&|k, p| bidir.independent(k, p), n);
    let found_eye = count(&|k, p| eye.independent(k, p), n);
    eprintln!("light-carrying paths in {n}: bidirectional {found_bidir}, eye-side {found_eye}");
    assert!(
        found_bidir >= 50 && 20 * found_eye < found_bidir,
        "{found_bidir} vs {found_eye}"
    );
}
