//! The splat-weight check: MH's expected-value weights keep the observer contract on toy
//! targets, and broken weightings (a dropped `1 - a` current-state splat, forced acceptance
//! splatting the accepted state with weight 1) fail it.
//!
//! Run with `cargo test -p mcmc-core --release --test splat_weights -- --nocapture` to see
//! every statistic and p-value.
//!
//! # Statistics
//! Each check runs [`STARTS`] independent exact starts, one step each, and tests the mean
//! splat-weighted histogram against the bin probabilities with the harness's chi-square
//! statistic, its covariance taken from the per-start contributions at the scale of the bin
//! probabilities (`mcmc_core::testing::SplatMoments::test` derives it). Under the contract
//! the p-value is asymptotically uniform (`tests/splat_weight_calibration.rs` checks it over
//! a seed sweep). This file runs
//! [`SPLAT_TESTS`] checks that must pass, each at the Sidak level
//! `1 - 0.99^(1/SPLAT_TESTS)`, so the probability of any false failure is 0.01; seeds are
//! fixed, so the outcome is deterministic. A broken weighting counts as caught when its
//! p-value is below [`OVERWHELMING`] = 1e-6 (a correct kernel gets there with probability
//! 1e-6).

use mcmc_core::testing::{
    toy_splat_weight_test, toy_stationarity_test, AsymmetricWalk, ForcedAcceptance,
    SplatFinalState, SplatParams, SplatWeightReport, StationarityParams, WithoutCurrentSplat,
};
use mcmc_core::toy::{PiecewiseConstant, Ridge, TorusMixture, ToyTarget, UniformMixture};
use mcmc_core::{GaussianRandomWalk, Kernel, Mh};

/// Tests in this file that must pass (Sidak correction): five splat-weight checks and one
/// stationarity test. Keep in sync.
const SPLAT_TESTS: usize = 6;

/// Independent exact starts per check.
const STARTS: usize = 20_000;

/// p-value below which a broken weighting counts as caught.
const OVERWHELMING: f64 = 1e-6;

fn grw(sigma: f64) -> Mh<GaussianRandomWalk> {
    Mh::new(GaussianRandomWalk::new(sigma).unwrap())
}

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

/// MH with a symmetric walk much wider than the spike of the DR paper's mixture of uniforms:
/// most candidates from the spike are rejected, so the `1 - a` splat carries a large part of
/// the weight there.
#[test]
fn mh_keeps_the_contract_on_the_uniform_mixture() {
    let target = UniformMixture::rioux_lavoie2020();
    let report = check("uniform mixture / MH GRW 0.5", &target, &grw(0.5), 1);
    assert!((report.mean_total_weight - 1.0).abs() < 1e-12);
    report.assert_passes("uniform mixture / MH GRW 0.5", SPLAT_TESTS);
}

/// An asymmetric proposal (drift and state-dependent scale) with its Hastings term, on the
/// target with zero-density holes: weights in every bin of positive probability, none in
/// the holes.
#[test]
fn mh_keeps_the_contract_with_a_hastings_term_and_holes() {
    let target = PiecewiseConstant::with_holes();
    let kernel = Mh::new(AsymmetricWalk::new(0.15, 0.05, 0.5).unwrap());
    let report = check("holes / MH asymmetric walk", &target, &kernel, 2);
    assert_eq!(report.impossible_weight, 0.0);
    report.assert_passes("holes / MH asymmetric walk", SPLAT_TESTS);
}

/// Two 2-D targets: a thin ridge and the torus mixture with mass across the seams.
#[test]
fn mh_keeps_the_contract_in_two_dimensions() {
    let report = check("ridge / MH GRW 0.5", &Ridge::thin(), &grw(0.5), 3);
    report.assert_passes("ridge / MH GRW 0.5", SPLAT_TESTS);
    let report = check(
        "torus mixture / MH GRW 0.1",
        &TorusMixture::across_seam(),
        &grw(0.1),
        4,
    );
    report.assert_passes("torus mixture / MH GRW 0.1", SPLAT_TESTS);
}

/// The plain estimator (splat the state after the step with weight 1) keeps the contract for
/// a correct kernel: what makes the forced-acceptance control below a test of the kernel's
/// move rather than of the weighting scheme.
#[test]
fn splatting_the_next_state_keeps_the_contract() {
    let target = UniformMixture::rioux_lavoie2020();
    let report = check(
        "uniform mixture / MH GRW 0.5, final state weight 1",
        &target,
        &SplatFinalState(grw(0.5)),
        5,
    );
    report.assert_passes("plain estimator", SPLAT_TESTS);
}

/// (a) Dropping the `1 - a` splat of the current state: the states are still right (the
/// stationarity test from exact starts passes, since the kernel moves exactly like MH), but
/// the splatted histogram is too light wherever candidates are rejected, and the splat-weight
/// check catches it.
#[test]
fn dropping_the_current_state_splat_fails() {
    let target = UniformMixture::rioux_lavoie2020();
    let bad = WithoutCurrentSplat(grw(0.5));
    let states = toy_stationarity_test(&target, &bad, &StationarityParams::new(10_000, 20, 6));
    eprintln!("without the current-state splat: stationarity of states {states}");
    states.assert_passes("states of MH without the current-state splat", SPLAT_TESTS);
    let report = check(
        "uniform mixture / without the current-state splat",
        &target,
        &bad,
        6,
    );
    assert!(report.mean_total_weight < 0.9, "{report}");
    assert!(report.p_value < OVERWHELMING, "{report}");
}

/// (b) Forced acceptance splatting only the accepted state with weight 1: after
/// `max_rejections = 0` rejections (i.e. at once) the candidate is accepted whatever its
/// density, and splatted with weight 1. One step from `pi` then splats `pi q`, not `pi`.
#[test]
fn forced_acceptance_with_weight_one_fails() {
    let target = UniformMixture::rioux_lavoie2020();
    let bad = SplatFinalState(ForcedAcceptance::new(grw(0.5), 0));
    let report = check(
        "uniform mixture / forced acceptance, weight 1",
        &target,
        &bad,
        7,
    );
    assert!(report.p_value < OVERWHELMING, "{report}");
    // The same bug on the torus target (forced acceptance takes candidates of positive
    // density only, so the weight stays on the torus but drifts out of the modes).
    let bad = SplatFinalState(ForcedAcceptance::new(grw(0.1), 0));
    let report = check(
        "torus mixture / forced acceptance, weight 1",
        &TorusMixture::across_seam(),
        &bad,
        8,
    );
    assert!(report.p_value < OVERWHELMING, "{report}");
}
