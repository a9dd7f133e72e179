//! PSS mutations as `mcmc_core` proposals: small steps, large steps and their mixture.

use mcmc_core::controller::LargeStepTunable;
use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::mutation::SmallMutation;
use crate::state::{Pending, PssState};
use crate::PssError;

/// All streams.
pub const ALL_STREAMS: u8 = 0xff;

/// Log density of a small step `from -> to` over fully materialised states of equal length:
/// the product of the per-coordinate kernel densities over mutated streams; coordinates of
/// other streams must be unchanged.
fn small_log_q(mutation: &SmallMutation, stream_mask: u8, from: &PssState, to: &PssState) -> f64 {
    let (a, b) = (from.raw_values(), to.raw_values());
    if a.len() != b.len() || from.streams() != to.streams() {
        return f64::NEG_INFINITY;
    }
    let streams = from.streams();
    let mut log_q = 0.0;
    for (i, (&x, &y)) in a.iter().zip(b).enumerate() {
        if stream_mask & (1 << (i % streams)) != 0 {
            log_q += mutation.log_density(x, y);
        } else if x != y {
            return f64::NEG_INFINITY;
        }
    }
    log_q
}

/// A small step: every coordinate of the selected streams is perturbed by a 1-D kernel
/// (applied lazily, see [`PssState`]). Symmetric on the torus.
///
/// `log_q` is the exact density for fully materialised states of equal length (what tests
/// and delayed rejection use); lazily grown coordinates are fresh uniforms, density 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmallStep {
    /// The per-coordinate kernel.
    pub mutation: SmallMutation,
    /// Streams to mutate (bit s = stream s); others are kept (MMLT can fix a subpath).
    pub stream_mask: u8,
}

impl SmallStep {
    /// A small step on all streams.
    #[must_use]
    pub const fn new(mutation: SmallMutation) -> Self {
        Self {
            mutation,
            stream_mask: ALL_STREAMS,
        }
    }
}

impl Proposal<PssState> for SmallStep {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        y.clone_from(x);
        y.set_pending(
            Pending::Small {
                mutation: self.mutation,
                stream_mask: self.stream_mask,
            },
            rng.random(),
        );
        Proposed::symmetric()
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        small_log_q(&self.mutation, self.stream_mask, from, to)
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

/// A large step: a fresh uniform point of primary sample space (an independent sample of the
/// path generator). Density 1 everywhere; symmetric.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LargeStep;

impl Proposal<PssState> for LargeStep {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        y.clone_from(x);
        y.set_pending(Pending::Large, rng.random());
        Proposed::symmetric()
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        if from.len() == to.len() {
            0.0
        } else {
            f64::NEG_INFINITY
        }
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

/// Kelemen-style PSSMLT proposal: a large step with probability `p_large`, else a small step
/// (Kelemen et al. 2002, section 4). Component 0 is the small step, component 1 the large
/// step. Both are symmetric and the selection does not depend on the state, so the Hastings
/// term is 0. `p_large` is tunable (automatic large-step control).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PssmltProposal {
    /// The small step.
    pub small: SmallStep,
    p_large: f64,
}

impl PssmltProposal {
    /// A mixture with large-step probability `p_large` in `[0, 1]`.
    pub fn new(small: SmallStep, p_large: f64) -> Result<Self, PssError> {
        if !(0.0..=1.0).contains(&p_large) {
            return Err(PssError::InvalidParameter {
                name: "p_large",
                value: p_large.to_string(),
                allowed: "[0, 1]",
            });
        }
        Ok(Self { small, p_large })
    }

    /// Kelemen et al. 2002's exponential small step (`s1 = 1/1024`, `s2 = 1/64`, section 4.1)
    /// with large-step probability 0.3 (the value of pbrt-v3 and of the DRMLT and Langevin
    /// authors' implementations).
    #[must_use]
    pub const fn kelemen2002() -> Self {
        Self {
            small: SmallStep::new(SmallMutation::Kelemen(crate::KelemenParams::kelemen2002())),
            p_large: 0.3,
        }
    }

    /// pbrt-v3's MLT: Gaussian small steps with `sigma = 0.01`, large-step probability 0.3.
    #[must_use]
    pub const fn pbrt_v3() -> Self {
        Self {
            small: SmallStep::new(SmallMutation::Gaussian { sigma: 0.01 }),
            p_large: 0.3,
        }
    }

    /// The large-step probability.
    #[must_use]
    pub fn p_large(&self) -> f64 {
        self.p_large
    }
}

impl Proposal<PssState> for PssmltProposal {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        if rng.random::<f64>() < self.p_large {
            LargeStep.propose(x, y, rng).with_component(1)
        } else {
            self.small.propose(x, y, rng)
        }
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        let small = (1.0 - self.p_large) * self.small.log_q(from, to).exp();
        let large = self.p_large * LargeStep.log_q(from, to).exp();
        (small + large).ln()
    }

    fn is_symmetric(&self) -> bool {
        true
    }

    fn num_components(&self) -> usize {
        2
    }

    fn log_q_component(&self, j: usize, from: &PssState, to: &PssState) -> f64 {
        match j {
            0 => (1.0 - self.p_large).ln() + self.small.log_q(from, to),
            _ => self.p_large.ln() + LargeStep.log_q(from, to),
        }
    }
}

impl LargeStepTunable for PssmltProposal {
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
