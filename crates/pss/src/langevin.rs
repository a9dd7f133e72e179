//! MALA in primary sample space: the coordinates a Langevin step moves, wrap-around, and the
//! torus displacement ([`mcmc_core::langevin`] holds the kernels and the adaptation).

use mcmc_core::langevin::{LangevinSpace, ProposalGaussian};
use mcmc_core::seed::mix64;
use mcmc_core::torus::wrap;

use crate::state::{Pending, PssState, MAX_STREAMS};

/// Salt of the key a MALA candidate gets (any coordinate it reads beyond the moved ones makes
/// it invalid anyway, so the key only has to differ from the parent's).
const MALA_SALT: u64 = 0x4d41_4c41_5053_5321;

/// The [`LangevinSpace`] of primary sample space: a MALA step moves exactly the *continuous*
/// coordinates the current state's last evaluation read — per stream `s`, the prefix
/// `0..read_counts()[s]` ([`PssState::read_counts`]) without the numbers the evaluation tagged
/// discrete ([`PssState::next_discrete`]: strategy, lobe and light choices, inert lens and
/// time numbers), in the order stream 0 first, then stream 1, ... (the order a
/// [`mcmc_core::DifferentiableTarget`] over [`PssState`] must write its gradient in: one
/// entry per continuous read, [`moved_indices`]). Moved coordinates wrap around the unit
/// torus, and the move's density is the *wrapped* Gaussian
/// ([`ProposalGaussian::log_density_wrapped`]), so a proposal across the seam has the right
/// density both ways (the reference implementation of Luan et al. 2020 wraps every
/// coordinate mod 1 too, and moves only the continuous numbers of a path; docs/methods/mala.md,
/// "Readings and departures").
///
/// # Layouts: read sets and discrete tags
/// The candidate is the current state with the moved coordinates replaced, no lazy mutation
/// attached; discrete and unread coordinates keep their values. A candidate whose evaluation
/// reads a different set of coordinates (a longer or shorter prefix of any stream) *or tags a
/// different set of them discrete* is rejected ([`LangevinSpace::same_layout`]). Write
/// `C(u)` for the continuous coordinates of `u` (a function of `u`: the read set and the tags
/// its evaluation produces). The MALA proposal from `x` is a density on the slice
/// `{y : y_j = x_j for j not in C(x)}` with respect to Lebesgue measure on the coordinates
/// `C(x)`; the reverse proposal from `y` is a density on the slice through `y` over `C(y)`.
/// Both are densities with respect to the same measure on the same slice exactly when
/// `C(y) = C(x)` (then the slices coincide, as `y` agrees with `x` off `C(x)`). Rejecting
/// every candidate with `C(y) != C(x)` makes the kernel a Metropolis-Hastings kernel on each
/// set `{u : C(u) = C, u_j = c_j for j not in C}`, reversible with respect to the target
/// restricted there, hence with respect to the target. Which coordinates are tagged changes
/// only efficiency; that the tags are compared at both ends is what makes it exact (a
/// kernel that skips the comparison moves `C(x)` forward and `C(y)` back, two densities
/// on slices of different dimension: a negative control in the tests). Moving a larger set
/// — say every stored coordinate, including stale ones the state did not read — is *not*
/// exact either (another negative control). Targets must read through [`PssState::begin`],
/// [`PssState::next_sample`] and [`PssState::next_discrete`].
///
/// # Example
/// ```
/// use mcmc_core::langevin::{Langevin, LangevinParams, Plain};
/// use pss::langevin::PssCoordinates;
///
/// let kernel = Langevin::new(LangevinParams::luan2020(), Plain, PssCoordinates).unwrap();
/// assert_eq!(kernel.params().epsilon, 0.01);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PssCoordinates;

/// Writes the interleaved indices of the coordinates [`PssCoordinates`] moves at `x` (the
/// continuous numbers of the read prefixes of its last evaluation), in the order of its
/// coordinates and gradients.
pub fn moved_indices(x: &PssState, out: &mut Vec<usize>) {
    out.clear();
    for_each_moved(x, |i| out.push(i));
}

/// Calls `f` with every moved coordinate index of `x`, in order.
fn for_each_moved(x: &PssState, mut f: impl FnMut(usize)) {
    let counts = x.read_counts();
    let streams = x.streams();
    for (s, &n) in counts.iter().enumerate().take(streams.min(MAX_STREAMS)) {
        for k in 0..n {
            if !x.is_discrete(s, k) {
                f(s + streams * k);
            }
        }
    }
}

/// Number of coordinates [`PssCoordinates`] moves at `x` (the length of its gradient).
#[must_use]
pub fn moved_count(x: &PssState) -> usize {
    let mut n = 0;
    for_each_moved(x, |_| n += 1);
    n
}

impl LangevinSpace<PssState> for PssCoordinates {
    fn read(&self, x: &PssState, out: &mut Vec<f64>) {
        out.clear();
        let values = x.raw_values();
        for_each_moved(x, |i| out.push(values.get(i).copied().unwrap_or(f64::NAN)));
    }

    fn write(&self, x: &PssState, coords: &[f64], y: &mut PssState) -> bool {
        y.clone_from(x);
        y.set_pending(Pending::None, mix64(x.key() ^ MALA_SALT));
        let mut k = 0;
        let mut ok = true;
        for_each_moved(x, |i| {
            match coords.get(k) {
                Some(&c) if c.is_finite() => y.set(i, wrap(c)),
                _ => ok = false,
            }
            k += 1;
        });
        ok && k == coords.len()
    }

    fn log_q(&self, q: &ProposalGaussian, from: &[f64], to: &[f64]) -> f64 {
        mcmc_core::Torus.log_q(q, from, to)
    }

    fn wraps(&self) -> bool {
        true
    }

    fn ghost(&self, x: &[f64], y: &[f64], z: &[f64], out: &mut Vec<f64>) {
        mcmc_core::Torus.ghost(x, y, z, out);
    }

    fn same_layout(&self, x: &PssState, y: &PssState) -> bool {
        x.streams() == y.streams()
            && x.read_counts() == y.read_counts()
            && x.discrete_mask() == y.discrete_mask()
    }

    /// Every stored coordinate that the move from `x` keeps fixed (read discrete or not read)
    /// equal in `x` and `y` (for the fully materialised states of the pairwise checks).
    fn same_slice(&self, x: &PssState, y: &PssState) -> bool {
        if x.streams() != y.streams() || x.len() != y.len() {
            return false;
        }
        let mut moved = vec![false; x.len()];
        for_each_moved(x, |i| {
            if let Some(m) = moved.get_mut(i) {
                *m = true;
            }
        });
        let (a, b) = (x.raw_values(), y.raw_values());
        (0..x.len()).all(|i| moved[i] || a[i] == b[i])
    }
}
