//! Two-stage delayed rejection (issue 9) through the mcmc-core harness: each acceptance rule
//! (Tierney-Mira, Green-Mira, orbital) passes the pairwise flow check, the exact finite-state
//! check where it applies, chi-square stationarity from exact starts (including a lazily
//! materialised state whose read set depends on the state, and mass across the torus seam) and
//! the splat-weight check; each check has a negative control that fails it. Then the two
//! measured claims of the DR paper: Tierney-Mira's vanishing second-stage acceptance after a
//! Kelemen first stage versus the orbital rule (section 4.3), and the 1-D toy of Fig. 3 where
//! DR has a lower integrated autocorrelation time than both single-stage kernels.
//!
//! Run with `cargo test -p mcmc-core --release --test delayed_rejection -- --nocapture` to see
//! every statistic (docs/methods/drmlt.md quotes them).
//!
//! # Statistics
//! Pairwise and finite-state checks are identities, checked to rounding (`1e-9` and `1e-12`
//! relative). Stationarity tests: independent exact starts, so the final states are i.i.d.
//! from pi under a correct kernel and Pearson's p-value is uniform. Splat-weight tests:
//! Hotelling's statistic of the mean splat-weighted histogram, asymptotically chi-square
//! (`mcmc_core::testing::splat_weights`). Comparisons (vanishing acceptance, autocorrelation
//! times): one-sided Welch z-tests on per-chain means of independent chains, which must reject
//! "no improvement". All [`STAT_TESTS`] of them run at the Sidak level
//! `1 - (1 - ALPHA)^(1/STAT_TESTS)` with `ALPHA = 0.01`: a correct kernel fails a stationarity
//! or splat test with probability at most 0.01 overall. Negative controls must reach
//! `p < 1e-6` ([`OVERWHELMING`]) or a finite-state asymmetry above `1e-6`
//! ([`GROSS_ASYMMETRY`], six orders above the check's tolerance; two-stage flows enter the
//! matrix with the factor `c^2 h^2`, so second-stage bugs show up smaller than first-stage
//! ones). Seeds are fixed: the outcome is deterministic.

#[path = "delayed_rejection/fixtures.rs"]
mod fixtures;

use std::cell::Cell;
use std::f64::consts::{FRAC_PI_6, PI};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;

use fixtures::{
    DisplacementBug, FourStates, LazyStripes, LazyTorus, OnLazy, OtherState, ProductKelemen,
    Ridges, ThirdState, FOUR,
};
use mcmc_core::delayed_rejection::{
    IndependentSecondStage, OrbitalWalk, RadialKelemen, WrappedCauchy, WrappedGaussianWalk,
};
use mcmc_core::proposal::{ConditionalProposal, FixedSelection};
use mcmc_core::stats::{integrated_autocorrelation_time, AcceptanceStats};
use mcmc_core::testing::broken::PaperSplatWeights;
use mcmc_core::testing::{
    assert_finite_state_balance, assert_pairwise_balance, assert_path_balance, finite_state_check,
    grid_centres, sidak_alpha, splat_weight_test, stationarity_test, toy_splat_weight_test,
    toy_stationarity_test, AsymmetricWalk, ChiSquareReport, FnBins, PairwiseParams, SplatParams,
    SplatWeightReport, StationarityParams, ThresholdSelection, ALPHA,
};
use mcmc_core::toy::special::normal_cdf;
use mcmc_core::toy::{wrap, Ridge, TorusMixture, ToyTarget, UniformMixture};
use mcmc_core::{
    Chain, DelayedRejection, Euclidean, GaussianRandomWalk, Kernel, Mh, Mixture, NoAdaptation,
    Observer, Proposed, StepInfo, Torus,
};
use proptest::prelude::*;
use proptest::strategy::BoxedStrategy;
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// Statistical tests in this file that must pass (Sidak correction): 11 stationarity tests,
/// 4 splat-weight tests, 3 vanishing-acceptance comparisons, 2 autocorrelation comparisons.
/// Keep in sync.
const STAT_TESTS: usize = 20;

/// Independent exact starts per stationarity test, and steps per start.
const STARTS: usize = 10_000;
const STEPS: u64 = 20;

/// Exact starts per lazy-state stationarity test (100 steps each; the controls use twice
/// as many).
const LAZY_STARTS: usize = 50_000;

/// Exact starts per splat-weight test (the 4-state toy uses ten times more).
const SPLAT_STARTS: usize = 20_000;

/// p-value below which a broken kernel counts as caught.
const OVERWHELMING: f64 = 1e-6;

/// Minimum finite-state asymmetry of a broken kernel.
const GROSS_ASYMMETRY: f64 = 1e-6;

