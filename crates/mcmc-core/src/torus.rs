//! The unit torus `[0, 1)^n` that primary sample space and the toy targets live on: wrapping,
//! minimal-image displacements and the wrapped normal density.

/// `x mod 1` in `[0, 1)`: wraps a real number onto the unit circle.
///
/// `x - floor(x)` rounds to `1.0` for a tiny negative `x` (e.g. `-1e-18`); that case is mapped
/// to `0.0`, so the result is always in `[0, 1)`.
///
/// # Example
/// ```
/// use mcmc_core::torus::wrap;
/// assert_eq!(wrap(1.25), 0.25);
/// assert_eq!(wrap(-0.25), 0.75);
/// assert_eq!(wrap(-1e-18), 0.0);
/// ```
#[inline]
#[must_use]
pub fn wrap(x: f64) -> f64 {
    // Fast paths (no `floor` call) with the same arithmetic as `x - x.floor()`.
    let w = if x > 0.0 && x < 1.0 {
        return x;
    } else if (1.0..2.0).contains(&x) {
        x - 1.0
    } else if (-1.0..0.0).contains(&x) {
        x - (-1.0)
    } else {
        x - x.floor()
    };
    if w >= 1.0 {
        0.0
    } else {
        w
    }
}

/// The minimal-image displacement `to - from` on the unit circle, in `[-1/2, 1/2]`: the
/// shortest signed step from `from` to `to` when both are read mod 1.
///
/// # Example
/// ```
/// use mcmc_core::torus::displacement;
/// assert!((displacement(0.9, 0.1) - 0.2).abs() < 1e-15);
/// assert!((displacement(0.1, 0.9) + 0.2).abs() < 1e-15);
/// ```
#[inline]
#[must_use]
pub fn displacement(from: f64, to: f64) -> f64 {
    let d = to - from;
    // Fast paths (no `round` call) with the same arithmetic as `d - d.round()`.
    if d.abs() < 0.5 {
        d
    } else if (0.5..1.5).contains(&d) {
        d - 1.0
    } else if d <= -0.5 && d > -1.5 {
        d - (-1.0)
    } else {
        d - d.round()
    }
}

/// Number of periodic images [`wrapped_normal_pdf`] sums on each side (`m = -3..=3`). With
/// `sd <= 0.25` the nearest omitted image is at least 2.5 / 0.25 = 10 standard deviations
/// away, so the truncation error is below `Phi(-10) = 7.6e-24`.
pub const WRAPPED_NORMAL_IMAGES: i32 = 3;

/// The density of the wrapped normal `sum_{m in Z} N(t + m; mean, sd^2)` at `t`, summing the
/// images `m = -3..=3` ([`WRAPPED_NORMAL_IMAGES`]): exact to `1e-23` relative for
/// `sd <= 0.25` and `|t - mean| <= 1` (e.g. `t` and `mean` in `[0, 1)`, or a difference of two
/// torus points with `mean = 0`).
///
/// # Example
/// ```
/// use mcmc_core::torus::wrapped_normal_pdf;
/// // The images at +-1 add mass: the wrapped density exceeds the plain one at t = 0.45.
/// let plain = (-0.5f64 * (0.45 / 0.25f64).powi(2)).exp() / (0.25 * (2.0 * std::f64::consts::PI).sqrt());
/// assert!(wrapped_normal_pdf(0.45, 0.0, 0.25) > plain);
/// ```
#[must_use]
pub fn wrapped_normal_pdf(t: f64, mean: f64, sd: f64) -> f64 {
    let norm = 1.0 / (sd * (2.0 * std::f64::consts::PI).sqrt());
    (-WRAPPED_NORMAL_IMAGES..=WRAPPED_NORMAL_IMAGES)
        .map(|m| {
            let z = (t + f64::from(m) - mean) / sd;
            norm * (-0.5 * z * z).exp()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_stays_in_unit_interval() {
        for x in [-1e-18, -0.5, 1.0, 2.25, -3.75, 0.0, 1e300, -1e300] {
            let y = wrap(x);
            assert!((0.0..1.0).contains(&y), "{x} -> {y}");
        }
        assert_eq!(wrap(-1e-18), 0.0);
        assert_eq!(wrap(1.25), 0.25);
        assert_eq!(wrap(-3.75), 0.25);
    }

    #[test]
    fn displacement_is_the_minimal_image() {
        for (from, to, d) in [
            (0.9, 0.1, 0.2),
            (0.1, 0.9, -0.2),
            (0.3, 0.5, 0.2),
            (0.0, 0.0, 0.0),
        ] {
            assert!((displacement(from, to) - d).abs() < 1e-12, "{from} -> {to}");
        }
    }

    /// The wrapped normal integrates to 1 over one period (midpoint rule).
    #[test]
    fn wrapped_normal_is_normalised() {
        let n = 100_000;
        let total: f64 = (0..n)
            .map(|i| wrapped_normal_pdf((i as f64 + 0.5) / n as f64, 0.9, 0.25) / n as f64)
            .sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
    }
}
