//! The pairwise stages of delayed-rejection MLT on primary-sample-space states, materialised
//! to a fixed layout.

use mcmc_core::controller::LargeStepTunable;
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::lazy_pairs::LazyPairwise;
use crate::orbital::Orbital;
use crate::pairwise::{torus_displacement, Group, PairLayout, PairwiseKelemen};
use crate::proposal::{LargeStep, ALL_STREAMS};
use crate::state::{Pending, PssState};
use crate::{KelemenParams, PssError, SmallMutation};

/// A pairwise stage ([`PairwiseKelemen`] or [`Orbital`]) on [`PssState`]s: it moves the
/// coordinates of `layout` in the streams of `stream_mask` and keeps every other coordinate.
///
/// # Materialisation
///
/// A lazy state is not enough for the orbital stage: `z` needs `x` and `y` at every
/// coordinate it moves. Both stages therefore write whole coordinates on a fixed layout, as
/// the authors' code does:
///
/// - A candidate starts as a copy of `x` with an *identity* pending mutation
///   ([`Pending::Small`] with an empty stream mask: no stream's iteration advances) and a
///   fresh key. The stage reads `x`'s value of every coordinate it moves through
///   [`PssState::get`] on the candidate: a coordinate `x` holds stale is drawn by the usual
///   catch-up and logged, so that `absorb_rejected` keeps it in `x` if the candidate is
///   rejected ([`PssState`], "Why lazy equals eager"). It then stores the moved value
///   ([`PssState::set`]).
/// - Coordinates outside the layout (and in streams outside the mask) are never touched:
///   if the target reads them, the candidate reads `x`'s values (identity). Both stages are
///   the identity there, so they stay symmetric; only large steps renew those coordinates.
///   For ergodicity (not for exactness) the layout should cover what the target reads.
/// - The delayed-rejection kernel calls `absorb_rejected(x, y)` after rejecting `y`, so when
///   the orbital stage runs, `x` is up to date on the layout; it reads `y`'s stored values,
///   which the first stage wrote. A `y` that does not come from a layout stage (another
///   pending mutation, or shorter than the layout) gets [`Proposed::Invalid`] (no second
///   stage; symmetric, since the reverse move sees the same `y`).
///
/// `catch_up` is the kernel with which stale coordinates of `x` are caught up: those the
/// chain's *lazy* small steps ([`crate::SmallStep`]) left stale. A chain that only takes
/// pairwise steps and large steps has none (a large step makes them fresh uniforms); the
/// default is Kelemen 2002's.
///
/// `log_q` is exact for states materialised on the layout, and compares the moved
/// coordinates only: kept coordinates contribute the same Dirac factor in both directions,
/// and a lazily grown state may store them stale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OnLayout<P> {
    /// The stage.
    pub stage: P,
    /// The coordinates it moves, per stream.
    pub layout: PairLayout,
    /// Streams it moves (bit s = stream s).
    pub stream_mask: u8,
    /// The kernel of stale coordinates' catch-up (see the type docs).
    pub catch_up: SmallMutation,
}

impl<P> OnLayout<P> {
    /// `stage` on every stream of `layout`, catching up with Kelemen 2002's kernel.
    #[must_use]
    pub const fn new(stage: P, layout: PairLayout) -> Self {
        Self {
            stage,
            layout,
            stream_mask: ALL_STREAMS,
            catch_up: SmallMutation::Kelemen(KelemenParams::kelemen2002()),
        }
    }

    /// The same stage restricted to the streams of `stream_mask` (MMLT's sensor-subpath-only
    /// second stage).
    #[must_use]
    pub const fn with_stream_mask(mut self, stream_mask: u8) -> Self {
        self.stream_mask = stream_mask;
        self
    }

    /// The same stage with another catch-up kernel.
    #[must_use]
    pub const fn with_catch_up(mut self, catch_up: SmallMutation) -> Self {
        self.catch_up = catch_up;
        self
    }

    /// Makes `candidate` a copy of `parent` with the identity pending mutation and `key`.
    pub(crate) fn begin_candidate(&self, parent: &PssState, candidate: &mut PssState, key: u64) {
        candidate.clone_from(parent);
        candidate.set_pending(
            Pending::Small {
                mutation: self.catch_up,
                stream_mask: 0,
            },
            key,
        );
    }
}

/// The stored value of coordinate `i`, or NaN beyond the stored length (every comparison
/// with NaN fails, so densities come out `-inf`).
pub(crate) fn stored(x: &PssState, i: usize) -> f64 {
    x.raw_values().get(i).copied().unwrap_or(f64::NAN)
}

