//! The render loop's normalisation `b` pooled from the bootstrap and every large-step
//! candidate (`render_loop::Normalization`): its standard error falls as the chains run
//! (negative control: large steps not counted, no fall); it is unbiased on toy targets of
//! known integral, one target and two targets with per-target chains (t-test over
//! replicates, and the reported standard error against the replicates' spread; negative
//! control: a wrong large-step weight is caught); bit-identical for 1 and 2 threads and for
//! the sum of shards; a given `b` is used as is.
//!
//! Run with `cargo test -p mcmc-core --release --test normalization -- --nocapture` to see
//! every statistic.
//!
//! # Statistics
//! [`REPLICATES`] independent runs (seeds) give `b'`; `t = (mean - b) / (sd / sqrt(R))` is
//! about standard normal for an unbiased estimator, so `|t| < 4` fails a correct one with
//! probability 6e-5. The wrong weight (large steps counted twice over, `f / q` with `q`
//! halved) moves the mean by about `(1 - a) b` with `a` the bootstrap's share of the samples,
//! dozens of standard errors.

use std::sync::atomic::AtomicBool;

use mcmc_core::proposal::Proposed;
use mcmc_core::render_loop::{
    ChainAllocation, ExactSplatGrid, LoopBudget, LoopOutput, LoopSettings, NormalizationMode,
    RenderLoop, Shard, SplatGrid,
};
use mcmc_core::testing::LargeStepWalk;
use mcmc_core::{Mh, NoAdaptation, NoProgress, Proposal};
use rand::Rng;

mod support;

use support::{Ramp, Uniform, RAMP};

/// The second toy target: `2 (1 + u0)` on `u0 >= 0.5`, integral 1.75.
const HALF: Ramp = Ramp {
    cut: 0.5,
    gain: 2.0,
    pixels: 4.0,
};

/// Replicates of the unbiasedness tests.
const REPLICATES: u64 = 200;

/// How a test kernel reports its large step to the loop.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Report {
    /// As it is (`q = 1` on the unit square).
    Honest,
    /// Not at all (negative control for the fall of the standard error).
    Hidden,
    /// With half its density: each large step counts as `2 f` (negative control).
    WrongWeight,
}

/// [`LargeStepWalk`] with its large step reported as [`Report`] says.
#[derive(Clone, Debug)]
struct Reported(LargeStepWalk, Report);

impl Proposal<Vec<f64>> for Reported {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        self.0.propose(x, y, rng)
    }
    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        self.0.log_q(from, to)
    }
    fn is_symmetric(&self) -> bool {
        self.0.is_symmetric()
    }
    fn num_components(&self) -> usize {
        self.0.num_components()
    }
    fn log_q_component(&self, j: usize, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        self.0.log_q_component(j, from, to)
    }
    fn log_hastings(&self, j: usize, x: &Vec<f64>, y: &Vec<f64>) -> f64 {
        self.0.log_hastings(j, x, y)
    }
    fn independent_density(&self, component: usize) -> Option<f64> {
        let q = self.0.independent_density(component);
        match self.1 {
            Report::Honest => q,
            Report::Hidden => None,
            Report::WrongWeight => q.map(|q| q / 2.0),
        }
    }
}

struct Run<'a> {
    targets: &'a [Ramp],
    bootstrap: u64,
    mutations: u64,
    seed: u64,
    report: Report,
    allocation: ChainAllocation,
    threads: usize,
    shard: Shard,
    mode: NormalizationMode,
}

