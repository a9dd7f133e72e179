//! The generic render loop: bounded memory and prompt cancellation with absurd bootstrap
//! sizes, time budgets that include the bootstrap, more chains than mutations, determinism
//! across thread counts, and correct partial results.
//!
//! Two tests measure wall time because responsiveness is what they check (a cancel must take
//! effect within a second; a time budget must be kept); their bounds are several times the
//! expected values so that a loaded machine does not make them flaky.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use mcmc_core::render_loop::{
    IndependentStates, LoopBudget, LoopSettings, RenderLoop, Splat, SplatGrid,
};
use mcmc_core::{GaussianRandomWalk, Mh, NoAdaptation, NoProgress, Target};

/// Counts live heap bytes and their peak, so the test can see an unbounded allocation.
struct Counting;
static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(live, Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// `f(u) = 1 + u0` on the unit square (zero outside), splatted at `(4 u0, 0.5)` on a 4x1 image.
#[derive(Clone, Copy)]
struct Ramp;

impl Target for Ramp {
    type State = Vec<f64>;
    type Payload = Option<Splat>;
    fn evaluate(&self, u: &mut Vec<f64>, out: &mut Option<Splat>) -> f64 {
        if !u.iter().all(|v| (0.0..1.0).contains(v)) {
            *out = None;
            return f64::NEG_INFINITY;
        }
        let f = 1.0 + u[0];
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

fn run(
    targets: &[Ramp],
    settings: &LoopSettings,
    cancel: &AtomicBool,
) -> mcmc_core::render_loop::LoopOutput<SplatGrid, ()> {
    RenderLoop {
        targets,
        states: &Uniform,
        kernel: |_| Mh::new(GaussianRandomWalk::new(0.2).unwrap()),
        controller: |_| NoAdaptation,
        sink: || SplatGrid::new(4, 1),
    }
    .run(settings, &NoProgress, cancel)
    .unwrap()
}

/// 10^8 bootstrap samples for each of 1025 targets (MMLT at max depth 1024): storing one
/// weight per sample would take 820 GB. The loop must start with bounded memory and stop
/// within a second of a cancel.
#[test]
fn huge_bootstrap_is_bounded_and_cancellable() {
    let targets = vec![Ramp; 1025];
    let settings = LoopSettings {
        bootstrap_samples: 100_000_000,
        budget: LoopBudget::Mutations(1_000_000),
        ..LoopSettings::default()
    };
    let cancel = AtomicBool::new(false);
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let (out, stopped_after) = std::thread::scope(|s| {
        let handle = s.spawn(|| run(&targets, &settings, &cancel));
        std::thread::sleep(Duration::from_millis(300));
        let t = Instant::now();
        cancel.store(true, Ordering::Relaxed);
        let out = handle.join().unwrap();
        (out, t.elapsed())
    });
    let peak = PEAK.load(Ordering::Relaxed) - before;
    eprintln!(
        "cancelled after {:?}, {} bootstrap samples evaluated, peak heap {} KiB",
        stopped_after,
        out.bootstrap_samples,
        peak / 1024
    );
    assert!(out.cancelled);
    assert!(out.bootstrap_samples > 0 && out.bootstrap_samples < 1025 * 100_000_000);
    assert!(stopped_after < Duration::from_secs(1), "{stopped_after:?}");
    assert!(peak < 64 << 20, "peak heap {peak} bytes");
}

/// A time budget covers the bootstrap: with a bootstrap that would take far longer, the loop
/// stops it at its share of the time, renders, and returns on time.
#[test]
fn time_budget_includes_the_bootstrap() {
    let settings = LoopSettings {
        bootstrap_samples: 1_000_000_000_000,
        budget: LoopBudget::Time(Duration::from_millis(800)),
        ..LoopSettings::default()
    };
    let t = Instant::now();
    let out = run(&[Ramp], &settings, &AtomicBool::new(false));
    let elapsed = t.elapsed();
    eprintln!("{elapsed:?}, notes {:?}", out.notes);
    assert!(elapsed < Duration::from_millis(2500), "{elapsed:?}");
    assert!(out.notes.iter().any(|n| n.contains("bootstrap stopped")));
    assert!(out.mutations > 0 && !out.cancelled);
    assert!(
        (out.b - 1.5).abs() < 10.0 * out.b_standard_error + 1e-3,
        "b {}",
        out.b
    );
}

#[test]
fn more_chains_than_mutations_is_capped_with_a_note() {
    let settings = LoopSettings {
        chains: 1_000_000,
        bootstrap_samples: 1000,
        budget: LoopBudget::Mutations(100),
        ..LoopSettings::default()
    };
    let out = run(&[Ramp], &settings, &AtomicBool::new(false));
    assert_eq!(out.chains, 100);
    assert_eq!(out.mutations, 100);
    assert!(out.notes.iter().any(|n| n.contains("using 100 chains")));
}

#[test]
fn same_seed_same_sink_for_any_thread_count() {
    let settings = LoopSettings {
        chains: 40,
        bootstrap_samples: 20_000,
        budget: LoopBudget::Mutations(50_000),
        round_mutations: 300,
        ..LoopSettings::default()
    };
    let with = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(&[Ramp], &settings, &AtomicBool::new(false)))
    };
    let (a, b) = (with(1), with(3));
    assert_eq!(a.sink, b.sink);
    assert_eq!(a.b.to_bits(), b.b.to_bits());
    let other = run(
        &[Ramp],
        &LoopSettings {
            seed: 1,
            ..settings
        },
        &AtomicBool::new(false),
    );
    assert_ne!(a.sink, other.sink);
}

/// Cancelled half-way through the chains, the image is still normalised by the mutations
/// actually made: its mean matches the exact image mean, 1.5, within the noise of a short run.
#[test]
fn a_cancelled_run_is_a_correct_partial_estimate() {
    let settings = LoopSettings {
        chains: 16,
        bootstrap_samples: 10_000,
        budget: LoopBudget::Mutations(u64::MAX / 2),
        ..LoopSettings::default()
    };
    let cancel = AtomicBool::new(false);
    let out = std::thread::scope(|s| {
        let handle = s.spawn(|| run(&[Ramp], &settings, &cancel));
        std::thread::sleep(Duration::from_millis(200));
        cancel.store(true, Ordering::Relaxed);
        handle.join().unwrap()
    });
    assert!(out.cancelled && out.mutations > 0);
    let mean: f64 = out.sink.pixels().iter().map(|p| p[0]).sum::<f64>() * out.splat_scale;
    assert!(
        (mean - 1.5).abs() < 0.05,
        "mean {mean} after {} mutations",
        out.mutations
    );
}

#[test]
fn invalid_settings_are_named() {
    for (settings, name) in [
        (
            LoopSettings {
                chains: 0,
                ..LoopSettings::default()
            },
            "chains",
        ),
        (
            LoopSettings {
                budget: LoopBudget::Mutations(0),
                ..LoopSettings::default()
            },
            "budget",
        ),
        (
            LoopSettings {
                bootstrap_time_share: 0.0,
                ..LoopSettings::default()
            },
            "bootstrap_time_share",
        ),
    ] {
        let err = settings.validate().unwrap_err();
        assert!(err.to_string().contains(name), "{err}");
    }
}
