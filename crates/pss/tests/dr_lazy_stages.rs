//! Tierney-Mira delayed rejection over *lazy* PSS small steps is exact on a target whose read
//! set depends on the state: the kernel brings lazy candidates up to date
//! (`mcmc_core::Point::catch_up_with`) before its second-stage ratio reads first-stage
//! densities of whole states (DR paper eq. 6-7; docs/methods/drmlt.md).
//!
//! # Setup
//! Target: `pss::testing::Stripes::narrow()` (reads `u1` only when `u0` lies in one of 16
//! stripes of width 1/32, one across the torus seam; half the mass in the stripes). Kernel:
//! `DelayedRejection::tierney_mira` with a lazy Gaussian small step (sigma 0.05) as first
//! stage and the same step, from `x`, as second stage (`IndependentSecondStage`), declared
//! symmetric. The ratio holds `Q1(y | z) / Q1(y | x)` over every stored coordinate: where `y`
//! or `z` did not read `u1`, the lazy state stores the parent's stale value there, so without
//! the catch-up the ratio reads `u1`'s of `x` instead of the candidates'.
//!
//! Tests: the lazy kernel (must pass), the same kernel over `pss::testing::Eager` stages
//! (positive control: candidates materialised when proposed), and the negative control, the
//! lazy kernel with the catch-up switched off (`with_stale_densities`, the kernel before the
//! fix; must fail).
//!
//! # Statistics
//! [`STARTS`] exact starts (fully materialised), [`STEPS`] steps each; Pearson's chi-square
//! with one degree of freedom on the share of final states in the stripes
//! (`Stripes::stripe_bins`, exact probabilities 1/2 and 1/2). Under a kernel that preserves pi
//! the final states are i.i.d. from pi, so the p-value is uniform: each of the
//! [`PASSING_TESTS`] tests that must pass uses the Sidak level for a file-wide false-failure
//! probability of 0.01; the negative control must reject at the same level. Seeds are fixed.
//! The bias is small per step (the stale ratio differs from the eager one only by the
//! density of `u1`'s perturbations), hence the many starts; measured with these sizes: the
//! negative control's statistic is about 80 (p ~ 1e-19).

use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::testing::{sidak_alpha, stationarity_test, ChiSquareReport, StationarityParams};
use mcmc_core::{DelayedRejection, Kernel};
use pss::testing::{Eager, ExactPssTarget, Stripes};
use pss::{SmallMutation, SmallStep};

/// Independent exact starts per test.
const STARTS: usize = 400_000;
/// Steps per start.
const STEPS: u64 = 20;
/// Tests in this file that must pass.
const PASSING_TESTS: usize = 2;

fn small() -> SmallStep {
    SmallStep::new(SmallMutation::Gaussian { sigma: 0.05 })
}

fn stripe_share<K: Kernel<Stripes> + Clone>(what: &str, kernel: &K, seed: u64) -> ChiSquareReport {
    let target = Stripes::narrow();
    let report = stationarity_test(
        &target,
        kernel,
        |rng| target.sample_exact(rng),
        &target.stripe_bins(),
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!("{what}: {report}");
    report
}

#[test]
fn tierney_mira_over_lazy_small_steps_keeps_pi() {
    let kernel = DelayedRejection::tierney_mira(small(), IndependentSecondStage(small()))
        .with_symmetric_second_stage();
    stripe_share("lazy stages", &kernel, 1).assert_passes("lazy stages", PASSING_TESTS);
}

#[test]
fn tierney_mira_over_eager_small_steps_keeps_pi() {
    let kernel =
        DelayedRejection::tierney_mira(Eager(small()), IndependentSecondStage(Eager(small())))
            .with_symmetric_second_stage();
    stripe_share("eager stages", &kernel, 2).assert_passes("eager stages", PASSING_TESTS);
}

#[test]
fn negative_control_stale_densities_fail() {
    let kernel = DelayedRejection::tierney_mira(small(), IndependentSecondStage(small()))
        .with_symmetric_second_stage()
        .with_stale_densities();
    let report = stripe_share("negative control (stale densities)", &kernel, 3);
    assert!(report.rejects(sidak_alpha(0.01, PASSING_TESTS)), "{report}");
}