/// The Sidak level of each statistical test of the file.
fn level() -> f64 {
    sidak_alpha(ALPHA, STAT_TESTS)
}

fn grw(sigma: f64) -> GaussianRandomWalk {
    GaussianRandomWalk::new(sigma).unwrap()
}

fn wrapped(sigma: f64) -> WrappedGaussianWalk {
    WrappedGaussianWalk::new(sigma).unwrap()
}

fn rho() -> f64 {
    WrappedCauchy::rioux_lavoie2020().rho()
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
    eprintln!("{what}: caught: {}", msg.lines().next().unwrap_or(""));
}

// ---- kernels ----

type Tm<P1, P2> = DelayedRejection<P1, IndependentSecondStage<P2>>;

/// The Fig. 3 setup: a bold first stage tuned to the plateau (`sigma = beta = 1`), a timid
/// second stage tuned to the spike (`sigma = alpha = 1/10`).
fn tm_fig3() -> Tm<GaussianRandomWalk, GaussianRandomWalk> {
    DelayedRejection::tierney_mira(grw(1.0), IndependentSecondStage(grw(0.1)))
        .with_symmetric_second_stage()
}

/// Tierney-Mira with an asymmetric second stage (drift, state-dependent scale): the `Q2`
/// terms of eq. 6 matter.
fn tm_asymmetric() -> Tm<GaussianRandomWalk, AsymmetricWalk> {
    DelayedRejection::tierney_mira(
        grw(0.2),
        IndependentSecondStage(AsymmetricWalk::new(0.5, 0.05, 0.5).unwrap()),
    )
}

/// A small/large first-stage mixture with state-dependent selection; the second stage runs
/// only after a rejected small step (component 0).
type MixtureKernel = Tm<Mixture<GaussianRandomWalk, ThresholdSelection>, GaussianRandomWalk>;

fn tm_mixture() -> MixtureKernel {
    let first = Mixture::new(
        vec![grw(0.05), grw(0.8)],
        ThresholdSelection::new(0.0, &[0.8, 0.2], &[0.3, 0.7]).unwrap(),
    )
    .unwrap();
    DelayedRejection::tierney_mira(first, IndependentSecondStage(grw(0.02)))
        .with_symmetric_second_stage()
        .second_stage_after(&[0])
        .unwrap()
}

fn gm_ridge(
) -> DelayedRejection<GaussianRandomWalk, IndependentSecondStage<GaussianRandomWalk>, Euclidean> {
    DelayedRejection::green_mira(grw(0.5), IndependentSecondStage(grw(0.05)), Euclidean)
        .with_symmetric_second_stage()
}

fn gm_torus(
) -> DelayedRejection<WrappedGaussianWalk, IndependentSecondStage<WrappedGaussianWalk>, Torus> {
    DelayedRejection::green_mira(wrapped(0.15), IndependentSecondStage(wrapped(0.03)), Torus)
}

fn tm_torus() -> Tm<WrappedGaussianWalk, WrappedGaussianWalk> {
    DelayedRejection::tierney_mira(wrapped(0.15), IndependentSecondStage(wrapped(0.03)))
        .with_symmetric_second_stage()
}

fn orbital_torus() -> DelayedRejection<RadialKelemen, OrbitalWalk> {
    DelayedRejection::orbital(
        RadialKelemen::on_torus(0.01, 0.3).unwrap(),
        OrbitalWalk::on_torus(rho()).unwrap(),
    )
}

fn orbital_ridge() -> DelayedRejection<RadialKelemen, OrbitalWalk> {
    DelayedRejection::orbital(
        RadialKelemen::new(0.02, 0.8).unwrap(),
        OrbitalWalk::new(rho()).unwrap(),
    )
}

// ---- 1. pairwise flow balance ----

/// States uniform on a toy's bounding box enlarged by `margin` on each side.
fn box_states<T: ToyTarget>(target: &T, margin: f64) -> BoxedStrategy<Vec<f64>> {
    let (lo, hi) = target.bounding_box();
    let ranges: Vec<_> = lo
        .iter()
        .zip(&hi)
        .map(|(&l, &h)| (l - margin * (h - l))..(h + margin * (h - l)))
        .collect();
    ranges.boxed()
}

/// Triples on the uniform mixture with `x`, `z` in the support and `y` anywhere wider: a
/// triple's flow is nonzero only if `y` can be rejected from both ends.
fn uniform_triples() -> impl Strategy<Value = Vec<Vec<f64>>> {
    (-0.1..1.0f64, -1.0..2.0f64, -0.1..1.0f64).prop_map(|(x, y, z)| vec![vec![x], vec![y], vec![z]])
}

