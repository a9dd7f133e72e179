//! Choosing the breakup point `b` from unnormalised weights (paper section 3.3, "Adaptive
//! dimensionality", and 3.4: a CDF over the vertices' roughness), and the probability of a
//! choice, which the estimator needs for every member of a lattice set.

/// Draws an index from the discrete distribution proportional to `weights`, by inversion with
/// the uniform number `u` in `[0, 1)`; returns the index and its probability.
///
/// Section 3.3 draws the breakup point `b` from a CDF built from the roughness of the
/// vertices `x_b`, `x_{b+1}`. `None` if no weight is positive (then there is nothing to
/// explore). Weights must be finite and `>= 0`.
///
/// # Example
///
/// ```
/// let weights = [0.0, 3.0, 1.0];
/// assert_eq!(lqmc::sample_breakup(&weights, 0.5), Some((1, 0.75)));
/// assert_eq!(lqmc::sample_breakup(&weights, 0.8), Some((2, 0.25)));
/// assert_eq!(lqmc::sample_breakup(&[0.0, 0.0], 0.5), None);
/// ```
#[must_use]
pub fn sample_breakup(weights: &[f64], u: f64) -> Option<(usize, f64)> {
    debug_assert!(weights.iter().all(|w| w.is_finite() && *w >= 0.0));
    let total: f64 = weights.iter().sum();
    if total <= 0.0 {
        return None;
    }
    let target = u * total;
    let mut acc = 0.0;
    let mut last = None;
    for (b, &w) in weights.iter().enumerate() {
        if w <= 0.0 {
            continue;
        }
        acc += w;
        last = Some((b, w / total));
        if target < acc {
            break;
        }
    }
    last
}

/// The probability that [`sample_breakup`] returns index `b` for these weights (0 if `b` is
/// out of range or all weights are zero): the `P(b | X_j)` a [`crate::LocalIntegrand`] reports
/// for each rebuilt member.
///
/// # Example
///
/// ```
/// assert_eq!(lqmc::breakup_probability(&[1.0, 3.0], 1), 0.75);
/// assert_eq!(lqmc::breakup_probability(&[1.0, 3.0], 2), 0.0);
/// ```
#[must_use]
pub fn breakup_probability(weights: &[f64], b: usize) -> f64 {
    let total: f64 = weights.iter().sum();
    match weights.get(b) {
        Some(&w) if total > 0.0 => w / total,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frequencies_match_probabilities() {
        let w = [0.5, 0.0, 2.0, 1.5];
        let n = 40_000;
        let mut counts = [0usize; 4];
        for i in 0..n {
            let u = (i as f64 + 0.5) / n as f64;
            let (b, p) = sample_breakup(&w, u).unwrap();
            assert_eq!(p, breakup_probability(&w, b));
            counts[b] += 1;
        }
        for (b, &count) in counts.iter().enumerate() {
            let f = count as f64 / n as f64;
            assert!((f - breakup_probability(&w, b)).abs() < 1e-3, "b {b}: {f}");
        }
        assert_eq!(counts[1], 0);
    }
}
