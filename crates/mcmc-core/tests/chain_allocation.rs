//! The render loop's per-target chain allocation (`ChainAllocation::PerTarget`) and stratified
//! bootstraps (`IndependentStates::strata`): exact images of two targets with very different
//! integrals (as MMLT's depths), the negative control (the per-target allocation scaled by
//! `b / N` instead of `b_d / n_d`), bit-identical output for 1 and 3 threads, and the
//! stratified bootstrap's whole-group rule (also when a time budget stops it inside a group).
//!
//! Run with `cargo test -p mcmc-core --release --test chain_allocation -- --nocapture` to see
//! every statistic.
//!
//! # Statistics
//! Each case renders [`R`] replicates (master seeds `seed0 + r`: independent bootstraps,
//! starts and chains); a pixel's replicate values are i.i.d., so
//! `T = (mean - exact) / (s / sqrt(R))` is Student's t with `R - 1 = 15` degrees of freedom
//! when unbiased (the loop's estimate is unbiased for any run length: see
//! `ChainAllocation::PerTarget`). The 12 comparisons that must pass share a
//! family-wise 0.001 (Bonferroni: 8.3e-5 each, two-sided critical value about 5.4 for 15
//! degrees of freedom; [`CRITICAL`] = 5.6 is a little more conservative). A broken weighting counts as
//! caught when its `|T|` exceeds [`CAUGHT`].

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use mcmc_core::render_loop::{
    ChainAllocation, IndependentStates, LoopBudget, LoopOutput, LoopSettings, RenderLoop, Splat,
    SplatGrid,
};
use mcmc_core::{GaussianRandomWalk, Mh, NoAdaptation, NoProgress, Target};

/// Replicates per case.
const R: u64 = 16;
/// Two-sided critical value of Student's t, 15 degrees of freedom, at or below
/// `0.001 / 12` (12 comparisons: 4 pixels x two allocations and a given normalisation;
/// about 5.4 for 8.3e-5, rounded up).
const CRITICAL: f64 = 5.6;
/// `|T|` above which a negative control counts as caught.
const CAUGHT: f64 = 20.0;

/// `f(u) = scale (1 + u0)` on `[0, 1)`, splatted on the two pixels of its half of a 4 x 1
/// image (`offset` 0: pixels 0-1; 2: pixels 2-3) with `rgb = f`.
#[derive(Clone, Copy)]
struct Half {
    scale: f64,
    offset: f32,
}

impl Target for Half {
    type State = Vec<f64>;
    type Payload = Option<Splat>;
    fn evaluate(&self, u: &mut Vec<f64>, out: &mut Option<Splat>) -> f64 {
        if !(0.0..1.0).contains(&u[0]) {
            *out = None;
            return f64::NEG_INFINITY;
        }
        let f = self.scale * (1.0 + u[0]);
        *out = Some(Splat {
            raster: [self.offset + 2.0 * u[0] as f32, 0.5],
            rgb: [f as f32; 3],
        });
        f.ln()
    }
}

/// Two targets whose integrals differ 50-fold (1.5 and 0.03): with 10 chains the second
/// gets one chain (its quota is 0.2).
const TARGETS: [Half; 2] = [
    Half {
        scale: 1.0,
        offset: 0.0,
    },
    Half {
        scale: 0.02,
        offset: 2.0,
    },
];

/// The exact image: pixel `x` of target `t` is `scale * integral of (1 + u)` over its half.
fn exact(x: usize) -> f64 {
    let (scale, half) = (TARGETS[x / 2].scale, x % 2);
    scale * if half == 0 { 0.625 } else { 0.875 }
}

fn h(k: u64) -> f64 {
    (mcmc_core::seed::mix64(k) >> 11) as f64 / (1u64 << 53) as f64
}

/// Independent uniform points of `[0, 1)`.
struct Uniform;

