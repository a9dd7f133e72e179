//! Chi-square goodness-of-fit tests of every BSDF's `sample` against its own `pdf`, in the style
//! of pbrt's `bsdfs` / `BSDFSampling` tests.
//!
//! For each case (BSDF, `wo`): draw `N` samples from `sample` with a seeded `Pcg64`, bin the
//! directions over the whole sphere in `(cos theta, phi)` (equal solid-angle bins), and compare
//! with the expected counts `N ∫_bin pdf dω` obtained by nested adaptive Simpson quadrature of
//! `pdf`. One extra bin holds the samples `sample` declined to produce (`None`), with expected
//! count `N (1 - ∫_S2 pdf)`: microfacet sampling loses the mass of directions that leave the
//! valid hemisphere, and `pdf` must not count it. Bins with expected count < 5 are pooled.
//! Delta lobes (smooth dielectric) are tested on the discrete lobe frequencies instead.
//!
//! Significance: alpha = 0.01 (`mcmc_core::testing::ALPHA`) for the whole file, split over the
//! [`total_tests`] tests with the Sidak correction `1 - (1 - alpha)^(1/M)`; pooling, statistic
//! and p-value come from `mcmc_core::testing::chi_square`. Negative controls (wrong pdf) must
//! fail at the same level. Run with `cargo test -p render --release --test bsdf_chi2 -- --nocapture` to see the
//! statistics of every case.

use glam::{Vec2, Vec3, Vec3A};
use mcmc_core::testing::chi_square::{self, MIN_EXPECTED};
use mcmc_core::testing::{sidak_alpha, ALPHA};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use render::material::{fresnel_dielectric, Bsdf, TransportMode};
use std::f64::consts::{PI, TAU};

/// Samples per case.
const SAMPLES: usize = 1_000_000;
/// Bins in `cos theta` over `[-1, 1]` (even, so that the horizon is a bin edge).
const COS_BINS: usize = 24;
/// Bins in `phi` over `[0, 2 pi)`.
const PHI_BINS: usize = 48;

/// Number of hypothesis tests in this file (glossy cases + delta cases), for Sidak.
fn total_tests() -> usize {
    glossy_cases().len() + smooth_dielectric_cases().len()
}

/// Per-test significance level: the file-wide [`ALPHA`] after the Sidak correction.
fn sidak_level() -> f64 {
    sidak_alpha(ALPHA, total_tests())
}

// ---------------------------------------------------------------------------------------------
// Binning, quadrature and the statistic.
// ---------------------------------------------------------------------------------------------

/// The direction with the given `cos theta` and `phi`.
fn direction(cos_theta: f64, phi: f64) -> Vec3A {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3A::new(
        (sin_theta * phi.cos()) as f32,
        (sin_theta * phi.sin()) as f32,
        cos_theta as f32,
    )
}

