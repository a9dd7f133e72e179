//! Delayed-rejection MLT kernels on a pair layout (Rioux-Lavoie et al. 2020,
//! docs/methods/drmlt.md): bold first stage, timid or orbital second stage, with per-stream
//! second-stage masks, optionally chosen per state.
//!
//! Every kernel here is *bold then timid* (DR paper section 5.1) and runs its second stage only
//! after a rejected small step, never after a large step (the authors' implementation; the
//! mixture terms are component-labelled, docs/methods/drmlt.md):
//! - [`orbital_kernel`] (section 4.4, eq. 11): a pairwise polar Kelemen first stage (radii
//!   x 1.9, the authors' preset [`PairwiseKelemenParams::drmlt2020`]) and the orbital second
//!   stage (wrapped Cauchy, rho = exp(-1/4)); [`lazy_orbital_kernel`] is the same rule on
//!   every pair of every stream, computed only where the target reads
//!   ([`crate::lazy_pairs`]: no layout, the cost of what a path reads);
//! - [`tierney_mira_kernel`] (eq. 6-7) and [`green_mira_kernel`] (eq. 12-14, the fictional
//!   state `y* = z - (y - x)` on the torus, [`LayoutGhost`]) as the authors run them (Fig. 7):
//!   a 1-D Kelemen first stage (eq. 9, `[1/1024, 1/64]`, every coordinate of the layout
//!   independently, [`kelemen_first_stage`]), then an isotropic Gaussian step from `x` with
//!   sigma `(1/64) x 0.1` ([`gaussian_timid_stage`]; [`PerCoordinateParams`]);
//! - [`pairwise_tierney_mira_kernel`] and [`pairwise_green_mira_kernel`]: the same rules over
//!   the orbital variant's pairwise first stage, then a timid pairwise Kelemen step from `x`
//!   with radii x [`TIMID_SCALE`] (this crate's own variants, kept for comparison).
//!
//! A renderer supplies two things: the [`PairLayout`] of coordinates the pairwise stages move
//! per stream (what its path sampler reads; coordinates beyond it are renewed by large steps
//! only, exactly, see [`OnLayout`]), and the streams the second stage moves
//! ([`SecondStageStreams`]). On PSSMLT the second stage moves every stream
//! ([`SecondStageStreams::all`]); on multiplexed MLT (section 5.1.2) it moves the camera
//! subpath only, except for states whose strategy needs another mask ("Handling Light
//! Tracing"): a [`StageChoice`] reads the current state and picks that mask. The second stage
//! must never move what the choice reads, so that `z` and the ghost make the same choice as
//! `x` and the reverse path is the one through the same stage.
//!
//! # Example
//! ```
//! use pss::dr::{orbital_kernel, SecondStageStreams};
//! use pss::PairLayout;
//!
//! // One stream, two coordinates (a 2-D integrand), large steps with probability 0.3.
//! let kernel = orbital_kernel(PairLayout::single_stream(2), 0.3, SecondStageStreams::all());
//! assert!(kernel.runs_second_stage_after(0) && !kernel.runs_second_stage_after(1));
//! ```

use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::{DelayedRejection, Proposed};
use rand::Rng;

use crate::lazy_pairs::{LazyOrbital, LazyPairParams, LazyPairwise};
use crate::on_layout::{LayoutGhost, OnLayout, PairwiseMltProposal};
use crate::orbital::Orbital;
use crate::pairwise::{PairLayout, PairwiseKelemen, PairwiseKelemenParams};
use crate::proposal::ALL_STREAMS;
use crate::state::PssState;
use crate::KelemenParams;
use crate::SmallMutation;
use crate::WrappedCauchy;

/// The scale of the timid second stage of Tierney-Mira and Green-Mira (the authors'
/// `scaleSecond`: their second-stage Gaussian has sigma x 0.1; the pairwise variants scale
/// their radii by it).
pub const TIMID_SCALE: f64 = 0.1;

/// The authors' Gaussian sigma, 1/64 (reference implementation's default `sigma`), which
/// [`TIMID_SCALE`] scales for the second stage of their Tierney-Mira and Green-Mira.
pub const AUTHORS_SIGMA: f64 = 1.0 / 64.0;

