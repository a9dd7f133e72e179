//! Kelemen et al. 2002's large-step MIS estimator (`render_loop::LargeStepMis`): the
//! splat-weight check from exact starts with two targets and three large-step
//! probabilities, over MH and over two-stage delayed rejection (Tierney-Mira, with and
//! without a second stage after large steps), two negative controls for each (the large
//! step's term dropped from the denominators; weights from a stale `p`), and the render loop with the option on: the
//! exact image of two targets with different `b_d`, bit-identical for 1 and 3 threads, no
//! allocation per mutation.
//!
//! Run with `cargo test -p mcmc-core --release --test large_step_mis -- --nocapture` to see
//! every statistic.
//!
//! # Statistics
//! As `tests/splat_weights.rs`: [`STARTS`] exact starts, one step each, the harness's
//! chi-square statistic of the mean splat-weighted histogram against the bin probabilities. The
//! combined estimator's weights do not sum to 1 per step (`(1 - a) m(x) + (a + 1) m(y)` on a
//! large step), only in expectation over `x ~ pi`, which is what the check tests. The
//! [`SPLAT_TESTS`] checks that must pass run at the Sidak level for an overall 0.01; a broken
//! weighting counts as caught below [`OVERWHELMING`] = 1e-6.

use std::sync::atomic::AtomicBool;

use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::render_loop::{
    IndependentStates, LargeStepMis, LoopBudget, LoopSettings, NormalizationMode, RenderLoop,
    Splat, SplatGrid, SplatObserver,
};
use mcmc_core::testing::{
    toy_splat_weight_test, CountingAllocator, LargeStepWalk, MisWithStaleProbability,
    MisWithoutLargeStepTerm, SplatParams, SplatWeightReport,
};
use mcmc_core::toy::{PiecewiseConstant, ToyTarget, UniformMixture};
use mcmc_core::{
    Chain, DelayedRejection, GaussianRandomWalk, Kernel, Mh, NoAdaptation, NoProgress, Target,
};
use rand::SeedableRng;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Splat-weight checks in this file that must pass (Sidak correction). Keep in sync.
const SPLAT_TESTS: usize = 7;

/// Independent exact starts per check.
const STARTS: usize = 20_000;

/// p-value below which a broken weighting counts as caught.
const OVERWHELMING: f64 = 1e-6;

fn check<T: ToyTarget, K: Kernel<T> + Clone>(
    what: &str,
    target: &T,
    kernel: &K,
    seed: u64,
) -> SplatWeightReport {
    let report = toy_splat_weight_test(target, kernel, &SplatParams::new(STARTS, seed));
    eprintln!("{what}: {report}");
    report
}

/// Small steps of 0.05, large steps uniform on the target's bounding box.
fn walk<T: ToyTarget>(target: &T, p_large: f64) -> LargeStepWalk {
    let (lo, hi) = target.bounding_box();
    LargeStepWalk::new(0.05, lo, hi, p_large).unwrap()
}

/// The combined estimator on a normalised toy target (`b = 1`).
fn mis<T: ToyTarget>(target: &T, p_large: f64) -> LargeStepMis<Mh<LargeStepWalk>> {
    let w = walk(target, p_large);
    let q = w.large_step_density();
    LargeStepMis::new(Mh::new(w), 1.0, q)
}

/// Holes and a plateau: the small step rarely crosses a hole, the large step lands in holes
/// (zero density, no splat) a fifth of the time.
#[test]
fn combined_estimator_is_unbiased_with_holes() {
    let target = PiecewiseConstant::with_holes();
    for (p, seed) in [(0.3, 1), (1.0, 2)] {
        let what = format!("holes / large-step MIS, p = {p}");
        let report = check(&what, &target, &mis(&target, p), seed);
        assert_eq!(report.impossible_weight, 0.0);
        report.assert_passes(&what, SPLAT_TESTS);
    }
}

/// The DR paper's spike-and-plateau mixture on `[-0.1, 1]` (large-step density `1 / 1.1`):
/// weight moves between the current state, the candidate and the independent sample very
/// unevenly across the two modes.
#[test]
fn combined_estimator_is_unbiased_on_the_uniform_mixture() {
    let target = UniformMixture::rioux_lavoie2020();
    for (p, seed) in [(0.1, 3), (0.5, 4)] {
        let what = format!("uniform mixture / large-step MIS, p = {p}");
        let report = check(&what, &target, &mis(&target, p), seed);
        report.assert_passes(&what, SPLAT_TESTS);
    }
}

/// Negative control: the Metropolis weights without the large step's term in the
/// denominators, plus the independent samples, count the large steps twice.
#[test]
fn dropping_the_large_step_term_fails() {
    let target = UniformMixture::rioux_lavoie2020();
    let bad = MisWithoutLargeStepTerm(Mh::new(walk(&target, 0.3)));
    let report = check("uniform mixture / MIS without p q", &target, &bad, 5);
    assert!(
        (report.mean_total_weight - 1.3).abs() < 0.05,
        "expected about 1 + p: {report}"
    );
    assert!(report.p_value < OVERWHELMING, "{report}");
}

