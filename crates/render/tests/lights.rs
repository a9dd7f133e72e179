//! The light model through every integrator: environment-map sampling (chi-square), a white
//! furnace under a uniform environment, closed-form irradiance from a point and a directional
//! light, and BDPT == PT with an environment map and a spot light. Each statistical test has a
//! negative control that the same check rejects.
//!
//! Block tests: an image is split into 4 x 4 blocks; each block mean (channel average) is
//! estimated from `R` independent replicates (different seeds: independent samplers, and for
//! the MCMC integrators independent bootstraps and chains), whose spread gives its standard
//! error. With 16 blocks and a family-wise level of 0.001 (Bonferroni: 6.25e-5 per block,
//! two-sided), the Student t critical value is about 5.5 for 15 degrees of freedom (R = 16)
//! and about 4.6 for the ~30 of a Welch two-sample test; we use [`Z_ONE_SAMPLE`] = 6 and
//! [`Z_TWO_SAMPLE`] = 5.

mod common;

use std::sync::atomic::AtomicBool;

use glam::{Vec2, Vec3, Vec3A};
use mcmc_core::testing::chi_square::{chi_square_test, MIN_EXPECTED};
use render::image::Image;
use render::light::{EnvironmentLight, PunctualLight};
use render::scene::{CameraSpec, Material, Mesh, Scene};
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};
use render::warp::{sample_uniform_sphere, uniform_sphere_pdf};

/// Replicates per integrator.
const R: usize = 16;
/// Critical |t| of the one-sample block test (see the module docs).
const Z_ONE_SAMPLE: f64 = 6.0;
/// Critical |t| of the two-sample (Welch) block test.
const Z_TWO_SAMPLE: f64 = 5.0;
/// Blocks per side.
const BLOCKS: usize = 4;

const ALL: [IntegratorKind; 4] = [
    IntegratorKind::Pt,
    IntegratorKind::Bdpt,
    IntegratorKind::Pssmlt,
    IntegratorKind::Mmlt,
];

fn settings(
    kind: IntegratorKind,
    size: u32,
    spp: u32,
    max_depth: u32,
    seed: u64,
) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        budget: Budget::SamplesPerPixel(spp),
        threads: 2,
        seed,
        max_depth,
        method: kind.settings().with_chains(64, 20_000),
    }
}

/// `R` replicates of `kind` with `spp` samples per pixel (4x as many mutations per pixel for
/// the MCMC integrators, whose per-mutation variance is higher, so that every control is
/// rejected at the same budgets).
fn replicates(scene: &Scene, kind: IntegratorKind, size: u32, spp: u32, depth: u32) -> Vec<Image> {
    let spp = match kind {
        IntegratorKind::Pssmlt | IntegratorKind::Mmlt => spp * 4,
        _ => spp,
    };
    (0..R)
        .map(|r| {
            let s = settings(
                kind,
                size,
                spp,
                depth,
                7919 * r as u64 + 31 * kind as u64 + 1,
            );
            let out = render(scene, &s, &NoProgress, &AtomicBool::new(false)).expect("render");
            assert!(
                out.image.pixels.iter().flatten().all(|c| c.is_finite()),
                "{kind:?}: non-finite pixel"
            );
            out.image
        })
        .collect()
}

/// Block means (channel average) of one image.
fn blocks(image: &Image) -> Vec<f64> {
    let b = image.width / BLOCKS;
    let mut out = [0.0; BLOCKS * BLOCKS];
    for y in 0..b * BLOCKS {
        for x in 0..b * BLOCKS {
            let p = image.pixels[y * image.width + x];
            out[(y / b) * BLOCKS + x / b] += p.iter().map(|&c| f64::from(c)).sum::<f64>() / 3.0;
        }
    }
    out.iter().map(|s| s / (b * b) as f64).collect()
}