impl Run<'_> {
    fn new(targets: &[Ramp], bootstrap: u64, mutations: u64, seed: u64) -> Run<'_> {
        Run {
            targets,
            bootstrap,
            mutations,
            seed,
            report: Report::Honest,
            allocation: ChainAllocation::Joint,
            threads: 1,
            shard: Shard::WHOLE,
            mode: NormalizationMode::Pooled,
        }
    }

    fn go<'g>(&self, grid: &'g ExactSplatGrid) -> LoopOutput<&'g ExactSplatGrid, ()> {
        let settings = LoopSettings {
            chains: 16,
            bootstrap_samples: self.bootstrap,
            budget: LoopBudget::Mutations(self.mutations),
            round_mutations: 200,
            jobs: 8,
            seed: self.seed,
            chain_allocation: self.allocation,
            shard: self.shard,
            normalization: self.mode,
            ..LoopSettings::default()
        };
        let report = self.report;
        rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads)
            .build()
            .unwrap()
            .install(|| {
                RenderLoop {
                    targets: self.targets,
                    states: &Uniform,
                    kernel: |_| {
                        let w = LargeStepWalk::new(0.1, vec![0.0; 2], vec![1.0; 2], 0.3).unwrap();
                        Mh::new(Reported(w, report))
                    },
                    controller: |_| NoAdaptation,
                    sink: || grid,
                }
                .run(&settings, &NoProgress, &AtomicBool::new(false))
                .unwrap()
            })
    }

    fn b(&self) -> (f64, f64) {
        let grid = ExactSplatGrid::new(4, 1);
        let out = self.go(&grid);
        (out.b, out.b_standard_error)
    }
}

/// Bootstrap's standard error, then after a short and a long run.
fn standard_errors(report: Report) -> [f64; 3] {
    let grid = ExactSplatGrid::new(4, 1);
    let mut run = Run::new(&[RAMP], 1000, 10_000, 3);
    run.report = report;
    let short = run.go(&grid);
    run.mutations = 300_000;
    let long_grid = ExactSplatGrid::new(4, 1);
    let long = run.go(&long_grid);
    eprintln!(
        "{report:?}: bootstrap {:.5}, 10k mutations {:.5} ({} large steps), 300k mutations {:.5} ({} large steps)",
        short.bootstrap_standard_error,
        short.b_standard_error,
        short.large_step_samples,
        long.b_standard_error,
        long.large_step_samples
    );
    [
        short.bootstrap_standard_error,
        short.b_standard_error,
        long.b_standard_error,
    ]
}

/// The fall the pooled estimator must show: 1000 bootstrap samples and about 90 000 large
/// steps give `sqrt(1000 / 91 000)`, about a tenth; a third is asked for.
fn falls(se: [f64; 3]) -> bool {
    se[2] < se[1] && se[2] < se[0] / 3.0
}

#[test]
fn standard_error_falls_as_the_chains_run() {
    assert!(falls(standard_errors(Report::Honest)));
}

/// Negative control: a kernel that does not report its large steps keeps the bootstrap's
/// standard error, however long the chains run.
#[test]
fn without_large_steps_counted_it_does_not_fall() {
    let se = standard_errors(Report::Hidden);
    assert_eq!(se[0], se[2]);
    assert!(!falls(se));
}

/// `t` statistic of the replicates' `b'` against `exact`, and the ratio of their standard
/// deviation to the mean reported standard error.
fn replicate(
    targets: &[Ramp],
    allocation: ChainAllocation,
    report: Report,
    exact: f64,
) -> (f64, f64) {
    let (mut sum, mut sum_sq, mut se_sum) = (0.0, 0.0, 0.0);
    for seed in 0..REPLICATES {
        let mut run = Run::new(targets, 100, 20_000, 1000 + seed);
        run.allocation = allocation;
        run.report = report;
        let (b, se) = run.b();
        sum += b;
        sum_sq += b * b;
        se_sum += se;
    }
    let r = REPLICATES as f64;
    let mean = sum / r;
    let sd = ((sum_sq / r - mean * mean) * r / (r - 1.0)).sqrt();
    let t = (mean - exact) / (sd / r.sqrt());
    let ratio = sd / (se_sum / r);
    eprintln!("{report:?} {allocation:?}: mean {mean:.5} (exact {exact}), sd {sd:.5}, t = {t:.2}, sd / reported se = {ratio:.3}");
    (t, ratio)
}

