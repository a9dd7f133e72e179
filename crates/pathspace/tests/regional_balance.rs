//! The regional-adaptive kernels with adaptation frozen: pairwise flow balance on random paths
//! of the test box (reverse density with the *proposed* state's region scale; mcmc-core's
//! harness, relative 1e-9) and chi-square stationarity from exact starts on the furnace box,
//! for the lens perturbation over screen partitions and the multi-chain perturbation over 4-D
//! partitions. Negative control: the reverse density at the *current* state's region scale
//! fails both.

mod common;

use mcmc_core::render_loop::SharedController;
use mcmc_core::testing::{
    assert_hastings_consistent, assert_path_balance, stationarity_test, FnBins, PairwiseParams,
    StationarityParams,
};
use mcmc_core::{Chain, Mh, Partition, Proposal, Proposed};
use pathspace::analytic::AnalyticScene;
use pathspace::regional::{
    DirectionPartition, PathPartition, PlanePartition, PooledRegionalStats, RegionalAdaptParams,
    RegionalSigmas, ScreenPartition, SharedRegionalAdaptation, SharedSigmas,
};
use pathspace::{
    ra_mixture, IndependenceMutation, IndependentSampler, Path, PathTarget, Perturbation,
    PerturbationKind, ScaleSource, UnidirectionalParams, UnidirectionalSampler,
};
use proptest::prelude::*;
use rand::{Rng, RngExt};

type Part<'a> = PathPartition<&'a AnalyticScene>;

fn sampler(scene: &AnalyticScene, segments: usize) -> UnidirectionalSampler<'_, AnalyticScene> {
    UnidirectionalSampler::new(
        scene,
        UnidirectionalParams {
            max_segments: segments,
            connect_probability: 0.5,
        },
    )
    .unwrap()
}

/// A screen quadtree refined three times (root, then two of its children), with a different
/// scale in every leaf (sigma from 0.01 to 0.4).
fn screen_sigmas(scene: &AnalyticScene) -> SharedSigmas<Part<'_>> {
    let part = PathPartition::Screen(ScreenPartition::new(
        scene,
        PlanePartition::quadtree(6).unwrap(),
    ));
    let mut s = RegionalSigmas::new(part, 0.0, 1.0).unwrap();
    s.split(0).unwrap();
    s.split(3).unwrap();
    s.split(1).unwrap();
    for k in 0..s.num_regions() {
        let sigma: f64 = 0.01 + 0.39 * (k as f64 / (s.num_regions() - 1) as f64);
        s.set_lambda(k, (sigma * sigma).ln());
    }
    SharedSigmas::new(s)
}

/// A 3 x 3 screen grid whose cells hold direction quadtrees, some split, with alternating
/// scales; `sigma_2 = 0.5 sigma_1`.
fn direction_sigmas(scene: &AnalyticScene) -> SharedSigmas<Part<'_>> {
    let part = PathPartition::Direction(
        DirectionPartition::new(scene, 3, PlanePartition::quadtree(6).unwrap()).unwrap(),
    );
    let mut s = RegionalSigmas::new(part, 0.0, 0.5).unwrap();
    for k in [0, 4, 8, 9] {
        s.split(k).unwrap();
    }
    for k in 0..s.num_regions() {
        let sigma: f64 = if k % 2 == 0 { 0.03 } else { 0.3 };
        s.set_lambda(k, (sigma * sigma).ln());
    }
    SharedSigmas::new(s)
}

/// `(x, y)` with `y` proposed from `x` (see `flow_balance.rs`).
fn proposed_pair<P: Proposal<Path>>(
    sampler: &UnidirectionalSampler<'_, AnalyticScene>,
    proposal: &P,
    seed: u64,
) -> Vec<Path> {
    let mut rng = common::rng(seed);
    let x = common::draw(sampler, &mut rng);
    let mut y = Path::new();
    for _ in 0..8 {
        if let Proposed::Move { .. } = proposal.propose(&x, &mut y, &mut rng) {
            return vec![x, y];
        }
    }
    let other = common::draw(sampler, &mut rng);
    vec![x, other]
}

fn check<P: Proposal<Path> + Clone>(scene: &AnalyticScene, name: &str, proposal: P, seed: u64) {
    let sampler = sampler(scene, 6);
    let target = PathTarget::new(scene);
    let params = PairwiseParams::with_seed(seed);
    let paths = any::<u64>().prop_map(|s| proposed_pair(&sampler, &proposal, s));
    let report = assert_path_balance(&target, &Mh::new(proposal.clone()), paths, &params);
    let states = any::<u64>().prop_map(|s| common::draw(&sampler, &mut common::rng(s)));
    let hastings = assert_hastings_consistent(&proposal, states, &params);
    eprintln!("{name}: {report:?}, Hastings {hastings:?}");
}