/// Orbit-constrained triples in the plane (or on the torus): `y = x + d (cos phi, sin phi)`
/// with `d` around the first stage's range, `z` on the circle centred at `y` through `x` at
/// angle offset `theta`.
fn orbit_triples(lo: f64, hi: f64, d_max: f64, torus: bool) -> BoxedStrategy<Vec<Vec<f64>>> {
    let place = move |v: f64| if torus { wrap(v) } else { v };
    ((lo..hi, lo..hi), 0.005..d_max, -PI..PI, -PI..PI)
        .prop_map(move |((x0, x1), d, phi, theta)| {
            let y = [x0 + d * phi.cos(), x1 + d * phi.sin()];
            let (w0, w1) = (x0 - y[0], x1 - y[1]);
            let (c, s) = (theta.cos(), theta.sin());
            let z = [y[0] + c * w0 - s * w1, y[1] + s * w0 + c * w1];
            vec![
                vec![x0, x1],
                vec![place(y[0]), place(y[1])],
                vec![place(z[0]), place(z[1])],
            ]
        })
        .boxed()
}

fn low_bar(seed: u64) -> PairwiseParams {
    PairwiseParams {
        min_informative: 0.05,
        ..PairwiseParams::with_seed(seed)
    }
}

#[test]
fn pairwise_tierney_mira() {
    let target = UniformMixture::rioux_lavoie2020();
    let states = box_states(&target, 0.05);
    for (what, seed) in [("asymmetric Q2", 11u64), ("mixture first stage", 12)] {
        let (pairs, triples) = if seed == 11 {
            let k = tm_asymmetric();
            (
                assert_pairwise_balance(&target, &k, states.clone(), &low_bar(seed)),
                assert_path_balance(
                    &target,
                    &k,
                    uniform_triples(),
                    &PairwiseParams::with_seed(seed),
                ),
            )
        } else {
            let k = tm_mixture();
            (
                assert_pairwise_balance(&target, &k, states.clone(), &low_bar(seed)),
                assert_path_balance(
                    &target,
                    &k,
                    uniform_triples(),
                    &PairwiseParams::with_seed(seed),
                ),
            )
        };
        eprintln!(
            "Tierney-Mira ({what}): random pairs+triples {}/{} informative, targeted triples \
             {}/{} (worst {:.1e})",
            pairs.informative,
            pairs.cases,
            triples.informative,
            triples.cases,
            triples.worst_log_difference
        );
    }
    // Negative control: the asymmetric second stage declared symmetric (eq. 7 where it does
    // not apply).
    let bad = tm_asymmetric().with_symmetric_second_stage();
    assert_fails(
        "TM with a wrongly symmetric Q2",
        "detailed balance violated",
        || {
            assert_path_balance(
                &target,
                &bad,
                uniform_triples(),
                &PairwiseParams::with_seed(13),
            );
        },
    );
}

#[test]
fn pairwise_green_mira() {
    let ridge = Ridge::thin();
    let asymmetric = DelayedRejection::green_mira(
        grw(0.5),
        IndependentSecondStage(AsymmetricWalk::new(0.1, 0.02, 0.5).unwrap()),
        Euclidean,
    );
    let r = assert_pairwise_balance(&ridge, &asymmetric, box_states(&ridge, 0.0), &low_bar(21));
    eprintln!(
        "Green-Mira on the ridge (asymmetric Q2): {}/{} informative (worst {:.1e})",
        r.informative, r.cases, r.worst_log_difference
    );
    let torus = TorusMixture::across_seam();
    let r = assert_pairwise_balance(&torus, &gm_torus(), box_states(&torus, 0.0), &low_bar(22));
    eprintln!(
        "Green-Mira on the torus: {}/{} informative (worst {:.1e})",
        r.informative, r.cases, r.worst_log_difference
    );
    // Negative control: a ghost that is not an involution.
    let bad = DelayedRejection::green_mira(
        wrapped(0.15),
        IndependentSecondStage(wrapped(0.03)),
        DisplacementBug,
    );
    assert_fails(
        "Green-Mira with y* = z - y",
        "detailed balance violated",
        || {
            assert_pairwise_balance(&torus, &bad, box_states(&torus, 0.0), &low_bar(23));
        },
    );
}

