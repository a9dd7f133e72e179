//! Delayed rejection "cheap then expensive": an isotropic Gaussian first stage, a MALA second
//! stage, Green & Mira's acceptance (DR paper, section 5.2).

use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};

use super::adaptation::Adaptation;
use super::gaussian::ProposalGaussian;
use super::kernel::{CurrentGradient, NoMove, LARGE_STEP_COMPONENT};
use super::params::LangevinParams;
use super::space::LangevinSpace;
use crate::delayed_rejection::rule::{ln_accept_from_ratio, ln_one_minus};
use crate::kernel::{mh_accept_prob, mh_log_accept_prob, Kernel, Observer, StepInfo};
use crate::mh::mh_decide;
use crate::proposal::{log_sum_exp, Proposal};
use crate::target::{DifferentiableTarget, Point, Sample, SampleOf};
use crate::tunable::LargeStepTunable;
use crate::McmcError;

/// Two-stage delayed rejection whose first stage is *cheap* — an isotropic Gaussian random
/// walk of standard deviation `sigma1`, evaluated without gradient — and whose second stage
/// is *expensive* — a MALA step from the current state with the [`Adaptation`]'s Gaussian,
/// its candidate evaluated with gradient — under Green & Mira's rule (DR paper, section 5.2,
/// which used H2MC for the second stage; eq. 12-14; docs/methods/mala.md).
///
/// After a rejected `y`, `z ~ N(x + Sigma(x) m(x) / 2, Sigma(x))` and the ghost is
/// `y* = z - (y - x)` (wrapped on a torus). Because the first stage is a symmetric walk and
/// `y* - z = x - y`, its densities cancel and
/// `a2 = min(1, pi(z) (1 - a1(z, y*)) T(z -> x) / (pi(x) (1 - a1(x, y)) T(x -> z)))`, with
/// `T` the MALA density under the same adaptation state (the reverse Gaussian at `z` uses
/// `g(z)`). The gradient is evaluated only at second-stage candidates and cached for the
/// current state; `y` and `y*` cost one plain evaluation each.
///
/// # Read sets
/// Both stages move the coordinates the current state's evaluation read
/// ([`LangevinSpace::read`]), and both reject a candidate whose evaluation read a different
/// set ([`LangevinSpace::same_layout`]): the first stage in `a1(x, y)` and in the reverse
/// `a1(z, y*)`, the second stage in `a2`. The kernel is then exact on each set of states with
/// one read set, as MALA is (docs/methods/mala.md, "Read sets"); a first stage that accepted
/// a change of read set would pair a walk in one dimension with its reverse in another.
///
/// Splatting is the unbiased three-point scheme of [`crate::DelayedRejection`]; large steps
/// (component 1, probability `p_large`) never run a second stage. The adaptation advances
/// after each step whose second stage ran, with the gradient at `x`.
///
/// # Example
/// ```
/// use mcmc_core::langevin::{CheapThenExpensive, LangevinParams, Plain};
/// use mcmc_core::toy::Ridge;
/// use mcmc_core::{Chain, Euclidean, NoAdaptation};
/// use rand::SeedableRng;
///
/// let params = LangevinParams { epsilon: 0.002, ..LangevinParams::luan2020() };
/// let kernel = CheapThenExpensive::new(params, 0.5, Plain, Euclidean).unwrap();
/// let target = Ridge::thin();
/// let mut chain = Chain::new(&target, kernel, NoAdaptation, rand_pcg::Pcg64::seed_from_u64(3), vec![0.0, 0.0]).unwrap();
/// chain.run(2000, &mut ()).unwrap();
/// assert!(chain.stats().stage_accepted[1] > 0);
/// ```
#[derive(Clone, Debug)]
pub struct CheapThenExpensive<A, Sp, L = NoMove> {
    params: LangevinParams,
    sigma1: f64,
    /// The second stage's adaptation.
    pub adaptation: A,
    /// The geometry of the moved coordinates.
    pub space: Sp,
    /// The large step.
    pub large_step: L,
    p_large: f64,
    current: CurrentGradient,
    coords: [Vec<f64>; 3],
    grad_z: Vec<f64>,
    forward: ProposalGaussian,
    reverse: ProposalGaussian,
}

