//! The pairwise orbital scheme of delayed-rejection MLT (issue 9, item 3): the wrapped Cauchy
//! sampler, the pairwise polar Kelemen first stage and the orbital second stage match their
//! densities, z stays on its orbit across the torus seams, the two-stage flows of the
//! closed-form acceptance of eq. 11 balance on every sampled triple, and a chain using them
//! keeps its target; each property has a negative control that must fail it.
//!
//! Run with `cargo test -p pss --release --test orbital -- --nocapture` to see the statistics.
//!
//! # Statistics
//! Every chi-square / KS test of correct code must pass at the Sidak level for [`TESTS`]
//! tests at overall level 0.01; a statistical negative control counts as caught when its
//! p-value is below [`OVERWHELMING`] = 1e-6. Flow balance is an identity checked to `1e-9`
//! relative on every triple: deterministic. Seeds are fixed: the outcome is deterministic.
//!
//! # Flows and chains
//! Detailed balance of "propose `y`, reject it, propose `z`, accept it" is, for each triple
//! `(x, y, z)`, `flow(x -> z via y) = flow(z -> x via y)` with the flow
//! `pi(x) q1(y|x) (1 - a1(x, y)) q2(z|x, y) a2(x, z)` and `a2` from eq. 11
//! ([`orbital_log_flow`]). It holds exactly when `q1(y|z) = q1(y|x)` and
//! `q2(x|z, y) = q2(z|x, y)`, which is what the proposals promise; the negative controls (a
//! first stage of independent 1-D Kelemen steps; an orbit built from the raw, not minimal,
//! displacement) break it on most or many triples.
//!
//! Chains run the library's kernel, `mcmc_core::DelayedRejection::orbital`: stage 1 MH with
//! the pairwise step, stage 2 (after a rejection) the orbital proposal with eq. 11; chi-square
//! stationarity from exact starts checks it on the torus target whose modes straddle both
//! seams and on a 3-D target with a lone third coordinate. Stationarity from exact starts is
//! a weak detector of these local errors (20 000 starts, 30-300 steps, measured while writing
//! this file: p = 0.44-0.93 for the independent first stage, 1.8e-2 to 1e-15 for the raw
//! orbit, 1e-9 to 7e-3 for a plain Metropolis second stage), so the negative controls are
//! the flow identities, which catch them deterministically.

use std::f64::consts::{PI, TAU};

