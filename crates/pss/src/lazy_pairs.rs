//! The orbital delayed-rejection stages at the cost of what a path reads: the pairwise polar
//! Kelemen first stage and the orbital second stage (DR paper section 4.4, Alg. 2) applied
//! lazily, pair by pair, to the coordinates the target reads, with the unread pairs caught up
//! exactly when first read.
//!
//! # The chain they define
//!
//! Both stages act on *every* pair `(2k, 2k + 1)` of every stream (an unbounded layout, no
//! lone coordinates): stage 1 moves each pair by an independent polar Kelemen step `d`, the
//! orbital stage puts each pair of `z` at `y + R(theta) (x - y) = x + d - R(theta) d`. The
//! closed-form acceptance of eq. 11 needs `Q1(y | z) = Q1(y | x)` and a symmetric `Q2`, which
//! hold pair by pair on this unbounded layout exactly as on a fixed one; no layout depends on
//! the state, so nothing is asymmetric. What is lazy is only *when* a pair is computed.
//!
//! # Why lazy equals eager
//!
//! [`crate::PssState`]'s argument (deferred decisions) with two kinds of missed steps. A pair
//! that no evaluation read since it was stored influenced no decision; given the chain's
//! history it is the stored pair moved by the `m1` accepted first-stage steps and the `m2`
//! accepted second-stage steps since (a fresh uniform pair after a large step): `m1` polar
//! Kelemen steps `d` and `m2` composite steps `d - R(theta) d`, all independent. Both are
//! translations on the torus, so their order does not matter, and the state counts them per
//! stream ([`crate::PssState`] keeps a second stamp for the accepted orbital steps). A
//! candidate draws the parent's pair from that law when it first reads it, logs it, and the
//! parent absorbs it on rejection, as for the per-coordinate lazy step. The two coordinates
//! of a pair are always computed and stored together, so they share their stamps.
//!
//! One more rule makes the second stage exact: a pair the rejected `y` read is *observed*
//! (its `d` entered `pi(y)` and the first decision), so its move in `z` is not a fresh
//! composite step but `y`'s own `d` rotated. [`LazyOrbital`] therefore computes `z` at every
//! pair `y` read when it proposes `z` (the cost of what `y` read), and lazily elsewhere.
//!
//! Random numbers: one key per candidate from the chain's RNG; the pair of stream `s`
//! starting at interleaved index `a` draws its radius, direction and rotation from the
//! sequence [`PairDraws`]`(key, a)`, so `z` can recompute `y`'s `d` from `y`'s key where `y`
//! did not read the pair (where it did, `d` is `y`'s pair minus `x`'s). A catch-up draws the
//! missed steps by their law: `m1` first-stage steps, then `m2` composite steps each drawn
//! as a length and a direction ([`LazyPairParams::composite_step`]). No trigonometry: the
//! directions are normalised points of the disc, the wrapped Cauchy rotation comes from
//! another such point ([`WrappedCauchy::rotation_of_point`]).

use mcmc_core::delayed_rejection::{Group, OrbitalWalk, WrappedCauchy};
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::seed::mix64;
use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::pairwise::{torus_displacement, PairwiseKelemenParams};
use crate::state::{split_index, Pending, PssState};

/// The laws of the lazy pairwise stages: the first stage's polar Kelemen radii and the
/// orbital stage's wrapped Cauchy angle (DR paper eq. 9-10), and the streams whose first
/// number no small step moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LazyPairParams {
    /// Radius bounds of the first stage.
    pub step: PairwiseKelemenParams,
    /// Angle law of the orbital stage.
    pub angle: WrappedCauchy,
    /// Streams (bit s = stream s) whose number 0 is kept by both stages (renewed by large
    /// steps only; MMLT's strategy choice, the DR paper's fixed strategy): their pairs are
    /// `(1, 2), (3, 4), ...`. Exact: a fixed partition into pairs and kept coordinates (a
    /// kept coordinate is its own reverse move in both stages). Default 0.
    pub fixed_first: u8,
}

impl LazyPairParams {
    /// The interleaved indices of the pair holding coordinate `index` of a state with
    /// `streams` streams, or `None` for a kept first number ([`LazyPairParams::fixed_first`]).
    #[inline]
    #[must_use]
    pub fn pair_of(&self, index: usize, streams: usize) -> Option<[usize; 2]> {
        let (k, stream) = split_index(index, streams);
        self.pair_at(k, stream, streams)
    }

