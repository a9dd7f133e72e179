//! The pairwise polar Kelemen step on primary sample space (the first stage of
//! delayed-rejection MLT's orbital scheme) and the layout of coordinate pairs over streams.
//!
//! The maths of the step is mcmc-core's [`mcmc_core::delayed_rejection::RadialKelemen`] on the
//! torus; this file keeps its PSS parameters and presets and how stream coordinates pair up
//! ([`PairLayout`]). See the [`crate::orbital`] module docs for the whole scheme.

use mcmc_core::delayed_rejection::RadialKelemen;
use mcmc_core::{Proposal, Proposed};
use rand::Rng;

use crate::mutation::KelemenParams;
use crate::state::MAX_STREAMS;
use crate::PssError;

/// The radius scale the DRMLT authors' code applies to Kelemen's bounds for its pairwise first
/// stage ("compensate pairwise vs i.i.d."; docs/methods/drmlt.md). The paper's Alg. 2 does not
/// mention it.
pub const DRMLT2020_RADIUS_SCALE: f64 = 1.9;

/// The principal displacement `to - from` on the unit circle, in `[-1/2, 1/2]`: the minimal
/// torus displacement between two coordinates in `[0, 1)` (re-exported from
/// [`mcmc_core::torus::displacement`], where it lives).
pub use mcmc_core::torus::displacement as torus_displacement;

/// Radius bounds of the pairwise polar Kelemen step: per pair of coordinates the displacement
/// has a uniform direction and a length log-uniform on `[r_min, r_max]` (Kelemen's
/// exponential law, DR paper eq. 9, used as a radius in Alg. 2).
///
/// # Notes
/// The paper's Alg. 2 draws the radius from Kelemen's law with `(s1, s2) = (1/1024, 1/64)`
/// ([`PairwiseKelemenParams::kelemen2002`]). The authors' code scales both bounds by
/// [`DRMLT2020_RADIUS_SCALE`] = 1.9 ([`PairwiseKelemenParams::drmlt2020`]), the setting of
/// the paper's renders, and the default here. 1.9 is a tuning constant, not a moment match:
/// with the same radius law, a polar step moves each coordinate by `r cos(phi)`, so matching
/// the 1-D Kelemen step's per-coordinate RMS displacement needs a scale `sqrt(2) ~ 1.41` and
/// matching its mean absolute displacement `pi / 2 ~ 1.57`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairwiseKelemenParams {
    /// Smallest radius.
    pub r_min: f64,
    /// Largest radius; below 1/2, so that the radius is the minimal torus distance.
    pub r_max: f64,
}

impl PairwiseKelemenParams {
    /// Validated bounds: `0 < r_min < r_max < 1/2`.
    ///
    /// # Errors
    /// [`PssError::InvalidParameter`] otherwise.
    pub fn new(r_min: f64, r_max: f64) -> Result<Self, PssError> {
        if !(r_min > 0.0 && r_min < r_max && r_max < 0.5) {
            return Err(PssError::InvalidParameter {
                name: "PairwiseKelemenParams (r_min, r_max)",
                value: format!("({r_min}, {r_max})"),
                allowed: "0 < r_min < r_max < 1/2",
            });
        }
        Ok(Self { r_min, r_max })
    }

    /// Kelemen's bounds `s1, s2` scaled by `scale` (validated like [`Self::new`]).
    ///
    /// # Errors
    /// [`PssError::InvalidParameter`] if the scaled bounds are invalid.
    pub fn from_kelemen(kelemen: KelemenParams, scale: f64) -> Result<Self, PssError> {
        Self::new(kelemen.s1 * scale, kelemen.s2 * scale)
    }

    /// The paper's Alg. 2 as written: radius on `[1/1024, 1/64]` (Kelemen et al. 2002).
    #[must_use]
    pub const fn kelemen2002() -> Self {
        Self {
            r_min: 1.0 / 1024.0,
            r_max: 1.0 / 64.0,
        }
    }

    /// The authors' code: radius on `[1.9/1024, 1.9/64]` ([`DRMLT2020_RADIUS_SCALE`]).
    #[must_use]
    pub const fn drmlt2020() -> Self {
        Self {
            r_min: DRMLT2020_RADIUS_SCALE / 1024.0,
            r_max: DRMLT2020_RADIUS_SCALE / 64.0,
        }
    }

    /// The radius law as mcmc-core's torus [`RadialKelemen`], which implements it.
    #[inline]
    #[must_use]
    pub const fn stage(&self) -> RadialKelemen {
        RadialKelemen::torus_unchecked(self.r_min, self.r_max)
    }

