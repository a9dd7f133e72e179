//! Automatic large-step control's estimation phase under a time budget (Zsolnai &
//! Szirmay-Kalos 2013, section 2; `render::mlt::TIME_BUDGET_ESTIMATION_STEPS`): the share of
//! the run's mutations it uses, read from the run's typed statistics, stays within the
//! documented bound for every integrator that takes `--large-step auto`; the old rule (the
//! whole requested phase as the first round) does not.

use std::sync::atomic::AtomicBool;
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

use mcmc_core::controller::AutoLargeStep;
use mcmc_core::render_loop::{LoopBudget, LoopSettings, RenderLoop};
use mcmc_core::Mh;
use pss::{FreshPss, KelemenParams, PssmltProposal, SmallMutation, SmallStep};
use render::bdpt::BdptParams;
use render::methods::direct_pass::DirectSettings;
use render::methods::{MalaSettings, MmltSettings, PssmltSettings};
use render::mlt::{
    LargeStepMode, MltBudget, MltDriver, MltSettings, PssmltTarget, StagedSplats,
    ESTIMATION_SHARE_DIVISOR, PATH_STREAMS, TIME_BUDGET_ESTIMATION_STEPS,
};
use render::session::{render, Budget, NoProgress, RenderSettings};
use render::Scene;

/// The documented bound on the share of a time-budget run's mutations that the estimation
/// phase uses (docs/methods/large-step-control.md): a tenth at the bootstrap's rate
/// (`ESTIMATION_SHARE_DIVISOR`), doubled for chains whose mutations cost up to twice a
/// bootstrap sample.
const SHARE_BOUND: f64 = 2.0 / ESTIMATION_SHARE_DIVISOR as f64;

const SIDE: usize = 16;

/// The time budget of every run here.
const TIME: Duration = Duration::from_millis(800);

/// Far more chains than the time affords: the loop starts only as many as the time left after
/// the bootstrap affords with the planned mutations each, so the share does not depend on the
/// machine's speed (a faster machine starts more chains, each planned the same).
const CHAINS: usize = 4096;

fn kernel(p: f64) -> Mh<PssmltProposal> {
    let small = SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
    Mh::new(PssmltProposal::new(small, p).unwrap())
}

fn mlt_settings() -> MltSettings {
    MltSettings {
        width: SIDE,
        height: SIDE,
        chains: CHAINS,
        bootstrap_samples: 10_000,
        budget: MltBudget::Time(TIME),
        large_step: LargeStepMode::Auto {
            initial: 0.5,
            estimation_steps: 1000,
        },
        seed: 3,
        streams: PATH_STREAMS,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    }
}

/// The tests of this file run one at a time: each measures a share of a time budget, which
/// another render on the same cores would shift (the chain plan is made at the bootstrap's
/// rate, the chains then run slower).
fn serial() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

#[test]
fn the_estimation_phase_of_a_time_budget_is_a_bounded_share() {
    let _serial = serial();
    let scene = Scene::cornell_box(SIDE as u32, SIDE as u32);
    let targets = [PssmltTarget::new(
        &scene,
        BdptParams::default(),
        SIDE as u32,
        SIDE as u32,
    )];
    let s = mlt_settings();
    let out = MltDriver::new(&targets, &s).run(kernel, &NoProgress, &AtomicBool::new(false));
    let e = out.large_step.expect("an estimate");
    let chains: usize = out.target_chains.iter().sum();
    let share = e.steps() as f64 / out.mutations as f64;
    eprintln!(
        "capped rule: {chains} chains, {} mutations, {} estimating ({share:.3})",
        out.mutations,
        e.steps()
    );
    assert!(chains < CHAINS, "the time budget must cap the chains");
    assert_eq!(e.steps(), chains as u64 * TIME_BUDGET_ESTIMATION_STEPS);
    assert!(share <= SHARE_BOUND, "estimation share {share:.3}");

    // Negative control: the old rule under a time budget (the requested 1000 mutations per
    // chain as the first round, the chains capped at one round each) on the same scene.
    let loop_settings = LoopSettings {
        chains: CHAINS,
        bootstrap_samples: 10_000,
        budget: LoopBudget::Time(TIME),
        seed: 3,
        round_mutations: 1000,
        ..LoopSettings::default()
    };
    let states = FreshPss::new(PATH_STREAMS).unwrap();
    let old = RenderLoop {
        targets: &targets,
        states: &states,
        kernel: |_| kernel(0.5),
        controller: |_| AutoLargeStep::pooled(1).unwrap(),
        sink: || StagedSplats::new(SIDE, SIDE, false),
    }
    .run(&loop_settings, &NoProgress, &AtomicBool::new(false))
    .unwrap();
    let old_share = old.shared.steps() as f64 / old.mutations as f64;
    eprintln!(
        "old rule: {} chains, {} mutations, {} estimating ({old_share:.3})",
        old.chains,
        old.mutations,
        old.shared.steps()
    );
    assert!(old_share > SHARE_BOUND, "old rule's share {old_share:.3}");
}

/// The share as every integrator with `--large-step auto` reports it in its typed statistics.
fn session_share(method: render::methods::MethodSettings) -> f64 {
    let settings = RenderSettings {
        width: SIDE as u32,
        height: SIDE as u32,
        budget: Budget::Time(TIME),
        threads: 2,
        seed: 5,
        max_depth: 5,
        method,
    };
    let out = render(
        &Scene::cornell_box(SIDE as u32, SIDE as u32),
        &settings,
        &NoProgress,
        &AtomicBool::new(false),
    )
    .unwrap();
    let stats = out.mcmc.expect("typed statistics");
    assert!(stats.large_step.is_some(), "no estimate: {:?}", out.notes);
    stats.estimation_share().expect("a share")
}

#[test]
fn every_auto_integrator_reports_a_bounded_share() {
    let _serial = serial();
    let mut pssmlt = PssmltSettings::zsolnai2013();
    pssmlt.chain.chains = CHAINS;
    let mut mmlt = MmltSettings::hachisuka2014();
    mmlt.chain = mmlt.chain.with_auto_large_step(0.5);
    mmlt.chain.chains = CHAINS;
    // Without the direct pass: MALA's chains then start at depth 2, where a Langevin
    // mutation costs several bootstrap samples, and the chain plan (made at the bootstrap's
    // rate) starts too many chains for a sub-second budget (a known limit, see
    // docs/methods/large-step-control.md).
    let mut mala = MalaSettings::luan2020();
    mala.direct = DirectSettings::OFF;
    mala.chain = mala.chain.with_auto_large_step(0.5);
    mala.chain.chains = CHAINS;
    for (name, method) in [
        ("pssmlt", pssmlt.into()),
        ("mmlt", mmlt.into()),
        ("mala", mala.into()),
    ] {
        let share = session_share(method);
        eprintln!("{name}: estimation share {share:.3}");
        assert!(share <= SHARE_BOUND, "{name}: estimation share {share:.3}");
    }
}
