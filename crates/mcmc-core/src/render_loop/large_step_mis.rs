//! Kelemen et al. 2002's multiple-importance combination of the large-step samples with the
//! Metropolis estimator: a kernel wrapper that reweights a kernel's expected-value splats.
//!
//! # The estimator (Kelemen, Szirmay-Kalos, Antal, Csonka 2002, section 4)
//! A chain with large-step probability `p` sees two kinds of samples of the integrand `g`
//! (a pixel's contribution, `f` its scalar target, `b = integral of f`, `pi = f / b`):
//!
//! 1. the Metropolis samples, `N` of them, distributed as `pi` (expected values: the current
//!    state with weight `1 - a` and the candidate with `a` per step);
//! 2. the large-step candidates, about `p N` of them, drawn *independently* from the large
//!    step's own density `q` (primary sample space: uniform, `q = 1`).
//!
//! The balance heuristic (Veach 1997, eq. 9.10) over the two techniques gives every sample
//! `s` the estimate `g(s) / (N pi(s) + p N q(s))`; summing over both kinds and taking
//! expected values over the accept decision gives the paper's weights (section 4, the
//! unnumbered estimator after eq. 5; LuxRender's and LuxCore's METROPOLIS sampler):
//!
//! ```text
//! large step:  y with (a + 1) / (f(y)/b + p q),   x with (1 - a) / (f(x)/b + p q)
//! small step:  y with  a      / (f(y)/b + p q),   x with (1 - a) / (f(x)/b + p q)
//! contribution of a weighted sample s:  g(s) * weight / N.
//! ```
//!
//! In the render loop's units (a splat adds `w rgb / f`, the sink is multiplied by `b / N`,
//! Kelemen eq. 5) the same estimator is the kernel's own splat weight `w` times
//!
//! ```text
//! m(s) = f(s) / (f(s) + b p q(s))  =  1 / (1 + b p q(s) / f(s)),
//! ```
//!
//! plus, on a large step, one more splat of the candidate with weight `m(y)`: so the
//! candidate of a large step gets `(a + 1) m(y)` and the current state `(1 - a) m(x)`.
//!
//! # Unbiasedness (derivation)
//! Let `h = g / f` (what a splat of weight 1 adds, before the factor `b / N`). One step from
//! `X ~ pi` with fixed `p` splats, in expectation,
//!
//! ```text
//! E[(1 - a) m h (x) + a m h (y)] + p E_q[m h (y)]
//!   = E_pi[m h] + p integral q m h            (the MH part: X' ~ pi, expected values)
//!   = integral m h (pi + p q)
//!   = integral (pi / (pi + p q)) h (pi + p q) = E_pi[h],
//! ```
//!
//! the same as the plain estimator: `b / N` times the sum over `N` steps is unbiased for
//! `b E_pi[h] = integral g`. Unlike the plain estimator, a *single* step does not keep the
//! per-state observer contract (`E[splat | X = x] = E[h(X') | x]`): only the average over
//! `x ~ pi` is right, which is exactly what the harness's splat-weight check tests
//! (`testing::splat_weight_test`, one step from exact starts).
//!
//! **p per step.** The weights use the large-step probability the kernel draws the step
//! with, read before the step: each step is then unbiased on its own, whatever `p` was at
//! other steps. Under automatic large-step control `p` is `initial` during the estimation
//! phase and the frozen estimate afterwards; both phases are weighted with their own `p`.
//! The only deviation is the one the plain estimator has too: the chosen `p` depends on the
//! chain's past (finite adaptation; the state is exactly `pi`-distributed only for a `p`
//! fixed in advance).
//!
//! **Estimated `b`.** The loop uses the bootstrap's estimate `b^_d` of the chain's target
//! (MMLT: one per depth, chains of target `d` getting a share `b^_d / b^` of the
//! mutations). With `b^_d = b_d (1 + e)`, the expectation of the combined estimator is
//! `integral g (1 + e m)` where the plain one gives `integral g (1 + e)`: the MIS estimator
//! is never more sensitive to the bootstrap's error, and not at all where large steps
//! dominate (`m` near 0).
//!
//! # Two-stage kernels
//! The derivation uses one property of the kernel's splats: the observer contract
//! `E[sum_i w_i k(s_i) | x] = E[k(X') | x]` for every function `k` (the splats are expected
//! values of the next state). Weighting each splat by `m(s_i)` is the contract for
//! `k = m h`, so its expectation from `x ~ pi` is `E_pi[m h]` whatever produced the splats.
//! Delayed rejection's three-point splats ([`crate::DelayedRejection`]: `y` with `a1`, then
//! `z` with `a2` and `x` with `1 - a2` after a second stage, or `x` with `1 - a1`; the same in
//! [`crate::langevin::CheapThenExpensive`]) keep that contract, so
//!
//! ```text
//! E[splats of one step] = E_pi[m h] + p E_q[m h (y)] = E_pi[h]
//! ```
//!
//! for them too, with the extra splat of the large-step candidate `y` as for MH: a large
//! step is component `j` of the first stage, drawn with probability `p` from the density
//! `q`, independently of `x`, and `y` is splatted whatever happens next (accepted at stage 1,
//! rejected, or rejected and followed by a second stage when the kernel runs one after large
//! steps). The second-stage candidate `z` is a Metropolis sample (its weight is part of the
//! contract), not a technique of its own: it gets `a2 m(z)`.
//!
//! Requirements: a kernel whose splats keep the observer contract, that leaves the
//! first-stage candidate in `scratch[0]` unless it is accepted at stage 1 (then it is in
//! `current`), as [`crate::Mh`], [`crate::DelayedRejection`] and
//! [`crate::langevin::CheapThenExpensive`] do, and whose large step (named by
//! [`LargeStepTunable::is_large_step`]) is an independent proposal of constant density
//! `q` on the target's support.

