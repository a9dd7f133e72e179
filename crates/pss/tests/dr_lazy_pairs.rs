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
//! straddles the seam), and `Gate` (below: the second pair is read only while `u_0` keeps a
//! gate open, so a rejected `y` often read a pair that `z`, with the gate closed, does not;
//! tested with wide radii `[0.05, 0.3]` and a uniform rotation angle, where `z`'s move on such
//! a pair, `y`'s `d` rotated, and a fresh composite step differ at the scale of the gate's
//! cells). Bins: the targets' exact bins (`ExactPssTarget::bins`), which also bin
//! coordinates the target does not read (they must stay uniform).
//!
//! Negative controls (each must fail the same check):
//! - the same orbital rule over a layout that follows the current state's read prefix
//!   (`PrefixLayout`: both stages move the pairs of what `x` read, eagerly, and keep the
//!   rest): the state-dependent layout the lazy stages replace, whose forward and reverse
//!   moves act on different coordinates;
//! - the lazy stages with `z` *not* computed on the pairs the rejected `y` read
//!   (`OrbitNotOnYsReads`: `z` lazy everywhere). A pair `y` read and `z` does not is then
//!   caught up later as a fresh composite step, although its move is `y`'s own, observed
//!   `d`, rotated: the rule "compute `z` on the pairs `y` read" is what this breaks. On
//!   `RoulettePath` with the paper's laws its bias is below what 200 000 starts resolve
//!   (chi-square p 0.1-0.9 over several laws and 20-100 steps), hence the gate.
//!
//! # Statistics
//! [`STARTS`] exact starts, [`STEPS`] steps each; Pearson's chi-square on the bins. Each of
//! the [`PASSING_TESTS`] tests that must pass uses the Sidak level for a file-wide
//! false-failure probability of 0.01; the negative controls must reject at the same level.
//! Power of the gate's control: 4 bins (3 degrees of freedom); a trial run at 100 000 starts
//! gave chi-square 36.7, a noncentrality of about 34, so about 67 at [`STARTS`]: the
//! statistic's mean is then about 70 with standard deviation about 17, against a critical
//! value of about 14.3 at the Sidak level (a false pass below 0.1 %).

use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::testing::{sidak_alpha, ChiSquareReport, StationarityParams};
use mcmc_core::{DelayedRejection, Kernel, Proposal, Proposed};
use pss::dr::{lazy_orbital_kernel, lazy_orbital_kernel_with, SecondStageStreams};
use pss::testing::{pss_stationarity_test, ExactPssTarget, RoulettePath, Stripes};
use pss::{
    LazyOrbital, LazyPairParams, LazyPairwise, OnLayout, Orbital, PairLayout, PairwiseKelemen,
    PairwiseKelemenParams, PairwiseMltProposal, Pending, PssState, WrappedCauchy,
};
use rand::{Rng, RngExt};

/// Independent exact starts per test.
const STARTS: usize = 200_000;
/// Steps per start.
const STEPS: u64 = 20;
/// Tests in this file that must pass.
const PASSING_TESTS: usize = 4;

/// Large-step probability of the gate tests (rare large steps: the rule "`z` on the pairs `y`
/// read" is about pairs left unread for many steps).
const RULE_P_LARGE: f64 = 0.05;

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

/// Negative control, second stage: [`LazyOrbital`] without its one rule, `z` computed lazily
/// on every pair, the pairs the rejected `y` read included (the density is the stage's own).
#[derive(Clone, Copy, Debug)]
struct OrbitNotOnYsReads(LazyOrbital);

impl ConditionalProposal<PssState> for OrbitNotOnYsReads {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &PssState,
        y: &PssState,
        z: &mut PssState,
        rng: &mut R,
    ) -> Proposed {
        z.clone_from(x);
        let pending = Pending::Orbit {
            params: self.0.params,
            first_key: y.key(),
            stream_mask: self.0.stream_mask,
        };
        z.set_pending(pending, rng.random());
        Proposed::symmetric()
    }
    fn log_q(&self, x: &PssState, y: &PssState, z: &PssState) -> f64 {
        self.0.log_q(x, y, z)
    }
}