/// The pairs cross region borders: the two states' scales differ for most of them.
#[test]
fn regional_lens_flow_balance() {
    let scene = AnalyticScene::test_box().unwrap();
    let sigmas = screen_sigmas(&scene);
    let pert = Perturbation::lens(&scene, sigmas.clone());
    let sampler = sampler(&scene, 6);
    let mut rng = common::rng(40);
    let (mut moves, mut crossing) = (0, 0);
    let mut y = Path::new();
    for _ in 0..2000 {
        let x = common::draw(&sampler, &mut rng);
        if let Proposed::Move { .. } = pert.propose(&x, &mut y, &mut rng) {
            moves += 1;
            crossing += usize::from(sigmas.sigmas(&x) != sigmas.sigmas(&y));
        }
    }
    eprintln!("{crossing} of {moves} moves change the region scale");
    assert!(crossing > moves / 10, "{crossing} of {moves}");
    check(&scene, "regional lens (screen quadtree)", pert, 41);
}

#[test]
fn regional_multi_chain_flow_balance() {
    let scene = AnalyticScene::test_box().unwrap();
    let pert = Perturbation::multi_chain(&scene, direction_sigmas(&scene));
    check(&scene, "regional multi-chain (4-D)", pert, 42);
}

#[test]
fn regional_ra_mixture_flow_balance() {
    let scene = AnalyticScene::test_box().unwrap();
    let m = ra_mixture(
        PerturbationKind::MultiChain,
        Perturbation::multi_chain(&scene, direction_sigmas(&scene)),
        common::bidirectional(&scene, 6),
    )
    .unwrap();
    check(
        &scene,
        "RA mixture (regional multi-chain + bidirectional)",
        m,
        43,
    );
}

/// The bug: the reverse density at the current state's region scale.
#[derive(Clone)]
struct CurrentScaleReverse<'a, Sc>(Perturbation<'a, AnalyticScene, Sc>);

impl<Sc: ScaleSource + Clone> Proposal<Path> for CurrentScaleReverse<'_, Sc> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        let s = self.0.scale().sigmas(x);
        if !self.0.propose_with(x, y, rng, s) {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.log_hastings(0, x, y))
    }
    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.0.log_q(from, to)
    }
    fn log_hastings(&self, _j: usize, x: &Path, y: &Path) -> f64 {
        let s = self.0.scale().sigmas(x);
        self.0.log_q_with(y, x, s) - self.0.log_q_with(x, y, s)
    }
}

#[test]
#[should_panic(expected = "detailed balance violated")]
fn negative_control_lens_reverse_at_current_region_scale_fails() {
    let scene = AnalyticScene::test_box().unwrap();
    let broken = CurrentScaleReverse(Perturbation::lens(&scene, screen_sigmas(&scene)));
    let sampler = sampler(&scene, 6);
    let paths = any::<u64>().prop_map(|s| proposed_pair(&sampler, &broken, s));
    assert_path_balance(
        &PathTarget::new(&scene),
        &Mh::new(broken.clone()),
        paths,
        &PairwiseParams::with_seed(44),
    );
}

#[test]
#[should_panic(expected = "detailed balance violated")]
fn negative_control_multi_chain_reverse_at_current_region_scale_fails() {
    let scene = AnalyticScene::test_box().unwrap();
    let broken = CurrentScaleReverse(Perturbation::multi_chain(&scene, direction_sigmas(&scene)));
    let sampler = sampler(&scene, 6);
    let paths = any::<u64>().prop_map(|s| proposed_pair(&sampler, &broken, s));
    assert_path_balance(
        &PathTarget::new(&scene),
        &Mh::new(broken.clone()),
        paths,
        &PairwiseParams::with_seed(45),
    );
}

// ---- stationarity from exact starts on the furnace box (see `stationarity.rs`) ----

const ALBEDO: f64 = 0.6;
const SEGMENTS: usize = 3;
/// Stationarity tests in this file that must pass (Sidak correction).
const TESTS: usize = 2;

fn furnace() -> AnalyticScene {
    AnalyticScene::furnace_box(ALBEDO, 1.0).unwrap()
}

fn exact_draw<R: Rng>(scene: &AnalyticScene, rng: &mut R) -> Path {
    let sampler = sampler(scene, SEGMENTS);
    let bound = SEGMENTS as f64 / 0.5;
    loop {
        let p = common::draw(&sampler, rng);
        let ratio = p.contribution(scene).luminance() / sampler.log_density(&p).exp();
        assert!(ratio <= bound * (1.0 + 1e-9));
        if rng.random::<f64>() * bound < ratio {
            return p;
        }
    }
}

