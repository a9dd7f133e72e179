//! The pairwise orbital second stage of delayed rejection (DR paper, section 4.4, Alg. 2
//! stage 2): each coordinate pair of `z` on the circle centred at the rejected `y` through `x`.

use rand::Rng;

use super::pairwise::{pairs, Group, Space};
use super::wrapped_cauchy::WrappedCauchy;
use crate::proposal::{ConditionalProposal, Proposed};
use crate::McmcError;

/// Relative tolerance of the on-orbit test of [`OrbitalWalk::groups_log_q`] (radii recomputed
/// from rotated, possibly wrapped coordinates differ from the original by rounding, about
/// `1e-16` relative).
pub const ORBIT_TOLERANCE: f64 = 1e-9;

/// The pairwise orbital second stage (DR paper, section 4.4, Alg. 2 stage 2): per coordinate
/// pair, `z = y + R(theta) (x - y)`, the rotation by an angle `theta` drawn from a
/// [`WrappedCauchy`] law (eq. 10); lone coordinates stay at `x`. In `R^n`
/// ([`OrbitalWalk::new`]) or on the unit torus ([`OrbitalWalk::on_torus`]). After
/// [`super::RadialKelemen`] as the first stage, a delayed-rejection kernel may use the
/// closed-form acceptance of eq. 11 ([`super::DrRule::Orbital`]), exactly.
///
/// # The scheme
///
/// Delayed rejection proposes `y` from the current state `x`; if `y` is rejected it proposes
/// `z` from `q2(z | x, y)`. The pairwise orbital scheme makes the second-stage acceptance the
/// closed form of eq. 11, `a2 = min(1, max(0, pi(z) - pi(y)) / (pi(x) - pi(y)))`, with two
/// pieces: a first stage whose density is a product over coordinate pairs of functions of
/// `|y_pair - x_pair|` only ([`super::RadialKelemen`]), and this second stage, which puts each
/// pair of `z` on the circle centred at `y_pair` through `x_pair` (the *orbit*), at angle
/// `theta` from `x_pair` seen from `y_pair`, `theta` drawn from a [`WrappedCauchy`] law
/// (eq. 10). Then `q1(y | z) = q1(y | x)` (same distance per pair) and `q2(x | z, y) =
/// q2(z | x, y)` (the reverse move needs angle `-theta`, and the law is symmetric), so the
/// Tierney-Mira ratio (eq. 6) reduces to eq. 11.
///
/// # Odd dimensions
///
/// A lone coordinate ([`Group::Single`]) stays at `x`'s value (its 1-D "orbit" `{x, 2y - x}`
/// taken at `x`): `|y_i - z_i| = |y_i - x_i|`, and "stay" is its own reverse, so eq. 11 stays
/// exact. (The authors' code instead rounds every dimension up to even.)
///
/// # The torus
///
/// On the unit torus ([`OrbitalWalk::on_torus`]) coordinates wrap mod 1 (the authors' code
/// reflects at the borders instead, which does not preserve distances) and all geometry uses
/// the *minimal* displacement ([`crate::torus::displacement`]): the orbit is centred at `y`
/// with radius `r = |min displacement(y -> x)|`, and `z = wrap(y + R(theta) (x - y))`. With
/// `r < 1/2` every component of the rotated vector is below 1/2, so the minimal displacement
/// `y -> z` is that vector: `z` is at torus distance `r` from `y`, and the reverse move `z ->
/// x` sees the same circle. A first stage on the torus never proposes `r >= 1/2`; for such a
/// pair the orbital stage reports [`Proposed::Invalid`] (no second stage, a valid choice
/// because it is symmetric: a state on an orbit of radius `< 1/2` has only such orbit-mates).
///
/// # Density of the singular second stage
///
/// `z` is confined to the product of the orbits, a set of Lebesgue measure zero, so `q2` has no
/// density. [`OrbitalWalk::groups_log_q`] is the density with respect to the product, over
/// pairs, of the angle measure `d theta` on the orbit circle (and the counting measure for the
/// coordinates it keeps): `sum over pairs of log p_WC(theta_pair)`, and `NEG_INFINITY` if `z`
/// is off the orbit of `(x, y)` (to [`ORBIT_TOLERANCE`] relative). The forward move `x -> z`
/// and the reverse `z -> x` (same `y`) live on the same set with the same reference measure,
/// so the ratio a kernel forms from these values is the exact Radon-Nikodym ratio; it is
/// always 1 for pairs that `propose` can produce, which is why eq. 11 has no `q2` term. (Arc
/// length `r d theta` would do as well: the factor `r` is the same in both directions.) The
/// same values serve a Green-Mira kernel: the fictional `y* = z - (y - x)` sees `x` on the
/// orbit of `(z, y*)` at the same angle, so its `q2` ratio is 1 too.
///
/// # Fixed dimension
///
/// The orbit needs `x` and `y` at every coordinate `z` reads, so the stage works on states of
/// a fixed layout: `Vec<f64>` points grouped by [`pairs`], or any state whose coordinates a
/// caller reads through the per-pair [`OrbitalWalk::orbit_pair`] and
/// [`OrbitalWalk::groups_log_q`] (`pss` does so for lazily grown primary-sample-space
/// states materialised on a fixed layout).
///
/// Random numbers: one uniform per pair, in order (including pairs with `x = y`).
///
/// # Example
/// ```
/// use mcmc_core::delayed_rejection::{OrbitalWalk, RadialKelemen};
/// use mcmc_core::proposal::ConditionalProposal;
/// use mcmc_core::Proposal;
/// use rand::SeedableRng;
///
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
/// let stage1 = RadialKelemen::rioux_lavoie2020();
/// let stage2 = OrbitalWalk::on_torus(0.5).unwrap();
/// let x = vec![0.995, 0.3];
/// let (mut y, mut z) = (Vec::new(), Vec::new());
/// stage1.propose(&x, &mut y, &mut rng);
/// stage2.propose(&x, &y, &mut z, &mut rng);
/// assert!(stage2.log_q(&x, &y, &z).is_finite());
/// // What eq. 11 relies on: q1(y | z) = q1(y | x).
/// assert!((stage1.log_q(&z, &y) - stage1.log_q(&x, &y)).abs() < 1e-9);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitalWalk {
    angle: WrappedCauchy,
    space: Space,
}

