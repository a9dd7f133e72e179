//! The pairwise orbital mutation on primary sample space: the second stage of
//! delayed-rejection MLT (DR paper, section 4.4, Alg. 2).
//!
//! The maths (the orbit of each pair, odd dimensions, the torus, the density of the singular
//! second stage) is mcmc-core's [`mcmc_core::delayed_rejection::OrbitalWalk`] on the torus;
//! see its documentation for the scheme. This file keeps what is specific to primary sample
//! space: which coordinates pair up, and the stage's PSS name and parameters.
//!
//! # The scheme
//!
//! - stage 1, [`crate::PairwiseKelemen`]: each pair of coordinates moves by
//!   `r (cos phi, sin phi)`, `phi` uniform, `r` from Kelemen's law; its density is a product
//!   over pairs of functions of `|y_pair - x_pair|` only;
//! - stage 2, [`Orbital`]: each pair of `z` lies on the circle centred at `y_pair` through
//!   `x_pair` (the *orbit*), at angle `theta` from `x_pair` seen from `y_pair`, `theta` drawn
//!   from a wrapped Cauchy law (eq. 10, [`crate::WrappedCauchy`]).
//!
//! Then the second-stage acceptance is the closed form of eq. 11.
//!
//! # Pairing
//!
//! Coordinates pair up per stream: a stream's numbers `(2k, 2k + 1)` form a pair
//! ([`crate::PairLayout`]; on a plain vector, `(0, 1), (2, 3), ...` as in the paper). For the
//! renderer's streams (`render::sampler::Stream`; `render::mlt` reads PSS stream s as
//! renderer stream s) this pairs every 2-D sample that starts at an even position of its
//! stream. In the current orders (PT camera stream: raster 2, lens 2, time 1, then 7 per
//! bounce: light choice, light position 2, lobe, direction 2, roulette; BDPT camera stream:
//! raster 2, lens 2, time 1, then lobe and direction 2 per bounce, +1 with roulette; BDPT
//! light stream: light choice, position 2, direction 2, then the same per bounce; MMLT's
//! connection stream starts with the strategy choice) the raster position `(0, 1)` and the
//! lens `(2, 3)` pair naturally, the light's position and direction are each split across
//! two pairs, and bounce directions alternate between natural and split pairs. That stays
//! exact (any partition into pairs and lone coordinates does) but is less natural; a
//! renderer that wants every 2-D sample paired pads it to an even position with one unused
//! number. A stream of odd dimension ends with a lone coordinate, which stage 1 moves by
//! Kelemen's 1-D step and stage 2 keeps at `x`'s value.
//!
//! # Fixed dimension
//!
//! The orbit needs `x` and `y` at every coordinate `z` reads, so both stages work on states
//! materialised to a fixed layout (as the authors' code does), never on lazily grown ones:
//! `Vec<f64>` points of `[0, 1)^n`, whose length is the layout
//! ([`crate::PairLayout::single_stream`]), and [`crate::PssState`]s through
//! [`crate::OnLayout`], which materialises a given [`crate::PairLayout`] exactly (its docs say how the lazy state's
//! catch-up and `absorb_rejected` are kept). Both stages are symmetric only because the
//! layout does not depend on the state: a layout that grew with what `x` has read would
//! perturb coordinates in one direction that the reverse move leaves alone.
//! [`crate::lazy_pairs`] removes the layout instead: both stages act on every pair of every
//! stream, computed only where the target reads, unread pairs caught up exactly.

use mcmc_core::delayed_rejection::{Group, OrbitalWalk, WrappedCauchy};
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::Proposed;
use rand::Rng;

