//! Lazy mutation of the PSS state has the same distribution as eager mutation, rejections
//! included.
//!
//! 1. **Catch-up of accepted steps** (`lazy_catch_up_matches_eager_mutation`): a state of three
//!    coordinates; the target reads only coordinate 0 for `k` accepted small steps, then reads
//!    coordinate 1. Lazily, coordinate 1 is caught up with `k + 1` perturbations at once;
//!    eagerly, each step perturbs it. Two-sample Kolmogorov-Smirnov test of the final values.
//! 2. **Random accept/reject sequences** (`lazy_equals_eager_with_rejections_*`): MH chains from
//!    a fixed start on targets whose read set depends on the state (`pss::testing::Stripes`,
//!    `pss::testing::RoulettePath`), so that candidates read coordinates the current state has
//!    not read for a while, and are accepted or rejected by the MH coin, which depends on the
//!    values they read. Lazy chains (the proposal as a renderer runs it) and eager chains (the
//!    same proposal wrapped in `pss::testing::Eager`, which perturbs every stored coordinate of
//!    the candidate when it is proposed) are run independently; the final states are fully
//!    materialised and their first two coordinates compared by a two-sample chi-square test
//!    on a 32 x 32 grid. Each test counts the rejections of candidates that read more
//!    coordinates than the current state's evaluation did, and requires many of them: a
//!    lazy state that re-draws the current state's stale coordinates at every proposal (and
//!    forgets them when the candidate is rejected) fails here, while sequences of accepted
//!    steps alone (test 1) cannot show it.
//! 3. **Large steps** refresh stale coordinates to uniforms, and a wrong eager reference is
//!    detected (negative control for test 1).
//!
//! Statistics: [`TESTS`] comparisons must pass, each at the Sidak level
//! `1 - 0.99^(1/TESTS)` (alpha = 0.01 for the file). Under "same distribution" the two-sample
//! chi-square statistic (bins pooled to smaller expected count >= 5) is asymptotically
//! chi-square and the KS p-value asymptotically uniform. Seeds are fixed: deterministic.

use std::sync::atomic::{AtomicUsize, Ordering};

use mcmc_core::seed::chain_seed;
use mcmc_core::testing::{
    chi_square_test, chi_square_two_sample, ks_two_sample, sidak_alpha, ExactBins, ALPHA,
};
use mcmc_core::{Chain, Kernel, Mh, NoAdaptation, Proposal, Target};
use pss::testing::{Eager, ExactPssTarget, RoulettePath, Stripes};
use pss::{KelemenParams, Pending, PssState, PssmltProposal, SmallMutation, SmallStep};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// Comparisons in this file that must pass (Sidak correction): 4 catch-up KS tests, 6
/// accept/reject sequence tests with 2 comparisons each, 1 large-step chi-square. Keep in
/// sync.
const TESTS: usize = 17;

/// The per-test level.
fn level() -> f64 {
    sidak_alpha(ALPHA, TESTS)
}

fn lazy_final(mutation: SmallMutation, k: u64, start: f64, rng: &mut Pcg64) -> f64 {
    let mut x = PssState::from_values(&[0.5, start, 0.25]);
    for _ in 0..k {
        // An accepted small step whose evaluation read only coordinate 0.
        x.set_pending(
            Pending::Small {
                mutation,
                stream_mask: 0xff,
            },
            rng.random(),
        );
        x.get(0);
    }
    x.set_pending(
        Pending::Small {
            mutation,
            stream_mask: 0xff,
        },
        rng.random(),
    );
    x.get(1)
}

fn eager_final(mutation: SmallMutation, k: u64, start: f64, rng: &mut Pcg64) -> f64 {
    let mut v = start;
    for _ in 0..=k {
        let key: u64 = rng.random();
        v = mutation.apply(v, 1, |d| pss::noise::uniform(key, 1, d));
    }
    v
}

