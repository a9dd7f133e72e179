//! The PSS mutations pass the `mcmc-core` correctness harness: pairwise detailed balance, the
//! exact finite-state check and stationarity from exact starts, on toy targets read from a
//! primary-sample-space state, including targets with mass across the torus seam; and
//! deliberately broken PSS proposals fail the same checks.
//!
//! Run with `cargo test -p pss --release --test harness -- --nocapture` to see every
//! statistic and p-value.
//!
//! # Setup
//! A toy target on `[0, 1)^d` becomes a PSS target through `pss::testing::OnPss`: it reads
//! the first `d` primary samples (`begin`, then `next_sample` d times) and returns the toy's
//! normalised log density. Targets: (a) the 2-D wrapped-Gaussian mixture whose modes straddle both seams
//! ([`TorusMixture::across_seam`]), (b) the 1-D piecewise-constant density with zero-density
//! holes ([`PiecewiseConstant::with_holes`]), (c) a smooth 1-D wrapped-normal mixture with 70%
//! of its mass in a mode centred at 0.985 ([`SeamBump`]). Kernels: MH with the Kelemen small
//! step (Kelemen 2002's `[1/1024, 1/64]` and a wide `[0.02, 0.2]`), the wrapped Gaussian small
//! step (sigma 0.05 and 0.3), the large step, and the PSSMLT mixture (`p_large = 0.3`).
//!
//! # Lazy states
//! The pairwise and finite-state checks work on fully materialised states
//! (`PssState::from_values`), where `log_q` is exact. The stationarity test exercises the
//! *lazy* state: each chain starts from `PssState::from_values(exact draw)`, and every
//! candidate is a lazily mutated copy whose coordinates are perturbed only when the target
//! reads them (counter-based noise), i.e. the code path a renderer runs.
//!
//! # Why the default Kelemen kernel needs fine grids
//! Its displacements lie in `[1/1024, 1/64]`, but distinct points of a 16-32 cell grid on the
//! circle are at least `1/32 > 1/64` apart: on such grids its discretised kernel is the
//! identity, and the finite-state check could not fail. It is checked on a 128-cell grid
//! (spacing `1/128`, inside its support), and the wide kernel `[0.02, 0.2]` covers the coarse
//! grids (spacings `1/32` and `1/12` lie in its support). 2-D grids fine enough for the
//! default kernel (e.g. 128^2 states) are too large for a dense matrix, so in 2-D only the
//! wide kernel, the Gaussians, the large step and the mixture are checked on a 12 x 12 grid.
//! Every finite-state check also asserts that every grid state of positive density has a
//! positive flow to another grid state, so no check is vacuous.
//!
//! # Statistics
//! - Pairwise and finite-state checks are identities checked to rounding (relative `1e-9`
//!   on log flows, `1e-12` on the flow matrix): deterministic, never flaky.
//! - Each stationarity test starts [`STARTS`] chains from independent exact draws and runs
//!   [`STEPS`] steps: if the kernel preserves pi the final states are i.i.d. from pi, so
//!   Pearson's statistic (bins pooled to expected count >= 5) is asymptotically chi-square and
//!   the p-value uniform. This file runs [`CHI_SQUARE_TESTS`] such tests on correct kernels;
//!   each must pass at the Sidak level `1 - (1 - 0.01)^(1/20) = 5.0e-4`, so the probability
//!   that any correct kernel fails is 0.01. Seeds are fixed: the outcome is deterministic.
//! - A broken kernel counts as caught when its p-value is below [`OVERWHELMING`] = 1e-6 (a
//!   correct kernel gets there with probability 1e-6), or when its finite-state asymmetry
//!   exceeds [`GROSS_ASYMMETRY`] = 1e-3 (nine orders above the tolerance that correct kernels
//!   meet at rounding level).

use std::panic::{catch_unwind, AssertUnwindSafe};

