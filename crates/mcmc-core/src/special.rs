//! Special functions for exact probabilities: log-gamma, regularised incomplete gamma, normal CDF.
//!
//! Written from the formulas (Numerical Recipes, 3rd ed., sections 6.1-6.2; Lanczos 1964), so
//! that truncated-normal normalisations, the toy targets' bin probabilities and the chi-square
//! survival function of `crate::testing` (feature `testing`) need no numerical dependency.

/// Lanczos coefficients for `g = 7`, `n = 9` (relative accuracy about `1e-15` for `x >= 0.5`).
const LANCZOS_G: f64 = 7.0;
#[allow(clippy::excessive_precision)]
const LANCZOS: [f64; 9] = [
    0.999_999_999_999_809_93,
    676.520_368_121_885_1,
    -1_259.139_216_722_402_8,
    771.323_428_777_653_13,
    -176.615_029_162_140_59,
    12.507_343_278_686_905,
    -0.138_571_095_265_720_12,
    9.984_369_578_019_571_6e-6,
    1.505_632_735_149_311_6e-7,
];

/// Relative convergence threshold of the series and the continued fraction.
const EPS: f64 = f64::EPSILON;
/// Smallest magnitude allowed in the modified Lentz algorithm.
const FPMIN: f64 = f64::MIN_POSITIVE / f64::EPSILON;
/// Iteration cap; both expansions converge in `O(sqrt(a))` terms for the arguments we use.
const MAX_ITER: usize = 100_000;

/// `ln Gamma(x)` for `x > 0` (Lanczos approximation; reflection formula below 0.5).
/// Returns NaN for `x <= 0` or NaN.
#[must_use]
pub fn ln_gamma(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return f64::NAN;
    }
    if x < 0.5 {
        // Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = LANCZOS[0];
    for (i, &c) in LANCZOS.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    let t = x + LANCZOS_G + 0.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// `x^a e^-x / Gamma(a)` in logs, the common prefactor of both expansions.
fn log_prefactor(a: f64, x: f64) -> f64 {
    -x + a * x.ln() - ln_gamma(a)
}

/// Series `gamma(a, x) / Gamma(a)` (NR eq. 6.2.5), valid and fast for `x < a + 1`.
fn lower_series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut del = 1.0 / a;
    let mut sum = del;
    for _ in 0..MAX_ITER {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if del.abs() < sum.abs() * EPS {
            break;
        }
    }
    sum * log_prefactor(a, x).exp()
}

/// Continued fraction `Gamma(a, x) / Gamma(a)` (NR eq. 6.2.7, modified Lentz), valid and fast
/// for `x >= a + 1`.
fn upper_continued_fraction(a: f64, x: f64) -> f64 {
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / FPMIN;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..MAX_ITER {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < FPMIN {
            d = FPMIN;
        }
        c = b + an / c;
        if c.abs() < FPMIN {
            c = FPMIN;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    log_prefactor(a, x).exp() * h
}

/// Regularised lower incomplete gamma `P(a, x) = gamma(a, x) / Gamma(a)` for `a > 0`,
/// `x >= 0` (NaN otherwise; 1 for `x = +inf`).
#[must_use]
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    if a.is_nan() || x.is_nan() || a <= 0.0 || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        0.0
    } else if x == f64::INFINITY {
        1.0
    } else if x < a + 1.0 {
        lower_series(a, x)
    } else {
        1.0 - upper_continued_fraction(a, x)
    }
}

/// Regularised upper incomplete gamma `Q(a, x) = 1 - P(a, x)`, computed directly (no
/// cancellation) in the upper tail.
#[must_use]
pub fn regularized_gamma_q(a: f64, x: f64) -> f64 {
    if a.is_nan() || x.is_nan() || a <= 0.0 || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        1.0
    } else if x == f64::INFINITY {
        0.0
    } else if x < a + 1.0 {
        1.0 - lower_series(a, x)
    } else {
        upper_continued_fraction(a, x)
    }
}

/// Standard normal CDF `Phi(x) = (1 + erf(x / sqrt 2)) / 2`, with `erf(t) = P(1/2, t^2)`;
/// the lower tail is computed as `Q(1/2, x^2/2) / 2` so it keeps full relative precision.
#[must_use]
pub fn normal_cdf(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    let tail = 0.5 * regularized_gamma_q(0.5, 0.5 * x * x);
    if x < 0.0 {
        tail
    } else {
        1.0 - tail
    }
}

/// `Phi(b) - Phi(a)` for `a <= b`, computed from whichever tail avoids cancellation.
#[must_use]
pub fn normal_interval(a: f64, b: f64) -> f64 {
    if b <= a {
        return 0.0;
    }
    if a >= 0.0 {
        // Both in the upper half: difference of upper tails.
        normal_cdf(-a) - normal_cdf(-b)
    } else {
        normal_cdf(b) - normal_cdf(a)
    }
}

