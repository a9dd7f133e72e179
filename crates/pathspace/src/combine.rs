//! The regional-adaptive paper's combination of a perturbation with a global mutation
//! (section 8.1): 0.5 each, the global one when the perturbation cannot apply.

use mcmc_core::proposal::{Mixture, Selection};
use mcmc_core::{McmcError, Proposal, Proposed};
use rand::Rng;

use crate::path::Path;
use crate::perturb::{eye_subpath_end, PerturbationKind};

/// One component of a path-space mutation mixture: a perturbation or a global mutation.
///
/// mcmc-core's [`Mixture`] holds components of one type; this enum puts a perturbation
/// (a [`crate::Perturbation`], or one wrapped by mcmc-core's `Scaled`/`Regional`) and a global
/// mutation (e.g. [`crate::IndependenceMutation`]) side by side.
#[derive(Clone, Debug)]
pub enum PathMutation<P, G> {
    /// The local move (component 0 in [`ra_mixture`]).
    Perturb(P),
    /// The global move (component 1 in [`ra_mixture`]).
    Global(G),
}

impl<P: Proposal<Path>, G: Proposal<Path>> Proposal<Path> for PathMutation<P, G> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        match self {
            Self::Perturb(p) => p.propose(x, y, rng),
            Self::Global(g) => g.propose(x, y, rng),
        }
    }

    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        match self {
            Self::Perturb(p) => p.log_q(from, to),
            Self::Global(g) => g.log_q(from, to),
        }
    }
}

/// The selection `s(j | x)` of section 8.1: the perturbation (component 0) with probability
/// `perturb_probability` if it applies to `x`, else 0; the global mutation (component 1) takes
/// the rest. Being state-dependent, it enters the Hastings term as `s(j | y) / s(j | x)`
/// (section 3.2), which [`Mixture`] accounts for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerturbOrGlobal {
    /// The perturbation whose applicability decides.
    pub kind: PerturbationKind,
    /// Probability of the perturbation where it applies (0.5 in the paper).
    pub perturb_probability: f64,
}

impl PerturbOrGlobal {
    /// The paper's choice: 0.5 each (section 8.1).
    #[must_use]
    pub const fn otsu2018(kind: PerturbationKind) -> Self {
        Self {
            kind,
            perturb_probability: 0.5,
        }
    }
}

impl Selection<Path> for PerturbOrGlobal {
    fn probabilities(&self, x: &Path, probs: &mut [f64]) {
        let p = if eye_subpath_end(self.kind, x).is_some() {
            self.perturb_probability
        } else {
            0.0
        };
        probs[0] = p;
        probs[1] = 1.0 - p;
    }
}

/// The mixture of section 8.1: `perturbation` with probability 0.5 where it applies,
/// `global` otherwise (component 0 = perturbation, 1 = global).
///
/// # Example
/// ```
/// use mcmc_core::Proposal;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{
///     ra_mixture, BidirectionalMutation, BidirectionalParams, FixedScale, Perturbation,
///     PerturbationKind,
/// };
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let mutation = ra_mixture(
///     PerturbationKind::Lens,
///     Perturbation::lens(&scene, FixedScale::otsu2018()),
///     BidirectionalMutation::new(&scene, BidirectionalParams::default()).unwrap(),
/// )
/// .unwrap();
/// assert_eq!(mutation.num_components(), 2);
/// ```
///
/// # Errors
/// Never for these two components (kept as `Result` because [`Mixture::new`] validates).
pub fn ra_mixture<P, G>(
    kind: PerturbationKind,
    perturbation: P,
    global: G,
) -> Result<Mixture<PathMutation<P, G>, PerturbOrGlobal>, McmcError> {
    Mixture::new(
        vec![
            PathMutation::Perturb(perturbation),
            PathMutation::Global(global),
        ],
        PerturbOrGlobal::otsu2018(kind),
    )
}

/// The selection of section 8.1 with the global move split between two global mutations
/// (components 1 and 2): the perturbation (component 0) with probability
/// `perturb_probability` where it applies, else 0; of the rest, `second_share` goes to
/// component 2 and the remainder to component 1. Every component keeps its own Hastings term
/// (mcmc-core's component-labelled [`Mixture`]), which matters when the global mutations'
/// densities live on different measures: a bidirectional mutation that keeps vertices of `x`
/// is singular with respect to an independence sampler's density, so the two cannot be summed
/// into one transition density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerturbOrGlobalPair {
    /// The perturbation and its probability where it applies.
    pub perturb: PerturbOrGlobal,
    /// Share of the global probability given to component 2.
    pub second_share: f64,
}

impl Selection<Path> for PerturbOrGlobalPair {
    fn probabilities(&self, x: &Path, probs: &mut [f64]) {
        let mut two = [0.0; 2];
        self.perturb.probabilities(x, &mut two);
        probs[0] = two[0];
        probs[1] = two[1] * (1.0 - self.second_share);
        probs[2] = two[1] * self.second_share;
    }
}
