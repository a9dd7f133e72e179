//! Splat-weight check: one kernel step from exact starts, a splat-weighted histogram, against pi.
//!
//! # What it checks
//! The [`Observer`] contract: for every function `h` of the state, the expected splat of one
//! step from `x`, `E[sum_j w_j h(s_j) | X = x]` over the samples `s_j` the step reports with
//! weights `w_j`, equals `E[h(X') | X = x]`, the expectation at the next state. If also the
//! kernel leaves `pi` invariant, then for `X ~ pi` the expected splat is `E_pi[h]`. Taking
//! `h = 1_b` for each bin `b` of a partition with exact probabilities `p_b`:
//!
//! ```text
//! E[c_b] = p_b,   c_b = sum_j w_j 1[s_j in b]   (one step from an exact start X ~ pi).
//! ```
//!
//! This is the estimator's unbiasedness, which no test of the chain's *states* sees: a kernel
//! can move correctly and splat wrongly (dropping the `1 - a` weight of the current state),
//! or splat "correctly" for a wrong move (weight 1 on a force-accepted candidate).
//!
//! # The statistic
//! Start `i` (of `N` independent exact starts, one step each) contributes a vector `c_i` of
//! the weight it splatted into each pooled bin ([`splat_moments`] gathers their first, second
//! and third moments). The weights need not sum to 1 (delayed rejection's unbiased scheme sums
//! to 1 only in expectation), so no multinomial formula applies; [`SplatMoments::test`]
//! compares the mean with `p` by a chi-square statistic whose covariance has the shape of
//! the observed weights and the scale of the hypothesis (its docs derive it, and say why the
//! plain sample covariance is anti-conservative at these sizes).
//!
//! Bins are pooled until `N p_b >= min_expected` ([`SPLAT_MIN_EXPECTED`] = 20 by default:
//! each bin's mean weight is then an average over at least ~20 non-zero contributions, so
//! the normal approximation is reasonable). Weight splatted into a bin of probability 0
//! makes the test fail outright.

use rand::SeedableRng;
use rand_pcg::Pcg64;

use super::chi_square::pool;
use super::splat_moments::SplatMoments;
use super::splat_statistic::SplatWeightReport;
use super::stationarity::ExactBins;
use crate::controller::NoAdaptation;
use crate::kernel::{Kernel, Observer};
use crate::seed::chain_seed;
use crate::target::{Sample, Target};
use crate::toy::ToyTarget;
use crate::Chain;

/// Default minimum expected splat weight `N p_b` per pooled bin.
pub const SPLAT_MIN_EXPECTED: f64 = 20.0;

/// Size and seed of a splat-weight test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatParams {
    /// Number of independent exact starts `N` (one kernel step each).
    pub starts: usize,
    /// Seed; start `i` uses `Pcg64::seed_from_u64(chain_seed(seed, i))` for its exact draw
    /// and its step.
    pub seed: u64,
    /// Minimum expected weight `N p_b` per bin after pooling (default
    /// [`SPLAT_MIN_EXPECTED`]).
    pub min_expected: f64,
}

impl SplatParams {
    /// `starts` exact starts with `seed`; bins pooled to expected weight `>= 20`.
    #[must_use]
    pub const fn new(starts: usize, seed: u64) -> Self {
        Self {
            starts,
            seed,
            min_expected: SPLAT_MIN_EXPECTED,
        }
    }
}

/// Records one step's splats as a sparse vector over pooled bins.
struct Recorder<'a, B: ?Sized> {
    bins: &'a B,
    pooled_of: &'a [Option<usize>],
    row: Vec<(usize, f64)>,
    total: f64,
    impossible: f64,
}

impl<S, P, B: ExactBins<S> + ?Sized> Observer<S, P> for Recorder<'_, B> {
    fn splat(&mut self, sample: &Sample<S, P>, weight: f64) {
        if weight == 0.0 {
            return;
        }
        self.total += weight;
        match self.pooled_of[self.bins.bin_of(&sample.state)] {
            Some(k) => match self.row.iter_mut().find(|(j, _)| *j == k) {
                Some(entry) => entry.1 += weight,
                None => self.row.push((k, weight)),
            },
            None => self.impossible += weight.abs(),
        }
    }
}

