//! Test proposals: an asymmetric random walk and a state-dependent selection for mixtures.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::proposal::{Proposal, Proposed, Selection};
use crate::McmcError;

/// A Gaussian random walk with a drift and a state-dependent scale, on `R^n`:
/// `y = x + drift + s(x) N(0, I)` with `s(x) = sigma exp(growth tanh(x_0))`.
///
/// Asymmetric in two ways (the drift, and the scale depending on the current state), with an
/// exact transition density `q(x -> y) = prod_i N(y_i - x_i - drift; 0, s(x)^2)`, so it
/// needs the full Hastings term: the proposal behind the negative controls
/// [`super::TreatedAsSymmetric`] and [`super::MhWithoutHastings`], and a correct asymmetric
/// proposal for MH tests. `s(x)` lies in `[sigma e^-growth, sigma e^growth]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AsymmetricWalk {
    sigma: f64,
    drift: f64,
    growth: f64,
}

impl AsymmetricWalk {
    /// A walk with base scale `sigma > 0`, finite `drift` (added to every coordinate) and
    /// `growth >= 0` (log-range of the scale).
    pub fn new(sigma: f64, drift: f64, growth: f64) -> Result<Self, McmcError> {
        McmcError::check_range("sigma", sigma, f64::MIN_POSITIVE, f64::MAX, "(0, inf)")?;
        McmcError::check_range("drift", drift, f64::MIN, f64::MAX, "finite")?;
        McmcError::check_range("growth", growth, 0.0, 50.0, "[0, 50]")?;
        Ok(Self {
            sigma,
            drift,
            growth,
        })
    }

    /// The scale `s(x)` used from state `x`.
    #[must_use]
    pub fn scale_at(&self, x: &[f64]) -> f64 {
        self.sigma * (self.growth * x[0].tanh()).exp()
    }
}

impl Proposal<Vec<f64>> for AsymmetricWalk {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        let s = self.scale_at(x);
        y.clear();
        y.extend(x.iter().map(|&xi| {
            let z: f64 = StandardNormal.sample(rng);
            xi + self.drift + s * z
        }));
        Proposed::hastings(self.log_q(y, x) - self.log_q(x, y))
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        if from.len() != to.len() {
            return f64::NEG_INFINITY;
        }
        let s = self.scale_at(from);
        let d2: f64 = from
            .iter()
            .zip(to)
            .map(|(a, b)| {
                let d = b - a - self.drift;
                d * d
            })
            .sum();
        let n = from.len() as f64;
        -0.5 * d2 / (s * s) - n * (s.ln() + crate::toy::HALF_LN_2PI)
    }
}

/// Selection probabilities that depend on which side of a threshold `x_0` lies:
/// `s(j | x) = below[j]` if `x_0 < threshold`, else `above[j]`.
///
/// With a [`crate::Mixture`] this exercises the component-labelled acceptance of the
/// regional-adaptive paper (section 3.2): a move across the threshold must carry the factor
/// `s(j | y) / s(j | x)`.
#[derive(Clone, Debug, PartialEq)]
pub struct ThresholdSelection {
    threshold: f64,
    below: Vec<f64>,
    above: Vec<f64>,
}

impl ThresholdSelection {
    /// Selection with the given weights on each side (normalised; same length, positive
    /// sums).
    pub fn new(threshold: f64, below: &[f64], above: &[f64]) -> Result<Self, McmcError> {
        McmcError::check_range("threshold", threshold, f64::MIN, f64::MAX, "finite")?;
        if below.len() != above.len() || below.is_empty() {
            return Err(McmcError::InvalidParameter {
                name: "below.len() - above.len()",
                value: below.len() as f64 - above.len() as f64,
                allowed: "equal, non-empty weight lists",
            });
        }
        let normalise = |w: &[f64]| -> Result<Vec<f64>, McmcError> {
            for &v in w {
                McmcError::check_range("selection weight", v, 0.0, f64::MAX, "[0, inf)")?;
            }
            let sum: f64 = w.iter().sum();
            McmcError::check_range(
                "sum of weights",
                sum,
                f64::MIN_POSITIVE,
                f64::MAX,
                "(0, inf)",
            )?;
            Ok(w.iter().map(|v| v / sum).collect())
        };
        Ok(Self {
            threshold,
            below: normalise(below)?,
            above: normalise(above)?,
        })
    }
}

