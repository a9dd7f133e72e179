//! Negative controls: deliberately broken proposals and kernels that the harness must reject.
//!
//! A correctness test that cannot fail proves nothing. Each control here reproduces a bug
//! seen in real MLT code (docs/architecture.md, "Using the correctness harness from another
//! crate"); tests show the harness catches it
//! on the same target and proposal where the correct kernel passes. Other crates reuse them to
//! show their own tests have teeth.

use rand::Rng;

use crate::kernel::{mh_log_accept_prob, Kernel, Observer, StepInfo};
use crate::proposal::{log_sum_exp, Proposal, Proposed};
use crate::render_loop::mis_step;
use crate::target::{Sample, SampleOf, Target};
use crate::tunable::LargeStepTunable;

/// Wraps an asymmetric proposal and *claims* it is symmetric: `propose` reports a Hastings
/// term of 0 and `is_symmetric` returns true, while `log_q` stays the true density.
///
/// The bug: a proposal whose scale or drift depends on the state (a regional scale, a
/// gradient step) fed to a "symmetric fast path". MH with it violates detailed balance, and
/// [`super::assert_symmetric_proposal`] / [`super::assert_hastings_consistent`] expose the
/// lie directly.
#[derive(Clone, Debug)]
pub struct TreatedAsSymmetric<P>(pub P);

impl<S, P: Proposal<S>> Proposal<S> for TreatedAsSymmetric<P> {
    fn propose<R: Rng + ?Sized>(&self, x: &S, y: &mut S, rng: &mut R) -> Proposed {
        match self.0.propose(x, y, rng) {
            Proposed::Move { component, .. } => Proposed::Move {
                log_hastings: 0.0,
                component,
            },
            invalid => invalid,
        }
    }

    fn log_q(&self, from: &S, to: &S) -> f64 {
        self.0.log_q(from, to)
    }

    fn is_symmetric(&self) -> bool {
        true
    }

    fn num_components(&self) -> usize {
        self.0.num_components()
    }

    fn log_q_component(&self, j: usize, from: &S, to: &S) -> f64 {
        self.0.log_q_component(j, from, to)
    }

    fn log_hastings(&self, _j: usize, _x: &S, _y: &S) -> f64 {
        0.0
    }
}

/// Metropolis-Hastings that forgets the Hastings term: it accepts with
/// `min(1, pi(y) / pi(x))` whatever the proposal reports, while its `log_flow` honestly uses
/// the true `q` (what the kernel really does).
///
/// The bug: plain Metropolis acceptance with an asymmetric proposal.
#[derive(Clone, Debug)]
pub struct MhWithoutHastings<P> {
    /// The (honest) proposal.
    pub proposal: P,
}

impl<T: Target, P: Proposal<T::State>> Kernel<T> for MhWithoutHastings<P> {
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
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let proposed = self
            .proposal
            .propose(&current.state, &mut scratch[0].state, rng);
        // The bug: the Hastings term is dropped; everything else is the real MH decision.
        crate::mh::mh_decide(
            target,
            current,
            &mut scratch[0],
            proposed,
            |_| 0.0,
            rng,
            observer,
        )
    }

    fn log_flow(&self, _target: &T, path: &[SampleOf<T>]) -> f64 {
        let [x, y] = path else {
            return f64::NEG_INFINITY;
        };
        let terms: Vec<f64> = (0..self.proposal.num_components())
            .map(|j| {
                // The flow of what the kernel really does: true q, acceptance without Hastings.
                let log_a = mh_log_accept_prob(x.log_density, y.log_density, 0.0);
                x.log_density + self.proposal.log_q_component(j, &x.state, &y.state) + log_a
            })
            .collect();
        log_sum_exp(&terms)
    }
}

/// Forces acceptance of the candidate after `max_rejections` consecutive rejections, as
/// LuxRender's and Corona's Metropolis samplers do ("maxconsecrejects") to escape sticky
/// states. It breaks detailed balance (the chain is no longer a Markov chain on the state
/// alone, and its stationary law is not `pi`), which the stationarity test exposes.
///
/// The wrapped kernel runs normally; if it rejected and the previous `max_rejections` steps
/// were all rejections, the last candidate it evaluated (left in
/// `scratch[stages_tried - 1]` by [`crate::Mh`] and by kernels that propose stage `s` into
/// `scratch[s - 1]`) is accepted anyway, provided its density is positive and finite.
/// Observers see the wrapped kernel's weights. `log_flow` reports the wrapped kernel's
/// (claimed) flow, so pairwise checks cannot see the bug: only the stationarity test can.
#[derive(Clone, Debug)]
pub struct ForcedAcceptance<K> {
    /// The wrapped kernel.
    pub inner: K,
    /// Consecutive rejections after which the next candidate is accepted.
    pub max_rejections: u32,
    rejections: u32,
}

