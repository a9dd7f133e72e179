//! The orbital second stage of delayed-rejection MLT (DR paper section 4.4, Alg. 2, stage 2;
//! docs/methods/drmlt.md): `z` stays on the circle centred at `y` through `x` across the torus
//! seams, with `q1(y|z) = q1(y|x)` and a symmetric `q2` (what eq. 11 needs), and `log_q` is
//! the density of the angles it draws; negative controls (the raw, not minimal, displacement;
//! a wrong concentration) must fail.
//!
//! Run with `cargo test -p pss --release --test orbital_second_stage -- --nocapture` to see
//! the statistics; the levels are in `orbital_support`.

mod orbital_support;

use std::f64::consts::{PI, TAU};

use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::testing::chi_square_test;
use mcmc_core::{Proposal, Proposed};
use orbital_support::{
    angle_bin, angle_bin_probabilities, on_orbit, orbit_angle, report, ANGLE_BINS, ANGLE_SAMPLES,
    OVERWHELMING, TESTS,
};
use pss::{torus_displacement, wrap, Orbital, PairwiseKelemen, WrappedCauchy};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

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