/// Bin index of a direction.
fn bin_of(w: Vec3A) -> usize {
    let c = f64::from(w.z).clamp(-1.0, 1.0);
    let ci = (((c + 1.0) * 0.5 * COS_BINS as f64) as usize).min(COS_BINS - 1);
    let mut phi = f64::from(w.y).atan2(f64::from(w.x));
    if phi < 0.0 {
        phi += TAU;
    }
    let pi = ((phi / TAU * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    ci * PHI_BINS + pi
}

/// Adaptive Simpson quadrature on `[a, b]` with at least `2^MIN_DEPTH` panels.
fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, eps: f64) -> f64 {
    const MIN_DEPTH: u32 = 2;
    const MAX_DEPTH: u32 = 12;
    fn rec(
        f: &dyn Fn(f64) -> f64,
        (a, b): (f64, f64),
        (fa, fm, fb): (f64, f64, f64),
        whole: f64,
        eps: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        let delta = left + right - whole;
        if depth >= MAX_DEPTH || (depth >= MIN_DEPTH && delta.abs() <= 15.0 * eps) {
            return left + right + delta / 15.0;
        }
        rec(f, (a, m), (fa, flm, fm), left, 0.5 * eps, depth + 1)
            + rec(f, (m, b), (fm, frm, fb), right, 0.5 * eps, depth + 1)
    }
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    rec(f, (a, b), (fa, fm, fb), whole, eps, 0)
}

/// `∫_bin pdf dω` for every bin (dω = d cos d phi), by nested adaptive Simpson.
fn integrate_bins(pdf: &dyn Fn(Vec3A) -> f32) -> Vec<f64> {
    let eps = 1e-8;
    let mut out = Vec::with_capacity(COS_BINS * PHI_BINS);
    for ci in 0..COS_BINS {
        let c0 = -1.0 + 2.0 * ci as f64 / COS_BINS as f64;
        let c1 = -1.0 + 2.0 * (ci + 1) as f64 / COS_BINS as f64;
        for pi in 0..PHI_BINS {
            let p0 = TAU * pi as f64 / PHI_BINS as f64;
            let p1 = TAU * (pi + 1) as f64 / PHI_BINS as f64;
            let inner = |c: f64| simpson(&|p| f64::from(pdf(direction(c, p))), p0, p1, eps);
            out.push(simpson(&inner, c0, c1, eps).max(0.0));
        }
    }
    out
}

/// Outcome of one chi-square test.
struct Chi2 {
    statistic: f64,
    dof: usize,
    p_value: f64,
    /// Samples in bins whose expected count is 0.
    stray: u64,
}

/// Pearson's statistic after pooling bins to an expected count of at least
/// [`MIN_EXPECTED`] (`mcmc_core::testing::chi_square`). Bins with zero expected count are left
/// out, their samples counted as `stray`.
fn chi2(observed: &[u64], expected: &[f64]) -> Chi2 {
    let pooled = chi_square::pool(observed, expected, MIN_EXPECTED);
    let statistic = chi_square::statistic(&pooled.observed, &pooled.expected);
    let dof = pooled.observed.len().saturating_sub(1);
    let p_value = if dof == 0 {
        1.0
    } else {
        chi_square::survival(statistic, dof as f64)
    };
    Chi2 {
        statistic,
        dof,
        p_value,
        stray: pooled.impossible,
    }
}

/// Samples `SAMPLES` directions of `bsdf` at `wo` and tests them against `pdf`.
fn run_case(bsdf: &Bsdf, wo: Vec3A, seed: u64, pdf: &dyn Fn(Vec3A) -> f32) -> Chi2 {
    let mode = TransportMode::Radiance;
    let mut rng = Pcg64::seed_from_u64(seed);
    let lost_bin = COS_BINS * PHI_BINS;
    let mut observed = vec![0u64; lost_bin + 1];
    for _ in 0..SAMPLES {
        let u: f32 = rng.random();
        let u2 = Vec2::new(rng.random(), rng.random());
        match bsdf.sample(wo, u, u2, mode) {
            Some(s) if s.pdf > 0.0 => observed[bin_of(s.wi)] += 1,
            _ => observed[lost_bin] += 1,
        }
    }
    let mut expected: Vec<f64> = integrate_bins(pdf)
        .into_iter()
        .map(|p| p * SAMPLES as f64)
        .collect();
    let total: f64 = expected.iter().sum();
    expected.push((SAMPLES as f64 - total).max(0.0));
    chi2(&observed, &expected)
}

// ---------------------------------------------------------------------------------------------
// Cases.
// ---------------------------------------------------------------------------------------------

/// A unit direction at polar angle `theta_deg` from `+z` (or from `-z` if `below`), azimuth
/// 30 degrees (off the bin edges).
fn wo_at(theta_deg: f64, below: bool) -> Vec3A {
    let t = theta_deg.to_radians();
    let c = if below { -t.cos() } else { t.cos() };
    direction(c, 30f64.to_radians())
}

/// A glossy (non-delta) test case.
struct Case {
    name: String,
    bsdf: Bsdf,
    wo: Vec3A,
}

/// Every non-delta case: Lambertian, rough conductor and rough dielectric over several `wo`
/// and roughnesses (`alpha` from 0.1 to 1; sharper lobes need finer bins than these).
fn glossy_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    let color = Vec3::new(0.9, 0.7, 0.5);
    for (theta, below) in [(0.0, false), (45.0, false), (85.0, false), (60.0, true)] {
        cases.push(Case {
            name: format!(
                "lambertian wo={theta}deg{}",
                if below { " below" } else { "" }
            ),
            bsdf: Bsdf::lambertian(color),
            wo: wo_at(theta, below),
        });
    }
    for alpha in [0.1f32, 0.3, 0.6, 1.0] {
        for (theta, below) in [(0.0, false), (45.0, false), (80.0, false), (30.0, true)] {
            cases.push(Case {
                name: format!(
                    "rough conductor alpha={alpha} wo={theta}deg{}",
                    if below { " below" } else { "" }
                ),
                bsdf: Bsdf::rough_conductor(color, alpha),
                wo: wo_at(theta, below),
            });
        }
    }
    for (eta, alphas) in [(1.5f32, &[0.1f32, 0.3, 0.7][..]), (1.0 / 1.33, &[0.3][..])] {
        for &alpha in alphas {
            for (theta, below) in [
                (0.0, false),
                (50.0, false),
                (80.0, false),
                (20.0, true),
                (60.0, true),
            ] {
                cases.push(Case {
                    name: format!(
                        "rough dielectric eta={eta:.3} alpha={alpha} wo={theta}deg{}",
                        if below { " inside" } else { "" }
                    ),
                    bsdf: Bsdf::rough_dielectric(eta, alpha, color),
                    wo: wo_at(theta, below),
                });
            }
        }
    }
    cases
}

