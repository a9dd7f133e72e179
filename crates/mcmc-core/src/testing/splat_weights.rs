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
//! Start `i` (of `N` independent exact starts, one step each) contributes a vector
//! `c_i = (c_i1, ..., c_iB)` over the `B` pooled bins. The `c_i` are i.i.d. with mean `mu`
//! and some covariance `Sigma` that depends on the kernel: MH's weights `(1 - a, a)` sum to 1
//! at every step, but delayed rejection's unbiased scheme sums to 1 only in expectation and
//! may leave `[0, 1]`, so no multinomial formula applies. The variance is therefore taken
//! from the data: with the sample mean `m` and sample covariance
//! `S = sum_i (c_i - m)(c_i - m)^T / (N - 1)`, the multivariate central limit theorem gives
//! `sqrt(N) (m - mu) -> Normal(0, Sigma)`, and since `S -> Sigma`, Hotelling's statistic
//!
//! ```text
//! T^2 = N (m - p)^T S^+ (m - p)  ->  chi^2 with rank(S) degrees of freedom
//! ```
//!
//! under the hypothesis `mu = p`. (Hotelling's exact law under normality is
//! `T^2 (N - r) / ((N - 1) r) ~ F(r, N - r)`; with `N >= 10^4` and `r <= 100` the chi-square
//! p-value differs from it by under 1% of itself.) `S^+` is the pseudo-inverse over the
//! eigen-directions of `S` with eigenvalue above `1e-10` times the largest. A direction with
//! (numerically) zero sample variance is one in which every start contributed exactly the
//! same amount, e.g. the total weight when weights always sum to 1; there the deviation
//! `v^T (m - p)` is deterministic, and it must vanish to within [`DETERMINISTIC_TOLERANCE`]
//! (rounding and the accuracy of the bin probabilities), else the statistic is infinite.
//!
//! Bins are pooled until `N p_b >= min_expected` ([`SPLAT_MIN_EXPECTED`] = 20 by default:
//! each bin's mean weight is then an average over at least ~20 non-zero contributions, so
//! the normal approximation and the covariance estimate are reasonable). Weight splatted into
//! a bin of probability 0 makes the test fail outright.

use std::fmt;

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::SeedableRng;
use rand_pcg::Pcg64;

use super::chi_square::{pool, sidak_alpha, survival, ALPHA};
use super::stationarity::ExactBins;
use crate::controller::NoAdaptation;
use crate::kernel::{Kernel, Observer};
use crate::seed::chain_seed;
use crate::target::{Sample, Target};
use crate::toy::ToyTarget;
use crate::Chain;

/// Default minimum expected splat weight `N p_b` per pooled bin.
pub const SPLAT_MIN_EXPECTED: f64 = 20.0;

/// Largest deviation of the mean splat from `p` tolerated along a direction in which every
/// start contributed exactly the same (see the module docs): far above rounding (`1e-15`
/// per operation) and the accuracy of exact bin probabilities (`1e-12`), far below any real
/// bias.
pub const DETERMINISTIC_TOLERANCE: f64 = 1e-9;

/// Relative eigenvalue below which a direction of the sample covariance counts as having
/// zero variance.
const RELATIVE_EIGEN_FLOOR: f64 = 1e-10;

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

/// The outcome of a splat-weight test.
#[derive(Clone, Debug, PartialEq)]
pub struct SplatWeightReport {
    /// Hotelling's `T^2` (`+inf` for weight in impossible bins or a deterministic bias).
    pub statistic: f64,
    /// Degrees of freedom: the rank of the sample covariance of the per-start vectors.
    pub degrees_of_freedom: usize,
    /// `P(chi^2_dof >= statistic)`: uniform on `[0, 1]` under the hypothesis (asymptotically).
    pub p_value: f64,
    /// Number of starts `N`.
    pub starts: usize,
    /// Mean over starts of the total weight one step splatted (1 for MH).
    pub mean_total_weight: f64,
    /// Total absolute weight splatted into bins of probability 0.
    pub impossible_weight: f64,
    /// The pooled bin whose mean weight deviates most (in standard errors) from its
    /// probability: (original bins, total weight splatted there, expected `N p`, z-score).
    pub worst_bin: Option<(Vec<usize>, f64, f64, f64)>,
}

impl fmt::Display for SplatWeightReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "T^2 = {:.3} with {} dof, p = {:.3e} ({} starts, mean total weight {:.5}, {:.3} \
             weight in zero-probability bins",
            self.statistic,
            self.degrees_of_freedom,
            self.p_value,
            self.starts,
            self.mean_total_weight,
            self.impossible_weight
        )?;
        if let Some((bins, w, e, z)) = &self.worst_bin {
            write!(
                f,
                "; worst bin(s) {bins:?}: weight {w:.1}, expected {e:.1}, z = {z:.2}"
            )?;
        }
        write!(f, ")")
    }
}

