//! How to decide: the transition kernel trait, step reports and observers.

use rand::Rng;

use crate::target::{Sample, SampleOf, Target};

/// Maximum number of stages of a kernel (MH has 1, delayed rejection 2).
pub const MAX_STAGES: usize = 2;

/// What one kernel step did. Small and `Copy`: controllers and statistics read it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInfo {
    /// Mixture component chosen at the first stage (0 for a plain proposal).
    pub component: usize,
    /// Number of stages that proposed a candidate (1 or 2).
    pub stages_tried: u8,
    /// Acceptance probability of each tried stage (0 for invalid candidates and untried
    /// stages).
    pub accept_prob: [f64; MAX_STAGES],
    /// Log density of each stage's candidate (`NEG_INFINITY` if invalid or untried).
    pub candidate_log_density: [f64; MAX_STAGES],
    /// The stage (1-based) whose candidate was accepted, or 0 if the chain stayed.
    pub accepted_stage: u8,
    /// True if a candidate had a NaN/+inf log density or a NaN Hastings term: it was
    /// rejected, and the chain reports the error.
    pub non_finite: bool,
}

impl StepInfo {
    /// A report for a step that has not proposed anything yet.
    #[must_use]
    pub const fn new(component: usize) -> Self {
        Self {
            component,
            stages_tried: 0,
            accept_prob: [0.0; MAX_STAGES],
            candidate_log_density: [f64::NEG_INFINITY; MAX_STAGES],
            accepted_stage: 0,
            non_finite: false,
        }
    }

    /// True if the chain moved.
    #[must_use]
    pub const fn accepted(&self) -> bool {
        self.accepted_stage != 0
    }
}

/// Receives every sample a step evaluated, with its expected-value weight, and the step report.
///
/// Expected-value splatting (Veach's thesis, section 11.3.3): for MH the current state gets
/// weight `1 - a` and the candidate `a`. The kernel does not know whether the observer splats
/// to a film, collects statistics or does nothing (`()`).
///
/// **The contract** every kernel keeps: for any function `h` of the state, the expected splat
/// of one step from `x`, `E[sum_i w_i h(s_i) | X = x]` over the samples `s_i` the step
/// reports with weights `w_i`, equals `E[h(X') | X = x]`, the expectation of `h` at the next
/// state. Summed over a chain this makes the splatted image an unbiased estimate of what the
/// chain's states would give, with less variance. MH's weights `(1 - a, a)` sum to 1 at every
/// step; delayed rejection's unbiased three-point scheme sums to 1 only in expectation, and its
/// weights may leave `[0, 1]`. The harness checks the contract directly
/// (`testing`: a splat-weighted histogram of one step from exact starts against `pi`).
pub trait Observer<S, P> {
    /// `sample` contributes with `weight` to this step's estimate (see the contract above).
    fn splat(&mut self, sample: &Sample<S, P>, weight: f64) {
        let _ = (sample, weight);
    }
    /// Receives a sample a multi-stage kernel proposed at stage `stage` (1 or 2) with its
    /// splat weight. Delayed-rejection kernels report their second-stage candidate through
    /// this (for the per-pixel "stage map" of the DR paper, Fig. 1 and 9); the default
    /// forwards to [`Observer::splat`], so observers that do not care see every splat alike.
    fn splat_at_stage(&mut self, sample: &Sample<S, P>, weight: f64, stage: u8) {
        let _ = stage;
        self.splat(sample, weight);
    }
    /// Called once at the end of each step.
    fn step(&mut self, info: &StepInfo) {
        let _ = info;
    }
}

impl<S, P> Observer<S, P> for () {}

/// One Markov transition that leaves the target invariant.
///
/// The chain owns the current sample (state + cached evaluation) and scratch samples for the
/// candidates; the kernel proposes into the scratch buffers, evaluates them, decides, reports
/// to the observer, and swaps the accepted candidate into `current`.
pub trait Kernel<T: Target> {
    /// Number of stages (candidates per step at most); the chain provides this many scratch
    /// samples.
    fn stages(&self) -> usize {
        1
    }

