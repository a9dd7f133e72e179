//! Path-traced samples per second on the built-in Cornell box (max depth 5): one thread
//! calling the path tracer directly, and the full `render()` session on two threads.
//!
//! `cargo bench -p render --bench pt` (add `-- --quick` for a short run).

use std::hint::black_box;
use std::sync::atomic::AtomicBool;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::UVec2;
use render::integrator::pt;
use render::sampler::IndependentSampler;
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

const SIZE: u32 = 64;

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
            let mut sum = 0.0f32;
            for y in 0..SIZE {
                for x in 0..SIZE {
                    sampler.start_pixel_sample(u64::from(y * SIZE + x), pass);
                    let (_, l) =
                        pt::sample_pixel(&scene, scene.camera(), UVec2::new(x, y), &mut sampler, 5);
                    sum += l.x;
                }
            }
            black_box(sum)
        })
    });

    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        integrator: IntegratorKind::Pt,
        budget: Budget::SamplesPerPixel(1),
        threads: 2,
        seed: 0,
        max_depth: 5,
        ..RenderSettings::default()
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