    /// The radius for a uniform `u` in `[0, 1)`: `r_max exp(-u ln(r_max / r_min))` (eq. 9).
    #[inline]
    #[must_use]
    pub fn radius(&self, u: f64) -> f64 {
        self.stage().radius(u)
    }

    /// `P(R <= r)` of the radius: `ln(r / r_min) / ln(r_max / r_min)` on `[r_min, r_max]`.
    #[must_use]
    pub fn radius_cdf(&self, r: f64) -> f64 {
        self.stage().radius_cdf(r)
    }

    /// Log density of the radius: `-ln(r ln(r_max / r_min))` on `[r_min, r_max]`.
    #[must_use]
    pub fn radius_log_pdf(&self, r: f64) -> f64 {
        self.stage().radius_log_pdf(r)
    }

    /// True if `r` is a radius of the law (to a relative `1e-9` of the bounds).
    #[inline]
    #[must_use]
    pub fn in_support(&self, r: f64) -> bool {
        self.stage().in_support(r)
    }

    /// Log density (w.r.t. area) of the pair displacement `(dx, dy)` (minimal torus
    /// displacements): `-ln(2 pi r^2 ln(r_max / r_min))` for `r = |(dx, dy)|` in the annulus.
    #[must_use]
    pub fn pair_log_density(&self, dx: f64, dy: f64) -> f64 {
        self.stage().pair_log_density(dx, dy)
    }

    /// Log density of the 1-D step of a lone coordinate (a radius with a random sign):
    /// `-ln(2 |d| ln(r_max / r_min))` for `|d|` in `[r_min, r_max]`.
    #[must_use]
    pub fn single_log_density(&self, d: f64) -> f64 {
        self.stage().single_log_density(d)
    }
}

impl Default for PairwiseKelemenParams {
    /// [`PairwiseKelemenParams::drmlt2020`].
    fn default() -> Self {
        Self::drmlt2020()
    }
}

/// A group of coordinates moved together: a pair (a point of the 2-torus) or a lone coordinate
/// (re-exported from [`mcmc_core::delayed_rejection::Group`], where it lives).
pub use mcmc_core::delayed_rejection::Group;

/// Which coordinates of a state the pairwise mutations move, and how they pair up: `streams`
/// streams with `dims[s]` numbers each, numbers `(2k, 2k + 1)` of a stream forming a pair, a
/// stream of odd dimension ending with a lone number. Stream `s`'s number `k` is the
/// interleaved coordinate `s + streams k` (the layout of [`crate::PssState`]).
///
/// # Example
/// ```
/// use pss::{Group, PairLayout};
///
/// let layout = PairLayout::new(2, &[4, 3]).unwrap();
/// let groups: Vec<Group> = layout.groups(0xff).collect();
/// assert_eq!(
///     groups,
///     [Group::Pair(0, 2), Group::Pair(4, 6), Group::Pair(1, 3), Group::Single(5)]
/// );
/// assert_eq!(PairLayout::single_stream(3).groups(0xff).count(), 2);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PairLayout {
    streams: usize,
    dims: [usize; MAX_STREAMS],
}

impl PairLayout {
    /// `streams` (1..=4) streams with `dims[s]` numbers each (`dims.len() == streams`).
    ///
    /// # Errors
    /// [`PssError::InvalidParameter`] if the stream count is out of range or does not match.
    pub fn new(streams: usize, dims: &[usize]) -> Result<Self, PssError> {
        if !(1..=MAX_STREAMS).contains(&streams) || dims.len() != streams {
            return Err(PssError::InvalidParameter {
                name: "PairLayout (streams, dims)",
                value: format!("({streams}, {dims:?})"),
                allowed: "1..=4 streams, one dimension per stream",
            });
        }
        let mut d = [0; MAX_STREAMS];
        d[..streams].copy_from_slice(dims);
        Ok(Self { streams, dims: d })
    }

    /// One stream of `dim` numbers: coordinates `(0, 1), (2, 3), ...` (a plain vector).
    #[must_use]
    pub const fn single_stream(dim: usize) -> Self {
        Self {
            streams: 1,
            dims: [dim, 0, 0, 0],
        }
    }

    /// Number of streams.
    #[must_use]
    pub const fn streams(&self) -> usize {
        self.streams
    }

    /// Number of numbers of stream `s` (0 beyond the stream count).
    #[must_use]
    pub fn dim(&self, s: usize) -> usize {
        if s < self.streams {
            self.dims[s]
        } else {
            0
        }
    }

