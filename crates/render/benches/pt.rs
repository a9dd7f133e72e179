//! Path-traced samples per second on the built-in Cornell box (max depth 5): one thread
//! calling the path tracer directly (64 x 64 pixels, one sample each per iteration) with
//! independent numbers and with Owen-scrambled Sobol points (the `pt` default), and the full
//! `render()` session on two threads (128 x 128 pixels, 4 samples per pixel).
//!
//! `cargo bench -p render --bench pt` (add `-- --quick` for a short run).

use std::hint::black_box;
use std::sync::atomic::AtomicBool;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::UVec2;
use render::integrator::pt;
use render::sampler::{IndependentSampler, PixelSampler, SobolSampler};
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

const SIZE: u32 = 64;

/// One sample of every pixel of the `SIZE x SIZE` image (sample index `pass`): the sum of the
/// red channel.
fn one_pass<S: PixelSampler>(scene: &Scene, sampler: &mut S, pass: u64) -> f32 {
    let mut sum = 0.0f32;
    for y in 0..SIZE {
        for x in 0..SIZE {
            sampler.start_pixel_sample(u64::from(y * SIZE + x), pass);
            let (_, l) = pt::sample_pixel(scene, scene.camera(), UVec2::new(x, y), sampler, 5);
            sum += l.x;
        }
    }
    sum
}

fn pt_cornell(c: &mut Criterion) {
    let scene = Scene::cornell_box(SIZE, SIZE);
    let samples = u64::from(SIZE * SIZE);
    let mut group = c.benchmark_group("pt_cornell_box");
    group.throughput(Throughput::Elements(samples));

    let mut pass = 0u64;
    group.bench_function("samples_1_thread", |b| {
        let mut sampler = IndependentSampler::new(1);
        b.iter(|| {
            pass += 1;
            black_box(one_pass(&scene, &mut sampler, pass))
        })
    });
    let mut pass = 0u64;
    group.bench_function("samples_1_thread_sobol", |b| {
        let mut sampler = SobolSampler::new(1);
        b.iter(|| {
            pass += 1;
            black_box(one_pass(&scene, &mut sampler, pass))
        })
    });

    // The session: 128 x 128 at 4 samples per pixel (65 536 samples per call, so that
    // creating the thread pool is amortised).
    group.throughput(Throughput::Elements(128 * 128 * 4));
    let settings = RenderSettings {
        method: IntegratorKind::Pt.settings(),
        width: 128,
        height: 128,
        budget: Budget::SamplesPerPixel(4),
        threads: 2,
        seed: 0,
        max_depth: 5,
    };
    let cancel = AtomicBool::new(false);
    group.bench_function("render_session_2_threads", |b| {
        b.iter(|| {
            black_box(
                render(&scene, &settings, &NoProgress, &cancel)
                    .unwrap()
                    .samples,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, pt_cornell);
criterion_main!(benches);