use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::testing::{
    chi_square_test, chi_square_two_sample, kolmogorov_survival, sidak_alpha, ChiSquareReport,
    StationarityParams, ALPHA,
};
use mcmc_core::toy::special::normal_interval;
use mcmc_core::toy::{wrapped_normal_pdf, Bins, TorusMixture, ToyTarget};
use mcmc_core::{Kernel, Proposal, Proposed, Target};
use pss::{
    torus_displacement, wrap, Orbital, PairwiseKelemen, PairwiseKelemenParams, WrappedCauchy,
    RIOUX_LAVOIE2020_RHO,
};
use rand::{Rng, RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;

/// Chi-square / KS tests of correct code in this file (Sidak correction). Keep in sync.
const TESTS: usize = 14;

/// p-value below which a negative control counts as caught.
const OVERWHELMING: f64 = 1e-6;

fn level() -> f64 {
    sidak_alpha(ALPHA, TESTS)
}

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// One-sample Kolmogorov-Smirnov test against a continuous CDF: `(D, p)` with Stephens'
/// small-sample correction.
fn ks_one_sample(samples: &mut [f64], cdf: impl Fn(f64) -> f64) -> (f64, f64) {
    samples.sort_by(f64::total_cmp);
    let n = samples.len() as f64;
    let mut d = 0.0f64;
    for (i, &x) in samples.iter().enumerate() {
        let f = cdf(x);
        d = d.max(f - i as f64 / n).max((i + 1) as f64 / n - f);
    }
    let lambda = (n.sqrt() + 0.12 + 0.11 / n.sqrt()) * d;
    (d, kolmogorov_survival(lambda))
}

/// Probability of each of `bins` equal-width angle bins on `[-pi, pi)` under the density
/// `pdf`, by the midpoint rule with 200 points per bin.
fn angle_bin_probabilities(bins: usize, mut pdf: impl FnMut(f64) -> f64) -> Vec<f64> {
    let width = TAU / bins as f64;
    let m = 200;
    (0..bins)
        .map(|k| {
            let lo = -PI + k as f64 * width;
            (0..m)
                .map(|i| pdf(lo + (i as f64 + 0.5) * width / m as f64) * width / m as f64)
                .sum()
        })
        .collect()
}

fn angle_bin(theta: f64, bins: usize) -> usize {
    (((theta + PI) / TAU * bins as f64).floor() as usize).min(bins - 1)
}

/// The angle from `x - y` to `z - y` (minimal torus displacements) of the pair `(a, b)`.
fn orbit_angle(x: &[f64], y: &[f64], z: &[f64], a: usize, b: usize) -> f64 {
    let (ux, uy) = (
        torus_displacement(y[a], x[a]),
        torus_displacement(y[b], x[b]),
    );
    let (vx, vy) = (
        torus_displacement(y[a], z[a]),
        torus_displacement(y[b], z[b]),
    );
    (ux * vy - uy * vx).atan2(ux * vx + uy * vy)
}

/// `z` on the orbit of `(x, y)` at angle `theta`, for the pair `(a, b)` (built here
/// independently of the library: rotation of the minimal displacement `x - y`).
fn on_orbit(x: &[f64], y: &[f64], z: &mut [f64], a: usize, b: usize, theta: f64) {
    let (ux, uy) = (
        torus_displacement(y[a], x[a]),
        torus_displacement(y[b], x[b]),
    );
    let (s, c) = theta.sin_cos();
    z[a] = wrap(y[a] + c * ux - s * uy);
    z[b] = wrap(y[b] + s * ux + c * uy);
}

fn report(what: &str, r: &ChiSquareReport) {
    println!("{what}: {r}");
}

// ---------------------------------------------------------------------------------------------
// Wrapped Cauchy
// ---------------------------------------------------------------------------------------------

const ANGLE_SAMPLES: usize = 200_000;
const ANGLE_BINS: usize = 48;

fn wrapped_cauchy_samples(sample: impl Fn(&mut Pcg64) -> f64, seed: u64) -> Vec<f64> {
    let mut rng = Pcg64::seed_from_u64(seed);
    (0..ANGLE_SAMPLES).map(|_| sample(&mut rng)).collect()
}

/// Chi-square of angle samples against the bin probabilities of eq. 10 with concentration
/// `rho` (integrated numerically from the density, independently of the CDF).
fn angle_chi_square(samples: &[f64], rho: f64) -> ChiSquareReport {
    let probabilities = angle_bin_probabilities(ANGLE_BINS, |t| {
        (1.0 - rho * rho) / (TAU * (1.0 + rho * rho - 2.0 * rho * t.cos()))
    });
    let mut counts = vec![0u64; ANGLE_BINS];
    for &t in samples {
        counts[angle_bin(t, ANGLE_BINS)] += 1;
    }
    chi_square_test(&counts, &probabilities, 5.0)
}

/// The authors' sampler (notes section 2): `|theta| = acos((v + c) / (1 + c v))`,
/// `v = cos(2 pi u)`, `c = 2 rho / (1 + rho^2)`, random sign. Two uniforms.
fn reference_sampler(rho: f64, rng: &mut Pcg64) -> f64 {
    let c = 2.0 * rho / (1.0 + rho * rho);
    let v = (TAU * rng.random::<f64>()).cos();
    let t = ((v + c) / (1.0 + c * v)).clamp(-1.0, 1.0).acos();
    if rng.random::<f64>() < 0.5 {
        t
    } else {
        -t
    }
}

#[test]
fn wrapped_cauchy_sampler_matches_its_density_and_cdf() {
    for (i, rho) in [0.3, RIOUX_LAVOIE2020_RHO, 0.95].into_iter().enumerate() {
        let wc = WrappedCauchy::new(rho).unwrap();
        let mut samples = wrapped_cauchy_samples(|rng| wc.sample(rng), 100 + i as u64);
        let chi = angle_chi_square(&samples, rho);
        report(
            &format!("wrapped Cauchy rho {rho:.4}, chi-square vs eq. 10"),
            &chi,
        );
        chi.assert_passes("wrapped Cauchy sampler vs eq. 10", TESTS);
        let (d, p) = ks_one_sample(&mut samples, |t| wc.cdf(t));
        println!("wrapped Cauchy rho {rho:.4}, KS vs closed-form CDF: D = {d:.2e}, p = {p:.3}");
        assert!(
            p >= level(),
            "KS rejects the sampler for rho {rho}: p = {p}"
        );
    }
}

#[test]
fn wrapped_cauchy_matches_the_reference_implementation_law() {
    let wc = WrappedCauchy::rioux_lavoie2020();
    let ours = wrapped_cauchy_samples(|rng| wc.sample(rng), 7);
    let theirs = wrapped_cauchy_samples(|rng| reference_sampler(RIOUX_LAVOIE2020_RHO, rng), 8);
    let bin = |s: &[f64]| {
        let mut c = vec![0u64; ANGLE_BINS];
        for &t in s {
            c[angle_bin(t, ANGLE_BINS)] += 1;
        }
        c
    };
    let r = chi_square_two_sample(&bin(&ours), &bin(&theirs), 5.0);
    report(
        "inverse-CDF sampler vs the authors' acos sampler (two-sample)",
        &r,
    );
    r.assert_passes("inverse-CDF vs acos sampler", TESTS);
}

#[test]
fn wrapped_cauchy_negative_controls_are_rejected() {
    let wc = WrappedCauchy::rioux_lavoie2020();
    let samples = wrapped_cauchy_samples(|rng| wc.sample(rng), 9);
    // A wrong rho: the default sampler tested against rho = 0.75.
    let wrong_rho = angle_chi_square(&samples, 0.75);
    report(
        "negative control: rho e^-1/4 samples vs rho 0.75",
        &wrong_rho,
    );
    assert!(wrong_rho.p_value < OVERWHELMING, "{wrong_rho}");
    // A wrong sampler: the quantile without its factor 2 (theta = atan(tan(..) / k)).
    let inverse_k = (1.0 - RIOUX_LAVOIE2020_RHO) / (1.0 + RIOUX_LAVOIE2020_RHO);
    let halved = wrapped_cauchy_samples(
        |rng| (inverse_k * (PI * (rng.random::<f64>() - 0.5)).tan()).atan(),
        10,
    );
    let wrong_sampler = angle_chi_square(&halved, RIOUX_LAVOIE2020_RHO);
    report(
        "negative control: quantile without its factor 2",
        &wrong_sampler,
    );
    assert!(wrong_sampler.p_value < OVERWHELMING, "{wrong_sampler}");
    let mut halved = halved;
    let (_, p) = ks_one_sample(&mut halved, |t| wc.cdf(t));
    assert!(p < OVERWHELMING, "KS misses the halved quantile: p = {p}");
}

// ---------------------------------------------------------------------------------------------
// Pairwise polar Kelemen step
// ---------------------------------------------------------------------------------------------

const STEP_SAMPLES: usize = 200_000;
const RADIUS_BINS: usize = 10;
const PHI_BINS: usize = 8;

/// Points whose pairs straddle the seams, and one inside.
const STARTS: [[f64; 2]; 3] = [[0.999, 0.0005], [0.5, 0.99999], [0.3, 0.6]];

/// `(r, phi)` of `STEP_SAMPLES` stage-1 moves of a pair (minimal displacements), cycling
/// over [`STARTS`].
fn polar_moves(step: &PairwiseKelemen, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut y = Vec::new();
    (0..STEP_SAMPLES)
        .map(|i| {
            let x = STARTS[i % STARTS.len()].to_vec();
            step.propose(&x, &mut y, &mut rng);
            let (dx, dy) = (
                torus_displacement(x[0], y[0]),
                torus_displacement(x[1], y[1]),
            );
            (dx.hypot(dy), dy.atan2(dx))
        })
        .collect()
}

/// Bin probabilities of polar cells (log-spaced radii on `[r_min, r_max]` x equal angles)
/// under the density `log_q(x, x + r (cos, sin))` that `step` reports, integrated in polar
/// coordinates (`r dr dphi`, midpoint rule); `x` is in the middle of the square.
fn polar_bin_probabilities(step: &PairwiseKelemen, params: PairwiseKelemenParams) -> Vec<f64> {
    let x = vec![0.5, 0.5];
    let m = 24;
    let mut probabilities = Vec::with_capacity(RADIUS_BINS * PHI_BINS);
    let edge =
        |k: usize| params.r_min * (params.r_max / params.r_min).powf(k as f64 / RADIUS_BINS as f64);
    for i in 0..RADIUS_BINS {
        let (r0, r1) = (edge(i), edge(i + 1));
        for j in 0..PHI_BINS {
            let p0 = -PI + TAU * j as f64 / PHI_BINS as f64;
            let mut p = 0.0;
            for a in 0..m {
                let r = r0 + (r1 - r0) * (a as f64 + 0.5) / m as f64;
                for b in 0..m {
                    let phi = p0 + TAU / PHI_BINS as f64 * (b as f64 + 0.5) / m as f64;
                    let y = vec![x[0] + r * phi.cos(), x[1] + r * phi.sin()];
                    p += step.log_q(&x, &y).exp() * r;
                }
            }
            probabilities.push(p * (r1 - r0) / m as f64 * TAU / PHI_BINS as f64 / m as f64);
        }
    }
    probabilities
}

fn polar_counts(moves: &[(f64, f64)], params: PairwiseKelemenParams) -> Vec<u64> {
    let mut counts = vec![0u64; RADIUS_BINS * PHI_BINS];
    let log_ratio = (params.r_max / params.r_min).ln();
    for &(r, phi) in moves {
        let i = ((r / params.r_min).ln() / log_ratio * RADIUS_BINS as f64).floor();
        let i = (i.max(0.0) as usize).min(RADIUS_BINS - 1);
        counts[i * PHI_BINS + angle_bin(phi, PHI_BINS)] += 1;
    }
    counts
}

#[test]
fn polar_kelemen_radius_and_angle_match_the_density() {
    let params = PairwiseKelemenParams::drmlt2020();
    let step = PairwiseKelemen::new(params);
    let moves = polar_moves(&step, 21);
    let mut radii: Vec<f64> = moves.iter().map(|m| m.0).collect();
    let (d, p) = ks_one_sample(&mut radii, |r| params.radius_cdf(r));
    println!("polar Kelemen radius, KS vs log-uniform CDF: D = {d:.2e}, p = {p:.3}");
    assert!(p >= level(), "radius KS: p = {p}");
    let probabilities = polar_bin_probabilities(&step, params);
    let total: f64 = probabilities.iter().sum();
    assert!((total - 1.0).abs() < 1e-4, "log_q integrates to {total}");
    let r = chi_square_test(&polar_counts(&moves, params), &probabilities, 5.0);
    report("polar Kelemen (r, phi) cells vs integrated log_q", &r);
    r.assert_passes("polar Kelemen cells vs log_q", TESTS);
}

#[test]
fn polar_kelemen_negative_controls_are_rejected() {
    // The authors' 1.9 scale sampled, the paper's unscaled radius law tested.
    let scaled = polar_moves(
        &PairwiseKelemen::new(PairwiseKelemenParams::drmlt2020()),
        22,
    );
    let unscaled = PairwiseKelemenParams::kelemen2002();
    let mut radii: Vec<f64> = scaled.iter().map(|m| m.0).collect();
    let (_, p) = ks_one_sample(&mut radii, |r| unscaled.radius_cdf(r));
    println!("negative control: 1.9-scaled radii vs the unscaled law: KS p = {p:.3e}");
    assert!(p < OVERWHELMING);
    // A wrong radius density with the right support: uniform on [r_min, r_max].
    let params = PairwiseKelemenParams::drmlt2020();
    let step = PairwiseKelemen::new(params);
    let moves = polar_moves(&step, 23);
    let edge =
        |k: usize| params.r_min * (params.r_max / params.r_min).powf(k as f64 / RADIUS_BINS as f64);
    let uniform_radius: Vec<f64> = (0..RADIUS_BINS * PHI_BINS)
        .map(|c| {
            let i = c / PHI_BINS;
            (edge(i + 1) - edge(i)) / (params.r_max - params.r_min) / PHI_BINS as f64
        })
        .collect();
    let r = chi_square_test(&polar_counts(&moves, params), &uniform_radius, 5.0);
    report(
        "negative control: radius tested against a uniform radius law",
        &r,
    );
    assert!(r.p_value < OVERWHELMING, "{r}");
    // A wrong angle: the direction drawn on a half circle only would leave half the cells
    // empty; instead test the two coordinates moved independently by Kelemen 1-D steps
    // (the product law the paper replaces) against the polar density.
    let mut rng = Pcg64::seed_from_u64(24);
    let independent: Vec<(f64, f64)> = (0..STEP_SAMPLES)
        .map(|_| {
            let mut d = [0.0; 2];
            for v in &mut d {
                let r = params.radius(rng.random());
                *v = if rng.random::<f64>() < 0.5 { r } else { -r };
            }
            (d[0].hypot(d[1]), d[1].atan2(d[0]))
        })
        .filter(|m| m.0 <= params.r_max)
        .collect();
    let r = chi_square_test(
        &polar_counts(&independent, params),
        &polar_bin_probabilities(&step, params),
        5.0,
    );
    report(
        "negative control: two independent 1-D Kelemen steps vs the polar law",
        &r,
    );
    assert!(r.p_value < OVERWHELMING, "{r}");
}

#[test]
fn lone_coordinate_step_matches_the_1d_density() {
    let params = PairwiseKelemenParams::drmlt2020();
    let step = PairwiseKelemen::new(params);
    let mut rng = Pcg64::seed_from_u64(31);
    let mut y = Vec::new();
    // Signed log-radius bins: 2 x RADIUS_BINS.
    let edge =
        |k: usize| params.r_min * (params.r_max / params.r_min).powf(k as f64 / RADIUS_BINS as f64);
    let mut counts = vec![0u64; 2 * RADIUS_BINS];
    for i in 0..STEP_SAMPLES {
        let x = vec![[0.9995, 0.0001, 0.4][i % 3]];
        step.propose(&x, &mut y, &mut rng);
        let d = torus_displacement(x[0], y[0]);
        let k = ((d.abs() / params.r_min).ln() / (params.r_max / params.r_min).ln()
            * RADIUS_BINS as f64)
            .floor()
            .clamp(0.0, (RADIUS_BINS - 1) as f64) as usize;
        counts[usize::from(d > 0.0) * RADIUS_BINS + k] += 1;
    }
    // Expected from the reported density, integrated numerically.
    let m = 400;
    let x = vec![0.5];
    let probabilities: Vec<f64> = (0..2 * RADIUS_BINS)
        .map(|c| {
            let sign = if c >= RADIUS_BINS { 1.0 } else { -1.0 };
            let (r0, r1) = (edge(c % RADIUS_BINS), edge(c % RADIUS_BINS + 1));
            (0..m)
                .map(|a| {
                    let r = r0 + (r1 - r0) * (a as f64 + 0.5) / m as f64;
                    step.log_q(&x, &vec![0.5 + sign * r]).exp() * (r1 - r0) / m as f64
                })
                .sum()
        })
        .collect();
    let r = chi_square_test(&counts, &probabilities, 5.0);
    report("lone coordinate: signed log-radius bins vs log_q", &r);
    r.assert_passes("lone coordinate step vs log_q", TESTS);
}

// ---------------------------------------------------------------------------------------------
// Orbital stage
// ---------------------------------------------------------------------------------------------

/// A current state and rejected candidate whose first pair straddles both seams, a second
/// pair inside, and a lone fifth coordinate.
fn seam_x_y() -> (Vec<f64>, Vec<f64>) {
    let x = vec![0.998, 0.003, 0.4, 0.7, 0.25];
    let y = vec![0.007, 0.994, 0.41, 0.69, 0.26];
    (x, y)
}

#[test]
fn orbital_z_stays_on_the_circle_centred_at_y_through_x() {
    let (stage1, stage2) = (PairwiseKelemen::default(), Orbital::default());
    let mut rng = Pcg64::seed_from_u64(41);
    let (mut y, mut z) = (Vec::new(), Vec::new());
    let mut worst = 0.0f64;
    let mut crossed = 0;
    for i in 0..100_000 {
        let x: Vec<f64> = (0..5)
            .map(|k| {
                let u: f64 = rng.random();
                if (i + k) % 3 == 0 {
                    wrap(0.03 * (u - 0.5))
                } else {
                    u
                }
            })
            .collect();
        stage1.propose(&x, &mut y, &mut rng);
        assert_eq!(
            stage2.propose(&x, &y, &mut z, &mut rng),
            Proposed::symmetric()
        );
        assert!(z.iter().all(|v| (0.0..1.0).contains(v)));
        for (a, b) in [(0, 1), (2, 3)] {
            let r = torus_displacement(y[a], x[a]).hypot(torus_displacement(y[b], x[b]));
            let s = torus_displacement(y[a], z[a]).hypot(torus_displacement(y[b], z[b]));
            worst = worst.max((r - s).abs() / r);
            if (z[a] - y[a]).abs() > 0.5 || (z[b] - y[b]).abs() > 0.5 {
                crossed += 1;
            }
        }
        assert_eq!(z[4], x[4], "the lone coordinate stays at x");
        let (forward, reverse) = (stage2.log_q(&x, &y, &z), stage2.log_q(&z, &y, &x));
        assert!(forward.is_finite() && (forward - reverse).abs() < 1e-9);
        let (q1x, q1z) = (stage1.log_q(&x, &y), stage1.log_q(&z, &y));
        assert!((q1x - q1z).abs() < 1e-9, "q1(y|x) {q1x} vs q1(y|z) {q1z}");
    }
    println!("orbit radius: worst relative error {worst:.2e}; {crossed} pairs wrapped a seam");
    assert!(worst < 1e-12);
    assert!(crossed > 1000, "the seams were not exercised: {crossed}");

    // Negative control: the same rotation applied to the *raw* displacement x - y (what a
    // non-torus implementation does) leaves the orbit when the pair straddles a seam.
    let (x, y) = seam_x_y();
    let theta: f64 = 0.3;
    let (ux, uy) = (x[0] - y[0], x[1] - y[1]);
    let (s, c) = theta.sin_cos();
    let raw = [wrap(y[0] + c * ux - s * uy), wrap(y[1] + s * ux + c * uy)];
    let r = torus_displacement(y[0], x[0]).hypot(torus_displacement(y[1], x[1]));
    let s_raw = torus_displacement(y[0], raw[0]).hypot(torus_displacement(y[1], raw[1]));
    println!("negative control: raw displacement orbit radius {s_raw:.4} vs {r:.4}");
    assert!((s_raw - r).abs() > 0.1 * r);
    let mut z_raw = x.clone();
    z_raw[0] = raw[0];
    z_raw[1] = raw[1];
    assert_eq!(stage2.log_q(&x, &y, &z_raw), f64::NEG_INFINITY);
}

/// Angle histograms of `n` orbital draws from fixed `(x, y)` for the two pairs.
fn orbital_angles(stage2: &Orbital, n: usize, seed: u64) -> Vec<(f64, f64)> {
    let (x, y) = seam_x_y();
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut z = Vec::new();
    (0..n)
        .map(|_| {
            stage2.propose(&x, &y, &mut z, &mut rng);
            (orbit_angle(&x, &y, &z, 0, 1), orbit_angle(&x, &y, &z, 2, 3))
        })
        .collect()
}

/// Bin probabilities of the first pair's angle under `density.log_q(x, y, z(theta))`.
fn orbit_bin_probabilities(density: &Orbital, bins: usize) -> Vec<f64> {
    let (x, y) = seam_x_y();
    let mut z = x.clone();
    angle_bin_probabilities(bins, |t| {
        on_orbit(&x, &y, &mut z, 0, 1, t);
        density.log_q(&x, &y, &z).exp()
    })
}

#[test]
fn orbital_log_q_is_the_density_of_the_angle() {
    let stage2 = Orbital::default();
    let angles = orbital_angles(&stage2, ANGLE_SAMPLES, 51);
    // The first pair (across the seams) alone: the second pair at theta = 0 contributes
    // log p_WC(0) to log_q, removed here.
    let log_p0 = stage2.angle.log_pdf(0.0);
    let (x, y) = seam_x_y();
    let mut z = x.clone();
    let probabilities = angle_bin_probabilities(ANGLE_BINS, |t| {
        on_orbit(&x, &y, &mut z, 0, 1, t);
        on_orbit(&x, &y, &mut z, 2, 3, 0.0);
        (stage2.log_q(&x, &y, &z) - log_p0).exp()
    });
    let total: f64 = probabilities.iter().sum();
    assert!(
        (total - 1.0).abs() < 1e-6,
        "log_q integrates to {total} over the orbit"
    );
    let mut counts = vec![0u64; ANGLE_BINS];
    for a in &angles {
        counts[angle_bin(a.0, ANGLE_BINS)] += 1;
    }
    let r = chi_square_test(&counts, &probabilities, 5.0);
    report("orbital angle (seam pair) vs integrated log_q", &r);
    r.assert_passes("orbital angle vs log_q", TESTS);

    // Both pairs jointly: log_q is the sum over pairs (8 x 8 cells, 2-D midpoint rule).
    let cells = 8;
    let m = 40;
    let width = TAU / cells as f64;
    let mut joint = vec![0.0; cells * cells];
    for (i, p) in joint.iter_mut().enumerate() {
        let (lo0, lo1) = (
            -PI + (i / cells) as f64 * width,
            -PI + (i % cells) as f64 * width,
        );
        for a in 0..m {
            on_orbit(
                &x,
                &y,
                &mut z,
                0,
                1,
                lo0 + (a as f64 + 0.5) * width / m as f64,
            );
            for b in 0..m {
                on_orbit(
                    &x,
                    &y,
                    &mut z,
                    2,
                    3,
                    lo1 + (b as f64 + 0.5) * width / m as f64,
                );
                *p += stage2.log_q(&x, &y, &z).exp() * (width / m as f64).powi(2);
            }
        }
    }
    let mut counts = vec![0u64; cells * cells];
    for a in &angles {
        counts[angle_bin(a.0, cells) * cells + angle_bin(a.1, cells)] += 1;
    }
    let r = chi_square_test(&counts, &joint, 5.0);
    report("orbital angles of both pairs vs integrated joint log_q", &r);
    r.assert_passes("orbital joint angles vs log_q", TESTS);
}

#[test]
fn orbital_wrong_rho_is_rejected() {
    let stage2 = Orbital::default();
    let angles = orbital_angles(&stage2, ANGLE_SAMPLES, 52);
    let wrong = Orbital::new(WrappedCauchy::new(0.75).unwrap());
    let probabilities = orbit_bin_probabilities(&wrong, ANGLE_BINS);
    let mut counts = vec![0u64; ANGLE_BINS];
    for a in &angles {
        counts[angle_bin(a.0, ANGLE_BINS)] += 1;
    }
    // The second pair's factor is constant in these bins only up to its own angle; the
    // probabilities are normalised over the first pair's angle.
    let total: f64 = probabilities.iter().sum();
    let probabilities: Vec<f64> = probabilities.iter().map(|p| p / total).collect();
    let r = chi_square_test(&counts, &probabilities, 5.0);
    report(
        "negative control: orbital angles vs the rho = 0.75 log_q",
        &r,
    );
    assert!(r.p_value < OVERWHELMING, "{r}");
}

// ---------------------------------------------------------------------------------------------
// A chain with the orbital acceptance (eq. 11)
// ---------------------------------------------------------------------------------------------

/// A 3-D target: [`TorusMixture::across_seam`] on the first pair times a wrapped normal
/// (mean 0.97, sd 0.06, across the seam) on the lone third coordinate.
///
/// Bins: a coarse `4 x 4 x 4` grid of `[0, 1)^3` (cell edges at multiples of 1/4, so the
/// seams are cell edges), with exact probabilities from the normal CDF differences of the 7
/// nearest periodic images per axis (as the torus mixture's own bins). Coarse cells give the
/// chi-square its power against smooth, large-scale departures.
#[derive(Clone, Debug)]
struct TorusTimesSeam {
    torus: TorusMixture,
}

const THIRD: (f64, f64) = (0.97, 0.06);

/// Cells per axis of [`TorusTimesSeam`]'s bins.
const CELLS: usize = 4;

/// `P(lo <= X < hi)` for the wrapped normal `(mean, sd)` on `[0, 1)`.
fn wrapped_interval(lo: f64, hi: f64, mean: f64, sd: f64) -> f64 {
    (-3..=3)
        .map(|m| {
            let m = f64::from(m);
            normal_interval((lo + m - mean) / sd, (hi + m - mean) / sd)
        })
        .sum()
}

impl Target for TorusTimesSeam {
    type State = Vec<f64>;
    type Payload = ();
    fn evaluate(&self, x: &mut Vec<f64>, _payload: &mut ()) -> f64 {
        self.log_density(x)
    }
}

impl ToyTarget for TorusTimesSeam {
    fn name(&self) -> &'static str {
        "torus mixture x seam normal"
    }
    fn dim(&self) -> usize {
        3
    }
    fn log_density(&self, x: &[f64]) -> f64 {
        if x.len() != 3 || !(0.0..1.0).contains(&x[2]) {
            return f64::NEG_INFINITY;
        }
        self.torus.log_density(&x[..2]) + wrapped_normal_pdf(x[2], THIRD.0, THIRD.1).ln()
    }
    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let mut x = self.torus.sample_exact(rng);
        let n: f64 = StandardNormal.sample(rng);
        x.push(wrap(THIRD.0 + THIRD.1 * n));
        x
    }
    fn bins(&self) -> Bins {
        let w = 1.0 / CELLS as f64;
        let cell = |i: usize| (i as f64 * w, (i + 1) as f64 * w);
        let mut probabilities = Vec::with_capacity(CELLS.pow(3));
        for i in 0..CELLS {
            for j in 0..CELLS {
                let pair: f64 = self
                    .torus
                    .components()
                    .iter()
                    .map(|c| {
                        c.weight
                            * wrapped_interval(cell(i).0, cell(i).1, c.mean[0], c.sd[0])
                            * wrapped_interval(cell(j).0, cell(j).1, c.mean[1], c.sd[1])
                    })
                    .sum();
                for k in 0..CELLS {
                    probabilities
                        .push(pair * wrapped_interval(cell(k).0, cell(k).1, THIRD.0, THIRD.1));
                }
            }
        }
        Bins::new(probabilities, |x| {
            let c = |v: f64| ((v * CELLS as f64) as usize).min(CELLS - 1);
            (c(x[0]) * CELLS + c(x[1])) * CELLS + c(x[2])
        })
    }
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0; 3], vec![1.0; 3])
    }
}