impl SplatWeightReport {
    /// True if the test rejects at level `alpha` (also when it has no degree of freedom).
    #[must_use]
    pub fn rejects(&self, alpha: f64) -> bool {
        self.degrees_of_freedom == 0 || self.p_value.is_nan() || self.p_value < alpha
    }

    /// Panics unless the test passes at the Sidak-corrected level for `tests_in_file` tests
    /// sharing the overall level [`ALPHA`].
    #[track_caller]
    pub fn assert_passes(&self, what: &str, tests_in_file: usize) {
        let level = sidak_alpha(ALPHA, tests_in_file);
        assert!(
            !self.rejects(level),
            "{what}: splat-weight test rejects at level {level:.2e} (alpha = {ALPHA}, Sidak \
             over {tests_in_file} tests): {self}"
        );
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
/// independent exact draws `sample_exact(rng)`, accumulates the splat-weighted histogram over
/// `bins`, and tests its mean against the bin probabilities with Hotelling's statistic (see
/// the module docs for the derivation).
///
/// # Panics
/// If an exact draw has zero density, or a step reports an error (NaN density).
pub fn splat_weight_test<T, K, B, F>(
    target: &T,
    kernel: &K,
    mut sample_exact: F,
    bins: &B,
    params: &SplatParams,
) -> SplatWeightReport
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
    let dim = groups.len();
    let mut sum = DVector::<f64>::zeros(dim);
    let mut cross = DMatrix::<f64>::zeros(dim, dim);
    let (mut total, mut impossible) = (0.0, 0.0);
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
        total += recorder.total;
        impossible += recorder.impossible;
        for &(j, cj) in &recorder.row {
            sum[j] += cj;
            for &(k, ck) in &recorder.row {
                cross[(j, k)] += cj * ck;
            }
        }
    }
    let nf = n as f64;
    let mean = &sum / nf;
    let covariance = (cross - &mean * mean.transpose() * nf) / (nf - 1.0).max(1.0);
    let deviation = &mean - DVector::from_vec(p.clone());
    let (statistic, degrees_of_freedom) = hotelling(&covariance, &deviation, nf);
    let statistic = if impossible > 0.0 {
        f64::INFINITY
    } else {
        statistic
    };
    let p_value = if degrees_of_freedom == 0 {
        1.0
    } else {
        survival(statistic, degrees_of_freedom as f64)
    };
    let worst_bin = (0..dim)
        .map(|k| {
            let se = (covariance[(k, k)] / nf).sqrt();
            let z = if se > 0.0 {
                deviation[k] / se
            } else if deviation[k].abs() > DETERMINISTIC_TOLERANCE {
                f64::INFINITY.copysign(deviation[k])
            } else {
                0.0
            };
            (k, z)
        })
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(k, z)| (groups[k].clone(), sum[k], nf * p[k], z));
    SplatWeightReport {
        statistic,
        degrees_of_freedom,
        p_value,
        starts: n,
        mean_total_weight: total / nf,
        impossible_weight: impossible,
        worst_bin,
    }
}

/// `N d^T S^+ d` over the eigen-directions of `S` with non-negligible variance, and their
/// number; `+inf` if `d` has a component above [`DETERMINISTIC_TOLERANCE`] along a direction
/// without variance.
fn hotelling(covariance: &DMatrix<f64>, deviation: &DVector<f64>, n: f64) -> (f64, usize) {
    let eigen = SymmetricEigen::new(covariance.clone());
    let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut statistic = 0.0;
    let mut rank = 0;
    for (k, &lambda) in eigen.eigenvalues.iter().enumerate() {
        let z = eigen.eigenvectors.column(k).dot(deviation);
        if largest > 0.0 && lambda > RELATIVE_EIGEN_FLOOR * largest {
            statistic += n * z * z / lambda;
            rank += 1;
        } else if z.abs() > DETERMINISTIC_TOLERANCE {
            statistic = f64::INFINITY;
        }
    }
    (statistic, rank)
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
    splat_weight_test(
        target,
        kernel,
        |rng| target.sample_exact(rng),
        &target.bins(),
        params,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hotelling_is_chi_square_in_whitened_coordinates() {
        // Diagonal covariance: T^2 is the sum of squared z-scores.
        let s = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 1.0]));
        let d = DVector::from_vec(vec![0.02, -0.01]);
        let (t, r) = hotelling(&s, &d, 10_000.0);
        assert_eq!(r, 2);
        assert!((t - (1.0 + 1.0)).abs() < 1e-12, "{t}");
        // A zero-variance direction is dropped when the mean agrees there, and fatal when not.
        let s = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 0.0]));
        assert_eq!(hotelling(&s, &d, 10_000.0).0, f64::INFINITY);
        let d = DVector::from_vec(vec![0.02, 0.0]);
        let (t, r) = hotelling(&s, &d, 10_000.0);
        assert_eq!(r, 1);
        assert!((t - 1.0).abs() < 1e-12);
    }
}