fn bins(scene: &AnalyticScene) -> FnBins<impl Fn(&Path) -> usize + '_> {
    let norm: f64 = (0..SEGMENTS).map(|j| ALBEDO.powi(j as i32)).sum();
    FnBins {
        probabilities: (0..SEGMENTS * 4)
            .map(|b| ALBEDO.powi((b / 4) as i32) / norm / 4.0)
            .collect(),
        bin_of: move |p: &Path| {
            let r = p.raster(scene).unwrap();
            (p.segments() - 1) * 4 + usize::from(r[0] >= 0.5) * 2 + usize::from(r[1] >= 0.5)
        },
    }
}

/// Scales learned by the shared controller (one chain, synchronised by hand every 2000
/// steps) on a screen quadtree, then frozen.
fn learned_screen_sigmas(scene: &AnalyticScene) -> SharedSigmas<Part<'_>> {
    let part = PathPartition::Screen(ScreenPartition::new(
        scene,
        PlanePartition::quadtree(6).unwrap(),
    ));
    let params = RegionalAdaptParams {
        split_after_visits: Some(1000),
        refine_every: 8000,
        ..RegionalAdaptParams::otsu2018()
    };
    let sigmas = SharedSigmas::new(RegionalSigmas::new(part, 1.0, 1.0).unwrap());
    let kernel = Mh::new(
        ra_mixture(
            PerturbationKind::Lens,
            Perturbation::lens(scene, sigmas),
            IndependenceMutation::new(sampler(scene, SEGMENTS)),
        )
        .unwrap(),
    );
    let target = PathTarget::new(scene);
    let mut rng = common::rng(50);
    let x0 = exact_draw(scene, &mut rng);
    let controller = SharedRegionalAdaptation::new(params).unwrap();
    let mut chain = Chain::new(&target, kernel, controller, rng, x0).unwrap();
    let mut pooled = PooledRegionalStats::default();
    for _ in 0..30 {
        chain.run(2000, &mut ()).unwrap();
        let (k, c) = chain.kernel_and_controller_mut();
        c.contribute(k, &mut pooled);
        pooled.end_round();
        c.receive(k, &pooled);
    }
    let learned = pooled.sigmas().unwrap().clone();
    let s: Vec<f64> = (0..learned.get().num_regions())
        .map(|k| learned.get().sigmas_of_region(k)[0])
        .collect();
    eprintln!("learned {} regions, sigma {s:.3?}", s.len());
    assert!(s.len() > 4);
    learned
}

#[test]
fn learned_regional_lens_and_independence_preserve_pi() {
    let scene = furnace();
    let kernel = Mh::new(
        ra_mixture(
            PerturbationKind::Lens,
            Perturbation::lens(&scene, learned_screen_sigmas(&scene)),
            IndependenceMutation::new(sampler(&scene, SEGMENTS)),
        )
        .unwrap(),
    );
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &kernel,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 10, 51),
    );
    eprintln!("{report:?}");
    report.assert_passes("learned regional lens + independence", TESTS);
}

/// A screen grid of 4 x 4 cells, scale 0.03 in the left column and 0.5 elsewhere (a
/// checkerboard would cancel in the quadrant bins).
fn left_column(scene: &AnalyticScene) -> SharedSigmas<Part<'_>> {
    let part = PathPartition::Screen(ScreenPartition::new(
        scene,
        PlanePartition::grid(4).unwrap(),
    ));
    let mut s = RegionalSigmas::new(part, 0.0, 1.0).unwrap();
    for k in 0..16 {
        let sigma: f64 = if k % 4 == 0 { 0.03 } else { 0.5 };
        s.set_lambda(k, (sigma * sigma).ln());
    }
    SharedSigmas::new(s)
}

#[test]
fn regional_multi_chain_and_bidirectional_preserve_pi() {
    let scene = furnace();
    let kernel = Mh::new(
        ra_mixture(
            PerturbationKind::MultiChain,
            Perturbation::multi_chain(&scene, direction_sigmas(&scene)),
            common::bidirectional(&scene, SEGMENTS),
        )
        .unwrap(),
    );
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &kernel,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 10, 52),
    );
    eprintln!("{report:?}");
    report.assert_passes("regional multi-chain + bidirectional", TESTS);
}

#[test]
fn negative_control_stationarity_reverse_at_current_region_scale_fails() {
    let scene = furnace();
    let sigmas = left_column(&scene);
    assert_eq!(sigmas.get().partition().num_regions(), 16);
    let kernel = Mh::new(CurrentScaleReverse(Perturbation::lens(
        &scene,
        sigmas.clone(),
    )));
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &kernel,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 30, 53),
    );
    eprintln!("broken: {report:?}");
    assert!(
        report.p_value < 1e-6,
        "the broken kernel passed: {report:?}"
    );
    // The correct kernel with the same scales passes.
    let ok = Mh::new(Perturbation::lens(&scene, sigmas));
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &ok,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 30, 54),
    );
    eprintln!("correct: {report:?}");
    report.assert_passes("left-column lens (control of the control)", TESTS + 1);
}
