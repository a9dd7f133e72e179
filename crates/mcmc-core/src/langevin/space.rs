//! The coordinates a MALA step moves, and the geometry of the move (Euclidean or torus).

use super::gaussian::ProposalGaussian;
use crate::delayed_rejection::{Euclidean, Torus};
use crate::torus::wrap;

/// How a Langevin kernel sees a state: the real coordinates it moves (and that the target's
/// gradient refers to), how a moved state is written, and the density of a move.
///
/// Implemented by geometry objects, like [`crate::StateArithmetic`]: [`Euclidean`] (`R^d`)
/// and [`Torus`] (`[0, 1)^d`, primary sample space: moved coordinates wrap, and the move's
/// density is the wrapped Gaussian) for `Vec<f64>` states. A crate with its own state type
/// implements it for its geometry (`pss` does for its lazy primary-sample-space state).
///
/// The gradient a [`crate::DifferentiableTarget`] writes must be indexed like
/// [`LangevinSpace::read`]'s coordinates.
pub trait LangevinSpace<S> {
    /// Writes the coordinates of `x` that the kernel moves into `out`.
    fn read(&self, x: &S, out: &mut Vec<f64>);
    /// Writes into `y` the state `x` with its moved coordinates set to `coords` (the
    /// unwrapped sum of `x`'s coordinates and an offset). Returns `false` if that is not a
    /// state of the space (the candidate is then invalid).
    fn write(&self, x: &S, coords: &[f64], y: &mut S) -> bool;
    /// Log density of moving from coordinates `from` to coordinates `to` (both as
    /// [`LangevinSpace::read`] reports them) under the offset Gaussian `q` formed at `from`.
    fn log_q(&self, q: &ProposalGaussian, from: &[f64], to: &[f64]) -> f64;
    /// True if moved coordinates wrap around (then only diagonal Gaussians are supported:
    /// the images of a full Gaussian do not factorise).
    fn wraps(&self) -> bool;
    /// Writes the ghost coordinates `z - (y - x)` of generalised delayed rejection into
    /// `out` (wrapped on a torus).
    fn ghost(&self, x: &[f64], y: &[f64], z: &[f64], out: &mut Vec<f64>);
    /// True if the evaluated candidate `y` has the same coordinate layout as `x` (the same
    /// coordinates read, hence moved). A candidate whose evaluation read a different set of
    /// coordinates is rejected: the kernels are exact on each set `{u : R(u) = R(x)}` of
    /// states with one read set `R` (docs/methods/mala.md). States of fixed dimension: always.
    fn same_layout(&self, x: &S, y: &S) -> bool {
        let _ = (x, y);
        true
    }
    /// True if a move from `x` can reach `y`: `y` agrees with `x` on every coordinate the
    /// kernel keeps fixed at `x` (its discrete and unread coordinates). Used by the flows of
    /// the pairwise checks ([`crate::Kernel::log_flow`]); states whose coordinates are all
    /// moved: always.
    fn same_slice(&self, x: &S, y: &S) -> bool {
        let _ = (x, y);
        true
    }
}

/// Writes `to - from` into a stack buffer (or `spill` beyond 64 dimensions) and calls `f`.
fn with_offset<R>(from: &[f64], to: &[f64], wrapped: bool, f: impl FnOnce(&[f64]) -> R) -> R {
    let d = from.len();
    let mut stack = [0.0f64; 64];
    let mut spill = Vec::new();
    let buf: &mut [f64] = if d <= 64 {
        &mut stack[..d]
    } else {
        spill.resize(d, 0.0);
        &mut spill
    };
    for ((o, &a), &b) in buf.iter_mut().zip(from).zip(to) {
        let delta = b - a;
        // Signed torus displacement in [-1/2, 1/2).
        *o = if wrapped {
            wrap(delta + 0.5) - 0.5
        } else {
            delta
        };
    }
    f(buf)
}

impl LangevinSpace<Vec<f64>> for Euclidean {
    fn read(&self, x: &Vec<f64>, out: &mut Vec<f64>) {
        out.clone_from(x);
    }
    fn write(&self, _x: &Vec<f64>, coords: &[f64], y: &mut Vec<f64>) -> bool {
        y.clear();
        y.extend_from_slice(coords);
        coords.iter().all(|c| c.is_finite())
    }
    fn log_q(&self, q: &ProposalGaussian, from: &[f64], to: &[f64]) -> f64 {
        if from.len() != to.len() || q.dim() != from.len() {
            return f64::NEG_INFINITY;
        }
        with_offset(from, to, false, |o| q.log_density(o))
    }
    fn wraps(&self) -> bool {
        false
    }
    fn ghost(&self, x: &[f64], y: &[f64], z: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend(x.iter().zip(y).zip(z).map(|((a, b), c)| c - b + a));
    }
}

impl LangevinSpace<Vec<f64>> for Torus {
    fn read(&self, x: &Vec<f64>, out: &mut Vec<f64>) {
        out.clone_from(x);
    }
    fn write(&self, _x: &Vec<f64>, coords: &[f64], y: &mut Vec<f64>) -> bool {
        y.clear();
        y.extend(coords.iter().map(|&c| wrap(c)));
        coords.iter().all(|c| c.is_finite())
    }
    fn log_q(&self, q: &ProposalGaussian, from: &[f64], to: &[f64]) -> f64 {
        if from.len() != to.len() || q.dim() != from.len() {
            return f64::NEG_INFINITY;
        }
        with_offset(from, to, true, |o| q.log_density_wrapped(o))
    }
    fn wraps(&self) -> bool {
        true
    }
    fn ghost(&self, x: &[f64], y: &[f64], z: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend(x.iter().zip(y).zip(z).map(|((a, b), c)| wrap(c - b + a)));
    }
}
