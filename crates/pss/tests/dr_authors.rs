//! The DRMLT authors' Tierney-Mira and Green-Mira (DR paper sections 4.1, 4.5 and Fig. 7;
//! docs/methods/drmlt.md): a 1-D Kelemen first stage on every coordinate of the layout
//! (eq. 9) and a Gaussian second stage from `x` (sigma 0.1/64 with the authors' values), on
//! primary-sample-space states, pass the correctness harness:
//!
//! - two-stage pairwise balance: on triples `(x, y, z)` with `y - x` in Kelemen's support and
//!   `z` near `x`, the kernel's forward and reverse path flows agree (identities, 1e-9);
//! - the finite-state check on a uniform 10 x 10 grid of the torus (exact linear algebra; the
//!   grid is permuted by the ghost map, so Green-Mira qualifies), with wider stages so that
//!   grid neighbours are reachable;
//! - stationarity from exact starts with the authors' values, on the torus mixture whose modes
//!   straddle both seams and on the narrow stripes whose read set depends on `u0` (one stripe
//!   across the seam; a chi-square of one degree of freedom on the stripe share and one on the
//!   target's fine bins).
//!
//! Negative control: the same stages under the orbital rule (eq. 11), i.e. Tierney-Mira
//! without its `Q1(y | z) / Q1(y | x)` ratio, or Green-Mira with `y` in place of the ghost in
//! `a1(z, .)`: it fails the pairwise and finite-state checks.
//!
//! Statistics: each chi-square test must pass at the Sidak level for [`CHI_SQUARE_TESTS`]
//! tests (false-failure probability 0.01 for the file); seeds are fixed.

use mcmc_core::testing::{
    assert_finite_state_balance, assert_path_balance, finite_state_check, grid_centres, path_flows,
    stationarity_test, PairwiseParams, StationarityParams,
};
use mcmc_core::toy::TorusMixture;
use mcmc_core::{DelayedRejection, Kernel};
use proptest::prelude::*;
use pss::dr::{
    gaussian_timid_stage, green_mira_kernel, kelemen_first_stage, tierney_mira_kernel, ByState,
    GaussianTimidStage, KelemenFirstStage, NormalOnly, PerCoordinateParams, SecondStageStreams,
};
use pss::testing::{pss_stationarity_test, ExactPssTarget, OnPss, Stripes};
use pss::{KelemenParams, LayoutGhost, PairLayout, PssState};

/// Chi-square tests in this file that must pass (Sidak correction). Keep in sync.
const CHI_SQUARE_TESTS: usize = 6;

/// Exact starts and steps of the stationarity tests.
const PARAMS: StationarityParams = StationarityParams::new(20_000, 30, 0);

fn two() -> PairLayout {
    PairLayout::single_stream(2)
}

/// Wider stages for the finite-state grid (spacing 0.1): Kelemen `[0.05, 0.25]`, sigma 0.08.
fn wide() -> PerCoordinateParams {
    PerCoordinateParams {
        kelemen: KelemenParams { s1: 0.05, s2: 0.25 },
        second_sigma: 0.08,
    }
}

type Stage1 = KelemenFirstStage;
type Stage2 = GaussianTimidStage;
type Tm = DelayedRejection<Stage1, ByState<Stage2, NormalOnly>>;
type Gm = DelayedRejection<Stage1, ByState<Stage2, NormalOnly>, LayoutGhost>;

fn tm(params: PerCoordinateParams, p_large: f64) -> Tm {
    tierney_mira_kernel(two(), p_large, SecondStageStreams::all(), params)
}

fn gm(params: PerCoordinateParams, p_large: f64) -> Gm {
    green_mira_kernel(two(), p_large, SecondStageStreams::all(), params)
}

/// The negative control: the authors' stages under the orbital rule.
fn dropped_ratio(params: PerCoordinateParams, p_large: f64) -> DelayedRejection<Stage1, Stage2> {
    DelayedRejection::orbital(
        kelemen_first_stage(two(), p_large, params),
        gaussian_timid_stage(two(), pss::ALL_STREAMS, params),
    )
    .second_stage_after_small_steps()
}

/// Triples `(x, y, z)`: `x` anywhere (many straddle a seam), `y - x` a Kelemen displacement of
/// each coordinate, `z - x` within three second-stage sigmas.
fn triples(params: PerCoordinateParams) -> BoxedStrategy<Vec<PssState>> {
    let KelemenParams { s1, s2 } = params.kelemen;
    let s = params.second_sigma;
    let kelemen = move |u: f64, up: bool| {
        let d = s2 * (s1 / s2).powf(u);
        if up {
            d
        } else {
            -d
        }
    };
    (
        (0.0..1.0f64, 0.0..1.0f64),
        (0.0..1.0f64, any::<bool>(), 0.0..1.0f64, any::<bool>()),
        (-3.0..3.0f64, -3.0..3.0f64),
    )
        .prop_map(move |((a, b), (u0, p0, u1, p1), (n0, n1))| {
            let x = [a, b];
            let y = [a + kelemen(u0, p0), b + kelemen(u1, p1)];
            let z = [a + s * n0, b + s * n1];
            vec![
                PssState::from_values(&x),
                PssState::from_values(&y),
                PssState::from_values(&z),
            ]
        })
        .boxed()
}

