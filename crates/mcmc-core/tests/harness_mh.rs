//! Metropolis-Hastings passes all three harness checks on every toy target, with a symmetric,
//! an asymmetric and a state-dependent mixture proposal (and a regional proposal).
//!
//! Run with `cargo test -p mcmc-core --all-features --release --test harness_mh -- --nocapture`
//! to see each test's chi-square statistic and p-value.
//!
//! Statistics: each stationarity test is exact under the null hypothesis (independent exact
//! starts, so the final states are i.i.d. from pi when the kernel preserves pi), so its p-value
//! is uniform. This file runs [`STATIONARITY_TESTS`] of them; each must pass at the Sidak level
//! `1 - 0.99^(1/23) = 4.4e-4`, which keeps the probability of any false failure in the file at
//! 0.01. Seeds are fixed, so the outcome is deterministic. The pairwise and finite-state checks
//! are identities checked to rounding (`1e-9` and `1e-12` relative), not statistics.

use mcmc_core::partition::UniformGrid;
use mcmc_core::proposal::{Regional, Scaled};
use mcmc_core::testing::{
    assert_finite_state_balance, assert_hastings_consistent, assert_pairwise_balance,
    assert_symmetric_proposal, grid_centres, toy_stationarity_test, AsymmetricWalk, PairwiseParams,
    StationarityParams, ThresholdSelection,
};
use mcmc_core::toy::{
    wrap, wrapped_normal_pdf, Banana, CorrelatedGaussian, GaussianMixture2d, PiecewiseConstant,
    Ridge, TorusMixture, ToyTarget, UniformMixture,
};
use mcmc_core::{GaussianRandomWalk, Kernel, Mh, Mixture, Proposal, Proposed};
use proptest::prelude::*;
use proptest::strategy::BoxedStrategy;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// Number of stationarity tests in this file (for the Sidak correction). Keep in sync.
const STATIONARITY_TESTS: usize = 23;

/// Independent exact starts per stationarity test: with >= 30 bins, expected counts are
/// >= 5 even for bins of probability 5e-4 after pooling.
const STARTS: usize = 10_000;
/// Kernel steps per start.
const STEPS: u64 = 20;

/// States drawn uniformly from the target's bounding box enlarged by `margin` on each side
/// (so some states lie outside the support).
fn box_states<T: ToyTarget>(target: &T, margin: f64) -> BoxedStrategy<Vec<f64>> {
    let (lo, hi) = target.bounding_box();
    let ranges: Vec<_> = lo
        .iter()
        .zip(&hi)
        .map(|(&l, &h)| {
            let m = margin * (h - l);
            (l - m)..(h + m)
        })
        .collect();
    ranges.boxed()
}

/// Runs the three checks for one kernel on one target. `cells`: the finite-state grid
/// (per axis) on the bounding box, or `None` to skip it.
fn check_kernel<T, K>(what: &str, target: &T, kernel: &K, cells: Option<&[usize]>, seed: u64)
where
    T: ToyTarget,
    K: Kernel<T> + Clone,
{
    let pairwise = assert_pairwise_balance(
        target,
        kernel,
        box_states(target, 0.1),
        &PairwiseParams::with_seed(seed),
    );
    if let Some(cells) = cells {
        let (lo, hi) = target.bounding_box();
        let (states, volume) = grid_centres(&lo, &hi, cells);
        let fs = assert_finite_state_balance(target, kernel, &states, volume);
        eprintln!(
            "{what}: finite-state {} states, asymmetry {:.1e}, pi K error {:.1e}",
            fs.states, fs.max_asymmetry, fs.max_stationarity_error
        );
    }
    let report = toy_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!(
        "{what}: pairwise {}/{} informative (worst {:.1e}); stationarity {report}",
        pairwise.informative, pairwise.cases, pairwise.worst_log_difference
    );
    report.assert_passes(what, STATIONARITY_TESTS);
}

fn grw(sigma: f64) -> Mh<GaussianRandomWalk> {
    Mh::new(GaussianRandomWalk::new(sigma).unwrap())
}

fn asym(sigma: f64, drift: f64) -> Mh<AsymmetricWalk> {
    Mh::new(AsymmetricWalk::new(sigma, drift, 0.5).unwrap())
}

/// A small and a large random walk, selected with probabilities that depend on the side of
/// `threshold` the current state is on (regional-adaptive paper, section 3.2).
fn mixture(
    small: f64,
    large: f64,
    threshold: f64,
) -> Mh<Mixture<GaussianRandomWalk, ThresholdSelection>> {
    Mh::new(
        Mixture::new(
            vec![
                GaussianRandomWalk::new(small).unwrap(),
                GaussianRandomWalk::new(large).unwrap(),
            ],
            ThresholdSelection::new(threshold, &[0.8, 0.2], &[0.3, 0.7]).unwrap(),
        )
        .unwrap(),
    )
}

// ---- 1-D mixture of uniforms (DR paper, eq. 8) ----