/// Per block: mean over replicates and the variance of that mean.
fn block_stats(reps: &[Image]) -> Vec<(f64, f64)> {
    let per: Vec<Vec<f64>> = reps.iter().map(blocks).collect();
    (0..BLOCKS * BLOCKS)
        .map(|k| {
            let vals: Vec<f64> = per.iter().map(|b| b[k]).collect();
            let n = vals.len() as f64;
            let m = vals.iter().sum::<f64>() / n;
            let v = vals.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
            (m, v / n)
        })
        .collect()
}

/// Largest |t| of the block means against `expected` (a relative floor of 1e-4 on the
/// standard error keeps noise-free blocks, e.g. pure environment, from dividing by 0).
fn max_t_one_sample(reps: &[Image], expected: &[f64]) -> f64 {
    block_stats(reps)
        .iter()
        .zip(expected)
        .map(|(&(m, v), &e)| (m - e).abs() / (v.sqrt() + 1e-4 * e.abs()).max(1e-12))
        .fold(0.0, f64::max)
}

/// Largest Welch |t| between the block means of two sets of replicates.
fn max_t_two_sample(a: &[Image], b: &[Image]) -> f64 {
    block_stats(a)
        .iter()
        .zip(block_stats(b))
        .map(|(&(ma, va), (mb, vb))| {
            (ma - mb).abs() / ((va + vb).sqrt() + 1e-4 * ma.abs()).max(1e-12)
        })
        .fold(0.0, f64::max)
}

/// A convex, flat-shaded polyhedron approximating a unit sphere (flat normals: the shading
/// frame is the geometry's, so the furnace argument is exact).
fn convex_ball(material: u32) -> Mesh {
    common::flat_shaded_sphere(8, 16, material, false)
}

/// A white (albedo `albedo`) convex ball under a uniform environment of radiance 1.
fn furnace(albedo: f32, size: u32) -> Scene {
    let camera = CameraSpec::look_at(Vec3A::new(0.0, 0.0, 3.0), Vec3A::ZERO, Vec3A::Y, 45.0);
    let white = Material::diffuse("white", Vec3::splat(albedo), Vec3::ZERO);
    let mut scene = Scene::new(convex_ball(0), vec![white], vec![], camera, size, size);
    scene.set_environment(Some(EnvironmentLight::constant(Vec3::ONE)));
    scene
}

/// The white furnace: a white Lambertian convex object under a uniform environment of
/// radiance 1 reflects radiance exactly 1 in every direction (one bounce suffices: no point
/// of a convex object sees another), so every pixel is 1 for every integrator. Control: an
/// albedo of 0.8 must be detected.
#[test]
fn white_furnace_through_every_integrator() {
    let size = 16;
    let expected = vec![1.0; BLOCKS * BLOCKS];
    let scene = furnace(1.0, size);
    assert!(
        scene.notes.is_empty(),
        "an explicit environment is not the default"
    );
    for kind in ALL {
        let reps = replicates(&scene, kind, size, 16, 3);
        let t = max_t_one_sample(&reps, &expected);
        assert!(t < Z_ONE_SAMPLE, "{kind:?}: furnace block |t| = {t:.2}");
    }
    // Negative control: the same check rejects a grey ball.
    let grey = furnace(0.8, size);
    for kind in [IntegratorKind::Pt, IntegratorKind::Mmlt] {
        let reps = replicates(&grey, kind, size, 16, 3);
        let t = max_t_one_sample(&reps, &expected);
        assert!(
            t > Z_ONE_SAMPLE,
            "{kind:?}: control not rejected (|t| = {t:.2})"
        );
    }
}

/// A Lambertian floor (albedo `ALBEDO`, the plane y = 0) seen from above.
const ALBEDO: f32 = 0.5;

fn floor_scene(size: u32, light: PunctualLight) -> Scene {
    let mut mesh = Mesh::new();
    let s = 3.0;
    mesh.add_quad(
        [
            Vec3A::new(-s, 0.0, -s),
            Vec3A::new(-s, 0.0, s),
            Vec3A::new(s, 0.0, s),
            Vec3A::new(s, 0.0, -s),
        ],
        0,
    );
    let camera = CameraSpec::look_at(Vec3A::new(0.0, 2.5, 0.0), Vec3A::ZERO, Vec3A::Z, 60.0);
    let floor = Material::diffuse("floor", Vec3::splat(ALBEDO), Vec3::ZERO);
    let mut scene = Scene::new(mesh, vec![floor], vec![], camera, size, size);
    scene.add_punctual_lights([light]);
    scene
}