use mcmc_core::testing::{
    assert_finite_state_balance, assert_hastings_consistent, assert_path_balance,
    assert_symmetric_proposal, chi_square_test, finite_state_check, grid_centres, sidak_alpha,
    ChiSquareReport, PairwiseParams, StationarityParams, TreatedAsSymmetric, ALPHA,
};
use mcmc_core::toy::special::normal_interval;
use mcmc_core::toy::{wrapped_normal_pdf, Bins, PiecewiseConstant, TorusMixture, ToyTarget};
use mcmc_core::{Chain, Kernel, Mh, NoAdaptation, Proposal, Sample, Target};
use proptest::prelude::*;
use proptest::strategy::BoxedStrategy;
use pss::testing::{
    pss_stationarity_test, ClampedKelemen, Eager, ExactPssTarget, OnPss, RegionalGaussian,
};
use pss::{wrap, KelemenParams, LargeStep, PssState, PssmltProposal, SmallMutation, SmallStep};
use rand::{Rng, RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;

/// Chi-square tests of correct kernels (and of the exact sampler of [`SeamBump`]) in this
/// file, for the Sidak correction: 6 kernels x 3 targets, the honest regional Gaussian, and
/// the sampler check. Keep in sync.
const CHI_SQUARE_TESTS: usize = 20;

/// Independent exact starts per stationarity test. The smallest bins (the torus target's
/// 12 x 12 grid has cells of probability ~1e-5) are pooled to expected count >= 5.
const STARTS: usize = 20_000;

/// Kernel steps per start.
const STEPS: u64 = 20;

/// p-value below which a broken kernel counts as caught.
const OVERWHELMING: f64 = 1e-6;

/// Minimum finite-state asymmetry of a broken kernel.
const GROSS_ASYMMETRY: f64 = 1e-3;

/// Minimum fraction of informative pairs (not both flows zero) in the pairwise checks. On the
/// target with holes (37.5% of `[0, 1)` has density 0, so a pair has both ends of positive
/// density with probability ~0.4-0.6) the pair strategy gives ~0.4-0.5 (a Kelemen kernel:
/// local pairs are in support with probability ~0.93, seam pairs join the two positive cells
/// next to the seam, independent pairs are out of support); on the other targets 0.65-1.
/// Measured: 0.39 (wide Kelemen, holes) to 1.0. 0.3 fails only if the strategy stops
/// exercising the kernel.
const MIN_INFORMATIVE: f64 = 0.3;

/// The largest dimension of the toy targets.
const MAX_DIM: usize = 2;

// ---------------------------------------------------------------------------------------------
// Targets
// ---------------------------------------------------------------------------------------------

/// (c) A smooth density on the circle with most of its mass across the seam:
/// `pi(x) = sum_k w_k sum_{m in Z} N(x + m; mu_k, sd_k^2)` on `[0, 1)` with the components of
/// [`SEAM_COMPONENTS`]. The main mode (mean 0.985, sd 0.05) straddles the seam: 66% of the
/// mass lies in `[0.9, 1) u [0, 0.1)` (40% below the seam, 26% above it), 31% in the two
/// bins next to it.
///
/// Bins: 32 equal cells of `[0, 1)` (probabilities: normal CDF differences of the 7 nearest
/// periodic images; the nearest omitted image is 2.5 / 0.1 = 25 sd away, so they are exact to
/// far below rounding) plus an overflow bin of probability 0.
#[derive(Clone, Copy, Debug)]
struct SeamBump;

/// `(weight, mean, sd)` of the components of [`SeamBump`].
const SEAM_COMPONENTS: [(f64, f64, f64); 2] = [(0.7, 0.985, 0.05), (0.3, 0.4, 0.1)];

/// Number of equal bins of [`SeamBump`].
const SEAM_BINS: usize = 32;

impl SeamBump {
    /// Exact probability of `[lo, hi) subset [0, 1)`.
    fn interval_probability(lo: f64, hi: f64) -> f64 {
        SEAM_COMPONENTS
            .iter()
            .map(|&(w, mu, sd)| {
                w * (-3..=3)
                    .map(|m| {
                        let m = f64::from(m);
                        normal_interval((lo + m - mu) / sd, (hi + m - mu) / sd)
                    })
                    .sum::<f64>()
            })
            .sum()
    }
}

impl Target for SeamBump {
    type State = Vec<f64>;
    type Payload = ();

    fn evaluate(&self, x: &mut Vec<f64>, _payload: &mut ()) -> f64 {
        self.log_density(x)
    }
}

impl ToyTarget for SeamBump {
    fn name(&self) -> &'static str {
        "seam bump (1-D)"
    }

    fn dim(&self) -> usize {
        1
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        if !(0.0..1.0).contains(&x[0]) {
            return f64::NEG_INFINITY;
        }
        SEAM_COMPONENTS
            .iter()
            .map(|&(w, mu, sd)| w * wrapped_normal_pdf(x[0], mu, sd))
            .sum::<f64>()
            .ln()
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let u: f64 = rng.random();
        let (_, mu, sd) = if u < SEAM_COMPONENTS[0].0 {
            SEAM_COMPONENTS[0]
        } else {
            SEAM_COMPONENTS[1]
        };
        let z: f64 = StandardNormal.sample(rng);
        vec![wrap(mu + sd * z)]
    }

    fn bins(&self) -> Bins {
        let n = SEAM_BINS as f64;
        let mut probabilities: Vec<f64> = (0..SEAM_BINS)
            .map(|i| Self::interval_probability(i as f64 / n, (i + 1) as f64 / n))
            .collect();
        probabilities.push(0.0);
        Bins::new(probabilities, move |x| {
            if (0.0..1.0).contains(&x[0]) {
                ((x[0] * n) as usize).min(SEAM_BINS - 1)
            } else {
                SEAM_BINS
            }
        })
    }

    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![1.0])
    }
}