/// The pairwise orbital second stage (DR paper section 4.4, Alg. 2, stage 2) on the unit
/// torus: per pair, `z = y + R(theta) (x - y)` with minimal torus displacements, wrapped, the
/// rotation by an angle `theta` drawn from the wrapped Cauchy law (eq. 10); lone coordinates
/// stay at `x`. It is mcmc-core's [`OrbitalWalk::torus_with`]`(angle)`.
///
/// See the [module docs](self) for the pairing and mcmc-core's [`OrbitalWalk`] for odd
/// dimensions, the torus, and the density `log_q` returns. With [`crate::PairwiseKelemen`] as
/// the first stage, a delayed-rejection kernel may use the closed-form acceptance of eq. 11,
/// exactly.
///
/// States: `Vec<f64>`, a point of `[0, 1)^n`, paired as [`crate::PairLayout::single_stream`]`(n)`;
/// [`crate::PssState`]s through [`crate::OnLayout`].
/// Random numbers: one uniform per pair, in order (including pairs with `x = y`).
///
/// # Example
/// ```
/// use mcmc_core::proposal::ConditionalProposal;
/// use mcmc_core::Proposal;
/// use pss::{torus_displacement, Orbital, PairwiseKelemen};
/// use rand::SeedableRng;
///
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
/// let (stage1, stage2) = (PairwiseKelemen::default(), Orbital::default());
/// let x = vec![0.995, 0.3];
/// let (mut y, mut z) = (Vec::new(), Vec::new());
/// stage1.propose(&x, &mut y, &mut rng);
/// stage2.propose(&x, &y, &mut z, &mut rng);
/// let distance = |a: &[f64], b: &[f64]| {
///     torus_displacement(a[0], b[0]).hypot(torus_displacement(a[1], b[1]))
/// };
/// assert!((distance(&y, &z) - distance(&y, &x)).abs() < 1e-12);
/// assert!(stage2.log_q(&x, &y, &z).is_finite());
/// // What eq. 11 relies on: q1(y | z) = q1(y | x).
/// assert!((stage1.log_q(&z, &y) - stage1.log_q(&x, &y)).abs() < 1e-9);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Orbital {
    /// The law of the angle offset.
    pub angle: WrappedCauchy,
}

impl Orbital {
    /// The orbital stage with angle law `angle`.
    #[must_use]
    pub const fn new(angle: WrappedCauchy) -> Self {
        Self { angle }
    }

    /// The stage as mcmc-core's torus [`OrbitalWalk`], which implements it.
    #[inline]
    #[must_use]
    pub const fn walk(&self) -> OrbitalWalk {
        OrbitalWalk::torus_with(self.angle)
    }

    /// The pair of `z` on the orbit of the pairs `x`, `y` ([`OrbitalWalk::orbit_pair`] on the
    /// torus): `y + R(theta) (x - y)` with minimal torus displacements, wrapped; `None` if the
    /// orbit's radius is `>= 1/2`. One uniform (drawn in both cases).
    #[inline]
    pub fn orbit_pair<R: Rng + ?Sized>(
        &self,
        x: [f64; 2],
        y: [f64; 2],
        rng: &mut R,
    ) -> Option<[f64; 2]> {
        self.walk().orbit_pair(x, y, rng)
    }

    /// `log q2(z | x, y)` over the coordinates of `groups` ([`OrbitalWalk::groups_log_q`] on
    /// the torus): the sum of the wrapped Cauchy log densities of the pairs' angles,
    /// `NEG_INFINITY` if `z` is off the orbit.
    pub fn groups_log_q(
        &self,
        groups: impl Iterator<Item = Group>,
        read_x: impl Fn(usize) -> f64,
        read_y: impl Fn(usize) -> f64,
        read_z: impl Fn(usize) -> f64,
    ) -> f64 {
        self.walk().groups_log_q(groups, read_x, read_y, read_z)
    }
}

