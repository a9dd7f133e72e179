//! The orbital delayed-rejection kernel at the cost of what the target reads
//! (`pss::dr::lazy_orbital_kernel`, `pss::LazyPairwise` and `pss::LazyOrbital`: pairs moved
//! lazily as the target reads them, unread pairs caught up exactly; DR paper section 4.4,
//! eq. 11) keeps pi on targets whose read set depends on the state, with mass across the
//! torus seam.
//!
//! # Setup
//! Targets: `pss::testing::Stripes::narrow()` (reads `u1` only when `u0` lies in one of 16
//! stripes, one across the seam; the pair `(u0, u1)` is then read whole or half) and
//! `pss::testing::RoulettePath` (a variable-length path: reads `u_0, u_1, ...` until a
//! stopping rule, so its read prefix ends inside a pair or at a pair's end, and long paths
//! read pairs the current state has not read for many steps; the continuation band at 0
//! straddles the seam). Bins: the targets' exact bins (`ExactPssTarget::bins`), which also
//! bin coordinates the target does not read (they must stay uniform).
//!
//! Negative control: the same orbital rule over a layout that follows the current state's
//! read prefix (`PrefixLayout`: both stages move the pairs of what `x` read, eagerly, and
//! keep the rest): the state-dependent layout the lazy stages replace, whose forward and
//! reverse moves act on different coordinates. Must fail the same check.
//!
//! # Statistics
//! [`STARTS`] exact starts, [`STEPS`] steps each; Pearson's chi-square on the bins. Each of
//! the [`PASSING_TESTS`] tests that must pass uses the Sidak level for a file-wide
//! false-failure probability of 0.01; the negative control must reject at the same level.

use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::testing::{sidak_alpha, ChiSquareReport, StationarityParams};
use mcmc_core::{DelayedRejection, Kernel, Proposal, Proposed};
use pss::dr::{lazy_orbital_kernel, lazy_orbital_kernel_with, SecondStageStreams};
use pss::testing::{pss_stationarity_test, ExactPssTarget, RoulettePath, Stripes};
use pss::{LazyPairParams, OnLayout, Orbital, PairLayout, PairwiseKelemen, PssState};
use rand::Rng;

/// Independent exact starts per test.
const STARTS: usize = 200_000;
/// Steps per start.
const STEPS: u64 = 20;
/// Tests in this file that must pass.
const PASSING_TESTS: usize = 3;

fn check<T, K>(what: &str, target: &T, kernel: &K, seed: u64) -> ChiSquareReport
where
    T: ExactPssTarget,
    K: Kernel<T> + Clone,
{
    let report = pss_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!("{what}: {report}");
    report
}

#[test]
fn lazy_orbital_keeps_pi_on_stripes() {
    let kernel = lazy_orbital_kernel(0.1, SecondStageStreams::all());
    check("lazy orbital, stripes", &Stripes::narrow(), &kernel, 1)
        .assert_passes("lazy orbital on stripes", PASSING_TESTS);
}

#[test]
fn lazy_orbital_keeps_pi_on_a_variable_length_path() {
    let kernel = lazy_orbital_kernel(0.1, SecondStageStreams::all());
    check(
        "lazy orbital, roulette path",
        &RoulettePath::default(),
        &kernel,
        2,
    )
    .assert_passes("lazy orbital on a roulette path", PASSING_TESTS);
}

/// The first number kept by both stages (MMLT's fixed strategy,
/// `LazyPairParams::fixed_first`): `u_0`, which decides whether the path continues, is
/// renewed by large steps only, the others pair up as `(1, 2), (3, 4), ...`.
#[test]
fn lazy_orbital_with_a_kept_first_number_keeps_pi() {
    let params = LazyPairParams::default().with_fixed_first(1);
    let kernel = lazy_orbital_kernel_with(params, 0.3, SecondStageStreams::all());
    check(
        "lazy orbital, kept u0, roulette path",
        &RoulettePath::default(),
        &kernel,
        4,
    )
    .assert_passes("lazy orbital with a kept first number", PASSING_TESTS);
}

/// The layout of what `x` read in its last evaluation (stream 0, rounded up to pairs).
fn prefix_of(x: &PssState) -> PairLayout {
    let n = x.read_counts()[0];
    PairLayout::single_stream(n + n % 2)
}

/// Negative control, first stage: the pairwise step over `x`'s read prefix.
#[derive(Clone, Copy, Debug)]
struct PrefixLayout;

impl Proposal<PssState> for PrefixLayout {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        OnLayout::new(PairwiseKelemen::default(), prefix_of(x)).propose(x, y, rng)
    }
    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        OnLayout::new(PairwiseKelemen::default(), prefix_of(from)).log_q(from, to)
    }
    fn is_symmetric(&self) -> bool {
        true
    }
}

impl ConditionalProposal<PssState> for PrefixLayout {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &PssState,
        y: &PssState,
        z: &mut PssState,
        rng: &mut R,
    ) -> Proposed {
        OnLayout::new(Orbital::default(), prefix_of(x)).propose(x, y, z, rng)
    }
    fn log_q(&self, x: &PssState, y: &PssState, z: &PssState) -> f64 {
        OnLayout::new(Orbital::default(), prefix_of(x)).log_q(x, y, z)
    }
}

#[test]
fn negative_control_prefix_layout_fails() {
    let kernel = DelayedRejection::orbital(PrefixLayout, PrefixLayout);
    let report = check(
        "negative control (layout of x's read prefix)",
        &RoulettePath::default(),
        &kernel,
        3,
    );
    assert!(report.rejects(sidak_alpha(0.01, PASSING_TESTS)), "{report}");
}
