//! The correctness harness: checks that a kernel leaves its target invariant (feature `testing`).
//!
//! Four complementary checks (docs/architecture.md, "Using the correctness harness from another
//! crate"), generic over any
//! [`Target`](crate::Target) and [`Kernel`](crate::Kernel), so the `pss`, `pathspace` and
//! `render` crates run them on their own kernels:
//!
//! 1. **Pairwise detailed balance** ([`assert_pairwise_balance`]): for random paths (pairs,
//!    and triples for two-stage kernels) drawn by a proptest strategy, the kernel's forward
//!    and reverse probability flows agree. Companions check proposals directly:
//!    [`assert_symmetric_proposal`] and [`assert_hastings_consistent`].
//! 2. **Exact finite-state check** ([`assert_finite_state_balance`]): the kernel discretised
//!    on a grid is a stochastic matrix `K` with `diag(pi) K` symmetric and `pi K = pi` to
//!    `1e-12`. Deterministic; catches a wrong acceptance formula exactly.
//! 3. **Stationarity from exact starts** ([`stationarity_test`], [`toy_stationarity_test`]):
//!    N independent exact draws from `pi`, k kernel steps each, chi-square of the final
//!    states against exact bin probabilities, with the statistic and p-value in a
//!    [`ChiSquareReport`]; [`ChiSquareReport::assert_passes`] applies `alpha = 0.01` with a
//!    Sidak correction for the number of tests in a file.
//! 4. **Splat weights** ([`splat_weight_test`], [`toy_splat_weight_test`]): N exact starts,
//!    ONE step each, the splat-weighted histogram of what the step reported to its
//!    [`Observer`](crate::Observer) compared with `N pi(bin)` by a chi-square statistic whose
//!    covariance takes its shape from the weights and its scale from `pi` (weights need not
//!    sum to 1; [`SplatMoments::test`]): the observer contract "the expected splat of one
//!    step from x equals `E[h(X') | X = x]`".
//!
//! Two-sample tests ([`chi_square_two_sample`], [`ks_two_sample`]) compare two samplers when the reference law is known only through a second sampler.
//!
//! [`broken`] holds negative controls (a lie about symmetry, a missing Hastings term, forced
//! acceptance, a dropped current-state splat) that must *fail* these checks, and
//! [`AsymmetricWalk`] / [`ThresholdSelection`] are test proposals with exact densities.
//!
//! # Example
//! ```
//! use mcmc_core::testing::{
//!     assert_finite_state_balance, assert_pairwise_balance, grid_centres, toy_stationarity_test,
//!     PairwiseParams, StationarityParams,
//! };
//! use mcmc_core::toy::{ToyTarget, UniformMixture};
//! use mcmc_core::{GaussianRandomWalk, Mh};
//!
//! let target = UniformMixture::rioux_lavoie2020();
//! let kernel = Mh::new(GaussianRandomWalk::new(0.3).unwrap());
//! // (1) pairwise detailed balance for random pairs in [-0.2, 1.1).
//! let states = proptest::collection::vec(-0.2..1.1f64, 1);
//! assert_pairwise_balance(&target, &kernel, states, &PairwiseParams::with_seed(1));
//! // (2) the exact finite-state check on 22 cells.
//! let (lo, hi) = target.bounding_box();
//! let (cells, volume) = grid_centres(&lo, &hi, &[22]);
//! assert_finite_state_balance(&target, &kernel, &cells, volume);
//! // (3) stationarity from 2000 exact starts, 10 steps each.
//! let report = toy_stationarity_test(&target, &kernel, &StationarityParams::new(2000, 10, 1));
//! report.assert_passes("MH on the uniform mixture", 1);
//! ```

mod allocations;
pub mod broken;
pub mod chi_square;
mod finite_state;
mod fixtures;
mod pairwise;
mod splat_moments;
mod splat_statistic;
mod splat_weights;
mod stationarity;
mod two_sample;

pub use allocations::CountingAllocator;
pub use broken::{
    ForcedAcceptance, MhWithoutHastings, MisWithStaleProbability, MisWithoutLargeStepTerm,
    SplatFinalState, TreatedAsSymmetric, WithoutCurrentSplat,
};
pub use chi_square::{chi_square_test, sidak_alpha, ChiSquareReport, ALPHA};
pub use finite_state::{
    assert_finite_state_balance, finite_state_check, grid_centres, FiniteStateReport,
    FINITE_STATE_TOLERANCE,
};
pub use fixtures::{AsymmetricWalk, LargeStepWalk, ThresholdSelection};
pub use pairwise::{
    assert_hastings_consistent, assert_pairwise_balance, assert_path_balance,
    assert_symmetric_proposal, log_values_agree, path_flows, PairwiseParams, PairwiseReport,
};
pub use splat_moments::SplatMoments;
pub use splat_statistic::{SplatWeightReport, DETERMINISTIC_TOLERANCE};
pub use splat_weights::{
    splat_moments, splat_weight_test, toy_splat_moments, toy_splat_weight_test, SplatParams,
    SPLAT_MIN_EXPECTED,
};
pub use stationarity::{
    chi_square_of_states, stationarity_test, toy_stationarity_test, ExactBins, FnBins,
    StationarityParams,
};
pub use two_sample::{
    chi_square_two_sample, kolmogorov_survival, ks_one_sample, ks_two_sample, KsReport,
};