#[test]
fn lazy_catch_up_matches_eager_mutation() {
    let n = 20_000;
    let mut rng = Pcg64::seed_from_u64(2024);
    let cases = [
        (SmallMutation::Kelemen(KelemenParams::kelemen2002()), 5),
        (SmallMutation::Kelemen(KelemenParams::kelemen2002()), 40),
        (SmallMutation::Gaussian { sigma: 0.01 }, 7),
        // Mass crosses the torus seam: start next to 0.
        (SmallMutation::Gaussian { sigma: 0.02 }, 3),
    ];
    for (mutation, k) in cases {
        let start = if matches!(mutation, SmallMutation::Gaussian { sigma } if sigma > 0.015) {
            0.005
        } else {
            0.4
        };
        let lazy: Vec<f64> = (0..n)
            .map(|_| lazy_final(mutation, k, start, &mut rng))
            .collect();
        let eager: Vec<f64> = (0..n)
            .map(|_| eager_final(mutation, k, start, &mut rng))
            .collect();
        let report = ks_two_sample(&lazy, &eager);
        eprintln!("catch-up {mutation:?}, k = {k}: {report}");
        assert!(
            report.p_value >= level(),
            "{mutation:?}, k = {k}: {report} (level {:.2e})",
            level()
        );
    }
}

#[test]
fn lazy_differs_from_wrong_step_count() {
    // Negative control: an eager reference with one step too few must be detected, so the
    // test above can fail.
    let n = 20_000;
    let mut rng = Pcg64::seed_from_u64(7);
    let mutation = SmallMutation::Gaussian { sigma: 0.01 };
    let lazy: Vec<f64> = (0..n)
        .map(|_| lazy_final(mutation, 3, 0.4, &mut rng))
        .collect();
    let eager: Vec<f64> = (0..n)
        .map(|_| eager_final(mutation, 1, 0.4, &mut rng))
        .collect();
    let report = ks_two_sample(&lazy, &eager);
    eprintln!("wrong step count: {report}");
    assert!(report.p_value < 1e-6, "{report}");
}

#[test]
fn coordinates_stale_before_a_large_step_are_fresh_uniforms() {
    let n = 20_000;
    let mut rng = Pcg64::seed_from_u64(11);
    let mutation = SmallMutation::Kelemen(KelemenParams::kelemen2002());
    let mut bins = [0u64; 10];
    for _ in 0..n {
        let mut x = PssState::from_values(&[0.5, 0.123]);
        x.set_pending(Pending::Large, rng.random());
        x.get(0);
        x.set_pending(
            Pending::Small {
                mutation,
                stream_mask: 0xff,
            },
            rng.random(),
        );
        let v = x.get(1);
        bins[(v * 10.0) as usize] += 1;
    }
    let report = chi_square_test(&bins, &[0.1; 10], 5.0);
    eprintln!("stale before a large step: {report}");
    report.assert_passes("stale before a large step", TESTS);
}

// ---------------------------------------------------------------------------------------------
// Random accept/reject sequences
// ---------------------------------------------------------------------------------------------

/// A target of `pss::testing` that can say how many coordinates an evaluation reads.
trait ReadCount: ExactPssTarget {
    fn reads(&self, x: &PssState) -> usize;
}

impl ReadCount for Stripes {
    fn reads(&self, x: &PssState) -> usize {
        Stripes::reads(self, x)
    }
}

impl ReadCount for RoulettePath {
    fn reads(&self, x: &PssState) -> usize {
        RoulettePath::reads(self, x)
    }
}

/// Wraps a target and records how many coordinates its last evaluation read (the chain
/// evaluates only candidates, so after a step this is the candidate's count).
struct Recording<'a, T> {
    inner: &'a T,
    last_reads: AtomicUsize,
}

impl<T: ReadCount> Target for Recording<'_, T> {
    type State = PssState;
    type Payload = ();

    fn evaluate(&self, x: &mut PssState, payload: &mut ()) -> f64 {
        let log_density = self.inner.evaluate(x, payload);
        self.last_reads
            .store(self.inner.reads(x), Ordering::Relaxed);
        log_density
    }
}

/// Grid cells per axis of the two-sample comparison.
const GRID: usize = 16;

