//! PSS mutations as `mcmc_core` proposals: small steps, large steps and their mixture.

use mcmc_core::controller::LargeStepTunable;
use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::mutation::SmallMutation;
use crate::raster::RasterStep;
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
    /// Uniform on primary sample space, density 1.
    fn independent_density(&self, _component: usize) -> Option<f64> {
        Some(1.0)
    }
}

/// Kelemen-style PSSMLT proposal: a large step with probability `p_large`, else a small step
/// (Kelemen et al. 2002, section 4). Component 0 is the small step, component 1 the large
/// step. Both are symmetric and the selection does not depend on the state, so the Hastings
/// term is 0. `p_large` is tunable (automatic large-step control).
///
/// Optionally ([`PssmltProposal::with_raster`], off by default) a fraction `q` of the small
/// steps are raster steps ([`RasterStep`], component 2: LuxCore's image mutation, read as a
/// separate move; [`crate::RasterParams`]). The mixture density is then
/// `(1 - p_large) (1 - q) q_small + p_large + (1 - p_large) q q_raster`, still symmetric.
/// With `q = 0` the proposal draws exactly the random numbers it drew without the option.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PssmltProposal {
    /// The small step.
    pub small: SmallStep,
    p_large: f64,
    /// The raster step (its catch-up kernel is replaced by `small`'s when used).
    raster: Option<RasterStep>,
    /// Fraction of the non-large steps that are raster steps.
    raster_probability: f64,
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
        Ok(Self {
            small,
            p_large,
            raster: None,
            raster_probability: 0.0,
        })
    }

    /// The same mixture in which a fraction `probability` (in `[0, 1]`) of the small steps are
    /// `raster` steps (component 2). `raster`'s catch-up kernel is ignored: the raster step
    /// catches stale coordinates up with this proposal's small-step kernel, the one that left
    /// them stale. Probability 0 turns the option off.
    pub fn with_raster(mut self, raster: RasterStep, probability: f64) -> Result<Self, PssError> {
        if !(0.0..=1.0).contains(&probability) {
            return Err(PssError::InvalidParameter {
                name: "raster probability",
                value: probability.to_string(),
                allowed: "[0, 1]",
            });
        }
        self.raster = (probability > 0.0).then_some(raster);
        self.raster_probability = if self.raster.is_some() {
            probability
        } else {
            0.0
        };
        Ok(self)
    }

    /// The raster step actually taken: `raster` with `small`'s kernel as catch-up.
    fn raster_step(&self) -> Option<RasterStep> {
        self.raster.map(|r| RasterStep {
            catch_up: self.small.mutation,
            ..r
        })
    }

    /// Fraction of the non-large steps that are raster steps (0: off).
    #[must_use]
    pub fn raster_probability(&self) -> f64 {
        self.raster_probability
    }

    /// Kelemen et al. 2002's exponential small step (`s1 = 1/1024`, `s2 = 1/64`, section 4.1)
    /// with large-step probability 0.3 (the value of pbrt-v3 and of the DRMLT and Langevin
    /// authors' implementations).
    #[must_use]
    pub const fn kelemen2002() -> Self {
        Self {
            small: SmallStep::new(SmallMutation::Kelemen(crate::KelemenParams::kelemen2002())),
            p_large: 0.3,
            raster: None,
            raster_probability: 0.0,
        }
    }

    /// pbrt-v3's MLT: Gaussian small steps with `sigma = 0.01`, large-step probability 0.3.
    #[must_use]
    pub const fn pbrt_v3() -> Self {
        Self {
            small: SmallStep::new(SmallMutation::Gaussian { sigma: 0.01 }),
            p_large: 0.3,
            raster: None,
            raster_probability: 0.0,
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
        // One uniform selects the component: [0, p) large, [p, p + (1 - p) q) raster, the
        // rest small (with q = 0 exactly the draws of the mixture without raster steps).
        let u = rng.random::<f64>();
        if u < self.p_large {
            return LargeStep.propose(x, y, rng).with_component(1);
        }
        if let Some(raster) = self.raster_step() {
            if u < self.p_large + (1.0 - self.p_large) * self.raster_probability {
                return raster.propose(x, y, rng).with_component(2);
            }
        }
        self.small.propose(x, y, rng)
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        let terms: [f64; 3] = std::array::from_fn(|j| self.log_q_component(j, from, to));
        mcmc_core::proposal::log_sum_exp(&terms)
    }

    fn is_symmetric(&self) -> bool {
        true
    }

    fn num_components(&self) -> usize {
        if self.raster.is_some() {
            3
        } else {
            2
        }
    }

    fn log_q_component(&self, j: usize, from: &PssState, to: &PssState) -> f64 {
        let q = self.raster_probability;
        match j {
            0 => (1.0 - self.p_large).ln() + (1.0 - q).ln() + self.small.log_q(from, to),
            1 => self.p_large.ln() + LargeStep.log_q(from, to),
            _ => match self.raster_step() {
                Some(r) => (1.0 - self.p_large).ln() + q.ln() + r.log_q(from, to),
                None => f64::NEG_INFINITY,
            },
        }
    }
    /// The large step (component 1) is uniform on primary sample space, density 1.
    fn independent_density(&self, component: usize) -> Option<f64> {
        (component == 1).then_some(1.0)
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