    /// The interleaved index of stream `s`'s number `k`.
    #[inline]
    #[must_use]
    pub const fn index(&self, s: usize, k: usize) -> usize {
        s + self.streams * k
    }

    /// Smallest state length that holds every coordinate of the layout.
    #[must_use]
    pub fn len(&self) -> usize {
        (0..self.streams)
            .filter(|&s| self.dims[s] > 0)
            .map(|s| self.index(s, self.dims[s] - 1) + 1)
            .max()
            .unwrap_or(0)
    }

    /// True if the layout has no coordinate.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The groups of the streams selected by `stream_mask` (bit s = stream s), stream by
    /// stream, pairs in order, the lone number (odd dimension) last. No allocation.
    pub fn groups(&self, stream_mask: u8) -> impl Iterator<Item = Group> + '_ {
        (0..self.streams)
            .filter(move |&s| stream_mask & (1 << s) != 0)
            .flat_map(move |s| {
                let n = self.dims[s];
                (0..n.div_ceil(2)).map(move |j| {
                    let k = 2 * j;
                    if k + 1 < n {
                        Group::Pair(self.index(s, k), self.index(s, k + 1))
                    } else {
                        Group::Single(self.index(s, k))
                    }
                })
            })
    }
}

/// The pairwise polar Kelemen step (DR paper, Alg. 2, stage 1): every pair of coordinates
/// moves by `r (cos phi, sin phi)` with `phi` uniform and `r` log-uniform on
/// `[r_min, r_max]`; a lone coordinate (odd dimension) moves by `+-r` (Kelemen's 1-D step with
/// the same radius law). Everything wraps around the unit torus. Symmetric. It is mcmc-core's
/// [`RadialKelemen`] on the torus with bounds `params`.
///
/// Its density is a product over groups, each a function of the *minimal torus* distance
/// `|y - x|` of the group only (circularly symmetric): the property that lets the orbital
/// second stage ([`crate::Orbital`]) drop the stage-1 ratio (eq. 11).
///
/// States: `Vec<f64>`, a point of `[0, 1)^n`, paired as [`PairLayout::single_stream`]`(n)`.
/// Random numbers, per group in order: the radius uniform, then the angle (pair) or sign
/// (lone coordinate) uniform.
///
/// # Example
/// ```
/// use mcmc_core::Proposal;
/// use pss::{PairwiseKelemen, PairwiseKelemenParams};
/// use rand::SeedableRng;
///
/// let step = PairwiseKelemen::new(PairwiseKelemenParams::drmlt2020());
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
/// let x = vec![0.999, 0.5, 0.25];
/// let mut y = Vec::new();
/// step.propose(&x, &mut y, &mut rng);
/// assert!(step.log_q(&x, &y).is_finite());
/// assert_eq!(step.log_q(&x, &y), step.log_q(&y, &x));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairwiseKelemen {
    /// Radius bounds.
    pub params: PairwiseKelemenParams,
}

impl PairwiseKelemen {
    /// The step with radius bounds `params`.
    #[must_use]
    pub const fn new(params: PairwiseKelemenParams) -> Self {
        Self { params }
    }

    /// A pair `(a, b)` moved by `r (cos phi, sin phi)` and wrapped
    /// ([`RadialKelemen::perturb_pair`]). Two uniforms: the radius, then the angle.
    #[inline]
    pub fn perturb_pair<R: Rng + ?Sized>(&self, pair: [f64; 2], rng: &mut R) -> [f64; 2] {
        self.params.stage().perturb_pair(pair, rng)
    }

    /// A lone coordinate moved by `+-r` and wrapped ([`RadialKelemen::perturb_single`]). Two
    /// uniforms: the radius, then the sign.
    #[inline]
    pub fn perturb_single<R: Rng + ?Sized>(&self, a: f64, rng: &mut R) -> f64 {
        self.params.stage().perturb_single(a, rng)
    }

    /// Log density of moving the coordinates of `groups` from `from` to `to` (the product of
    /// the group densities), with the coordinates read by `from(i)` and `to(i)`
    /// ([`RadialKelemen::groups_log_q`]).
    pub fn groups_log_q(
        &self,
        groups: impl Iterator<Item = Group>,
        from: impl Fn(usize) -> f64,
        to: impl Fn(usize) -> f64,
    ) -> f64 {
        self.params.stage().groups_log_q(groups, from, to)
    }
}

