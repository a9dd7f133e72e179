//! The bold first stage of orbital delayed-rejection MLT (DR paper section 4.4, Alg. 2,
//! stage 1; docs/methods/drmlt.md): the pairwise polar Kelemen step's radius and angle, and
//! the 1-D step of a lone coordinate, match the densities `log_q` reports, across the torus
//! seams; negative controls (the unscaled radius law, a uniform radius, two independent 1-D
//! steps) must fail.
//!
//! Run with `cargo test -p pss --release --test orbital_first_stage -- --nocapture` to see the
//! statistics; the levels are in `orbital_support`.

mod orbital_support;

use std::f64::consts::{PI, TAU};

use mcmc_core::testing::chi_square_test;
use mcmc_core::testing::ks_one_sample;
use mcmc_core::Proposal;
use orbital_support::{angle_bin, level, report, OVERWHELMING, TESTS};
use pss::{torus_displacement, PairwiseKelemen, PairwiseKelemenParams};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

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
    let radii: Vec<f64> = moves.iter().map(|m| m.0).collect();
    let (d, p) = ks_one_sample(&radii, |r| params.radius_cdf(r));
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
    let radii: Vec<f64> = scaled.iter().map(|m| m.0).collect();
    let (_, p) = ks_one_sample(&radii, |r| unscaled.radius_cdf(r));
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