impl<A: Adaptation, Sp> CheapThenExpensive<A, Sp, NoMove> {
    /// A kernel with first-stage standard deviation `sigma1`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] if `sigma1` is not positive and finite or `params` is
    /// out of range.
    pub fn new(
        params: LangevinParams,
        sigma1: f64,
        adaptation: A,
        space: Sp,
    ) -> Result<Self, McmcError> {
        params.validate()?;
        McmcError::check_range("sigma1", sigma1, 1e-12, 1e6, "(0, 1e6]")?;
        Ok(Self {
            params,
            sigma1,
            adaptation,
            space,
            large_step: NoMove,
            p_large: 0.0,
            current: CurrentGradient::default(),
            coords: Default::default(),
            grad_z: Vec::new(),
            forward: ProposalGaussian::default(),
            reverse: ProposalGaussian::default(),
        })
    }
}

impl<A, Sp, L> CheapThenExpensive<A, Sp, L> {
    /// Mixes in a large step with probability `p`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] unless `p` is in `[0, 1]`.
    pub fn with_large_step<L2>(
        self,
        large_step: L2,
        p: f64,
    ) -> Result<CheapThenExpensive<A, Sp, L2>, McmcError> {
        McmcError::check_range("large-step probability", p, 0.0, 1.0, "[0, 1]")?;
        Ok(CheapThenExpensive {
            params: self.params,
            sigma1: self.sigma1,
            adaptation: self.adaptation,
            space: self.space,
            large_step,
            p_large: p,
            current: self.current,
            coords: self.coords,
            grad_z: self.grad_z,
            forward: self.forward,
            reverse: self.reverse,
        })
    }

    /// The first stage's standard deviation.
    #[must_use]
    pub fn sigma1(&self) -> f64 {
        self.sigma1
    }

    /// Log density of the first stage's isotropic Gaussian for the move `from -> to`.
    fn log_q1<S>(&self, from: &S, to: &S) -> f64
    where
        Sp: LangevinSpace<S>,
    {
        if !self.space.same_slice(from, to) {
            return f64::NEG_INFINITY;
        }
        let (mut u, mut v) = (Vec::new(), Vec::new());
        self.space.read(from, &mut u);
        self.space.read(to, &mut v);
        let mut q = ProposalGaussian::default();
        isotropic(&self.params, self.sigma1, u.len(), &mut q);
        self.space.log_q(&q, &u, &v)
    }
}

/// The isotropic `N(0, sigma^2 I)` as a [`ProposalGaussian`].
fn isotropic(params: &LangevinParams, sigma: f64, d: usize, out: &mut ProposalGaussian) {
    let p = LangevinParams {
        epsilon: sigma * sigma,
        preconditioner_range: [0.0, f64::INFINITY],
        max_std: f64::INFINITY,
        ..*params
    };
    let ones = vec![1.0; d];
    let zeros = vec![0.0; d];
    out.set_diagonal(&p, &ones, &zeros);
}

/// The first stage's acceptance probability for the evaluated move `x -> y`: the MH
/// ratio of the symmetric walk, and 0 when `y`'s evaluation read a different set of
/// coordinates than `x`'s ([`LangevinSpace::same_layout`]). The walk moves exactly the
/// coordinates `x` read, so a move that changes the read set has no reverse move of the
/// same kind: accepting it would break detailed balance, as for MALA (docs/methods/mala.md,
/// "Read sets"). Both stages are thus exact on each set of states with one read set.
fn first_stage_accept<S, Sp: LangevinSpace<S>>(space: &Sp, x: (&S, f64), y: (&S, f64)) -> f64 {
    if space.same_layout(x.0, y.0) {
        mh_accept_prob(x.1, y.1, 0.0)
    } else {
        0.0
    }
}