/// Expected block means of the floor scene: the closed-form radiance `radiance(x)` at the
/// floor point seen through each of 8 x 8 sub-pixel positions of every pixel.
fn expected_blocks(scene: &Scene, radiance: impl Fn(Vec3A) -> f64) -> Vec<f64> {
    let cam = scene.camera();
    let size = scene.camera().width() as usize;
    let mut img = Image::new(size, size);
    for y in 0..size {
        for x in 0..size {
            let mut sum = 0.0;
            for sy in 0..8 {
                for sx in 0..8 {
                    let p = Vec2::new(
                        x as f32 + (sx as f32 + 0.5) / 8.0,
                        y as f32 + (sy as f32 + 0.5) / 8.0,
                    );
                    let ray = cam.generate_ray(p, Vec2::ZERO, 0.0);
                    let t = -ray.origin.y / ray.dir.y;
                    sum += radiance(ray.origin + ray.dir * t);
                }
            }
            let v = (sum / 64.0) as f32;
            img.set(x, y, [v, v, v]);
        }
    }
    blocks(&img)
}

/// A point light of intensity `I` at height `h` over a Lambertian plane of albedo `rho`:
/// radiance `rho / pi * I * h / d^3` at a point at distance `d` (irradiance
/// `I cos(theta) / d^2`, `cos(theta) = h / d`). A directional light of irradiance `E` at
/// angle `theta` from the normal: uniform `rho / pi * E cos(theta)`. Controls: the point
/// light's closed form with the inverse square law dropped (`1 / d` instead of `1 / d^3`
/// falloff) and a directional light 25 % brighter are rejected (MMLT's block means of this
/// uniform image vary by about 5 % between replicates at this budget).
#[test]
fn punctual_lights_match_closed_form() {
    let size = 16;
    let (h, intensity) = (1.2f32, 3.0f32);
    let point = floor_scene(
        size,
        PunctualLight::point(Vec3A::new(0.3, h, -0.2), Vec3::splat(intensity)),
    );
    let rho_pi = f64::from(ALBEDO) / std::f64::consts::PI;
    let exact = |x: Vec3A| {
        let d = (Vec3A::new(0.3, h, -0.2) - x).length() as f64;
        rho_pi * f64::from(intensity) * f64::from(h) / d.powi(3)
    };
    let expected = expected_blocks(&point, exact);
    let wrong = expected_blocks(&point, |x| {
        let d = (Vec3A::new(0.3, h, -0.2) - x).length() as f64;
        rho_pi * f64::from(intensity) * f64::from(h) / d.powi(3) * d * d / f64::from(h * h)
    });
    let (theta, e) = (0.5f32, 2.0f32);
    let dir = -Vec3A::new(theta.sin(), theta.cos(), 0.0);
    let sun = floor_scene(size, PunctualLight::directional(dir, Vec3::splat(e)));
    let sun_exact = vec![rho_pi * f64::from(e * theta.cos()); BLOCKS * BLOCKS];
    let sun_wrong: Vec<f64> = sun_exact.iter().map(|v| v * 1.25).collect();
    for kind in ALL {
        let reps = replicates(&point, kind, size, 16, 2);
        let t = max_t_one_sample(&reps, &expected);
        assert!(t < Z_ONE_SAMPLE, "{kind:?}: point light block |t| = {t:.2}");
        let control = max_t_one_sample(&reps, &wrong);
        assert!(
            control > Z_ONE_SAMPLE,
            "{kind:?}: point control |t| = {control:.2}"
        );
        let reps = replicates(&sun, kind, size, 16, 2);
        let t = max_t_one_sample(&reps, &sun_exact);
        assert!(
            t < Z_ONE_SAMPLE,
            "{kind:?}: directional light block |t| = {t:.2}"
        );
        let control = max_t_one_sample(&reps, &sun_wrong);
        assert!(
            control > Z_ONE_SAMPLE,
            "{kind:?}: directional control |t| = {control:.2}"
        );
    }
}

