//! PSS targets with exact samplers and exact bins, and the harness checks run on them.

use mcmc_core::testing::{
    chi_square_test, splat_weight_test, stationarity_test, ChiSquareReport, ExactBins, SplatParams,
    SplatWeightReport, StationarityParams,
};
use mcmc_core::{Kernel, Target};
use rand::{Rng, SeedableRng};

use crate::PssState;

/// A partition of primary sample space into bins with exact probabilities under a target.
///
/// The assignment receives the state *as the chain holds it*, possibly with stale (not yet
/// brought up to date) coordinates: assignments therefore read through a clone
/// (`x.clone().get(i)`), which brings the coordinates they look at up to date exactly as a
/// target evaluation would.
pub struct PssBins {
    probabilities: Vec<f64>,
    assign: Box<AssignFn>,
}

/// The bin assignment function of [`PssBins`].
type AssignFn = dyn Fn(&PssState) -> usize + Send + Sync;

impl std::fmt::Debug for PssBins {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PssBins")
            .field("probabilities", &self.probabilities)
            .finish_non_exhaustive()
    }
}

impl PssBins {
    /// Bins from their exact probabilities (summing to 1) and an assignment `x -> bin`
    /// (`< probabilities.len()`).
    pub fn new(
        probabilities: Vec<f64>,
        assign: impl Fn(&PssState) -> usize + Send + Sync + 'static,
    ) -> Self {
        debug_assert!(probabilities.iter().all(|p| *p >= 0.0 && p.is_finite()));
        Self {
            probabilities,
            assign: Box::new(assign),
        }
    }

    /// Number of bins.
    #[must_use]
    pub fn len(&self) -> usize {
        self.probabilities.len()
    }

    /// True if there are no bins.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.probabilities.is_empty()
    }
}

impl ExactBins<PssState> for PssBins {
    fn probabilities(&self) -> &[f64] {
        &self.probabilities
    }

    fn bin_of(&self, x: &PssState) -> usize {
        (self.assign)(x)
    }
}

/// A target on primary sample space whose normalised density is known in closed form, with an
/// exact sampler and exact bins: the PSS counterpart of [`mcmc_core::toy::ToyTarget`].
pub trait ExactPssTarget: Target<State = PssState, Payload = ()> {
    /// A short name for failure messages.
    fn name(&self) -> &'static str;

    /// An exact, independent draw from the target as a *fully materialised* state
    /// ([`PssState::from_values`]): every coordinate the target reads is stored, plus, if the
    /// target documents it, some it does not read (uniform under the target).
    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> PssState;

    /// Bins with exact probabilities (each target documents how they are computed).
    fn bins(&self) -> PssBins;
}

/// Stationarity from exact starts ([`mcmc_core::testing::stationarity_test`]) on an
/// [`ExactPssTarget`]: `params.starts` chains from independent exact draws, `params.steps`
/// steps of `kernel` each, chi-square of the final states against the target's bins.
pub fn pss_stationarity_test<T, K>(
    target: &T,
    kernel: &K,
    params: &StationarityParams,
) -> ChiSquareReport
where
    T: ExactPssTarget,
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

/// The splat-weight check ([`mcmc_core::testing::splat_weight_test`]) on an
/// [`ExactPssTarget`]: one step of `kernel` from each of `params.starts` exact draws.
pub fn pss_splat_weight_test<T, K>(
    target: &T,
    kernel: &K,
    params: &SplatParams,
) -> SplatWeightReport
where
    T: ExactPssTarget,
    K: Kernel<T> + Clone,
{
    splat_weight_test(
        target,
        kernel,
        |rng| target.sample_exact(rng),
        &target.bins(),
        params,
    )
}

/// Chi-square of `samples` exact draws against the target's bins: checks that the exact
/// sampler and the bin probabilities agree (bins pooled to expected count `>= 5`).
pub fn exact_sampler_test<T: ExactPssTarget>(
    target: &T,
    samples: usize,
    seed: u64,
) -> ChiSquareReport {
    let bins = target.bins();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut counts = vec![0u64; bins.len()];
    for _ in 0..samples {
        counts[bins.bin_of(&target.sample_exact(&mut rng))] += 1;
    }
    chi_square_test(&counts, bins.probabilities(), 5.0)
}