    /// [`LazyPairParams::pair_of`] for the `k`-th number of stream `stream`.
    #[inline]
    #[must_use]
    pub fn pair_at(&self, k: usize, stream: usize, streams: usize) -> Option<[usize; 2]> {
        let offset = usize::from(self.fixed_first & (1 << stream) != 0);
        if k < offset {
            return None;
        }
        let first = ((k - offset) & !1) + offset;
        let a = stream + streams * first;
        Some([a, a + streams])
    }
}

impl LazyPairParams {
    /// The authors' values: radii `[1.9/1024, 1.9/64]`
    /// ([`PairwiseKelemenParams::drmlt2020`]), `rho = exp(-1/4)` (section 5.1.1).
    #[must_use]
    pub fn rioux_lavoie2020() -> Self {
        Self {
            step: PairwiseKelemenParams::drmlt2020(),
            angle: WrappedCauchy::rioux_lavoie2020(),
            fixed_first: 0,
        }
    }

    /// The same laws keeping the first number of the streams of `streams`.
    #[must_use]
    pub const fn with_fixed_first(mut self, streams: u8) -> Self {
        self.fixed_first = streams;
        self
    }

    /// The first-stage displacement of a pair drawn from `draws`: `r (cos phi, sin phi)`, `r`
    /// log-uniform (eq. 9), the direction uniform on the circle and independent of `r`: both
    /// from one point of the disc ([`PairDraws::direction_and_uniform`]).
    #[inline]
    #[must_use]
    pub fn step_displacement(&self, draws: &mut PairDraws) -> [f64; 2] {
        self.step_displacement_with(self.log_radius_ratio(), draws)
    }

    /// `ln(r_max / r_min)` of the first stage's radii (computed once per pair, not per draw).
    #[inline]
    #[must_use]
    pub fn log_radius_ratio(&self) -> f64 {
        (self.step.r_max / self.step.r_min).ln()
    }

    /// The radius `r_max exp(-u ln(r_max / r_min))` of eq. 9 ([`PairwiseKelemenParams::radius`])
    /// given `log_ratio` = [`LazyPairParams::log_radius_ratio`]; `u` uniform on `[0, 1)` or
    /// on `(0, 1]` gives the same law.
    #[inline]
    fn radius_with(&self, log_ratio: f64, u: f64) -> f64 {
        self.step.r_max * (-u * log_ratio).exp()
    }

    /// [`LazyPairParams::step_displacement`] given [`LazyPairParams::log_radius_ratio`].
    #[inline]
    #[must_use]
    pub fn step_displacement_with(&self, log_ratio: f64, draws: &mut PairDraws) -> [f64; 2] {
        let ([cos, sin], u) = draws.direction_and_uniform();
        let r = self.radius_with(log_ratio, u);
        [r * cos, r * sin]
    }

    /// The rotation `R(theta)` of the orbital stage (eq. 10) drawn from `draws`, as
    /// `(cos theta, sin theta)` ([`WrappedCauchy::rotation_of_point`] of a uniform point of
    /// the disc: no trigonometry).
    #[inline]
    #[must_use]
    pub fn rotation(&self, draws: &mut PairDraws) -> (f64, f64) {
        let [x, y, _] = draws.disc_point();
        self.angle.rotation_of_point(x, y)
    }

    /// The move `d - R(theta) d` of a pair on its orbit (eq. 10), `R(theta)` given as
    /// `(cos theta, sin theta)`.
    #[inline]
    #[must_use]
    pub fn orbit_displacement(&self, d: [f64; 2], (cos, sin): (f64, f64)) -> [f64; 2] {
        [
            d[0] - (cos * d[0] - sin * d[1]),
            d[1] - (sin * d[0] + cos * d[1]),
        ]
    }

    /// One composite step `d - R(theta) d` with `d` a first-stage step, drawn by its law
    /// rather than by its parts: for `d = r e^(i phi)`, `d - R(theta) d = r (1 - e^(i theta))
    /// e^(i phi)` has length `2 r |sin(theta / 2)|` and, `phi` being uniform and independent
    /// of `r` and `theta`, a uniform direction independent of its length. So: a radius and a
    /// direction (one disc point, [`PairDraws::direction_and_uniform`]) and a half-angle sine
    /// ([`WrappedCauchy::half_angle_sine_of_point`] of another).
    /// `log_ratio`: [`LazyPairParams::log_radius_ratio`].
    #[inline]
    #[must_use]
    pub fn composite_step(&self, log_ratio: f64, draws: &mut PairDraws) -> [f64; 2] {
        let ([cos, sin], u) = draws.direction_and_uniform();
        let r = self.radius_with(log_ratio, u);
        let [x, y, _] = draws.disc_point();
        let length = 2.0 * r * self.angle.half_angle_sine_of_point(x, y);
        [length * cos, length * sin]
    }

