//! A fixed-dimension toy target evaluated on the first primary samples of a PSS state.

use mcmc_core::toy::ToyTarget;
use mcmc_core::Target;
use rand::Rng;

use super::exact::{ExactPssTarget, PssBins};
use crate::{PssError, PssState};

/// The largest toy dimension [`OnPss`] accepts (its evaluation reads into a stack buffer of
/// this size, so it does not allocate).
pub const MAX_FIXED_DIM: usize = 16;

/// A toy target on `[0, 1)^d` (from [`mcmc_core::toy`]) as a PSS target: evaluation rewinds
/// the state (`begin`), reads the first `d` primary samples of stream 0 and returns the toy's
/// normalised log density. Its read set is always the same `d` coordinates.
///
/// Exact starts are `PssState::from_values(toy.sample_exact(rng))`; bins are the toy's bins
/// on the first `d` coordinates ([`ExactPssTarget`]).
#[derive(Clone, Debug)]
pub struct OnPss<T> {
    toy: T,
}

impl<T: ToyTarget> OnPss<T> {
    /// Wraps `toy`, whose dimension must be in `1..=MAX_FIXED_DIM`.
    pub fn new(toy: T) -> Result<Self, PssError> {
        let d = toy.dim();
        if !(1..=MAX_FIXED_DIM).contains(&d) {
            return Err(PssError::InvalidParameter {
                name: "toy dimension",
                value: d.to_string(),
                allowed: "1..=16",
            });
        }
        Ok(Self { toy })
    }

    /// The wrapped toy target.
    pub fn toy(&self) -> &T {
        &self.toy
    }
}

impl<T: ToyTarget> Target for OnPss<T> {
    type State = PssState;
    type Payload = ();

    fn evaluate(&self, x: &mut PssState, _payload: &mut ()) -> f64 {
        let d = self.toy.dim();
        let mut u = [0.0; MAX_FIXED_DIM];
        x.begin();
        for v in &mut u[..d] {
            *v = x.next_sample();
        }
        self.toy.log_density(&u[..d])
    }
}

impl<T: ToyTarget> ExactPssTarget for OnPss<T> {
    fn name(&self) -> &'static str {
        self.toy.name()
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> PssState {
        PssState::from_values(&self.toy.sample_exact(rng))
    }

    fn bins(&self) -> PssBins {
        let bins = self.toy.bins();
        let d = self.toy.dim();
        PssBins::new(bins.probabilities().to_vec(), move |x: &PssState| {
            let mut x = x.clone();
            let mut u = [0.0; MAX_FIXED_DIM];
            for (i, v) in u[..d].iter_mut().enumerate() {
                *v = x.get(i);
            }
            bins.bin_of(&u[..d])
        })
    }
}

/// Central finite differences of the toy's log density over the first `d` samples, with
/// probes wrapped onto the torus (`h = 1e-6`; a non-finite difference gives 0). The gradient
/// is in the order [`crate::langevin::PssCoordinates`] moves the coordinates (stream 0's
/// prefix), so MALA runs on these targets.
impl<T: ToyTarget> mcmc_core::DifferentiableTarget for OnPss<T> {
    fn evaluate_with_grad(&self, x: &mut PssState, payload: &mut (), grad: &mut Vec<f64>) -> f64 {
        const H: f64 = 1e-6;
        let value = self.evaluate(x, payload);
        let d = self.toy.dim();
        let mut u = [0.0; MAX_FIXED_DIM];
        u[..d].copy_from_slice(&x.raw_values()[..d]);
        grad.clear();
        for i in 0..d {
            let mut probe = u;
            probe[i] = mcmc_core::torus::wrap(u[i] + H);
            let plus = self.toy.log_density(&probe[..d]);
            probe[i] = mcmc_core::torus::wrap(u[i] - H);
            let minus = self.toy.log_density(&probe[..d]);
            let g = (plus - minus) / (2.0 * H);
            grad.push(if g.is_finite() { g } else { 0.0 });
        }
        value
    }
}
