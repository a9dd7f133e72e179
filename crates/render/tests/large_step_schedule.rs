//! The Langevin MLT authors' large-step schedule (`LargeStepMode::Schedule`, the code preset's
//! `MalaSettings::CODE_LARGE_STEP`): probability 0.05 for the first tenth of every chain's
//! mutations, then 0.2. The count of large steps a render reports must be what the schedule
//! predicts (a binomial sum, its threshold five standard deviations), and the same check must
//! reject a chain that ran one probability throughout (the negative control).

use std::sync::atomic::AtomicBool;

use render::methods::direct_pass::DirectSettings;
use render::methods::{MalaSettings, McmcStats};
use render::mlt::mala::{MalaConfig, MalaVariant};
use render::mlt::{LargeStepMode, ESTIMATION_SHARE_DIVISOR};
use render::session::{render, Budget, NoProgress, RenderSettings};
use render::Scene;

use mcmc_core::langevin::LARGE_STEP_COMPONENT;

const SIDE: u32 = 16;
const CHAINS: usize = 64;
const MUTATIONS_PER_PIXEL: u64 = 1000;

/// A plain-MALA render with the code preset's chains (its fallback step and large steps
/// `large_step`), no direct pass; returns its typed statistics.
fn run(large_step: LargeStepMode) -> McmcStats {
    let code = MalaSettings::luan2020_code();
    let mut mala = MalaSettings {
        config: MalaConfig {
            variant: MalaVariant::Plain,
            ..code.config
        },
        direct: DirectSettings::OFF,
        ..code
    };
    mala.chain.chains = CHAINS;
    mala.chain.bootstrap_samples = 20_000;
    mala.chain.large_step = large_step;
    let settings = RenderSettings {
        width: SIDE,
        height: SIDE,
        budget: Budget::SamplesPerPixel(MUTATIONS_PER_PIXEL as u32),
        threads: 2,
        seed: 11,
        max_depth: 3,
        method: mala.into(),
    };
    let out = render(
        &Scene::cornell_box(SIDE, SIDE),
        &settings,
        &NoProgress,
        &AtomicBool::new(false),
    )
    .expect("render");
    out.mcmc.expect("typed statistics")
}

/// `z` of the large steps counted in `stats` against the schedule `0.05` for the first tenth
/// of each chain's mutations and `0.2` after (every chain runs its equal share).
fn schedule_z(stats: &McmcStats) -> f64 {
    let chains: usize = stats.target_chains.iter().sum();
    assert_eq!(chains, CHAINS, "chains started");
    let total = MUTATIONS_PER_PIXEL * u64::from(SIDE * SIDE);
    assert_eq!(stats.mutations, total, "mutations");
    let per_chain = total / CHAINS as u64;
    let warm_up = per_chain / ESTIMATION_SHARE_DIVISOR;
    let (early, late) = (warm_up as f64, (per_chain - warm_up) as f64);
    let n = CHAINS as f64;
    let mean = n * (0.05 * early + 0.2 * late);
    let variance = n * (0.05 * 0.95 * early + 0.2 * 0.8 * late);
    let observed = stats.acceptance.proposed[LARGE_STEP_COMPONENT] as f64;
    (observed - mean) / variance.sqrt()
}

#[test]
fn the_code_schedule_switches_after_a_tenth_of_each_chain() {
    assert_eq!(
        MalaSettings::luan2020_code().chain.large_step,
        LargeStepMode::Schedule {
            initial: 0.05,
            then: 0.2
        }
    );
    let stats = run(MalaSettings::CODE_LARGE_STEP);
    let z = schedule_z(&stats);
    eprintln!("schedule: z = {z:.2}");
    assert!(z.abs() < 5.0, "large steps of the schedule: z = {z:.2}");
    assert_eq!(stats.large_step_probability, 0.2);
    // Negative controls: one probability throughout (the old preset's fixed step at the
    // schedule's late value, and its early value) is rejected by the same check.
    for p in [0.2, 0.05] {
        let z = schedule_z(&run(LargeStepMode::Fixed(p)));
        eprintln!("fixed {p}: z = {z:.2}");
        assert!(
            z.abs() > 5.0,
            "fixed {p} passes for the schedule: z = {z:.2}"
        );
    }
}
