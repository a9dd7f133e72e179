//! The state arithmetic of Green & Mira's delayed rejection: the fictional state `y* = z - (y - x)`.

use crate::torus::wrap;

/// Computes the fictional ("ghost") state of generalised delayed rejection (Green & Mira 2001;
/// DR paper, section 4.5, Fig. 6): `y* = z - (y - x)`, the first-stage candidate translated
/// by the second-stage move.
///
/// The reverse path of `x -> (y rejected) -> z` passes through `y*` instead of `y`:
/// `z -> (y* rejected) -> x`. The map `(x, y, z) -> (z, y*, x)` must be an involution that
/// preserves volume (its own ghost is `x - (y* - z) = y`), which a translation on `R^n` or on
/// the torus `[0, 1)^n` is. Implementations write into `out` (a caller-owned buffer reused
/// every step).
///
/// The trait is implemented by *geometry objects* rather than by state types, so that one
/// state type can have several arithmetics: [`Euclidean`] and [`Torus`] both handle `f64`,
/// `Vec<f64>` and `[f64; N]`; a crate with its own state type implements it for its own
/// geometry or for [`Torus`] (`impl StateArithmetic<MyState> for Torus` is allowed by the
/// orphan rules because `MyState` is local).
///
/// # Notes
/// Lazily materialised states (primary sample space): the ghost's evaluation must not draw
/// coordinates of `x` that `z` does not carry; see [`super::DelayedRejection`] for what the
/// kernel calls `absorb_rejected` with.
///
/// # Example
/// ```
/// use mcmc_core::{Euclidean, StateArithmetic, Torus};
///
/// let (x, y, z) = (vec![0.5, 0.5], vec![0.6, 0.5], vec![0.95, 0.5]);
/// let mut ghost = Vec::new();
/// Euclidean.ghost(&x, &y, &z, &mut ghost);
/// assert!((ghost[0] - 0.85).abs() < 1e-12);
/// let z = vec![0.05, 0.5];
/// Torus.ghost(&x, &y, &z, &mut ghost); // 0.05 - 0.1 wraps to 0.95
/// assert!((ghost[0] - 0.95).abs() < 1e-12);
/// ```
pub trait StateArithmetic<S> {
    /// Writes `y* = z - (y - x)` into `out`.
    fn ghost(&self, x: &S, y: &S, z: &S, out: &mut S);
}

/// The arithmetic of rules that never form a ghost (Tierney-Mira, orbital). Uninhabited: a
/// `DrRule::GreenMira(NoGhost)` cannot be constructed, so `ghost` is never called.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NoGhost {}

impl<S> StateArithmetic<S> for NoGhost {
    fn ghost(&self, _x: &S, _y: &S, _z: &S, _out: &mut S) {
        match *self {}
    }
}

/// Plain coordinate-wise arithmetic on `R^n`: `y*_i = z_i - y_i + x_i`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Euclidean;

/// Arithmetic on the unit torus `[0, 1)^n` (primary sample space, the toy torus targets):
/// `y*_i = wrap(z_i - y_i + x_i)`, with [`crate::torus::wrap`]. A translation of the torus,
/// so the ghost map is a volume-preserving involution there, and it maps a uniform grid of
/// cell centres onto itself (what the exact finite-state check of Green-Mira needs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Torus;

#[inline]
fn plain(x: f64, y: f64, z: f64) -> f64 {
    z - y + x
}

#[inline]
fn wrapped(x: f64, y: f64, z: f64) -> f64 {
    wrap(z - y + x)
}

/// Writes `f` coordinate-wise into `out` (resized to `z`'s length; states of one chain share
/// a dimension, which a debug assertion checks).
fn coordinatewise(
    x: &[f64],
    y: &[f64],
    z: &[f64],
    out: &mut Vec<f64>,
    f: fn(f64, f64, f64) -> f64,
) {
    debug_assert!(
        x.len() == y.len() && y.len() == z.len(),
        "ghost of states of different dimensions ({}, {}, {})",
        x.len(),
        y.len(),
        z.len()
    );
    out.clear();
    out.extend(x.iter().zip(y).zip(z).map(|((&a, &b), &c)| f(a, b, c)));
}

macro_rules! impl_arithmetic {
    ($geometry:ty, $f:expr) => {
        impl StateArithmetic<f64> for $geometry {
            fn ghost(&self, x: &f64, y: &f64, z: &f64, out: &mut f64) {
                *out = $f(*x, *y, *z);
            }
        }

        impl StateArithmetic<Vec<f64>> for $geometry {
            fn ghost(&self, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>, out: &mut Vec<f64>) {
                coordinatewise(x, y, z, out, $f);
            }
        }

        impl<const N: usize> StateArithmetic<[f64; N]> for $geometry {
            fn ghost(&self, x: &[f64; N], y: &[f64; N], z: &[f64; N], out: &mut [f64; N]) {
                for i in 0..N {
                    out[i] = $f(x[i], y[i], z[i]);
                }
            }
        }
    };
}

impl_arithmetic!(Euclidean, plain);
impl_arithmetic!(Torus, wrapped);

#[cfg(test)]
mod tests {
    use super::*;

    /// The ghost map is an involution: the ghost of `(z, y*, x)` is `y`.
    #[test]
    fn ghost_of_the_reverse_path_is_the_rejected_candidate() {
        let (x, y, z) = (vec![0.1, 0.9], vec![0.3, 0.05], vec![0.95, 0.4]);
        for geometry in 0..2 {
            let (mut g, mut back) = (Vec::new(), Vec::new());
            if geometry == 0 {
                Euclidean.ghost(&x, &y, &z, &mut g);
                Euclidean.ghost(&z, &g, &x, &mut back);
            } else {
                Torus.ghost(&x, &y, &z, &mut g);
                assert!(g.iter().all(|v| (0.0..1.0).contains(v)), "{g:?}");
                Torus.ghost(&z, &g, &x, &mut back);
            }
            for (b, y) in back.iter().zip(&y) {
                assert!((b - y).abs() < 1e-12, "{back:?} vs {y:?}");
            }
        }
    }

    #[test]
    fn scalars_and_arrays_agree_with_vectors() {
        let mut s = 0.0;
        Euclidean.ghost(&1.0, &3.0, &2.0, &mut s);
        assert_eq!(s, 0.0);
        Torus.ghost(&0.25, &0.75, &0.25, &mut s);
        assert_eq!(s, 0.75);
        let mut a = [0.0; 2];
        Torus.ghost(&[0.5, 0.5], &[0.6, 0.4], &[0.05, 0.95], &mut a);
        let mut v = Vec::new();
        Torus.ghost(&vec![0.5, 0.5], &vec![0.6, 0.4], &vec![0.05, 0.95], &mut v);
        assert_eq!(a.to_vec(), v);
    }
}
