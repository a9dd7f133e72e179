//! Throughput of the bidirectional integrators on `scenes/cornell-glass.gltf` (64x64, max
//! depth 5, one thread): BDPT samples/s, PSSMLT and MMLT mutations/s, and the cost of the MCMC
//! bookkeeping alone (MH on a PSS target that reads 20 numbers and traces nothing); Langevin
//! MLT's mutations/s and the cost of a finite-difference value + gradient against a value.
//!
//! `cargo bench -p render --bench mlt` (add `-- --quick` for a short run).

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec2;
use mcmc_core::render_loop::{SplatGrid, SplatObserver};
use mcmc_core::DifferentiableTarget;
use mcmc_core::{Chain, Mh, NoAdaptation, Target};
use pss::{KelemenParams, PssState, PssmltProposal, SmallMutation, SmallStep};
use rand::SeedableRng;
use render::autodiff::Lane;
use render::bdpt::diff::{evaluate_strategy, DiffScene, Dual, Evaluation};
use render::bdpt::{self, BdptParams, BdptScratch};
use render::mlt::dr::DrBase;
use render::mlt::mala::{self, DifferentiableMmlt, GradientMethod, MalaConfig, MalaVariant};
use render::mlt::{MmltTarget, PssmltTarget, PATH_STREAMS};
use render::sampler::{IndependentSampler, Sampler};
use render::scene::Scene;

const SIZE: u32 = 64;
const STEPS: u64 = 1_000;

fn scene() -> Scene {
    scene_named("cornell-glass")
}

fn scene_named(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../scenes/{name}.gltf"));
    let mut s = Scene::load(&path).unwrap_or_else(|_| Scene::cornell_box(SIZE, SIZE));
    s.set_resolution(SIZE, SIZE);
    s
}

fn kernel() -> Mh<PssmltProposal> {
    let small = SmallStep::new(SmallMutation::Kelemen(KelemenParams::kelemen2002()));
    Mh::new(PssmltProposal::new(small, 0.3).expect("valid p"))
}

/// Steps a chain of `kernel` started from a bootstrap sample of `target` chosen by luminance.
fn bench_chain<T, K>(c: &mut Criterion, name: &str, target: &T, kernel: K)
where
    T: Target<State = PssState, Payload = render::mlt::PathPayload>,
    K: mcmc_core::Kernel<T>,
{
    bench_chain_in(c, "mutations_cornell_glass", name, target, kernel);
}

/// [`bench_chain`] in the benchmark group `group`.
fn bench_chain_in<T, K>(c: &mut Criterion, group: &str, name: &str, target: &T, kernel: K)
where
    T: Target<State = PssState, Payload = render::mlt::PathPayload>,
    K: mcmc_core::Kernel<T>,
{
    // One of 2000 independent points chosen in proportion to f (the loop's resampling with
    // offset 0.5), so the benchmarked chain starts in the stationary distribution.
    let mut payload = T::Payload::default();
    let weights: Vec<f64> = (0..2_000u64)
        .map(|i| {
            let mut x = PssState::new(PATH_STREAMS, i);
            target.evaluate(&mut x, &mut payload).exp()
        })
        .collect();
    let half = 0.5 * weights.iter().sum::<f64>();
    let mut acc = 0.0;
    let start = weights
        .iter()
        .position(|w| {
            acc += w;
            acc > half
        })
        .unwrap_or(0) as u64;
    let state = PssState::new(PATH_STREAMS, start);
    let rng = rand_pcg::Pcg64::seed_from_u64(3);
    let Ok(mut chain) = Chain::new(target, kernel, NoAdaptation, rng, state) else {
        return;
    };
    let mut buffer = SplatGrid::new(SIZE as usize, SIZE as usize);
    let mut group = c.benchmark_group(group);
    group.throughput(Throughput::Elements(STEPS));
    group.bench_function(name, |b| {
        b.iter(|| {
            let mut obs = SplatObserver::new(&mut buffer);
            for _ in 0..STEPS {
                let _ = chain.step(&mut obs);
            }
        })
    });
    group.finish();
}