/// Negative control: weights from another `p` than the one the step was drawn with (the
/// kernel draws with 0.1, the weights use 0.6).
#[test]
fn weights_from_a_stale_large_step_probability_fail() {
    let target = UniformMixture::rioux_lavoie2020();
    let w = walk(&target, 0.1);
    let bad = MisWithStaleProbability {
        b_q: w.large_step_density(),
        kernel: Mh::new(w),
        p_weights: 0.6,
    };
    let report = check("uniform mixture / MIS with a stale p", &target, &bad, 6);
    assert!(report.p_value < OVERWHELMING, "{report}");
}

/// Tierney-Mira delayed rejection over [`walk`] (bold first stage with large steps), a timid
/// Gaussian second stage from `x`; after small steps only (the DR paper's setting) or after
/// large steps too.
fn delayed_rejection<T: ToyTarget>(
    target: &T,
    p_large: f64,
    after_large_steps: bool,
) -> DelayedRejection<LargeStepWalk, IndependentSecondStage<GaussianRandomWalk>> {
    let dr = DelayedRejection::tierney_mira(
        walk(target, p_large),
        IndependentSecondStage(GaussianRandomWalk::new(0.01).unwrap()),
    )
    .with_symmetric_second_stage();
    if after_large_steps {
        dr
    } else {
        dr.second_stage_after_small_steps()
    }
}

/// Two-stage kernels keep the observer contract, so the same weights are unbiased for them:
/// each splat (`y`, `z`, `x`) times `m`, plus the large-step candidate's extra splat.
#[test]
fn combined_estimator_is_unbiased_for_delayed_rejection() {
    let mixture = UniformMixture::rioux_lavoie2020();
    let holes = PiecewiseConstant::with_holes();
    for (after_large, p, seed) in [(false, 0.3, 7), (true, 0.5, 8)] {
        let what = format!("uniform mixture / DR + MIS, p = {p}, after large {after_large}");
        let w = walk(&mixture, p);
        let kernel = LargeStepMis::new(
            delayed_rejection(&mixture, p, after_large),
            1.0,
            w.large_step_density(),
        );
        let report = check(&what, &mixture, &kernel, seed);
        report.assert_passes(&what, SPLAT_TESTS);
    }
    let w = walk(&holes, 0.3);
    let kernel = LargeStepMis::new(
        delayed_rejection(&holes, 0.3, false),
        1.0,
        w.large_step_density(),
    );
    let what = "holes / DR + MIS, p = 0.3";
    check(what, &holes, &kernel, 9).assert_passes(what, SPLAT_TESTS);
}

/// Negative controls over delayed rejection: the large step's term dropped, and a stale `p`.
#[test]
fn broken_weights_fail_for_delayed_rejection() {
    let target = UniformMixture::rioux_lavoie2020();
    let bad = MisWithoutLargeStepTerm(delayed_rejection(&target, 0.3, false));
    let report = check("uniform mixture / DR + MIS without p q", &target, &bad, 10);
    assert!(report.p_value < OVERWHELMING, "{report}");
    let stale = MisWithStaleProbability {
        b_q: walk(&target, 0.1).large_step_density(),
        kernel: delayed_rejection(&target, 0.1, false),
        p_weights: 0.6,
    };
    let report = check(
        "uniform mixture / DR + MIS with a stale p",
        &target,
        &stale,
        11,
    );
    assert!(report.p_value < OVERWHELMING, "{report}");
}

/// `f(u) = 1 + slope u0` on the unit square, splatted at `(4 u0, 0.5)` on a 4 x 1 image.
#[derive(Clone, Copy)]
struct Ramp(f64);

impl Target for Ramp {
    type State = Vec<f64>;
    type Payload = Option<Splat>;
    fn evaluate(&self, u: &mut Vec<f64>, out: &mut Option<Splat>) -> f64 {
        if !u.iter().all(|v| (0.0..1.0).contains(v)) {
            *out = None;
            return f64::NEG_INFINITY;
        }
        let f = 1.0 + self.0 * u[0];
        *out = Some(Splat {
            raster: [4.0 * u[0] as f32, 0.5],
            rgb: [f as f32; 3],
        });
        f.ln()
    }
}

/// Independent uniform points of the unit square from a key.
struct Uniform;

impl IndependentStates<Vec<f64>> for Uniform {
    fn empty(&self) -> Vec<f64> {
        vec![0.0; 2]
    }
    fn independent(&self, key: u64, u: &mut Vec<f64>) {
        let h = |k: u64| (mcmc_core::seed::mix64(k) >> 11) as f64 / (1u64 << 53) as f64;
        u.clear();
        u.extend([h(key), h(key ^ 0x55)]);
    }
}