/// Independent 1-D Kelemen steps per coordinate (the product law of PSSMLT): not circularly
/// symmetric per pair, so eq. 11 is wrong with it (negative control).
#[derive(Clone, Copy, Debug)]
struct IndependentKelemen(PairwiseKelemenParams);

impl Proposal<Vec<f64>> for IndependentKelemen {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clone_from(x);
        for v in y.iter_mut() {
            let r = self.0.radius(rng.random());
            *v = wrap(*v + if rng.random::<f64>() < 0.5 { r } else { -r });
        }
        Proposed::symmetric()
    }
    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        from.iter()
            .zip(to)
            .map(|(a, b)| self.0.single_log_density(torus_displacement(*a, *b)))
            .sum()
    }
    fn is_symmetric(&self) -> bool {
        true
    }
}

/// The orbital rotation applied to the raw displacement `x - y` (no minimal image):
/// negative control for the torus handling.
#[derive(Clone, Copy, Debug)]
struct RawOrbital(WrappedCauchy);

impl ConditionalProposal<Vec<f64>> for RawOrbital {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &Vec<f64>,
        y: &Vec<f64>,
        z: &mut Vec<f64>,
        rng: &mut R,
    ) -> Proposed {
        z.clone_from(x);
        for k in 0..x.len() / 2 {
            let (a, b) = (2 * k, 2 * k + 1);
            let (ux, uy) = (x[a] - y[a], x[b] - y[b]);
            let (s, c) = self.0.sample(rng).sin_cos();
            z[a] = wrap(y[a] + c * ux - s * uy);
            z[b] = wrap(y[b] + s * ux + c * uy);
        }
        Proposed::symmetric()
    }
    fn log_q(&self, _x: &Vec<f64>, _y: &Vec<f64>, _z: &Vec<f64>) -> f64 {
        0.0
    }
}

