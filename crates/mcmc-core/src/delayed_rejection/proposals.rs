//! Stages for delayed rejection on `Vec<f64>` states: the wrapped Cauchy, a pairwise radial
//! Kelemen first stage, a pairwise orbital second stage, and adapters.
//!
//! These are the toy (state-space-agnostic) counterparts of the primary-sample-space
//! mutations of the DR paper's section 4.4 and Alg. 2, on plain vectors in `R^n` or on the
//! unit torus `[0, 1)^n`, for tests and examples; the `pss` crate has its own for `PssState`.

use std::f64::consts::TAU;

use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};

use crate::proposal::{ConditionalProposal, Proposal, Proposed};
use crate::torus::{wrap, wrapped_normal_pdf};
use crate::McmcError;

use super::wrapped_cauchy::WrappedCauchy;

/// Relative tolerance on `|z - y| = |x - y|` when [`OrbitalWalk::log_q`] decides whether `z`
/// lies on the orbit (rounding of a rotation is about `1e-16` relative).
pub const ORBIT_TOLERANCE: f64 = 1e-9;

/// How a pairwise stage measures and applies displacements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Space {
    Plane,
    Torus,
}

impl Space {
    /// The displacement `to - from` (on the torus: the minimal image, in `[-1/2, 1/2]`).
    fn delta(self, from: f64, to: f64) -> f64 {
        let d = to - from;
        match self {
            Space::Plane => d,
            Space::Torus => d - d.round(),
        }
    }

    fn place(self, v: f64) -> f64 {
        match self {
            Space::Plane => v,
            Space::Torus => wrap(v),
        }
    }
}

/// The pairwise polar Kelemen step (DR paper, Alg. 2 stage 1; the reference implementation's
/// orbital first stage): coordinates in pairs `(0, 1), (2, 3), ...`; each pair moves by
/// `d (cos phi, sin phi)` with `phi` uniform and `d` log-uniform on `[s1, s2]`, so the pair
/// density is `1 / (2 pi d^2 ln(s2 / s1))` for `s1 <= d <= s2` (radially symmetric, zero near
/// the centre and beyond `s2`). An odd trailing coordinate takes a 1-D Kelemen step (eq. 9:
/// random sign, `|d|` log-uniform, density `1 / (2 |d| ln(s2 / s1))`). Symmetric.
///
/// On the torus ([`RadialKelemen::on_torus`], `s2 < 1/2`) the candidate is wrapped and
/// distances are minimal-image ones: with `s2 < 1/2` at most one image is in range, so the
/// density stays radial (what the orbital rule needs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadialKelemen {
    s1: f64,
    s2: f64,
    log_ratio: f64,
    space: Space,
}

impl RadialKelemen {
    /// A step in `R^n` with `0 < s1 < s2`.
    pub fn new(s1: f64, s2: f64) -> Result<Self, McmcError> {
        McmcError::check_range("s1", s1, f64::MIN_POSITIVE, f64::MAX, "(0, inf)")?;
        McmcError::check_range("s2", s2, s1 * (1.0 + 1e-12), f64::MAX, "(s1, inf)")?;
        Ok(Self {
            s1,
            s2,
            log_ratio: (s2 / s1).ln(),
            space: Space::Plane,
        })
    }

    /// A step on the torus `[0, 1)^n` with `0 < s1 < s2 < 1/2`.
    pub fn on_torus(s1: f64, s2: f64) -> Result<Self, McmcError> {
        McmcError::check_range("s2", s2, 0.0, 0.5 - 1e-12, "(s1, 1/2)")?;
        let mut k = Self::new(s1, s2)?;
        k.space = Space::Torus;
        Ok(k)
    }

    /// The reference implementation's orbital first stage: Kelemen 2002's bounds
    /// `[1/1024, 1/64]` scaled by 1.9 ("compensate pairwise vs i.i.d."), on the torus
    /// (../shared/notes/reference-implementations.md, section 2).
    #[must_use]
    pub fn rioux_lavoie2020() -> Self {
        Self::on_torus(1.9 / 1024.0, 1.9 / 64.0).expect("valid constants")
    }