/// The stages of the authors' Tierney-Mira and Green-Mira: a 1-D Kelemen first stage on
/// every coordinate and a Gaussian second stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerCoordinateParams {
    /// The first stage's Kelemen bounds (eq. 9).
    pub kelemen: KelemenParams,
    /// The second stage's standard deviation per coordinate.
    pub second_sigma: f64,
}

impl PerCoordinateParams {
    /// The authors' values (DR paper sections 4.3 and 5.1, Fig. 7; reference implementation
    /// defaults): Kelemen `[1/1024, 1/64]` (not scaled: the x 1.9 is the pairwise step's),
    /// second-stage sigma `AUTHORS_SIGMA x TIMID_SCALE = 0.1/64`.
    #[must_use]
    pub const fn rioux_lavoie2020() -> Self {
        Self {
            kelemen: KelemenParams::kelemen2002(),
            second_sigma: AUTHORS_SIGMA * TIMID_SCALE,
        }
    }
}

/// The authors' first stage of Tierney-Mira and Green-Mira ([`kelemen_first_stage`]).
pub type KelemenFirstStage = PairwiseMltProposal<OnLayout<SmallMutation>>;

/// The authors' second stage of Tierney-Mira and Green-Mira ([`gaussian_timid_stage`]).
pub type GaussianTimidStage = IndependentSecondStage<OnLayout<SmallMutation>>;

impl Default for PerCoordinateParams {
    fn default() -> Self {
        Self::rioux_lavoie2020()
    }
}

/// Which of two second stages a state gets: the *alternate* one where
/// [`StageChoice::alternate`] is true, the *normal* one elsewhere.
///
/// The choice must depend only on coordinates the second stage does not move (the DR paper's
/// MMLT strategy choice, section 5.1.2), so that `z` and the ghost choose as `x` does.
pub trait StageChoice {
    /// True if the current state `x` gets the alternate second stage.
    fn alternate(&self, x: &PssState) -> bool;
}

/// The normal second stage for every state (no per-state choice).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NormalOnly;

impl StageChoice for NormalOnly {
    #[inline]
    fn alternate(&self, _x: &PssState) -> bool {
        false
    }
}

/// `None` chooses the normal stage for every state; `Some(c)` chooses as `c`.
impl<C: StageChoice> StageChoice for Option<C> {
    #[inline]
    fn alternate(&self, x: &PssState) -> bool {
        match self {
            Some(c) => c.alternate(x),
            None => false,
        }
    }
}

/// The streams the second stage moves (bit `s` = stream `s`): `normal` for every state,
/// `alternate` for the states `choice` picks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SecondStageStreams<C = NormalOnly> {
    /// The streams moved from every state `choice` does not pick.
    pub normal: u8,
    /// The streams moved from the states `choice` picks.
    pub alternate: u8,
    /// Which states get `alternate`.
    pub choice: C,
}

impl SecondStageStreams<NormalOnly> {
    /// Every stream, from every state (DRMLT on PSSMLT, section 5.1.1).
    #[must_use]
    pub const fn all() -> Self {
        Self::only(ALL_STREAMS)
    }

    /// The streams of `mask`, from every state.
    #[must_use]
    pub const fn only(mask: u8) -> Self {
        Self {
            normal: mask,
            alternate: mask,
            choice: NormalOnly,
        }
    }
}

impl<C> SecondStageStreams<C> {
    /// The second stage made by `stage(mask)` for both masks, chosen per state.
    pub fn stages<P>(self, stage: impl Fn(u8) -> P) -> ByState<P, C> {
        ByState {
            normal: stage(self.normal),
            alternate: stage(self.alternate),
            choice: self.choice,
        }
    }
}

/// A second stage chosen per current state (DR paper section 5.1.2, "Handling Light
/// Tracing"): `alternate` where `choice` picks `x`, `normal` elsewhere. Exact when the choice
/// reads only coordinates neither stage moves (see [`StageChoice`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ByState<P, C> {
    /// The stage of every state `choice` does not pick.
    pub normal: P,
    /// The stage of the states `choice` picks.
    pub alternate: P,
    /// Which states get `alternate`.
    pub choice: C,
}

impl<P, C: StageChoice> ByState<P, C> {
    /// The stage of current state `x`.
    #[inline]
    pub fn pick(&self, x: &PssState) -> &P {
        if self.choice.alternate(x) {
            &self.alternate
        } else {
            &self.normal
        }
    }
}