/// On `Vec<f64>`, paired as [`PairLayout::single_stream`] (mcmc-core's [`RadialKelemen`] on
/// the torus).
impl Proposal<Vec<f64>> for PairwiseKelemen {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        self.params.stage().propose(x, y, rng)
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        self.params.stage().log_q(from, to)
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use std::f64::consts::TAU;

    #[test]
    fn params_are_validated_and_presets_match_the_papers() {
        assert!(PairwiseKelemenParams::new(0.0, 0.1).is_err());
        assert!(PairwiseKelemenParams::new(0.1, 0.1).is_err());
        assert!(PairwiseKelemenParams::new(0.01, 0.5).is_err());
        assert!(PairwiseKelemenParams::new(0.01, f64::NAN).is_err());
        let scaled = PairwiseKelemenParams::from_kelemen(
            KelemenParams::kelemen2002(),
            DRMLT2020_RADIUS_SCALE,
        )
        .unwrap();
        assert_eq!(scaled, PairwiseKelemenParams::drmlt2020());
        assert_eq!(
            PairwiseKelemenParams::from_kelemen(KelemenParams::kelemen2002(), 1.0).unwrap(),
            PairwiseKelemenParams::kelemen2002()
        );
    }

    #[test]
    fn radius_law_is_log_uniform() {
        let p = PairwiseKelemenParams::drmlt2020();
        assert!((p.radius(0.0) - p.r_max).abs() < 1e-18);
        assert!((p.radius(1.0) - p.r_min).abs() < 1e-15);
        for u in [0.1, 0.5, 0.9] {
            // radius(u) is decreasing: P(R <= radius(u)) = 1 - u.
            assert!((p.radius_cdf(p.radius(u)) - (1.0 - u)).abs() < 1e-12);
        }
        // The densities integrate to 1 (radius on its support, pair over the annulus in polar
        // coordinates, lone coordinate over both signs).
        let n = 100_000;
        let (mut radius, mut pair, mut single) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64;
            let r = p.r_min + (p.r_max - p.r_min) * t;
            let dr = (p.r_max - p.r_min) / n as f64;
            radius += p.radius_log_pdf(r).exp() * dr;
            pair += p.pair_log_density(r, 0.0).exp() * TAU * r * dr;
            single += 2.0 * p.single_log_density(-r).exp() * dr;
        }
        for total in [radius, pair, single] {
            assert!((total - 1.0).abs() < 1e-6, "{radius} {pair} {single}");
        }
        assert_eq!(p.pair_log_density(p.r_min * 0.99, 0.0), f64::NEG_INFINITY);
        assert_eq!(p.single_log_density(p.r_max * 1.01), f64::NEG_INFINITY);
    }

    #[test]
    fn layout_pairs_consecutive_numbers_of_each_stream() {
        let layout = PairLayout::new(3, &[5, 2, 0]).unwrap();
        assert_eq!(layout.len(), 13);
        let all: Vec<Group> = layout.groups(0xff).collect();
        assert_eq!(
            all,
            [
                Group::Pair(0, 3),
                Group::Pair(6, 9),
                Group::Single(12),
                Group::Pair(1, 4)
            ]
        );
        let light: Vec<Group> = layout.groups(0b10).collect();
        assert_eq!(light, [Group::Pair(1, 4)]);
        assert!(PairLayout::new(0, &[]).is_err());
        assert!(PairLayout::new(2, &[1]).is_err());
        assert!(PairLayout::new(5, &[1; 5]).is_err());
        assert!(PairLayout::single_stream(0).is_empty());
        assert_eq!(PairLayout::single_stream(3).dim(1), 0);
    }

    #[test]
    fn steps_wrap_and_have_their_radius() {
        let step = PairwiseKelemen::default();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let x = vec![0.9999, 0.0001, 0.5, 0.999_99, 0.3];
        let mut y = Vec::new();
        for _ in 0..1000 {
            step.propose(&x, &mut y, &mut rng);
            assert!(y.iter().all(|v| (0.0..1.0).contains(v)));
            for (a, b) in [(0, 1), (2, 3)] {
                let r = torus_displacement(x[a], y[a]).hypot(torus_displacement(x[b], y[b]));
                assert!(step.params.in_support(r), "{r}");
            }
            let lq = step.log_q(&x, &y);
            assert!(lq.is_finite());
            assert_eq!(lq, step.log_q(&y, &x));
        }
        assert_eq!(step.log_q(&x, &x), f64::NEG_INFINITY);
        assert_eq!(step.log_q(&x, &y[..4].to_vec()), f64::NEG_INFINITY);
    }
}
