//! The render loop under extreme chain counts and budgets: chains capped at what a time budget
//! affords, a chain set-up that stops on a cancel or a deadline (and still mutates under a
//! deadline), and the notes that say when an image is not what it seems (targets with light
//! but no chain, a normalisation resting on a few samples).
//!
//! No test asserts on wall time; each has a control run that must not trigger what it checks.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use mcmc_core::render_loop::{
    ChainSlot, LoopBudget, LoopOutput, LoopSettings, RenderLoop, SplatGrid, MIN_TIME_MUTATIONS,
};
use mcmc_core::{GaussianRandomWalk, Mh, NoAdaptation, NoProgress};

mod support;

use support::{Ramp, Uniform, RAMP};

/// Runs the loop over `targets`; `on_kernel` is called with every chain's slot as its kernel
/// is made (to cancel or stall the set-up at a chosen chain).
fn run_with(
    targets: &[Ramp],
    settings: &LoopSettings,
    cancel: &AtomicBool,
    on_kernel: impl Fn(ChainSlot) + Sync,
) -> LoopOutput<SplatGrid, ()> {
    RenderLoop {
        targets,
        states: &Uniform,
        kernel: |slot| {
            on_kernel(slot);
            Mh::new(GaussianRandomWalk::new(0.2).unwrap())
        },
        controller: |_| NoAdaptation,
        sink: || SplatGrid::new(4, 1),
    }
    .run(settings, &NoProgress, cancel)
    .unwrap()
}

fn run(targets: &[Ramp], settings: &LoopSettings) -> LoopOutput<SplatGrid, ()> {
    run_with(targets, settings, &AtomicBool::new(false), |_| {})
}

fn has_note(out: &LoopOutput<SplatGrid, ()>, needle: &str) -> bool {
    out.notes.iter().any(|n| n.contains(needle))
}

fn lit(out: &LoopOutput<SplatGrid, ()>) -> bool {
    (0..4).any(|x| out.sink.get(x, 0)[0] > 0.0)
}

/// A million chains under a short time budget: the loop starts only what the time left
/// affords at the bootstrap's rate, says so, and renders (it used to set up every chain,
/// past the deadline and through gigabytes, and end black).
#[test]
fn many_chains_under_a_time_budget_are_capped_with_a_note() {
    let settings = LoopSettings {
        chains: mcmc_core::render_loop::MAX_CHAINS,
        bootstrap_samples: 10_000,
        budget: LoopBudget::Time(Duration::from_millis(300)),
        ..LoopSettings::default()
    };
    let out = run(&[RAMP], &settings);
    eprintln!(
        "{} chains, {} mutations: {:?}",
        out.chains, out.mutations, out.notes
    );
    assert!(out.chains < settings.chains, "{}", out.chains);
    assert!(has_note(&out, "what the time left"), "{:?}", out.notes);
    assert!(out.mutations > 0 && lit(&out) && !out.cancelled);
    // A round each (1000 mutations) or MIN_TIME_MUTATIONS, whichever is more.
    let planned = MIN_TIME_MUTATIONS.max(settings.round_mutations);
    assert!(
        has_note(&out, &format!("at least {planned} mutations per chain")),
        "{:?}",
        out.notes
    );
    // Control: a few chains are never capped.
    let few = run(
        &[RAMP],
        &LoopSettings {
            chains: 8,
            ..settings
        },
    );
    assert_eq!(few.chains, 8);
    assert!(!has_note(&few, "what the time left"), "{:?}", few.notes);
}

/// The chain set-up polls the cancel flag: a cancel during it stops it and says why.
#[test]
fn a_cancel_stops_the_chain_set_up() {
    let settings = LoopSettings {
        chains: 4096,
        bootstrap_samples: 10_000,
        budget: LoopBudget::Mutations(1_000_000),
        ..LoopSettings::default()
    };
    let cancel = AtomicBool::new(false);
    let out = run_with(&[RAMP], &settings, &cancel, |slot| {
        if slot.chain == 300 {
            cancel.store(true, Ordering::Relaxed);
        }
    });
    assert!(out.cancelled);
    assert!(out.chains < 4096, "{}", out.chains);
    assert!(
        has_note(&out, "cancelled while the chains were being started"),
        "{:?}",
        out.notes
    );
    assert_eq!(out.mutations, 0);
    assert!(has_note(&out, "image is black"), "{:?}", out.notes);
    // Control: without the cancel every chain starts and runs.
    let full = run(&[RAMP], &settings);
    assert_eq!((full.chains, full.mutations), (4096, 1_000_000));
    assert!(!has_note(&full, "being started"), "{:?}", full.notes);
}

