//! Lazy PSS mutation leaves the target invariant when the set of coordinates the target reads
//! depends on the state (`docs/methods/pssmlt-mmlt.md`, "Why lazy PSS is exact"): stationarity
//! from exact starts for the Kelemen small step, the Gaussian small step and the PSSMLT
//! mixture, on two targets of `pss::testing` whose read set varies, and a broken proposal fails
//! the same test.
//!
//! Run with `cargo test -p pss --release --test read_set_stationarity -- --nocapture` to see
//! every statistic and p-value.
//!
//! # Setup
//! Targets (`pss::testing`): `Stripes` reads `u1` only when `u0` lies in one of four stripes
//! (one across the torus seam), where the density is high or low on bands of `u1`;
//! `RoulettePath` reads `u_0, u_1, ...` until a coordinate leaves a continuation region that
//! straddles the seam, with density a product of per-coordinate factors. Each start is a fully
//! materialised exact draw from pi (`PssState::from_values`; the roulette path also stores two
//! unread coordinates after the path); each chain then runs [`STEPS`] steps of MH with the
//! *lazy* proposal, as a renderer does: the candidate is a copy with a pending mutation, and
//! coordinates are brought up to date only when the target reads them. A chain outside the
//! stripes (or with a short path) leaves `u1` (or `u_L`) unread for many accepted steps, and
//! candidates that read it again are often rejected: exactly the situation where a lazy state
//! that re-draws the current state's stale coordinates at every proposal is biased (the bug the
//! exact lazy state fixed). The final states are binned by the targets' exact bins, which bring
//! the coordinates they look at up to date (for `Stripes` that includes `u1` where the target
//! does not read it: it must be uniform there).
//!
//! Kernels: Kelemen 2002's exponential small step (`[1/1024, 1/64]`), pbrt-v3's wrapped
//! Gaussian small step (sigma 0.01), and the PSSMLT mixture of the Kelemen small step with the
//! large step (`p_large = 0.3`). Positive controls: the same small steps made eager
//! (`pss::testing::Eager`: every stored coordinate of the candidate is perturbed when it is
//! proposed) on `Stripes`.
//!
//! # Sizes
//! [`STARTS`] = 10^5 chains of [`STEPS`] = 100 steps. The bias of re-drawn coordinates builds
//! up over the run (each re-drawing proposal from a stale state adds some), and the large-step
//! mixture dilutes it (30% of its proposals ignore the current state). With these sizes the
//! pre-fix lazy state (commit 5677c34, which re-drew stale coordinates at every proposal)
//! failed every lazy test here: chi2 = 4598 (Kelemen), 6994 (Gaussian) and 129.4
//! (PSSMLT, p = 5.6e-14) with 31 dof on `Stripes`; chi2 = 3882 (Kelemen), 2952 (Gaussian)
//! and 672 (PSSMLT, p = 3.2e-79) with 116 dof on `RoulettePath`; the eager controls passed.
//! Each test takes a few seconds.
//!
//! # Statistics
//! If the kernel preserves pi, the final states of independent chains from independent exact
//! starts are i.i.d. from pi, so Pearson's statistic (bins pooled to expected count >= 5) is
//! asymptotically chi-square and the p-value uniform. This file runs [`CHI_SQUARE_TESTS`]
//! tests that must pass (two exact-sampler checks, six lazy kernels, two eager kernels, the
//! honest regional Gaussian, two splat-weight checks), each at the Sidak level
//! `1 - 0.99^(1/13) = 7.7e-4`, so the probability that any correct kernel fails is 0.01. Seeds are fixed: deterministic. The
//! negative control must reach p < [`OVERWHELMING`] = 1e-6.

use mcmc_core::testing::{
    sidak_alpha, ChiSquareReport, SplatParams, StationarityParams, TreatedAsSymmetric, ALPHA,
};
use mcmc_core::{Chain, Kernel, Mh, NoAdaptation};
use pss::testing::{
    exact_sampler_test, pss_splat_weight_test, pss_stationarity_test, Eager, ExactPssTarget,
    RegionalGaussian, RoulettePath, Stripes,
};
use pss::{KelemenParams, PssmltProposal, SmallMutation, SmallStep};
use rand::SeedableRng;
use rand_pcg::Pcg64;

/// Chi-square tests in this file that must pass, for the Sidak correction. Keep in sync.
const CHI_SQUARE_TESTS: usize = 13;

/// Independent exact starts per stationarity test.
const STARTS: usize = 100_000;

/// Kernel steps per start.
const STEPS: u64 = 100;

/// p-value below which a broken kernel counts as caught.
const OVERWHELMING: f64 = 1e-6;

fn kelemen() -> SmallStep {
    SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap())
}

fn gaussian() -> SmallStep {
    SmallStep::new(SmallMutation::gaussian(0.01).unwrap())
}

fn pssmlt() -> PssmltProposal {
    PssmltProposal::new(kelemen(), 0.3).unwrap()
}

/// Acceptance rate of one 4000-step chain from an exact start. A kernel that never moves
/// passes any stationarity test, and one that never rejects cannot show the bias this file
/// is about, so each kernel must accept at least 5% and reject at least 1% of its proposals
/// (one rejection per chain of [`STEPS`] steps on average; the small steps on `Stripes`
/// reject 2-4%, inside a band most moves are accepted).
fn acceptance<T, K>(target: &T, kernel: &K, seed: u64) -> f64
where
    T: ExactPssTarget,
    K: Kernel<T> + Clone,
{
    let mut rng = Pcg64::seed_from_u64(seed);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(target, kernel.clone(), NoAdaptation, rng, start).unwrap();
    chain.run(4000, &mut ()).unwrap();
    chain.stats().acceptance_rate()
}