impl Selection<Vec<f64>> for ThresholdSelection {
    fn probabilities(&self, x: &Vec<f64>, probs: &mut [f64]) {
        let side = if x[0] < self.threshold {
            &self.below
        } else {
            &self.above
        };
        probs.copy_from_slice(side);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn asymmetric_walk_density_is_normalised_and_asymmetric() {
        let q = AsymmetricWalk::new(0.3, 0.1, 0.5).unwrap();
        let h = 1e-3;
        let x = vec![0.4];
        let total: f64 = (-3000..3000)
            .map(|i| q.log_q(&x, &vec![i as f64 * h]).exp() * h)
            .sum();
        assert!((total - 1.0).abs() < 1e-6, "{total}");
        let y = vec![0.9];
        assert!((q.log_q(&x, &y) - q.log_q(&y, &x)).abs() > 0.1);
        assert!(AsymmetricWalk::new(0.0, 0.0, 0.0).is_err());
    }

    #[test]
    fn threshold_selection_switches_sides() {
        let s = ThresholdSelection::new(0.0, &[1.0, 3.0], &[1.0, 1.0]).unwrap();
        let mut p = [0.0; 2];
        s.probabilities(&vec![-1.0], &mut p);
        assert_eq!(p, [0.25, 0.75]);
        s.probabilities(&vec![0.0], &mut p);
        assert_eq!(p, [0.5, 0.5]);
        assert!(ThresholdSelection::new(0.0, &[1.0], &[1.0, 2.0]).is_err());
    }
}

/// Kelemen et al. 2002's mutation mixture on a box of `R^n`: with probability `1 - p` a
/// Gaussian random walk (the small step, component 0), with probability `p` an independent
/// uniform draw on the box (the large step, component 1, density `1 / volume`). The toy
/// counterpart of `pss::PssmltProposal`, for tests of large-step control and of the
/// large-step MIS estimator ([`crate::render_loop::LargeStepMis`]).
#[derive(Clone, Debug)]
pub struct LargeStepWalk {
    small: crate::proposal::GaussianRandomWalk,
    large: crate::proposal::IndependentUniform,
    volume: f64,
    p_large: f64,
}

impl LargeStepWalk {
    /// Small steps of scale `sigma > 0`, large steps uniform on `[lo, hi]`, large-step
    /// probability `p_large` in `[0, 1]`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] for a parameter out of range or an invalid box.
    pub fn new(sigma: f64, lo: Vec<f64>, hi: Vec<f64>, p_large: f64) -> Result<Self, McmcError> {
        McmcError::check_range("p_large", p_large, 0.0, 1.0, "[0, 1]")?;
        let volume = lo.iter().zip(&hi).map(|(l, h)| h - l).product();
        Ok(Self {
            small: crate::proposal::GaussianRandomWalk::new(sigma)?,
            large: crate::proposal::IndependentUniform::new(lo, hi)?,
            volume,
            p_large,
        })
    }

    /// The large step's density `q = 1 / volume` on the box.
    #[must_use]
    pub fn large_step_density(&self) -> f64 {
        1.0 / self.volume
    }
}

impl Proposal<Vec<f64>> for LargeStepWalk {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        if rand::RngExt::random::<f64>(rng) < self.p_large {
            self.large.propose(x, y, rng).with_component(1)
        } else {
            self.small.propose(x, y, rng)
        }
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        let small = (1.0 - self.p_large) * self.small.log_q(from, to).exp();
        let large = self.p_large * self.large.log_q(from, to).exp();
        (small + large).ln()
    }

    fn num_components(&self) -> usize {
        2
    }

    fn log_q_component(&self, j: usize, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        match j {
            0 => (1.0 - self.p_large).ln() + self.small.log_q(from, to),
            _ => self.p_large.ln() + self.large.log_q(from, to),
        }
    }

    fn independent_density(&self, component: usize) -> Option<f64> {
        (component == 1).then(|| self.large_step_density())
    }

    fn log_hastings(&self, j: usize, x: &Vec<f64>, y: &Vec<f64>) -> f64 {
        match j {
            0 => 0.0,
            _ => self.large.log_q(y, x) - self.large.log_q(x, y),
        }
    }
}

impl crate::tunable::LargeStepTunable for LargeStepWalk {
    fn large_step_probability(&self) -> f64 {
        self.p_large
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.p_large = p.clamp(0.0, 1.0);
    }
    fn is_large_step(&self, component: usize) -> bool {
        component == 1
    }
}