use rand::Rng;

use super::ChainSlot;
use crate::kernel::{Kernel, Observer, StepInfo};
use crate::target::{Sample, SampleOf, Target};
use crate::tunable::LargeStepTunable;

/// Wraps a kernel with a large step (single-stage or two-stage) and splats with Kelemen et al. 2002's
/// multiple-importance combination of the large-step samples and the Metropolis samples
/// (section 4; see the module docs for the weights and the derivation). Disabled, it is
/// the kernel itself (one branch per step).
///
/// Allocation-free and deterministic: one `exp` per splat and one extra splat per large
/// step.
///
/// # Example
/// ```
/// use mcmc_core::proposal::IndependentUniform;
/// use mcmc_core::render_loop::LargeStepMis;
/// use mcmc_core::Mh;
///
/// let kernel = Mh::new(IndependentUniform::new(vec![0.0], vec![1.0]).unwrap());
/// // A target of integral b = 2 over the unit interval, whose large step has density 1.
/// let mis = LargeStepMis::new(kernel, 2.0, 1.0);
/// assert!(mis.is_enabled());
/// ```
#[derive(Clone, Debug)]
pub struct LargeStepMis<K> {
    kernel: K,
    /// `b q`: the target's integral times the large step's density (0 = disabled).
    b_q: f64,
}

impl<K> LargeStepMis<K> {
    /// The combined estimator for a target of integral `b` (its bootstrap estimate) whose
    /// large step draws with constant density `large_step_density` (`q`; 1 in primary sample
    /// space). Disabled unless `b q` is positive and finite.
    pub fn new(kernel: K, b: f64, large_step_density: f64) -> Self {
        let b_q = b * large_step_density;
        Self {
            kernel,
            b_q: if b_q.is_finite() && b_q > 0.0 {
                b_q
            } else {
                0.0
            },
        }
    }

    /// The kernel unchanged (the plain expected-value estimator).
    pub const fn disabled(kernel: K) -> Self {
        Self { kernel, b_q: 0.0 }
    }

    /// Enabled iff the render loop asks for it ([`super::LoopSettings::large_step_mis`],
    /// passed in [`ChainSlot::large_step_mis`]), with the chain's target's bootstrap
    /// estimate [`ChainSlot::target_b`].
    pub fn for_slot(kernel: K, slot: ChainSlot, large_step_density: f64) -> Self {
        if slot.large_step_mis {
            Self::new(kernel, slot.target_b, large_step_density)
        } else {
            Self::disabled(kernel)
        }
    }

    /// True if the splats are reweighted.
    #[must_use]
    pub fn is_enabled(&self) -> bool {
        self.b_q > 0.0
    }

    /// The wrapped kernel.
    pub fn kernel(&self) -> &K {
        &self.kernel
    }

    /// Mutable access to the wrapped kernel.
    pub fn kernel_mut(&mut self) -> &mut K {
        &mut self.kernel
    }
}

/// `m = f / (f + c)` from `ln f` and `c = b p q` (1 when `c = 0`, 0 for `f = 0`).
#[inline]
pub(crate) fn mis_factor(log_f: f64, c: f64) -> f64 {
    if c == 0.0 {
        1.0
    } else {
        1.0 / (1.0 + c * (-log_f).exp())
    }
}

