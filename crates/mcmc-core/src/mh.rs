//! The Metropolis-Hastings kernel with general (asymmetric) proposals.

use rand::{Rng, RngExt};

use crate::kernel::{mh_accept_prob, mh_log_accept_prob, Kernel, Observer, StepInfo};
use crate::proposal::{log_sum_exp, Proposal, Proposed};
use crate::target::{Point, SampleOf, Target};
use crate::tunable::{HasSharedScales, LargeStepTunable, RegionalTunable, ScaleTunable};

/// Metropolis-Hastings (Metropolis et al. 1953; Hastings 1970; DR paper eq. 3):
/// propose `y ~ q(. | x)` and accept with `a = min(1, pi(y) q(y->x) / (pi(x) q(x->y)))`.
///
/// For symmetric proposals the Hastings term is 0 and never computed. A candidate with zero
/// density is never accepted; an invalid candidate is rejected without evaluating the target;
/// a NaN density or Hastings term is rejected and flagged (`StepInfo::non_finite`), and the
/// [`crate::Chain`] turns it into an error.
///
/// After a rejection the kernel calls [`crate::Point::absorb_rejected`] on the current state
/// (lazily materialised states keep what the candidate's evaluation drew of them).
///
/// Random numbers per step, in order: the proposal's, then one uniform for the decision
/// (drawn only when `0 < a < 1`).
#[derive(Clone, Debug)]
pub struct Mh<P> {
    /// The proposal.
    pub proposal: P,
}

/// The decision half of an MH step, once `y` holds the candidate `proposed` describes:
/// evaluate it, compute `a` with the Hastings term mapped by `hastings` (the identity for
/// [`Mh`]; negative controls in `testing` drop it), report to the observer, accept or reject.
pub(crate) fn mh_decide<T, R, O>(
    target: &T,
    current: &mut SampleOf<T>,
    y: &mut SampleOf<T>,
    proposed: Proposed,
    hastings: impl Fn(f64) -> f64,
    rng: &mut R,
    observer: &mut O,
) -> StepInfo
where
    T: Target,
    R: Rng + ?Sized,
    O: Observer<T::State, T::Payload> + ?Sized,
{
    let mut info = StepInfo::new(proposed.component());
    info.stages_tried = 1;
    let a = match proposed {
        Proposed::Invalid { .. } => 0.0,
        Proposed::Move { log_hastings, .. } => {
            y.log_density = target.evaluate(&mut y.state, &mut y.payload);
            info.candidate_log_density[0] = y.log_density;
            if y.log_density.is_nan() || y.log_density == f64::INFINITY || log_hastings.is_nan() {
                info.non_finite = true;
                0.0
            } else {
                mh_accept_prob(current.log_density, y.log_density, hastings(log_hastings))
            }
        }
    };
    info.accept_prob[0] = a;
    observer.splat(current, 1.0 - a);
    if a > 0.0 {
        observer.splat(y, a);
    }
    let accept = a >= 1.0 || (a > 0.0 && rng.random::<f64>() < a);
    if accept {
        std::mem::swap(current, y);
        info.accepted_stage = 1;
    } else if matches!(proposed, Proposed::Move { .. }) {
        current.state.absorb_rejected(&y.state);
    }
    observer.step(&info);
    info
}

impl<P> Mh<P> {
    /// An MH kernel with the given proposal.
    pub fn new(proposal: P) -> Self {
        Self { proposal }
    }
}

impl<T: Target, P: Proposal<T::State>> Kernel<T> for Mh<P> {
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
        mh_decide(
            target,
            current,
            &mut scratch[0],
            proposed,
            |h| h,
            rng,
            observer,
        )
    }

    fn log_flow(&self, _target: &T, path: &[SampleOf<T>]) -> f64 {
        let [x, y] = path else {
            return f64::NEG_INFINITY;
        };
        let n = self.proposal.num_components();
        let terms: Vec<f64> = (0..n)
            .map(|j| {
                let log_q = self.proposal.log_q_component(j, &x.state, &y.state);
                let h = self.proposal.log_hastings(j, &x.state, &y.state);
                x.log_density + log_q + mh_log_accept_prob(x.log_density, y.log_density, h)
            })
            .collect();
        log_sum_exp(&terms)
    }

    fn independent_density(&self, component: usize) -> Option<f64> {
        self.proposal.independent_density(component)
    }
}

impl<P: ScaleTunable> ScaleTunable for Mh<P> {
    fn log_scale(&self) -> f64 {
        self.proposal.log_scale()
    }
    fn set_log_scale(&mut self, lambda: f64) {
        self.proposal.set_log_scale(lambda);
    }
}

impl<S, P: RegionalTunable<S>> RegionalTunable<S> for Mh<P> {
    fn region_of(&self, x: &S) -> usize {
        self.proposal.region_of(x)
    }
    fn num_regions(&self) -> usize {
        self.proposal.num_regions()
    }
    fn log_scale_of(&self, region: usize) -> f64 {
        self.proposal.log_scale_of(region)
    }
    fn set_log_scale_of(&mut self, region: usize, lambda: f64) {
        self.proposal.set_log_scale_of(region, lambda);
    }
    fn split_region(&mut self, region: usize) -> Option<std::ops::Range<usize>> {
        self.proposal.split_region(region)
    }
}

impl<P: LargeStepTunable> LargeStepTunable for Mh<P> {
    fn large_step_probability(&self) -> f64 {
        self.proposal.large_step_probability()
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.proposal.set_large_step_probability(p);
    }
    fn is_large_step(&self, component: usize) -> bool {
        self.proposal.is_large_step(component)
    }
}

impl<P: HasSharedScales> HasSharedScales for Mh<P> {
    type Scales = P::Scales;
    fn shared_scales(&self) -> Option<&P::Scales> {
        self.proposal.shared_scales()
    }
    fn shared_scales_mut(&mut self) -> Option<&mut P::Scales> {
        self.proposal.shared_scales_mut()
    }
}
