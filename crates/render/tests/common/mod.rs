//! Shared fixtures of the render integration tests.
#![allow(dead_code, unreachable_pub)]

pub mod coverage;
pub mod gradient;
pub mod stats;

use glam::{Vec2, Vec3, Vec3A};
use std::path::Path;

use render::scene::{CameraSpec, Material, Mesh, Scene};

/// Emitted radiance of the analytic enclosure's walls.
pub const ENCLOSURE_LE: f32 = 0.5;
/// Albedo of the analytic enclosure's walls.
pub const ENCLOSURE_ALBEDO: f32 = 0.6;

/// The inside of a closed, flat-shaded sphere (a tessellated polyhedron: the closed form does
/// not need a true sphere) whose walls are Lambertian with albedo `rho` and emit `Le` towards
/// the inside. Radiance is uniform: with paths of at most `D` bounces it is
/// `Le (1 - rho^(D+1)) / (1 - rho)` everywhere (the furnace argument: every reflection of a
/// uniform radiance field of a Lambertian wall returns `rho` times it). Flat normals keep the
/// shading frame equal to the geometry, so the closed form is exact.
pub fn analytic_enclosure(width: u32, height: u32) -> Scene {
    let mesh = flat_shaded_sphere(12, 24, 0, true);
    let wall = Material::diffuse(
        "wall",
        Vec3::splat(ENCLOSURE_ALBEDO),
        Vec3::splat(ENCLOSURE_LE),
    );
    let camera = CameraSpec::look_at(
        Vec3A::new(0.0, 0.0, 0.3),
        Vec3A::new(0.0, 0.1, -1.0),
        Vec3A::Y,
        60.0,
    );
    Scene::new(mesh, vec![wall], vec![], camera, width, height)
}

/// A unit sphere at the origin tessellated into `rings x segments` as [`Mesh::add_sphere`]
/// does, with flat normals (each triangle's geometric normal at its vertices, so the shading
/// frame is the geometry's), all of material `material`; `inward` faces the centre.
pub fn flat_shaded_sphere(rings: u32, segments: u32, material: u32, inward: bool) -> Mesh {
    let mut smooth = Mesh::new();
    smooth.add_sphere(Vec3A::ZERO, 1.0, rings, segments, material, inward);
    let mut mesh = Mesh::new();
    for tri in 0..smooth.triangle_count() {
        let [a, b, c] = smooth.vertices(tri);
        let n = (b - a).cross(c - a).normalize();
        let i0 = mesh.add_vertex(a, n, Vec2::ZERO);
        let i1 = mesh.add_vertex(b, n, Vec2::ZERO);
        let i2 = mesh.add_vertex(c, n, Vec2::ZERO);
        mesh.add_triangle([i0, i1, i2], material);
    }
    mesh
}

/// The exact radiance of [`analytic_enclosure`] for paths of at most `max_depth` bounces.
pub fn enclosure_radiance(max_depth: u32) -> f64 {
    let rho = f64::from(ENCLOSURE_ALBEDO);
    f64::from(ENCLOSURE_LE) * (1.0 - rho.powi(max_depth as i32 + 1)) / (1.0 - rho)
}

/// Mean and standard error of the per-pixel means of an image (channel 0), treating pixels as
/// independent (true for independent samplers).
pub fn mean_and_se(pixels: &[[f32; 3]]) -> (f64, f64) {
    let n = pixels.len() as f64;
    let mean = pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / n;
    let var = pixels
        .iter()
        .map(|p| (f64::from(p[0]) - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// `k` independent BDPT renders of `scene` (seeds `seed0 .. seed0 + k`, `spp` samples per
/// pixel each, one thread's worth of work each): the replicate reference the MCMC convergence
/// tests compare against (`stats::against_reference`). Every render is checked finite and
/// non-negative with nothing dropped.
pub fn bdpt_replicates(
    scene: &Scene,
    params: &render::bdpt::BdptParams,
    spp: u32,
    k: usize,
    seed0: u64,
) -> Vec<render::image::Image> {
    (0..k as u64)
        .map(|i| {
            let out = render::bdpt::render_bdpt(
                scene,
                params,
                Some(spp),
                None,
                seed0 + i,
                false,
                &render::session::NoProgress,
                &std::sync::atomic::AtomicBool::new(false),
            );
            assert_eq!(out.dropped, 0, "BDPT reference replicate {i}");
            stats::assert_finite_non_negative(&out.image, "BDPT reference");
            out.image
        })
        .collect()
}

/// The bundled scene `scenes/<name>` at `size x size` pixels.
pub fn scene_file(name: &str, size: u32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    let mut scene = Scene::load(&path).unwrap();
    scene.set_resolution(size, size);
    scene
}