/// Forwards splats multiplied by [`mis_factor`]; holds back the end-of-step call (the
/// wrapper sends it after the extra large-step splat).
struct MisObserver<'o, O: ?Sized> {
    inner: &'o mut O,
    c: f64,
}

impl<S, P, O: Observer<S, P> + ?Sized> Observer<S, P> for MisObserver<'_, O> {
    #[inline]
    fn splat(&mut self, sample: &Sample<S, P>, weight: f64) {
        let m = mis_factor(sample.log_density, self.c);
        self.inner.splat(sample, weight * m);
    }
    #[inline]
    fn splat_at_stage(&mut self, sample: &Sample<S, P>, weight: f64, stage: u8) {
        let m = mis_factor(sample.log_density, self.c);
        self.inner.splat_at_stage(sample, weight * m, stage);
    }
    fn step(&mut self, _info: &StepInfo) {}
}

/// One step of `kernel` with the MIS weights of `c` (`= b p q`, the denominators' large-step
/// term) and the extra splat of a large step's candidate; shared by [`LargeStepMis`] and the
/// negative controls of `testing`.
pub(crate) fn mis_step<T, K, R, O>(
    kernel: &mut K,
    c: f64,
    target: &T,
    current: &mut SampleOf<T>,
    scratch: &mut [SampleOf<T>],
    rng: &mut R,
    observer: &mut O,
) -> StepInfo
where
    T: Target,
    K: Kernel<T> + LargeStepTunable,
    R: Rng + ?Sized,
    O: Observer<T::State, T::Payload> + ?Sized,
{
    let info = {
        let mut mis = MisObserver {
            inner: &mut *observer,
            c,
        };
        kernel.step(target, current, scratch, rng, &mut mis)
    };
    let log_fy = info.candidate_log_density[0];
    if kernel.is_large_step(info.component) && log_fy.is_finite() {
        // The candidate: swapped into `current` if accepted at stage 1, still in
        // `scratch[0]` otherwise (a second stage, if any, proposes into `scratch[1]`).
        let y: &SampleOf<T> = if info.accepted_stage == 1 {
            current
        } else {
            &scratch[0]
        };
        debug_assert_eq!(y.log_density.to_bits(), log_fy.to_bits());
        observer.splat(y, mis_factor(log_fy, c));
    }
    observer.step(&info);
    info
}

impl<T: Target, K: Kernel<T> + LargeStepTunable> Kernel<T> for LargeStepMis<K> {
    fn stages(&self) -> usize {
        self.kernel.stages()
    }

    #[inline]
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
        if self.b_q == 0.0 {
            return self.kernel.step(target, current, scratch, rng, observer);
        }
        // The probability this step is drawn with (a controller may change it afterwards).
        let c = self.b_q * self.kernel.large_step_probability();
        mis_step(&mut self.kernel, c, target, current, scratch, rng, observer)
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        self.kernel.log_flow(target, path)
    }

    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        self.kernel.reverse_path(target, path)
    }

    fn independent_density(&self, component: usize) -> Option<f64> {
        self.kernel.independent_density(component)
    }
}

impl<K: LargeStepTunable> LargeStepTunable for LargeStepMis<K> {
    fn large_step_probability(&self) -> f64 {
        self.kernel.large_step_probability()
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.kernel.set_large_step_probability(p);
    }
    fn is_large_step(&self, component: usize) -> bool {
        self.kernel.is_large_step(component)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factor_is_the_balance_heuristic() {
        // f = 3, b p q = 1: m = 3 / 4.
        assert!((mis_factor(3f64.ln(), 1.0) - 0.75).abs() < 1e-15);
        assert_eq!(mis_factor(3f64.ln(), 0.0), 1.0);
        assert_eq!(mis_factor(f64::NEG_INFINITY, 1.0), 0.0);
        assert_eq!(mis_factor(f64::NEG_INFINITY, 0.0), 1.0);
        assert!(mis_factor(800.0, 1.0) == 1.0);
    }

    #[test]
    fn constructors() {
        assert!(!LargeStepMis::new((), 0.0, 1.0).is_enabled());
        assert!(!LargeStepMis::new((), f64::NAN, 1.0).is_enabled());
        assert!(!LargeStepMis::disabled(()).is_enabled());
        let slot = ChainSlot {
            chain: 0,
            target: 0,
            target_b: 2.0,
            large_step_mis: true,
        };
        assert!(LargeStepMis::for_slot((), slot, 1.0).is_enabled());
        let off = ChainSlot {
            large_step_mis: false,
            ..slot
        };
        assert!(!LargeStepMis::for_slot((), off, 1.0).is_enabled());
    }
}