/// The chain set-up polls the deadline: a set-up that outlives the budget stops, says so, and
/// the chains started still run their first mutations, so the image is not black.
#[test]
fn a_deadline_during_the_set_up_stops_it_and_the_image_still_has_light() {
    // Rounds of one mutation: the time cap plans 100 mutations per chain, so that all 1024
    // chains are affordable and the stall below, not the cap, decides.
    let settings = LoopSettings {
        chains: 1024,
        bootstrap_samples: 10_000,
        budget: LoopBudget::Time(Duration::from_millis(1000)),
        round_mutations: 1,
        ..LoopSettings::default()
    };
    let out = run_with(&[RAMP], &settings, &AtomicBool::new(false), |slot| {
        if slot.chain == 300 {
            std::thread::sleep(Duration::from_millis(1200));
        }
    });
    eprintln!(
        "{} chains, {} mutations: {:?}",
        out.chains, out.mutations, out.notes
    );
    assert!(out.chains < 1024 && !out.cancelled, "{}", out.chains);
    assert!(
        has_note(
            &out,
            "the time budget ran out while the chains were being started"
        ),
        "{:?}",
        out.notes
    );
    assert!(out.mutations > 0 && lit(&out), "{}", out.mutations);
    assert!(!has_note(&out, "image is black"), "{:?}", out.notes);
    // Control: a set-up that does not stall starts every chain.
    let full = run(&[RAMP], &settings);
    assert_eq!(full.chains, 1024);
    assert!(!has_note(&full, "being started"), "{:?}", full.notes);
}

/// One chain over two targets with the same light (the joint allocation, pbrt's): one target
/// gets no chain, and the note says the image shows only the other's light, scaled.
#[test]
fn targets_with_light_but_no_chain_are_noted_under_the_joint_allocation() {
    let settings = LoopSettings {
        chains: 1,
        bootstrap_samples: 2000,
        budget: LoopBudget::Mutations(10_000),
        ..LoopSettings::default()
    };
    let out = run(&[RAMP, RAMP], &settings);
    assert!(
        has_note(&out, "1 of 2 target(s) with light"),
        "{:?}",
        out.notes
    );
    assert!(has_note(&out, "right only on average"), "{:?}", out.notes);
    // Control: with 64 chains both targets get chains.
    let many = run(
        &[RAMP, RAMP],
        &LoopSettings {
            chains: 64,
            ..settings
        },
    );
    assert!(many.target_chains.iter().all(|&n| n > 0));
    assert!(!has_note(&many, "got no chain"), "{:?}", many.notes);
}

/// A target whose light covers 0.2 % of its domain but carries half of `b`, in a bootstrap of
/// 1000 samples: its `b_d` rests on about two samples, and the note says `b` is uncertain
/// beyond its standard error.
#[test]
fn rare_light_in_a_small_bootstrap_is_noted() {
    let targets = [
        RAMP,
        Ramp {
            cut: 0.998,
            gain: 400.0,
            pixels: 4.0,
        },
    ];
    let settings = LoopSettings {
        chains: 16,
        bootstrap_samples: 1000,
        budget: LoopBudget::Mutations(1000),
        ..LoopSettings::default()
    };
    let seed = (0..20)
        .find(|&seed| {
            let out = run(&targets, &LoopSettings { seed, ..settings });
            out.target_hits[1] > 0
        })
        .expect("some seed finds the rare light");
    let out = run(&targets, &LoopSettings { seed, ..settings });
    assert!(out.target_hits[1] < 30, "{:?}", out.target_hits);
    assert!(has_note(&out, "b is uncertain"), "{:?}", out.notes);
    // Control: 100 000 samples find it about 200 times.
    let big = run(
        &targets,
        &LoopSettings {
            bootstrap_samples: 100_000,
            seed,
            ..settings
        },
    );
    assert!(big.target_hits[1] >= 30, "{:?}", big.target_hits);
    assert!(!has_note(&big, "b is uncertain"), "{:?}", big.notes);
}
