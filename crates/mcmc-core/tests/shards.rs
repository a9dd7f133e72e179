//! A render loop split into shards: with the order-independent `ExactSplatGrid` as the sink,
//! the shards' splat sums and mutation counts add up bit for bit to the whole render's, for
//! chains that are independent (a shard runs only its own jobs) and for chains coupled by a
//! shared controller (every shard runs every chain and keeps only its own jobs' splats).
//! Negative controls: a per-job f64 sink merged in job order does not add up exactly, and a
//! coupled controller run as if it were independent changes the image.

use std::sync::atomic::AtomicBool;

use mcmc_core::proposal::Scaled;
use mcmc_core::render_loop::{
    ExactSplatGrid, LoopBudget, LoopSettings, RenderLoop, Shard, SharedController, SplatGrid,
    SplatSink,
};
use mcmc_core::tunable::ScaleTunable;
use mcmc_core::{Controller, GaussianRandomWalk, Mh, NoAdaptation, NoProgress, StepInfo};

mod support;

use support::{Ramp, Uniform};

/// The ramp on an 8 x 1 image.
const RAMP8: Ramp = Ramp {
    cut: 0.0,
    gain: 1.0,
    pixels: 8.0,
};

/// A controller that couples the chains: after every round each chain's step size becomes
/// a function of the acceptances pooled over all chains.
#[derive(Clone, Copy, Default)]
struct Coupled {
    accepted: u64,
}

impl<K: ScaleTunable, S> Controller<K, S> for Coupled {
    fn after_step(&mut self, _kernel: &mut K, info: &StepInfo) {
        self.accepted += u64::from(info.accepted_stage > 0);
    }
    fn is_frozen(&self) -> bool {
        false
    }
}

impl<K: ScaleTunable> SharedController<K> for Coupled {
    type Shared = u64;
    fn contribute(&mut self, _kernel: &mut K, pooled: &mut u64) {
        *pooled += std::mem::take(&mut self.accepted);
    }
    fn receive(&mut self, kernel: &mut K, pooled: &u64) {
        kernel.set_log_scale(-1.0 - (*pooled % 7) as f64 * 0.2);
    }
}

/// Same as [`Coupled`] but declaring its chains independent: wrong, for the negative control.
#[derive(Clone, Copy, Default)]
struct CoupledButDeclaredIndependent(Coupled);

impl<K: ScaleTunable, S> Controller<K, S> for CoupledButDeclaredIndependent {
    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        Controller::<K, S>::after_step(&mut self.0, kernel, info);
    }
    fn is_frozen(&self) -> bool {
        false
    }
}

impl<K: ScaleTunable> SharedController<K> for CoupledButDeclaredIndependent {
    type Shared = u64;
    fn contribute(&mut self, kernel: &mut K, pooled: &mut u64) {
        self.0.contribute(kernel, pooled);
    }
    fn receive(&mut self, kernel: &mut K, pooled: &u64) {
        self.0.receive(kernel, pooled);
    }
    const COUPLES_CHAINS: bool = false;
}

fn settings(shard: Shard) -> LoopSettings {
    LoopSettings {
        chains: 64,
        bootstrap_samples: 4000,
        budget: LoopBudget::Mutations(200_000),
        round_mutations: 100,
        jobs: 16,
        seed: 11,
        shard,
        ..LoopSettings::default()
    }
}

/// Runs shard `shard` with controller `C` into `grid`; returns the mutations it counted.
fn run_into<C>(grid: &ExactSplatGrid, shard: Shard, controller: C) -> (u64, f64)
where
    C: Controller<Mh<Scaled<GaussianRandomWalk>>, Vec<f64>>
        + SharedController<Mh<Scaled<GaussianRandomWalk>>>
        + Copy
        + Send
        + Sync,
{
    let out = RenderLoop {
        targets: &[RAMP8],
        states: &Uniform,
        kernel: |_| Mh::new(Scaled::new(GaussianRandomWalk::new(0.2).unwrap(), -3.0)),
        controller: |_| controller,
        sink: || grid,
    }
    .run(&settings(shard), &NoProgress, &AtomicBool::new(false))
    .unwrap();
    (out.mutations, out.b)
}

fn raw(grid: &ExactSplatGrid) -> Vec<[i128; 3]> {
    (0..8).map(|i| grid.raw(i)).collect()
}

/// Whole render vs the sum of `count` shards, for controller `C`.
fn shards_add_up<C>(controller: C, count: u32) -> bool
where
    C: Controller<Mh<Scaled<GaussianRandomWalk>>, Vec<f64>>
        + SharedController<Mh<Scaled<GaussianRandomWalk>>>
        + Copy
        + Send
        + Sync,
{
    let whole = ExactSplatGrid::new(8, 1);
    let (n_whole, b_whole) = run_into(&whole, Shard::WHOLE, controller);
    let sum = ExactSplatGrid::new(8, 1);
    let mut n_sum = 0;
    for index in (0..count).rev() {
        let part = ExactSplatGrid::new(8, 1);
        let (n, b) = run_into(&part, Shard { index, count }, controller);
        assert_eq!(
            b.to_bits(),
            b_whole.to_bits(),
            "every shard draws the same bootstrap"
        );
        assert!(n < n_whole || count == 1);
        n_sum += n;
        assert!(sum.add_grid(&part));
    }
    assert_eq!(n_sum, n_whole);
    raw(&sum) == raw(&whole)
}

#[test]
fn independent_chains_shards_add_up_bit_for_bit() {
    for count in [1, 2, 3, 4, 7] {
        assert!(shards_add_up(NoAdaptation, count), "{count} shards");
    }
}

#[test]
fn coupled_chains_shards_add_up_bit_for_bit() {
    for count in [2, 4] {
        assert!(shards_add_up(Coupled::default(), count), "{count} shards");
    }
}

/// Negative control: a coupled controller that claims independence lets each shard run
/// only its own chains, so the pooled statistics (and the image) differ from the whole
/// render's.
#[test]
fn coupled_chains_run_as_independent_do_not_add_up() {
    assert!(!shards_add_up(CoupledButDeclaredIndependent::default(), 4));
}

/// Negative control for the sink: f64 per-job grids summed per shard, then the shards'
/// sums added, differ in the last bits from the whole render's job-order sum.
#[test]
fn f64_job_grids_do_not_add_up_exactly() {
    let run = |shard: Shard| {
        RenderLoop {
            targets: &[RAMP8],
            states: &Uniform,
            kernel: |_| Mh::new(GaussianRandomWalk::new(0.2).unwrap()),
            controller: |_| NoAdaptation,
            sink: || SplatGrid::new(8, 1),
        }
        .run(&settings(shard), &NoProgress, &AtomicBool::new(false))
        .unwrap()
        .sink
    };
    let whole = run(Shard::WHOLE);
    let mut sum = SplatGrid::new(8, 1);
    for index in (0..4).rev() {
        sum.merge(&run(Shard { index, count: 4 }));
    }
    assert_ne!(sum.pixels(), whole.pixels());
}

#[test]
fn shard_out_of_range_is_an_error() {
    let grid = ExactSplatGrid::new(8, 1);
    let result = RenderLoop {
        targets: &[RAMP8],
        states: &Uniform,
        kernel: |_| Mh::new(GaussianRandomWalk::new(0.2).unwrap()),
        controller: |_| NoAdaptation,
        sink: || &grid,
    }
    .run(
        &settings(Shard { index: 4, count: 4 }),
        &NoProgress,
        &AtomicBool::new(false),
    );
    assert!(result.is_err());
}
