//! MMLT's robustness options (`docs/performance.md`, "MMLT robustness") on real scenes: the
//! per-depth chain allocation (`ChainAllocation::PerTarget`) and the strategy-stratified
//! bootstrap (`MmltStrata`) converge to the BDPT reference on the Cornell box, alone and
//! together, with the default 256 chains and with 6 chains (one per depth: the allocation's
//! weights `b_d / n_d` then carry everything); the negative control, the per-depth allocation
//! scaled by `b / N` as the joint allocation is, fails; the stratified bootstrap's `b` matches
//! the analytic enclosure; 1 and 2 threads give the same image.
//!
//! Statistics as in `mlt_convergence.rs` (module docs there): `R` replicate renders with
//! independent seeds against `K` BDPT replicates, Welch t on the image mean and on 4 x 4
//! block means, the critical value from Student's t with `min(R, K) - 1` degrees of freedom
//! at a Bonferroni level over this file's `N_COMPARISONS` comparisons (family-wise 0.001),
//! and the relMSE of the replicate average below 3x its expectation under no bias.
//!
//! Run with `cargo test -p render --release --test mmlt_robust -- --nocapture` to see every
//! statistic.

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::stats::{
    against_reference, assert_finite_non_negative, block_t, mean_se, relmse_observed_and_expected,
    t_critical,
};
use common::{analytic_enclosure, bdpt_replicates, enclosure_radiance};
use mcmc_core::render_loop::ChainAllocation;
use mcmc_core::Mh;
use pss::{KelemenParams, PssmltProposal, SmallMutation, SmallStep};
use render::bdpt::BdptParams;
use render::image::Image;
use render::mlt::{
    mmlt_depth_normalization, LargeStepMode, MltBudget, MltDriver, MltEstimator, MltOutput,
    MltSettings, MmltTarget, PATH_STREAMS,
};
use render::scene::Scene;
use render::session::NoProgress;

/// Family-wise false-alarm probability of the comparisons that must pass.
const ALPHA_FAMILY: f64 = 0.001;
/// MMLT replicates per configuration.
const R: usize = 16;
/// BDPT reference replicates.
const K: usize = 16;
/// Blocks per side of the regional comparison.
const BLOCKS: usize = 4;
/// Comparisons that must pass: 5 Cornell configurations x (mean + 16 blocks), the enclosure.
const N_COMPARISONS: usize = 5 * (1 + BLOCKS * BLOCKS) + 1;

const CORNELL: u32 = 16;
const DEPTH: u32 = 5;
const REF_SPP: u32 = 256;
const MPP: f64 = 512.0;

fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32)
}

fn kernel(p: f64) -> Mh<PssmltProposal> {
    let small = SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
    Mh::new(PssmltProposal::new(small, p).unwrap())
}

fn params() -> BdptParams {
    BdptParams {
        max_depth: DEPTH,
        ..BdptParams::default()
    }
}

fn cornell() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::cornell_box(CORNELL, CORNELL))
}

fn reference() -> &'static [Image] {
    static REFERENCE: OnceLock<Vec<Image>> = OnceLock::new();
    REFERENCE.get_or_init(|| bdpt_replicates(cornell(), &params(), REF_SPP, K, 190_000))
}

fn mmlt(scene: &Scene, seed: u64, chains: usize, estimator: MltEstimator) -> MltOutput {
    mmlt_normalized(scene, seed, chains, estimator, None)
}

fn mmlt_normalized(
    scene: &Scene,
    seed: u64,
    chains: usize,
    estimator: MltEstimator,
    normalization: Option<&[f64]>,
) -> MltOutput {
    let (w, h) = (scene.camera().width(), scene.camera().height());
    let settings = MltSettings {
        width: w as usize,
        height: h as usize,
        chains,
        bootstrap_samples: 20_000,
        budget: MltBudget::MutationsPerPixel(MPP),
        large_step: LargeStepMode::Fixed(0.3),
        seed,
        streams: PATH_STREAMS,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    };
    let targets = MmltTarget::all_depths(scene, params(), w, h);
    let cancel = AtomicBool::new(false);
    let out = match normalization {
        Some(nb) => MltDriver::new(&targets, &settings)
            .estimator(estimator)
            .normalized(nb)
            .run(kernel, &NoProgress, &cancel),
        None => MltDriver::new(&targets, &settings)
            .estimator(estimator)
            .run(kernel, &NoProgress, &cancel),
    };
    assert!(out.message.is_none(), "{:?}", out.message);
    assert_finite_non_negative(&out.image, "MMLT");
    out
}

fn replicates(seed0: u64, chains: usize, estimator: MltEstimator) -> Vec<MltOutput> {
    (0..R as u64)
        .map(|r| mmlt(cornell(), seed0 + r, chains, estimator))
        .collect()
}

fn estimator(chain_allocation: ChainAllocation, strategy_strata: bool) -> MltEstimator {
    MltEstimator {
        chain_allocation,
        strategy_strata,
        ..MltEstimator::plain()
    }
}

fn images(outs: &[MltOutput]) -> Vec<Image> {
    outs.iter().map(|o| o.image.clone()).collect()
}