/// Runs one step of `kernel` (a fresh clone, no adaptation) from each of `params.starts`
/// independent exact draws `sample_exact(rng)` and gathers the moments of the per-start
/// splat vectors over `bins`, pooled to expected weight `>= params.min_expected`.
///
/// # Panics
/// If an exact draw has zero density, or a step reports an error (NaN density).
pub fn splat_moments<T, K, B, F>(
    target: &T,
    kernel: &K,
    mut sample_exact: F,
    bins: &B,
    params: &SplatParams,
) -> SplatMoments
where
    T: Target,
    K: Kernel<T> + Clone,
    B: ExactBins<T::State> + ?Sized,
    F: FnMut(&mut Pcg64) -> T::State,
{
    let n = params.starts;
    let probabilities = bins.probabilities();
    let expected: Vec<f64> = probabilities.iter().map(|p| p * n as f64).collect();
    let groups = pool(&vec![0; expected.len()], &expected, params.min_expected).groups;
    let mut pooled_of = vec![None; expected.len()];
    for (k, group) in groups.iter().enumerate() {
        for &b in group {
            pooled_of[b] = Some(k);
        }
    }
    let p: Vec<f64> = groups
        .iter()
        .map(|g| g.iter().map(|&b| probabilities[b]).sum())
        .collect();
    let mut moments = SplatMoments::new(groups, p);
    let mut recorder = Recorder {
        bins,
        pooled_of: &pooled_of,
        row: Vec::new(),
        total: 0.0,
        impossible: 0.0,
    };
    for i in 0..n {
        let mut rng = Pcg64::seed_from_u64(chain_seed(params.seed, i as u64));
        let start = sample_exact(&mut rng);
        let mut chain = Chain::new(target, kernel.clone(), NoAdaptation, rng, start)
            .unwrap_or_else(|e| panic!("exact start {i} is not a valid chain start: {e}"));
        recorder.row.clear();
        recorder.total = 0.0;
        recorder.impossible = 0.0;
        if let Err(e) = chain.step(&mut recorder) {
            panic!("step from start {i} failed: {e}");
        }
        moments.push(&recorder.row, recorder.total, recorder.impossible);
    }
    moments
}

/// Runs one step of `kernel` (a fresh clone, no adaptation) from each of `params.starts`
/// independent exact draws `sample_exact(rng)`, accumulates the splat-weighted histogram over
/// `bins`, and tests its mean against the bin probabilities ([`SplatMoments::test`], whose
/// docs derive the statistic).
///
/// # Panics
/// If an exact draw has zero density, or a step reports an error (NaN density).
pub fn splat_weight_test<T, K, B, F>(
    target: &T,
    kernel: &K,
    sample_exact: F,
    bins: &B,
    params: &SplatParams,
) -> SplatWeightReport
where
    T: Target,
    K: Kernel<T> + Clone,
    B: ExactBins<T::State> + ?Sized,
    F: FnMut(&mut Pcg64) -> T::State,
{
    splat_moments(target, kernel, sample_exact, bins, params).test()
}

/// [`splat_weight_test`] for a toy target, with its exact sampler and default bins.
pub fn toy_splat_weight_test<T, K>(
    target: &T,
    kernel: &K,
    params: &SplatParams,
) -> SplatWeightReport
where
    T: ToyTarget,
    K: Kernel<T> + Clone,
{
    toy_splat_moments(target, kernel, params).test()
}

/// [`splat_moments`] for a toy target, with its exact sampler and default bins.
pub fn toy_splat_moments<T, K>(target: &T, kernel: &K, params: &SplatParams) -> SplatMoments
where
    T: ToyTarget,
    K: Kernel<T> + Clone,
{
    splat_moments(
        target,
        kernel,
        |rng| target.sample_exact(rng),
        &target.bins(),
        params,
    )
}