fn torus() -> OnPss<TorusMixture> {
    OnPss::new(TorusMixture::across_seam()).unwrap()
}

fn holes() -> OnPss<PiecewiseConstant> {
    OnPss::new(PiecewiseConstant::with_holes()).unwrap()
}

fn seam() -> OnPss<SeamBump> {
    OnPss::new(SeamBump).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Kernels
// ---------------------------------------------------------------------------------------------

fn kelemen_default() -> SmallMutation {
    SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap()
}

/// Wide enough that the spacings of 32-cell and 12-cell grids (1/32, 1/12, 2/12) are in its
/// support `[0.02, 0.2]`.
fn kelemen_wide() -> SmallMutation {
    SmallMutation::kelemen(KelemenParams { s1: 0.02, s2: 0.2 }).unwrap()
}

fn gaussian(sigma: f64) -> SmallMutation {
    SmallMutation::gaussian(sigma).unwrap()
}

/// The uniform box step (corona-13's KMLT kernel), wide enough to be seen on the coarse grids.
fn uniform_box() -> SmallMutation {
    SmallMutation::uniform(0.1).unwrap()
}

fn small(m: SmallMutation) -> Mh<SmallStep> {
    Mh::new(SmallStep::new(m))
}

fn pssmlt_proposal(m: SmallMutation) -> PssmltProposal {
    PssmltProposal::new(SmallStep::new(m), 0.3).unwrap()
}

/// The range `[lo, hi]` of displacement magnitudes the pair strategy draws (log-uniformly):
/// the kernel's support with a 10% margin on each side for Kelemen (so ~7% of the local pairs
/// fall just outside it: both flows zero, as they must be), `[0.01, 3] sigma` for Gaussians,
/// and the whole circle for the large step.
fn displacements(m: Option<SmallMutation>) -> (f64, f64) {
    match m {
        Some(SmallMutation::Kelemen(KelemenParams { s1, s2 })) => (0.9 * s1, 1.1 * s2),
        Some(SmallMutation::Gaussian { sigma }) => (0.01 * sigma, (3.0 * sigma).min(0.5)),
        Some(SmallMutation::Uniform { amount }) => (1e-3 * amount, 1.1 * amount),
        None => (1e-3, 0.5),
    }
}

// ---------------------------------------------------------------------------------------------
// Strategies
// ---------------------------------------------------------------------------------------------

/// Pairs `[x, y]` of fully materialised `d`-dimensional states:
/// - half are local: `y = wrap(x + delta)` with a random sign and a log-uniform magnitude in
///   `[lo, hi]` per coordinate (these cross the seam when `x` is within `|delta|` of it);
/// - a quarter straddle the seam in every coordinate: `x_i = v r` just above 0 and
///   `y_i = wrap(x_i - r)` just below 1, for `r` log-uniform in `[lo, hi]`, in either order;
/// - a quarter are independent uniform pairs (informative for the Gaussians and the large
///   step, mostly out of support for Kelemen).
fn pairs(d: usize, (lo, hi): (f64, f64)) -> BoxedStrategy<Vec<PssState>> {
    let magnitude = move |u: f64| lo * (hi / lo).powf(u);
    let local =
        prop::collection::vec((0.0..1.0f64, 0.0..1.0f64, any::<bool>()), d).prop_map(move |c| {
            let x: Vec<f64> = c.iter().map(|t| t.0).collect();
            let y: Vec<f64> = c
                .iter()
                .map(|&(x, u, up)| {
                    let r = magnitude(u);
                    wrap(if up { x + r } else { x - r })
                })
                .collect();
            vec![PssState::from_values(&x), PssState::from_values(&y)]
        });
    let across = (
        prop::collection::vec((0.0..1.0f64, 0.0..1.0f64), d),
        any::<bool>(),
    )
        .prop_map(move |(c, swap)| {
            let (mut x, mut y) = (Vec::new(), Vec::new());
            for (v, u) in c {
                let r = magnitude(u);
                x.push(v * r);
                y.push(wrap(v * r - r));
            }
            if swap {
                std::mem::swap(&mut x, &mut y);
            }
            vec![PssState::from_values(&x), PssState::from_values(&y)]
        });
    let independent = (
        prop::collection::vec(0.0..1.0f64, d),
        prop::collection::vec(0.0..1.0f64, d),
    )
        .prop_map(|(x, y)| vec![PssState::from_values(&x), PssState::from_values(&y)]);
    prop_oneof![2 => local, 1 => across, 1 => independent].boxed()
}

/// Single fully materialised states, each coordinate uniform on `[0, 1)` or next to the seam
/// (`[0, 0.02)` or `[0.98, 1)`), so that proposed candidates and independent pairs often
/// straddle the seam.
fn states(d: usize) -> BoxedStrategy<PssState> {
    prop::collection::vec(prop_oneof![0.0..1.0f64, 0.0..0.02f64, 0.98..1.0f64], d)
        .prop_map(|v| PssState::from_values(&v))
        .boxed()
}

// ---------------------------------------------------------------------------------------------
// The three checks
// ---------------------------------------------------------------------------------------------

fn check_pairwise<T, K>(what: &str, target: &OnPss<T>, kernel: &K, range: (f64, f64), seed: u64)
where
    T: ToyTarget,
    K: Kernel<OnPss<T>>,
{
    let params = PairwiseParams {
        min_informative: MIN_INFORMATIVE,
        ..PairwiseParams::with_seed(seed)
    };
    let r = assert_path_balance(target, kernel, pairs(target.toy().dim(), range), &params);
    eprintln!(
        "{what}: pairwise balance on {}/{} informative pairs (worst |log flow difference| {:.1e})",
        r.informative, r.cases, r.worst_log_difference
    );
}

/// The finite-state check on a regular grid of `[0, 1)^d`, plus non-vacuity: every grid state
/// of positive density has a positive flow to some other grid state.
fn check_finite_state<T, K>(what: &str, target: &OnPss<T>, kernel: &K, cells: &[usize])
where
    T: ToyTarget,
    K: Kernel<OnPss<T>>,
{
    let (states, volume) = grid_states(target, cells);
    let r = assert_finite_state_balance(target, kernel, &states, volume);
    let samples: Vec<_> = states
        .iter()
        .map(|s| Sample::evaluate(target, s.clone()))
        .collect();
    let support: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].log_density > f64::NEG_INFINITY)
        .collect();
    let mut moves = 0usize;
    for &i in &support {
        let out = support
            .iter()
            .filter(|&&j| {
                j != i
                    && kernel
                        .log_flow(target, &[samples[i].clone(), samples[j].clone()])
                        .is_finite()
            })
            .count();
        assert!(
            out > 0,
            "{what}: grid state {:?} has no flow to any other grid state: the finite-state \
             check would be vacuous on this grid",
            states[i].raw_values()
        );
        moves += out;
    }
    eprintln!(
        "{what}: finite-state on {cells:?} cells: {} states, {moves} positive off-diagonal \
         flows, asymmetry {:.1e}, pi K error {:.1e}",
        r.states, r.max_asymmetry, r.max_stationarity_error
    );
}