    /// The sum of `first` first-stage steps and `second` composite steps of the pair at `a`,
    /// drawn from `key` (the catch-up of missed accepted steps: translations commute, so only
    /// the counts matter). `log_ratio`: [`LazyPairParams::log_radius_ratio`].
    #[must_use]
    pub fn missed_steps(
        &self,
        log_ratio: f64,
        key: u64,
        a: u64,
        first: u64,
        second: u64,
    ) -> [f64; 2] {
        let mut draws = PairDraws::new(key, a);
        let mut total = [0.0, 0.0];
        for _ in 0..first {
            let d = self.step_displacement_with(log_ratio, &mut draws);
            total[0] += d[0];
            total[1] += d[1];
        }
        for _ in 0..second {
            let d = self.composite_step(log_ratio, &mut draws);
            total[0] += d[0];
            total[1] += d[1];
        }
        total
    }
}

/// The random numbers of one pair of one candidate: a sequence of uniforms that is a pure
/// function of `(key, a)` (the candidate's noise key and the pair's first interleaved index),
/// drawn in order (SplitMix64 from a hashed start: one hash to start, one per uniform, where
/// [`crate::noise::uniform`] costs three). Different keys or pairs give independent
/// sequences, and the result does not depend on the order in which pairs are read.
///
/// The pair moves sit on the path sampler's critical path (a path reads a number and at once
/// traces with it), so the draws are built for latency: one hash to start a sequence, and
/// points of the disc used whole, their angle for a direction without a square root and
/// their squared radius as a second uniform ([`PairDraws::direction_and_uniform`]).
#[derive(Clone, Copy, Debug)]
pub struct PairDraws {
    state: u64,
}

/// The SplitMix64 increment (odd: the counter visits every value).
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// Salt of the pair sequences.
const PAIR_SALT: u64 = 0x7061_6972_2d64_7277;

/// Tries of the disc point's rejection sampler before its fallback.
const DISC_TRIES: u32 = 32;

impl PairDraws {
    /// The sequence of the pair at `a` for the noise key `key`.
    #[inline]
    #[must_use]
    pub fn new(key: u64, a: u64) -> Self {
        // `a * GOLDEN` is injective in `a` (an odd multiplier), so distinct pairs of one key
        // start from distinct inputs, which the bijective `mix64` scatters.
        Self {
            state: mix64(key ^ a.wrapping_mul(GOLDEN) ^ PAIR_SALT),
        }
    }

    /// The next uniform in `[0, 1)` (53 random bits).
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        self.state = self.state.wrapping_add(GOLDEN);
        (mix64(self.state) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A point `[x, y, q = x^2 + y^2]` uniform on the unit disc without its centre (the first
    /// point of the square `[-1, 1)^2` inside it; about 1.27 points on average): its angle
    /// is uniform on the circle, `q` is uniform on `(0, 1]`, and the two are independent.
    /// After 32 rejected points (probability below `1e-21`) the point `sqrt(v) e^(2 pi i u)`
    /// of two further uniforms, which has the same law.
    #[inline]
    pub fn disc_point(&mut self) -> [f64; 3] {
        for _ in 0..DISC_TRIES {
            let x = 2.0 * self.uniform() - 1.0;
            let y = 2.0 * self.uniform() - 1.0;
            let q = x * x + y * y;
            if q <= 1.0 && q > 0.0 {
                return [x, y, q];
            }
        }
        self.disc_fallback()
    }

    #[cold]
    #[inline(never)]
    fn disc_fallback(&mut self) -> [f64; 3] {
        let (sin, cos) = (std::f64::consts::TAU * self.uniform()).sin_cos();
        let q = 1.0 - self.uniform();
        let r = q.sqrt();
        [r * cos, r * sin, q]
    }

    /// A direction uniform on the unit circle and a uniform on `(0, 1]` independent of it,
    /// from one [`PairDraws::disc_point`] `(x, y, q)`: the direction at twice the point's
    /// angle, `((x^2 - y^2) / q, 2 x y / q)` (doubling an angle uniform on the circle leaves
    /// it uniform; von Neumann's construction, no square root, no trigonometry), and `q`.
    #[inline]
    pub fn direction_and_uniform(&mut self) -> ([f64; 2], f64) {
        let [x, y, q] = self.disc_point();
        let inv = 1.0 / q;
        ([(x * x - y * y) * inv, 2.0 * x * y * inv], q)
    }

    /// A direction uniform on the unit circle ([`PairDraws::direction_and_uniform`]).
    #[inline]
    pub fn direction(&mut self) -> [f64; 2] {
        self.direction_and_uniform().0
    }
}

impl Default for LazyPairParams {
    fn default() -> Self {
        Self::rioux_lavoie2020()
    }
}

/// The lazy pairwise polar Kelemen first stage: the candidate is a copy of `x` with the
/// pending [`Pending::Pairs`]; each pair the target reads is caught up and moved then (see
/// the [module docs](self)). Symmetric.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LazyPairwise {
    /// Radius and angle laws.
    pub params: LazyPairParams,
}

/// The pairs of `streams` streams whose coordinates are below `len`, as groups.
fn stored_pairs(params: LazyPairParams, streams: usize, len: usize) -> impl Iterator<Item = Group> {
    (0..len).filter_map(move |i| match params.pair_of(i, streams) {
        Some([a, b]) if a == i && b < len => Some(Group::Pair(a, b)),
        _ => None,
    })
}

impl Proposal<PssState> for LazyPairwise {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        y.clone_from(x);
        y.set_pending(Pending::Pairs(self.params), rng.random());
        Proposed::symmetric()
    }