#[test]
fn pairwise_orbital() {
    let ridge = Ridge::thin();
    let kernel = orbital_ridge();
    // Pairs at first-stage distances (the first two states of orbit triples).
    let pairs = orbit_triples(-1.5, 1.5, 0.9, false).prop_map(|t| t[..2].to_vec());
    assert_path_balance(&ridge, &kernel, pairs, &PairwiseParams::with_seed(31));
    let r = assert_path_balance(
        &ridge,
        &kernel,
        orbit_triples(-1.5, 1.5, 0.9, false),
        &low_bar(31),
    );
    eprintln!(
        "orbital on the ridge: orbit triples {}/{} informative (worst {:.1e})",
        r.informative, r.cases, r.worst_log_difference
    );
    let torus = TorusMixture::across_seam();
    let kernel = orbital_torus();
    let r = assert_path_balance(
        &torus,
        &kernel,
        orbit_triples(0.0, 1.0, 0.32, true),
        &low_bar(32),
    );
    eprintln!(
        "orbital on the torus: orbit triples {}/{} informative (worst {:.1e})",
        r.informative, r.cases, r.worst_log_difference
    );
    // Negative control: the orbital rule with a second stage off the orbit (eq. 11 drops a
    // Q1 ratio that is not 1 there).
    let bad = DelayedRejection::orbital(grw(0.3), IndependentSecondStage(grw(0.1)));
    assert_fails(
        "orbital rule off the orbit",
        "detailed balance violated",
        || {
            assert_pairwise_balance(&ridge, &bad, box_states(&ridge, 0.0), &low_bar(33));
        },
    );
}

// ---- 2. the exact finite-state check ----

#[test]
fn finite_state_tierney_mira() {
    let target = UniformMixture::rioux_lavoie2020();
    let (lo, hi) = target.bounding_box();
    let (cells, volume) = grid_centres(&lo, &hi, &[22]);
    let a = assert_finite_state_balance(&target, &tm_asymmetric(), &cells, volume);
    let b = assert_finite_state_balance(&target, &tm_mixture(), &cells, volume);
    let four = [0.0, 1.0, 2.0, 3.0];
    let kernel = DelayedRejection::tierney_mira(OtherState, ThirdState);
    let c = assert_finite_state_balance(&FourStates, &kernel, &four, 1.0);
    eprintln!(
        "finite-state Tierney-Mira: asymmetric Q2 {:.1e}, mixture {:.1e}, 4 states {:.1e}",
        a.max_asymmetry, b.max_asymmetry, c.max_asymmetry
    );
    let bad = tm_asymmetric().with_symmetric_second_stage();
    let asym = finite_state_check(&target, &bad, &cells, volume).max_asymmetry;
    eprintln!("finite-state, wrongly symmetric Q2: asymmetry {asym:.2e}");
    assert!(asym > GROSS_ASYMMETRY, "{asym}");
}

/// Green-Mira on a uniform 10 x 10 grid of the torus: the ghost map permutes the grid, so
/// the two-stage sum of the finite-state check is exact.
#[test]
fn finite_state_green_mira_on_a_torus_grid() {
    let target = TorusMixture::across_seam();
    let (cells, volume) = grid_centres(&[0.0, 0.0], &[1.0, 1.0], &[10, 10]);
    let r = assert_finite_state_balance(&target, &gm_torus(), &cells, volume);
    eprintln!(
        "finite-state Green-Mira on the torus: {} states, asymmetry {:.1e}, pi K error {:.1e}",
        r.states, r.max_asymmetry, r.max_stationarity_error
    );
    let bad = DelayedRejection::green_mira(
        wrapped(0.15),
        IndependentSecondStage(wrapped(0.03)),
        DisplacementBug,
    );
    let asym = finite_state_check(&target, &bad, &cells, volume).max_asymmetry;
    eprintln!("finite-state Green-Mira with y* = z - y: asymmetry {asym:.2e}");
    assert!(asym > GROSS_ASYMMETRY, "{asym}");
}

// ---- 3. stationarity from exact starts ----

fn stationary<T: ToyTarget, K: Kernel<T> + Clone>(what: &str, target: &T, kernel: &K, seed: u64) {
    let report = toy_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!("{what}: {report}");
    report.assert_passes(what, STAT_TESTS);
}

#[test]
fn stationarity_tierney_mira() {
    let target = UniformMixture::rioux_lavoie2020();
    stationary("uniform mixture / TM Fig. 3", &target, &tm_fig3(), 41);
    stationary(
        "uniform mixture / TM asymmetric Q2",
        &target,
        &tm_asymmetric(),
        42,
    );
    stationary(
        "uniform mixture / TM small-large mixture",
        &target,
        &tm_mixture(),
        43,
    );
    stationary(
        "torus mixture / TM wrapped",
        &TorusMixture::across_seam(),
        &tm_torus(),
        44,
    );
}

#[test]
fn stationarity_green_mira_and_orbital() {
    stationary("ridge / GM", &Ridge::thin(), &gm_ridge(), 45);
    let torus = TorusMixture::across_seam();
    stationary("torus mixture / GM torus", &torus, &gm_torus(), 46);
    stationary(
        "torus mixture / orbital torus",
        &torus,
        &orbital_torus(),
        47,
    );
    stationary("ridge / orbital", &Ridge::thin(), &orbital_ridge(), 48);
}