fn grid_states<T: ToyTarget>(target: &OnPss<T>, cells: &[usize]) -> (Vec<PssState>, f64) {
    let (lo, hi) = target.toy().bounding_box();
    let (centres, volume) = grid_centres(&lo, &hi, cells);
    let states = centres.iter().map(|c| PssState::from_values(c)).collect();
    (states, volume)
}

/// Stationarity from exact starts: `PssState::from_values(exact draw)`, then [`STEPS`] lazy
/// kernel steps; the final states' first `d` coordinates are binned with the toy's exact
/// bins (`pss::testing::OnPss` as an `ExactPssTarget`).
fn stationarity<T, K>(target: &OnPss<T>, kernel: &K, seed: u64) -> ChiSquareReport
where
    T: ToyTarget,
    K: Kernel<OnPss<T>> + Clone,
{
    pss_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(STARTS, STEPS, seed),
    )
}

/// Acceptance rate of one 2000-step chain from an exact start: a kernel that never moves
/// passes any stationarity test, so each correct kernel must accept at least 5% of its
/// proposals (every kernel here accepts far more; the rates are printed).
fn assert_moves<T, K>(what: &str, target: &OnPss<T>, kernel: &K, seed: u64) -> f64
where
    T: ToyTarget,
    K: Kernel<OnPss<T>> + Clone,
{
    let mut rng = Pcg64::seed_from_u64(seed);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(target, kernel.clone(), NoAdaptation, rng, start).unwrap();
    chain.run(2000, &mut ()).unwrap();
    let rate = chain.stats().acceptance_rate();
    assert!(rate > 0.05, "{what}: acceptance rate {rate}");
    rate
}