/// Wide radii, so that few steps cross the modes and the seams often.
fn wide() -> PairwiseKelemenParams {
    PairwiseKelemenParams::new(0.01, 0.2).unwrap()
}

const CHAIN_STARTS: usize = 20_000;
const CHAIN_STEPS: u64 = 30;

fn run<T: ToyTarget, K: Kernel<T> + Clone>(target: &T, kernel: &K, seed: u64) -> ChiSquareReport {
    mcmc_core::testing::toy_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(CHAIN_STARTS, CHAIN_STEPS, seed),
    )
}

#[test]
fn orbital_rule_keeps_targets_across_the_seams() {
    let kernel =
        mcmc_core::DelayedRejection::orbital(PairwiseKelemen::new(wide()), Orbital::default());
    let torus = TorusMixture::across_seam();
    let r = run(&torus, &kernel, 61);
    report("eq. 11 chain on the torus mixture (2-D)", &r);
    r.assert_passes("orbital DR on torus mixture", TESTS);
    let three = TorusTimesSeam { torus };
    let r = run(&three, &kernel, 62);
    report(
        "eq. 11 chain on torus x seam normal (3-D, lone coordinate)",
        &r,
    );
    r.assert_passes("orbital DR on 3-D target", TESTS);
}

/// `log pi(x) + log q1(y | x) + log(1 - a1(x, y)) + log q2(z | x, y) + log a2(x, z)` with
/// `a1 = min(1, pi(y) / pi(x))` and `a2` from eq. 11: the log probability flow density of
/// "propose y, reject it, propose z, accept it" that an orbital DR kernel realises.
fn orbital_log_flow<T: ToyTarget>(
    target: &T,
    q1: &impl Proposal<Vec<f64>>,
    q2: &impl ConditionalProposal<Vec<f64>>,
    [x, y, z]: [&Vec<f64>; 3],
) -> f64 {
    let (lx, ly, lz) = (
        target.log_density(x),
        target.log_density(y),
        target.log_density(z),
    );
    if lx == f64::NEG_INFINITY || ly >= lx {
        return f64::NEG_INFINITY;
    }
    let py = (ly - lx).exp();
    let a2 = (((lz - lx).exp() - py).max(0.0) / (1.0 - py)).min(1.0);
    lx + q1.log_q(x, y) + (-py).ln_1p() + q2.log_q(x, y, z) + a2.ln()
}