impl IndependentStates<Vec<f64>> for Uniform {
    fn empty(&self) -> Vec<f64> {
        vec![0.0]
    }
    fn independent(&self, key: u64, u: &mut Vec<f64>) {
        u[0] = h(key);
    }
}

fn run<T, S>(
    targets: &[T],
    states: &S,
    settings: &LoopSettings,
    threads: usize,
) -> LoopOutput<SplatGrid, ()>
where
    T: Target<State = Vec<f64>, Payload = Option<Splat>> + Sync,
    S: IndependentStates<Vec<f64>>,
{
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| {
            RenderLoop {
                targets,
                states,
                kernel: |_| Mh::new(GaussianRandomWalk::new(0.1).unwrap()),
                controller: |_| NoAdaptation,
                sink: || SplatGrid::new(4, 1),
            }
            .run(settings, &NoProgress, &AtomicBool::new(false))
            .unwrap()
        })
}

fn settings(seed: u64, allocation: ChainAllocation) -> LoopSettings {
    LoopSettings {
        chains: 10,
        bootstrap_samples: 2_000,
        budget: LoopBudget::Mutations(200_000),
        seed,
        chain_allocation: allocation,
        ..LoopSettings::default()
    }
}

/// Pixel `x` of an output (the sink times `b / N`: the integral over the pixel's `u` range,
/// as [`exact`]), and the same pixel
/// with the per-target chain factor undone (every splat scaled by `b / N` alone).
fn pixels(out: &LoopOutput<SplatGrid, ()>) -> ([f64; 4], [f64; 4]) {
    let chains: usize = out.target_chains.iter().sum();
    let per_chain_b = out.b / chains as f64;
    let mut with = [0.0; 4];
    let mut without = [0.0; 4];
    for x in 0..4 {
        let t = x / 2;
        with[x] = out.sink.get(x, 0)[0] * out.splat_scale;
        let factor = out.target_b[t] / out.target_chains[t] as f64 / per_chain_b;
        without[x] = with[x] / factor;
    }
    (with, without)
}

fn t_stat(values: &[f64], exact: f64) -> f64 {
    let n = values.len() as f64;
    let m = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m - exact) / (var / n).sqrt().max(1e-300)
}

/// Both allocations reproduce the exact image; the per-target one gives the small target
/// exactly one chain (largest remainders with at least one chain), and scaling its splats by
/// `b / N` instead of `b_d / n_d` (the negative control) makes that target's pixels about
/// `0.1 / 0.0196 = 5` times too bright: caught.
#[test]
fn per_target_allocation_is_unbiased_and_the_wrong_scale_is_caught() {
    for allocation in [ChainAllocation::Joint, ChainAllocation::PerTarget] {
        let mut with: Vec<[f64; 4]> = Vec::new();
        let mut without: Vec<[f64; 4]> = Vec::new();
        for r in 0..R {
            let out = run(&TARGETS, &Uniform, &settings(100 + r, allocation), 1);
            assert_eq!(out.target_chains.iter().sum::<usize>(), 10);
            if allocation == ChainAllocation::PerTarget {
                assert_eq!(out.target_chains, [9, 1], "seed {r}");
            }
            let (a, b) = pixels(&out);
            with.push(a);
            without.push(b);
        }
        for x in 0..4 {
            let values: Vec<f64> = with.iter().map(|p| p[x]).collect();
            let t = t_stat(&values, exact(x));
            eprintln!(
                "{allocation:?} pixel {x}: mean {:.5} exact {:.5} t {t:.2}",
                values.iter().sum::<f64>() / R as f64,
                exact(x)
            );
            assert!(t.abs() < CRITICAL, "{allocation:?} pixel {x}: t {t}");
        }
        if allocation == ChainAllocation::PerTarget {
            for x in 2..4 {
                let values: Vec<f64> = without.iter().map(|p| p[x]).collect();
                let t = t_stat(&values, exact(x));
                eprintln!(
                    "negative control (b / N scale) pixel {x}: mean {:.5} exact {:.5} t {t:.1}",
                    values.iter().sum::<f64>() / R as f64,
                    exact(x)
                );
                assert!(
                    t > CAUGHT,
                    "the negative control must fail: pixel {x}, t {t}"
                );
            }
        }
    }
}