/// All three checks for one kernel on one target; `cells`: the finite-state grid, if any.
fn check_on<T, K>(
    what: &str,
    target: &OnPss<T>,
    kernel: &K,
    range: (f64, f64),
    cells: Option<&[usize]>,
    seed: u64,
) where
    T: ToyTarget,
    K: Kernel<OnPss<T>> + Clone,
{
    check_pairwise(what, target, kernel, range, seed);
    if let Some(cells) = cells {
        check_finite_state(what, target, kernel, cells);
    }
    let rate = assert_moves(what, target, kernel, seed);
    let report = stationarity(target, kernel, seed);
    eprintln!("{what}: acceptance {rate:.3}; stationarity {report}");
    report.assert_passes(what, CHI_SQUARE_TESTS);
}

/// [`check_on`] on the three targets: 1-D grids of `cells_1d` cells for (b) and (c), a
/// `cells_2d`^2 grid for (a) if given.
fn check_kernel<K>(
    name: &str,
    kernel: &K,
    range: (f64, f64),
    cells_1d: usize,
    cells_2d: Option<usize>,
    seed: u64,
) where
    K: Kernel<OnPss<TorusMixture>>
        + Kernel<OnPss<PiecewiseConstant>>
        + Kernel<OnPss<SeamBump>>
        + Clone,
{
    let grid_2d = cells_2d.map(|n| [n, n]);
    check_on(
        &format!("torus mixture / {name}"),
        &torus(),
        kernel,
        range,
        grid_2d.as_ref().map(|g| &g[..]),
        10 * seed,
    );
    check_on(
        &format!("holes / {name}"),
        &holes(),
        kernel,
        range,
        Some(&[cells_1d]),
        10 * seed + 1,
    );
    check_on(
        &format!("seam bump / {name}"),
        &seam(),
        kernel,
        range,
        Some(&[cells_1d]),
        10 * seed + 2,
    );
}

// ---------------------------------------------------------------------------------------------
// Tests: the target, the proposals, the kernels
// ---------------------------------------------------------------------------------------------