impl<K> ForcedAcceptance<K> {
    /// Wraps `inner`, forcing acceptance after `max_rejections` consecutive rejections.
    pub fn new(inner: K, max_rejections: u32) -> Self {
        Self {
            inner,
            max_rejections,
            rejections: 0,
        }
    }
}

impl<T: Target, K: Kernel<T>> Kernel<T> for ForcedAcceptance<K> {
    fn stages(&self) -> usize {
        self.inner.stages()
    }

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
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let mut info = self.inner.step(target, current, scratch, rng, observer);
        if info.accepted() {
            self.rejections = 0;
            return info;
        }
        let stage = usize::from(info.stages_tried.max(1));
        let candidate = info.candidate_log_density[stage - 1];
        if self.rejections >= self.max_rejections && candidate.is_finite() && !info.non_finite {
            // The bug: accept regardless of the acceptance probability.
            std::mem::swap(current, &mut scratch[stage - 1]);
            info.accepted_stage = stage as u8;
            self.rejections = 0;
        } else {
            self.rejections += 1;
        }
        info
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        self.inner.log_flow(target, path)
    }

    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        self.inner.reverse_path(target, path)
    }
}

/// Forwards every splat except those of one sample (identified by address) to `inner`.
struct SkipSample<'a, S, P, O: ?Sized> {
    skip: *const Sample<S, P>,
    inner: &'a mut O,
}

impl<S, P, O: Observer<S, P> + ?Sized> Observer<S, P> for SkipSample<'_, S, P, O> {
    fn splat(&mut self, sample: &Sample<S, P>, weight: f64) {
        if !std::ptr::eq(sample, self.skip) {
            self.inner.splat(sample, weight);
        }
    }

    fn step(&mut self, info: &StepInfo) {
        self.inner.step(info);
    }
}

/// Runs a kernel unchanged but hides the splat of the *current* state from the observer:
/// for MH, the `1 - a` weight of Veach's expected-value splatting is dropped and only the
/// candidate's `a` reaches the film.
///
/// The bug: an observer written as "splat the candidate with its acceptance probability",
/// forgetting the rejected part. The chain's states are correct (stationarity tests pass);
/// the image is too dark wherever candidates are rejected, which only the splat-weight check
/// ([`super::splat_weight_test`]) sees. The current sample is recognised by its address, so
/// this works for any kernel that splats the current sample in place (as [`crate::Mh`] does).
#[derive(Clone, Debug)]
pub struct WithoutCurrentSplat<K>(pub K);

impl<T: Target, K: Kernel<T>> Kernel<T> for WithoutCurrentSplat<K> {
    fn stages(&self) -> usize {
        self.0.stages()
    }

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
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let mut hiding = SkipSample {
            skip: std::ptr::from_ref(current),
            inner: observer,
        };
        self.0.step(target, current, scratch, rng, &mut hiding)
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        self.0.log_flow(target, path)
    }

    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        self.0.reverse_path(target, path)
    }
}

/// Runs a kernel with its splats hidden and instead splats the state the chain is in after
/// the step, with weight 1: the plain (not expected-value) estimator.
///
/// For a correct kernel this keeps the observer contract (the expected splat from `x` is
/// `E[h(X') | X = x]` by definition), so `SplatFinalState(Mh)` passes the splat-weight
/// check. Around [`ForcedAcceptance`] it is the weighting of samplers that force-accept after
/// rejections ("splat only the accepted state with weight 1"): one step then splats the
/// candidate whatever its density, and the check fails.
#[derive(Clone, Debug)]
pub struct SplatFinalState<K>(pub K);

impl<T: Target, K: Kernel<T>> Kernel<T> for SplatFinalState<K> {
    fn stages(&self) -> usize {
        self.0.stages()
    }

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
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let info = self.0.step(target, current, scratch, rng, &mut ());
        observer.splat(current, 1.0);
        observer.step(&info);
        info
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        self.0.log_flow(target, path)
    }

    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        self.0.reverse_path(target, path)
    }
}

