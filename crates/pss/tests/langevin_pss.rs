//! MALA in primary sample space (`pss::langevin::PssCoordinates` with the kernels of
//! `mcmc_core::langevin`): pairwise flow balance and stationarity from exact starts on a
//! wrapped mixture with mass across the torus seams, and stationarity on targets whose read
//! set depends on the state (stripes; a roulette path of varying length), where a candidate
//! that reads a different set of coordinates is rejected — by both stages of
//! cheap-then-expensive too. Negative controls: the move density without the wrap-around (the
//! unwrapped Gaussian of the displacement) fails at the seam; cheap-then-expensive over a space
//! that ignores read-set changes (what its first stage did before it checked them) fails on
//! the stripes.
//!
//! Statistics: each stationarity test must pass at the Sidak level for
//! [`STATIONARITY_TESTS`] tests (false-failure probability 0.01 for the file); the negative
//! control must fail at the same level. Pairwise checks are identities (1e-9 relative).

use mcmc_core::langevin::{
    CheapThenExpensive, Hybrid, Langevin, LangevinParams, LangevinSpace, Online, Plain,
    ProposalGaussian,
};
use mcmc_core::testing::{
    assert_path_balance, sidak_alpha, stationarity_test, PairwiseParams, StationarityParams,
};
use mcmc_core::toy::{wrap, TorusMixture};
use mcmc_core::{Chain, Kernel, NoAdaptation};
use proptest::prelude::*;
use pss::langevin::PssCoordinates;
use pss::testing::{
    pss_stationarity_test, BlindPssCoordinates, Blindness, ExactPssTarget, OnPss, RoulettePath,
    Stripes,
};
use pss::{LargeStep, PssState};
use rand::SeedableRng;

const STATIONARITY_TESTS: usize = 10;
const STARTS: usize = 10_000;
const STEPS: u64 = 20;

fn params(epsilon: f64) -> LangevinParams {
    LangevinParams {
        epsilon,
        cache_size: 300,
        ..LangevinParams::luan2020()
    }
}

/// Near pairs of fully materialised 2-D states, wrapped onto the torus (the kernel's
/// candidates always are), with `x` anywhere, so that many pairs straddle a seam.
fn near_pairs(scale: f64) -> BoxedStrategy<Vec<PssState>> {
    (0.0..1.0f64, 0.0..1.0f64, -3.0..3.0f64, -3.0..3.0f64)
        .prop_map(move |(a, b, n0, n1)| {
            vec![
                PssState::from_values(&[a, b]),
                PssState::from_values(&[wrap(a + scale * n0), wrap(b + scale * n1)]),
            ]
        })
        .boxed()
}

fn check<T, K>(what: &str, target: &T, kernel: &K, seed: u64, pairwise_scale: Option<f64>)
where
    T: ExactPssTarget,
    K: Kernel<T> + Clone,
{
    if let Some(scale) = pairwise_scale {
        let r = assert_path_balance(
            target,
            kernel,
            near_pairs(scale),
            &PairwiseParams::with_seed(seed),
        );
        eprintln!(
            "{what}: pairwise {}/{} informative (worst {:.1e})",
            r.informative, r.cases, r.worst_log_difference
        );
    }
    let report = pss_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!("{what}: stationarity {report}");
    report.assert_passes(what, STATIONARITY_TESTS);
}

fn warmed<T: ExactPssTarget, K: Kernel<T> + Clone>(
    target: &T,
    kernel: K,
    warmup: u64,
    seed: u64,
) -> K {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(target, kernel, NoAdaptation, rng, start).unwrap();
    chain.run(warmup, &mut ()).unwrap();
    chain.kernel().clone()
}

#[test]
fn torus_mixture_plain_online_hybrid_and_cheap_then_expensive() {
    let target = OnPss::new(TorusMixture::across_seam()).unwrap();
    let p = params(0.002);
    let plain = Langevin::new(p, Plain, PssCoordinates)
        .unwrap()
        .with_large_step(LargeStep, 0.1)
        .unwrap();
    check(
        "torus / plain MALA + large step",
        &target,
        &plain,
        1,
        Some(0.05),
    );
    let mut online = warmed(
        &target,
        Langevin::new(p, Online::new(true), PssCoordinates).unwrap(),
        500,
        2,
    );
    online.freeze();
    check(
        "torus / online (DA, frozen)",
        &target,
        &online,
        3,
        Some(0.05),
    );
    let hybrid = warmed(
        &target,
        Langevin::new(p, Hybrid::new(&p), PssCoordinates).unwrap(),
        2000,
        4,
    );
    assert!(
        !hybrid.adaptation.is_online(),
        "the hybrid's cache should be full"
    );
    check(
        "torus / hybrid (cache stage)",
        &target,
        &hybrid,
        5,
        Some(0.05),
    );
    let cte = CheapThenExpensive::new(p, 0.1, Plain, PssCoordinates).unwrap();
    check("torus / cheap-then-expensive", &target, &cte, 6, None);
}

