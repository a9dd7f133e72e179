//! Calibration of the splat-weight check: over a sweep of seeds its p-values are uniform for
//! correct kernels, Hotelling's statistic with the sample covariance (the check's former
//! statistic) fails the same sweep, and a wrong splat weight fails it too.
//!
//! Run with `cargo test -p mcmc-core --release --test splat_weight_calibration -- --nocapture`
//! to see the sweeps' summaries.
//!
//! # Setup
//! The uniform mixture of the DR paper with fine bins (50 on the spike, 500 on the plateau):
//! at [`STARTS`] exact starts, pooled to expected weight 20 (the harness default), 285
//! pooled bins, so every bin is as sparse as the default allows and a bias of a few percent
//! per bin adds up. Three correct kernels with different weightings: MH (weights `1 - a`,
//! `a`, summing to 1), large-step MIS (three weights, summing to 1 only in expectation) and
//! Tierney-Mira delayed rejection (up to three weights). Each runs [`SEEDS`] independent
//! checks (seeds `0..SEEDS` offset per kernel).
//!
//! # Statistics
//! Under the hypothesis each check's p-value is uniform on `[0, 1]`, and the checks of a
//! sweep are independent, so the one-sample Kolmogorov-Smirnov statistic
//! `D = sup_u |F_n(u) - u|` of a kernel's [`SEEDS`] p-values has Kolmogorov's law. The three
//! correct kernels' sweeps must each pass at the Sidak level for an overall [`KS_LEVEL`] =
//! 1e-3: the probability that this file fails for a calibrated check is 1e-3 (seeds are
//! fixed, so the outcome is deterministic). A sweep counts as non-uniform when its KS
//! p-value is below [`KS_LEVEL`]; each control is a sweep that must be non-uniform.

use std::sync::OnceLock;

use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::render_loop::LargeStepMis;
use mcmc_core::special::chi_square_sf;
use mcmc_core::testing::{
    ks_one_sample, sidak_alpha, splat_moments, LargeStepWalk, MisWithStaleProbability,
    SplatMoments, SplatParams, DETERMINISTIC_TOLERANCE,
};
use mcmc_core::toy::{uniform_edges, Bins, ToyTarget, UniformMixture};
use mcmc_core::{DelayedRejection, GaussianRandomWalk, Kernel, Mh};
use nalgebra::SymmetricEigen;
use rayon::prelude::*;

/// Exact starts per check.
const STARTS: usize = 10_000;

/// Checks per sweep.
const SEEDS: u64 = 200;

/// Overall level of the uniformity checks of the correct kernels; also the KS p-value
/// below which a control's sweep counts as non-uniform.
const KS_LEVEL: f64 = 1e-3;

/// Large-step probability the MIS kernels draw with.
const P_LARGE: f64 = 0.3;

fn target() -> UniformMixture {
    UniformMixture::rioux_lavoie2020()
}

/// 50 bins on the spike, 500 on the plateau, and the two (empty) tails.
fn fine_bins() -> Bins {
    let t = target();
    let mut edges = uniform_edges(-t.a(), 0.0, 50);
    edges.pop();
    edges.extend(uniform_edges(0.0, t.b(), 500));
    Bins::from_cdf(edges, move |x| t.cdf(x), |x| x[0])
}

fn grw(sigma: f64) -> GaussianRandomWalk {
    GaussianRandomWalk::new(sigma).unwrap()
}

fn large_step_walk() -> LargeStepWalk {
    let (lo, hi) = target().bounding_box();
    LargeStepWalk::new(0.05, lo, hi, P_LARGE).unwrap()
}

/// Hotelling's `T^2 = N d^T S^+ d` with the sample covariance `S` (pseudo-inverse over
/// eigenvalues above `1e-10` times the largest) and its chi-square p-value with `rank(S)`
/// degrees of freedom: the check's former statistic, kept here as the negative control of
/// the calibration.
fn hotelling_p_value(moments: &SplatMoments) -> f64 {
    let deviation = moments.mean() - moments.probabilities();
    let eigen = SymmetricEigen::new(moments.sample_covariance());
    let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
    let (mut statistic, mut rank) = (0.0, 0);
    for (k, &lambda) in eigen.eigenvalues.iter().enumerate() {
        let z = eigen.eigenvectors.column(k).dot(&deviation);
        if lambda > 1e-10 * largest {
            statistic += moments.starts() as f64 * z * z / lambda;
            rank += 1;
        } else if z.abs() > DETERMINISTIC_TOLERANCE {
            statistic = f64::INFINITY;
        }
    }
    chi_square_sf(statistic, f64::from(rank))
}

/// The one-sample KS statistic of `p_values` against the uniform law and its p-value.
fn ks_uniform(p_values: &[f64]) -> (f64, f64) {
    ks_one_sample(p_values, |u| u)
}

/// The p-values of one sweep, by the check's statistic and by Hotelling's.
struct Sweep {
    name: &'static str,
    p_values: Vec<f64>,
    hotelling: Vec<f64>,
}