    /// The bounds `(s1, s2)`.
    #[must_use]
    pub fn bounds(&self) -> (f64, f64) {
        (self.s1, self.s2)
    }

    fn radius<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.s2 * (-self.log_ratio * rng.random::<f64>()).exp()
    }

    fn log_pair_density(&self, d: f64) -> f64 {
        if d < self.s1 || d > self.s2 {
            f64::NEG_INFINITY
        } else {
            -(TAU * self.log_ratio).ln() - 2.0 * d.ln()
        }
    }
}

impl Proposal<Vec<f64>> for RadialKelemen {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clone_from(x);
        let pairs = x.len() / 2;
        for p in 0..pairs {
            let d = self.radius(rng);
            let phi = TAU * rng.random::<f64>();
            y[2 * p] = self.space.place(x[2 * p] + d * phi.cos());
            y[2 * p + 1] = self.space.place(x[2 * p + 1] + d * phi.sin());
        }
        if x.len() % 2 == 1 {
            let i = x.len() - 1;
            let d = self.radius(rng);
            let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
            y[i] = self.space.place(x[i] + sign * d);
        }
        Proposed::symmetric()
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        if from.len() != to.len() {
            return f64::NEG_INFINITY;
        }
        let mut log_q = 0.0;
        for p in 0..from.len() / 2 {
            let dx = self.space.delta(from[2 * p], to[2 * p]);
            let dy = self.space.delta(from[2 * p + 1], to[2 * p + 1]);
            log_q += self.log_pair_density(dx.hypot(dy));
        }
        if from.len() % 2 == 1 {
            let i = from.len() - 1;
            let d = self.space.delta(from[i], to[i]).abs();
            log_q += if d < self.s1 || d > self.s2 {
                f64::NEG_INFINITY
            } else {
                -(2.0 * d * self.log_ratio).ln()
            };
        }
        log_q
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

/// The pairwise orbital second stage (DR paper, section 4.4, Alg. 2 stage 2): in each
/// coordinate pair, `z` lies on the circle centred at the rejected `y` through the current
/// `x`, at the angle of `x` (seen from `y`) plus a [`WrappedCauchy`] offset. An odd trailing
/// coordinate stays at `x` (its 1-D "orbit" `{x, 2y - x}` is taken at `x`).
///
/// Then `|z - y| = |x - y|` per pair, so a radially symmetric pairwise first stage has
/// `Q1(y|z) = Q1(y|x)`, and the move is symmetric (`Q2(z|x,y) = Q2(x|z,y)`): the conditions
/// of the orbital rule (eq. 11).
///
/// **Density.** The proposal is singular (it lives on a product of circles).
/// [`ConditionalProposal::log_q`] returns the density with respect to the product of the
/// pairs' angle measures, `sum over pairs of ln p(theta)`, for `z` on the orbit (to
/// [`ORBIT_TOLERANCE`] relative), and `-inf` off it (also when a pair's `x = y` but `z != x`;
/// with `x = y` and `z = x` the factor is 1). The reverse path `z -> (y) -> x` maps the pair
/// angles `theta -> -theta` by a rotation about `y`, whose Jacobian is 1, so forward and
/// reverse densities on the orbit compare directly, which is what a flow check needs.
///
/// On the torus ([`OrbitalWalk::on_torus`]) displacements are minimal-image ones and `z` is
/// wrapped; exact while every pair's `|x - y| < 1/2` (e.g. after [`RadialKelemen::on_torus`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitalWalk {
    angle: WrappedCauchy,
    space: Space,
}

impl OrbitalWalk {
    /// An orbital stage in `R^n` with wrapped Cauchy concentration `rho` in `[0, 1)`.
    pub fn new(rho: f64) -> Result<Self, McmcError> {
        Ok(Self {
            angle: WrappedCauchy::new(rho)?,
            space: Space::Plane,
        })
    }