/// Target (c) is normalised, its bin probabilities are the integrals of its density, and its
/// exact sampler matches them (a chi-square test, counted in [`CHI_SQUARE_TESTS`]).
#[test]
fn seam_target_is_exact() {
    let t = SeamBump;
    let bins = t.bins();
    let total: f64 = bins.probabilities().iter().sum();
    assert!((total - 1.0).abs() < 1e-12, "bins sum to {total}");
    // Midpoint rule with 2^14 cells per bin: error ~ h^2 max|pi''| / 24 per unit mass, below
    // 1e-9 here (|pi''| <= 0.7 / (0.05^3 sqrt(2 pi)) ~ 2.2e3, h = 1/(32 * 2^14)).
    let per_bin = 1 << 14;
    let h = 1.0 / (SEAM_BINS * per_bin) as f64;
    for (i, &p) in bins.probabilities()[..SEAM_BINS].iter().enumerate() {
        let integral: f64 = (0..per_bin)
            .map(|k| t.log_density(&[((i * per_bin + k) as f64 + 0.5) * h]).exp() * h)
            .sum();
        assert!((integral - p).abs() < 1e-9, "bin {i}: {integral} vs {p}");
    }
    // Mass across the seam: the density just past 0 exceeds that at 0.9.
    assert!(t.log_density(&[0.02]) > t.log_density(&[0.9]));
    let mut rng = Pcg64::seed_from_u64(1);
    let mut counts = vec![0u64; bins.len()];
    for _ in 0..STARTS {
        counts[bins.bin_of(&t.sample_exact(&mut rng))] += 1;
    }
    let report = chi_square_test(&counts, bins.probabilities(), 5.0);
    eprintln!("seam bump exact sampler: {report}");
    report.assert_passes("seam bump exact sampler", CHI_SQUARE_TESTS);
}

fn check_proposal<P: Proposal<PssState> + Clone>(what: &str, proposal: &P, seed: u64) {
    for d in 1..=MAX_DIM {
        let params = PairwiseParams::with_seed(seed + d as u64);
        let eager = Eager(proposal.clone());
        let s = assert_symmetric_proposal(&eager, states(d), &params);
        let h = assert_hastings_consistent(&eager, states(d), &params);
        eprintln!(
            "{what}, d = {d}: symmetric on {} pairs, Hastings-consistent on {} candidates",
            s.informative, h.informative
        );
    }
}

/// Every PSS proposal claims symmetry: `log_q(x, y) == log_q(y, x)` for independent pairs and
/// for proposed candidates (many of them across the seam), and the Hastings term `propose`
/// reports (0) is the one its densities imply, per mixture component.
#[test]
fn proposals_are_symmetric_and_hastings_consistent() {
    check_proposal("Kelemen default", &SmallStep::new(kelemen_default()), 1);
    check_proposal("Kelemen wide", &SmallStep::new(kelemen_wide()), 3);
    check_proposal("Gaussian 0.05", &SmallStep::new(gaussian(0.05)), 5);
    check_proposal("Gaussian 0.3", &SmallStep::new(gaussian(0.3)), 7);
    check_proposal("Uniform 0.1", &SmallStep::new(uniform_box()), 13);
    check_proposal("large step", &LargeStep, 9);
    check_proposal("PSSMLT", &pssmlt_proposal(kelemen_default()), 11);
}