/// Stationarity from exact starts, with the acceptance rate checked and everything printed.
fn stationarity<T, K>(what: &str, target: &T, kernel: &K, seed: u64) -> ChiSquareReport
where
    T: ExactPssTarget,
    K: Kernel<T> + Clone,
{
    let rate = acceptance(target, kernel, seed);
    assert!(
        (0.05..=0.99).contains(&rate),
        "{what}: acceptance rate {rate}"
    );
    let report = pss_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!("{what}: acceptance {rate:.3}; stationarity {report}");
    report
}

fn check<T, K>(what: &str, target: &T, kernel: &K, seed: u64)
where
    T: ExactPssTarget,
    K: Kernel<T> + Clone,
{
    stationarity(what, target, kernel, seed).assert_passes(what, CHI_SQUARE_TESTS);
}

/// The exact samplers agree with the exact bins (whose agreement with the evaluated densities
/// the targets' unit tests check).
#[test]
fn exact_samplers_match_their_bins() {
    for (what, report) in [
        (
            "stripes",
            exact_sampler_test(&Stripes::default(), STARTS, 1),
        ),
        (
            "roulette path",
            exact_sampler_test(&RoulettePath::default(), STARTS, 2),
        ),
    ] {
        eprintln!("{what} exact sampler: {report}");
        report.assert_passes(what, CHI_SQUARE_TESTS);
    }
}

#[test]
fn lazy_kelemen_keeps_pi_on_stripes() {
    check(
        "stripes / lazy Kelemen",
        &Stripes::default(),
        &Mh::new(kelemen()),
        10,
    );
}

#[test]
fn lazy_gaussian_keeps_pi_on_stripes() {
    check(
        "stripes / lazy Gaussian 0.01",
        &Stripes::default(),
        &Mh::new(gaussian()),
        11,
    );
}

#[test]
fn lazy_pssmlt_keeps_pi_on_stripes() {
    check(
        "stripes / lazy PSSMLT (Kelemen, p_large 0.3)",
        &Stripes::default(),
        &Mh::new(pssmlt()),
        12,
    );
}

#[test]
fn lazy_kelemen_keeps_pi_on_roulette_paths() {
    check(
        "roulette / lazy Kelemen",
        &RoulettePath::default(),
        &Mh::new(kelemen()),
        20,
    );
}

#[test]
fn lazy_gaussian_keeps_pi_on_roulette_paths() {
    check(
        "roulette / lazy Gaussian 0.01",
        &RoulettePath::default(),
        &Mh::new(gaussian()),
        21,
    );
}

#[test]
fn lazy_pssmlt_keeps_pi_on_roulette_paths() {
    check(
        "roulette / lazy PSSMLT (Kelemen, p_large 0.3)",
        &RoulettePath::default(),
        &Mh::new(pssmlt()),
        22,
    );
}

/// Positive controls: the same small steps made eager pass on the same target, so a failure
/// of the lazy tests above is a failure of laziness, not of the target, its bins or the test.
#[test]
fn eager_small_steps_keep_pi_on_stripes() {
    check(
        "stripes / eager Kelemen",
        &Stripes::default(),
        &Mh::new(Eager(kelemen())),
        30,
    );
    check(
        "stripes / eager Gaussian 0.01",
        &Stripes::default(),
        &Mh::new(Eager(gaussian())),
        31,
    );
}

/// Negative control: an asymmetric proposal (a Gaussian whose sigma depends on the region of
/// `u0`) passes with its Hastings term and fails the same test when treated as symmetric.
#[test]
fn asymmetric_proposal_treated_as_symmetric_fails() {
    let target = Stripes::default();
    let honest = RegionalGaussian::new(0.03, 0.2).unwrap();
    check("stripes / regional Gaussian", &target, &Mh::new(honest), 40);
    let bad = Mh::new(TreatedAsSymmetric(honest));
    let report = stationarity(
        "stripes / regional Gaussian treated as symmetric",
        &target,
        &bad,
        41,
    );
    assert!(report.p_value < OVERWHELMING, "{report}");
    assert!(report.rejects(sidak_alpha(ALPHA, CHI_SQUARE_TESTS)));
}

/// The observer contract on read-set targets: one lazy PSSMLT step from each exact start
/// splats `1 - a` on the current state and `a` on the (lazily evaluated) candidate, and the
/// splat-weighted histogram matches pi (the harness's splat-weight statistic, `mcmc_core::testing`).
#[test]
fn lazy_pssmlt_splat_weights_keep_the_contract() {
    let params = SplatParams::new(STARTS, 50);
    let report = pss_splat_weight_test(&Stripes::default(), &Mh::new(pssmlt()), &params);
    eprintln!("stripes / lazy PSSMLT splat weights: {report}");
    report.assert_passes("stripes / lazy PSSMLT splat weights", CHI_SQUARE_TESTS);
    let params = SplatParams::new(STARTS, 51);
    let report = pss_splat_weight_test(&RoulettePath::default(), &Mh::new(pssmlt()), &params);
    eprintln!("roulette / lazy PSSMLT splat weights: {report}");
    report.assert_passes("roulette / lazy PSSMLT splat weights", CHI_SQUARE_TESTS);
}
