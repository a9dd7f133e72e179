//! Negative controls: each deliberately broken kernel FAILS the harness on a setup where the
//! correct kernel passes, so the harness demonstrably catches these bugs.
//!
//! Thresholds: a broken kernel must fail *overwhelmingly*: its finite-state asymmetry must
//! exceed `1e-3` (the correct kernel's is at rounding level, below `1e-12`), and its
//! stationarity p-value must be below `1e-6` (a correct kernel gets there with probability
//! `1e-6`). The correct kernels' stationarity tests ([`STATIONARITY_TESTS`] of them in this
//! file) pass at the Sidak level for alpha = 0.01.

use std::panic::{catch_unwind, AssertUnwindSafe};

use mcmc_core::testing::{
    assert_finite_state_balance, assert_hastings_consistent, assert_pairwise_balance,
    assert_symmetric_proposal, finite_state_check, grid_centres, toy_stationarity_test,
    AsymmetricWalk, ForcedAcceptance, MhWithoutHastings, PairwiseParams, StationarityParams,
    TreatedAsSymmetric,
};
use mcmc_core::toy::{PiecewiseConstant, ToyTarget, UniformMixture};
use mcmc_core::{GaussianRandomWalk, Kernel, Mh};
use proptest::prelude::*;

/// Stationarity tests of *correct* kernels in this file (Sidak correction).
const STATIONARITY_TESTS: usize = 3;

/// p-value below which a broken kernel counts as caught.
const OVERWHELMING: f64 = 1e-6;

/// Minimum finite-state asymmetry of a broken kernel (9 orders above the tolerance).
const GROSS_ASYMMETRY: f64 = 1e-3;

/// The setup shared by the asymmetric-proposal controls: the DR paper's mixture of uniforms
/// and a drifting walk whose scale grows to the right.
fn setup() -> (UniformMixture, AsymmetricWalk) {
    (
        UniformMixture::rioux_lavoie2020(),
        AsymmetricWalk::new(0.2, 0.05, 0.5).unwrap(),
    )
}

fn states() -> impl Strategy<Value = Vec<f64>> + Clone {
    prop::collection::vec(-0.15..1.05f64, 1)
}

/// Runs `f`, which must panic with a message containing `needle`.
fn assert_fails(what: &str, needle: &str, f: impl FnOnce()) {
    let err = catch_unwind(AssertUnwindSafe(f)).expect_err(what);
    let msg = err
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| err.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_default();
    assert!(msg.contains(needle), "{what}: unexpected failure {msg}");
    eprintln!(
        "{what}: caught as expected: {}",
        msg.lines().next().unwrap_or("")
    );
}

fn finite_state_asymmetry<K: Kernel<UniformMixture>>(target: &UniformMixture, kernel: &K) -> f64 {
    let (lo, hi) = target.bounding_box();
    let (cells, volume) = grid_centres(&lo, &hi, &[22]);
    finite_state_check(target, kernel, &cells, volume).max_asymmetry
}

