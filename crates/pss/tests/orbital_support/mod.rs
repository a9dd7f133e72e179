//! Shared by the orbital test files (`orbital_*.rs`): the significance level, the KS test and
//! the angle helpers of the pairwise orbital scheme of delayed-rejection MLT (DR paper,
//! section 4.4, Alg. 2; docs/methods/drmlt.md).
//!
//! # Statistics
//! Every chi-square / KS test of correct code in the orbital test files must pass at the
//! Sidak level for [`TESTS`] tests (all files together) at overall level 0.01; a statistical
//! negative control counts as caught when its p-value is below [`OVERWHELMING`] = 1e-6. Flow
//! balance is an identity checked to `1e-9` relative on every triple: deterministic. Seeds are
//! fixed: the outcome is deterministic.

// Each test file uses its own part of the helpers.
#![allow(dead_code)]

use std::f64::consts::{PI, TAU};

use mcmc_core::testing::{sidak_alpha, ChiSquareReport, ALPHA};
use pss::{torus_displacement, wrap};

/// Chi-square / KS tests of correct code in the orbital test files together (Sidak
/// correction): 7 in `orbital_wrapped_cauchy.rs`, 3 in `orbital_first_stage.rs`, 2 in
/// `orbital_second_stage.rs`, 2 in `orbital_balance.rs`. Keep in sync.
pub(crate) const TESTS: usize = 16;

/// p-value below which a negative control counts as caught.
pub(crate) const OVERWHELMING: f64 = 1e-6;

/// The Sidak level of one test of correct code.
pub(crate) fn level() -> f64 {
    sidak_alpha(ALPHA, TESTS)
}

/// Angle samples per histogram.
pub(crate) const ANGLE_SAMPLES: usize = 200_000;
/// Bins of an angle histogram on `[-pi, pi)`.
pub(crate) const ANGLE_BINS: usize = 48;

/// Probability of each of `bins` equal-width angle bins on `[-pi, pi)` under the density
/// `pdf`, by the midpoint rule with 200 points per bin.
pub(crate) fn angle_bin_probabilities(bins: usize, mut pdf: impl FnMut(f64) -> f64) -> Vec<f64> {
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

/// The bin of angle `theta` among `bins` equal-width bins on `[-pi, pi)`.
pub(crate) fn angle_bin(theta: f64, bins: usize) -> usize {
    (((theta + PI) / TAU * bins as f64).floor() as usize).min(bins - 1)
}

/// The angle from `x - y` to `z - y` (minimal torus displacements) of the pair `(a, b)`.
pub(crate) fn orbit_angle(x: &[f64], y: &[f64], z: &[f64], a: usize, b: usize) -> f64 {
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
pub(crate) fn on_orbit(x: &[f64], y: &[f64], z: &mut [f64], a: usize, b: usize, theta: f64) {
    let (ux, uy) = (
        torus_displacement(y[a], x[a]),
        torus_displacement(y[b], x[b]),
    );
    let (s, c) = theta.sin_cos();
    z[a] = wrap(y[a] + c * ux - s * uy);
    z[b] = wrap(y[b] + s * ux + c * uy);
}

/// Prints a chi-square report (see it with `--nocapture`).
pub(crate) fn report(what: &str, r: &ChiSquareReport) {
    println!("{what}: {r}");
}
