//! The exact finite-state check: a discretised kernel matrix must be reversible and stationary.
//!
//! The state space is replaced by a grid of cell centres `x_1..x_n` (cell volume `h`), the
//! target by `pi_i proportional to pi(x_i)`, and the kernel by the matrix
//!
//! ```text
//! K_ij = c h exp(log_flow([x_i, x_j]) - log pi(x_i))                         (i != j)
//!      + sum_k c^2 h^2 exp(log_flow([x_i, x_k, x_j]) - log pi(x_i))          (two stages)
//! K_ii = 1 - sum_{j != i} K_ij
//! ```
//!
//! i.e. the kernel's own transition densities (proposal times acceptance, as the kernel
//! computes them in [`Kernel::log_flow`]) integrated by the midpoint rule. The intermediate
//! (rejected) state `x_k` of a two-stage path ranges over *all* grid cells, including those of
//! zero density; the states `x_i`, `x_j` over the cells of positive density.
//!
//! Why this is exact: `pi_i K_ij` is `c h exp(log_flow_ij) / Z`, so `diag(pi) K` is symmetric
//! exactly when the kernel's flows are (detailed balance), whatever the discretisation. The
//! common factor `c < 1` (and `c^2` for the second stage, whose flows balance separately)
//! only rescales off-diagonal entries, which keeps `diag(pi) K` symmetric while making every
//! row's off-diagonal sum at most 1, so `K` is a stochastic matrix and `pi K = pi` follows
//! from symmetry. Both properties are then checked with plain linear algebra to `1e-12`
//! relative to the largest entry: no sampling, so the check never flakes, and a wrong
//! acceptance formula shows up as an asymmetry many orders of magnitude above rounding.
//!
//! For a Green-Mira kernel whose reverse path passes through a fictional state `y*`, the
//! two-stage sum is symmetric only if the map `k -> k*` permutes the grid (a uniform grid on a
//! torus); on a bounded grid check such kernels pairwise instead.

use nalgebra::{DMatrix, DVector};

use crate::kernel::Kernel;
use crate::target::{Sample, SampleOf, Target};

/// Tolerance of the finite-state check, relative to the largest entry.
pub const FINITE_STATE_TOLERANCE: f64 = 1e-12;

/// What the finite-state check measured.
#[derive(Clone, Debug, PartialEq)]
pub struct FiniteStateReport {
    /// Number of states with positive density (the matrix size).
    pub states: usize,
    /// The common scale `c`.
    pub scale: f64,
    /// `max |F_ij - F_ji| / max |F|` with `F = diag(pi) K`.
    pub max_asymmetry: f64,
    /// The pair `(i, j)` (indices into the caller's state list) of the worst asymmetry.
    pub worst_pair: (usize, usize),
    /// `F_ij` and `F_ji` at the worst pair.
    pub worst_flows: (f64, f64),
    /// `max_j |(pi K)_j - pi_j| / max pi`.
    pub max_stationarity_error: f64,
    /// The smallest diagonal entry of `K` (must be `>= 0` for a stochastic matrix).
    pub min_diagonal: f64,
}

/// The centres of a regular grid on the box `[lo, hi)` with `cells[d]` cells along axis `d`
/// (first axis slowest), and the cell volume.
#[must_use]
pub fn grid_centres(lo: &[f64], hi: &[f64], cells: &[usize]) -> (Vec<Vec<f64>>, f64) {
    let dim = lo.len();
    assert!(hi.len() == dim && cells.len() == dim && dim > 0);
    let width: Vec<f64> = (0..dim)
        .map(|d| (hi[d] - lo[d]) / cells[d] as f64)
        .collect();
    let volume = width.iter().product();
    let total: usize = cells.iter().product();
    let centres = (0..total)
        .map(|mut flat| {
            let mut x = vec![0.0; dim];
            for d in (0..dim).rev() {
                let i = flat % cells[d];
                flat /= cells[d];
                x[d] = lo[d] + (i as f64 + 0.5) * width[d];
            }
            x
        })
        .collect();
    (centres, volume)
}

