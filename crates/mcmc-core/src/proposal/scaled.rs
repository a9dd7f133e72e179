//! Proposals whose size is a parameter, with a global or a per-region scale.

use rand::Rng;

use super::{Proposal, Proposed};
use crate::partition::Partition;
use crate::tunable::{RegionalTunable, ScaleTunable};

/// A proposal family indexed by a scale `lambda = log sigma^2` (regional-adaptive paper,
/// eq. 4): the thing adaptive controllers tune.
pub trait ScaledProposal<S> {
    /// Draws `y ~ T_lambda(. | x)`.
    fn propose_at_scale<R: Rng + ?Sized>(
        &self,
        lambda: f64,
        x: &S,
        y: &mut S,
        rng: &mut R,
    ) -> Proposed;
    /// `log T_lambda(from -> to)`.
    fn log_q_at_scale(&self, lambda: f64, from: &S, to: &S) -> f64;
}

/// A [`ScaledProposal`] at one global scale `lambda`, tunable by
/// [`crate::controller::GlobalScale`].
#[derive(Clone, Debug)]
pub struct Scaled<P> {
    /// The proposal family.
    pub inner: P,
    /// `lambda = log sigma^2`.
    pub lambda: f64,
}

impl<P> Scaled<P> {
    /// `inner` at scale `lambda = log sigma^2`.
    pub fn new(inner: P, lambda: f64) -> Self {
        Self { inner, lambda }
    }
}

impl<S, P: ScaledProposal<S>> Proposal<S> for Scaled<P> {
    fn propose<R: Rng + ?Sized>(&self, x: &S, y: &mut S, rng: &mut R) -> Proposed {
        match self.inner.propose_at_scale(self.lambda, x, y, rng) {
            Proposed::Move { .. } => Proposed::Move {
                log_hastings: self.inner.log_q_at_scale(self.lambda, y, x)
                    - self.inner.log_q_at_scale(self.lambda, x, y),
                component: 0,
            },
            invalid => invalid,
        }
    }

    fn log_q(&self, from: &S, to: &S) -> f64 {
        self.inner.log_q_at_scale(self.lambda, from, to)
    }
}

impl<P> ScaleTunable for Scaled<P> {
    fn log_scale(&self) -> f64 {
        self.lambda
    }
    fn set_log_scale(&mut self, lambda: f64) {
        self.lambda = lambda;
    }
}

/// A [`ScaledProposal`] whose scale depends on the region of the current state:
/// `y ~ T_{lambda_k(x)}(. | x)` with `k(x)` from a [`Partition`] (regional-adaptive paper,
/// section 4).
///
/// The reverse density uses the scale of the *proposed* state's region,
/// `T_{lambda_k(y)}(x | y)`, so the kernel is asymmetric across region borders and the
/// Hastings term accounts for it (the paper's pitfall 6 in our reference notes).
#[derive(Clone, Debug)]
pub struct Regional<P, Part> {
    /// The proposal family.
    pub inner: P,
    /// The partition of the state space into regions.
    pub partition: Part,
    lambdas: Vec<f64>,
}

impl<P, Part> Regional<P, Part> {
    /// `inner` with every region of `partition` at scale `lambda0`.
    pub fn new<S>(inner: P, partition: Part, lambda0: f64) -> Self
    where
        Part: Partition<S>,
    {
        let n = partition.num_regions();
        Self {
            inner,
            partition,
            lambdas: vec![lambda0; n],
        }
    }

    /// The per-region scales, indexed by region id.
    #[must_use]
    pub fn lambdas(&self) -> &[f64] {
        &self.lambdas
    }
}

impl<S, P: ScaledProposal<S>, Part: Partition<S>> Proposal<S> for Regional<P, Part> {
    fn propose<R: Rng + ?Sized>(&self, x: &S, y: &mut S, rng: &mut R) -> Proposed {
        let lx = self.lambdas[self.partition.region(x)];
        match self.inner.propose_at_scale(lx, x, y, rng) {
            Proposed::Move { .. } => {
                let ly = self.lambdas[self.partition.region(y)];
                Proposed::Move {
                    log_hastings: self.inner.log_q_at_scale(ly, y, x)
                        - self.inner.log_q_at_scale(lx, x, y),
                    component: 0,
                }
            }
            invalid => invalid,
        }
    }

    fn log_q(&self, from: &S, to: &S) -> f64 {
        self.inner
            .log_q_at_scale(self.lambdas[self.partition.region(from)], from, to)
    }
}

impl<S, P, Part: Partition<S>> RegionalTunable<S> for Regional<P, Part> {
    fn region_of(&self, x: &S) -> usize {
        self.partition.region(x)
    }
    fn num_regions(&self) -> usize {
        self.lambdas.len()
    }
    fn log_scale_of(&self, region: usize) -> f64 {
        self.lambdas[region]
    }
    fn set_log_scale_of(&mut self, region: usize, lambda: f64) {
        self.lambdas[region] = lambda;
    }
    fn split_region(&mut self, region: usize) -> Option<std::ops::Range<usize>> {
        let children = self.partition.split(region)?;
        let parent = self.lambdas[region];
        self.lambdas.resize(self.partition.num_regions(), parent);
        // Children inherit the parent's scale (regional-adaptive paper, section 5.2).
        for k in children.clone() {
            self.lambdas[k] = parent;
        }
        Some(children)
    }
}
