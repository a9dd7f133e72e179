//! Closest-hit and any-hit ray throughput of the obvhs CWBVH on a procedurally displaced
//! sphere of 114 176 triangles (generated here), for incoherent rays from inside (like
//! path-tracing bounces) and for primary rays from a pinhole camera outside; and the BVH
//! build time (obvhs `medium_build`, single-threaded).
//!
//! `cargo bench -p render --bench rays` (add `-- --quick` for a short run).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{Vec2, Vec3A};
use render::bvh::Bvh;
use render::camera::Camera;
use render::sampler::{IndependentSampler, Sampler};
use render::scene::Mesh;
use render::warp::sample_uniform_sphere;

/// Rays per batch (one criterion iteration).
const RAYS: usize = 100_000;

/// A unit sphere with 224 rings and 256 segments (114 176 triangles) whose radius is
/// modulated by `1 + 0.08 sin(9θ) sin(7φ)`: concave and convex regions, like real geometry.
fn bumpy_sphere() -> Mesh {
    let mut m = Mesh::new();
    m.add_sphere(Vec3A::ZERO, 1.0, 224, 256, 0, false);
    for p in &mut m.positions {
        let d = p.normalize();
        let theta = d.y.clamp(-1.0, 1.0).acos();
        let phi = d.z.atan2(d.x);
        *p = d * (1.0 + 0.08 * (9.0 * theta).sin() * (7.0 * phi).sin());
    }
    m
}

fn rays(c: &mut Criterion) {
    let mesh = bumpy_sphere();
    assert!(mesh.triangle_count() >= 100_000);
    let bvh = Bvh::build(&mesh);
    let mut s = IndependentSampler::new(9);

    // Incoherent: random origins in a ball of radius 0.5, uniform random directions.
    let inside: Vec<(Vec3A, Vec3A)> = (0..RAYS)
        .map(|i| {
            s.start_pixel_sample(i as u64, 0);
            let o = sample_uniform_sphere(s.next_2d()) * 0.5 * s.next_1d();
            (o, sample_uniform_sphere(s.next_2d()))
        })
        .collect();
    // Primary: a 316 x 316 pinhole camera at distance 3 (about 60% of the rays hit).
    let cam = Camera::perspective(
        Vec3A::new(0.0, 0.0, 3.0),
        Vec3A::ZERO,
        Vec3A::Y,
        50.0,
        316,
        316,
    );
    let primary: Vec<(Vec3A, Vec3A)> = (0..RAYS)
        .map(|i| {
            let p = Vec2::new((i % 316) as f32 + 0.5, (i / 316) as f32 + 0.5);
            let r = cam.generate_ray(p, Vec2::ZERO, 0.0);
            (r.origin, r.dir)
        })
        .collect();

    let mut group = c.benchmark_group("rays_114k_tris");
    group.throughput(Throughput::Elements(RAYS as u64));
    group.bench_function("closest_hit_incoherent", |b| {
        b.iter(|| {
            let mut hits = 0usize;
            for &(o, d) in &inside {
                hits += usize::from(bvh.intersect(o, d, f32::INFINITY).is_some());
            }
            black_box(hits)
        })
    });
    group.bench_function("closest_hit_primary", |b| {
        b.iter(|| {
            let mut hits = 0usize;
            for &(o, d) in &primary {
                hits += usize::from(bvh.intersect(o, d, f32::INFINITY).is_some());
            }
            black_box(hits)
        })
    });
    group.bench_function("any_hit_incoherent", |b| {
        b.iter(|| {
            let mut hits = 0usize;
            for &(o, d) in &inside {
                hits += usize::from(bvh.occluded(o, d, 10.0));
            }
            black_box(hits)
        })
    });
    group.finish();

    let mut build = c.benchmark_group("bvh_build");
    build.sample_size(10);
    build.throughput(Throughput::Elements(mesh.triangle_count() as u64));
    build.bench_function("cwbvh_medium_114k_tris", |b| {
        b.iter(|| black_box(Bvh::build(&mesh)))
    });
    build.finish();
}

criterion_group!(benches, rays);
criterion_main!(benches);