/// Over `n` triples `x ~ pi` (half of them moved next to a seam), `y ~ q1(. | x)`,
/// `z ~ q2(. | x, y)`: the number of triples with a positive flow either way, and the
/// number whose forward flow `x -> z` (through `y`) and reverse flow `z -> x` (through the
/// same `y`) differ by more than `1e-9` relative. Detailed balance of the two-stage kernel
/// is exactly "no such triple".
fn flow_mismatches<T: ToyTarget>(
    target: &T,
    q1: &impl Proposal<Vec<f64>>,
    q2: &impl ConditionalProposal<Vec<f64>>,
    n: usize,
    seed: u64,
) -> (usize, usize) {
    let mut rng = Pcg64::seed_from_u64(seed);
    let (mut y, mut z) = (Vec::new(), Vec::new());
    let (mut informative, mut mismatched) = (0, 0);
    for i in 0..n {
        let mut x = target.sample_exact(&mut rng);
        if i % 2 == 0 {
            x[0] = wrap(0.05 * (rng.random::<f64>() - 0.5));
        }
        q1.propose(&x, &mut y, &mut rng);
        if matches!(
            q2.propose(&x, &y, &mut z, &mut rng),
            Proposed::Invalid { .. }
        ) {
            continue;
        }
        let forward = orbital_log_flow(target, q1, q2, [&x, &y, &z]);
        let reverse = orbital_log_flow(target, q1, q2, [&z, &y, &x]);
        if forward == f64::NEG_INFINITY && reverse == f64::NEG_INFINITY {
            continue;
        }
        informative += 1;
        let balanced = (forward - reverse).abs() <= 1e-9 * forward.abs().max(1.0);
        if !balanced {
            mismatched += 1;
        }
    }
    (informative, mismatched)
}