#[test]
fn uniform_mixture_grw() {
    check_kernel(
        "uniform mixture / GRW",
        &UniformMixture::rioux_lavoie2020(),
        &grw(0.3),
        Some(&[22]),
        1,
    );
}

#[test]
fn uniform_mixture_asymmetric() {
    check_kernel(
        "uniform mixture / asymmetric",
        &UniformMixture::rioux_lavoie2020(),
        &asym(0.2, 0.05),
        Some(&[22]),
        2,
    );
}

#[test]
fn uniform_mixture_mixture() {
    check_kernel(
        "uniform mixture / mixture",
        &UniformMixture::rioux_lavoie2020(),
        &mixture(0.05, 0.5, 0.0),
        Some(&[22]),
        3,
    );
}

// ---- 2-D ridge ----

#[test]
fn ridge_grw() {
    check_kernel("ridge / GRW", &Ridge::thin(), &grw(0.3), Some(&[16, 16]), 4);
}

#[test]
fn ridge_asymmetric() {
    check_kernel(
        "ridge / asymmetric",
        &Ridge::thin(),
        &asym(0.25, 0.05),
        Some(&[16, 16]),
        5,
    );
}

#[test]
fn ridge_mixture() {
    check_kernel(
        "ridge / mixture",
        &Ridge::thin(),
        &mixture(0.05, 0.5, 0.0),
        Some(&[16, 16]),
        6,
    );
}

// ---- 2-D disconnected mixture ----

#[test]
fn disconnected_grw() {
    check_kernel(
        "disconnected / GRW",
        &GaussianMixture2d::disconnected(),
        &grw(0.5),
        Some(&[16, 16]),
        7,
    );
}

#[test]
fn disconnected_asymmetric() {
    check_kernel(
        "disconnected / asymmetric",
        &GaussianMixture2d::disconnected(),
        &asym(0.4, 0.1),
        Some(&[16, 16]),
        8,
    );
}

#[test]
fn disconnected_mixture() {
    check_kernel(
        "disconnected / mixture",
        &GaussianMixture2d::disconnected(),
        &mixture(0.2, 1.5, 0.0),
        Some(&[16, 16]),
        9,
    );
}

// ---- 2-D mixture on the torus ----

/// A wrapped Gaussian walk on the unit torus: `y = (x + sigma N(0, I)) mod 1`, symmetric, with
/// the wrapped normal as its exact density. Only for states in `[0, 1)^2`.
#[derive(Clone, Debug)]
struct WrappedWalk {
    sigma: f64,
}