/// Runs a two-stage kernel unchanged but splats with the DR paper's weights (Fig. 8,
/// section 4.6): `w_y = a1`, `w_z = (1 - a1) a2`, `w_x = 1 - w_y - w_z`, where `a2 = 0` when
/// no second stage ran (the reference implementation's `SplatList` weights).
///
/// The bug: those are the probabilities of the three outcomes *before* `y`'s fate is known,
/// but `z` (and `a2`) exist only after a rejection of `y`. One step then splats, in
/// expectation, `a1 h(y) + (1 - a1) [(1 - a1) a2 h(z) + (1 - (1 - a1) a2) h(x)] + a1 (1 - a1)
/// h(x)` instead of `a1 h(y) + (1 - a1) [a2 h(z) + (1 - a2) h(x)]`: weight moves from the
/// second-stage candidates to the current state, which the splat-weight check
/// ([`super::splat_weight_test`]) sees (docs/methods/drmlt.md has the numbers). The chain's
/// states are unaffected.
///
/// The samples are found by the layout [`crate::DelayedRejection`] (and [`crate::Mh`])
/// keep: the stage-`s` candidate is proposed into `scratch[s - 1]` and acceptance is a swap,
/// so after the step the old current state is in `scratch[accepted_stage - 1]` if a
/// candidate was accepted.
#[derive(Clone, Debug)]
pub struct PaperSplatWeights<K>(pub K);

impl<T: Target, K: Kernel<T>> Kernel<T> for PaperSplatWeights<K> {
    fn stages(&self) -> usize {
        self.0.stages()
    }

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
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let info = self.0.step(target, current, scratch, rng, &mut ());
        let a1 = info.accept_prob[0];
        let a2 = if info.stages_tried >= 2 {
            info.accept_prob[1]
        } else {
            0.0
        };
        let (w_y, w_z) = (a1, (1.0 - a1) * a2);
        let w_x = 1.0 - w_y - w_z;
        // Where x, y and z are after the step.
        let (x, y, z) = match info.accepted_stage {
            0 => (&*current, &scratch[0], &scratch[1]),
            1 => (&scratch[0], &*current, &scratch[1]),
            _ => (&scratch[1], &scratch[0], &*current),
        };
        if w_y > 0.0 {
            observer.splat(y, w_y);
        }
        if w_z > 0.0 {
            observer.splat(z, w_z);
        }
        observer.splat(x, w_x);
        observer.step(&info);
        info
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        self.0.log_flow(target, path)
    }

    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        self.0.reverse_path(target, path)
    }
}

/// Kelemen et al. 2002's large-step MIS estimator ([`crate::render_loop::LargeStepMis`])
/// with the large step's term dropped from the denominators: every splat keeps its MH
/// weight (`f / (f + 0) = 1`), and a large step's candidate still gets its extra splat.
///
/// The bug: writing the weights as `(a + 1) / (f(y)/b)` and `(1 - a) / (f(x)/b)` (the
/// Metropolis technique alone) while adding the independent samples: the large steps are
/// counted twice, so one step from `pi` splats `1 + p` in expectation.
#[derive(Clone, Debug)]
pub struct MisWithoutLargeStepTerm<K>(pub K);

impl<T: Target, K: Kernel<T> + LargeStepTunable> Kernel<T> for MisWithoutLargeStepTerm<K> {
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
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        mis_step(&mut self.0, 0.0, target, current, scratch, rng, observer)
    }

    fn stages(&self) -> usize {
        self.0.stages()
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        self.0.log_flow(target, path)
    }
}

/// Kelemen et al. 2002's large-step MIS estimator weighted with a large-step probability
/// `p_weights` other than the one the kernel draws with (`b_q` is `b` times the large
/// step's density, as in [`crate::render_loop::LargeStepMis::new`]).
///
/// The bug: weights computed from a stale or final `p` (e.g. the automatic controller's
/// estimate applied to the steps of its estimation phase, which used the initial `p`). One
/// step from `pi` then splats `integral h pi (pi + p q) / (pi + p' q)`, not `E_pi[h]`.
#[derive(Clone, Debug)]
pub struct MisWithStaleProbability<K> {
    /// The kernel (it draws with its own large-step probability).
    pub kernel: K,
    /// `b q`: the target's integral times the large step's density.
    pub b_q: f64,
    /// The large-step probability the weights use.
    pub p_weights: f64,
}

impl<T: Target, K: Kernel<T> + LargeStepTunable> Kernel<T> for MisWithStaleProbability<K> {
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
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let c = self.b_q * self.p_weights;
        mis_step(&mut self.kernel, c, target, current, scratch, rng, observer)
    }

    fn stages(&self) -> usize {
        self.kernel.stages()
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        self.kernel.log_flow(target, path)
    }
}
