//! The pairwise orbital mutation: the second stage of delayed-rejection MLT (paper section 4.4).
//!
//! # The scheme
//!
//! Delayed rejection (DR paper, ../shared/papers/delayed-rejection-mlt.txt, Alg. 1) proposes
//! `y` from the current state `x`; if `y` is rejected it proposes `z` from `q2(z | x, y)`. The
//! pairwise orbital scheme (section 4.4, Alg. 2) makes the second-stage acceptance the closed
//! form of eq. 11, `a2 = min(1, max(0, pi(z) - pi(y)) / (pi(x) - pi(y)))`, with two pieces:
//!
//! - stage 1, [`crate::PairwiseKelemen`]: each pair of coordinates moves by
//!   `r (cos phi, sin phi)`, `phi` uniform, `r` from Kelemen's law; its density is a product
//!   over pairs of functions of `|y_pair - x_pair|` only;
//! - stage 2, [`Orbital`]: each pair of `z` lies on the circle centred at `y_pair` through
//!   `x_pair` (the *orbit*), at angle `theta` from `x_pair` seen from `y_pair`, `theta` drawn
//!   from a wrapped Cauchy law (eq. 10, [`crate::WrappedCauchy`]).
//!
//! Then `q1(y | z) = q1(y | x)` (same distance per pair) and `q2(x | z, y) = q2(z | x, y)`
//! (the reverse move needs angle `-theta`, and the law is symmetric), so the Tierney-Mira
//! ratio (eq. 6) reduces to `pi(z) (1 - a1(z, y)) / (pi(x) (1 - a1(x, y)))`, which is eq. 11.
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
//! number.
//!
//! # Odd dimensions
//!
//! A stream of odd dimension ends with a lone coordinate. Stage 1 moves it by Kelemen's 1-D
//! step with the same radius law (random sign); stage 2 keeps it at `x`'s value. Both keep
//! eq. 11 exact: `|y_i - z_i| = |y_i - x_i|`, and "stay" is its own reverse. (The authors'
//! code instead rounds every dimension up to even, except for one sampler where an odd
//! dimension indexes past the end.) Any other coordinate stage 2 does not move stays at
//! `x`'s value, for the same reason.
//!
//! # The torus
//!
//! Coordinates live on the unit circle `[0, 1)` with wrap-around (mod 1; the authors' code
//! reflects at the borders instead, which does not preserve distances). All geometry uses the
//! *minimal* torus displacement ([`crate::torus_displacement`]): the orbit is centred at `y`
//! with radius `r = |min displacement(y -> x)|`, and `z = wrap(y + r (cos, sin))`. With
//! `r < 1/2` every component of `r (cos, sin)` is below 1/2, so the minimal displacement
//! `y -> z` is that vector: `z` is at torus distance `r` from `y`, and the reverse move
//! `z -> x` sees the same circle. Stage 1 never proposes `r >= 1/2` (its `r_max < 1/2`); for
//! such a pair the orbital stage reports [`Proposed::Invalid`] (no second stage, which is a
//! valid choice because it is symmetric: a state on an orbit of radius `< 1/2` has only such
//! orbit-mates).
//!
//! # Density of the singular second stage
//!
//! `z` is confined to the product of the orbits, a set of Lebesgue measure zero, so `q2` has no
//! density on `[0, 1)^n`. [`Orbital`]'s `log_q(x, y, z)` is the density with respect to the
//! product, over pairs, of the angle measure `d theta` on the orbit circle (and the counting
//! measure for the coordinates it keeps): `sum over pairs of log p_WC(theta_pair)`, and
//! `NEG_INFINITY` if `z` is off the orbit of `(x, y)`. The forward move `x -> z` and the
//! reverse `z -> x` (same `y`) live on the same set with the same reference measure, so the
//! ratio a kernel forms from these values is the exact Radon-Nikodym ratio; it is always 1
//! for pairs that `propose` can produce, which is why eq. 11 has no `q2` term. (Arc length
//! `r d theta` would do as well: the factor `r` is the same in both directions.) The same
//! values serve a Green-Mira kernel: the fictional `y* = z - (y - x)` sees `x` on the orbit
//! of `(z, y*)` at the same angle, so its `q2` ratio is 1 too.
//!
//! # Fixed dimension
//!
//! The orbit needs `x` and `y` at every coordinate `z` reads, so both stages work on states
//! materialised to a fixed layout (as the authors' code does), never on lazily grown ones:
//! `Vec<f64>` points of `[0, 1)^n`, whose length is the layout
//! ([`PairLayout::single_stream`]), and [`crate::PssState`]s through [`crate::OnLayout`],
//! which materialises a given [`PairLayout`] exactly (its docs say how the lazy state's
//! catch-up and `absorb_rejected` are kept). Both stages are symmetric only because the
//! layout does not depend on the state: a layout that grew with what `x` has read would
//! perturb coordinates in one direction that the reverse move leaves alone.