impl OrbitalWalk {
    /// An orbital stage in `R^n` with wrapped Cauchy concentration `rho` in `[0, 1)`.
    ///
    /// # Errors
    /// As [`WrappedCauchy::new`].
    pub fn new(rho: f64) -> Result<Self, McmcError> {
        Ok(Self {
            angle: WrappedCauchy::new(rho)?,
            space: Space::Plane,
        })
    }

    /// An orbital stage on the torus `[0, 1)^n` with concentration `rho` in `[0, 1)`.
    ///
    /// # Errors
    /// As [`WrappedCauchy::new`].
    pub fn on_torus(rho: f64) -> Result<Self, McmcError> {
        Ok(Self::torus_with(WrappedCauchy::new(rho)?))
    }

    /// An orbital stage on the torus `[0, 1)^n` with angle law `angle`.
    #[must_use]
    pub const fn torus_with(angle: WrappedCauchy) -> Self {
        Self {
            angle,
            space: Space::Torus,
        }
    }

    /// The angle distribution.
    #[must_use]
    pub fn angle_distribution(&self) -> WrappedCauchy {
        self.angle
    }

    /// The pair of `z` on the orbit of the pairs `x`, `y`: `y + R(theta) (x - y)` (on the
    /// torus with minimal displacements, wrapped); `None` on the torus if the orbit's radius
    /// is `>= 1/2`. One uniform (drawn in both cases).
    #[inline]
    pub fn orbit_pair<R: Rng + ?Sized>(
        &self,
        x: [f64; 2],
        y: [f64; 2],
        rng: &mut R,
    ) -> Option<[f64; 2]> {
        let dx = self.space.delta(y[0], x[0]);
        let dy = self.space.delta(y[1], x[1]);
        let (cos, sin) = self.angle.sample_rotation(rng);
        if self.space == Space::Torus && dx * dx + dy * dy >= 0.25 {
            return None;
        }
        Some([
            self.space.place(y[0] + cos * dx - sin * dy),
            self.space.place(y[1] + sin * dx + cos * dy),
        ])
    }

