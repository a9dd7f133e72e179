//! Mixtures of proposals with state-dependent selection probabilities s(j|x).

use rand::{Rng, RngExt};

use super::{log_sum_exp, Proposal, Proposed};
use crate::tunable::HasSharedScales;
use crate::McmcError;

/// Selection probabilities `s(j | x)` of a [`Mixture`]'s components.
pub trait Selection<S> {
    /// Writes `s(j | x)` for every component into `probs` (same length as the component list);
    /// they must be non-negative and sum to 1.
    fn probabilities(&self, x: &S, probs: &mut [f64]);
}

/// State-independent selection probabilities.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedSelection {
    probs: Vec<f64>,
}

impl FixedSelection {
    /// Selection with the given weights (normalised; non-negative, finite, positive sum).
    pub fn new(weights: &[f64]) -> Result<Self, McmcError> {
        let sum: f64 = weights.iter().sum();
        for &w in weights {
            McmcError::check_range("selection weight", w, 0.0, f64::MAX, "[0, inf)")?;
        }
        McmcError::check_range(
            "sum of selection weights",
            sum,
            f64::MIN_POSITIVE,
            f64::MAX,
            "(0, inf)",
        )?;
        Ok(Self {
            probs: weights.iter().map(|w| w / sum).collect(),
        })
    }

    /// The normalised probabilities.
    #[must_use]
    pub fn probabilities(&self) -> &[f64] {
        &self.probs
    }

    /// Replaces the probabilities (normalised). Used by controllers, e.g. automatic
    /// large-step control; see [`FixedSelection::new`] for the requirements.
    pub fn set(&mut self, weights: &[f64]) -> Result<(), McmcError> {
        *self = Self::new(weights)?;
        Ok(())
    }
}

impl<S> Selection<S> for FixedSelection {
    fn probabilities(&self, _x: &S, probs: &mut [f64]) {
        probs.copy_from_slice(&self.probs);
    }
}

/// Maximum number of mixture components (selection probabilities live on the stack).
pub const MAX_COMPONENTS: usize = 8;

/// A mixture of proposals: draw `j ~ s(. | x)`, then `y ~ T_j(. | x)`.
///
/// The reported Hastings term is the component-labelled one of the regional-adaptive paper
/// (section 3.2):
/// `log T_j(y -> x) - log T_j(x -> y) + log s(j | y) - log s(j | x)`.
/// This is a valid MH kernel for any selection function (the component index is an auxiliary
/// variable), and it never needs the other components' densities.
///
/// Components are one type `P`; use an enum of proposals for heterogeneous mixtures.
/// Mixtures of mixtures are not flattened: a component must itself be a single proposal.
#[derive(Clone, Debug)]
pub struct Mixture<P, Sel> {
    components: Vec<P>,
    selection: Sel,
}

impl<P, Sel> Mixture<P, Sel> {
    /// A mixture of `components` (1..=8 of them) selected by `selection`.
    pub fn new(components: Vec<P>, selection: Sel) -> Result<Self, McmcError> {
        if components.is_empty() || components.len() > MAX_COMPONENTS {
            return Err(McmcError::InvalidParameter {
                name: "components.len()",
                value: components.len() as f64,
                allowed: "1..=8",
            });
        }
        Ok(Self {
            components,
            selection,
        })
    }

    /// The components.
    #[must_use]
    pub fn components(&self) -> &[P] {
        &self.components
    }

    /// Mutable access to the components (for controllers).
    pub fn components_mut(&mut self) -> &mut [P] {
        &mut self.components
    }

    /// The selection function.
    #[must_use]
    pub fn selection(&self) -> &Sel {
        &self.selection
    }

    /// Mutable access to the selection function (for controllers).
    pub fn selection_mut(&mut self) -> &mut Sel {
        &mut self.selection
    }

    fn probs<S>(&self, x: &S) -> [f64; MAX_COMPONENTS]
    where
        Sel: Selection<S>,
    {
        let mut probs = [0.0; MAX_COMPONENTS];
        self.selection
            .probabilities(x, &mut probs[..self.components.len()]);
        probs
    }
}

impl<S, P: Proposal<S>, Sel: Selection<S>> Proposal<S> for Mixture<P, Sel> {
    fn propose<R: Rng + ?Sized>(&self, x: &S, y: &mut S, rng: &mut R) -> Proposed {
        let n = self.components.len();
        let probs = self.probs(x);
        let u: f64 = rng.random();
        let mut j = n - 1;
        let mut cdf = 0.0;
        for (i, p) in probs[..n].iter().enumerate() {
            cdf += p;
            if u < cdf {
                j = i;
                break;
            }
        }
        // Guard against rounding: never pick a component with zero probability.
        while probs[j] == 0.0 && j > 0 {
            j -= 1;
        }
        match self.components[j].propose(x, y, rng) {
            Proposed::Move { log_hastings, .. } => {
                let back = self.probs(y);
                let log_hastings = log_hastings + back[j].ln() - probs[j].ln();
                Proposed::Move {
                    log_hastings,
                    component: j,
                }
            }
            Proposed::Invalid { .. } => Proposed::Invalid { component: j },
        }
    }

    fn log_q(&self, from: &S, to: &S) -> f64 {
        let mut terms = [f64::NEG_INFINITY; MAX_COMPONENTS];
        for (j, t) in terms.iter_mut().enumerate().take(self.components.len()) {
            *t = self.log_q_component(j, from, to);
        }
        log_sum_exp(&terms[..self.components.len()])
    }

    fn num_components(&self) -> usize {
        self.components.len()
    }

    fn log_q_component(&self, j: usize, from: &S, to: &S) -> f64 {
        let p = self.probs(from)[j];
        if p == 0.0 {
            return f64::NEG_INFINITY;
        }
        p.ln() + self.components[j].log_q(from, to)
    }

    fn log_hastings(&self, j: usize, x: &S, y: &S) -> f64 {
        let (px, py) = (self.probs(x)[j], self.probs(y)[j]);
        self.components[j].log_hastings(0, x, y) + py.ln() - px.ln()
    }
}

/// The handle of the first component that has one.
impl<P: HasSharedScales, Sel> HasSharedScales for Mixture<P, Sel> {
    type Scales = P::Scales;
    fn shared_scales(&self) -> Option<&P::Scales> {
        self.components()
            .iter()
            .find_map(HasSharedScales::shared_scales)
    }
    fn shared_scales_mut(&mut self) -> Option<&mut P::Scales> {
        self.components_mut()
            .iter_mut()
            .find_map(HasSharedScales::shared_scales_mut)
    }
}
