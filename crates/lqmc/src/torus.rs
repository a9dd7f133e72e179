//! Arithmetic on the unit torus `[0, 1)^s`: wrapping into `[0, 1)` and shortest differences.

use crate::halton::ONE_MINUS_EPSILON;

/// `{x}`: `x` modulo one, in `[0, 1)` (also for tiny negative `x`, where `x - floor(x)` would
/// round to 1).
#[inline]
#[must_use]
pub fn wrap_unit(x: f64) -> f64 {
    let y = x - x.floor();
    if y >= 1.0 {
        ONE_MINUS_EPSILON
    } else {
        y
    }
}

/// The shortest signed difference `a - b` on the unit circle, in `[-0.5, 0.5]`.
#[inline]
#[must_use]
pub fn torus_difference(a: f64, b: f64) -> f64 {
    let d = a - b;
    d - d.round()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping() {
        assert_eq!(wrap_unit(1.25), 0.25);
        assert_eq!(wrap_unit(-0.25), 0.75);
        assert!(wrap_unit(-1e-20) < 1.0);
        assert_eq!(wrap_unit(0.0), 0.0);
        assert!((torus_difference(0.95, 0.05) + 0.1).abs() < 1e-15);
        assert!((torus_difference(0.05, 0.95) - 0.1).abs() < 1e-15);
        assert!((torus_difference(0.3, 0.1) - 0.2).abs() < 1e-15);
    }
}