fn integrators(c: &mut Criterion) {
    let scene = scene();
    let params = BdptParams::default();

    let mut group = c.benchmark_group("bdpt_cornell_glass");
    group.throughput(Throughput::Elements(u64::from(SIZE * SIZE)));
    let mut pass = 0u64;
    let mut scratch = BdptScratch::default();
    group.bench_function("samples_1_thread", |b| {
        let mut sampler = IndependentSampler::new(1);
        b.iter(|| {
            pass += 1;
            let mut sum = 0.0f32;
            for y in 0..SIZE {
                for x in 0..SIZE {
                    sampler.start_pixel_sample(u64::from(y * SIZE + x), pass);
                    let p = Vec2::new(x as f32, y as f32) + sampler.next_2d();
                    bdpt::sample(&scene, &mut sampler, p, &params, true, &mut scratch, |sp| {
                        sum += sp.l.x
                    });
                }
            }
            black_box(sum)
        })
    });
    group.finish();

    bench_chain(
        c,
        "pssmlt_1_thread",
        &PssmltTarget::new(&scene, params, SIZE, SIZE),
        kernel(),
    );
    // MMLT: the chain of depth 2 (most of the image's light in this scene is 1-2 bounces).
    let mmlt = MmltTarget::all_depths(&scene, params, SIZE, SIZE);
    bench_chain(c, "mmlt_depth2_1_thread", &mmlt[2], kernel());
    // Langevin MLT on the same depth: plain and hybrid MALA (dual-number gradients), and plain
    // MALA with finite-difference gradients.
    let config = MalaConfig::default();
    let small = SmallMutation::Kelemen(KelemenParams::kelemen2002());
    let diff = DifferentiableMmlt::new(mmlt[2], config.fd_step);
    for variant in [MalaVariant::Plain, MalaVariant::Hybrid] {
        let config = MalaConfig { variant, ..config };
        bench_chain(
            c,
            &format!("{}_depth2_1_thread", variant.name()),
            &diff,
            mala::mala_kernel(&config, 2, small, 0.3),
        );
    }
    let config = MalaConfig {
        variant: MalaVariant::Plain,
        ..config
    };
    bench_chain(
        c,
        "mala_fd_depth2_1_thread",
        &diff.with_method(GradientMethod::FiniteDifference),
        mala::mala_kernel(&config, 2, small, 0.3),
    );
}

/// The cost of one value + gradient of the MMLT targets of depth 1-3 against one value, at a
/// state with light: dual numbers (one f32 evaluation plus one replay in `Dual<N>`) and finite
/// differences (`2 d + 1` evaluations for `d` moved coordinates).
fn gradient(c: &mut Criterion) {
    let scene = scene();
    let params = BdptParams::default();
    for depth in [1u32, 2, 3] {
        let target = DifferentiableMmlt::new(
            MmltTarget::all_depths(&scene, params, SIZE, SIZE)[depth as usize],
            1e-4,
        );
        let mut payload = render::mlt::PathPayload::default();
        let Some(key) = (0..10_000u64).find(|&k| {
            let mut x = PssState::new(PATH_STREAMS, k);
            target.evaluate(&mut x, &mut payload).is_finite()
        }) else {
            continue;
        };
        let mut x = PssState::new(PATH_STREAMS, key);
        target.evaluate(&mut x, &mut payload);
        let dims: usize = x.read_counts().iter().sum();
        let moved = pss::langevin::moved_count(&x);
        let mut group = c.benchmark_group(format!("mmlt_depth{depth}_{dims}_dims_{moved}_moved"));
        group.bench_function("value", |b| {
            b.iter(|| black_box(target.evaluate(&mut x, &mut payload)))
        });
        let mut grad = Vec::new();
        group.bench_function("value_and_gradient_dual", |b| {
            b.iter(|| black_box(target.evaluate_with_grad(&mut x, &mut payload, &mut grad)))
        });
        let constant_mis = target.with_method(GradientMethod::DualConstantMis);
        group.bench_function("value_and_gradient_dual_constant_mis", |b| {
            b.iter(|| black_box(constant_mis.evaluate_with_grad(&mut x, &mut payload, &mut grad)))
        });
        // The replay alone in f64 (no derivatives): what the dual pass costs without lanes.
        let counts = x.read_counts();
        let lanes = [0, counts[0], counts[0] + counts[1]];
        let (scene_ref, size) = (&scene, Vec2::splat(SIZE as f32));
        group.bench_function("replay_f64", |b| {
            b.iter(|| {
                black_box(evaluate_strategy::<f64>(
                    scene_ref,
                    depth,
                    size,
                    params.heuristic,
                    x.raw_values(),
                    PATH_STREAMS,
                    lanes,
                    |v, _| v,
                ))
            })
        });
        // The replay alone in dual numbers with the lanes the default gradient uses (the
        // smallest of 8 / 12 / 16 that holds the moved coordinates), f64 and f32 lanes: the
        // breakdown of `value_and_gradient_dual` (f32 lanes) against its f64-lane predecessor.
        let diff = DiffScene::new(&scene).expect("supported scene");
        let mask = x.discrete_mask();
        let replay = DualReplay {
            diff: &diff,
            depth,
            size,
            heuristic: params.heuristic,
            values: x.raw_values(),
            discrete: [mask[0], mask[1], mask[2]],
        };
        match moved {
            0..=8 => replay.bench::<8>(&mut group),
            9..=10 => replay.bench::<10>(&mut group),
            11..=12 => replay.bench::<12>(&mut group),
            _ => replay.bench::<16>(&mut group),
        }
        let fd = target.with_method(GradientMethod::FiniteDifference);
        group.bench_function("value_and_gradient_fd", |b| {
            b.iter(|| black_box(fd.evaluate_with_grad(&mut x, &mut payload, &mut grad)))
        });
        group.finish();
    }
}