/// Negative control: the orbital rule after a Gaussian first stage with a Gaussian second
/// stage (no orbit): eq. 11 without its assumptions.
#[test]
fn stationarity_catches_the_orbital_rule_off_the_orbit() {
    let target = UniformMixture::rioux_lavoie2020();
    let bad = DelayedRejection::orbital(grw(0.2), IndependentSecondStage(grw(0.6)));
    let report = toy_stationarity_test(&target, &bad, &StationarityParams::new(STARTS, STEPS, 49));
    eprintln!("uniform mixture / orbital rule off the orbit: {report}");
    assert!(report.p_value < OVERWHELMING, "{report}");
}

type LazyKernel<P1, P2, G> = DelayedRejection<OnLazy<P1>, P2, G>;

fn lazy_test<const A: bool, K>(what: &str, kernel: &K, seed: u64, starts: usize) -> ChiSquareReport
where
    K: Kernel<LazyStripes<A>> + Clone,
{
    let target = LazyStripes::<A>;
    let report = stationarity_test(
        &target,
        kernel,
        |rng| target.sample_exact(rng),
        &target.bins(),
        &StationarityParams::new(starts, 100, seed),
    );
    eprintln!("lazy stripes / {what}: {report}");
    report
}

fn lazy_tm<const A: bool>() -> LazyKernel<
    WrappedGaussianWalk,
    OnLazy<IndependentSecondStage<WrappedGaussianWalk>>,
    mcmc_core::NoGhost,
> {
    DelayedRejection::tierney_mira(
        OnLazy(wrapped(0.05)),
        OnLazy(IndependentSecondStage(wrapped(0.05))),
    )
    .with_symmetric_second_stage()
}

fn lazy_orbital<const A: bool>(
) -> LazyKernel<RadialKelemen, OnLazy<OrbitalWalk>, mcmc_core::NoGhost> {
    DelayedRejection::orbital(
        OnLazy(RadialKelemen::on_torus(0.01, 0.1).unwrap()),
        OnLazy(OrbitalWalk::on_torus(rho()).unwrap()),
    )
}

/// Lazily materialised states (the read set depends on the state): every rule keeps the
/// target when the kernel absorbs what a rejected first-stage candidate drew before the
/// second stage proposes.
#[test]
fn stationarity_with_a_state_dependent_read_set() {
    lazy_test::<true, _>("TM", &lazy_tm::<true>(), 51, LAZY_STARTS)
        .assert_passes("lazy / TM", STAT_TESTS);
    let gm = DelayedRejection::green_mira(
        OnLazy(wrapped(0.05)),
        OnLazy(IndependentSecondStage(wrapped(0.05))),
        LazyTorus,
    )
    .with_symmetric_second_stage();
    lazy_test::<true, _>("GM", &gm, 52, LAZY_STARTS).assert_passes("lazy / GM", STAT_TESTS);
    lazy_test::<true, _>("orbital", &lazy_orbital::<true>(), 53, LAZY_STARTS)
        .assert_passes("lazy / orbital", STAT_TESTS);
}

/// Negative control: a state that never absorbs, so the second stage draws the unread
/// coordinate afresh and the ratio compares `y` and `z` at different values of it.
#[test]
fn stationarity_catches_a_second_stage_blind_to_the_rejected_draws() {
    let tm = lazy_test::<false, _>(
        "TM, no absorb (control)",
        &lazy_tm::<false>(),
        54,
        2 * LAZY_STARTS,
    );
    assert!(tm.p_value < OVERWHELMING, "{tm}");
    let orbital = lazy_test::<false, _>(
        "orbital, no absorb (control)",
        &lazy_orbital::<false>(),
        55,
        2 * LAZY_STARTS,
    );
    assert!(orbital.p_value < OVERWHELMING, "{orbital}");
}

// ---- 4. splat weights ----

fn splat<T: ToyTarget, K: Kernel<T> + Clone>(
    what: &str,
    target: &T,
    kernel: &K,
    seed: u64,
) -> SplatWeightReport {
    let report = toy_splat_weight_test(target, kernel, &SplatParams::new(SPLAT_STARTS, seed));
    eprintln!("{what}: {report}");
    report
}

fn four_state_splat<K: Kernel<FourStates> + Clone>(
    kernel: &K,
    starts: usize,
    seed: u64,
) -> SplatWeightReport {
    let bins = FnBins {
        probabilities: FOUR.to_vec(),
        bin_of: |x: &f64| fixtures::index(*x).unwrap(),
    };
    let sample = |rng: &mut Pcg64| {
        let u: f64 = rng.random();
        let mut cdf = 0.0;
        for (i, p) in FOUR.iter().enumerate() {
            cdf += p;
            if u < cdf {
                return i as f64;
            }
        }
        3.0
    };
    splat_weight_test(
        &FourStates,
        kernel,
        sample,
        &bins,
        &SplatParams::new(starts, seed),
    )
}