/// A synthetic sky: a horizontal gradient, a bright sun blob, dark below the horizon.
fn sky_map() -> Image {
    let (w, h) = (64, 32);
    let mut img = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let up = 1.0 - y as f32 / h as f32;
            let mut c = [0.2 + 0.6 * up, 0.3 + 0.5 * up, 0.5 + 0.5 * up];
            if y >= h / 2 {
                c = [0.05, 0.04, 0.03];
            }
            if (x as i32 - 40).abs() <= 1 && (y as i32 - 9).abs() <= 1 {
                c = [60.0, 50.0, 40.0];
            }
            img.set(x, y, c);
        }
    }
    img
}

/// An open scene: a floor, a box and a glossy block, lit by the sky map and a spot light.
fn sky_and_spot_scene(size: u32) -> Scene {
    let mut mesh = Mesh::new();
    let s = 2.0;
    mesh.add_quad(
        [
            Vec3A::new(-s, 0.0, -s),
            Vec3A::new(-s, 0.0, s),
            Vec3A::new(s, 0.0, s),
            Vec3A::new(s, 0.0, -s),
        ],
        0,
    );
    mesh.add_box(
        glam::Mat4::from_scale_rotation_translation(
            glam::Vec3::new(0.6, 0.8, 0.6),
            glam::Quat::from_rotation_y(0.4),
            glam::Vec3::new(-0.4, 0.4, -0.3),
        ),
        1,
    );
    mesh.add_box(
        glam::Mat4::from_scale_rotation_translation(
            glam::Vec3::new(0.5, 0.3, 0.5),
            glam::Quat::IDENTITY,
            glam::Vec3::new(0.6, 0.15, 0.4),
        ),
        2,
    );
    let camera = CameraSpec::look_at(
        Vec3A::new(0.0, 1.6, 3.0),
        Vec3A::new(0.0, 0.3, 0.0),
        Vec3A::Y,
        50.0,
    );
    let glossy = Material {
        name: "glossy".into(),
        base_color: Vec3::new(0.8, 0.6, 0.3),
        metallic: 1.0,
        roughness: 0.4,
        ..Material::default()
    };
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.6), Vec3::ZERO),
        Material::diffuse("box", Vec3::new(0.7, 0.3, 0.3), Vec3::ZERO),
        glossy,
    ];
    let mut scene = Scene::new(mesh, materials, vec![], camera, size, size);
    scene.set_environment(Some(EnvironmentLight::from_map(sky_map(), 1.0, 25.0)));
    scene.add_punctual_lights([PunctualLight::spot(
        Vec3A::new(0.8, 1.8, 0.8),
        Vec3A::new(-0.3, -1.0, -0.4),
        Vec3::new(8.0, 7.0, 5.0),
        0.3,
        0.6,
    )]);
    scene
}

/// BDPT (every strategy, MIS with the infinite and the delta light) equals PT on an open
/// scene lit by an environment map and a spot light. Control: the same check rejects PT with
/// the environment 10 % brighter.
#[test]
fn bdpt_equals_pt_with_environment_map_and_spot_light() {
    let size = 16;
    let scene = sky_and_spot_scene(size);
    let pt = replicates(&scene, IntegratorKind::Pt, size, 32, 4);
    let bd = replicates(&scene, IntegratorKind::Bdpt, size, 16, 4);
    let t = max_t_two_sample(&pt, &bd);
    assert!(t < Z_TWO_SAMPLE, "BDPT vs PT: block |t| = {t:.2}");
    let mut brighter = scene.clone();
    brighter.set_environment(Some(EnvironmentLight::from_map(sky_map(), 1.1, 25.0)));
    let pt_bright = replicates(&brighter, IntegratorKind::Pt, size, 32, 4);
    let control = max_t_two_sample(&pt_bright, &bd);
    assert!(
        control > Z_TWO_SAMPLE,
        "control not rejected: |t| = {control:.2}"
    );
}