/// The per-target allocation is bit-identical for 1 and 3 threads, and differs from the
/// joint one.
#[test]
fn per_target_allocation_is_deterministic() {
    let s = settings(7, ChainAllocation::PerTarget);
    let a = run(&TARGETS, &Uniform, &s, 1);
    let b = run(&TARGETS, &Uniform, &s, 3);
    assert_eq!(a.sink, b.sink);
    assert_eq!(a.target_chains, b.target_chains);
    let joint = run(&TARGETS, &Uniform, &settings(7, ChainAllocation::Joint), 1);
    assert_ne!(a.sink, joint.sink);
}

/// `f(u) = 10` on `[0, 1/n)` and 1 elsewhere (integral `(9 + n) / n`), splatted at pixel 0.
#[derive(Clone, Copy)]
struct Step(u64);

impl Step {
    fn integral(self) -> f64 {
        (9 + self.0) as f64 / self.0 as f64
    }
}

impl Target for Step {
    type State = Vec<f64>;
    type Payload = Option<Splat>;
    fn evaluate(&self, u: &mut Vec<f64>, out: &mut Option<Splat>) -> f64 {
        if !(0.0..1.0).contains(&u[0]) {
            *out = None;
            return f64::NEG_INFINITY;
        }
        let f: f64 = if u[0] * (self.0 as f64) < 1.0 {
            10.0
        } else {
            1.0
        };
        *out = Some(Splat {
            raster: [0.5, 0.5],
            rgb: [f as f32; 3],
        });
        f.ln()
    }
}

/// Strata per target of [`STEPS`].
const STRATA: [u64; 4] = [3, 5, 7, 11];
/// One step target per entry of [`STRATA`].
const STEPS: [Step; 4] = [Step(3), Step(5), Step(7), Step(11)];

/// Uniform points with `STRATA[t]` strata for target `t` (`u0` moved into the `k`-th
/// interval), or none (`strata: false`).
struct Strata {
    strata: bool,
}

impl IndependentStates<Vec<f64>> for Strata {
    fn empty(&self) -> Vec<f64> {
        vec![0.0]
    }
    fn independent(&self, key: u64, u: &mut Vec<f64>) {
        u[0] = h(key);
    }
    fn strata(&self, target: usize) -> u64 {
        if self.strata {
            STRATA[target]
        } else {
            1
        }
    }
    fn stratified(&self, key: u64, stratum: u64, strata: u64, u: &mut Vec<f64>) {
        u[0] = (stratum as f64 + h(key)) / strata as f64;
    }
}

