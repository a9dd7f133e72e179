//! How to move: proposals with exact transition densities, mixtures and scale wrappers.

mod conditional;
mod gaussian;
mod independent;
mod mixture;
mod scaled;

pub use conditional::ConditionalProposal;
pub use gaussian::GaussianRandomWalk;
pub use independent::IndependentUniform;
pub use mixture::{FixedSelection, Mixture, Selection, MAX_COMPONENTS};
pub use scaled::{Regional, Scaled, ScaledProposal};

use rand::Rng;

/// What a proposal reports about the candidate it wrote.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Proposed {
    /// A candidate was written. `log_hastings` is `log q(y -> x) - log q(x -> y)` for the
    /// component that generated it (including any state-dependent selection terms);
    /// `component` names that component (0 for a single proposal).
    Move {
        /// `log q(y -> x) - log q(x -> y)`; `NEG_INFINITY` if the reverse move is impossible.
        log_hastings: f64,
        /// Index of the mixture component that generated the candidate.
        component: usize,
    },
    /// The proposal could not produce a valid candidate (e.g. a path perturbation changed the
    /// path structure). Counts as a rejection; the target is not evaluated.
    Invalid {
        /// Index of the mixture component that failed.
        component: usize,
    },
}

impl Proposed {
    /// A move from a symmetric proposal (Hastings term 0) of component 0.
    #[must_use]
    pub const fn symmetric() -> Self {
        Proposed::Move {
            log_hastings: 0.0,
            component: 0,
        }
    }

    /// A move with the given log Hastings term, component 0.
    #[must_use]
    pub const fn hastings(log_hastings: f64) -> Self {
        Proposed::Move {
            log_hastings,
            component: 0,
        }
    }

    /// The component that produced this outcome.
    #[must_use]
    pub const fn component(&self) -> usize {
        match *self {
            Proposed::Move { component, .. } | Proposed::Invalid { component } => component,
        }
    }

    /// The same outcome attributed to `component`.
    #[must_use]
    pub const fn with_component(self, component: usize) -> Self {
        match self {
            Proposed::Move { log_hastings, .. } => Proposed::Move {
                log_hastings,
                component,
            },
            Proposed::Invalid { .. } => Proposed::Invalid { component },
        }
    }
}

/// A Markov transition proposal `q(x -> y)` that exposes its transition density.
///
/// Proposals never own a random number generator: the chain passes one down. They write the
/// candidate into a caller-owned buffer (`y`), which the caller may have filled with anything;
/// implementations typically start with `y.clone_from(x)`.
///
/// A proposal may be a *mixture* of components selected with (state-dependent) probability
/// `s(j | x)`; then `log_q_component(j, ..)` includes `log s(j | from)`, and the chain is the
/// component-labelled MH of the regional-adaptive paper, section 3.2: the acceptance ratio uses
/// `pi(y) T_j(x|y) s(j|y) / (pi(x) T_j(y|x) s(j|x))` for the component j that was drawn.
pub trait Proposal<S> {
    /// Draws a candidate `y` given the current state `x`.
    fn propose<R: Rng + ?Sized>(&self, x: &S, y: &mut S, rng: &mut R) -> Proposed;

    /// Log transition density `log q(from -> to)` (marginal over components); `NEG_INFINITY`
    /// if `to` cannot be reached.
    fn log_q(&self, from: &S, to: &S) -> f64;

    /// True if `q(x -> y) == q(y -> x)` for all pairs; then the Hastings term is 0 and tests
    /// assert the symmetry.
    fn is_symmetric(&self) -> bool {
        false
    }

    /// Number of mixture components (1 for a plain proposal).
    fn num_components(&self) -> usize {
        1
    }

    /// `log s(j | from) + log T_j(from -> to)`: the density of moving through component `j`.
    fn log_q_component(&self, j: usize, from: &S, to: &S) -> f64 {
        debug_assert_eq!(j, 0);
        self.log_q(from, to)
    }

    /// `(log q_j(a -> b) - c, log q_j(x -> y) - c)` for some `c` common to both: the two
    /// first-stage densities of delayed rejection's second-stage ratio (DR paper eq. 6 and
    /// 12: `Q1_j(y* | z)` over `Q1_j(y | x)`), each without the factors they share. The
    /// default evaluates both densities whole (`c = 0`); a proposal whose density is a
    /// product over coordinates may skip the coordinates where `a = x` and `b = y` (those the
    /// second stage did not move), whose factors are equal. `NEG_INFINITY` entries as
    /// [`Proposal::log_q_component`] gives them.
    fn log_q_component_pair(&self, j: usize, a: &S, b: &S, x: &S, y: &S) -> (f64, f64) {
        (self.log_q_component(j, a, b), self.log_q_component(j, x, y))
    }

    /// The Hastings term `propose` reports for a move `x -> y` through component `j`.
    /// Correct proposals never override this; it exists so that tests can evaluate the
    /// acceptance a kernel *would* compute for any pair, and so that deliberately broken
    /// proposals (negative controls) can lie about it.
    fn log_hastings(&self, j: usize, x: &S, y: &S) -> f64 {
        if self.is_symmetric() {
            0.0
        } else {
            self.log_q_component(j, y, x) - self.log_q_component(j, x, y)
        }
    }

    /// `Some(q)` if component `component` draws its candidate independently of the current
    /// state with the constant density `q` on the support of the target, from the distribution
    /// the render loop's independent states are drawn from (a large step of primary sample
    /// space: uniform, `q = 1`); `None` (the default) for any other move. A candidate `y` of
    /// such a component is an independent sample of the target's integral, `f(y) / q`
    /// (Kelemen et al. 2002, section 4), which the render loop pools into its normalisation
    /// ([`crate::render_loop::Normalization`]).
    fn independent_density(&self, component: usize) -> Option<f64> {
        let _ = component;
        None
    }
}

/// log-sum-exp of a slice, robust to `NEG_INFINITY` entries.
#[must_use]
pub fn log_sum_exp(values: &[f64]) -> f64 {
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY || max.is_nan() {
        return max;
    }
    max + values.iter().map(|v| (v - max).exp()).sum::<f64>().ln()
}