#[test]
fn per_depth_allocation_matches_bdpt() {
    let outs = replicates(31_000, 256, estimator(ChainAllocation::PerTarget, false));
    for o in &outs {
        assert_eq!(o.target_chains.iter().sum::<usize>(), 256);
        assert!(
            o.target_chains.iter().all(|&n| n >= 1),
            "{:?}",
            o.target_chains
        );
    }
    against_reference(
        "cornell MMLT per-depth",
        &images(&outs),
        reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn strategy_strata_match_bdpt() {
    let outs = replicates(32_000, 256, estimator(ChainAllocation::Joint, true));
    against_reference(
        "cornell MMLT strata",
        &images(&outs),
        reference(),
        BLOCKS,
        critical(),
    );
    let both = replicates(33_000, 256, estimator(ChainAllocation::PerTarget, true));
    against_reference(
        "cornell MMLT per-depth + strata",
        &images(&both),
        reference(),
        BLOCKS,
        critical(),
    );
}

/// Six chains for six depths: one chain per depth, each weighted `b_d` (the correct
/// estimator), against the same chains weighted `b / 6` each (the joint allocation's scale:
/// the negative control, which must fail).
#[test]
fn one_chain_per_depth_needs_the_per_depth_scale() {
    let outs = replicates(34_000, 6, estimator(ChainAllocation::PerTarget, false));
    for o in &outs {
        assert_eq!(o.target_chains, [1; 6]);
    }
    against_reference(
        "cornell MMLT per-depth, 6 chains",
        &images(&outs),
        reference(),
        BLOCKS,
        critical(),
    );
    let wrong = images(&replicates(
        34_000,
        6,
        estimator(ChainAllocation::PerTargetWithJointScale, false),
    ));
    let blocks = block_t(&wrong, reference(), BLOCKS);
    let max_t = blocks.iter().map(|b| b[0].abs()).fold(0.0, f64::max);
    let (observed, expected) = relmse_observed_and_expected(&wrong, reference());
    eprintln!(
        "negative control (per-depth chains, b / N scale): max block |t| {max_t:.1} \
         (critical {:.2}), relMSE ratio {:.1}",
        critical(),
        observed / expected
    );
    assert!(
        max_t > 2.0 * critical() && observed > 3.0 * expected,
        "the negative control must fail: max |t| {max_t}, relMSE {observed} vs {expected}"
    );
}

/// Each depth's integral from 20 000 all-strategy BDPT samples instead of the bootstrap
/// (`MltDriver::normalized`): consistent (the start bias of importance resampling is far
/// below this test's resolution), so it must match the reference; the negative control, the
/// same normalisation shifted by one depth (`b_d` of depth `d + 1` for depth `d`), must not.
#[test]
fn bdpt_normalization_matches_bdpt() {
    let (w, h) = (CORNELL, CORNELL);
    let cancel = AtomicBool::new(false);
    let mut good = Vec::new();
    let mut wrong = Vec::new();
    for r in 0..R as u64 {
        let seed = 36_000 + r;
        let nb =
            mmlt_depth_normalization(cornell(), params(), w, h, 20_000, seed, &cancel).unwrap();
        assert_eq!(nb.len(), DEPTH as usize + 1);
        let out = mmlt_normalized(cornell(), seed, 256, MltEstimator::plain(), Some(&nb));
        assert_eq!(out.target_b, nb);
        good.push(out.image);
        let mut shifted = nb.clone();
        shifted.rotate_left(1);
        shifted[DEPTH as usize] = 0.0;
        let out = mmlt_normalized(cornell(), seed, 256, MltEstimator::plain(), Some(&shifted));
        wrong.push(out.image);
    }
    against_reference(
        "cornell MMLT BDPT normalisation",
        &good,
        reference(),
        BLOCKS,
        critical(),
    );
    let blocks = block_t(&wrong, reference(), BLOCKS);
    let max_t = blocks.iter().map(|b| b[0].abs()).fold(0.0, f64::max);
    eprintln!("negative control (normalisation shifted by one depth): max block |t| {max_t:.1}");
    assert!(
        max_t > 2.0 * critical(),
        "the negative control must fail: {max_t}"
    );
}

/// The analytic enclosure (radiance known in closed form): with strata, the image mean is
/// the stratified bootstrap's `b`, which must match it.
#[test]
fn strategy_strata_match_the_analytic_enclosure() {
    let scene = analytic_enclosure(16, 16);
    let enclosure_params = BdptParams {
        max_depth: 3,
        ..BdptParams::default()
    };
    let exact = enclosure_radiance(3);
    let means: Vec<f64> = (0..R as u64)
        .map(|r| {
            let settings = MltSettings {
                width: 16,
                height: 16,
                chains: 64,
                bootstrap_samples: 20_000,
                budget: MltBudget::MutationsPerPixel(32.0),
                large_step: LargeStepMode::Fixed(0.3),
                seed: 35_000 + r,
                streams: PATH_STREAMS,
                stage_map: false,
                shard: render::shard::Shard::WHOLE,
                normalization: Default::default(),
            };
            let out = MltDriver::new(
                &MmltTarget::all_depths(&scene, enclosure_params, 16, 16),
                &settings,
            )
            .estimator(estimator(ChainAllocation::PerTarget, true))
            .run(kernel, &NoProgress, &AtomicBool::new(false));
            out.image.mean()[0]
        })
        .collect();
    let (m, se) = mean_se(&means);
    let t = (m - exact) / se;
    eprintln!("enclosure MMLT strata: mean {m:.6} exact {exact:.6} se {se:.2e} t {t:.2}");
    assert!((m - exact).abs() < critical() * se + 1e-6 * exact, "t {t}");
}

/// Bit-identical images for 1 and 2 threads with both options on.
#[test]
fn options_are_deterministic_across_threads() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                mmlt(
                    cornell(),
                    5,
                    64,
                    estimator(ChainAllocation::PerTarget, true),
                )
            })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.image.pixels, b.image.pixels);
    assert_eq!(a.target_chains, b.target_chains);
}