/// Across the seam, `log_q` is finite, symmetric, and equal to that of the same displacement
/// in the interior of the square (translation invariance on the torus): a kernel that does not
/// wrap its density would give `-inf` or a different value here.
fn check_seam_densities<P: Proposal<PssState>>(what: &str, p: &P, (lo, hi): (f64, f64)) {
    let mut rng = Pcg64::seed_from_u64(17);
    let agree = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()));
    for _ in 0..2000 {
        let d = rng.random_range(1..=MAX_DIM);
        let (mut x, mut y, mut xi, mut yi) = (vec![], vec![], vec![], vec![]);
        for _ in 0..d {
            let r = lo * (hi / lo).powf(rng.random::<f64>());
            let v: f64 = rng.random();
            // Across the seam (x just above 0, y just below 1) ...
            x.push(v * r);
            y.push(wrap(v * r - r));
            // ... and the same displacement around 1/2.
            xi.push(0.5 + v * r);
            yi.push(0.5 + v * r - r);
        }
        let (x, y) = (PssState::from_values(&x), PssState::from_values(&y));
        let (xi, yi) = (PssState::from_values(&xi), PssState::from_values(&yi));
        let (fwd, bwd, inner) = (p.log_q(&x, &y), p.log_q(&y, &x), p.log_q(&xi, &yi));
        assert!(
            fwd.is_finite(),
            "{what}: log_q across the seam is {fwd}: {x:?} -> {y:?}"
        );
        assert!(agree(fwd, bwd), "{what}: {fwd} vs reverse {bwd}");
        assert!(
            agree(fwd, inner),
            "{what}: {fwd} across the seam vs {inner} inside"
        );
    }
}

#[test]
fn densities_wrap_across_the_seam() {
    // Displacements strictly inside each kernel's support.
    check_seam_densities(
        "Kelemen default",
        &SmallStep::new(kelemen_default()),
        (1.01 / 1024.0, 0.99 / 64.0),
    );
    check_seam_densities(
        "Kelemen wide",
        &SmallStep::new(kelemen_wide()),
        (0.0202, 0.198),
    );
    check_seam_densities(
        "Gaussian 0.05",
        &SmallStep::new(gaussian(0.05)),
        (5e-4, 0.15),
    );
    check_seam_densities("Gaussian 0.3", &SmallStep::new(gaussian(0.3)), (3e-3, 0.45));
    check_seam_densities("Uniform 0.1", &SmallStep::new(uniform_box()), (1e-3, 0.099));
    check_seam_densities("large step", &LargeStep, (1e-3, 0.45));
    check_seam_densities(
        "PSSMLT",
        &pssmlt_proposal(kelemen_default()),
        (1.01 / 1024.0, 0.99 / 64.0),
    );
}

#[test]
fn kelemen_default_passes() {
    let m = kelemen_default();
    check_kernel(
        "Kelemen [1/1024, 1/64]",
        &small(m),
        displacements(Some(m)),
        128,
        None,
        1,
    );
}

#[test]
fn kelemen_wide_passes() {
    let m = kelemen_wide();
    check_kernel(
        "Kelemen [0.02, 0.2]",
        &small(m),
        displacements(Some(m)),
        32,
        Some(12),
        2,
    );
}

#[test]
fn gaussian_narrow_passes() {
    let m = gaussian(0.05);
    check_kernel(
        "Gaussian 0.05",
        &small(m),
        displacements(Some(m)),
        32,
        Some(12),
        3,
    );
}

#[test]
fn gaussian_wide_passes() {
    let m = gaussian(0.3);
    check_kernel(
        "Gaussian 0.3",
        &small(m),
        displacements(Some(m)),
        32,
        Some(12),
        4,
    );
}

#[test]
fn uniform_box_passes() {
    let m = uniform_box();
    check_kernel(
        "Uniform box 0.1",
        &small(m),
        displacements(Some(m)),
        32,
        Some(12),
        13,
    );
}

#[test]
fn large_step_passes() {
    check_kernel(
        "large step",
        &Mh::new(LargeStep),
        displacements(None),
        16,
        Some(12),
        5,
    );
}

#[test]
fn pssmlt_passes() {
    // Kelemen 2002's configuration: all three checks (finite-state on the 128-cell grid, where
    // its small steps are visible).
    let m = kelemen_default();
    let kernel = Mh::new(pssmlt_proposal(m));
    check_kernel(
        "PSSMLT (Kelemen default, p_large 0.3)",
        &kernel,
        displacements(Some(m)),
        128,
        None,
        6,
    );
    // With the wide small step, both components are visible on the coarse 1-D grids and on
    // the 12 x 12 torus grid (pairwise and finite-state only: the stationarity budget is spent).
    let m = kelemen_wide();
    let kernel = Mh::new(pssmlt_proposal(m));
    let what = "PSSMLT (Kelemen wide, p_large 0.3)";
    let range = displacements(Some(m));
    check_pairwise(what, &torus(), &kernel, range, 70);
    check_finite_state(what, &torus(), &kernel, &[12, 12]);
    check_pairwise(what, &holes(), &kernel, range, 71);
    check_finite_state(what, &holes(), &kernel, &[32]);
    check_pairwise(what, &seam(), &kernel, range, 72);
    check_finite_state(what, &seam(), &kernel, &[32]);
}

