//! The pairwise polar Kelemen step: the first stage of delayed rejection's orbital scheme (DR
//! paper, section 4.4, Alg. 2 stage 1), in the plane or on the unit torus.

use std::f64::consts::{LN_2, TAU};

use rand::{Rng, RngExt};

use super::pairwise::{pairs, Group, Space};
use crate::proposal::{Proposal, Proposed};
use crate::McmcError;

/// Relative tolerance on radii recomputed from (wrapped) coordinates: a radius drawn as exactly
/// `s2` may come back as `s2 (1 + 1e-15)`.
const RADIUS_TOLERANCE: f64 = 1e-9;

/// The pairwise polar Kelemen step (DR paper, Alg. 2 stage 1; the authors' code's orbital
/// first stage): every coordinate pair moves by `r (cos phi, sin phi)` with `phi` uniform and
/// `r` log-uniform on `[s1, s2]` (Kelemen's exponential law, eq. 9, used as a radius), so the
/// pair density is `1 / (2 pi r^2 ln(s2 / s1))` for `s1 <= r <= s2` (radially symmetric, zero
/// near the centre and beyond `s2`). A lone coordinate ([`Group::Single`], odd dimension)
/// moves by `+-r` with the same radius law (density `1 / (2 |d| ln(s2 / s1))`). Symmetric.
///
/// Its density is a product over groups, each a function of the distance `|y - x|` of the
/// group only: the property that lets the orbital second stage ([`super::OrbitalWalk`]) drop
/// the first-stage ratio (eq. 11).
///
/// On the torus ([`RadialKelemen::on_torus`], `s2 < 1/2`) the candidate is wrapped and
/// distances are minimal-image ones: with `s2 < 1/2` at most one image is in range, so the
/// density stays radial. Densities accept radii within a relative `1e-9` of the bounds
/// (rounding of recomputed radii).
///
/// Random numbers, per group in order ([`pairs`] on a `Vec<f64>`): the radius uniform, then
/// the angle (pair) or sign (lone coordinate) uniform.
///
/// # Example
/// ```
/// use mcmc_core::delayed_rejection::RadialKelemen;
/// use mcmc_core::Proposal;
/// use rand::SeedableRng;
///
/// let step = RadialKelemen::rioux_lavoie2020();
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
/// let x = vec![0.999, 0.5, 0.25];
/// let mut y = Vec::new();
/// step.propose(&x, &mut y, &mut rng);
/// assert!(step.log_q(&x, &y).is_finite());
/// assert_eq!(step.log_q(&x, &y), step.log_q(&y, &x));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadialKelemen {
    s1: f64,
    s2: f64,
    space: Space,
}

impl RadialKelemen {
    /// A step in `R^n` with `0 < s1 < s2`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] for bounds outside that range.
    pub fn new(s1: f64, s2: f64) -> Result<Self, McmcError> {
        McmcError::check_range("s1", s1, f64::MIN_POSITIVE, f64::MAX, "(0, inf)")?;
        McmcError::check_range("s2", s2, s1 * (1.0 + 1e-12), f64::MAX, "(s1, inf)")?;
        Ok(Self {
            s1,
            s2,
            space: Space::Plane,
        })
    }

    /// A step on the torus `[0, 1)^n` with `0 < s1 < s2 < 1/2`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] for bounds outside that range.
    pub fn on_torus(s1: f64, s2: f64) -> Result<Self, McmcError> {
        McmcError::check_range("s2", s2, 0.0, 0.5 - 1e-12, "(s1, 1/2)")?;
        Self::new(s1, s2)?;
        Ok(Self::torus_unchecked(s1, s2))
    }

    /// A step on the torus with bounds the caller has validated (`0 < s1 < s2 < 1/2`, as
    /// `pss::PairwiseKelemenParams::new` does).
    #[must_use]
    pub const fn torus_unchecked(s1: f64, s2: f64) -> Self {
        Self {
            s1,
            s2,
            space: Space::Torus,
        }
    }