impl Sweep {
    /// The checks of a sweep are independent (one seed each), so they run on the rayon pool;
    /// the p-values are collected in seed order, whatever the number of threads.
    fn run<K: Kernel<UniformMixture> + Clone + Sync>(
        name: &'static str,
        kernel: &K,
        base: u64,
    ) -> Self {
        let checks: Vec<(f64, f64)> = (base..base + SEEDS)
            .into_par_iter()
            .map_init(
                || (target(), fine_bins()),
                |(t, bins), seed| {
                    let params = SplatParams::new(STARTS, seed);
                    let moments =
                        splat_moments(&*t, kernel, |rng| t.sample_exact(rng), &*bins, &params);
                    (moments.test().p_value, hotelling_p_value(&moments))
                },
            )
            .collect();
        let (p_values, hotelling) = checks.into_iter().unzip();
        let sweep = Self {
            name,
            p_values,
            hotelling,
        };
        eprintln!("{}", sweep.summary());
        sweep
    }

    fn summary(&self) -> String {
        let below = |p: &[f64], a: f64| p.iter().filter(|&&p| p < a).count();
        let (d, ks) = ks_uniform(&self.p_values);
        let (dh, ksh) = ks_uniform(&self.hotelling);
        format!(
            "{}: {SEEDS} checks; T: KS D = {d:.3}, p = {ks:.2e}, {} below 0.05, {} below \
             0.01; Hotelling: KS D = {dh:.3}, p = {ksh:.2e}, {} below 0.05, {} below 0.01",
            self.name,
            below(&self.p_values, 0.05),
            below(&self.p_values, 0.01),
            below(&self.hotelling, 0.05),
            below(&self.hotelling, 0.01),
        )
    }
}

/// The sweeps of the three correct kernels, run once for the tests that read them.
fn correct_sweeps() -> &'static [Sweep] {
    static SWEEPS: OnceLock<Vec<Sweep>> = OnceLock::new();
    SWEEPS.get_or_init(|| {
        let walk = large_step_walk();
        let b_q = walk.large_step_density();
        let dr = DelayedRejection::tierney_mira(grw(1.0), IndependentSecondStage(grw(0.1)))
            .with_symmetric_second_stage();
        vec![
            Sweep::run("MH, GRW 0.5", &Mh::new(grw(0.5)), 0),
            Sweep::run(
                "large-step MIS, p = 0.3",
                &LargeStepMis::new(Mh::new(walk), 1.0, b_q),
                1_000,
            ),
            Sweep::run("delayed rejection (Tierney-Mira)", &dr, 2_000),
        ]
    })
}

/// The check's p-values are uniform for every correct kernel (Sidak over the three sweeps).
#[test]
fn p_values_are_uniform_for_correct_kernels() {
    let level = sidak_alpha(KS_LEVEL, 3);
    for sweep in correct_sweeps() {
        let (d, p) = ks_uniform(&sweep.p_values);
        assert!(
            p >= level,
            "{}: KS D = {d:.3}, p = {p:.2e} below {level:.2e}: {}",
            sweep.name,
            sweep.summary()
        );
    }
}

/// Negative control of the calibration: Hotelling's statistic with the sample covariance,
/// on the very same moments, is anti-conservative here, and the KS check sees it in every
/// sweep.
#[test]
fn hotelling_with_the_sample_covariance_fails_the_calibration() {
    for sweep in correct_sweeps() {
        let (d, p) = ks_uniform(&sweep.hotelling);
        assert!(p < KS_LEVEL, "{}: KS D = {d:.3}, p = {p:.2e}", sweep.name);
        let too_small = sweep.hotelling.iter().filter(|&&p| p < 0.05).count();
        assert!(
            too_small > 2 * SEEDS as usize / 20,
            "{}: Hotelling's p-values below 0.05 in {too_small} of {SEEDS} checks, not more \
             than twice the nominal rate",
            sweep.name
        );
    }
}

/// Negative control of the check: large-step MIS weighted with a stale large-step
/// probability (0.33 instead of 0.3) splats about three percent too little on the plateau;
/// the sweep's p-values pile up near 0.
#[test]
fn a_wrong_splat_weight_fails_the_sweep() {
    let walk = large_step_walk();
    let bad = MisWithStaleProbability {
        b_q: walk.large_step_density(),
        kernel: Mh::new(walk),
        p_weights: 0.33,
    };
    let sweep = Sweep::run("large-step MIS weighted with p = 0.33", &bad, 3_000);
    let (d, p) = ks_uniform(&sweep.p_values);
    assert!(p < KS_LEVEL, "KS D = {d:.3}, p = {p:.2e}");
    let failing = sweep.p_values.iter().filter(|&&p| p < 0.05).count();
    assert!(
        2 * failing > SEEDS as usize,
        "only {failing} of {SEEDS} checks reject at 0.05"
    );
}