#[test]
fn state_dependent_read_sets() {
    // Piecewise-constant densities: MALA is a Gaussian walk on the coordinates the current
    // state read; candidates reading a different set are rejected.
    let p = params(0.0025);
    let kernel = Langevin::new(p, Plain, PssCoordinates)
        .unwrap()
        .with_large_step(LargeStep, 0.1)
        .unwrap();
    check(
        "stripes / plain MALA",
        &Stripes::default(),
        &kernel,
        7,
        None,
    );
    check(
        "roulette path / plain MALA",
        &RoulettePath::default(),
        &kernel,
        8,
        None,
    );
}

/// The negative control: PSS coordinates whose move density forgets the wrap-around.
#[derive(Clone, Copy, Debug)]
struct Unwrapped;

impl LangevinSpace<PssState> for Unwrapped {
    fn read(&self, x: &PssState, out: &mut Vec<f64>) {
        PssCoordinates.read(x, out);
    }
    fn write(&self, x: &PssState, coords: &[f64], y: &mut PssState) -> bool {
        PssCoordinates.write(x, coords, y)
    }
    fn log_q(&self, q: &ProposalGaussian, from: &[f64], to: &[f64]) -> f64 {
        let offset: Vec<f64> = from.iter().zip(to).map(|(a, b)| b - a).collect();
        q.log_density(&offset)
    }
    fn wraps(&self) -> bool {
        true
    }
    fn ghost(&self, x: &[f64], y: &[f64], z: &[f64], out: &mut Vec<f64>) {
        PssCoordinates.ghost(x, y, z, out);
    }
    fn same_layout(&self, x: &PssState, y: &PssState) -> bool {
        PssCoordinates.same_layout(x, y)
    }
}

#[test]
fn negative_control_unwrapped_density_fails_at_the_seam() {
    let target = OnPss::new(TorusMixture::across_seam()).unwrap();
    let kernel = Langevin::new(params(0.01), Plain, Unwrapped).unwrap();
    let report = pss_stationarity_test(&target, &kernel, &StationarityParams::new(STARTS, 100, 9));
    eprintln!("negative control (unwrapped density): {report}");
    assert!(
        report.rejects(sidak_alpha(0.01, STATIONARITY_TESTS)),
        "{report}"
    );
}

/// Cheap-then-expensive as the renderer builds it on MMLT: a small first-stage walk, a
/// MALA second stage, large steps with probability 0.1.
fn cheap_then_expensive<Sp>(space: Sp) -> impl Kernel<Stripes> + Clone
where
    Sp: LangevinSpace<PssState> + Clone,
{
    let p = LangevinParams {
        epsilon: 0.001,
        ..LangevinParams::luan2020()
    };
    CheapThenExpensive::new(p, 0.03, Plain, space)
        .unwrap()
        .with_large_step(LargeStep, 0.1)
        .unwrap()
}

/// Steps per start of the cheap-then-expensive read-set tests (long enough for a first stage
/// that crosses stripe edges to move the stripe share visibly).
const CTE_STEPS: u64 = 100;

/// Exact starts of the cheap-then-expensive read-set tests.
const CTE_STARTS: usize = 10_000;

/// Stationarity from exact starts with a chi-square of one degree of freedom on the share of
/// states in the stripes ([`Stripes::stripe_bins`]).
fn stripe_share_test<K: Kernel<Stripes> + Clone>(
    target: &Stripes,
    kernel: &K,
    seed: u64,
) -> mcmc_core::testing::ChiSquareReport {
    stationarity_test(
        target,
        kernel,
        |rng| target.sample_exact(rng),
        &target.stripe_bins(),
        &StationarityParams::new(CTE_STARTS, CTE_STEPS, seed),
    )
}

#[test]
fn cheap_then_expensive_keeps_the_read_set() {
    let target = Stripes::narrow();
    let report = stripe_share_test(&target, &cheap_then_expensive(PssCoordinates), 10);
    eprintln!("stripes / cheap-then-expensive + large step: {report}");
    report.assert_passes("stripes / cheap-then-expensive", STATIONARITY_TESTS);
}

#[test]
fn negative_control_cheap_then_expensive_across_read_sets_fails() {
    let target = Stripes::narrow();
    let report = stripe_share_test(
        &target,
        &cheap_then_expensive(BlindPssCoordinates(Blindness::ReadSet)),
        11,
    );
    eprintln!("negative control (first stage across read sets): {report}");
    assert!(
        report.rejects(sidak_alpha(0.01, STATIONARITY_TESTS)),
        "{report}"
    );
}
