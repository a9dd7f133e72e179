//! Stationarity from exact starts: N independent exact draws, k kernel steps each, chi-square.
//!
//! If `x_0 ~ pi` exactly and the kernel leaves `pi` invariant, then `x_k ~ pi` exactly for
//! every `k`. Running N independent chains from independent exact draws therefore gives N
//! *independent* draws from `pi` after k steps, and a plain chi-square goodness-of-fit test
//! applies with no autocorrelation correction and no burn-in (docs/architecture.md, "Using the
//! correctness harness from another crate"). Under the hypothesis the p-value is uniform, so a fixed level `alpha` bounds the
//! false-failure probability; a kernel that does not preserve `pi` drifts away from it, and
//! with enough steps and starts the statistic grows without bound.

use rand::SeedableRng;
use rand_pcg::Pcg64;

use super::chi_square::{chi_square_test, ChiSquareReport, MIN_EXPECTED};
use crate::controller::NoAdaptation;
use crate::kernel::Kernel;
use crate::seed::chain_seed;
use crate::target::Target;
use crate::toy::{Bins, ToyTarget};
use crate::Chain;

/// A partition of a state space into bins with exact probabilities under the target.
pub trait ExactBins<S: ?Sized> {
    /// The exact probability of each bin (summing to 1).
    fn probabilities(&self) -> &[f64];
    /// The bin containing `x` (`< probabilities().len()`).
    fn bin_of(&self, x: &S) -> usize;
}

impl ExactBins<Vec<f64>> for Bins {
    fn probabilities(&self) -> &[f64] {
        Bins::probabilities(self)
    }
    fn bin_of(&self, x: &Vec<f64>) -> usize {
        Bins::bin_of(self, x)
    }
}

/// Bins given by a closure, for states other than `Vec<f64>` (e.g. primary-sample-space
/// states in the `pss` crate).
#[derive(Clone, Debug)]
pub struct FnBins<F> {
    /// The exact probability of each bin.
    pub probabilities: Vec<f64>,
    /// The assignment `x -> bin`.
    pub bin_of: F,
}

impl<S: ?Sized, F: Fn(&S) -> usize> ExactBins<S> for FnBins<F> {
    fn probabilities(&self) -> &[f64] {
        &self.probabilities
    }
    fn bin_of(&self, x: &S) -> usize {
        (self.bin_of)(x)
    }
}

/// Size and seed of a stationarity test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StationarityParams {
    /// Number of independent exact starts `N`.
    pub starts: usize,
    /// Kernel steps per start `k`.
    pub steps: u64,
    /// Seed; start `i` uses `Pcg64::seed_from_u64(chain_seed(seed, i))` for both its exact
    /// draw and its steps.
    pub seed: u64,
    /// Minimum expected count per bin after pooling (default 5).
    pub min_expected: f64,
}

impl StationarityParams {
    /// `starts` exact starts, `steps` steps each, with `seed`; bins pooled to expected
    /// count `>= 5`.
    #[must_use]
    pub const fn new(starts: usize, steps: u64, seed: u64) -> Self {
        Self {
            starts,
            steps,
            seed,
            min_expected: MIN_EXPECTED,
        }
    }
}

/// Runs `params.starts` independent chains of `kernel` (a fresh clone each, no adaptation),
/// each from an exact draw `sample_exact(rng)` and for `params.steps` steps, and tests the
/// final states against `bins` with Pearson's chi-square.
///
/// # Panics
/// If a chain reports an error (a NaN density is a bug in the target or kernel) or an exact
/// draw has zero density.
pub fn stationarity_test<T, K, B, F>(
    target: &T,
    kernel: &K,
    mut sample_exact: F,
    bins: &B,
    params: &StationarityParams,
) -> ChiSquareReport
where
    T: Target,
    K: Kernel<T> + Clone,
    B: ExactBins<T::State> + ?Sized,
    F: FnMut(&mut Pcg64) -> T::State,
{
    let mut counts = vec![0u64; bins.probabilities().len()];
    for i in 0..params.starts {
        let mut rng = Pcg64::seed_from_u64(chain_seed(params.seed, i as u64));
        let start = sample_exact(&mut rng);
        let mut chain = Chain::new(target, kernel.clone(), NoAdaptation, rng, start)
            .unwrap_or_else(|e| panic!("exact start {i} is not a valid chain start: {e}"));
        if let Err(e) = chain.run(params.steps, &mut ()) {
            panic!("chain {i} failed: {e}");
        }
        counts[bins.bin_of(chain.state())] += 1;
    }
    chi_square_test(&counts, bins.probabilities(), params.min_expected)
}

/// [`stationarity_test`] for a toy target, with its exact sampler and default bins.
pub fn toy_stationarity_test<T, K>(
    target: &T,
    kernel: &K,
    params: &StationarityParams,
) -> ChiSquareReport
where
    T: ToyTarget,
    K: Kernel<T> + Clone,
{
    stationarity_test(
        target,
        kernel,
        |rng| target.sample_exact(rng),
        &target.bins(),
        params,
    )
}

/// Chi-square of already computed states (from a custom driver) against `bins`.
pub fn chi_square_of_states<'a, S, B, I>(states: I, bins: &B, min_expected: f64) -> ChiSquareReport
where
    S: 'a + ?Sized,
    B: ExactBins<S> + ?Sized,
    I: IntoIterator<Item = &'a S>,
{
    let mut counts = vec![0u64; bins.probabilities().len()];
    for x in states {
        counts[bins.bin_of(x)] += 1;
    }
    chi_square_test(&counts, bins.probabilities(), min_expected)
}