impl<P: ConditionalProposal<PssState>, C: StageChoice> ConditionalProposal<PssState>
    for ByState<P, C>
{
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &PssState,
        y: &PssState,
        z: &mut PssState,
        rng: &mut R,
    ) -> Proposed {
        self.pick(x).propose(x, y, z, rng)
    }
    fn log_q(&self, x: &PssState, y: &PssState, z: &PssState) -> f64 {
        self.pick(x).log_q(x, y, z)
    }
}

/// The bold first stage: a large step with probability `p_large` (clamped to `[0, 1]`), else
/// the pairwise polar Kelemen step on every stream of `layout` with the authors' radii
/// ([`PairwiseKelemenParams::drmlt2020`]).
#[must_use]
pub fn first_stage(layout: PairLayout, p_large: f64) -> PairwiseMltProposal {
    let small = OnLayout::new(
        PairwiseKelemen {
            params: PairwiseKelemenParams::drmlt2020(),
        },
        layout,
    );
    PairwiseMltProposal::new(small, p_large.clamp(0.0, 1.0))
        .unwrap_or_else(|_| unreachable!("clamped"))
}

/// The timid second stage of the pairwise Tierney-Mira and Green-Mira: a pairwise Kelemen
/// step from `x` with radii scaled by [`TIMID_SCALE`], on the streams of `stream_mask`.
#[must_use]
pub fn timid_stage(
    layout: PairLayout,
    stream_mask: u8,
) -> IndependentSecondStage<OnLayout<PairwiseKelemen>> {
    let p = PairwiseKelemenParams::drmlt2020();
    let params = PairwiseKelemenParams::new(p.r_min * TIMID_SCALE, p.r_max * TIMID_SCALE)
        .unwrap_or_else(|_| unreachable!("scaled presets stay valid"));
    IndependentSecondStage(
        OnLayout::new(PairwiseKelemen { params }, layout).with_stream_mask(stream_mask),
    )
}

/// The orbital stage (wrapped Cauchy angle, eq. 10) on the streams of `stream_mask`.
#[must_use]
pub fn orbital_stage(layout: PairLayout, stream_mask: u8) -> OnLayout<Orbital> {
    OnLayout::new(
        Orbital {
            angle: WrappedCauchy::default(),
        },
        layout,
    )
    .with_stream_mask(stream_mask)
}

/// The orbital kernel (DR paper section 4.4, eq. 11): [`first_stage`], then
/// [`orbital_stage`] on the streams of `streams` after a rejected small step.
#[must_use]
pub fn orbital_kernel<C>(
    layout: PairLayout,
    p_large: f64,
    streams: SecondStageStreams<C>,
) -> DelayedRejection<PairwiseMltProposal, ByState<OnLayout<Orbital>, C>> {
    let second = streams.stages(|mask| orbital_stage(layout, mask));
    DelayedRejection::orbital(first_stage(layout, p_large), second).second_stage_after_small_steps()
}

/// The lazy bold first stage: a large step with probability `p_large` (clamped to
/// `[0, 1]`), else the pairwise polar Kelemen step on every pair of every stream, computed
/// pair by pair as the target reads ([`LazyPairwise`], the authors' radii).
#[must_use]
pub fn lazy_first_stage(p_large: f64) -> PairwiseMltProposal<LazyPairwise> {
    PairwiseMltProposal::new(LazyPairwise::default(), p_large.clamp(0.0, 1.0))
        .unwrap_or_else(|_| unreachable!("clamped"))
}

/// The orbital kernel at the cost of what the target reads (DR paper section 4.4, eq. 11;
/// [`crate::lazy_pairs`]): [`lazy_first_stage`], then the lazy orbital stage
/// ([`LazyOrbital`]) on the streams of `streams` after a rejected small step. The same chain
/// as [`orbital_kernel`] on an unbounded layout (no lone coordinates), with no layout to
/// choose: every pair of every stream moves, and each costs only when a path reads it.
#[must_use]
pub fn lazy_orbital_kernel<C>(
    p_large: f64,
    streams: SecondStageStreams<C>,
) -> DelayedRejection<PairwiseMltProposal<LazyPairwise>, ByState<LazyOrbital, C>> {
    lazy_orbital_kernel_with(LazyPairParams::default(), p_large, streams)
}