#[test]
fn pooled_b_is_unbiased_with_a_right_standard_error() {
    let (t, ratio) = replicate(&[RAMP], ChainAllocation::Joint, Report::Honest, 1.5);
    assert!(t.abs() < 4.0, "t = {t}");
    // sd of 200 replicates is known to about 5 %: 0.8..1.25 is five of those.
    assert!((0.8..1.25).contains(&ratio), "sd / se = {ratio}");
    let (t, ratio) = replicate(
        &[RAMP, HALF],
        ChainAllocation::PerTarget,
        Report::Honest,
        3.25,
    );
    assert!(t.abs() < 4.0, "two targets: t = {t}");
    assert!(
        (0.8..1.25).contains(&ratio),
        "two targets: sd / se = {ratio}"
    );
}

/// Negative control: large steps counted with the wrong weight bias `b'`.
#[test]
fn a_wrong_large_step_weight_is_caught() {
    let (t, _) = replicate(&[RAMP], ChainAllocation::Joint, Report::WrongWeight, 1.5);
    assert!(t.abs() > 4.0, "t = {t}");
}

/// The image's brightness is `b'`: the sink times `b' / N` (the splat scale) sums to `b'`.
#[test]
fn the_image_is_scaled_with_the_pooled_b() {
    let run = Run::new(&[RAMP], 1000, 100_000, 5);
    let grid = SplatGrid::new(4, 1);
    let settings = LoopSettings {
        bootstrap_samples: 1000,
        budget: LoopBudget::Mutations(100_000),
        seed: 5,
        ..LoopSettings::default()
    };
    let out = RenderLoop {
        targets: run.targets,
        states: &Uniform,
        kernel: |_| Mh::new(LargeStepWalk::new(0.1, vec![0.0; 2], vec![1.0; 2], 0.3).unwrap()),
        controller: |_| NoAdaptation,
        sink: || grid.clone(),
    }
    .run(&settings, &NoProgress, &AtomicBool::new(false))
    .unwrap();
    assert!(out.large_step_samples > 20_000);
    assert_ne!(out.b, out.bootstrap_b);
    let brightness: f64 = (0..4).map(|x| out.sink.get(x, 0)[0]).sum::<f64>() * out.splat_scale;
    assert!(
        (brightness / out.b - 1.0).abs() < 1e-9,
        "{brightness} vs {}",
        out.b
    );
}

/// 1 and 2 threads give the same bits; so do two shards' normalisations added.
#[test]
fn deterministic_across_threads_and_shards() {
    let mut run = Run::new(&[RAMP, HALF], 1000, 50_000, 9);
    run.allocation = ChainAllocation::PerTarget;
    let whole_grid = ExactSplatGrid::new(4, 1);
    let whole = run.go(&whole_grid);
    run.threads = 2;
    let two_grid = ExactSplatGrid::new(4, 1);
    let two = run.go(&two_grid);
    assert_eq!(whole.b.to_bits(), two.b.to_bits());
    assert_eq!(whole.splat_scale.to_bits(), two.splat_scale.to_bits());
    let mut parts = Vec::new();
    for index in 0..2 {
        run.shard = Shard { index, count: 2 };
        parts.push(run.go(&ExactSplatGrid::new(4, 1)).normalization);
    }
    let mut sum = parts[0].clone();
    sum.add(&parts[1]).unwrap();
    assert_eq!(sum, whole.normalization);
    assert_eq!(sum.estimate().b.to_bits(), whole.b.to_bits());
}

/// A given `b` scales the image as it is, with no error estimate; an invalid one is refused.
#[test]
fn a_given_b_is_used() {
    let mut run = Run::new(&[RAMP], 1000, 20_000, 2);
    run.mode = NormalizationMode::Given(2.0);
    assert_eq!(run.b(), (2.0, 0.0));
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let settings = LoopSettings {
            normalization: NormalizationMode::Given(bad),
            ..LoopSettings::default()
        };
        assert!(settings.validate().is_err(), "{bad}");
    }
}