/// Runs the glossy cases whose name starts with `prefix` and asserts they all pass.
fn run_family(prefix: &str) {
    let level = sidak_level();
    let mut failures = Vec::new();
    for (index, case) in glossy_cases().iter().enumerate() {
        if !case.name.starts_with(prefix) {
            continue;
        }
        let mode = TransportMode::Radiance;
        let pdf = |wi: Vec3A| case.bsdf.pdf(case.wo, wi, mode);
        let r = run_case(&case.bsdf, case.wo, 0x5eed_0000 + index as u64, &pdf);
        let line = format!(
            "{:<55} chi2 = {:>9.2}  dof = {:>4}  p = {:.4}  stray = {}",
            case.name, r.statistic, r.dof, r.p_value, r.stray
        );
        println!("{line}");
        // Samples in bins where the quadrature found no density at all: allow a few from bins
        // whose support the quadrature grid missed, but not a systematic leak.
        if r.p_value < level || r.stray > 10 {
            failures.push(line);
        }
    }
    assert!(
        failures.is_empty(),
        "chi-square test failed at level {level:.3e} (alpha {ALPHA}, Sidak over {} tests):\n{}",
        total_tests(),
        failures.join("\n")
    );
}

#[test]
fn lambertian_sampling_matches_pdf() {
    run_family("lambertian");
}

#[test]
fn rough_conductor_sampling_matches_pdf() {
    run_family("rough conductor");
}

#[test]
fn rough_dielectric_sampling_matches_pdf() {
    run_family("rough dielectric");
}

/// Smooth dielectric cases: `(eta, theta, below)`, including total internal reflection.
fn smooth_dielectric_cases() -> Vec<(f32, f64, bool)> {
    vec![
        (1.5, 0.0, false),
        (1.5, 60.0, false),
        (1.5, 85.0, false),
        (1.5, 30.0, true),
        (1.33, 40.0, true),
    ]
}