/// With strata, every group of `n` samples averages to the exact integral whatever the
/// point: `b_d` is exactly `(9 + n) / n` for any number of samples, because a trailing
/// partial group is not counted (with 40 samples of 3 strata, counting the 40th, of
/// stratum 0, would give `(13 * 12 + 10) / 40 = 4.15` instead of 4). Also when a time
/// budget stops the bootstrap between batches (4 x 10^7 samples cannot finish in a quarter
/// of 0.2 s; a batch holds 2048 rows, not a multiple of 3, 5, 7 or 11, so some target is cut
/// inside a group unless the batch count is a multiple of 1155). Both allocations.
#[test]
fn stratified_bootstrap_counts_whole_groups_only() {
    let exact = |out: &LoopOutput<SplatGrid, ()>, what: &str| {
        for (t, step) in STEPS.iter().enumerate() {
            // Exact up to the rounding of `exp(ln f)` and of the sums.
            let (got, want) = (out.target_b[t], step.integral());
            assert!(
                (got - want).abs() < 1e-12 * want,
                "{what}: target {t}: {got} vs {want}"
            );
        }
    };
    for allocation in [ChainAllocation::Joint, ChainAllocation::PerTarget] {
        for per_target in [15, 40, 3_001] {
            let s = LoopSettings {
                chains: 4,
                bootstrap_samples: per_target,
                budget: LoopBudget::Mutations(1_000),
                chain_allocation: allocation,
                ..LoopSettings::default()
            };
            let out = run(&STEPS, &Strata { strata: true }, &s, 2);
            eprintln!(
                "{allocation:?}, {per_target} samples: b_d {:?}",
                out.target_b
            );
            exact(&out, &format!("{allocation:?}, {per_target} samples"));
        }
        let s = LoopSettings {
            chains: 4,
            bootstrap_samples: 10_000_000,
            budget: LoopBudget::Time(Duration::from_millis(200)),
            chain_allocation: allocation,
            ..LoopSettings::default()
        };
        let out = run(&STEPS, &Strata { strata: true }, &s, 2);
        let rows = out.bootstrap_samples / 4;
        eprintln!(
            "{allocation:?}, stopped after {rows} rows (mod 3, 5, 7, 11: {:?}): b_d {:?}",
            STRATA.map(|n| rows % n),
            out.target_b
        );
        assert!(rows < 10_000_000, "the bootstrap should have stopped early");
        exact(&out, &format!("{allocation:?}, stopped early"));
        assert!(out.mutations > 0);
    }
}

/// The same targets without strata: `b_d` is the plain mean, not exact (the control showing
/// that the exactness above comes from the strata).
#[test]
fn unstratified_bootstrap_is_not_exact() {
    let s = LoopSettings {
        chains: 4,
        bootstrap_samples: 3_001,
        budget: LoopBudget::Mutations(1_000),
        ..LoopSettings::default()
    };
    let out = run(&STEPS, &Strata { strata: false }, &s, 1);
    for (t, step) in STEPS.iter().enumerate() {
        assert_ne!(out.target_b[t], step.integral());
        assert!(
            (out.target_b[t] - step.integral()).abs() < 0.5,
            "{:?}",
            out.target_b
        );
    }
}

/// `run_normalized` with the exact integrals (1.5, 0.03): the image matches the exact one
/// (the bootstrap only picks starts), `b` reports the normalisation, and a normalisation of
/// the wrong length is refused.
#[test]
fn given_normalization_replaces_the_bootstrap_estimate() {
    let exact_b = [1.5, 0.03];
    let mut values: Vec<[f64; 4]> = Vec::new();
    for r in 0..R {
        let out = RenderLoop {
            targets: &TARGETS,
            states: &Uniform,
            kernel: |_| Mh::new(GaussianRandomWalk::new(0.1).unwrap()),
            controller: |_| NoAdaptation,
            sink: || SplatGrid::new(4, 1),
        }
        .run_normalized(
            &settings(300 + r, ChainAllocation::Joint),
            &exact_b,
            &NoProgress,
            &AtomicBool::new(false),
        )
        .unwrap();
        assert_eq!(out.target_b, exact_b);
        assert_eq!(out.target_chains, [9, 1]);
        values.push(pixels(&out).0);
    }
    for x in 0..4 {
        let v: Vec<f64> = values.iter().map(|p| p[x]).collect();
        let t = t_stat(&v, exact(x));
        eprintln!("normalised pixel {x}: t {t:.2}");
        assert!(t.abs() < CRITICAL, "pixel {x}: t {t}");
    }
    let refused = RenderLoop {
        targets: &TARGETS,
        states: &Uniform,
        kernel: |_| Mh::new(GaussianRandomWalk::new(0.1).unwrap()),
        controller: |_| NoAdaptation,
        sink: || SplatGrid::new(4, 1),
    }
    .run_normalized(
        &settings(1, ChainAllocation::Joint),
        &[1.0],
        &NoProgress,
        &AtomicBool::new(false),
    );
    assert!(refused.is_err());
}