/// A gate: reads `u_0`; if `u_0 < GATE` (open) it also reads the second pair and the
/// density is `HIGH` for `u_2 < WIDTH`, `LOW` elsewhere; closed, the density is `CLOSED` and
/// the second pair is not read (uniform under pi).
#[derive(Clone, Copy, Debug)]
struct Gate;

const GATE: f64 = 0.5;
const WIDTH: f64 = 0.25;
const HIGH: f64 = 4.0;
const LOW: f64 = 0.05;
const CLOSED: f64 = 1.0;

impl Gate {
    /// Unnormalised masses of (closed, u2 high), (closed, low), (open, high), (open, low).
    fn masses() -> [f64; 4] {
        [
            (1.0 - GATE) * CLOSED * WIDTH,
            (1.0 - GATE) * CLOSED * (1.0 - WIDTH),
            GATE * HIGH * WIDTH,
            GATE * LOW * (1.0 - WIDTH),
        ]
    }
    fn bin(u0: f64, u2: f64) -> usize {
        2 * usize::from(u0 < GATE) + usize::from(u2 >= WIDTH)
    }
}

impl mcmc_core::Target for Gate {
    type State = PssState;
    type Payload = ();
    fn evaluate(&self, x: &mut PssState, _payload: &mut ()) -> f64 {
        let z: f64 = Gate::masses().iter().sum();
        x.begin();
        let u0 = x.next_sample();
        let f = if u0 < GATE {
            x.next_sample();
            if x.next_sample() < WIDTH {
                HIGH
            } else {
                LOW
            }
        } else {
            CLOSED
        };
        (f / z).ln()
    }
}

impl ExactPssTarget for Gate {
    fn name(&self) -> &'static str {
        "gate (reads the second pair only when open)"
    }
    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> PssState {
        let masses = Gate::masses();
        let z: f64 = masses.iter().sum();
        let mut t = rng.random::<f64>() * z;
        let mut bin = 3;
        for (k, m) in masses.iter().enumerate() {
            if t < *m {
                bin = k;
                break;
            }
            t -= m;
        }
        let (open, low) = (bin >= 2, bin % 2 == 1);
        let u0 = if open {
            GATE * rng.random::<f64>()
        } else {
            GATE + (1.0 - GATE) * rng.random::<f64>()
        };
        let u2 = if low {
            WIDTH + (1.0 - WIDTH) * rng.random::<f64>()
        } else {
            WIDTH * rng.random::<f64>()
        };
        PssState::from_values(&[u0, rng.random(), u2, rng.random()])
    }
    fn bins(&self) -> pss::testing::PssBins {
        let masses = Gate::masses();
        let z: f64 = masses.iter().sum();
        pss::testing::PssBins::new(masses.iter().map(|m| m / z).collect(), |x| {
            let mut x = x.clone();
            Gate::bin(x.get(0), x.get(2))
        })
    }
}

/// The laws of the rule's test: wide radii `[0.05, 0.3]` and a uniform angle (`rho = 0`), so
/// that `z`'s move on a pair `y` read (`y`'s `d` rotated) and a fresh composite step differ
/// at the scale of the gate's cells; rare large steps.
fn rule_params() -> LazyPairParams {
    LazyPairParams {
        step: PairwiseKelemenParams::new(0.05, 0.3).expect("valid radii"),
        angle: WrappedCauchy::new(0.0).expect("valid rho"),
        fixed_first: 0,
    }
}

#[test]
fn lazy_orbital_keeps_pi_on_the_gate() {
    let kernel = lazy_orbital_kernel_with(rule_params(), RULE_P_LARGE, SecondStageStreams::all());
    check("lazy orbital, gate", &Gate, &kernel, 6)
        .assert_passes("lazy orbital on the gate", PASSING_TESTS);
}

#[test]
fn negative_control_z_not_on_the_pairs_y_read_fails() {
    let params = rule_params();
    let first =
        PairwiseMltProposal::new(LazyPairwise { params }, RULE_P_LARGE).expect("valid probability");
    let wrong = DelayedRejection::orbital(
        first,
        OrbitNotOnYsReads(LazyOrbital::new(params, pss::ALL_STREAMS)),
    )
    .second_stage_after_small_steps();
    let report = check(
        "negative control (z not computed on the pairs y read), gate",
        &Gate,
        &wrong,
        5,
    );
    assert!(report.rejects(sidak_alpha(0.01, PASSING_TESTS)), "{report}");
}