/// Chi-square test of environment-map sampling against its pdf: directions binned on an
/// equal-area grid (16 bins in azimuth x 8 in cos(theta)), expected counts from a fine
/// quadrature of the pdf. Control: the samples of a map rotated by 30 degrees are rejected.
#[test]
fn environment_sampling_matches_its_pdf() {
    let env = EnvironmentLight::from_map(sky_map(), 1.0, 0.0);
    let rotated = EnvironmentLight::from_map(sky_map(), 1.0, 30.0);
    let (nphi, nz) = (16usize, 8usize);
    let bin = |w: Vec3A| {
        let phi = w.z.atan2(w.x).rem_euclid(std::f32::consts::TAU) / std::f32::consts::TAU;
        let z = 0.5 * (w.y + 1.0);
        let i = ((phi * nphi as f32) as usize).min(nphi - 1);
        let j = ((z * nz as f32) as usize).min(nz - 1);
        j * nphi + i
    };
    // Expected probabilities: uniform-sphere quadrature of pdf / uniform pdf.
    let q = 600;
    let mut probs = vec![0.0f64; nphi * nz];
    for a in 0..q {
        for b in 0..q {
            let w = sample_uniform_sphere(Vec2::new(
                (a as f32 + 0.5) / q as f32,
                (b as f32 + 0.5) / q as f32,
            ));
            probs[bin(w)] += f64::from(env.pdf(w) / uniform_sphere_pdf()) / f64::from(q * q);
        }
    }
    let total: f64 = probs.iter().sum();
    assert!((total - 1.0).abs() < 0.01, "pdf integrates to {total}");
    let n = 200_000u32;
    let mut counts = vec![0u64; nphi * nz];
    let mut counts_rotated = vec![0u64; nphi * nz];
    let mut mismatches = 0u32;
    for i in 0..n {
        // A (0, 2)-sequence-free, deterministic scramble of the unit square.
        let u = Vec2::new(
            (f64::from(i) * 0.754_877_666_246_692_7).fract() as f32,
            (f64::from(i) * 0.569_840_290_998_053_3).fract() as f32,
        );
        if let Some(s) = env.sample(u) {
            counts[bin(s.wi)] += 1;
            // pdf() re-derives the texel from the direction: f32 rounding may put a sample
            // drawn exactly on a texel border into the neighbour (a set of measure zero).
            if (env.pdf(s.wi) - s.pdf).abs() > 2e-3 * s.pdf {
                mismatches += 1;
            }
        }
        if let Some(s) = rotated.sample(u) {
            counts_rotated[bin(s.wi)] += 1;
        }
    }
    assert!(
        mismatches <= n / 1000,
        "{mismatches} samples whose pdf() disagrees"
    );
    chi_square_test(&counts, &probs, MIN_EXPECTED).assert_passes("environment sampling", 2);
    let control = chi_square_test(&counts_rotated, &probs, MIN_EXPECTED);
    assert!(control.rejects(1e-6), "control: {control}");
}

/// A scene without any light renders under the default environment (and says so); with the
/// environment switched off it is black.
#[test]
fn default_environment_and_switching_it_off() {
    let size = 8;
    let camera = CameraSpec::look_at(Vec3A::new(0.0, 0.0, 3.0), Vec3A::ZERO, Vec3A::Y, 45.0);
    let white = Material::diffuse("white", Vec3::ONE, Vec3::ZERO);
    let mut scene = Scene::new(convex_ball(0), vec![white], vec![], camera, size, size);
    assert!(scene.uses_default_environment());
    assert!(scene
        .notes
        .iter()
        .any(|n| n.contains("default uniform white environment")));
    let s = settings(IntegratorKind::Pt, size, 4, 3, 1);
    let out = render(&scene, &s, &NoProgress, &AtomicBool::new(false)).unwrap();
    let mean = out.image.pixels.iter().map(|p| p[1]).sum::<f32>() / (size * size) as f32;
    assert!((mean - 1.0).abs() < 0.05, "{mean}");
    scene.set_environment(None);
    assert!(scene.lights().is_empty() && scene.notes.is_empty());
    let out = render(&scene, &s, &NoProgress, &AtomicBool::new(false)).unwrap();
    assert!(out.image.pixels.iter().flatten().all(|&c| c == 0.0));
    // A light of its own replaces the default environment.
    let mut lit = Scene::new(
        convex_ball(0),
        vec![Material::diffuse("w", Vec3::ONE, Vec3::ZERO)],
        vec![],
        camera,
        size,
        size,
    );
    lit.add_punctual_lights([PunctualLight::point(Vec3A::new(0.0, 3.0, 0.0), Vec3::ONE)]);
    assert!(!lit.uses_default_environment() && lit.lights().environment().is_none());
}