    /// Performs one transition.
    fn step<R, O>(
        &mut self,
        target: &T,
        current: &mut SampleOf<T>,
        scratch: &mut [SampleOf<T>],
        rng: &mut R,
        observer: &mut O,
    ) -> StepInfo
    where
        R: Rng + ?Sized,
        O: Observer<T::State, T::Payload> + ?Sized;

    /// Log of the probability flow density along a transition path, for testing detailed
    /// balance: for `path = [x, y]`, `log pi(x) + log K(x -> y)` restricted to moves that go
    /// straight to `y` (first stage); for a delayed-rejection kernel and `path = [x, y, z]`,
    /// the flow of proposing `y`, rejecting it, and moving to `z`. The samples are evaluated.
    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64;

    /// The path whose flow must equal that of `path` under detailed balance. For MH and
    /// Tierney-Mira DR it is `path` reversed; Green-Mira DR passes through a fictional state.
    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        let _ = target;
        path.iter().rev().cloned().collect()
    }

    /// `Some(q)` if the first-stage candidate of mixture component `component` was drawn
    /// independently of the current state with constant density `q` from the distribution
    /// of the render loop's independent states ([`crate::Proposal::independent_density`]):
    /// its density `f` (reported in [`StepInfo::candidate_log_density`]) then gives one more
    /// independent sample `f / q` of the target's integral. `None` (the default) for kernels
    /// without such a move; the render loop then keeps the bootstrap's normalisation.
    fn independent_density(&self, component: usize) -> Option<f64> {
        let _ = component;
        None
    }
}

/// `min(1, exp(log_ratio))` with NaN mapped to 0.
#[inline]
#[must_use]
pub fn accept_prob_from_log_ratio(log_ratio: f64) -> f64 {
    if log_ratio >= 0.0 {
        1.0
    } else if log_ratio.is_nan() {
        0.0
    } else {
        log_ratio.exp()
    }
}

/// MH acceptance probability `min(1, pi(y) q(y->x) / (pi(x) q(x->y)))` from log densities
/// and the log Hastings term. A candidate of zero density is never accepted, whatever the
/// other terms are (this also covers `-inf - -inf`).
#[inline]
#[must_use]
pub fn mh_accept_prob(log_pi_x: f64, log_pi_y: f64, log_hastings: f64) -> f64 {
    if log_pi_y == f64::NEG_INFINITY || log_hastings == f64::NEG_INFINITY {
        return 0.0;
    }
    if log_pi_x == f64::NEG_INFINITY {
        // Leaving a zero-density state (only possible from a bad start): always move.
        return 1.0;
    }
    accept_prob_from_log_ratio(log_pi_y - log_pi_x + log_hastings)
}

/// `ln` of [`mh_accept_prob`], computed in log space: `min(0, log_pi_y - log_pi_x +
/// log_hastings)`, `NEG_INFINITY` for a zero-density candidate or an impossible reverse move,
/// 0 when leaving a zero-density state, `NEG_INFINITY` for NaN ratios.
///
/// Use it for flows (`log_flow`): `mh_accept_prob(..).ln()` underflows to `-inf` (or loses
/// precision in the subnormal range) once the log ratio is below about -708, which happens
/// for legitimate pairs far out in a target's tails.
#[inline]
#[must_use]
pub fn mh_log_accept_prob(log_pi_x: f64, log_pi_y: f64, log_hastings: f64) -> f64 {
    if log_pi_y == f64::NEG_INFINITY || log_hastings == f64::NEG_INFINITY {
        return f64::NEG_INFINITY;
    }
    if log_pi_x == f64::NEG_INFINITY {
        return 0.0;
    }
    let log_ratio = log_pi_y - log_pi_x + log_hastings;
    if log_ratio >= 0.0 {
        0.0
    } else if log_ratio.is_nan() {
        f64::NEG_INFINITY
    } else {
        log_ratio
    }
}