/// The exact expected splat of one step from `pi` on the 4-state toy, by enumeration, for the
/// unbiased scheme and for the paper's Fig. 8 weights (Tierney-Mira, uniform stages).
fn four_state_exact() -> ([f64; 4], [f64; 4]) {
    let (mut unbiased, mut paper) = ([0.0; 4], [0.0; 4]);
    for x in 0..4 {
        for y in (0..4).filter(|&y| y != x) {
            let w = FOUR[x] / 3.0;
            let a1 = (FOUR[y] / FOUR[x]).min(1.0);
            unbiased[y] += w * a1;
            paper[y] += w * a1 * a1;
            paper[x] += w * a1 * (1.0 - a1);
            for z in (0..4).filter(|&z| z != x && z != y) {
                let a1_zy = (FOUR[y] / FOUR[z]).min(1.0);
                let a2 = (FOUR[z] * (1.0 - a1_zy) / (FOUR[x] * (1.0 - a1))).min(1.0);
                let v = w * (1.0 - a1) / 2.0;
                unbiased[z] += v * a2;
                unbiased[x] += v * (1.0 - a2);
                paper[y] += v * a1;
                paper[z] += v * (1.0 - a1) * a2;
                paper[x] += v * (1.0 - a1) * (1.0 - a2);
            }
        }
    }
    (unbiased, paper)
}

/// The kernel's unbiased three-point splatting keeps the observer contract on the 4-state
/// Tierney-Mira toy; the paper's Fig. 8 weights do not (exactly: by enumeration; and through
/// the harness's statistical check).
#[test]
fn splat_weights_on_four_states() {
    let (unbiased, paper) = four_state_exact();
    for i in 0..4 {
        assert!((unbiased[i] - FOUR[i]).abs() < 1e-12, "{unbiased:?}");
    }
    let rel: Vec<String> = (0..4)
        .map(|i| format!("{:+.2}%", 100.0 * (paper[i] / FOUR[i] - 1.0)))
        .collect();
    eprintln!("4 states, exact expected splat / pi - 1 with the paper's weights: {rel:?}");
    assert!((0..4).any(|i| (paper[i] / FOUR[i] - 1.0).abs() > 0.01));

    let kernel = DelayedRejection::tierney_mira(OtherState, ThirdState);
    let good = four_state_splat(&kernel, 10 * SPLAT_STARTS, 61);
    eprintln!("4 states / TM, unbiased splats: {good}");
    good.assert_passes("4 states / TM", STAT_TESTS);
    let bad = four_state_splat(&PaperSplatWeights(kernel), 10 * SPLAT_STARTS, 62);
    eprintln!("4 states / TM, paper's weights: {bad}");
    assert!(bad.p_value < OVERWHELMING, "{bad}");
}

#[test]
fn splat_weights_on_toy_targets() {
    let uniform = UniformMixture::rioux_lavoie2020();
    splat(
        "uniform mixture / TM small-large mixture",
        &uniform,
        &tm_mixture(),
        63,
    )
    .assert_passes("uniform / TM mixture", STAT_TESTS);
    splat(
        "torus mixture / orbital",
        &TorusMixture::across_seam(),
        &orbital_torus(),
        64,
    )
    .assert_passes("torus / orbital", STAT_TESTS);
    splat(
        "ridge / GM (ghost never splatted)",
        &Ridge::thin(),
        &gm_ridge(),
        65,
    )
    .assert_passes("ridge / GM", STAT_TESTS);
}

// ---- 5. vanishing second-stage acceptance (section 4.3) ----

/// Counts second-stage proposals whose candidate `z` cannot reach the rejected `y` with the
/// first stage (`Q1(y | z) = 0`: the Tierney-Mira ratio vanishes, Fig. 4).
#[derive(Clone, Debug)]
struct CountVanished<Q, Q1> {
    inner: Q,
    first: Q1,
    counts: Rc<Cell<(u64, u64)>>,
}

impl<Q: ConditionalProposal<Vec<f64>>, Q1: mcmc_core::Proposal<Vec<f64>>>
    ConditionalProposal<Vec<f64>> for CountVanished<Q, Q1>
{
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &Vec<f64>,
        y: &Vec<f64>,
        z: &mut Vec<f64>,
        rng: &mut R,
    ) -> Proposed {
        let p = self.inner.propose(x, y, z, rng);
        let (vanished, total) = self.counts.get();
        let v = u64::from(self.first.log_q(z, y) == f64::NEG_INFINITY);
        self.counts.set((vanished + v, total + 1));
        p
    }
    fn log_q(&self, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        self.inner.log_q(x, y, z)
    }
}

