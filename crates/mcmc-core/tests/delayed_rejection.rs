//! Two-stage delayed rejection (DR paper, section 4) through the mcmc-core harness: each
//! acceptance rule (Tierney-Mira, Green-Mira, orbital) passes the pairwise flow check, the exact finite-state
//! check where it applies, chi-square stationarity from exact starts (including a lazily
//! materialised state whose read set depends on the state, and mass across the torus seam) and
//! the splat-weight check; each check has a negative control that fails it. Then the two
//! measured claims of the DR paper: Tierney-Mira's vanishing second-stage acceptance after a
//! Kelemen first stage versus the orbital rule (section 4.3), and the 1-D toy of Fig. 3 where
//! DR has a lower integrated autocorrelation time than both single-stage kernels (module
//! `delayed_rejection/measurements.rs`; test fixtures in `delayed_rejection/fixtures.rs`).
//!
//! Run with `cargo test -p mcmc-core --release --test delayed_rejection -- --nocapture` to see
//! every statistic (docs/methods/drmlt.md quotes them).
//!
//! # Statistics
//! Pairwise and finite-state checks are identities, checked to rounding (`1e-9` and `1e-12`
//! relative). Stationarity tests: independent exact starts, so the final states are i.i.d.
//! from pi under a correct kernel and Pearson's p-value is uniform. Splat-weight tests:
//! the harness's chi-square statistic of the mean splat-weighted histogram
//! (`mcmc_core::testing::SplatMoments::test`). Comparisons (vanishing acceptance, autocorrelation
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
#[path = "delayed_rejection/measurements.rs"]
mod measurements;

use std::f64::consts::PI;
use std::panic::{catch_unwind, AssertUnwindSafe};

use fixtures::{
    DisplacementBug, FourStates, LazyStripes, LazyTorus, OnLazy, OtherState, ThirdState, FOUR,
};
use mcmc_core::delayed_rejection::{
    IndependentSecondStage, OrbitalWalk, RadialKelemen, WrappedCauchy, WrappedGaussianWalk,
};
use mcmc_core::proposal::FixedSelection;
use mcmc_core::testing::broken::PaperSplatWeights;
use mcmc_core::testing::{
    assert_finite_state_balance, assert_pairwise_balance, assert_path_balance, finite_state_check,
    grid_centres, sidak_alpha, splat_weight_test, stationarity_test, toy_splat_weight_test,
    toy_stationarity_test, AsymmetricWalk, ChiSquareReport, FnBins, PairwiseParams, SplatParams,
    SplatWeightReport, StationarityParams, ThresholdSelection, ALPHA,
};
use mcmc_core::toy::{wrap, Ridge, TorusMixture, ToyTarget, UniformMixture};
use mcmc_core::{
    Chain, DelayedRejection, Euclidean, GaussianRandomWalk, Kernel, Mixture, NoAdaptation, Torus,
};
use proptest::prelude::*;
use proptest::strategy::BoxedStrategy;
use rand::{RngExt, SeedableRng};
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
