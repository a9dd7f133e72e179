//! Pairwise detailed balance and proposal self-consistency, driven by proptest.
//!
//! Detailed balance of a kernel `K` with respect to `pi` is the identity of probability flows
//! `pi(x) K(x -> y) = pi(y) K(y -> x)` for every pair of states (DR paper, eq. 3-4); for a
//! two-stage delayed-rejection kernel the same holds for the flow through `(x, y, z)` and its
//! reverse path (eq. 6; through the fictional state `y*` for Green & Mira, section 4.5).
//! [`Kernel::log_flow`] computes the flow from the same acceptance formula the kernel uses;
//! these checks assert the identity for paths drawn by a proptest [`Strategy`]. Every check
//! uses a runner seeded from the caller's seed, so it is reproducible and never flaky.

use std::cell::Cell;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use rand::SeedableRng;
use rand_pcg::Pcg64;

use crate::kernel::Kernel;
use crate::proposal::{Proposal, Proposed};
use crate::seed::mix64;
use crate::target::{Sample, SampleOf, Target};

/// Parameters of the proptest-driven checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairwiseParams {
    /// Number of random cases.
    pub cases: u32,
    /// Seed of the proptest runner (ChaCha, derived from this by SplitMix).
    pub seed: u64,
    /// Relative tolerance on flows (and on densities for the proposal checks): two log values
    /// `a`, `b` agree if `|a - b| <= rel_tol * (1 + max(|a|, |b|))`, i.e. the flows agree to
    /// `rel_tol` relatively, allowing for rounding of large log values.
    pub rel_tol: f64,
    /// Minimum fraction of cases that must be informative (not both flows zero); below it the
    /// check fails, because a check that sees only zero flows cannot fail.
    pub min_informative: f64,
}

impl Default for PairwiseParams {
    /// 512 cases, seed 0, relative tolerance `1e-9`, at least a tenth informative.
    fn default() -> Self {
        Self {
            cases: 512,
            seed: 0,
            rel_tol: 1e-9,
            min_informative: 0.1,
        }
    }
}

impl PairwiseParams {
    /// The defaults with another seed.
    #[must_use]
    pub fn with_seed(seed: u64) -> Self {
        Self {
            seed,
            ..Self::default()
        }
    }
}

/// What a pairwise check saw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairwiseReport {
    /// Cases run.
    pub cases: u32,
    /// Cases where at least one side was nonzero (the others are skipped).
    pub informative: u32,
    /// The largest `|log a - log b|` among informative cases.
    pub worst_log_difference: f64,
}

/// True if two log values agree in the sense of [`PairwiseParams::rel_tol`]; equal infinities
/// agree, NaN agrees with nothing.
#[must_use]
pub fn log_values_agree(a: f64, b: f64, rel_tol: f64) -> bool {
    if a == b {
        return true;
    }
    if !a.is_finite() || !b.is_finite() {
        return false;
    }
    (a - b).abs() <= rel_tol * (1.0 + a.abs().max(b.abs()))
}

fn runner(params: &PairwiseParams) -> TestRunner {
    let mut seed = [0u8; 32];
    for (k, chunk) in seed.chunks_mut(8).enumerate() {
        chunk.copy_from_slice(
            &mix64(params.seed ^ (k as u64).wrapping_mul(0x9e37_79b9)).to_le_bytes(),
        );
    }
    let config = Config {
        cases: params.cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed))
}

fn finish<V: std::fmt::Debug>(
    what: &str,
    result: Result<(), proptest::test_runner::TestError<V>>,
    params: &PairwiseParams,
    informative: &Cell<u32>,
    worst: &Cell<f64>,
) -> PairwiseReport {
    if let Err(e) = result {
        panic!("{what}: {e}");
    }
    let report = PairwiseReport {
        cases: params.cases,
        informative: informative.get(),
        worst_log_difference: worst.get(),
    };
    assert!(
        f64::from(report.informative) >= params.min_informative * f64::from(params.cases),
        "{what}: only {} of {} cases were informative (both sides zero in the rest): the \
         strategy does not exercise the check",
        report.informative,
        report.cases
    );
    report
}

/// The forward and reverse log flows of one path (evaluated here).
#[must_use]
pub fn path_flows<T, K>(target: &T, kernel: &K, path: &[T::State]) -> (f64, f64)
where
    T: Target,
    K: Kernel<T>,
{
    let samples: Vec<SampleOf<T>> = path
        .iter()
        .map(|s| Sample::evaluate(target, s.clone()))
        .collect();
    let forward = kernel.log_flow(target, &samples);
    let reverse_path = kernel.reverse_path(target, &samples);
    let backward = kernel.log_flow(target, &reverse_path);
    (forward, backward)
}

/// Asserts detailed balance `log_flow(path) == log_flow(reverse_path(path))` for random paths
/// of `kernel.stages() + 1` states (pairs for MH, pairs and triples for two-stage kernels: a
/// two-stage kernel is checked on both), each state drawn independently from `states`.
/// Paths whose two flows are both zero are skipped.
///
/// # Panics
/// On the first violation (after proptest's shrinking, with the minimal failing path), or if
/// fewer than `params.min_informative` of the cases were informative.
pub fn assert_pairwise_balance<T, K, St>(
    target: &T,
    kernel: &K,
    states: St,
    params: &PairwiseParams,
) -> PairwiseReport
where
    T: Target,
    K: Kernel<T>,
    St: Strategy<Value = T::State> + Clone,
{
    let mut report = assert_path_balance(
        target,
        kernel,
        prop::collection::vec(states.clone(), 2),
        params,
    );
    if kernel.stages() >= 2 {
        let triples = assert_path_balance(
            target,
            kernel,
            prop::collection::vec(states, 3),
            &PairwiseParams {
                seed: params.seed ^ 0x7472_6970,
                ..*params
            },
        );
        report.informative = report.informative.min(triples.informative);
        report.worst_log_difference = report
            .worst_log_difference
            .max(triples.worst_log_difference);
    }
    report
}