/// One path's replay in dual numbers (`DiffScene::evaluate_continuous`), the continuous numbers
/// of every stream starting at lane 0 (the streams' lanes overlap: the arithmetic per operation
/// depends on `N` only, so this times the gradient's replay, not its layout).
struct DualReplay<'a> {
    diff: &'a DiffScene<'a>,
    depth: u32,
    size: Vec2,
    heuristic: render::bdpt::MisHeuristic,
    values: &'a [f64],
    discrete: [u64; 3],
}

impl DualReplay<'_> {
    fn run<const N: usize, L: Lane>(&self) -> Evaluation<Dual<N, L>> {
        self.diff.evaluate_continuous::<Dual<N, L>>(
            self.depth,
            self.size,
            self.heuristic,
            self.values,
            PATH_STREAMS,
            [0; 3],
            self.discrete,
            Dual::variable,
        )
    }

    fn bench<const N: usize>(
        &self,
        group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    ) {
        group.bench_function(format!("replay_dual{N}_f64_lanes"), |b| {
            b.iter(|| black_box(self.run::<N, f64>()))
        });
        group.bench_function(format!("replay_dual{N}_f32_lanes"), |b| {
            b.iter(|| black_box(self.run::<N, f32>()))
        });
    }
}

/// A PSS target that reads 20 numbers and returns a smooth density: MCMC bookkeeping only.
struct Cheap;

impl Target for Cheap {
    type State = PssState;
    type Payload = ();
    fn evaluate(&self, x: &mut PssState, _: &mut ()) -> f64 {
        x.begin();
        let mut s = 0.0;
        for _ in 0..20 {
            s += x.next_sample();
        }
        -(s - 10.0).powi(2)
    }
}

fn bookkeeping(c: &mut Criterion) {
    let rng = rand_pcg::Pcg64::seed_from_u64(5);
    let mut chain =
        Chain::new(&Cheap, kernel(), NoAdaptation, rng, PssState::new(1, 9)).expect("start");
    let mut group = c.benchmark_group("mcmc_bookkeeping");
    group.throughput(Throughput::Elements(STEPS));
    group.bench_function("mh_pss_20_dims", |b| {
        b.iter(|| {
            for _ in 0..STEPS {
                let _ = chain.step(&mut ());
            }
        })
    });
    group.finish();
}

/// Delayed rejection's step cost at max depth 5: DR orbital (lazy pairwise stages,
/// `render::mlt::dr::lazy_orbital_kernel`) against one-stage Kelemen on the same target, on
/// PSSMLT and on the MMLT chains of depth 2 and 4, per scene (64x64, one thread, large steps
/// 0.3). The ratio of their mutations per second is the step cost.
fn dr_step_cost(c: &mut Criterion) {
    for name in ["cornell-glass", "glossy-highlight", "caustic-pool"] {
        let mut scene = scene_named(name);
        scene.set_resolution(SIZE, SIZE);
        let params = BdptParams::default();
        let group = format!("dr_step_cost_{}", name.replace('-', "_"));
        let pssmlt = PssmltTarget::new(&scene, params, SIZE, SIZE);
        bench_chain_in(c, &group, "pssmlt_kelemen", &pssmlt, kernel());
        let dr = render::mlt::dr::lazy_orbital_kernel(DrBase::Pssmlt, 0.3, 0, false);
        bench_chain_in(c, &group, "pssmlt_dr_orbital", &pssmlt, dr);
        let mmlt = MmltTarget::all_depths(&scene, params, SIZE, SIZE);
        for depth in [2u32, 4] {
            let target = &mmlt[depth as usize];
            bench_chain_in(c, &group, &format!("mmlt{depth}_kelemen"), target, kernel());
            let dr = render::mlt::dr::lazy_orbital_kernel(DrBase::Mmlt, 0.3, depth, false);
            bench_chain_in(c, &group, &format!("mmlt{depth}_dr_orbital"), target, dr);
        }
    }
}

criterion_group!(benches, integrators, gradient, bookkeeping);
criterion_group! {
    name = dr;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3)).warm_up_time(std::time::Duration::from_secs(1));
    targets = dr_step_cost
}
criterion_main!(benches, dr);
