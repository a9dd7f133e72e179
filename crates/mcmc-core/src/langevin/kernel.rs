//! The MALA kernel: evaluate the candidate with its gradient, then decide; mixed with large
//! steps and a plain fallback step, component-labelled.

use rand::{Rng, RngExt};

use super::adaptation::Adaptation;
use super::gaussian::ProposalGaussian;
use super::params::LangevinParams;
use super::space::LangevinSpace;
use crate::kernel::{mh_accept_prob, mh_log_accept_prob, Kernel, Observer, StepInfo};
use crate::mh::mh_decide;
use crate::proposal::{log_sum_exp, Proposal, Proposed};
use crate::target::{DifferentiableTarget, Point, SampleOf};
use crate::tunable::LargeStepTunable;
use crate::McmcError;

/// A proposal that is never selected (the default large step and fallback of [`Langevin`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoMove;

impl<S> Proposal<S> for NoMove {
    fn propose<R: Rng + ?Sized>(&self, _x: &S, _y: &mut S, _rng: &mut R) -> Proposed {
        Proposed::Invalid { component: 0 }
    }
    fn log_q(&self, _from: &S, _to: &S) -> f64 {
        f64::NEG_INFINITY
    }
}

/// Mixture component of a MALA step.
pub const MALA_COMPONENT: usize = 0;
/// Mixture component of a large step.
pub const LARGE_STEP_COMPONENT: usize = 1;
/// Mixture component of the plain fallback step.
pub const FALLBACK_COMPONENT: usize = 2;

/// The gradient at the chain's current state, cached with a copy of the state's coordinates
/// and log density so that it is computed once per state and recomputed only if the chain's
/// current sample was replaced from outside the kernel.
#[derive(Clone, Debug, Default)]
pub(crate) struct CurrentGradient {
    pub(crate) coords: Vec<f64>,
    pub(crate) gradient: Vec<f64>,
    log_density_bits: u64,
    valid: bool,
    /// True once a MALA step proposed from this state (the cache stores states once).
    pub(crate) visited: bool,
}

impl CurrentGradient {
    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
        self.visited = false;
    }

    /// Makes `coords` (and, if `with_gradient`, `gradient`) describe `current`, evaluating the
    /// gradient in `scratch` when it is not cached. Returns the evaluations done (0 or 1).
    pub(crate) fn ensure<T, Sp>(
        &mut self,
        target: &T,
        space: &Sp,
        params: &LangevinParams,
        current: &SampleOf<T>,
        scratch: &mut SampleOf<T>,
        with_gradient: bool,
    ) where
        T: DifferentiableTarget,
        Sp: LangevinSpace<T::State>,
    {
        let bits = current.log_density.to_bits();
        let mut coords = std::mem::take(&mut self.coords);
        space.read(&current.state, &mut coords);
        let same = self.valid && bits == self.log_density_bits && coords == self.coords;
        if !same {
            self.valid = false;
            self.visited = false;
        }
        // Keep the previous buffer's allocation in `coords` for the next call.
        std::mem::swap(&mut self.coords, &mut coords);
        if !same && with_gradient {
            scratch.state.clone_from(&current.state);
            target.evaluate_with_grad(&mut scratch.state, &mut scratch.payload, &mut self.gradient);
            params.truncate(&mut self.gradient);
            self.log_density_bits = bits;
            self.valid = true;
        } else if !same {
            self.gradient.clear();
            self.log_density_bits = bits;
            self.valid = true;
        } else if with_gradient && self.gradient.len() != self.coords.len() {
            scratch.state.clone_from(&current.state);
            target.evaluate_with_grad(&mut scratch.state, &mut scratch.payload, &mut self.gradient);
            params.truncate(&mut self.gradient);
        }
    }
}