#[test]
fn asymmetric_proposal_treated_as_symmetric_fails() {
    let (target, walk) = setup();
    let params = PairwiseParams::with_seed(101);

    // The correct kernel passes every check on this setup.
    let good = Mh::new(walk);
    assert_pairwise_balance(&target, &good, states(), &params);
    let (lo, hi) = target.bounding_box();
    let (cells, volume) = grid_centres(&lo, &hi, &[22]);
    assert_finite_state_balance(&target, &good, &cells, volume);
    assert_hastings_consistent(&walk, states(), &params);
    let report = toy_stationarity_test(&target, &good, &StationarityParams::new(10_000, 50, 101));
    eprintln!("correct MH, asymmetric walk: {report}");
    report.assert_passes("correct MH with the asymmetric walk", STATIONARITY_TESTS);

    // The lie: Hastings term 0.
    let liar = TreatedAsSymmetric(walk);
    let bad = Mh::new(liar.clone());
    assert_fails("pairwise", "detailed balance violated", || {
        assert_pairwise_balance(&target, &bad, states(), &params);
    });
    let asym = finite_state_asymmetry(&target, &bad);
    eprintln!("treated as symmetric: finite-state asymmetry {asym:.3e}");
    assert!(asym > GROSS_ASYMMETRY, "asymmetry {asym}");
    assert_fails("finite-state", "is not symmetric", || {
        assert_finite_state_balance(&target, &bad, &cells, volume);
    });
    assert_fails("symmetry claim", "claims symmetry", || {
        assert_symmetric_proposal(&liar, states(), &params);
    });
    assert_fails("Hastings term", "transition densities give", || {
        assert_hastings_consistent(&liar, states(), &params);
    });
    let report = toy_stationarity_test(&target, &bad, &StationarityParams::new(10_000, 50, 101));
    eprintln!("treated as symmetric: {report}");
    assert!(report.p_value < OVERWHELMING, "{report}");
}

#[test]
fn missing_hastings_term_fails() {
    let (target, walk) = setup();
    let params = PairwiseParams::with_seed(102);
    // (The correct kernel on this setup passes: see the previous test.)
    let bad = MhWithoutHastings { proposal: walk };
    assert_fails("pairwise", "detailed balance violated", || {
        assert_pairwise_balance(&target, &bad, states(), &params);
    });
    let asym = finite_state_asymmetry(&target, &bad);
    eprintln!("missing Hastings: finite-state asymmetry {asym:.3e}");
    assert!(asym > GROSS_ASYMMETRY, "asymmetry {asym}");
    let good_asym = finite_state_asymmetry(&target, &Mh::new(walk));
    assert!(good_asym < 1e-12, "correct kernel asymmetry {good_asym}");
    let report = toy_stationarity_test(&target, &bad, &StationarityParams::new(10_000, 50, 102));
    eprintln!("missing Hastings: {report}");
    assert!(report.p_value < OVERWHELMING, "{report}");
}

#[test]
fn forced_acceptance_fails_stationarity() {
    // A random walk much wider than the spike: from the spike most candidates are rejected
    // (outside the support, or on the plateau with ratio 1/10), so forcing acceptance after
    // 2 rejections drains the spike.
    let target = UniformMixture::rioux_lavoie2020();
    let good = Mh::new(GaussianRandomWalk::new(0.5).unwrap());
    let bad = ForcedAcceptance::new(good.clone(), 2);
    let params = StationarityParams::new(10_000, 20, 103);

    let report = toy_stationarity_test(&target, &good, &params);
    eprintln!("correct MH: {report}");
    report.assert_passes("correct MH, forced-acceptance setup", STATIONARITY_TESTS);

    let report = toy_stationarity_test(&target, &bad, &params);
    eprintln!("forced acceptance: {report}");
    assert!(report.p_value < OVERWHELMING, "{report}");

    // The pairwise check cannot see this bug: the wrapper reports the inner kernel's flows.
    // Stationarity is the check that covers kernels with hidden state.
    assert_pairwise_balance(&target, &bad, states(), &PairwiseParams::with_seed(103));
}

#[test]
fn forced_acceptance_fails_with_holes() {
    // Same bug on the target with holes: a hole-jumping walk is rejected often near holes.
    let target = PiecewiseConstant::with_holes();
    let good = Mh::new(GaussianRandomWalk::new(0.2).unwrap());
    let bad = ForcedAcceptance::new(good.clone(), 1);
    let params = StationarityParams::new(10_000, 20, 104);
    let report = toy_stationarity_test(&target, &good, &params);
    eprintln!("correct MH (holes): {report}");
    report.assert_passes("correct MH, holes", STATIONARITY_TESTS);
    let report = toy_stationarity_test(&target, &bad, &params);
    eprintln!("forced acceptance (holes): {report}");
    assert!(report.p_value < OVERWHELMING, "{report}");
}