    /// The authors' code's orbital first stage: Kelemen 2002's bounds `[1/1024, 1/64]` scaled
    /// by 1.9 ("compensate pairwise vs i.i.d."), on the torus (the DR paper's renders,
    /// section 5; docs/methods/drmlt.md).
    #[must_use]
    pub fn rioux_lavoie2020() -> Self {
        Self::on_torus(1.9 / 1024.0, 1.9 / 64.0).expect("valid constants")
    }

    /// The bounds `(s1, s2)`.
    #[must_use]
    pub fn bounds(&self) -> (f64, f64) {
        (self.s1, self.s2)
    }

    /// `ln(s2 / s1)`.
    #[inline]
    fn log_ratio(&self) -> f64 {
        (self.s2 / self.s1).ln()
    }

    /// The radius for a uniform `u` in `[0, 1)`: `s2 exp(-u ln(s2 / s1))` (eq. 9).
    #[inline]
    #[must_use]
    pub fn radius(&self, u: f64) -> f64 {
        self.s2 * (-u * self.log_ratio()).exp()
    }

    /// `P(R <= r)` of the radius: `ln(r / s1) / ln(s2 / s1)` on `[s1, s2]`.
    #[must_use]
    pub fn radius_cdf(&self, r: f64) -> f64 {
        ((r / self.s1).ln() / self.log_ratio()).clamp(0.0, 1.0)
    }

    /// Log density of the radius: `-ln(r ln(s2 / s1))` on `[s1, s2]`.
    #[must_use]
    pub fn radius_log_pdf(&self, r: f64) -> f64 {
        if self.in_support(r) {
            -(r * self.log_ratio()).ln()
        } else {
            f64::NEG_INFINITY
        }
    }

    /// True if `r` is a radius of the law (to the relative tolerance of the bounds).
    #[inline]
    #[must_use]
    pub fn in_support(&self, r: f64) -> bool {
        r >= self.s1 * (1.0 - RADIUS_TOLERANCE) && r <= self.s2 * (1.0 + RADIUS_TOLERANCE)
    }

    /// Log density (w.r.t. area) of the pair displacement `(dx, dy)`:
    /// `-ln(2 pi r^2 ln(s2 / s1))` for `r = |(dx, dy)|` in the annulus.
    #[must_use]
    pub fn pair_log_density(&self, dx: f64, dy: f64) -> f64 {
        let r = dx.hypot(dy);
        if self.in_support(r) {
            -(TAU * r * r * self.log_ratio()).ln()
        } else {
            f64::NEG_INFINITY
        }
    }

    /// Log density of the 1-D step of a lone coordinate (a radius with a random sign):
    /// `-ln(2 |d| ln(s2 / s1))` for `|d|` in `[s1, s2]`.
    #[must_use]
    pub fn single_log_density(&self, d: f64) -> f64 {
        let r = d.abs();
        if self.in_support(r) {
            -(r * self.log_ratio()).ln() - LN_2
        } else {
            f64::NEG_INFINITY
        }
    }

    /// A pair `(a, b)` moved by `r (cos phi, sin phi)` (wrapped on the torus). Two uniforms:
    /// the radius, then the angle.
    #[inline]
    pub fn perturb_pair<R: Rng + ?Sized>(&self, [a, b]: [f64; 2], rng: &mut R) -> [f64; 2] {
        let r = self.radius(rng.random());
        let (sin, cos) = (TAU * rng.random::<f64>()).sin_cos();
        [self.space.place(a + r * cos), self.space.place(b + r * sin)]
    }

    /// A lone coordinate moved by `+-r` (wrapped on the torus). Two uniforms: the radius, then
    /// the sign.
    #[inline]
    pub fn perturb_single<R: Rng + ?Sized>(&self, a: f64, rng: &mut R) -> f64 {
        let r = self.radius(rng.random());
        self.space.place(if rng.random::<f64>() < 0.5 {
            a + r
        } else {
            a - r
        })
    }