/// Chains per side of the comparisons with small steps, and with the PSSMLT mixture on the
/// roulette path.
const CHAINS: usize = 50_000;

/// Chains per side of the comparison with the PSSMLT mixture on `Stripes`. The mixture
/// forgets the start after a few steps, and what remains of a lazy bias builds up slowly and
/// is diluted by the large steps (with the pre-fix lazy state, 10^5 chains per side gave
/// p = 3.7e-3 on `Stripes`, 3 x 10^5 gave 8e-16; on the roulette path 5 x 10^4 suffice).
const CHAINS_MIXTURE: usize = 300_000;

/// Steps per chain.
const SEQUENCE_STEPS: u64 = 100;

/// What a batch of chains from a fixed start produced.
struct Outcome {
    /// Histogram of the final, fully materialised `(u0, u1)` on the `GRID x GRID` grid.
    histogram: Vec<u64>,
    /// Histogram of the final states over the target's exact bins.
    target_bins: Vec<u64>,
    /// Rejections of candidates that read more coordinates than the current state's last
    /// evaluation did.
    stale_rejections: u64,
    /// All steps.
    steps: u64,
}

/// Runs `chains` chains of [`SEQUENCE_STEPS`] MH steps from `start` (chain `i` seeded with
/// `chain_seed(seed, i)`), bins each final state with the target's bins, materialises it and
/// bins its first two coordinates.
fn sequences<T, P>(target: &T, proposal: &P, start: &PssState, chains: usize, seed: u64) -> Outcome
where
    T: ReadCount,
    P: Proposal<PssState> + Clone,
    Mh<P>: for<'a> Kernel<Recording<'a, T>>,
{
    let recording = Recording {
        inner: target,
        last_reads: AtomicUsize::new(0),
    };
    let mut histogram = vec![0u64; GRID * GRID];
    let bins = target.bins();
    let mut target_bins = vec![0u64; bins.len()];
    let mut stale_rejections = 0;
    for i in 0..chains {
        let rng = Pcg64::seed_from_u64(chain_seed(seed, i as u64));
        let mut chain = Chain::new(
            &recording,
            Mh::new(proposal.clone()),
            NoAdaptation,
            rng,
            start.clone(),
        )
        .unwrap();
        let mut current_reads = target.reads(start);
        for _ in 0..SEQUENCE_STEPS {
            let info = chain.step(&mut ()).unwrap();
            let candidate_reads = recording.last_reads.load(Ordering::Relaxed);
            if info.accepted() {
                current_reads = candidate_reads;
            } else if candidate_reads > current_reads {
                stale_rejections += 1;
            }
        }
        target_bins[bins.bin_of(chain.state())] += 1;
        let mut last = chain.state().clone();
        last.materialize();
        let cell = |u: f64| ((u * GRID as f64) as usize).min(GRID - 1);
        let v = last.raw_values();
        histogram[cell(v[0]) * GRID + cell(v[1])] += 1;
    }
    Outcome {
        histogram,
        target_bins,
        stale_rejections,
        steps: chains as u64 * SEQUENCE_STEPS,
    }
}