const TRIPLES: usize = 20_000;

#[test]
fn orbital_flows_balance_on_orbit_triples() {
    let target = TorusTimesSeam {
        torus: TorusMixture::across_seam(),
    };
    for (what, params) in [
        ("default radii", PairwiseKelemenParams::drmlt2020()),
        ("wide radii", wide()),
    ] {
        let (informative, mismatched) = flow_mismatches(
            &target,
            &PairwiseKelemen::new(params),
            &Orbital::default(),
            TRIPLES,
            71,
        );
        println!("flow balance, {what}: {mismatched} of {informative} informative triples differ");
        assert!(informative > TRIPLES / 4, "too few informative triples");
        assert_eq!(mismatched, 0);
    }
}

#[test]
fn orbital_flow_negative_controls_fail() {
    let target = TorusTimesSeam {
        torus: TorusMixture::across_seam(),
    };
    let independent = flow_mismatches(
        &target,
        &IndependentKelemen(wide()),
        &Orbital::default(),
        TRIPLES,
        72,
    );
    let raw = flow_mismatches(
        &target,
        &PairwiseKelemen::new(wide()),
        &RawOrbital(WrappedCauchy::rioux_lavoie2020()),
        TRIPLES,
        73,
    );
    for (what, (informative, mismatched)) in [
        ("first stage of independent 1-D Kelemen steps", independent),
        ("orbit from the raw displacement", raw),
    ] {
        println!(
            "negative control, {what}: {mismatched} of {informative} informative triples differ"
        );
        assert!(
            mismatched * 20 > informative,
            "{what}: only {mismatched} of {informative} triples out of balance"
        );
    }
}