use std::f64::consts::PI;

use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::Proposed;
use rand::Rng;

use crate::mutation::wrap;
use crate::pairwise::{torus_displacement, Group, PairLayout};
use mcmc_core::delayed_rejection::WrappedCauchy;

/// Relative tolerance of the on-orbit test of [`Orbital`]'s `log_q` (radii recomputed from
/// wrapped coordinates differ from the drawn one by rounding).
const ORBIT_TOLERANCE: f64 = 1e-9;

/// The pairwise orbital second stage (DR paper section 4.4, Alg. 2, stage 2): per pair,
/// `z = y + R(theta) (x - y)` on the torus, the rotation by an angle `theta` drawn from the
/// wrapped Cauchy law (eq. 10); lone coordinates stay at `x`.
///
/// See the [module docs](self) for the pairing, odd dimensions, the torus, and the density
/// `log_q` returns. With [`crate::PairwiseKelemen`] as the first stage, a delayed-rejection
/// kernel may use the closed-form acceptance of eq. 11, exactly.
///
/// States: `Vec<f64>`, a point of `[0, 1)^n`, paired as [`PairLayout::single_stream`]`(n)`.
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

    /// The pair of `z` on the orbit of the pairs `x`, `y`: `y + R(theta) (x - y)` with minimal
    /// torus displacements, wrapped; `None` if the orbit's radius is `>= 1/2`. One uniform
    /// (drawn in both cases).
    #[inline]
    pub fn orbit_pair<R: Rng + ?Sized>(
        &self,
        x: [f64; 2],
        y: [f64; 2],
        rng: &mut R,
    ) -> Option<[f64; 2]> {
        let dx = torus_displacement(y[0], x[0]);
        let dy = torus_displacement(y[1], x[1]);
        let theta = self.angle.sample(rng);
        if dx.hypot(dy) >= 0.5 {
            return None;
        }
        let (sin, cos) = theta.sin_cos();
        Some([
            wrap(y[0] + cos * dx - sin * dy),
            wrap(y[1] + sin * dx + cos * dy),
        ])
    }

    /// `log q2(z | x, y)` over the coordinates of `groups` (see the module docs for the
    /// reference measure): the sum of the wrapped Cauchy log densities of the pairs' angles,
    /// `NEG_INFINITY` if `z` is off the orbit.
    pub fn groups_log_q(
        &self,
        groups: impl Iterator<Item = Group>,
        read_x: impl Fn(usize) -> f64,
        read_y: impl Fn(usize) -> f64,
        read_z: impl Fn(usize) -> f64,
    ) -> f64 {
        let mut log_q = 0.0;
        for group in groups {
            match group {
                Group::Pair(a, b) => {
                    let (ya, yb) = (read_y(a), read_y(b));
                    let (ux, uy) = (
                        torus_displacement(ya, read_x(a)),
                        torus_displacement(yb, read_x(b)),
                    );
                    let (vx, vy) = (
                        torus_displacement(ya, read_z(a)),
                        torus_displacement(yb, read_z(b)),
                    );
                    let (r, s) = (ux.hypot(uy), vx.hypot(vy));
                    if r >= 0.5 || (r - s).abs() > ORBIT_TOLERANCE * r.max(f64::MIN_POSITIVE) {
                        return f64::NEG_INFINITY;
                    }
                    if r > 0.0 {
                        let theta = (ux * vy - uy * vx).atan2(ux * vx + uy * vy);
                        log_q += self.angle.log_pdf(theta.clamp(-PI, PI));
                    }
                }
                Group::Single(a) => {
                    if read_z(a) != read_x(a) {
                        return f64::NEG_INFINITY;
                    }
                }
            }
        }
        log_q
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
        z.clone_from(x);
        if y.len() != x.len() {
            return Proposed::Invalid { component: 0 };
        }
        for group in PairLayout::single_stream(x.len()).groups(1) {
            // Lone coordinates stay at x (z is a copy of x).
            if let Group::Pair(a, b) = group {
                match self.orbit_pair([x[a], x[b]], [y[a], y[b]], rng) {
                    Some(pair) => [z[a], z[b]] = pair,
                    None => return Proposed::Invalid { component: 0 },
                }
            }
        }
        Proposed::symmetric()
    }

    /// The density of `z` on the orbit of `(x, y)` w.r.t. the product of the orbits' angle
    /// measures (module docs); `NEG_INFINITY` off the orbit or for mismatched lengths.
    fn log_q(&self, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        if y.len() != x.len() || z.len() != x.len() {
            return f64::NEG_INFINITY;
        }
        let layout = PairLayout::single_stream(x.len());
        self.groups_log_q(layout.groups(1), |i| x[i], |i| y[i], |i| z[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pairwise::PairwiseKelemen;
    use mcmc_core::Proposal;
    use rand::{RngExt, SeedableRng};

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
