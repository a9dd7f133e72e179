//! What is sampled: unnormalised target densities and their evaluated samples.

/// A state of a Markov chain. `Clone::clone_from` is used to copy states into preallocated
/// buffers, so states that own heap memory (`Vec<f64>`, a primary-sample-space vector) are
/// reused without allocating per step.
///
/// Implemented for `f64`, `Vec<f64>`, `Vec<f32>` and `[f64; N]`; a state type of your own
/// needs one line, `impl mcmc_core::Point for MyState {}`, unless it is *lazily
/// materialised* (it draws parts of itself while a target reads it, like `pss::PssState`):
/// then it implements [`Point::absorb_rejected`].
///
/// # Example
/// ```
/// #[derive(Clone, Debug)]
/// struct Path { vertices: Vec<[f64; 3]> }
/// impl mcmc_core::Point for Path {}
/// ```
pub trait Point: Clone + Send + std::fmt::Debug {
    /// Called by every kernel on the current state right after a candidate proposed from it
    /// was evaluated and rejected, before anything else is proposed from it.
    ///
    /// A lazily materialised state copies from `rejected` the values of *its own* coordinates
    /// that the candidate's evaluation drew, so that the current state does not change with the
    /// candidate's fate (what makes lazy primary-sample-space mutation exact: see
    /// `pss::PssState`). The default does nothing, which is right for every state that is
    /// fully defined when it is created.
    fn absorb_rejected(&mut self, rejected: &Self) {
        let _ = rejected;
    }

    /// Called by kernels whose acceptance reads proposal densities of whole states (delayed
    /// rejection under Tierney & Mira's or Green & Mira's rule, eq. 6 and 12-14 of the DR
    /// paper) on an evaluated candidate, before those densities are computed, with `known`
    /// either the state it was proposed from (its parent) or another candidate proposed from
    /// the same parent (a sibling).
    ///
    /// A lazily mutated candidate stores stale values for the coordinates its evaluation did
    /// not read, so a density over its stored coordinates would read values the eager
    /// candidate does not have. It must bring every coordinate it stores, the parent stores,
    /// or the sibling drew of the parent, up to date, logging the parent values it draws as an
    /// evaluation does (so that [`Point::absorb_rejected`] keeps them). The default does
    /// nothing, which is right for every state that is fully defined when it is proposed.
    fn catch_up_with(&mut self, known: &Self) {
        let _ = known;
    }
}

impl Point for f64 {}
impl Point for Vec<f64> {}
impl Point for Vec<f32> {}
impl<const N: usize> Point for [f64; N] {}

/// An unnormalised density over a state space: the thing a Markov chain samples.
///
/// Targets are shared by many chains (`&self`, `Sync`) and never own a random number
/// generator: a target is a deterministic function of the state.
///
/// # Notes
/// `evaluate` takes the state mutably so that lazily defined states (a primary sample space
/// vector that grows as the path consumes dimensions, or a state that caches its own gradient)
/// can materialise what the evaluation reads. It must not change the point the state
/// represents: evaluating twice gives the same result.
pub trait Target: Sync {
    /// The state space.
    type State: Point;
    /// What an evaluation produces besides the density (for rendering: the pixel position and
    /// RGB contribution of each splat; `()` for toy targets). Written into a caller-owned buffer
    /// so that evaluation does not allocate.
    type Payload: Clone + Default + Send + std::fmt::Debug;

    /// Evaluates the target at `x`: returns the log density (`f64::NEG_INFINITY` for zero) and
    /// writes the payload into `payload` (overwriting it).
    fn evaluate(&self, x: &mut Self::State, payload: &mut Self::Payload) -> f64;
}

/// A target that can also differentiate its log density.
pub trait DifferentiableTarget: Target {
    /// As [`Target::evaluate`], and also writes the gradient of the log density with respect to
    /// the state's coordinates into `grad` (resized by the target to the state's dimension).
    fn evaluate_with_grad(
        &self,
        x: &mut Self::State,
        payload: &mut Self::Payload,
        grad: &mut Vec<f64>,
    ) -> f64;
}

/// An evaluated state: the state, its log density and its payload. Chains cache the current
/// sample, so a state is never evaluated twice.
#[derive(Clone, Debug)]
pub struct Sample<S, P> {
    /// The state.
    pub state: S,
    /// Its log target density (`f64::NEG_INFINITY` for zero).
    pub log_density: f64,
    /// What the target evaluation produced besides the density.
    pub payload: P,
}

/// The [`Sample`] type of a target.
pub type SampleOf<T> = Sample<<T as Target>::State, <T as Target>::Payload>;

impl<S: Point, P: Clone + Default + Send + std::fmt::Debug> Sample<S, P> {
    /// Evaluates `target` at `state` and wraps the result.
    pub fn evaluate<T>(target: &T, mut state: S) -> Self
    where
        T: Target<State = S, Payload = P> + ?Sized,
    {
        let mut payload = P::default();
        let log_density = target.evaluate(&mut state, &mut payload);
        Self {
            state,
            log_density,
            payload,
        }
    }

    /// Copies `other` into `self`, reusing `self`'s allocations.
    pub fn copy_from(&mut self, other: &Self) {
        self.state.clone_from(&other.state);
        self.log_density = other.log_density;
        self.payload.clone_from(&other.payload);
    }
}

/// Central finite-difference gradient of the log density of a target over `Vec<f64>` states:
/// for tests, and for targets that cannot differentiate.
///
/// Returns the log density at `x`. Coordinates where the density is zero on either side get
/// a zero derivative.
pub fn finite_difference_gradient<T>(target: &T, x: &[f64], h: f64, grad: &mut Vec<f64>) -> f64
where
    T: Target<State = Vec<f64>> + ?Sized,
{
    let mut payload = T::Payload::default();
    let mut probe = x.to_vec();
    let centre = target.evaluate(&mut probe, &mut payload);
    grad.clear();
    grad.resize(x.len(), 0.0);
    for i in 0..x.len() {
        probe.copy_from_slice(x);
        probe[i] = x[i] + h;
        let plus = target.evaluate(&mut probe, &mut payload);
        probe[i] = x[i] - h;
        let minus = target.evaluate(&mut probe, &mut payload);
        let d = (plus - minus) / (2.0 * h);
        grad[i] = if d.is_finite() { d } else { 0.0 };
    }
    centre
}

/// Wraps a target over `Vec<f64>` with a central finite-difference gradient (step `h`).
#[derive(Clone, Copy, Debug)]
pub struct FiniteDifference<T> {
    /// The wrapped target.
    pub target: T,
    /// Finite-difference step.
    pub h: f64,
}

impl<T: Target<State = Vec<f64>>> Target for FiniteDifference<T> {
    type State = Vec<f64>;
    type Payload = T::Payload;
    fn evaluate(&self, x: &mut Vec<f64>, payload: &mut T::Payload) -> f64 {
        self.target.evaluate(x, payload)
    }
}

impl<T: Target<State = Vec<f64>>> DifferentiableTarget for FiniteDifference<T> {
    fn evaluate_with_grad(
        &self,
        x: &mut Vec<f64>,
        payload: &mut T::Payload,
        grad: &mut Vec<f64>,
    ) -> f64 {
        finite_difference_gradient(&self.target, x, self.h, grad);
        self.target.evaluate(x, payload)
    }
}