impl Proposal<Vec<f64>> for WrappedWalk {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clear();
        y.extend(x.iter().map(|&v| {
            let z: f64 = StandardNormal.sample(rng);
            wrap(v + self.sigma * z)
        }));
        Proposed::symmetric()
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        from.iter()
            .zip(to)
            .map(|(&a, &b)| wrapped_normal_pdf(wrap(b - a), 0.0, self.sigma).ln())
            .sum()
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

fn torus_states() -> BoxedStrategy<Vec<f64>> {
    prop::collection::vec(0.0..1.0f64, 2).boxed()
}

#[test]
fn torus_grw() {
    check_kernel(
        "torus / GRW (no wrap)",
        &TorusMixture::across_seam(),
        &grw(0.1),
        Some(&[16, 16]),
        10,
    );
}

#[test]
fn torus_asymmetric() {
    check_kernel(
        "torus / asymmetric (no wrap)",
        &TorusMixture::across_seam(),
        &asym(0.08, 0.02),
        Some(&[16, 16]),
        11,
    );
}

#[test]
fn torus_mixture() {
    check_kernel(
        "torus / mixture (no wrap)",
        &TorusMixture::across_seam(),
        &mixture(0.03, 0.2, 0.5),
        Some(&[16, 16]),
        12,
    );
}

#[test]
fn torus_wrapped_walk() {
    let target = TorusMixture::across_seam();
    let walk = WrappedWalk { sigma: 0.1 };
    // Symmetry including wrap-around: pairs across the seam have equal densities both ways.
    assert_symmetric_proposal(&walk, torus_states(), &PairwiseParams::with_seed(13));
    assert_hastings_consistent(&walk, torus_states(), &PairwiseParams::with_seed(13));
    check_kernel(
        "torus / wrapped walk",
        &target,
        &Mh::new(walk),
        Some(&[16, 16]),
        13,
    );
}

// ---- 2-D banana ----

#[test]
fn banana_grw() {
    check_kernel(
        "banana / GRW",
        &Banana::curved(),
        &grw(1.0),
        Some(&[16, 16]),
        14,
    );
}

#[test]
fn banana_asymmetric() {
    check_kernel(
        "banana / asymmetric",
        &Banana::curved(),
        &asym(0.8, 0.2),
        Some(&[16, 16]),
        15,
    );
}

#[test]
fn banana_mixture() {
    check_kernel(
        "banana / mixture",
        &Banana::curved(),
        &mixture(0.3, 2.0, 0.0),
        Some(&[16, 16]),
        16,
    );
}

// ---- n-D correlated Gaussian (finite-state on a 2-D instance) ----

fn gaussian_10d() -> CorrelatedGaussian {
    CorrelatedGaussian::ar1(10, 0.9).unwrap()
}

fn gaussian_2d() -> CorrelatedGaussian {
    CorrelatedGaussian::new(vec![0.5, -1.0], &[1.0, 0.8, 0.8, 2.0]).unwrap()
}

#[test]
fn correlated_gaussian_grw() {
    let kernel = grw(0.3);
    check_kernel("gaussian 10-D / GRW", &gaussian_10d(), &kernel, None, 17);
    assert_finite_state_balance_2d(&grw(0.5));
}

#[test]
fn correlated_gaussian_asymmetric() {
    check_kernel(
        "gaussian 10-D / asymmetric",
        &gaussian_10d(),
        &asym(0.25, 0.03),
        None,
        18,
    );
    assert_finite_state_balance_2d(&asym(0.4, 0.1));
}

#[test]
fn correlated_gaussian_mixture() {
    check_kernel(
        "gaussian 10-D / mixture",
        &gaussian_10d(),
        &mixture(0.1, 0.5, 0.0),
        None,
        19,
    );
    assert_finite_state_balance_2d(&mixture(0.2, 1.0, 0.5));
}

fn assert_finite_state_balance_2d<K: Kernel<CorrelatedGaussian>>(kernel: &K) {
    let target = gaussian_2d();
    let (lo, hi) = target.bounding_box();
    let (states, volume) = grid_centres(&lo, &hi, &[16, 16]);
    assert_finite_state_balance(&target, kernel, &states, volume);
}

// ---- piecewise constant with holes ----

#[test]
fn holes_grw() {
    check_kernel(
        "holes / GRW",
        &PiecewiseConstant::with_holes(),
        &grw(0.15),
        Some(&[32]),
        20,
    );
}

#[test]
fn holes_asymmetric() {
    check_kernel(
        "holes / asymmetric",
        &PiecewiseConstant::with_holes(),
        &asym(0.1, 0.03),
        Some(&[32]),
        21,
    );
}

#[test]
fn holes_mixture() {
    check_kernel(
        "holes / mixture",
        &PiecewiseConstant::with_holes(),
        &mixture(0.03, 0.3, 0.5),
        Some(&[32]),
        22,
    );
}

// ---- regional proposal: asymmetric across region borders ----

/// Per-region scales `lambda = log sigma^2` that differ strongly between neighbouring regions.
fn regional(grid: UniformGrid, sigmas: &[f64]) -> Mh<Regional<GaussianRandomWalk, UniformGrid>> {
    use mcmc_core::controller::RegionalTunable;
    let mut p = Regional::new::<Vec<f64>>(GaussianRandomWalk::new(1.0).unwrap(), grid, 0.0);
    let n = RegionalTunable::<Vec<f64>>::num_regions(&p);
    for k in 0..n {
        let s = sigmas[k % sigmas.len()];
        RegionalTunable::<Vec<f64>>::set_log_scale_of(&mut p, k, (s * s).ln());
    }
    Mh::new(p)
}

#[test]
fn regional_uniform_mixture() {
    let target = UniformMixture::rioux_lavoie2020();
    let kernel = regional(
        UniformGrid::new(1, 11, -0.1, 1.0).unwrap(),
        &[0.05, 0.4, 0.15],
    );
    check_kernel(
        "uniform mixture / regional",
        &target,
        &kernel,
        Some(&[22]),
        23,
    );
    assert_hastings_consistent(
        &kernel.proposal,
        box_states(&target, 0.1),
        &PairwiseParams::with_seed(23),
    );
}

#[test]
fn regional_ridge() {
    let target = Ridge::thin();
    let kernel = regional(
        UniformGrid::new(2, 4, -3.0, 3.0).unwrap(),
        &[0.1, 0.5, 0.25],
    );
    // Pairwise and finite-state only (the stationarity budget of this file is spent above).
    assert_pairwise_balance(
        &target,
        &kernel,
        box_states(&target, 0.1),
        &PairwiseParams::with_seed(24),
    );
    let (lo, hi) = target.bounding_box();
    let (states, volume) = grid_centres(&lo, &hi, &[16, 16]);
    assert_finite_state_balance(&target, &kernel, &states, volume);
}

// ---- proposals report the Hastings term their densities imply ----

#[test]
fn proposals_are_self_consistent() {
    let states = prop::collection::vec(-2.0..2.0f64, 2);
    let params = PairwiseParams::with_seed(25);
    let walk = GaussianRandomWalk::new(0.4).unwrap();
    assert_symmetric_proposal(&walk, states.clone(), &params);
    assert_hastings_consistent(&walk, states.clone(), &params);
    assert_hastings_consistent(
        &AsymmetricWalk::new(0.3, 0.1, 0.5).unwrap(),
        states.clone(),
        &params,
    );
    assert_hastings_consistent(&mixture(0.1, 1.0, 0.0).proposal, states.clone(), &params);
    assert_hastings_consistent(&Scaled::new(walk, -1.0), states, &params);
}