/// A floor whose vertex normals are all tilted by `tilt` radians about +X (shading normal !=
/// geometric normal), under an emissive quad and a point light.
fn tilted_floor(size: u32, tilt: f32) -> Scene {
    let mut mesh = Mesh::new();
    let n = Vec3A::new(0.0, tilt.cos(), tilt.sin());
    let s = 2.0;
    let c = [
        Vec3A::new(-s, 0.0, -s),
        Vec3A::new(-s, 0.0, s),
        Vec3A::new(s, 0.0, s),
        Vec3A::new(s, 0.0, -s),
    ];
    let i: Vec<u32> = c
        .iter()
        .map(|&p| mesh.add_vertex(p, n, Vec2::ZERO))
        .collect();
    mesh.add_triangle([i[0], i[1], i[2]], 0);
    mesh.add_triangle([i[0], i[2], i[3]], 0);
    mesh.add_quad(
        [
            Vec3A::new(-0.3, 1.5, -0.3),
            Vec3A::new(0.3, 1.5, -0.3),
            Vec3A::new(0.3, 1.5, 0.3),
            Vec3A::new(-0.3, 1.5, 0.3),
        ],
        1,
    );
    let camera = CameraSpec::look_at(Vec3A::new(0.0, 1.2, 2.5), Vec3A::ZERO, Vec3A::Y, 50.0);
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.7), Vec3::ZERO),
        Material::diffuse("lamp", Vec3::ZERO, Vec3::splat(5.0)),
    ];
    let mut scene = Scene::new(mesh, materials, vec![], camera, size, size);
    scene.add_punctual_lights([PunctualLight::point(
        Vec3A::new(1.0, 1.0, 0.5),
        Vec3::splat(2.0),
    )]);
    scene
}

/// BDPT equals PT when shading normals differ from geometric ones: light-subpath vertices need
/// Veach's shading-normal correction in their connections, not only in the random walk (a
/// missing correction made BDPT about 8 % darker here). Control: the same check rejects PT on
/// the untilted floor against BDPT on the tilted one.
#[test]
fn bdpt_equals_pt_with_tilted_shading_normals() {
    let size = 16;
    let tilted = tilted_floor(size, 0.6);
    let pt = replicates(&tilted, IntegratorKind::Pt, size, 32, 2);
    let bd = replicates(&tilted, IntegratorKind::Bdpt, size, 16, 2);
    let t = max_t_two_sample(&pt, &bd);
    assert!(
        t < Z_TWO_SAMPLE,
        "BDPT vs PT, tilted normals: block |t| = {t:.2}"
    );
    let flat = replicates(&tilted_floor(size, 0.0), IntegratorKind::Pt, size, 32, 2);
    let control = max_t_two_sample(&flat, &bd);
    assert!(
        control > Z_TWO_SAMPLE,
        "control not rejected: |t| = {control:.2}"
    );
}

