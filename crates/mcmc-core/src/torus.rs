//! The unit torus `[0, 1)^n` that primary sample space and the toy targets live on: wrapping.

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
    let w = x - x.floor();
    if w >= 1.0 {
        0.0
    } else {
        w
    }
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
}