    /// An orbital stage on the torus `[0, 1)^n`.
    pub fn on_torus(rho: f64) -> Result<Self, McmcError> {
        let mut o = Self::new(rho)?;
        o.space = Space::Torus;
        Ok(o)
    }

    /// The angle distribution.
    #[must_use]
    pub fn angle_distribution(&self) -> WrappedCauchy {
        self.angle
    }
}

impl ConditionalProposal<Vec<f64>> for OrbitalWalk {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &Vec<f64>,
        y: &Vec<f64>,
        z: &mut Vec<f64>,
        rng: &mut R,
    ) -> Proposed {
        if x.len() != y.len() {
            return Proposed::Invalid { component: 0 };
        }
        z.clone_from(x);
        for p in 0..x.len() / 2 {
            let (i, k) = (2 * p, 2 * p + 1);
            let wx = self.space.delta(y[i], x[i]);
            let wy = self.space.delta(y[k], x[k]);
            let r = wx.hypot(wy);
            let mu = wy.atan2(wx) + self.angle.quantile(rng.random::<f64>());
            if r > 0.0 {
                z[i] = self.space.place(y[i] + r * mu.cos());
                z[k] = self.space.place(y[k] + r * mu.sin());
            }
        }
        Proposed::symmetric()
    }

    fn log_q(&self, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        if x.len() != y.len() || x.len() != z.len() {
            return f64::NEG_INFINITY;
        }
        let mut log_q = 0.0;
        for p in 0..x.len() / 2 {
            let (i, k) = (2 * p, 2 * p + 1);
            let (xa, xb) = (self.space.delta(y[i], x[i]), self.space.delta(y[k], x[k]));
            let (za, zb) = (self.space.delta(y[i], z[i]), self.space.delta(y[k], z[k]));
            let (rx, rz) = (xa.hypot(xb), za.hypot(zb));
            if (rx - rz).abs() > ORBIT_TOLERANCE * rx.max(rz) {
                return f64::NEG_INFINITY;
            }
            if rx == 0.0 {
                continue; // x = y = z in this pair: a point orbit, probability 1.
            }
            log_q += self.angle.log_pdf(zb.atan2(za) - xb.atan2(xa));
        }
        if x.len() % 2 == 1 && z[x.len() - 1] != x[x.len() - 1] {
            return f64::NEG_INFINITY;
        }
        log_q
    }
}

/// A second stage that ignores the rejected candidate: `z ~ P(. | x)`, so
/// `Q2(z | x, y) = P(z | x)` (e.g. the reference implementation's timid Gaussian second stage
/// of the Tierney-Mira and Green-Mira variants, sigma = first-stage sigma / 10).
/// Symmetric when `P` is: then use
/// [`super::DelayedRejection::with_symmetric_second_stage`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndependentSecondStage<P>(pub P);

impl<S, P: Proposal<S>> ConditionalProposal<S> for IndependentSecondStage<P> {
    fn propose<R: Rng + ?Sized>(&self, x: &S, _y: &S, z: &mut S, rng: &mut R) -> Proposed {
        self.0.propose(x, z, rng)
    }

    fn log_q(&self, x: &S, _y: &S, z: &S) -> f64 {
        self.0.log_q(x, z)
    }
}

/// The Gaussian random walk on the unit torus: `y_i = wrap(x_i + sigma N(0, 1))`, with the
/// wrapped normal as its exact density (images `-3..=3`, exact to `1e-23` for
/// `sigma <= 1/4`). Symmetric. Only for states in `[0, 1)^n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrappedGaussianWalk {
    sigma: f64,
}

impl WrappedGaussianWalk {
    /// A walk with standard deviation `sigma` in `(0, 1/4]`.
    pub fn new(sigma: f64) -> Result<Self, McmcError> {
        McmcError::check_range("sigma", sigma, f64::MIN_POSITIVE, 0.25, "(0, 0.25]")?;
        Ok(Self { sigma })
    }

    /// The standard deviation per coordinate.
    #[must_use]
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
}