impl ConditionalProposal<Vec<f64>> for Orbital {
    /// `z` on the orbit of `(x, y)`; [`Proposed::Invalid`] if `y` has another length than `x`
    /// or a pair's orbit has radius `>= 1/2`. Symmetric (`log_hastings = 0`).
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &Vec<f64>,
        y: &Vec<f64>,
        z: &mut Vec<f64>,
        rng: &mut R,
    ) -> Proposed {
        self.walk().propose(x, y, z, rng)
    }

    /// The density of `z` on the orbit of `(x, y)` w.r.t. the product of the orbits' angle
    /// measures; `NEG_INFINITY` off the orbit or for mismatched lengths.
    fn log_q(&self, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        self.walk().log_q(x, y, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mutation::wrap;
    use crate::pairwise::{torus_displacement, PairwiseKelemen};
    use mcmc_core::Proposal;
    use rand::{RngExt, SeedableRng};
    use std::f64::consts::PI;

    #[test]
    fn z_lies_on_the_orbit_and_the_reverse_move_has_the_same_density() {
        let (stage1, stage2) = (PairwiseKelemen::default(), Orbital::default());
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let (mut y, mut z) = (Vec::new(), Vec::new());
        for i in 0..2000 {
            // Points near the seams half of the time.
            let x: Vec<f64> = (0..5)
                .map(|k| {
                    let u = rng.random::<f64>();
                    if (i + k) % 2 == 0 {
                        wrap(0.01 * (u - 0.5))
                    } else {
                        u
                    }
                })
                .collect();
            stage1.propose(&x, &mut y, &mut rng);
            assert_eq!(
                stage2.propose(&x, &y, &mut z, &mut rng),
                Proposed::symmetric()
            );
            for (a, b) in [(0, 1), (2, 3)] {
                let r = torus_displacement(y[a], x[a]).hypot(torus_displacement(y[b], x[b]));
                let s = torus_displacement(y[a], z[a]).hypot(torus_displacement(y[b], z[b]));
                assert!((r - s).abs() < 1e-14, "{r} vs {s}");
            }
            assert_eq!(z[4], x[4]);
            let forward = stage2.log_q(&x, &y, &z);
            let reverse = stage2.log_q(&z, &y, &x);
            assert!(forward.is_finite());
            assert!((forward - reverse).abs() < 1e-9, "{forward} vs {reverse}");
            let (q1x, q1z) = (stage1.log_q(&x, &y), stage1.log_q(&z, &y));
            assert!((q1x - q1z).abs() < 1e-9, "{q1x} vs {q1z}");
        }
    }

    #[test]
    fn off_orbit_and_far_states_are_impossible() {
        let o = Orbital::default();
        let x = vec![0.5, 0.5, 0.1];
        let y = vec![0.51, 0.5, 0.2];
        assert!(o.log_q(&x, &y, &vec![0.52, 0.5, 0.1]).is_finite());
        assert_eq!(o.log_q(&x, &y, &vec![0.53, 0.5, 0.1]), f64::NEG_INFINITY);
        assert_eq!(o.log_q(&x, &y, &vec![0.52, 0.5, 0.2]), f64::NEG_INFINITY);
        assert_eq!(o.log_q(&x, &y, &vec![0.52, 0.5]), f64::NEG_INFINITY);
        // theta = pi: the antipode of x on the orbit.
        let expected = o.angle.log_pdf(PI);
        assert!((o.log_q(&x, &y, &vec![0.52, 0.5, 0.1]) - expected).abs() < 1e-9);
        // A pair whose orbit has radius >= 1/2 has no second stage.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
        let mut z = Vec::new();
        let far = vec![0.0, 0.0];
        let y_far = vec![0.45, 0.45];
        assert_eq!(
            o.propose(&far, &y_far, &mut z, &mut rng),
            Proposed::Invalid { component: 0 }
        );
        assert_eq!(o.log_q(&far, &y_far, &far), f64::NEG_INFINITY);
        assert_eq!(
            o.propose(&far, &vec![0.1], &mut z, &mut rng),
            Proposed::Invalid { component: 0 }
        );
        // x == y on a pair: the orbit is a point.
        assert_eq!(o.propose(&x, &x, &mut z, &mut rng), Proposed::symmetric());
        assert_eq!(z, x);
        assert_eq!(o.log_q(&x, &x, &x), 0.0);
    }
}