fn torus() -> OnPss<TorusMixture> {
    OnPss::new(TorusMixture::across_seam()).unwrap()
}

/// Path balance on `cases` triples, at least a fraction `min_informative` of them with a
/// positive flow.
fn pairwise<K: Kernel<OnPss<TorusMixture>>>(
    what: &str,
    kernel: &K,
    params: PerCoordinateParams,
    (cases, min_informative): (u32, f64),
) {
    let r = assert_path_balance(
        &torus(),
        kernel,
        triples(params),
        &PairwiseParams {
            cases,
            min_informative,
            ..PairwiseParams::with_seed(11)
        },
    );
    eprintln!(
        "{what}: path balance {}/{} informative (worst {:.1e})",
        r.informative, r.cases, r.worst_log_difference
    );
}

/// Tierney-Mira's flows are positive on about a third of the triples.
const TM_CASES: (u32, f64) = (512, 0.1);

/// Green-Mira's second stage is rarely accepted at small scales on a smooth target: after a
/// rejected downhill `y`, the ghost `y* = z - (y - x)` lies uphill of `z`, so `a1(z, y*) = 1`
/// and `a2 = 0` (both flows zero). More cases, a lower informative share.
const GM_CASES: (u32, f64) = (4096, 0.01);

fn grid() -> (Vec<PssState>, f64) {
    let (centres, volume) = grid_centres(&[0.0, 0.0], &[1.0, 1.0], &[10, 10]);
    (
        centres.iter().map(|c| PssState::from_values(c)).collect(),
        volume,
    )
}

fn stationarity<K: Kernel<OnPss<TorusMixture>> + Kernel<Stripes> + Clone>(
    what: &str,
    kernel: &K,
    seed: u64,
) {
    let p = StationarityParams { seed, ..PARAMS };
    let r = pss_stationarity_test(&torus(), kernel, &p);
    eprintln!("{what} / torus mixture: {r}");
    r.assert_passes(what, CHI_SQUARE_TESTS);
    let stripes = Stripes::narrow();
    let share = stationarity_test(
        &stripes,
        kernel,
        |rng| stripes.sample_exact(rng),
        &stripes.stripe_bins(),
        &StationarityParams {
            seed: seed + 1,
            ..PARAMS
        },
    );
    eprintln!("{what} / stripes, share: {share}");
    share.assert_passes(what, CHI_SQUARE_TESTS);
    let fine = pss_stationarity_test(
        &stripes,
        kernel,
        &StationarityParams {
            seed: seed + 2,
            ..PARAMS
        },
    );
    eprintln!("{what} / stripes, fine bins: {fine}");
    fine.assert_passes(what, CHI_SQUARE_TESTS);
}

#[test]
fn tierney_mira_passes_the_harness() {
    let authors = PerCoordinateParams::rioux_lavoie2020();
    pairwise("tierney-mira", &tm(authors, 0.0), authors, TM_CASES);
    pairwise(
        "tierney-mira + large steps",
        &tm(authors, 0.3),
        authors,
        TM_CASES,
    );
    pairwise("tierney-mira, wide", &tm(wide(), 0.2), wide(), TM_CASES);
    let (states, volume) = grid();
    let r = assert_finite_state_balance(&torus(), &tm(wide(), 0.2), &states, volume);
    eprintln!(
        "tierney-mira: finite-state asymmetry {:.1e}",
        r.max_asymmetry
    );
    stationarity("tierney-mira", &tm(authors, 0.3), 100);
}

#[test]
fn green_mira_passes_the_harness() {
    let authors = PerCoordinateParams::rioux_lavoie2020();
    pairwise("green-mira", &gm(authors, 0.0), authors, GM_CASES);
    pairwise(
        "green-mira + large steps",
        &gm(authors, 0.3),
        authors,
        GM_CASES,
    );
    pairwise("green-mira, wide", &gm(wide(), 0.2), wide(), GM_CASES);
    let (states, volume) = grid();
    let r = assert_finite_state_balance(&torus(), &gm(wide(), 0.2), &states, volume);
    eprintln!("green-mira: finite-state asymmetry {:.1e}", r.max_asymmetry);
    stationarity("green-mira", &gm(authors, 0.3), 200);
}

#[test]
fn negative_control_dropped_first_stage_ratio_fails() {
    let authors = PerCoordinateParams::rioux_lavoie2020();
    let target = torus();
    let kernel = dropped_ratio(authors, 0.0);
    let mut runner = proptest::test_runner::TestRunner::new_with_rng(
        proptest::test_runner::Config::default(),
        proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        ),
    );
    let mut unbalanced = 0;
    for _ in 0..256 {
        let path = triples(authors).new_tree(&mut runner).unwrap().current();
        let (f, b) = path_flows(&target, &kernel, &path);
        if (f.is_finite() || b.is_finite()) && (f - b).abs() > 1e-6 {
            unbalanced += 1;
        }
    }
    eprintln!("negative control: {unbalanced}/256 unbalanced paths");
    assert!(unbalanced > 25, "{unbalanced}");
    let (states, volume) = grid();
    let r = finite_state_check(&target, &dropped_ratio(wide(), 0.2), &states, volume);
    eprintln!(
        "negative control: finite-state asymmetry {:.1e}",
        r.max_asymmetry
    );
    assert!(r.max_asymmetry > 1e-6, "{r:?}");
}