/// Lazy versus eager chains of `proposal` on `target` from `start`: two two-sample chi-square
/// tests of the final states, one on the grid of their first two materialised coordinates,
/// one on the target's exact bins (which look at the coordinates the target reads, and for
/// `Stripes` at the unread `u1` too); both must pass. At least 1% of all steps must be
/// rejections of candidates that read coordinates the current state had not read.
fn lazy_equals_eager<T, P>(
    what: &str,
    target: &T,
    proposal: P,
    start: &[f64],
    chains: usize,
    seed: u64,
) where
    T: ReadCount,
    P: Proposal<PssState> + Clone,
    Mh<P>: for<'a> Kernel<Recording<'a, T>>,
    Mh<Eager<P>>: for<'a> Kernel<Recording<'a, T>>,
{
    let start = PssState::from_values(start);
    let lazy = sequences(target, &proposal, &start, chains, 2 * seed);
    let eager = sequences(target, &Eager(proposal), &start, chains, 2 * seed + 1);
    let grid = chi_square_two_sample(&lazy.histogram, &eager.histogram, 5.0);
    let bins = chi_square_two_sample(&lazy.target_bins, &eager.target_bins, 5.0);
    let share = |o: &Outcome| o.stale_rejections as f64 / o.steps as f64;
    eprintln!(
        "{what}: lazy vs eager on the (u0, u1) grid: {grid}\n{what}: lazy vs eager on the \
         target's bins: {bins}\n{what}: rejections of candidates that read a coordinate the \
         current state had not: {:.2}% (lazy), {:.2}% (eager) of steps",
        100.0 * share(&lazy),
        100.0 * share(&eager)
    );
    assert!(
        share(&lazy) > 0.01 && share(&eager) > 0.01,
        "{what}: too few rejections of candidates reading stale coordinates"
    );
    grid.assert_passes(&format!("{what} (grid)"), TESTS);
    bins.assert_passes(&format!("{what} (target bins)"), TESTS);
}

fn kelemen() -> SmallStep {
    SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap())
}

fn gaussian() -> SmallStep {
    SmallStep::new(SmallMutation::gaussian(0.01).unwrap())
}

fn pssmlt() -> PssmltProposal {
    PssmltProposal::new(kelemen(), 0.3).unwrap()
}

/// The start on `Stripes`: `u0 = 0.09` lies outside the stripes, 0.028 from the stripe
/// `[15/16, 1/16)` that straddles the seam, and `u1 = 0.09` on a low band: candidates that
/// enter the stripe read `u1`, which the chain stopped reading, and are mostly rejected.
const STRIPES_START: [f64; 2] = [0.09, 0.09];

/// The start on the roulette path: `u0` stops the path (a stop cell 1/64 from a continuation
/// cell); the remaining coordinates are stored but unread, so candidates that extend the path
/// read them stale. The target is limited to 8 vertices, so no chain reads past the stored
/// coordinates (eager mutation perturbs exactly those).
const ROULETTE_START: [f64; 8] = [0.047, 0.55, 0.3, 0.8, 0.05, 0.6, 0.1, 0.9];

/// The default roulette path limited to 8 vertices.
fn roulette() -> RoulettePath {
    RoulettePath::new(8, [2.6, 2.0, 0.05, 0.05], 8, 0).unwrap()
}

#[test]
fn lazy_equals_eager_with_rejections_stripes_kelemen() {
    let what = "stripes / Kelemen";
    lazy_equals_eager(
        what,
        &Stripes::default(),
        kelemen(),
        &STRIPES_START,
        CHAINS,
        1,
    );
}

#[test]
fn lazy_equals_eager_with_rejections_stripes_gaussian() {
    let what = "stripes / Gaussian 0.01";
    lazy_equals_eager(
        what,
        &Stripes::default(),
        gaussian(),
        &STRIPES_START,
        CHAINS,
        2,
    );
}

#[test]
fn lazy_equals_eager_with_rejections_stripes_pssmlt() {
    let what = "stripes / PSSMLT (Kelemen, p_large 0.3)";
    lazy_equals_eager(
        what,
        &Stripes::default(),
        pssmlt(),
        &STRIPES_START,
        CHAINS_MIXTURE,
        3,
    );
}

#[test]
fn lazy_equals_eager_with_rejections_roulette_kelemen() {
    let what = "roulette / Kelemen";
    lazy_equals_eager(what, &roulette(), kelemen(), &ROULETTE_START, CHAINS, 4);
}

#[test]
fn lazy_equals_eager_with_rejections_roulette_gaussian() {
    let what = "roulette / Gaussian 0.01";
    lazy_equals_eager(what, &roulette(), gaussian(), &ROULETTE_START, CHAINS, 5);
}

#[test]
fn lazy_equals_eager_with_rejections_roulette_pssmlt() {
    let what = "roulette / PSSMLT (Kelemen, p_large 0.3)";
    lazy_equals_eager(what, &roulette(), pssmlt(), &ROULETTE_START, CHAINS, 6);
}