/// Per-chain mean second-stage acceptance probability.
#[derive(Default)]
struct StageTwo {
    tried: u64,
    sum: f64,
}

impl<S, P> Observer<S, P> for StageTwo {
    fn step(&mut self, info: &StepInfo) {
        if info.stages_tried == 2 {
            self.tried += 1;
            self.sum += info.accept_prob[1];
        }
    }
}

/// Mean and standard error over `chains` independent chains (exact starts, 500 steps) of the
/// per-chain mean `a2`.
fn mean_a2<K: Kernel<Ridges> + Clone>(target: &Ridges, kernel: &K, seed: u64) -> (f64, f64) {
    let chains = 200;
    let means: Vec<f64> = (0..chains)
        .map(|i| {
            let mut rng = Pcg64::seed_from_u64(mcmc_core::seed::chain_seed(seed, i));
            let x0 = target.sample_exact(&mut rng);
            let mut chain = Chain::new(target, kernel.clone(), NoAdaptation, rng, x0).unwrap();
            let mut o = StageTwo::default();
            chain.run(500, &mut o).unwrap();
            o.sum / o.tried.max(1) as f64
        })
        .collect();
    mean_and_se(&means)
}

fn mean_and_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// The one-sided standard normal quantile `z` with `P(Z > z) = p` (bisection on the CDF).
fn upper_quantile(p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 40.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if 1.0 - normal_cdf(mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Asserts `big > small` by a one-sided Welch z-test at the file's Sidak level.
fn assert_greater(what: &str, big: (f64, f64), small: (f64, f64)) {
    let z = (big.0 - small.0) / (big.1 * big.1 + small.1 * small.1).sqrt();
    let z_crit = upper_quantile(level());
    eprintln!(
        "{what}: {:.4} +- {:.4} vs {:.4} +- {:.4}, z = {z:.1} (critical {z_crit:.2})",
        big.0, big.1, small.0, small.1
    );
    assert!(z > z_crit, "{what}: z = {z} <= {z_crit}");
}

/// Tierney-Mira after Kelemen's product mutation (eq. 9, bounds [1/1024, 1/64]) with the
/// reference implementation's timid Gaussian second stage (sigma = 1/640) against the orbital
/// rule after the pairwise polar Kelemen step (bounds x 1.9, rho = exp(-1/4)), on a thin ridge
/// at the Kelemen scale (across-sd 0.005), in 2-D and as 8 independent pairs (16-D).
#[test]
fn tierney_mira_vanishes_where_the_orbital_rule_does_not() {
    let ridge = Ridge::new(FRAC_PI_6, 0.2, 0.005).unwrap();
    let kelemen = ProductKelemen::kelemen2002();
    let mut results = Vec::new();
    for (pairs, seed) in [(1usize, 71u64), (8, 72)] {
        let target = Ridges { ridge, pairs };
        let counts = Rc::new(Cell::new((0, 0)));
        let tm = DelayedRejection::tierney_mira(
            kelemen,
            CountVanished {
                inner: IndependentSecondStage(grw(1.0 / 640.0)),
                first: kelemen,
                counts: counts.clone(),
            },
        )
        .with_symmetric_second_stage();
        let radial = RadialKelemen::new(1.9 / 1024.0, 1.9 / 64.0).unwrap();
        let orbit_counts = Rc::new(Cell::new((0, 0)));
        let orbital = DelayedRejection::orbital(
            radial,
            CountVanished {
                inner: OrbitalWalk::new(rho()).unwrap(),
                first: radial,
                counts: orbit_counts.clone(),
            },
        );
        let gm = DelayedRejection::green_mira(
            kelemen,
            IndependentSecondStage(grw(1.0 / 640.0)),
            Euclidean,
        )
        .with_symmetric_second_stage();
        let a_tm = mean_a2(&target, &tm, seed);
        let a_orbital = mean_a2(&target, &orbital, seed);
        let a_gm = mean_a2(&target, &gm, seed);
        let (v, n) = counts.get();
        let (vo, no) = orbit_counts.get();
        eprintln!(
            "{}-D ridge: mean a2 TM {:.4} (Q1(y|z) = 0 in {:.1}% of {n}), GM {:.4}, orbital {:.4} \
             (Q1(y|z) = 0 in {vo} of {no})",
            2 * pairs,
            a_tm.0,
            100.0 * v as f64 / n as f64,
            a_gm.0,
            a_orbital.0
        );
        assert_eq!(vo, 0, "the orbital stage left the first stage's support");
        assert!(v > 0);
        assert_greater(
            &format!("{}-D: orbital a2 > TM a2", 2 * pairs),
            a_orbital,
            a_tm,
        );
        results.push(a_tm);
    }
    assert_greater("TM a2: 2-D > 16-D", results[0], results[1]);
}

// ---- 6. the 1-D toy of Fig. 3: integrated autocorrelation times ----

/// Integrated autocorrelation times of `x` and of `1[x < 0]` (the spike) over `chains`
/// independent chains from exact starts, and the acceptance rate.
fn iats<K: Kernel<UniformMixture> + Clone>(
    kernel: &K,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, AcceptanceStats) {
    let target = UniformMixture::rioux_lavoie2020();
    let (chains, steps) = (16u64, 50_000usize);
    let (mut tau_x, mut tau_spike) = (Vec::new(), Vec::new());
    let mut stats = AcceptanceStats::default();
    for i in 0..chains {
        let mut rng = Pcg64::seed_from_u64(mcmc_core::seed::chain_seed(seed, i));
        let x0 = target.sample_exact(&mut rng);
        let mut chain = Chain::new(&target, kernel.clone(), NoAdaptation, rng, x0).unwrap();
        let (mut xs, mut spike) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
        for _ in 0..steps {
            chain.step(&mut ()).unwrap();
            xs.push(chain.state()[0]);
            spike.push(f64::from(u8::from(chain.state()[0] < 0.0)));
        }
        tau_x.push(integrated_autocorrelation_time(&xs));
        tau_spike.push(integrated_autocorrelation_time(&spike));
        stats.merge(chain.stats());
    }
    (tau_x, tau_spike, stats)
}

/// Fig. 3: MH with a large sigma (beta = 1, the plateau), MH with a small sigma (alpha = 1/10,
/// the spike), and Tierney-Mira DR with the large step first and the small one second.
#[test]
fn delayed_rejection_mixes_faster_on_the_fig3_toy() {
    let large = iats(&Mh::new(grw(1.0)), 81);
    let small = iats(&Mh::new(grw(0.1)), 82);
    let dr = iats(&tm_fig3(), 83);
    let gm = iats(
        &DelayedRejection::green_mira(grw(1.0), IndependentSecondStage(grw(0.1)), Euclidean)
            .with_symmetric_second_stage(),
        84,
    );
    for (name, r) in [
        ("MH sigma 1", &large),
        ("MH sigma 0.1", &small),
        ("DR TM 1 then 0.1", &dr),
        ("DR GM 1 then 0.1", &gm),
    ] {
        let (x, s) = (mean_and_se(&r.0), mean_and_se(&r.1));
        eprintln!(
            "Fig. 3 toy, {name}: acceptance {:.3} (stage 1 {:.3}, stage 2 {:.3} of {:.1}% of \
             steps; mean a1 {:.3}, mean a2 {:.3}), IAT(x) {:.1} +- {:.1}, IAT(1[x<0]) {:.1} +- \
             {:.1}",
            r.2.acceptance_rate(),
            r.2.stage_acceptance_rate(0),
            r.2.stage_acceptance_rate(1),
            100.0 * r.2.stage_tried[1] as f64 / r.2.steps as f64,
            r.2.stage_mean_accept_prob(0),
            r.2.stage_mean_accept_prob(1),
            x.0,
            x.1,
            s.0,
            s.1
        );
    }
    assert_greater(
        "IAT(x): MH sigma 1 > DR",
        mean_and_se(&large.0),
        mean_and_se(&dr.0),
    );
    assert_greater(
        "IAT(x): MH sigma 0.1 > DR",
        mean_and_se(&small.0),
        mean_and_se(&dr.0),
    );
}

#[test]
fn fixed_selection_mixture_second_stage_after_small_steps() {
    // `second_stage_after` validates its indices, and a kernel restricted to component 0
    // never runs a second stage after component 1.
    let first = Mixture::new(
        vec![grw(0.05), grw(2.0)],
        FixedSelection::new(&[0.5, 0.5]).unwrap(),
    )
    .unwrap();
    let k = DelayedRejection::tierney_mira(first, IndependentSecondStage(grw(0.01)));
    assert!(k.clone().second_stage_after(&[8]).is_err());
    let k = k.second_stage_after(&[0]).unwrap();
    let target = UniformMixture::rioux_lavoie2020();
    let rng = Pcg64::seed_from_u64(9);
    let mut chain = Chain::new(&target, k, NoAdaptation, rng, vec![-0.05]).unwrap();
    for _ in 0..5000 {
        let info = chain.step(&mut ()).unwrap();
        assert!(info.component == 0 || info.stages_tried == 1, "{info:?}");
    }
}
