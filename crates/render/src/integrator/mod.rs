//! Integrators that turn camera rays into radiance estimates, drawing every random number from
//! a [`crate::sampler::Sampler`]; multiple-importance-sampling weights shared by them.

pub mod halton_sampler;
pub mod lqmc;
pub mod pt;
pub mod pt_driver;
pub mod qmc;
pub mod vertex_path;

/// Veach's power heuristic with exponent 2 for one sample from each of two strategies:
/// `f² / (f² + g²)` (Veach 1997, eq. 9.13). Infinite `f` (a delta strategy) gives 1; `f = 0`
/// gives 0.
#[inline]
#[must_use]
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    if f.is_infinite() {
        return 1.0;
    }
    if f.is_nan() || f <= 0.0 {
        return 0.0;
    }
    // 1 / (1 + (g/f)²) avoids under- and overflow of the squares.
    let r = g / f;
    let w = 1.0 / (1.0 + r * r);
    if w.is_nan() {
        0.0
    } else {
        w
    }
}

/// The balance heuristic `f / (f + g)` (Veach 1997, eq. 9.10).
#[inline]
#[must_use]
pub fn balance_heuristic(f: f32, g: f32) -> f32 {
    if f.is_infinite() {
        return 1.0;
    }
    if f.is_nan() || f <= 0.0 {
        return 0.0;
    }
    let w = 1.0 / (1.0 + g / f);
    if w.is_nan() {
        0.0
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heuristics_sum_to_one() {
        for (f, g) in [(1.0, 2.0), (0.3, 0.0), (5e-20, 7e-20), (1e20, 3e19)] {
            assert!((power_heuristic(f, g) + power_heuristic(g, f) - 1.0).abs() < 1e-5);
            assert!((balance_heuristic(f, g) + balance_heuristic(g, f) - 1.0).abs() < 1e-5);
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
    }
}