impl Proposal<PssState> for OnLayout<PairwiseKelemen> {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        self.begin_candidate(x, y, rng.random());
        if x.streams() != self.layout.streams() {
            return Proposed::Invalid { component: 0 };
        }
        for group in self.layout.groups(self.stream_mask) {
            match group {
                Group::Pair(a, b) => {
                    let [va, vb] = self.stage.perturb_pair([y.get(a), y.get(b)], rng);
                    y.set(a, va);
                    y.set(b, vb);
                }
                Group::Single(a) => {
                    let v = self.stage.perturb_single(y.get(a), rng);
                    y.set(a, v);
                }
            }
        }
        Proposed::symmetric()
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        if from.streams() != self.layout.streams() || to.streams() != self.layout.streams() {
            return f64::NEG_INFINITY;
        }
        let p = &self.stage.params;
        let mut log_q = 0.0;
        for group in self.layout.groups(self.stream_mask) {
            let d = |i| torus_displacement(stored(from, i), stored(to, i));
            log_q += match group {
                Group::Pair(a, b) => p.pair_log_density(d(a), d(b)),
                Group::Single(a) => p.single_log_density(d(a)),
            };
            if log_q.is_nan() || log_q == f64::NEG_INFINITY {
                return f64::NEG_INFINITY;
            }
        }
        log_q
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

impl ConditionalProposal<PssState> for OnLayout<Orbital> {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &PssState,
        y: &PssState,
        z: &mut PssState,
        rng: &mut R,
    ) -> Proposed {
        self.begin_candidate(x, z, rng.random());
        let from_layout_stage = matches!(y.pending(), Pending::Small { stream_mask: 0, .. });
        if !from_layout_stage
            || x.streams() != self.layout.streams()
            || y.streams() != x.streams()
            || y.len() < self.layout.len()
        {
            return Proposed::Invalid { component: 0 };
        }
        for group in self.layout.groups(self.stream_mask) {
            match group {
                Group::Pair(a, b) => {
                    let xs = [z.get(a), z.get(b)];
                    let ys = [stored(y, a), stored(y, b)];
                    match self.stage.orbit_pair(xs, ys, rng) {
                        Some([va, vb]) => {
                            z.set(a, va);
                            z.set(b, vb);
                        }
                        None => return Proposed::Invalid { component: 0 },
                    }
                }
                Group::Single(a) => {
                    // Kept at x: read so that a stale x is caught up (and logged) as for pairs.
                    z.get(a);
                }
            }
        }
        Proposed::symmetric()
    }

    fn log_q(&self, x: &PssState, y: &PssState, z: &PssState) -> f64 {
        if x.streams() != self.layout.streams()
            || y.streams() != x.streams()
            || z.streams() != x.streams()
        {
            return f64::NEG_INFINITY;
        }
        let log_q = self.stage.groups_log_q(
            self.layout.groups(self.stream_mask),
            |i| stored(x, i),
            |i| stored(y, i),
            |i| stored(z, i),
        );
        if log_q.is_nan() {
            f64::NEG_INFINITY
        } else {
            log_q
        }
    }
}

/// The first stage of DRMLT on PSSMLT (paper section 5.1.1, the authors' code): a large step
/// with probability `p_large`, else a layout step `small` — by default the pairwise polar
/// Kelemen step on `layout` (the orbital variant's), or the per-coordinate 1-D step of the
/// authors' Tierney-Mira and Green-Mira ([`OnLayout`]`<`[`SmallMutation`]`>`). Component 0
/// is the layout step, component 1 the large step; both symmetric; `p_large` tunable
/// (automatic large-step control).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairwiseMltProposal<S = OnLayout<PairwiseKelemen>> {
    /// The layout step.
    pub small: S,
    p_large: f64,
}

impl<S> PairwiseMltProposal<S> {
    /// The mixture with large-step probability `p_large` in `[0, 1]`.
    ///
    /// # Errors
    /// [`PssError::InvalidParameter`] if `p_large` is outside `[0, 1]`.
    pub fn new(small: S, p_large: f64) -> Result<Self, PssError> {
        if !(0.0..=1.0).contains(&p_large) {
            return Err(PssError::InvalidParameter {
                name: "p_large",
                value: p_large.to_string(),
                allowed: "[0, 1]",
            });
        }
        Ok(Self { small, p_large })
    }

    /// The large-step probability.
    #[must_use]
    pub fn p_large(&self) -> f64 {
        self.p_large
    }
}