/// [`lazy_orbital_kernel`] with the laws and kept first numbers of `params` (both stages use
/// the same pairing: [`LazyPairParams::fixed_first`]).
#[must_use]
pub fn lazy_orbital_kernel_with<C>(
    params: LazyPairParams,
    p_large: f64,
    streams: SecondStageStreams<C>,
) -> DelayedRejection<PairwiseMltProposal<LazyPairwise>, ByState<LazyOrbital, C>> {
    let first = PairwiseMltProposal::new(LazyPairwise { params }, p_large.clamp(0.0, 1.0))
        .unwrap_or_else(|_| unreachable!("clamped"));
    let second = streams.stages(|mask| LazyOrbital::new(params, mask));
    DelayedRejection::orbital(first, second).second_stage_after_small_steps()
}

/// The authors' bold first stage of Tierney-Mira and Green-Mira: a large step with
/// probability `p_large` (clamped to `[0, 1]`), else Kelemen's 1-D perturbation (DR paper
/// eq. 9, bounds `params.kelemen`) applied independently to every coordinate of every
/// stream of `layout`.
#[must_use]
pub fn kelemen_first_stage(
    layout: PairLayout,
    p_large: f64,
    params: PerCoordinateParams,
) -> KelemenFirstStage {
    let small = OnLayout::new(SmallMutation::Kelemen(params.kelemen), layout);
    PairwiseMltProposal::new(small, p_large.clamp(0.0, 1.0))
        .unwrap_or_else(|_| unreachable!("clamped"))
}

/// The authors' timid second stage of Tierney-Mira and Green-Mira: an isotropic Gaussian step
/// from `x` (standard deviation `params.second_sigma` per coordinate, wrapped) on every
/// coordinate of `layout` in the streams of `stream_mask`; it ignores the rejected `y` and is
/// symmetric.
#[must_use]
pub fn gaussian_timid_stage(
    layout: PairLayout,
    stream_mask: u8,
    params: PerCoordinateParams,
) -> GaussianTimidStage {
    let sigma = params.second_sigma;
    IndependentSecondStage(
        OnLayout::new(SmallMutation::Gaussian { sigma }, layout).with_stream_mask(stream_mask),
    )
}

/// The authors' Tierney-Mira kernel (eq. 6-7, Fig. 7): [`kelemen_first_stage`], then
/// [`gaussian_timid_stage`] on the streams of `streams` after a rejected small step. Its ratio
/// keeps `Q1(y | z) / Q1(y | x)`, which vanishes wherever a coordinate of `y - z` leaves
/// Kelemen's support (the vanishing acceptance of section 4.3, what the paper shows).
#[must_use]
pub fn tierney_mira_kernel<C>(
    layout: PairLayout,
    p_large: f64,
    streams: SecondStageStreams<C>,
    params: PerCoordinateParams,
) -> DelayedRejection<KelemenFirstStage, ByState<GaussianTimidStage, C>> {
    DelayedRejection::tierney_mira(
        kelemen_first_stage(layout, p_large, params),
        streams.stages(|mask| gaussian_timid_stage(layout, mask, params)),
    )
    .with_symmetric_second_stage()
    .second_stage_after_small_steps()
}

/// The authors' Green-Mira kernel (eq. 12-14, Fig. 7): the stages of [`tierney_mira_kernel`]
/// with the ghost `y* = z - (y - x)` on every stream of `layout` ([`LayoutGhost`]).
#[must_use]
pub fn green_mira_kernel<C>(
    layout: PairLayout,
    p_large: f64,
    streams: SecondStageStreams<C>,
    params: PerCoordinateParams,
) -> DelayedRejection<KelemenFirstStage, ByState<GaussianTimidStage, C>, LayoutGhost> {
    DelayedRejection::green_mira(
        kelemen_first_stage(layout, p_large, params),
        streams.stages(|mask| gaussian_timid_stage(layout, mask, params)),
        LayoutGhost {
            layout,
            stream_mask: ALL_STREAMS,
        },
    )
    .with_symmetric_second_stage()
    .second_stage_after_small_steps()
}

/// The pairwise Tierney-Mira kernel (eq. 6-7): [`first_stage`], then [`timid_stage`] on the
/// streams of `streams` after a rejected small step.
#[must_use]
pub fn pairwise_tierney_mira_kernel<C>(
    layout: PairLayout,
    p_large: f64,
    streams: SecondStageStreams<C>,
) -> DelayedRejection<
    PairwiseMltProposal,
    ByState<IndependentSecondStage<OnLayout<PairwiseKelemen>>, C>,