// ---------------------------------------------------------------------------------------------
// Negative controls
// ---------------------------------------------------------------------------------------------

/// Runs `f`, which must panic with a message containing `needle`.
fn assert_fails(what: &str, needle: &str, f: impl FnOnce()) {
    let err = catch_unwind(AssertUnwindSafe(f)).expect_err(what);
    let msg = err
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| err.downcast_ref::<&str>().map(|s| (*s).to_string()))
        .unwrap_or_default();
    assert!(msg.contains(needle), "{what}: unexpected failure {msg}");
    eprintln!(
        "{what}: caught as expected: {}",
        msg.lines().next().unwrap_or("")
    );
}

/// The regional Gaussian with its Hastings term passes every check on the seam target; the
/// same proposal treated as symmetric (the "Hastings term of the wrong sigma" bug: the
/// reverse density uses the forward move's sigma, so the ratio is taken as 1) fails them all.
#[test]
fn regional_gaussian_needs_its_hastings_term() {
    let target = seam();
    let honest = RegionalGaussian::new(0.03, 0.2).unwrap();
    let range = (3e-4, 0.5);
    let what = "seam bump / regional Gaussian (0.03 | 0.2)";
    assert_hastings_consistent(&honest, states(1), &PairwiseParams::with_seed(81));
    check_on(what, &target, &Mh::new(honest), range, Some(&[32]), 81);

    let liar = TreatedAsSymmetric(honest);
    let bad = Mh::new(liar.clone());
    assert_fails("treated as symmetric: pairwise", "detailed balance", || {
        check_pairwise(what, &target, &bad, range, 82);
    });
    let (grid, volume) = grid_states(&target, &[32]);
    let asymmetry = finite_state_check(&target, &bad, &grid, volume).max_asymmetry;
    eprintln!("treated as symmetric: finite-state asymmetry {asymmetry:.3e}");
    assert!(asymmetry > GROSS_ASYMMETRY, "asymmetry {asymmetry}");
    assert_fails(
        "treated as symmetric: finite-state",
        "is not symmetric",
        || {
            assert_finite_state_balance(&target, &bad, &grid, volume);
        },
    );
    assert_fails(
        "treated as symmetric: symmetry claim",
        "claims symmetry",
        || {
            assert_symmetric_proposal(&liar, states(1), &PairwiseParams::with_seed(83));
        },
    );
    let report = stationarity(&target, &bad, 84);
    eprintln!("treated as symmetric: stationarity {report}");
    assert!(report.p_value < OVERWHELMING, "{report}");
}

/// The clamping step piles mass onto the boundary points and never crosses the seam. The
/// correct wrap-around kernel with the same parameters passes on the same target
/// (`kelemen_wide_passes`, "seam bump"); the clamped one fails stationarity. Its flows are
/// computed from the claimed (correct) density, so the pairwise and finite-state checks
/// cannot see this bug: a mismatch between `propose` and `log_q` is only visible to the
/// sampling test (as for forced acceptance in mcmc-core).
#[test]
fn clamped_kelemen_fails_stationarity() {
    let target = seam();
    let bad = Mh::new(ClampedKelemen::new(KelemenParams { s1: 0.02, s2: 0.2 }).unwrap());
    let (grid, volume) = grid_states(&target, &[32]);
    assert_finite_state_balance(&target, &bad, &grid, volume);
    let report = stationarity(&target, &bad, 91);
    eprintln!("clamped Kelemen: stationarity {report}");
    assert!(report.p_value < OVERWHELMING, "{report}");
    assert!(report.rejects(sidak_alpha(ALPHA, CHI_SQUARE_TESTS)));
}