    /// The density of the pairs stored in both states (exact for states materialised to the
    /// same length; the kernel's orbital rule never needs it).
    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        if from.streams() != to.streams() {
            return f64::NEG_INFINITY;
        }
        let stage = self.params.step.stage();
        let read = |s: &PssState, i: usize| s.raw_values()[i];
        let log_q = stage.groups_log_q(
            stored_pairs(self.params, from.streams(), from.len().min(to.len())),
            |i| read(from, i),
            |i| read(to, i),
        );
        if log_q.is_nan() {
            f64::NEG_INFINITY
        } else {
            log_q
        }
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

/// The lazy orbital second stage on the streams of `stream_mask`: `z` is a copy of `x` with
/// the pending [`Pending::Orbit`] of `y`'s key, computed at once on the pairs `y` read and
/// lazily elsewhere (see the [module docs](self)); other streams keep `x`'s values.
/// [`Proposed::Invalid`] unless `y` is a [`LazyPairwise`] candidate of `x`. Symmetric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LazyOrbital {
    /// Radius and angle laws (the first stage's radii: `z` recomputes `y`'s moves).
    pub params: LazyPairParams,
    /// Streams moved (bit s = stream s).
    pub stream_mask: u8,
}

impl LazyOrbital {
    /// The stage on the streams of `stream_mask`.
    #[must_use]
    pub fn new(params: LazyPairParams, stream_mask: u8) -> Self {
        Self {
            params,
            stream_mask,
        }
    }
}