/// The Metropolis-adjusted Langevin algorithm with adaptation (Luan et al. 2020, Alg. 1):
/// with probability `p_large` a large
/// step (any [`Proposal`], e.g. an independent uniform sample), with probability
/// `p_fallback` a plain fallback step (any proposal, e.g. an isotropic Gaussian that escapes
/// states where the gradient misleads), otherwise a MALA step from the [`Adaptation`]'s
/// Gaussian `N(u + Sigma m / 2, Sigma)`.
///
/// MALA's Hastings term needs the gradient at the candidate, which exists only once the
/// candidate is evaluated, so this is a kernel, not a [`Proposal`]: a MALA step evaluates the
/// candidate *with* its gradient ([`DifferentiableTarget::evaluate_with_grad`]), forms the
/// reverse Gaussian there under the same adaptation state, and decides. The current state's
/// gradient is cached with it (never recomputed while the chain stays); states reached by a
/// large or fallback step are evaluated without gradient, and their gradient is computed the
/// first time a MALA step starts from them.
///
/// The acceptance is component-labelled like [`crate::Mh`] over a [`crate::Mixture`]: the
/// selection probabilities do not depend on the state, so each component's ratio is its own
/// MH ratio. After a MALA step the adaptation advances with the gradient at the state the
/// step started from ([`Adaptation::adapt`]), unless frozen.
///
/// # Random numbers
/// Per step: one uniform for the component, then the component's (MALA: one standard normal
/// per coordinate), then one uniform for the decision (only when `0 < a < 1`).
///
/// # Example
/// ```
/// use mcmc_core::langevin::{Langevin, LangevinParams, Online};
/// use mcmc_core::toy::Ridge;
/// use mcmc_core::{Chain, Euclidean, NoAdaptation};
/// use rand::SeedableRng;
///
/// let target = Ridge::thin();
/// let params = LangevinParams { epsilon: 0.0025, ..LangevinParams::luan2020() };
/// let kernel = Langevin::new(params, Online::new(true), Euclidean).unwrap();
/// let rng = rand_pcg::Pcg64::seed_from_u64(1);
/// let mut chain = Chain::new(&target, kernel, NoAdaptation, rng, vec![0.0, 0.0]).unwrap();
/// chain.run(2000, &mut ()).unwrap();
/// assert!(chain.stats().acceptance_rate() > 0.2);
/// ```
#[derive(Clone, Debug)]
pub struct Langevin<A, Sp, L = NoMove, F = NoMove> {
    params: LangevinParams,
    /// The adaptation (its state `theta`).
    pub adaptation: A,
    /// The geometry of the moved coordinates.
    pub space: Sp,
    /// The large step (selected with probability [`Langevin::large_step_probability`]).
    pub large_step: L,
    p_large: f64,
    /// The fallback step (selected with probability [`Langevin::fallback_probability`]).
    pub fallback: F,
    p_fallback: f64,
    current: CurrentGradient,
    grad_y: Vec<f64>,
    coords_y: Vec<f64>,
    offset: Vec<f64>,
    forward: ProposalGaussian,
    reverse: ProposalGaussian,
}

impl<A: Adaptation, Sp> Langevin<A, Sp, NoMove, NoMove> {
    /// MALA steps only.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] if `params` is out of range.
    pub fn new(params: LangevinParams, adaptation: A, space: Sp) -> Result<Self, McmcError> {
        params.validate()?;
        Ok(Self {
            params,
            adaptation,
            space,
            large_step: NoMove,
            p_large: 0.0,
            fallback: NoMove,
            p_fallback: 0.0,
            current: CurrentGradient::default(),
            grad_y: Vec::new(),
            coords_y: Vec::new(),
            offset: Vec::new(),
            forward: ProposalGaussian::default(),
            reverse: ProposalGaussian::default(),
        })
    }
}

