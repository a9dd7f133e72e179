//! The angle law of the orbital second stage of delayed-rejection MLT (DR paper section 4.4,
//! eq. 10; docs/methods/drmlt.md): the wrapped Cauchy sampler matches its density and its
//! closed-form CDF, and the law of the authors' two-uniform sampler; negative controls (a
//! wrong concentration, a quantile without its factor 2) must fail.
//!
//! Run with `cargo test -p pss --release --test orbital_wrapped_cauchy -- --nocapture` to see
//! the statistics; the levels are in `orbital_support`.

mod orbital_support;

use std::f64::consts::{PI, TAU};

use mcmc_core::testing::{chi_square_test, chi_square_two_sample, ks_one_sample, ChiSquareReport};
use orbital_support::{
    angle_bin, angle_bin_probabilities, level, report, ANGLE_BINS, ANGLE_SAMPLES, OVERWHELMING,
    TESTS,
};
use pss::{WrappedCauchy, RIOUX_LAVOIE2020_RHO};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

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

/// The authors' sampler (their implementation of the DR paper, as quoted in
/// `mcmc_core::delayed_rejection::WrappedCauchy`): `|theta| = acos((v + c) / (1 + c v))`,
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
        let samples = wrapped_cauchy_samples(|rng| wc.sample(rng), 100 + i as u64);
        let chi = angle_chi_square(&samples, rho);
        report(
            &format!("wrapped Cauchy rho {rho:.4}, chi-square vs eq. 10"),
            &chi,
        );
        chi.assert_passes("wrapped Cauchy sampler vs eq. 10", TESTS);
        let (d, p) = ks_one_sample(&samples, |t| wc.cdf(t));
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
    let (_, p) = ks_one_sample(&halved, |t| wc.cdf(t));
    assert!(p < OVERWHELMING, "KS misses the halved quantile: p = {p}");
}

/// The angle of a rotation `(cos, sin)`.
fn angle_of((cos, sin): (f64, f64)) -> f64 {
    sin.atan2(cos)
}

/// The rotation sampler without the angle (`WrappedCauchy::rotation`: half-angle tangent,
/// no arctangent, no sine-cosine) has the law of the quantile sampler: KS against the
/// closed-form CDF and a two-sample chi-square against `WrappedCauchy::sample`; negative
/// control: the same identities with the tangent scaled by `k` instead of `1 / k` (the
/// concentration's reciprocal), rejected by both.
#[test]
fn rotation_sampler_has_the_quantile_law() {
    let wc = WrappedCauchy::rioux_lavoie2020();
    let rotation = wrapped_cauchy_samples(|rng| angle_of(wc.sample_rotation(rng)), 21);
    let (d, p) = ks_one_sample(&rotation, |t| wc.cdf(t));
    println!("rotation sampler, KS vs the CDF: D = {d:.2e}, p = {p:.3}");
    assert!(p >= level(), "KS rejects the rotation sampler: p = {p}");
    let quantile = wrapped_cauchy_samples(|rng| wc.sample(rng), 22);
    let bin = |s: &[f64]| {
        let mut c = vec![0u64; ANGLE_BINS];
        for &t in s {
            c[angle_bin(t, ANGLE_BINS)] += 1;
        }
        c
    };
    let r = chi_square_two_sample(&bin(&rotation), &bin(&quantile), 5.0);
    report("rotation sampler vs quantile sampler (two-sample)", &r);
    r.assert_passes("rotation vs quantile sampler", TESTS);

    let k = (1.0 + RIOUX_LAVOIE2020_RHO) / (1.0 - RIOUX_LAVOIE2020_RHO);
    let wrong = wrapped_cauchy_samples(
        |rng| {
            let tau = (PI * (rng.random::<f64>() - 0.5)).tan() * k;
            let inv = 1.0 / (1.0 + tau * tau);
            angle_of(((1.0 - tau * tau) * inv, 2.0 * tau * inv))
        },
        23,
    );
    let (_, p) = ks_one_sample(&wrong, |t| wc.cdf(t));
    assert!(
        p < OVERWHELMING,
        "KS misses the reciprocal concentration: p = {p}"
    );
    let r = chi_square_two_sample(&bin(&wrong), &bin(&quantile), 5.0);
    report("negative control: tangent scaled by k, two-sample", &r);
    assert!(r.p_value < OVERWHELMING, "{r}");
}
