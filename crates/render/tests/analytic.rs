//! Analytic scene: the inside of a closed box whose walls all emit radiance `Le` and reflect
//! diffusely with albedo `ρ`. Radiance is then the same everywhere and in every direction,
//! `L = Le + ρ L`, so `L = Le / (1 - ρ)` (per RGB channel); a path tracer limited to `D`
//! bounces converges to the partial sum `Le (1 - ρ^(D+1)) / (1 - ρ)`.
//!
//! # Error bound
//! With the one-pixel box filter, a pixel value `X_j` is the mean of its `N` samples. Pixels
//! use disjoint keys of the counter-based samplers (independent numbers, or Sobol points
//! scrambled per pixel), so the `P` pixel values are independent and
//! identically distributed with mean `μ` (every pixel sees the same radiance) and some variance
//! `σ²`. The image mean `M = Σ X_j / P` then has standard deviation `σ / √P`, and `σ` is
//! estimated by the sample standard deviation `s` of the pixel values (P = 1024, so the
//! estimate is good). We require `|M - μ| <= 5 s / √P + 1e-5 μ`: by the central limit theorem a
//! correct renderer fails with probability about 6e-7 per channel (the 1e-5 μ covers f32
//! rounding). A biased renderer (e.g. a missing MIS weight, double-counted emission, or a
//! cosine error) is off by far more than 5 standard errors at these sample counts.

use std::sync::atomic::AtomicBool;

use glam::{Mat4, Vec3, Vec3A};
use render::bdpt::Roulette;
use render::methods::PtSettings;
use render::sampler::SamplerKind;
use render::scene::{CameraSpec, Material, Mesh, Scene};
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

const SIZE: u32 = 32;

/// A 4 x 4 x 4 box seen from inside: mirroring the unit cube flips its winding, so every face
/// points inwards (and emits inwards).
fn furnace_box(albedo: Vec3, emission: Vec3) -> Scene {
    let mut mesh = Mesh::new();
    mesh.add_box(Mat4::from_scale(glam::Vec3::new(-4.0, 4.0, 4.0)), 0);
    let camera = CameraSpec::look_at(
        Vec3A::new(0.3, -0.2, 0.1),
        Vec3A::new(1.0, 0.5, 2.0),
        Vec3A::Y,
        90.0,
    );
    Scene::new(
        mesh,
        vec![Material::diffuse("wall", albedo, emission)],
        vec![],
        camera,
        SIZE,
        SIZE,
    )
}

/// Renders and checks every channel of the image mean against `expected`.
fn check(scene: &Scene, spp: u32, max_depth: u32, expected: Vec3) {
    check_with(scene, spp, max_depth, expected, None, None).unwrap();
}

/// [`check`] with a sampler and a roulette setting; `Err` names the failing channel.
fn check_with(
    scene: &Scene,
    spp: u32,
    max_depth: u32,
    expected: Vec3,
    sampler: Option<SamplerKind>,
    roulette: Option<Roulette>,
) -> Result<(), String> {
    let defaults = PtSettings::default();
    let settings = RenderSettings {
        method: PtSettings {
            sampler: sampler.unwrap_or(defaults.sampler),
            roulette: roulette.map_or(defaults.roulette, |r| r.start),
        }
        .into(),
        width: SIZE,
        height: SIZE,
        budget: Budget::SamplesPerPixel(spp),
        threads: 2,
        seed: 42,
        max_depth,
    };
    let out = render(scene, &settings, &NoProgress, &AtomicBool::new(false)).unwrap();
    assert_eq!(out.dropped_nonfinite, 0);
    let p = out.image.pixels.len() as f64;
    for c in 0..3 {
        let values: Vec<f64> = out.image.pixels.iter().map(|px| f64::from(px[c])).collect();
        let mean = values.iter().sum::<f64>() / p;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (p - 1.0);
        let std_error = (var / p).sqrt();
        let mu = f64::from(expected[c]);
        let bound = 5.0 * std_error + 1e-5 * mu;
        println!("channel {c}: mean {mean:.5}, exact {mu:.5}, bound {bound:.5}");
        if (mean - mu).abs() > bound {
            return Err(format!(
                "channel {c}: mean {mean} vs exact {mu} (bound {bound}, std error {std_error})"
            ));
        }
    }
    Ok(())
}

/// Radiance with at most `depth` bounces: `Le Σ_{k=0..depth} ρ^k`.
fn partial_sum(le: Vec3, rho: Vec3, depth: u32) -> Vec3 {
    (0..=depth).fold(Vec3::ZERO, |acc, k| acc + le * rho.powf(k as f32))
}

#[test]
fn closed_emissive_diffuse_box_has_radiance_le_over_one_minus_rho() {
    let (rho, le) = (Vec3::new(0.5, 0.8, 0.2), Vec3::new(1.0, 0.5, 2.0));
    let scene = furnace_box(rho, le);
    // 200 bounces: the truncation ρ^201 is below 1e-19 of the sum.
    let exact = le / (Vec3::ONE - rho);
    assert!((partial_sum(le, rho, 200) - exact).abs().max_element() < 1e-5);
    check(&scene, 16, 200, exact);
}

#[test]
fn direct_lighting_only_is_le_times_one_plus_rho() {
    // Depth 1: emission seen directly plus one bounce, where MIS combines light and BSDF
    // sampling; both strategies see emitters everywhere, so a wrong MIS weight shows.
    let (rho, le) = (Vec3::splat(0.6), Vec3::new(1.0, 2.0, 3.0));
    let scene = furnace_box(rho, le);
    check(&scene, 8, 1, partial_sum(le, rho, 1));
    check(&scene, 8, 3, partial_sum(le, rho, 3));
}

/// Both samplers, with Russian roulette from bounce 3 (the default), from bounce 1 and off,
/// converge to the partial sum; the negative control (the partial sum one bounce short)
/// fails the same check.
#[test]
fn both_samplers_with_and_without_roulette_match_the_partial_sum() {
    let (rho, le) = (Vec3::new(0.7, 0.5, 0.9), Vec3::new(1.0, 2.0, 0.5));
    let scene = furnace_box(rho, le);
    let depth = 6;
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        for roulette in [
            None,
            Some(Roulette { start: Some(1) }),
            Some(Roulette { start: None }),
        ] {
            println!("{sampler:?}, roulette {roulette:?}");
            check_with(
                &scene,
                8,
                depth,
                partial_sum(le, rho, depth),
                Some(sampler),
                roulette,
            )
            .unwrap_or_else(|e| panic!("{sampler:?}, roulette {roulette:?}: {e}"));
            let short = partial_sum(le, rho, depth - 1);
            assert!(
                check_with(&scene, 8, depth, short, Some(sampler), roulette).is_err(),
                "{sampler:?}, roulette {roulette:?}: the negative control passed"
            );
        }
    }
}

#[test]
fn depth_zero_is_exactly_le() {
    let le = Vec3::new(0.25, 0.5, 1.0);
    let scene = furnace_box(Vec3::splat(0.5), le);
    let settings = RenderSettings {
        method: IntegratorKind::Pt.settings(),
        width: 8,
        height: 8,
        budget: Budget::SamplesPerPixel(2),
        threads: 1,
        seed: 1,
        max_depth: 0,
    };
    let out = render(&scene, &settings, &NoProgress, &AtomicBool::new(false)).unwrap();
    for px in &out.image.pixels {
        assert_eq!(*px, le.to_array());
    }
}