impl<A, Sp, L, F> Langevin<A, Sp, L, F> {
    /// Mixes in a large step selected with probability `p` (Alg. 1's `pi_global`).
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] unless `0 <= p` and `p + p_fallback <= 1`.
    pub fn with_large_step<L2>(
        self,
        large_step: L2,
        p: f64,
    ) -> Result<Langevin<A, Sp, L2, F>, McmcError> {
        McmcError::check_range(
            "large-step probability",
            p,
            0.0,
            1.0 - self.p_fallback,
            "[0, 1 - fallback probability]",
        )?;
        Ok(Langevin {
            params: self.params,
            adaptation: self.adaptation,
            space: self.space,
            large_step,
            p_large: p,
            fallback: self.fallback,
            p_fallback: self.p_fallback,
            current: self.current,
            grad_y: self.grad_y,
            coords_y: self.coords_y,
            offset: self.offset,
            forward: self.forward,
            reverse: self.reverse,
        })
    }

    /// Mixes in a fallback step selected with probability `p` (the authors' code: an
    /// isotropic Gaussian with probability 0.1).
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] unless `0 <= p` and `p + p_large <= 1`.
    pub fn with_fallback<F2>(
        self,
        fallback: F2,
        p: f64,
    ) -> Result<Langevin<A, Sp, L, F2>, McmcError> {
        McmcError::check_range(
            "fallback probability",
            p,
            0.0,
            1.0 - self.p_large,
            "[0, 1 - large-step probability]",
        )?;
        Ok(Langevin {
            params: self.params,
            adaptation: self.adaptation,
            space: self.space,
            large_step: self.large_step,
            p_large: self.p_large,
            fallback,
            p_fallback: p,
            current: self.current,
            grad_y: self.grad_y,
            coords_y: self.coords_y,
            offset: self.offset,
            forward: self.forward,
            reverse: self.reverse,
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &LangevinParams {
        &self.params
    }

    /// The probability of a fallback step.
    #[must_use]
    pub fn fallback_probability(&self) -> f64 {
        self.p_fallback
    }

    /// The probability of a MALA step.
    #[must_use]
    pub fn mala_probability(&self) -> f64 {
        1.0 - self.p_large - self.p_fallback
    }

    /// Freezes the adaptation (its state no longer changes): the kernel is then a fixed
    /// MH kernel, which is what the harness checks.
    pub fn freeze(&mut self)
    where
        A: Adaptation,
    {
        self.adaptation.freeze();
    }
}

impl<A, Sp, L, F> Langevin<A, Sp, L, F>
where
    A: Adaptation,
{
    /// `log T(from -> to)` of the MALA component under the current adaptation state, for
    /// evaluated states with their truncated gradients (tests and `log_flow`).
    pub fn log_mala_density<S>(&self, from: &S, grad_from: &[f64], to: &S) -> f64
    where
        Sp: LangevinSpace<S>,
    {
        let mut adaptation = self.adaptation.clone();
        self.log_mala_density_with(&mut adaptation, from, grad_from, to)
    }

    /// As [`Langevin::log_mala_density`], forming the Gaussian with `adaptation` (the kernel
    /// forms the forward Gaussian, then the reverse one, with the same object; `log_flow`
    /// does the same, so that an adaptation whose reverse differs is seen by the pairwise
    /// check).
    fn log_mala_density_with<S>(
        &self,
        adaptation: &mut A,
        from: &S,
        grad_from: &[f64],
        to: &S,
    ) -> f64
    where
        Sp: LangevinSpace<S>,
    {
        if !self.space.same_layout(from, to) || !self.space.same_slice(from, to) {
            return f64::NEG_INFINITY;
        }
        let (mut u, mut v) = (Vec::new(), Vec::new());
        self.space.read(from, &mut u);
        self.space.read(to, &mut v);
        if u.len() != v.len() {
            return f64::NEG_INFINITY;
        }
        let mut q = ProposalGaussian::default();
        adaptation.gaussian(&self.params, &u, grad_from, &mut q);
        self.space.log_q(&q, &u, &v)
    }
}

fn gradient_of<T: DifferentiableTarget>(
    target: &T,
    x: &SampleOf<T>,
    params: &LangevinParams,
) -> Vec<f64> {
    let mut state = x.state.clone();
    let mut payload = T::Payload::default();
    let mut g = Vec::new();
    target.evaluate_with_grad(&mut state, &mut payload, &mut g);
    params.truncate(&mut g);
    g
}

impl<T, A, Sp, L, F> Kernel<T> for Langevin<A, Sp, L, F>
where
    T: DifferentiableTarget,
    A: Adaptation,
    Sp: LangevinSpace<T::State>,
    L: Proposal<T::State>,
    F: Proposal<T::State>,
{
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
        let [y, spare, ..] = scratch else {
            panic!("Langevin needs two scratch samples (the chain provides Kernel::stages() + 1)");
        };
        let r: f64 = if self.p_large + self.p_fallback > 0.0 {
            rng.random()
        } else {
            1.0
        };
        if r < self.p_large + self.p_fallback {
            let (proposed, component) = if r < self.p_large {
                (
                    self.large_step.propose(&current.state, &mut y.state, rng),
                    LARGE_STEP_COMPONENT,
                )
            } else {
                (
                    self.fallback.propose(&current.state, &mut y.state, rng),
                    FALLBACK_COMPONENT,
                )
            };
            let info = mh_decide(
                target,
                current,
                y,
                proposed.with_component(component),
                |h| h,
                rng,
                observer,
            );
            if info.accepted() {
                self.current.invalidate();
                if component == LARGE_STEP_COMPONENT {
                    self.adaptation.restart(&self.params);
                }
            }
            return info;
        }

        // MALA step from x with the cached gradient.
        self.space.read(&current.state, &mut self.coords_y);
        let needs_gradient = self.adaptation.needs_gradient(self.coords_y.len());
        self.current.ensure(
            target,
            &self.space,
            &self.params,
            current,
            spare,
            needs_gradient,
        );
        let mut info = StepInfo::new(MALA_COMPONENT);
        info.stages_tried = 1;
        let ux = &self.current.coords;
        let gx: &[f64] = if needs_gradient {
            &self.current.gradient
        } else {
            &[]
        };
        self.adaptation
            .gaussian(&self.params, ux, gx, &mut self.forward);
        self.forward.sample(rng, &mut self.offset);
        for (o, &u) in self.offset.iter_mut().zip(ux) {
            *o += u;
        }
        let mut a = 0.0;
        let valid = self.space.write(&current.state, &self.offset, &mut y.state);
        if valid {
            y.log_density = if needs_gradient {
                let ld = target.evaluate_with_grad(&mut y.state, &mut y.payload, &mut self.grad_y);
                self.params.truncate(&mut self.grad_y);
                ld
            } else {
                self.grad_y.clear();
                target.evaluate(&mut y.state, &mut y.payload)
            };
            info.candidate_log_density[0] = y.log_density;
            if y.log_density.is_nan() || y.log_density == f64::INFINITY {
                info.non_finite = true;
            } else if y.log_density > f64::NEG_INFINITY {
                self.space.read(&y.state, &mut self.coords_y);
                if self.coords_y.len() == ux.len()
                    && self.space.same_layout(&current.state, &y.state)
                {
                    self.adaptation.gaussian(
                        &self.params,
                        &self.coords_y,
                        &self.grad_y,
                        &mut self.reverse,
                    );
                    let log_fwd = self.space.log_q(&self.forward, ux, &self.coords_y);
                    let log_rev = self.space.log_q(&self.reverse, &self.coords_y, ux);
                    let h = log_rev - log_fwd;
                    if h.is_nan() {
                        info.non_finite = true;
                    } else {
                        a = mh_accept_prob(current.log_density, y.log_density, h);
                    }
                }
            }
        }
        info.accept_prob[0] = a;
        observer.splat(current, 1.0 - a);
        if a > 0.0 {
            observer.splat(y, a);
        }
        let accept = a >= 1.0 || (a > 0.0 && rng.random::<f64>() < a);
        // theta_{t+1}: fold in the gradient at the state the step started from.
        if !self.adaptation.is_frozen() {
            let first = !self.current.visited;
            self.adaptation.adapt(
                &self.params,
                &self.current.coords,
                gx_owned(needs_gradient, &self.current.gradient),
                first,
            );
        }
        self.current.visited = true;
        if accept {
            std::mem::swap(current, y);
            info.accepted_stage = 1;
            std::mem::swap(&mut self.current.coords, &mut self.coords_y);
            std::mem::swap(&mut self.current.gradient, &mut self.grad_y);
            self.current.accepted(current.log_density, needs_gradient);
        } else if valid {
            current.state.absorb_rejected(&y.state);
        }
        observer.step(&info);
        info
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        let [x, y] = path else {
            return f64::NEG_INFINITY;
        };
        let mut terms = Vec::new();
        let mut add_proposal = |p_sel: f64, log_q: f64, h: f64| {
            if p_sel > 0.0 {
                terms.push(
                    p_sel.ln()
                        + x.log_density
                        + log_q
                        + mh_log_accept_prob(x.log_density, y.log_density, h),
                );
            }
        };
        for j in 0..self.large_step.num_components() {
            let q = self.large_step.log_q_component(j, &x.state, &y.state);
            let h = self.large_step.log_hastings(j, &x.state, &y.state);
            add_proposal(self.p_large, q, h);
        }
        for j in 0..self.fallback.num_components() {
            let q = self.fallback.log_q_component(j, &x.state, &y.state);
            let h = self.fallback.log_hastings(j, &x.state, &y.state);
            add_proposal(self.p_fallback, q, h);
        }
        let p_mala = self.mala_probability();
        if p_mala > 0.0 {
            let gx = gradient_of(target, x, &self.params);
            let gy = gradient_of(target, y, &self.params);
            let mut adaptation = self.adaptation.clone();
            let fwd = self.log_mala_density_with(&mut adaptation, &x.state, &gx, &y.state);
            let rev = self.log_mala_density_with(&mut adaptation, &y.state, &gy, &x.state);
            terms.push(
                p_mala.ln()
                    + x.log_density
                    + fwd
                    + mh_log_accept_prob(x.log_density, y.log_density, rev - fwd),
            );
        }
        log_sum_exp(&terms)
    }
}

/// The gradient slice to adapt with (empty when the adaptation did not need it).
fn gx_owned(needs_gradient: bool, gradient: &[f64]) -> &[f64] {
    if needs_gradient {
        gradient
    } else {
        &[]
    }
}

impl CurrentGradient {
    /// After an accepted MALA step the candidate's coordinates and gradient (swapped in by
    /// the kernel) describe the new current state.
    pub(crate) fn accepted(&mut self, log_density: f64, has_gradient: bool) {
        self.log_density_bits = log_density.to_bits();
        self.valid = true;
        if !has_gradient {
            self.gradient.clear();
        }
        self.visited = false;
    }
}

impl<A, Sp, L, F> LargeStepTunable for Langevin<A, Sp, L, F> {
    fn large_step_probability(&self) -> f64 {
        self.p_large
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.p_large = p.clamp(0.0, 1.0 - self.p_fallback);
    }
    fn is_large_step(&self, component: usize) -> bool {
        component == LARGE_STEP_COMPONENT
    }
}

/// A kernel whose adaptation may own gradient caches (for [`super::CacheSharing`]).
pub trait HasGradientCache {
    /// Calls `f` on every gradient cache of the kernel.
    fn for_each_gradient_cache(&mut self, f: &mut dyn FnMut(&mut super::CacheView));
}

impl<A: Adaptation, Sp, L, F> HasGradientCache for Langevin<A, Sp, L, F> {
    fn for_each_gradient_cache(&mut self, f: &mut dyn FnMut(&mut super::CacheView)) {
        self.adaptation.for_each_cache(f);
    }
}

// `Point` is used in doc links and bounds of the kernel impl through `SampleOf`.
#[allow(unused_imports)]
use Point as _;