/// Mutations of a loop run.
const MUTATIONS: u64 = 2_000_000;

fn run_loop(
    targets: &[Ramp],
    mis_on: bool,
    threads: usize,
    seed: u64,
) -> (SplatGrid, f64, Vec<f64>) {
    let settings = LoopSettings {
        chains: 200,
        bootstrap_samples: 20_000,
        budget: LoopBudget::Mutations(MUTATIONS),
        round_mutations: 500,
        seed,
        large_step_mis: mis_on,
        // The bootstrap's `b` alone, so that the per-target `b_d` sum to it exactly.
        normalization: NormalizationMode::Bootstrap,
        ..LoopSettings::default()
    };
    let out = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| {
            RenderLoop {
                targets,
                states: &Uniform,
                kernel: |slot| {
                    let w = LargeStepWalk::new(0.1, vec![0.0; 2], vec![1.0; 2], 0.3).unwrap();
                    LargeStepMis::for_slot(Mh::new(w), slot, 1.0)
                },
                controller: |_| NoAdaptation,
                sink: || SplatGrid::new(4, 1),
            }
            .run(&settings, &NoProgress, &AtomicBool::new(false))
            .unwrap()
        });
    (out.sink, out.splat_scale, out.target_b)
}

/// Pixel `x` of the image (the sink times `b / N` times the pixel count).
fn pixel(sink: &SplatGrid, scale: f64, x: usize) -> f64 {
    sink.get(x, 0)[0] * scale * 4.0
}

/// One target: with the option on, the loop's image matches the exact one (pixel `x`:
/// `1 + (2x + 1) / 8`), is bit-identical for 1 and 3 threads, and differs from the plain
/// estimator's.
#[test]
fn render_loop_with_the_option_is_exact_and_deterministic() {
    let targets = [Ramp(1.0)];
    let (a, scale, _) = run_loop(&targets, true, 1, 7);
    for x in 0..4 {
        let exact = 1.0 + (2.0 * x as f64 + 1.0) / 8.0;
        let got = pixel(&a, scale, x);
        eprintln!("pixel {x}: {got:.4} (exact {exact:.4})");
        assert!(
            (got - exact).abs() < 0.02 * exact,
            "pixel {x}: {got} vs {exact}"
        );
    }
    let (b, _, _) = run_loop(&targets, true, 3, 7);
    assert_eq!(a, b, "1 vs 3 threads");
    let (plain, _, _) = run_loop(&targets, false, 1, 7);
    assert_ne!(a, plain, "the option changes the weights");
}

/// Two targets with different integrals (1.5 and 0.75), as MMLT's depths: each chain
/// weights with its own target's `b_d`, and the per-target `b_d` sum to `b`. The chains'
/// allocation to targets is random (systematic resampling over interleaved targets: binomial-like,
/// e.g. 29 and 11 of 40 chains instead of 26.7 and 13.3), which both estimators share, so
/// the image is compared with the plain estimator's on the same chains (the MIS wrapper
/// draws no random numbers: the chains' paths are identical, only the weights differ).
#[test]
fn render_loop_weights_each_target_with_its_own_b() {
    let targets = [Ramp(1.0), Ramp(-0.5)];
    let (a, scale, target_b) = run_loop(&targets, true, 1, 7);
    let (plain, plain_scale, _) = run_loop(&targets, false, 1, 7);
    assert!((target_b[0] - 1.5).abs() < 0.02 && (target_b[1] - 0.75).abs() < 0.02);
    assert!((target_b.iter().sum::<f64>() / (scale * MUTATIONS as f64) - 1.0).abs() < 1e-12);
    for x in 0..4 {
        let (got, without) = (pixel(&a, scale, x), pixel(&plain, plain_scale, x));
        eprintln!("pixel {x}: {got:.4} (plain estimator on the same chains {without:.4})");
        assert!(
            (got - without).abs() < 0.01 * without,
            "pixel {x}: {got} vs {without}"
        );
    }
}

/// A step of the wrapped kernel allocates nothing once the chain's buffers exist (counted
/// on this thread only: other tests run in parallel).
#[test]
fn a_step_allocates_nothing() {
    let target = Ramp(1.0);
    let w = LargeStepWalk::new(0.1, vec![0.0; 2], vec![1.0; 2], 0.5).unwrap();
    let kernel = LargeStepMis::new(Mh::new(w), 1.5, 1.0);
    let rng = rand_pcg::Pcg64::seed_from_u64(3);
    let mut chain = Chain::new(&target, kernel, NoAdaptation, rng, vec![0.5, 0.5]).unwrap();
    let mut grid = SplatGrid::new(4, 1);
    let mut observer = SplatObserver::new(&mut grid);
    chain.run(100, &mut observer).unwrap();
    let before = CountingAllocator::allocations();
    chain.run(10_000, &mut observer).unwrap();
    assert_eq!(CountingAllocator::allocations(), before);
}
