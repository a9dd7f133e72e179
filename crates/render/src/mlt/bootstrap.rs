//! The bootstrap of an MCMC render: estimate the normalisation `b` from independent samples
//! and resample chain starts in proportion to their target value.

use mcmc_core::seed::{chain_seed, mix64};
use mcmc_core::Target;
use pss::PssState;
use rayon::prelude::*;

/// The result of a bootstrap.
#[derive(Clone, Debug)]
pub struct Bootstrap {
    /// Target value `f(u_i)` (not log) of each bootstrap sample, in sample order.
    pub weights: Vec<f64>,
    /// Mean of `weights`: the estimate of `b = integral of f over primary sample space`.
    pub b: f64,
}

/// The noise key of bootstrap sample `index`: a fresh [`PssState::new`] with this key
/// reproduces the sample exactly, so chain starts need no stored state.
#[must_use]
pub fn bootstrap_key(seed: u64, index: u64) -> u64 {
    chain_seed(mix64(seed ^ 0xb007_5724_7000_0001), index)
}

impl Bootstrap {
    /// Evaluates `n` independent samples of `target` (in parallel on the current rayon pool;
    /// the result does not depend on the thread count) with `streams` PSS streams.
    /// Non-finite values count as zero.
    pub fn run<T>(target: &T, streams: usize, n: usize, seed: u64) -> Self
    where
        T: Target<State = PssState>,
    {
        let weights: Vec<f64> = (0..n)
            .into_par_iter()
            .map_init(T::Payload::default, |payload, i| {
                let mut state = PssState::new(streams, bootstrap_key(seed, i as u64));
                let ld = target.evaluate(&mut state, payload);
                let f = ld.exp();
                if f.is_finite() {
                    f
                } else {
                    0.0
                }
            })
            .collect();
        // Sequential sum: a fixed order, hence bit-reproducible.
        let b = if n == 0 {
            0.0
        } else {
            weights.iter().sum::<f64>() / n as f64
        };
        Self { weights, b }
    }

    /// True if no bootstrap sample carried light.
    #[must_use]
    pub fn found_nothing(&self) -> bool {
        self.b.is_nan() || self.b <= 0.0
    }

    /// Systematic resampling (Veach's thesis, p. 340; Kitagawa 1996): `count` sample indices
    /// chosen in proportion to their weights with one uniform offset `u` in [0, 1). Returns an
    /// empty vector if all weights are zero.
    #[must_use]
    pub fn resample(&self, count: usize, u: f64) -> Vec<usize> {
        let total: f64 = self.weights.iter().sum();
        if total.is_nan() || total <= 0.0 || count == 0 {
            return Vec::new();
        }
        let step = total / count as f64;
        let mut out = Vec::with_capacity(count);
        let mut cdf = 0.0;
        let mut i = 0;
        for c in 0..count {
            let target = (c as f64 + u.clamp(0.0, 1.0 - f64::EPSILON)) * step;
            while i + 1 < self.weights.len() && cdf + self.weights[i] <= target {
                cdf += self.weights[i];
                i += 1;
            }
            // Never pick a zero-weight sample (possible through rounding at the end).
            let mut j = i;
            while self.weights[j] == 0.0 && j > 0 {
                j -= 1;
            }
            out.push(j);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_is_proportional() {
        let bs = Bootstrap {
            weights: vec![0.0, 1.0, 3.0, 0.0],
            b: 1.0,
        };
        let idx = bs.resample(4, 0.5);
        assert_eq!(idx, vec![1, 2, 2, 2]);
        let none = Bootstrap {
            weights: vec![0.0; 3],
            b: 0.0,
        };
        assert!(none.resample(5, 0.3).is_empty());
        assert!(none.found_nothing());
    }

    #[test]
    fn resampling_never_picks_zero_weight() {
        let bs = Bootstrap {
            weights: vec![1.0, 0.0, 0.0],
            b: 1.0 / 3.0,
        };
        for u in [0.0, 0.5, 0.999_999] {
            assert!(bs.resample(7, u).iter().all(|&i| i == 0));
        }
    }
}