> {
    DelayedRejection::tierney_mira(
        first_stage(layout, p_large),
        streams.stages(|mask| timid_stage(layout, mask)),
    )
    .with_symmetric_second_stage()
    .second_stage_after_small_steps()
}

/// The pairwise Green-Mira kernel (eq. 12-14): the stages of [`pairwise_tierney_mira_kernel`]
/// with the ghost `y* = z - (y - x)` on every stream of `layout` ([`LayoutGhost`]).
#[must_use]
pub fn pairwise_green_mira_kernel<C>(
    layout: PairLayout,
    p_large: f64,
    streams: SecondStageStreams<C>,
) -> DelayedRejection<
    PairwiseMltProposal,
    ByState<IndependentSecondStage<OnLayout<PairwiseKelemen>>, C>,
    LayoutGhost,
> {
    DelayedRejection::green_mira(
        first_stage(layout, p_large),
        streams.stages(|mask| timid_stage(layout, mask)),
        LayoutGhost {
            layout,
            stream_mask: ALL_STREAMS,
        },
    )
    .with_symmetric_second_stage()
    .second_stage_after_small_steps()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Picks states whose first stored coordinate is below one half.
    #[derive(Clone, Copy)]
    struct LowFirst;
    impl StageChoice for LowFirst {
        fn alternate(&self, x: &PssState) -> bool {
            x.raw_values().first().is_some_and(|&u| u < 0.5)
        }
    }

    #[test]
    fn the_choice_picks_the_stage_and_none_always_picks_normal() {
        let layout = PairLayout::new(2, &[2, 2]).unwrap();
        let streams = SecondStageStreams {
            normal: 0b01,
            alternate: 0b11,
            choice: Some(LowFirst),
        };
        let second = streams.stages(|mask| orbital_stage(layout, mask));
        let mut x = PssState::new(2, 1);
        x.set(0, 0.25);
        assert_eq!(second.pick(&x).stream_mask, 0b11);
        x.set(0, 0.75);
        assert_eq!(second.pick(&x).stream_mask, 0b01);
        let never = SecondStageStreams {
            choice: None::<LowFirst>,
            ..streams
        };
        x.set(0, 0.25);
        assert_eq!(
            never
                .stages(|mask| orbital_stage(layout, mask))
                .pick(&x)
                .stream_mask,
            0b01
        );
        let all = SecondStageStreams::all().stages(|mask| timid_stage(layout, mask));
        assert_eq!(all.pick(&x).0.stream_mask, ALL_STREAMS);
    }

    #[test]
    fn kernels_skip_the_second_stage_after_large_steps() {
        let layout = PairLayout::single_stream(4);
        let o = orbital_kernel(layout, 0.3, SecondStageStreams::all());
        let t = pairwise_tierney_mira_kernel(layout, 0.3, SecondStageStreams::all());
        let g = pairwise_green_mira_kernel(layout, 0.3, SecondStageStreams::all());
        let params = PerCoordinateParams::rioux_lavoie2020();
        let at = tierney_mira_kernel(layout, 0.3, SecondStageStreams::all(), params);
        let ag = green_mira_kernel(layout, 0.3, SecondStageStreams::all(), params);
        assert!(at.runs_second_stage_after(0) && !at.runs_second_stage_after(1));
        assert!(ag.runs_second_stage_after(0) && !ag.runs_second_stage_after(1));
        assert!(at.has_symmetric_second_stage() && ag.has_symmetric_second_stage());
        assert_eq!(params.second_sigma, 0.1 / 64.0);
        assert_eq!(params.kelemen, KelemenParams::kelemen2002());
        assert_eq!(at.first.p_large(), 0.3);
        assert!(o.runs_second_stage_after(0) && !o.runs_second_stage_after(1));
        assert!(t.runs_second_stage_after(0) && !t.runs_second_stage_after(1));
        assert!(g.runs_second_stage_after(0) && !g.runs_second_stage_after(1));
        assert!(t.has_symmetric_second_stage() && g.has_symmetric_second_stage());
        assert_eq!(o.first.p_large(), 0.3);
        assert_eq!(first_stage(layout, 2.0).p_large(), 1.0);
        let timid = timid_stage(layout, ALL_STREAMS).0.stage.params;
        let bold = PairwiseKelemenParams::drmlt2020();
        assert_eq!(timid.r_max, bold.r_max * TIMID_SCALE);
    }
}