/// Chi-square CDF with `k` degrees of freedom: `P(k/2, x/2)` (0 for `x <= 0`).
#[must_use]
pub fn chi_square_cdf(x: f64, k: f64) -> f64 {
    if x <= 0.0 {
        0.0
    } else {
        regularized_gamma_p(0.5 * k, 0.5 * x)
    }
}

/// Chi-square survival function `1 - CDF = Q(k/2, x/2)` (1 for `x <= 0`, 0 for `+inf`).
#[must_use]
pub fn chi_square_sf(x: f64, k: f64) -> f64 {
    if x.is_nan() || k.is_nan() {
        f64::NAN
    } else if x <= 0.0 {
        1.0
    } else {
        regularized_gamma_q(0.5 * k, 0.5 * x)
    }
}

/// The `x` with `cdf(x) = p` for an increasing `cdf` on `[lo, hi]`, by bisection to machine
/// precision (used to place equal-probability bin edges; the bins' probabilities are then
/// recomputed from the edges, so the edges need not be exact).
#[must_use]
pub fn bisect_quantile(cdf: impl Fn(f64) -> f64, p: f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-300)
    }

    #[test]
    fn ln_gamma_known_values() {
        let pi = std::f64::consts::PI;
        assert!(close(ln_gamma(0.5), 0.5 * pi.ln(), 1e-14));
        assert!(close(ln_gamma(1.0).exp(), 1.0, 1e-14) || ln_gamma(1.0).abs() < 1e-14);
        assert!(close(ln_gamma(5.0), 24f64.ln(), 1e-14));
        assert!(close(ln_gamma(10.5), 1_133_278.388_948_785_f64.ln(), 1e-13));
        assert!(close(ln_gamma(0.1), 9.513_507_698_668_732_f64.ln(), 1e-13));
        assert!(ln_gamma(0.0).is_nan());
    }

    #[test]
    fn incomplete_gamma_known_values() {
        // P(1, x) = 1 - e^-x.
        for x in [0.01f64, 0.5, 1.0, 3.0, 20.0] {
            assert!(close(regularized_gamma_p(1.0, x), 1.0 - (-x).exp(), 1e-13));
            assert!(close(regularized_gamma_q(1.0, x), (-x).exp(), 1e-13));
        }
        // P(1/2, t^2) = erf(t); erf(1) = 0.8427007929497149.
        assert!(close(
            regularized_gamma_p(0.5, 1.0),
            0.842_700_792_949_714_9,
            1e-14
        ));
        assert_eq!(regularized_gamma_p(2.0, 0.0), 0.0);
        assert_eq!(regularized_gamma_q(2.0, f64::INFINITY), 0.0);
        assert!(regularized_gamma_p(-1.0, 1.0).is_nan());
    }

    #[test]
    fn chi_square_critical_values() {
        // Tabulated 95% quantiles (e.g. NIST/SEMATECH e-Handbook, table 1.3.6.7.4).
        assert!(close(
            chi_square_sf(3.841_458_820_694_124, 1.0),
            0.05,
            1e-12
        ));
        assert!(close(
            chi_square_sf(18.307_038_053_275_146, 10.0),
            0.05,
            1e-12
        ));
        // 99% quantile with 30 dof.
        assert!(close(
            chi_square_sf(50.892_181_311_517_71, 30.0),
            0.01,
            1e-10
        ));
        // Two degrees of freedom: sf(x) = e^{-x/2}.
        assert!(close(chi_square_sf(7.0, 2.0), (-3.5f64).exp(), 1e-13));
        assert!(close(
            chi_square_cdf(7.0, 2.0),
            1.0 - (-3.5f64).exp(),
            1e-13
        ));
        assert_eq!(chi_square_sf(f64::INFINITY, 4.0), 0.0);
        assert_eq!(chi_square_sf(0.0, 4.0), 1.0);
    }

    #[test]
    fn normal_cdf_known_values() {
        assert!(close(normal_cdf(1.959_963_984_540_054), 0.975, 1e-14));
        assert!(close(normal_cdf(-1.959_963_984_540_054), 0.025, 1e-13));
        assert_eq!(normal_cdf(0.0), 0.5);
        // Deep tail keeps relative precision: Phi(-10) = 7.619853024160527e-24.
        assert!(close(normal_cdf(-10.0), 7.619_853_024_160_527e-24, 1e-10));
        assert!(close(
            normal_interval(9.0, 10.0),
            normal_cdf(-9.0) - normal_cdf(-10.0),
            1e-14
        ));
        assert!(close(
            normal_interval(-1.0, 1.0),
            0.682_689_492_137_085_9,
            1e-14
        ));
    }

    #[test]
    fn bisection_inverts_a_cdf() {
        let x = bisect_quantile(|x| chi_square_cdf(x, 10.0), 0.95, 0.0, 1000.0);
        assert!(close(x, 18.307_038_053_275_146, 1e-12));
    }
}