/// A floor lit from above by an emitter quad spanning x in [-0.5, 0.5]: either emitting
/// uniformly over `[x0, x1]` only (an untextured quad of that extent), or the full quad with an
/// emissive texture white on its left half and black on its right (`textured`).
fn emissive_texture_scene(size: u32, textured: bool, x0: f32, x1: f32) -> Scene {
    use render::scene::{Texture, TextureFilter, TextureRef};
    let mut mesh = Mesh::new();
    let s = 2.0;
    mesh.add_quad(
        [
            Vec3A::new(-s, 0.0, -s),
            Vec3A::new(-s, 0.0, s),
            Vec3A::new(s, 0.0, s),
            Vec3A::new(s, 0.0, -s),
        ],
        0,
    );
    // Facing down; UV u runs with x (left half u < 0.5).
    let y = 1.0;
    let corners = [
        (Vec3A::new(x0, y, -0.5), Vec2::new(0.0, 0.0)),
        (Vec3A::new(x1, y, -0.5), Vec2::new(1.0, 0.0)),
        (Vec3A::new(x1, y, 0.5), Vec2::new(1.0, 1.0)),
        (Vec3A::new(x0, y, 0.5), Vec2::new(0.0, 1.0)),
    ];
    let i: Vec<u32> = corners
        .iter()
        .map(|&(p, uv)| mesh.add_vertex(p, -Vec3A::Y, uv))
        .collect();
    mesh.add_triangle([i[0], i[1], i[2]], 1);
    mesh.add_triangle([i[0], i[2], i[3]], 1);
    let camera = CameraSpec::look_at(
        Vec3A::new(0.0, 0.6, 2.2),
        Vec3A::new(0.0, 0.0, 0.0),
        Vec3A::Y,
        60.0,
    );
    let mut lamp = Material::diffuse("lamp", Vec3::ZERO, Vec3::splat(4.0));
    let mut textures = vec![];
    if textured {
        let texels: Vec<Vec3> = (0..8)
            .map(|x| if x < 4 { Vec3::ONE } else { Vec3::ZERO })
            .collect();
        let mut t = Texture::new(8, 1, texels).unwrap();
        t.filter = TextureFilter::Nearest;
        textures.push(t);
        lamp.emissive_texture = Some(TextureRef::new(0));
    }
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.7), Vec3::ZERO),
        lamp,
    ];
    Scene::new(mesh, materials, textures, camera, size, size)
}

/// Emissive textures light the scene through light sampling too: a quad whose emissive
/// texture is white on its left half lights the floor exactly as an untextured quad covering
/// only that half (PT, BDPT and MMLT on the textured scene against PT on the half quad).
/// Control: the full untextured quad (twice the power) is rejected. (BDPT once skipped its
/// next-event strategy whenever the unused light subpath started on a black texel: 37 %
/// too dark here, |t| 43.)
#[test]
fn emissive_textures_light_through_every_strategy() {
    let size = 16;
    let textured = emissive_texture_scene(size, true, -0.5, 0.5);
    let half = emissive_texture_scene(size, false, -0.5, 0.0);
    let full = emissive_texture_scene(size, false, -0.5, 0.5);
    // The textured emitter's power counts the texture's mean (half of it).
    let (tl, hl) = (textured.lights(), half.lights());
    let power = |l: &render::light::Lights| l.lights().iter().map(|a| a.power()).sum::<f32>();
    assert!(
        (power(tl) / power(hl) - 1.0).abs() < 0.05,
        "{} vs {}",
        power(tl),
        power(hl)
    );
    // Depth 1: the emitter seen directly and direct light on the floor.
    let reference = replicates(&half, IntegratorKind::Pt, size, 32, 1);
    for kind in [
        IntegratorKind::Pt,
        IntegratorKind::Bdpt,
        IntegratorKind::Mmlt,
    ] {
        let reps = replicates(&textured, kind, size, 32, 1);
        let t = max_t_two_sample(&reference, &reps);
        assert!(
            t < Z_TWO_SAMPLE,
            "{kind:?}: emissive texture block |t| = {t:.2}"
        );
    }
    let control = replicates(&full, IntegratorKind::Pt, size, 32, 1);
    let t = max_t_two_sample(&reference, &control);
    assert!(t > Z_TWO_SAMPLE, "control not rejected: |t| = {t:.2}");
}