    /// `log q2(z | x, y)` over the coordinates of `groups`, read through `read_x`, `read_y`,
    /// `read_z` (see the type docs for the reference measure): the sum of the wrapped Cauchy
    /// log densities of the pairs' angles, `NEG_INFINITY` if `z` is off the orbit (or, on the
    /// torus, the orbit's radius is `>= 1/2`) or a lone coordinate of `z` differs from `x`.
    pub fn groups_log_q(
        &self,
        groups: impl Iterator<Item = Group>,
        read_x: impl Fn(usize) -> f64,
        read_y: impl Fn(usize) -> f64,
        read_z: impl Fn(usize) -> f64,
    ) -> f64 {
        let space = self.space;
        let mut log_q = 0.0;
        for group in groups {
            match group {
                Group::Pair(a, b) => {
                    let (ya, yb) = (read_y(a), read_y(b));
                    let (ux, uy) = (space.delta(ya, read_x(a)), space.delta(yb, read_x(b)));
                    let (vx, vy) = (space.delta(ya, read_z(a)), space.delta(yb, read_z(b)));
                    let r = (ux * ux + uy * uy).sqrt();
                    let s = (vx * vx + vy * vy).sqrt();
                    if (space == Space::Torus && r >= 0.5)
                        || (r - s).abs() > ORBIT_TOLERANCE * r.max(f64::MIN_POSITIVE)
                    {
                        return f64::NEG_INFINITY;
                    }
                    if r > 0.0 {
                        // cos theta of the rotation x -> z about y: eq. 10 needs no angle.
                        log_q += self.angle.log_pdf_cos((ux * vx + uy * vy) / (r * s));
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

impl ConditionalProposal<Vec<f64>> for OrbitalWalk {
    /// `z` on the orbit of `(x, y)`, grouped by [`pairs`]; [`Proposed::Invalid`] if `y` has
    /// another length than `x` or (on the torus) a pair's orbit has radius `>= 1/2`.
    /// Symmetric (`log_hastings = 0`).
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
        for group in pairs(x.len()) {
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
    /// measures (type docs); `NEG_INFINITY` off the orbit or for mismatched lengths.
    fn log_q(&self, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        if y.len() != x.len() || z.len() != x.len() {
            return f64::NEG_INFINITY;
        }
        self.groups_log_q(pairs(x.len()), |i| x[i], |i| y[i], |i| z[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::delayed_rejection::RadialKelemen;
    use crate::proposal::Proposal;
    use crate::torus::{displacement, wrap};
    use rand::{RngExt, SeedableRng};
    use std::f64::consts::PI;

    /// Proposals land where their densities are positive; the orbital stage stays on the
    /// orbit, is symmetric there, and wraps on the torus.
    #[test]
    fn orbital_stage_stays_on_the_orbit() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        for torus in [false, true] {
            let (k, o) = if torus {
                (
                    RadialKelemen::on_torus(0.01, 0.3).unwrap(),
                    OrbitalWalk::on_torus(0.5).unwrap(),
                )
            } else {
                (
                    RadialKelemen::new(0.01, 0.3).unwrap(),
                    OrbitalWalk::new(0.5).unwrap(),
                )
            };
            let x = vec![0.98, 0.02, 0.5, 0.4, 0.7];
            let (mut y, mut z) = (Vec::new(), Vec::new());
            for _ in 0..200 {
                k.propose(&x, &mut y, &mut rng);
                assert!(k.log_q(&x, &y).is_finite());
                assert_eq!(k.log_q(&x, &y), k.log_q(&y, &x));
                o.propose(&x, &y, &mut z, &mut rng);
                if torus {
                    assert!(z.iter().all(|v| (0.0..1.0).contains(v)), "{z:?}");
                }
                let (f, b) = (o.log_q(&x, &y, &z), o.log_q(&z, &y, &x));
                assert!(f.is_finite() && (f - b).abs() < 1e-9, "{f} vs {b}");
                // Q1(y | z) = Q1(y | x) on the orbit.
                assert!((k.log_q(&z, &y) - k.log_q(&x, &y)).abs() < 1e-9);
                assert_eq!(z[4], x[4]);
            }
            let mut off = z.clone();
            off[0] = wrap(off[0] + 1e-3);
            assert_eq!(o.log_q(&x, &y, &off), f64::NEG_INFINITY);
        }
    }

    /// Near the torus seams the orbit radius is kept to rounding, and the reverse move has the
    /// same density.
    #[test]
    fn torus_orbits_keep_their_radius_across_the_seams() {
        let stage1 = RadialKelemen::rioux_lavoie2020();
        let stage2 = OrbitalWalk::torus_with(WrappedCauchy::rioux_lavoie2020());
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let (mut y, mut z) = (Vec::new(), Vec::new());
        for i in 0..2000 {
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
                let r = displacement(y[a], x[a]).hypot(displacement(y[b], x[b]));
                let s = displacement(y[a], z[a]).hypot(displacement(y[b], z[b]));
                assert!((r - s).abs() < 1e-14, "{r} vs {s}");
            }
            let (forward, reverse) = (stage2.log_q(&x, &y, &z), stage2.log_q(&z, &y, &x));
            assert!(forward.is_finite() && (forward - reverse).abs() < 1e-9);
        }
    }

    #[test]
    fn off_orbit_far_and_point_orbits() {
        let o = OrbitalWalk::on_torus(0.5).unwrap();
        let x = vec![0.5, 0.5, 0.1];
        let y = vec![0.51, 0.5, 0.2];
        assert!(o.log_q(&x, &y, &vec![0.52, 0.5, 0.1]).is_finite());
        assert_eq!(o.log_q(&x, &y, &vec![0.53, 0.5, 0.1]), f64::NEG_INFINITY);
        assert_eq!(o.log_q(&x, &y, &vec![0.52, 0.5, 0.2]), f64::NEG_INFINITY);
        assert_eq!(o.log_q(&x, &y, &vec![0.52, 0.5]), f64::NEG_INFINITY);
        // theta = pi: the antipode of x on the orbit.
        let expected = o.angle_distribution().log_pdf(PI);
        assert!((o.log_q(&x, &y, &vec![0.52, 0.5, 0.1]) - expected).abs() < 1e-9);
        // On the torus, a pair whose orbit has radius >= 1/2 has no second stage; in the
        // plane it has.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
        let mut z = Vec::new();
        let (far, y_far) = (vec![0.0, 0.0], vec![0.45, 0.45]);
        assert_eq!(
            o.propose(&far, &y_far, &mut z, &mut rng),
            Proposed::Invalid { component: 0 }
        );
        assert_eq!(o.log_q(&far, &y_far, &far), f64::NEG_INFINITY);
        let plane = OrbitalWalk::new(0.5).unwrap();
        assert_eq!(
            plane.propose(&far, &y_far, &mut z, &mut rng),
            Proposed::symmetric()
        );
        assert!(plane.log_q(&far, &y_far, &z).is_finite());
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
