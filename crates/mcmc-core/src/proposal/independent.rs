//! An independent uniform proposal on a box: the large step of toy targets on `R^n`.

use rand::{Rng, RngExt};

use super::{Proposal, Proposed};
use crate::McmcError;

/// Proposes a point uniformly in the box `[lo, hi]` (coordinate-wise), ignoring the current
/// state: an independence sampler, the "large step" of targets on `R^n` (Kelemen et al. 2002's
/// large step is the same move on the unit cube): `q(x -> y) = 1 / volume` for every `y` in
/// the box, 0 outside. Symmetric between states of the box only: from a state outside it the
/// reverse move is impossible, so the Hastings term is `-inf` there (not declared symmetric).
///
/// # Example
/// ```
/// use mcmc_core::proposal::IndependentUniform;
/// use mcmc_core::Proposal;
/// use rand::SeedableRng;
///
/// let large = IndependentUniform::new(vec![-1.0, 0.0], vec![1.0, 4.0]).unwrap();
/// let mut y = Vec::new();
/// large.propose(&vec![0.0, 0.0], &mut y, &mut rand_pcg::Pcg64::seed_from_u64(1));
/// assert!((-1.0..=1.0).contains(&y[0]) && (0.0..=4.0).contains(&y[1]));
/// assert!((large.log_q(&vec![0.0, 0.0], &y) + 8f64.ln()).abs() < 1e-12);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct IndependentUniform {
    lo: Vec<f64>,
    hi: Vec<f64>,
    log_volume: f64,
}

impl IndependentUniform {
    /// The box `[lo, hi]`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] if the bounds differ in length, are empty, not finite,
    /// or `lo >= hi` in some coordinate.
    pub fn new(lo: Vec<f64>, hi: Vec<f64>) -> Result<Self, McmcError> {
        if lo.is_empty() || lo.len() != hi.len() {
            return Err(McmcError::InvalidParameter {
                name: "box bounds",
                value: lo.len() as f64,
                allowed: "as many lower as upper bounds, at least one",
            });
        }
        for (&l, &h) in lo.iter().zip(&hi) {
            if !(l.is_finite() && h.is_finite() && l < h) {
                return Err(McmcError::InvalidParameter {
                    name: "box bounds",
                    value: l,
                    allowed: "finite, lo < hi in every coordinate",
                });
            }
        }
        let log_volume = lo.iter().zip(&hi).map(|(l, h)| (h - l).ln()).sum();
        Ok(Self { lo, hi, log_volume })
    }
}

impl IndependentUniform {
    /// True if `x` lies in the box.
    #[must_use]
    pub fn contains(&self, x: &[f64]) -> bool {
        x.len() == self.lo.len()
            && x.iter()
                .zip(self.lo.iter().zip(&self.hi))
                .all(|(v, (l, h))| *v >= *l && *v <= *h)
    }
}

impl Proposal<Vec<f64>> for IndependentUniform {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clear();
        y.extend(
            self.lo
                .iter()
                .zip(&self.hi)
                .map(|(l, h)| l + (h - l) * rng.random::<f64>()),
        );
        Proposed::hastings(if self.contains(x) {
            0.0
        } else {
            f64::NEG_INFINITY
        })
    }

    fn log_q(&self, _from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        if self.contains(to) {
            -self.log_volume
        } else {
            f64::NEG_INFINITY
        }
    }
}
