//! MALA in primary sample space: the coordinates a Langevin step moves, wrap-around, and the
//! torus displacement ([`mcmc_core::langevin`] holds the kernels and the adaptation).

use mcmc_core::langevin::{LangevinSpace, ProposalGaussian};
use mcmc_core::seed::mix64;
use mcmc_core::torus::wrap;

use crate::state::{Pending, PssState, MAX_STREAMS};

/// Salt of the key a MALA candidate gets (any coordinate it reads beyond the moved ones makes
/// it invalid anyway, so the key only has to differ from the parent's).
const MALA_SALT: u64 = 0x4d41_4c41_5053_5321;

/// The [`LangevinSpace`] of primary sample space: a MALA step moves exactly the coordinates
/// the current state's last evaluation read — per stream `s`, the prefix
/// `0..read_counts()[s]` ([`PssState::read_counts`]), in the order stream 0 first, then
/// stream 1, ... (the order a [`mcmc_core::DifferentiableTarget`] over [`PssState`] must
/// write its gradient in). Moved coordinates wrap around the unit torus, and the move's
/// density is the *wrapped* Gaussian ([`ProposalGaussian::log_density_wrapped`]), so a
/// proposal across the seam has the right density both ways (the reference implementation of
/// Luan et al. 2020 wraps every coordinate mod 1 too; docs/methods/mala.md, "Readings and
/// departures", item "Read sets").
///
/// # Read sets
/// The candidate is the current state with the moved coordinates replaced, no lazy mutation
/// attached. A candidate whose evaluation reads a different set of coordinates (a longer or
/// shorter prefix of any stream) is rejected ([`LangevinSpace::same_layout`]): the Langevin
/// kernels are then exact on each set `{u : R(u) = R}` of states with one read set, which is
/// what makes MALA exact on targets whose read set depends on the state (Russian roulette,
/// varying path length). Moving a larger set — say every stored coordinate, including stale
/// ones the state did not read — is *not* exact (a negative control in the tests). Targets
/// must read through [`PssState::begin`] and [`PssState::next_sample`].
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
/// read prefixes of its last evaluation), in the order of its coordinates and gradients.
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
            f(s + streams * k);
        }
    }
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
        x.streams() == y.streams() && x.read_counts() == y.read_counts()
    }
}