fn non_finite(ld: f64) -> bool {
    ld.is_nan() || ld == f64::INFINITY
}

impl<A: Adaptation, Sp, L> CheapThenExpensive<A, Sp, L> {
    /// `ln a2` for evaluated `x, y, z, y*` with the gradients at `x` and `z`.
    #[allow(clippy::too_many_arguments)]
    fn ln_a2<S>(
        &self,
        adaptation: &mut A,
        x: (&S, f64, &[f64]),
        z: (&S, f64, &[f64]),
        ystar: (&S, f64),
        ln_one_minus_a1: f64,
        fwd: &mut ProposalGaussian,
        rev: &mut ProposalGaussian,
    ) -> f64
    where
        Sp: LangevinSpace<S>,
    {
        if z.1 == f64::NEG_INFINITY {
            return f64::NEG_INFINITY;
        }
        let (mut u, mut v) = (Vec::new(), Vec::new());
        self.space.read(x.0, &mut u);
        self.space.read(z.0, &mut v);
        if u.len() != v.len() {
            return f64::NEG_INFINITY;
        }
        adaptation.gaussian(&self.params, &u, x.2, fwd);
        adaptation.gaussian(&self.params, &v, z.2, rev);
        let a1_rev = first_stage_accept(&self.space, (z.0, z.1), ystar);
        let num = z.1 + ln_one_minus(a1_rev) + self.space.log_q(rev, &v, &u);
        let den = x.1 + ln_one_minus_a1 + self.space.log_q(fwd, &u, &v);
        ln_accept_from_ratio(num, den)
    }