/// Asserts detailed balance for paths drawn by `paths` (any length the kernel's `log_flow`
/// understands), for callers that need correlated states (e.g. `z` near `x`).
///
/// # Panics
/// As [`assert_pairwise_balance`].
pub fn assert_path_balance<T, K, St>(
    target: &T,
    kernel: &K,
    paths: St,
    params: &PairwiseParams,
) -> PairwiseReport
where
    T: Target,
    K: Kernel<T>,
    St: Strategy<Value = Vec<T::State>>,
{
    let informative = Cell::new(0u32);
    let worst = Cell::new(0.0f64);
    let result = runner(params).run(&paths, |path| {
        let (f, b) = path_flows(target, kernel, &path);
        if f == f64::NEG_INFINITY && b == f64::NEG_INFINITY {
            return Ok(());
        }
        if !log_values_agree(f, b, params.rel_tol) {
            return Err(TestCaseError::fail(format!(
                "detailed balance violated: log flow {f} forward vs {b} reverse \
                 (difference {})",
                f - b
            )));
        }
        informative.set(informative.get() + 1);
        worst.set(worst.get().max((f - b).abs()));
        Ok(())
    });
    finish(
        "pairwise detailed balance",
        result,
        params,
        &informative,
        &worst,
    )
}

/// Asserts that a proposal claiming [`Proposal::is_symmetric`] has `log_q(x, y) ==
/// log_q(y, x)`, for independent pairs from `states` and for pairs `(x, y)` where `y` was
/// proposed from `x` (so that bounded-support proposals are exercised too).
///
/// # Panics
/// If the proposal does not claim symmetry, or on the first asymmetric pair.
pub fn assert_symmetric_proposal<S, P, St>(
    proposal: &P,
    states: St,
    params: &PairwiseParams,
) -> PairwiseReport
where
    S: Clone + std::fmt::Debug,
    P: Proposal<S>,
    St: Strategy<Value = S> + Clone,
{
    assert!(
        proposal.is_symmetric(),
        "assert_symmetric_proposal: the proposal does not claim to be symmetric"
    );
    let informative = Cell::new(0u32);
    let worst = Cell::new(0.0f64);
    let result = runner(params).run(&(states.clone(), states, any::<u64>()), |(x, z, seed)| {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut y = x.clone();
        let proposed = proposal.propose(&x, &mut y, &mut rng);
        let mut pairs = vec![(x.clone(), z)];
        if matches!(proposed, Proposed::Move { .. }) {
            pairs.push((x, y));
        }
        for (a, b) in pairs {
            let (fwd, bwd) = (proposal.log_q(&a, &b), proposal.log_q(&b, &a));
            if fwd == f64::NEG_INFINITY && bwd == f64::NEG_INFINITY {
                continue;
            }
            prop_assert!(
                log_values_agree(fwd, bwd, params.rel_tol),
                "proposal claims symmetry but log_q(x, y) = {fwd}, log_q(y, x) = {bwd} for \
                 x = {a:?}, y = {b:?}"
            );
            informative.set(informative.get() + 1);
            worst.set(worst.get().max((fwd - bwd).abs()));
        }
        Ok(())
    });
    finish("symmetric proposal", result, params, &informative, &worst)
}

/// Asserts that for a candidate `y` proposed from `x` through component `j`, the Hastings term
/// returned by [`Proposal::propose`] equals [`Proposal::log_hastings`]`(j, x, y)`, and that
/// this equals the true density ratio `log_q_component(j, y, x) - log_q_component(j, x, y)`
/// (regional-adaptive paper, section 3.2, for mixtures). The second identity is what a
/// proposal that lies about its symmetry violates.
///
/// # Panics
/// On the first inconsistent candidate, or if fewer than `params.min_informative` of the
/// proposals were valid moves.
pub fn assert_hastings_consistent<S, P, St>(
    proposal: &P,
    states: St,
    params: &PairwiseParams,
) -> PairwiseReport
where
    S: Clone + std::fmt::Debug,
    P: Proposal<S>,
    St: Strategy<Value = S>,
{
    let informative = Cell::new(0u32);
    let worst = Cell::new(0.0f64);
    let result = runner(params).run(&(states, any::<u64>()), |(x, seed)| {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut y = x.clone();
        let (reported, j) = match proposal.propose(&x, &mut y, &mut rng) {
            Proposed::Move {
                log_hastings,
                component,
            } => (log_hastings, component),
            Proposed::Invalid { .. } => return Ok(()),
        };
        let claimed = proposal.log_hastings(j, &x, &y);
        prop_assert!(
            log_values_agree(reported, claimed, params.rel_tol),
            "propose reported log Hastings {reported} but log_hastings({j}, x, y) = {claimed} \
             for x = {x:?}, y = {y:?}"
        );
        let truth = proposal.log_q_component(j, &y, &x) - proposal.log_q_component(j, &x, &y);
        prop_assert!(
            log_values_agree(claimed, truth, params.rel_tol),
            "log_hastings({j}, x, y) = {claimed} but the transition densities give {truth} \
             (log q(y->x) - log q(x->y)) for x = {x:?}, y = {y:?}"
        );
        informative.set(informative.get() + 1);
        worst.set(worst.get().max((claimed - truth).abs()));
        Ok(())
    });
    finish("Hastings consistency", result, params, &informative, &worst)
}