impl ConditionalProposal<PssState> for LazyOrbital {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &PssState,
        y: &PssState,
        z: &mut PssState,
        rng: &mut R,
    ) -> Proposed {
        z.clone_from(x);
        let pending = Pending::Orbit {
            params: self.params,
            first_key: y.key(),
            stream_mask: self.stream_mask,
        };
        z.set_pending(pending, rng.random());
        if !matches!(y.pending(), Pending::Pairs(p) if p == self.params)
            || y.parent_key() != x.key()
            || y.streams() != x.streams()
        {
            return Proposed::Invalid { component: 0 };
        }
        z.materialize_read_by(y, self.stream_mask);
        Proposed::symmetric()
    }

    /// The orbital density ([`OrbitalWalk::groups_log_q`]) of the moved pairs stored in all
    /// three states (exact for states materialised to the same length).
    fn log_q(&self, x: &PssState, y: &PssState, z: &PssState) -> f64 {
        if y.streams() != x.streams() || z.streams() != x.streams() {
            return f64::NEG_INFINITY;
        }
        let streams = x.streams();
        let mask = self.stream_mask;
        let groups = stored_pairs(self.params, streams, x.len().min(y.len()).min(z.len())).filter(
            move |g| match *g {
                Group::Pair(a, _) | Group::Single(a) => mask & (1 << (a % streams)) != 0,
            },
        );
        let read = |s: &PssState, i: usize| s.raw_values()[i];
        let log_q = OrbitalWalk::torus_with(self.params.angle).groups_log_q(
            groups,
            |i| read(x, i),
            |i| read(y, i),
            |i| read(z, i),
        );
        // Unmoved streams must keep x's values.
        let kept = (0..x.len().min(z.len()))
            .filter(|&i| mask & (1 << (i % streams)) == 0)
            .all(|i| torus_displacement(read(x, i), read(z, i)) == 0.0);
        if log_q.is_nan() || !kept {
            f64::NEG_INFINITY
        } else {
            log_q
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcmc_core::testing::{chi_square_test, sidak_alpha, ChiSquareReport, ALPHA};
    use std::f64::consts::PI;

    #[test]
    fn directions_are_unit_and_uniform_in_angle() {
        let n = 200_000;
        let mut bins = [0u32; 20];
        for i in 0..n {
            let [c, s] = PairDraws::new(i, 3).direction();
            assert!((c * c + s * s - 1.0).abs() < 1e-12);
            let t = (s.atan2(c) + PI) / (2.0 * PI);
            bins[((t * 20.0) as usize).min(19)] += 1;
        }
        // Each bin has mean 10 000 and sd ~98: 6 sd bound.
        for b in bins {
            assert!((i64::from(b) - 10_000).abs() < 600, "{bins:?}");
        }
    }

    /// Joint chi-square of a sampler's displacements against eq. 9's law: `v = ln(r_max / r)
    /// / ln(r_max / r_min)` uniform, the angle uniform, the two independent (8 x 8 equal
    /// bins; a radius outside the support counts as impossible).
    fn step_law_report(mut draw: impl FnMut(u64) -> [f64; 2]) -> ChiSquareReport {
        let p = LazyPairParams::default();
        let ratio = p.log_radius_ratio();
        let mut bins = [0u64; 64];
        let mut outside = 0;
        for i in 0..200_000 {
            let [dx, dy] = draw(i);
            let v = (p.step.r_max / dx.hypot(dy)).ln() / ratio;
            if !(-1e-9..=1.0 + 1e-9).contains(&v) {
                outside += 1;
                continue;
            }
            let t = (dy.atan2(dx) + PI) / (2.0 * PI);
            let (a, b) = ((v * 8.0) as usize, (t * 8.0) as usize);
            bins[a.min(7) * 8 + b.min(7)] += 1;
        }
        let mut report = chi_square_test(&bins, &[1.0 / 64.0; 64], 5.0);
        if outside > 0 {
            report.statistic = f64::INFINITY;
            report.p_value = 0.0;
        }
        report
    }

    /// The step's radius and direction come from one disc point (its squared radius and
    /// its doubled angle): the law of eq. 9, radius and direction independent. Negative
    /// control: the radius from the same point's abscissa, which depends on the angle,
    /// fails the same check.
    #[test]
    fn step_radius_and_direction_from_one_point_have_the_law() {
        let p = LazyPairParams::default();
        let ratio = p.log_radius_ratio();
        let report =
            step_law_report(|i| p.step_displacement_with(ratio, &mut PairDraws::new(i, 7)));
        report.assert_passes("step displacement", 2);
        let wrong = step_law_report(|i| {
            let mut draws = PairDraws::new(i, 7);
            let [x, y, q] = draws.disc_point();
            let r = p.radius_with(ratio, 0.5 * (x + 1.0));
            [r * (x * x - y * y) / q, r * 2.0 * x * y / q]
        });
        assert!(
            wrong.rejects(sidak_alpha(ALPHA, 2)),
            "control passed: {wrong}"
        );
    }

    #[test]
    fn radius_with_a_precomputed_ratio_is_the_stage_radius() {
        let p = LazyPairParams::default();
        let ratio = p.log_radius_ratio();
        for u in [0.0, 0.1, 0.5, 0.9, 0.999] {
            assert!((p.radius_with(ratio, u) - p.step.radius(u)).abs() < 1e-18);
        }
    }

    #[test]
    fn kept_first_numbers_shift_the_pairs() {
        let p = LazyPairParams::default();
        assert_eq!(p.pair_of(5, 3), Some([2, 5]));
        let kept = p.with_fixed_first(0b100);
        assert_eq!(kept.pair_of(2, 3), None);
        assert_eq!(kept.pair_of(5, 3), Some([5, 8]));
        assert_eq!(kept.pair_of(8, 3), Some([5, 8]));
        assert_eq!(kept.pair_of(4, 3), Some([1, 4]));
    }
}