/// Delta lobes: the reflection/transmission choice is a Bernoulli(R) trial, tested with a
/// 2-cell chi-square; the directions must be exactly the mirror / Snell directions.
#[test]
fn smooth_dielectric_lobe_frequencies() {
    let level = sidak_level();
    let mut failures = Vec::new();
    for (index, (eta, theta, below)) in smooth_dielectric_cases().into_iter().enumerate() {
        let bsdf = Bsdf::smooth_dielectric(eta, Vec3::ONE);
        let wo = wo_at(theta, below);
        let r = f64::from(fresnel_dielectric(wo.z, eta));
        let mut rng = Pcg64::seed_from_u64(0xde17a + index as u64);
        let mut counts = [0u64; 2];
        for _ in 0..SAMPLES {
            let u: f32 = rng.random();
            let s = bsdf.sample(
                wo,
                u,
                Vec2::new(rng.random(), rng.random()),
                TransportMode::Radiance,
            );
            let s = s.expect("smooth dielectric always samples");
            assert!(s.is_specular);
            let reflected = s.wi.z * wo.z > 0.0;
            let p = if reflected { r } else { 1.0 - r };
            assert!(
                (f64::from(s.pdf) - p).abs() < 1e-6,
                "pdf {} vs lobe probability {p}",
                s.pdf
            );
            counts[usize::from(!reflected)] += 1;
        }
        let expected = [r * SAMPLES as f64, (1.0 - r) * SAMPLES as f64];
        let result = chi2(&counts, &expected);
        let line = format!(
            "smooth dielectric eta={eta} wo={theta}deg{}: R = {r:.4}, reflected {} of {SAMPLES}, \
             chi2 = {:.3}, dof = {}, p = {:.4}",
            if below { " inside" } else { "" },
            counts[0],
            result.statistic,
            result.dof,
            result.p_value
        );
        println!("{line}");
        // A certain outcome (R = 1 at total internal reflection) must be exact.
        let exact_ok = !(r >= 1.0 && counts[1] > 0);
        if result.p_value < level || !exact_ok {
            failures.push(line);
        }
    }
    assert!(
        failures.is_empty(),
        "level {level:.3e}:\n{}",
        failures.join("\n")
    );
}

/// Negative controls: the same machinery must reject a sampler whose pdf is wrong, at the same
/// corrected level, so a passing test means something.
#[test]
fn negative_controls_are_rejected() {
    let level = sidak_level();
    // Cosine-weighted samples tested against the uniform-hemisphere density.
    let lambertian = Bsdf::lambertian(Vec3::ONE);
    let wo = wo_at(30.0, false);
    let wrong = |wi: Vec3A| if wi.z > 0.0 { (0.5 / PI) as f32 } else { 0.0 };
    let r = run_case(&lambertian, wo, 1, &wrong);
    println!(
        "control: lambertian vs uniform pdf: chi2 = {:.1}, p = {:.2e}",
        r.statistic, r.p_value
    );
    assert!(
        r.p_value < level,
        "uniform-pdf control passed: p = {}",
        r.p_value
    );

    // GGX samples at alpha 0.3 tested against the pdf of alpha 0.33 (a 10% roughness error).
    let sampled = Bsdf::rough_conductor(Vec3::ONE, 0.3);
    let claimed = Bsdf::rough_conductor(Vec3::ONE, 0.33);
    let wo = wo_at(45.0, false);
    let wrong = |wi: Vec3A| claimed.pdf(wo, wi, TransportMode::Radiance);
    let r = run_case(&sampled, wo, 2, &wrong);
    println!(
        "control: ggx 0.3 vs pdf of 0.33: chi2 = {:.1}, p = {:.2e}",
        r.statistic, r.p_value
    );
    assert!(
        r.p_value < level,
        "roughness control passed: p = {}",
        r.p_value
    );

    // Rough glass samples tested against the pdf of a slightly different IOR (shifts the
    // transmission lobe and the Fresnel lobe choice).
    let sampled = Bsdf::rough_dielectric(1.5, 0.3, Vec3::ONE);
    let claimed = Bsdf::rough_dielectric(1.6, 0.3, Vec3::ONE);
    let wo = wo_at(50.0, false);
    let wrong = |wi: Vec3A| claimed.pdf(wo, wi, TransportMode::Radiance);
    let r = run_case(&sampled, wo, 3, &wrong);
    println!(
        "control: glass 1.5 vs pdf of 1.6: chi2 = {:.1}, p = {:.2e}",
        r.statistic, r.p_value
    );
    assert!(r.p_value < level, "ior control passed: p = {}", r.p_value);
}
