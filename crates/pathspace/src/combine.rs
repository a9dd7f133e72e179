//! The regional-adaptive paper's combination of a perturbation with a global mutation
//! (section 8.1): 0.5 each, the global one when the perturbation cannot apply.

use mcmc_core::proposal::{Mixture, Selection};
use mcmc_core::{McmcError, Proposal, Proposed};
use rand::{Rng, RngExt};

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

/// Two global mutations blended into one proposal: `second` with probability
/// `second_probability`, else `first`, with the blend's own transition density
/// `T(y | x) = (1 - q) T_1(y | x) + q T_2(y | x)` in the Hastings term (so, unlike a
/// component-labelled [`Mixture`], it can sit inside one as a single component).
///
/// pathmlt blends the bidirectional mutation with the independence mutation of a
/// bidirectional sampler: the latter reaches, in one step, paths whose share of the image is
/// too small for deletions of short subpaths to find.
///
/// # Example
/// ```
/// use mcmc_core::Proposal;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{
///     BidirectionalMutation, BidirectionalParams, BidirectionalSampler,
///     BidirectionalSamplerParams, Blend, IndependenceMutation,
/// };
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let sampler = BidirectionalSampler::new(&scene, BidirectionalSamplerParams::default()).unwrap();
/// let blend = Blend::new(
///     BidirectionalMutation::new(&scene, BidirectionalParams::default()).unwrap(),
///     IndependenceMutation::new(sampler),
///     0.5,
/// )
/// .unwrap();
/// assert_eq!(blend.num_components(), 1);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Blend<A, B> {
    first: A,
    second: B,
    second_probability: f64,
}

impl<A, B> Blend<A, B> {
    /// The blend drawing from `second` with probability `second_probability`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] for a probability outside `[0, 1]`.
    pub fn new(first: A, second: B, second_probability: f64) -> Result<Self, McmcError> {
        if !(0.0..=1.0).contains(&second_probability) {
            return Err(McmcError::InvalidParameter {
                name: "second_probability",
                value: second_probability,
                allowed: "[0, 1]",
            });
        }
        Ok(Self {
            first,
            second,
            second_probability,
        })
    }
}

impl<A: Proposal<Path>, B: Proposal<Path>> Proposal<Path> for Blend<A, B> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        let second = rng.random::<f64>() < self.second_probability;
        let drawn = if second {
            self.second.propose(x, y, rng)
        } else {
            self.first.propose(x, y, rng)
        };
        if let Proposed::Invalid { .. } = drawn {
            return Proposed::Invalid { component: 0 };
        }
        let forward = self.log_q(x, y);
        if !forward.is_finite() {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.log_q(y, x) - forward)
    }

    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        let q = self.second_probability;
        let first = if q < 1.0 {
            (1.0 - q).ln() + self.first.log_q(from, to)
        } else {
            f64::NEG_INFINITY
        };
        let second = if q > 0.0 {
            q.ln() + self.second.log_q(from, to)
        } else {
            f64::NEG_INFINITY
        };
        mcmc_core::proposal::log_sum_exp(&[first, second])
    }
}