/// Builds the discretised kernel on `states` (cell centres of common volume `cell_volume`)
/// and measures the asymmetry of `diag(pi) K` and the error of `pi K = pi`.
///
/// # Panics
/// If no state has positive density, or a flow is NaN.
pub fn finite_state_check<T, K>(
    target: &T,
    kernel: &K,
    states: &[T::State],
    cell_volume: f64,
) -> FiniteStateReport
where
    T: Target,
    K: Kernel<T>,
{
    let all: Vec<SampleOf<T>> = states
        .iter()
        .map(|s| Sample::evaluate(target, s.clone()))
        .collect();
    let support: Vec<usize> = (0..all.len())
        .filter(|&i| all[i].log_density > f64::NEG_INFINITY)
        .collect();
    let n = support.len();
    assert!(n > 0, "finite-state check: no state has positive density");
    let two_stage = kernel.stages() >= 2;
    let h = cell_volume;

    // Unscaled stage-1 and stage-2 transition masses q1[i][j], q2[i][j] (without c).
    let mut q1 = DMatrix::<f64>::zeros(n, n);
    let mut q2 = DMatrix::<f64>::zeros(n, n);
    let mut path = vec![all[0].clone(), all[0].clone()];
    let mut path3 = vec![all[0].clone(), all[0].clone(), all[0].clone()];
    for (a, &i) in support.iter().enumerate() {
        let log_pi_i = all[i].log_density;
        for (b, &j) in support.iter().enumerate() {
            if a == b {
                continue;
            }
            path[0].clone_from(&all[i]);
            path[1].clone_from(&all[j]);
            let f = kernel.log_flow(target, &path);
            assert!(!f.is_nan(), "NaN flow from state {i} to {j}");
            q1[(a, b)] = h * (f - log_pi_i).exp();
            if two_stage {
                let mut sum = 0.0;
                path3[0].clone_from(&all[i]);
                path3[2].clone_from(&all[j]);
                for mid in &all {
                    path3[1].clone_from(mid);
                    let f = kernel.log_flow(target, &path3);
                    assert!(!f.is_nan(), "NaN two-stage flow from state {i} to {j}");
                    sum += h * h * (f - log_pi_i).exp();
                }
                q2[(a, b)] = sum;
            }
        }
    }
    let max_row = |m: &DMatrix<f64>| {
        m.row_iter()
            .map(|r| r.iter().sum::<f64>())
            .fold(0.0f64, f64::max)
    };
    // c r1 + c^2 r2 <= 1/2 + 1/4 < 1 for every row.
    let scale = 0.5 / 1f64.max(max_row(&q1)).max(max_row(&q2).sqrt());
    let mut k = q1 * scale + q2 * (scale * scale);
    for a in 0..n {
        let off: f64 = k.row(a).iter().sum();
        k[(a, a)] = 1.0 - off;
    }
    let min_diagonal = (0..n).map(|a| k[(a, a)]).fold(f64::INFINITY, f64::min);

    // pi normalised over the support.
    let max_log = support
        .iter()
        .map(|&i| all[i].log_density)
        .fold(f64::NEG_INFINITY, f64::max);
    let mut pi = DVector::<f64>::from_iterator(
        n,
        support
            .iter()
            .map(|&i| (all[i].log_density - max_log).exp()),
    );
    let z = pi.sum();
    pi /= z;

    let flow = DMatrix::from_diagonal(&pi) * &k;
    let max_flow = flow.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut max_asymmetry = 0.0;
    let mut worst = (0, 0);
    for a in 0..n {
        for b in a + 1..n {
            let d = (flow[(a, b)] - flow[(b, a)]).abs() / max_flow;
            if d > max_asymmetry {
                max_asymmetry = d;
                worst = (a, b);
            }
        }
    }
    let pi_k = k.transpose() * &pi;
    let max_pi = pi.max();
    let max_stationarity_error = (0..n)
        .map(|j| (pi_k[j] - pi[j]).abs() / max_pi)
        .fold(0.0f64, f64::max);
    FiniteStateReport {
        states: n,
        scale,
        max_asymmetry,
        worst_pair: (support[worst.0], support[worst.1]),
        worst_flows: (flow[worst], flow[(worst.1, worst.0)]),
        max_stationarity_error,
        min_diagonal,
    }
}

/// Runs [`finite_state_check`] and asserts `diag(pi) K` symmetric and `pi K = pi` to
/// [`FINITE_STATE_TOLERANCE`] relative to the largest entry, and `K` stochastic.
///
/// # Panics
/// With the worst asymmetric pair (states and flows) in the message.
#[track_caller]
pub fn assert_finite_state_balance<T, K>(
    target: &T,
    kernel: &K,
    states: &[T::State],
    cell_volume: f64,
) -> FiniteStateReport
where
    T: Target,
    K: Kernel<T>,
{
    let r = finite_state_check(target, kernel, states, cell_volume);
    let (i, j) = r.worst_pair;
    assert!(
        r.max_asymmetry <= FINITE_STATE_TOLERANCE,
        "finite-state check: diag(pi) K is not symmetric: worst relative asymmetry {:.3e} \
         between state {i} = {:?} and state {j} = {:?} (flows {:.6e} vs {:.6e}); \
         pi K = pi error {:.3e}; {} states",
        r.max_asymmetry,
        states[i],
        states[j],
        r.worst_flows.0,
        r.worst_flows.1,
        r.max_stationarity_error,
        r.states
    );
    assert!(
        r.max_stationarity_error <= FINITE_STATE_TOLERANCE,
        "finite-state check: pi K != pi: relative error {:.3e} ({} states)",
        r.max_stationarity_error,
        r.states
    );
    assert!(
        r.min_diagonal >= 0.0,
        "finite-state check: K is not stochastic ({r:?})"
    );
    r
}