    /// Log density of moving the coordinates of `groups` from `from` to `to` (the product of
    /// the group densities), with the coordinates read by `from(i)` and `to(i)`.
    pub fn groups_log_q(
        &self,
        groups: impl Iterator<Item = Group>,
        from: impl Fn(usize) -> f64,
        to: impl Fn(usize) -> f64,
    ) -> f64 {
        let space = self.space;
        let mut log_q = 0.0;
        for group in groups {
            log_q += match group {
                Group::Pair(a, b) => {
                    self.pair_log_density(space.delta(from(a), to(a)), space.delta(from(b), to(b)))
                }
                Group::Single(a) => self.single_log_density(space.delta(from(a), to(a))),
            };
            if log_q == f64::NEG_INFINITY {
                break;
            }
        }
        log_q
    }
}

impl Proposal<Vec<f64>> for RadialKelemen {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clone_from(x);
        for group in pairs(x.len()) {
            match group {
                Group::Pair(a, b) => [y[a], y[b]] = self.perturb_pair([x[a], x[b]], rng),
                Group::Single(a) => y[a] = self.perturb_single(x[a], rng),
            }
        }
        Proposed::symmetric()
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        if from.len() != to.len() {
            return f64::NEG_INFINITY;
        }
        self.groups_log_q(pairs(from.len()), |i| from[i], |i| to[i])
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::torus::displacement;
    use rand::SeedableRng;

    #[test]
    fn constructors_validate() {
        assert!(RadialKelemen::new(0.1, 0.1).is_err());
        assert!(RadialKelemen::new(0.0, 0.1).is_err());
        assert!(RadialKelemen::new(0.01, f64::NAN).is_err());
        assert!(RadialKelemen::on_torus(0.1, 0.6).is_err());
        assert!(RadialKelemen::on_torus(0.01, 0.5).is_err());
        let k = RadialKelemen::rioux_lavoie2020();
        assert_eq!(k.bounds(), (1.9 / 1024.0, 1.9 / 64.0));
    }

    #[test]
    fn radius_law_is_log_uniform_and_the_densities_are_normalised() {
        let k = RadialKelemen::new(0.01, 0.2).unwrap();
        assert!((k.radius(0.0) - 0.2).abs() < 1e-18);
        assert!((k.radius(1.0) - 0.01).abs() < 1e-15);
        for u in [0.1, 0.5, 0.9] {
            // radius(u) is decreasing: P(R <= radius(u)) = 1 - u.
            assert!((k.radius_cdf(k.radius(u)) - (1.0 - u)).abs() < 1e-12);
        }
        // The radius over its support, the pair over the annulus in polar coordinates, the
        // lone coordinate over both signs.
        let n = 100_000;
        let (mut radius, mut pair, mut single) = (0.0, 0.0, 0.0);
        let dr = (0.2 - 0.01) / n as f64;
        for i in 0..n {
            let r = 0.01 + (i as f64 + 0.5) * dr;
            radius += k.radius_log_pdf(r).exp() * dr;
            pair += k.pair_log_density(r, 0.0).exp() * TAU * r * dr;
            single += 2.0 * k.single_log_density(-r).exp() * dr;
        }
        for total in [radius, pair, single] {
            assert!((total - 1.0).abs() < 1e-6, "{radius} {pair} {single}");
        }
        assert_eq!(k.pair_log_density(0.0099, 0.0), f64::NEG_INFINITY);
        assert_eq!(k.single_log_density(0.21), f64::NEG_INFINITY);
    }

    #[test]
    fn torus_steps_wrap_and_have_their_radius() {
        let step = RadialKelemen::rioux_lavoie2020();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let x = vec![0.9999, 0.0001, 0.5, 0.999_99, 0.3];
        let mut y = Vec::new();
        for _ in 0..1000 {
            step.propose(&x, &mut y, &mut rng);
            assert!(y.iter().all(|v| (0.0..1.0).contains(v)));
            for (a, b) in [(0, 1), (2, 3)] {
                let r = displacement(x[a], y[a]).hypot(displacement(x[b], y[b]));
                assert!(step.in_support(r), "{r}");
            }
            let lq = step.log_q(&x, &y);
            assert!(lq.is_finite());
            assert_eq!(lq, step.log_q(&y, &x));
        }
        assert_eq!(step.log_q(&x, &x), f64::NEG_INFINITY);
        assert_eq!(step.log_q(&x, &y[..4].to_vec()), f64::NEG_INFINITY);
    }
}