    fn ghost_of<S: Point>(&self, x: &S, y: &S, z: &S) -> Option<S>
    where
        Sp: LangevinSpace<S>,
    {
        let (mut a, mut b, mut c, mut g) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        self.space.read(x, &mut a);
        self.space.read(y, &mut b);
        self.space.read(z, &mut c);
        self.space.ghost(&a, &b, &c, &mut g);
        let mut out = z.clone();
        self.space.write(z, &g, &mut out).then_some(out)
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

impl<T, A, Sp, L> Kernel<T> for CheapThenExpensive<A, Sp, L>
where
    T: DifferentiableTarget,
    A: Adaptation,
    Sp: LangevinSpace<T::State>,
    L: Proposal<T::State>,
{
    fn stages(&self) -> usize {
        2
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
        let [y, z, ghost, ..] = scratch else {
            panic!("CheapThenExpensive needs three scratch samples (Kernel::stages() + 1)");
        };
        if self.p_large > 0.0 && rng.random::<f64>() < self.p_large {
            let proposed = self.large_step.propose(&current.state, &mut y.state, rng);
            let info = mh_decide(
                target,
                current,
                y,
                proposed.with_component(LARGE_STEP_COMPONENT),
                |h| h,
                rng,
                observer,
            );
            if info.accepted() {
                self.current.invalidate();
            }
            return info;
        }

        // Stage 1: symmetric isotropic walk, plain evaluation.
        let [cx, cy, cz] = &mut self.coords;
        self.space.read(&current.state, cx);
        cy.clear();
        cy.extend(cx.iter().map(|&u| {
            let w: f64 = StandardNormal.sample(rng);
            u + self.sigma1 * w
        }));
        let mut info = StepInfo::new(0);
        info.stages_tried = 1;
        let mut a1 = 0.0;
        let y_valid = self.space.write(&current.state, cy, &mut y.state);
        if y_valid {
            y.log_density = target.evaluate(&mut y.state, &mut y.payload);
            info.candidate_log_density[0] = y.log_density;
            if non_finite(y.log_density) {
                info.non_finite = true;
            } else {
                a1 = first_stage_accept(
                    &self.space,
                    (&current.state, current.log_density),
                    (&y.state, y.log_density),
                );
            }
        }
        info.accept_prob[0] = a1;
        if a1 > 0.0 {
            observer.splat(y, a1);
        }
        if !y_valid || info.non_finite || a1 >= 1.0 {
            observer.splat(current, 1.0 - a1);
            if a1 >= 1.0 {
                std::mem::swap(current, y);
                info.accepted_stage = 1;
                self.current.invalidate();
            }
            observer.step(&info);
            return info;
        }
        if a1 > 0.0 && rng.random::<f64>() < a1 {
            std::mem::swap(current, y);
            info.accepted_stage = 1;
            self.current.invalidate();
            observer.step(&info);
            return info;
        }
        current.state.absorb_rejected(&y.state);

        // Stage 2: MALA from x (gradient cached), z evaluated with gradient.
        info.stages_tried = 2;
        self.space.read(&current.state, cx);
        let needs_gradient = self.adaptation.needs_gradient(cx.len());
        self.current.ensure(
            target,
            &self.space,
            &self.params,
            current,
            ghost,
            needs_gradient,
        );
        let gx: &[f64] = if needs_gradient {
            &self.current.gradient
        } else {
            &[]
        };
        self.adaptation
            .gaussian(&self.params, &self.current.coords, gx, &mut self.forward);
        self.forward.sample(rng, cz);
        for (o, &u) in cz.iter_mut().zip(&self.current.coords) {
            *o += u;
        }
        let mut a2 = 0.0;
        let z_valid = self.space.write(&current.state, cz, &mut z.state);
        let mut ghost_evaluated = false;
        if z_valid {
            z.log_density = if needs_gradient {
                let ld = target.evaluate_with_grad(&mut z.state, &mut z.payload, &mut self.grad_z);
                self.params.truncate(&mut self.grad_z);
                ld
            } else {
                self.grad_z.clear();
                target.evaluate(&mut z.state, &mut z.payload)
            };
            info.candidate_log_density[1] = z.log_density;
            if non_finite(z.log_density) {
                info.non_finite = true;
            } else if z.log_density > f64::NEG_INFINITY {
                // Ghost y* = z - (y - x), from the coordinates as the states hold them.
                self.space.read(&y.state, cy);
                self.space.read(&z.state, cz);
                let mut g = std::mem::take(cx);
                self.space.ghost(&self.current.coords, cy, cz, &mut g);
                let ghost_valid = self.space.write(&z.state, &g, &mut ghost.state);
                *cx = g;
                if ghost_valid {
                    ghost.log_density = target.evaluate(&mut ghost.state, &mut ghost.payload);
                    ghost_evaluated = true;
                    if non_finite(ghost.log_density) {
                        info.non_finite = true;
                    } else if cz.len() == self.current.coords.len()
                        && self.space.same_layout(&current.state, &z.state)
                    {
                        self.adaptation
                            .gaussian(&self.params, cz, &self.grad_z, &mut self.reverse);
                        let a1_rev = first_stage_accept(
                            &self.space,
                            (&z.state, z.log_density),
                            (&ghost.state, ghost.log_density),
                        );
                        let num = z.log_density
                            + ln_one_minus(a1_rev)
                            + self.space.log_q(&self.reverse, cz, &self.current.coords);
                        let den = current.log_density
                            + ln_one_minus(a1)
                            + self.space.log_q(&self.forward, &self.current.coords, cz);
                        let ln_a2 = ln_accept_from_ratio(num, den);
                        if ln_a2.is_nan() {
                            info.non_finite = true;
                        } else {
                            a2 = ln_a2.exp();
                        }
                    }
                }
            }
        }
        info.accept_prob[1] = a2;
        if a2 > 0.0 {
            observer.splat_at_stage(z, a2, 2);
        }
        observer.splat(current, 1.0 - a2);
        let accept = a2 >= 1.0 || (a2 > 0.0 && rng.random::<f64>() < a2);
        if !self.adaptation.is_frozen() {
            let first = !self.current.visited;
            let g: &[f64] = if needs_gradient {
                &self.current.gradient
            } else {
                &[]
            };
            self.adaptation
                .adapt(&self.params, &self.current.coords, g, first);
        }
        self.current.visited = true;
        if accept {
            std::mem::swap(current, z);
            info.accepted_stage = 2;
            std::mem::swap(&mut self.current.coords, cz);
            std::mem::swap(&mut self.current.gradient, &mut self.grad_z);
            self.current.accepted(current.log_density, needs_gradient);
        } else if z_valid {
            current.state.absorb_rejected(&z.state);
        }
        if ghost_evaluated {
            current.state.absorb_rejected(&ghost.state);
        }
        observer.step(&info);
        info
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        let p_local = 1.0 - self.p_large;
        match path {
            [x, y] => {
                let mut terms = vec![];
                if p_local > 0.0 && self.space.same_layout(&x.state, &y.state) {
                    terms.push(
                        p_local.ln()
                            + x.log_density
                            + self.log_q1(&x.state, &y.state)
                            + mh_log_accept_prob(x.log_density, y.log_density, 0.0),
                    );
                }
                if self.p_large > 0.0 {
                    for j in 0..self.large_step.num_components() {
                        let h = self.large_step.log_hastings(j, &x.state, &y.state);
                        terms.push(
                            self.p_large.ln()
                                + x.log_density
                                + self.large_step.log_q_component(j, &x.state, &y.state)
                                + mh_log_accept_prob(x.log_density, y.log_density, h),
                        );
                    }
                }
                log_sum_exp(&terms)
            }
            [x, y, z] => {
                if p_local <= 0.0
                    || x.log_density == f64::NEG_INFINITY
                    || !self.space.same_layout(&x.state, &z.state)
                    || !self.space.same_slice(&x.state, &z.state)
                {
                    return f64::NEG_INFINITY;
                }
                let Some(ghost) = self.ghost_of(&x.state, &y.state, &z.state) else {
                    return f64::NEG_INFINITY;
                };
                let ghost = Sample::evaluate(target, ghost);
                let gx = gradient_of(target, x, &self.params);
                let gz = gradient_of(target, z, &self.params);
                let ln_one_minus_a1 = ln_one_minus(first_stage_accept(
                    &self.space,
                    (&x.state, x.log_density),
                    (&y.state, y.log_density),
                ));
                let mut adaptation = self.adaptation.clone();
                let (mut f, mut r) = (ProposalGaussian::default(), ProposalGaussian::default());
                let ln_a2 = self.ln_a2(
                    &mut adaptation,
                    (&x.state, x.log_density, &gx),
                    (&z.state, z.log_density, &gz),
                    (&ghost.state, ghost.log_density),
                    ln_one_minus_a1,
                    &mut f,
                    &mut r,
                );
                let (mut u, mut v) = (Vec::new(), Vec::new());
                self.space.read(&x.state, &mut u);
                self.space.read(&z.state, &mut v);
                let log_q2 = self.space.log_q(&f, &u, &v);
                p_local.ln()
                    + x.log_density
                    + self.log_q1(&x.state, &y.state)
                    + ln_one_minus_a1
                    + log_q2
                    + ln_a2
            }
            _ => f64::NEG_INFINITY,
        }
    }

    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        match path {
            [x, y, z] => match self.ghost_of(&x.state, &y.state, &z.state) {
                Some(g) => vec![z.clone(), Sample::evaluate(target, g), x.clone()],
                None => path.iter().rev().cloned().collect(),
            },
            _ => path.iter().rev().cloned().collect(),
        }
    }
}

impl<A, Sp, L> LargeStepTunable for CheapThenExpensive<A, Sp, L> {
    fn large_step_probability(&self) -> f64 {
        self.p_large
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.p_large = p.clamp(0.0, 1.0);
    }
    fn is_large_step(&self, component: usize) -> bool {
        component == LARGE_STEP_COMPONENT
    }
}

impl<A: Adaptation, Sp, L> super::HasGradientCache for CheapThenExpensive<A, Sp, L> {
    fn for_each_gradient_cache(&mut self, f: &mut dyn FnMut(&mut super::CacheView)) {
        self.adaptation.for_each_cache(f);
    }
}