impl<S: Proposal<PssState> + LogQPair> Proposal<PssState> for PairwiseMltProposal<S> {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        if rng.random::<f64>() < self.p_large {
            LargeStep.propose(x, y, rng).with_component(1)
        } else {
            self.small.propose(x, y, rng)
        }
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        let small = (1.0 - self.p_large) * self.small.log_q(from, to).exp();
        let large = self.p_large * LargeStep.log_q(from, to).exp();
        (small + large).ln()
    }

    fn is_symmetric(&self) -> bool {
        true
    }

    fn num_components(&self) -> usize {
        2
    }

    fn log_q_component(&self, j: usize, from: &PssState, to: &PssState) -> f64 {
        match j {
            0 => (1.0 - self.p_large).ln() + self.small.log_q(from, to),
            _ => self.p_large.ln() + LargeStep.log_q(from, to),
        }
    }

    /// Component 0: the layout step's pair of densities without their shared factors
    /// (the selection probability, and whatever the small step skips); component 1 whole.
    fn log_q_component_pair(
        &self,
        j: usize,
        a: &PssState,
        b: &PssState,
        x: &PssState,
        y: &PssState,
    ) -> (f64, f64) {
        match j {
            0 => self.small.log_q_pair(a, b, x, y),
            _ => (self.log_q_component(j, a, b), self.log_q_component(j, x, y)),
        }
    }
}

/// A small step whose density over a pair of moves can skip the factors the moves share.
pub trait LogQPair {
    /// `(log q(a -> b) - c, log q(x -> y) - c)` for some `c` common to both
    /// ([`Proposal::log_q_component_pair`]).
    fn log_q_pair(&self, a: &PssState, b: &PssState, x: &PssState, y: &PssState) -> (f64, f64);
}

impl LogQPair for OnLayout<PairwiseKelemen> {
    /// Per group of the layout, skipping those where `a = x` and `b = y` bit for bit (the
    /// density is a product over groups).
    fn log_q_pair(&self, a: &PssState, b: &PssState, x: &PssState, y: &PssState) -> (f64, f64) {
        let streams = self.layout.streams();
        if [a, b, x, y].iter().any(|s| s.streams() != streams) {
            return (f64::NEG_INFINITY, f64::NEG_INFINITY);
        }
        let p = &self.stage.params;
        let same = |i: usize| stored(a, i) == stored(x, i) && stored(b, i) == stored(y, i);
        let density = |from: &PssState, to: &PssState, group: Group| {
            let d = |i| torus_displacement(stored(from, i), stored(to, i));
            match group {
                Group::Pair(i, k) => p.pair_log_density(d(i), d(k)),
                Group::Single(i) => p.single_log_density(d(i)),
            }
        };
        let (mut forward, mut reverse) = (0.0, 0.0);
        for group in self.layout.groups(self.stream_mask) {
            let unmoved = match group {
                Group::Pair(i, k) => same(i) && same(k),
                Group::Single(i) => same(i),
            };
            if !unmoved {
                forward += density(a, b, group);
                reverse += density(x, y, group);
            }
        }
        let clean = |v: f64| if v.is_nan() { f64::NEG_INFINITY } else { v };
        (clean(forward), clean(reverse))
    }
}

impl LogQPair for LazyPairwise {
    /// Whole densities (the orbital rule never needs them).
    fn log_q_pair(&self, a: &PssState, b: &PssState, x: &PssState, y: &PssState) -> (f64, f64) {
        (self.log_q(a, b), self.log_q(x, y))
    }
}

