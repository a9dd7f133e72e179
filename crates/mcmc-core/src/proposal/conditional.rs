//! Second-stage proposals of delayed rejection: a move that sees both the current state and
//! the candidate the first stage proposed and the kernel rejected (Tierney & Mira 1999; Green &
//! Mira 2001; the delayed-rejection MLT paper, Rioux-Lavoie, Litalien et al. 2020, section 4;
//! docs/methods/drmlt.md).

use rand::Rng;

use super::Proposed;

/// A conditional proposal `q2(z | x, y)`: draws `z` given the current state `x` and the
/// rejected first-stage candidate `y`, and exposes its density.
///
/// Delayed-rejection kernels (`mcmc_core::kernel`) call [`ConditionalProposal::propose`]
/// after a rejected first stage and evaluate the reverse density `q2(y* | z, x)` (Tierney-Mira:
/// `y* = y`; Green-Mira: the fictional state `y* = z - (y - x)`) with
/// [`ConditionalProposal::log_q`]. Like [`super::Proposal`], implementations never own a
/// random number generator and write into a caller-owned buffer.
pub trait ConditionalProposal<S> {
    /// Draws `z` given the current state `x` and the rejected candidate `y`. The returned
    /// [`Proposed::Move`]'s `log_hastings` is ignored by delayed-rejection kernels (they form
    /// their acceptance from [`ConditionalProposal::log_q`]); `Invalid` counts as a rejection.
    fn propose<R: Rng + ?Sized>(&self, x: &S, y: &S, z: &mut S, rng: &mut R) -> Proposed;

    /// `log q2(z | x, y)`: the density of proposing `z` from current state `x` after the
    /// rejected candidate `y`; `NEG_INFINITY` if impossible. For proposals singular with
    /// respect to the state space's base measure (the orbital stage moves on a circle), the
    /// density with respect to the measure on the constrained set, documented by the
    /// implementation, such that the kernel's ratio is exact.
    fn log_q(&self, x: &S, y: &S, z: &S) -> f64;
}