impl Proposal<Vec<f64>> for WrappedGaussianWalk {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clear();
        y.extend(x.iter().map(|&v| {
            let n: f64 = StandardNormal.sample(rng);
            wrap(v + self.sigma * n)
        }));
        Proposed::symmetric()
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        if from.len() != to.len() {
            return f64::NEG_INFINITY;
        }
        from.iter()
            .zip(to)
            .map(|(&a, &b)| wrapped_normal_pdf(wrap(b - a), 0.0, self.sigma).ln())
            .sum()
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use std::f64::consts::PI;

    #[test]
    fn constructors_validate() {
        assert!(WrappedCauchy::new(1.0).is_err());
        assert!(WrappedCauchy::new(-0.1).is_err());
        assert!(RadialKelemen::new(0.1, 0.1).is_err());
        assert!(RadialKelemen::new(0.0, 0.1).is_err());
        assert!(RadialKelemen::on_torus(0.1, 0.6).is_err());
        assert!(OrbitalWalk::new(f64::NAN).is_err());
        assert!(WrappedGaussianWalk::new(0.3).is_err());
        let k = RadialKelemen::rioux_lavoie2020();
        assert_eq!(k.bounds(), (1.9 / 1024.0, 1.9 / 64.0));
        assert!((WrappedCauchy::rioux_lavoie2020().rho() - 0.778_800_783).abs() < 1e-9);
    }

    /// The wrapped Cauchy density integrates to 1, and inverse-CDF samples follow it: the
    /// fraction of `angle(u)` below `t` is `F(t)`, checked on a fine `u` grid (deterministic).
    #[test]
    fn wrapped_cauchy_is_normalised_and_inverts_its_cdf() {
        let wc = WrappedCauchy::new(0.7).unwrap();
        let n = 200_000;
        let h = TAU / n as f64;
        let total: f64 = (0..n)
            .map(|i| wc.log_pdf(-PI + (i as f64 + 0.5) * h).exp() * h)
            .sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        // CDF by quadrature at a few points vs the sampler's quantiles.
        for &u in &[0.05, 0.3, 0.5, 0.77, 0.99] {
            let t = wc.quantile(u);
            let m = 100_000;
            let w = (t + PI) / m as f64;
            let cdf: f64 = (0..m)
                .map(|i| wc.log_pdf(-PI + (i as f64 + 0.5) * w).exp() * w)
                .sum();
            assert!((cdf - u).abs() < 1e-8, "u {u}: F(angle(u)) = {cdf}");
        }
    }

    /// The pair density integrates to 1 over the annulus (polar quadrature), and the 1-D
    /// trailing factor too.
    #[test]
    fn radial_kelemen_is_normalised() {
        let k = RadialKelemen::new(0.01, 0.2).unwrap();
        let n = 100_000;
        let h = (0.2 - 0.01) / n as f64;
        let pair: f64 = (0..n)
            .map(|i| {
                let d = 0.01 + (i as f64 + 0.5) * h;
                k.log_pair_density(d).exp() * TAU * d * h
            })
            .sum();
        assert!((pair - 1.0).abs() < 1e-8, "{pair}");
        let x = vec![0.0];
        let w = 0.42 / (2 * n) as f64;
        let line: f64 = (0..2 * n)
            .map(|i| k.log_q(&x, &vec![-0.21 + (i as f64 + 0.5) * w]).exp() * w)
            .sum();
        assert!((line - 1.0).abs() < 1e-3, "{line}");
    }

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

    #[test]
    fn wrapped_walk_is_symmetric_across_the_seam() {
        let w = WrappedGaussianWalk::new(0.1).unwrap();
        let (a, b) = (vec![0.97, 0.5], vec![0.02, 0.45]);
        assert!((w.log_q(&a, &b) - w.log_q(&b, &a)).abs() < 1e-12);
        let i = IndependentSecondStage(w);
        assert_eq!(i.log_q(&a, &vec![0.3, 0.3], &b), w.log_q(&a, &b));
    }
}