impl<S> LargeStepTunable for PairwiseMltProposal<S> {
    fn large_step_probability(&self) -> f64 {
        self.p_large
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.p_large = p.clamp(0.0, 1.0);
    }
    fn is_large_step(&self, component: usize) -> bool {
        component == 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SmallStep;
    use mcmc_core::Point;
    use rand::SeedableRng;

    fn distance(a: &PssState, b: &PssState, i: usize, j: usize) -> f64 {
        torus_displacement(a.raw_values()[i], b.raw_values()[i])
            .hypot(torus_displacement(a.raw_values()[j], b.raw_values()[j]))
    }

    #[test]
    fn stages_materialise_the_layout_and_keep_everything_else() {
        // Two streams: 3 camera numbers (a pair, a lone one), 2 light numbers (a pair).
        let layout = PairLayout::new(2, &[3, 2]).unwrap();
        let first = OnLayout::new(PairwiseKelemen::default(), layout);
        let second = OnLayout::new(Orbital::default(), layout).with_stream_mask(0b01);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let (mut y, mut z) = (PssState::new(2, 0), PssState::new(2, 0));
        for key in 0..200 {
            // A fresh lazy state: nothing stored, every coordinate a deferred uniform.
            let mut x = PssState::new(2, key);
            assert_eq!(first.propose(&x, &mut y, &mut rng), Proposed::symmetric());
            assert!(y.len() >= layout.len());
            // A coordinate outside the layout reads x's value (identity) ...
            let outside = y.get(layout.index(0, 4));
            // ... and the rejection makes x keep what y drew of it.
            x.absorb_rejected(&y);
            assert_eq!(x.clone().get(layout.index(0, 4)), outside);
            let r = first.stage.params;
            for (i, j) in [(0, 2), (1, 3)] {
                let d = distance(&x, &y, i, j);
                assert!(d >= r.r_min * 0.999 && d <= r.r_max * 1.001, "{d}");
            }
            let lone = torus_displacement(x.raw_values()[4], y.raw_values()[4]).abs();
            assert!(lone >= r.r_min * 0.999 && lone <= r.r_max * 1.001);
            assert!(first.log_q(&x, &y).is_finite());
            assert_eq!(first.log_q(&x, &y), first.log_q(&y, &x));

            assert_eq!(
                second.propose(&x, &y, &mut z, &mut rng),
                Proposed::symmetric()
            );
            assert!((distance(&y, &z, 0, 2) - distance(&y, &x, 0, 2)).abs() < 1e-12);
            // The lone camera number and the whole light stream stay at x.
            for i in [1, 3, 4] {
                assert_eq!(z.raw_values()[i], x.raw_values()[i], "coordinate {i}");
            }
            let (forward, reverse) = (second.log_q(&x, &y, &z), second.log_q(&z, &y, &x));
            assert!(forward.is_finite() && (forward - reverse).abs() < 1e-9);
            assert!((first.log_q(&z, &y) - first.log_q(&x, &y)).abs() < 1e-9);
        }
    }

    #[test]
    fn second_stage_needs_a_candidate_of_a_layout_stage() {
        let layout = PairLayout::single_stream(4);
        let second = OnLayout::new(Orbital::default(), layout);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(6);
        let x = PssState::from_values(&[0.1, 0.2, 0.3, 0.4]);
        let (mut y, mut z) = (PssState::new(1, 0), PssState::new(1, 0));
        let invalid = Proposed::Invalid { component: 0 };
        LargeStep.propose(&x, &mut y, &mut rng);
        y.materialize();
        assert_eq!(second.propose(&x, &y, &mut z, &mut rng), invalid);
        SmallStep::new(SmallMutation::Gaussian { sigma: 0.01 }).propose(&x, &mut y, &mut rng);
        y.materialize();
        assert_eq!(second.propose(&x, &y, &mut z, &mut rng), invalid);
        // Too short for the layout, or the wrong stream count.
        let short = OnLayout::new(PairwiseKelemen::default(), PairLayout::single_stream(2));
        short.propose(&x, &mut y, &mut rng);
        let longer = OnLayout::new(Orbital::default(), PairLayout::single_stream(6));
        assert_eq!(longer.propose(&x, &y, &mut z, &mut rng), invalid);
        let two = OnLayout::new(
            PairwiseKelemen::default(),
            PairLayout::new(2, &[2, 2]).unwrap(),
        );
        assert_eq!(two.propose(&x, &mut y, &mut rng), invalid);
    }

    #[test]
    fn mixture_validates_and_tunes_p_large() {
        let small = OnLayout::new(PairwiseKelemen::default(), PairLayout::single_stream(2));
        assert!(PairwiseMltProposal::new(small, 1.5).is_err());
        let mut p = PairwiseMltProposal::new(small, 0.3).unwrap();
        p.set_large_step_probability(0.5);
        assert_eq!(p.p_large(), 0.5);
        assert!(p.is_large_step(1) && !p.is_large_step(0));
    }
}

/// Green-Mira's fictional state on a layout (DR paper eq. 12-14): `y* = z - (y - x)` per
/// coordinate of `layout` in the streams of `stream_mask`, with the minimal torus
/// displacement `d(x, y)` and the result wrapped to `[0, 1)`; every other coordinate is
/// `x`'s (as for the stages, which keep them). Exact for states materialised on the layout
/// (what [`OnLayout`] stages produce). The ghost is a copy of `x` with the identity pending
/// mutation, so the target can evaluate it; it is never splatted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayoutGhost {
    /// The coordinates the stages move.
    pub layout: PairLayout,
    /// Streams the stages move.
    pub stream_mask: u8,
}

impl mcmc_core::StateArithmetic<PssState> for LayoutGhost {
    fn ghost(&self, x: &PssState, y: &PssState, z: &PssState, out: &mut PssState) {
        out.clone_from(x);
        out.set_pending(
            Pending::Small {
                mutation: SmallMutation::Kelemen(KelemenParams::kelemen2002()),
                stream_mask: 0,
            },
            z.key().rotate_left(17) ^ 0x5851_f42d_4c95_7f2d,
        );
        let mut put = |i: usize| {
            let v = stored(z, i) - torus_displacement(stored(x, i), stored(y, i));
            if v.is_finite() {
                out.set(i, crate::wrap(v));
            }
        };
        for group in self.layout.groups(self.stream_mask) {
            match group {
                Group::Pair(a, b) => {
                    put(a);
                    put(b);
                }
                Group::Single(a) => put(a),
            }
        }
    }
}
