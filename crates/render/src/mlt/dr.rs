//! Delayed-rejection MLT (Rioux-Lavoie et al. 2020, docs/methods/drmlt.md)
//! on the path samplers: the kernels of `mcmc_core::delayed_rejection` with the pairwise
//! primary-sample-space stages of `pss` ([`pss::OnLayout`], [`pss::LazyPairwise`]).
//!
//! The kernels are `pss`'s renderer-agnostic recipes ([`pss::dr`]: every variant *bold then
//! timid*, section 5.1, the second stage only after a rejected small step); this module keeps
//! what is specific to BDPT, the path tracer and MMLT:
//! - the orbital rule needs no layout ([`lazy_orbital_kernel`]: every pair of every stream,
//!   computed where the path sampler reads); the other rules move a fixed layout per chain,
//!   sized to what the path sampler reads ([`dr_layout`] for BDPT, [`pt_layout`] for the path
//!   tracer, [`mmlt_layout`] per MMLT depth; [`chain_layout`]); coordinates beyond it are
//!   renewed by large steps only (exact, see [`pss::OnLayout`]);
//! - the second stage's streams. On MMLT (`DrBase::Mmlt`, section 5.1.2) the second stage
//!   moves only the camera stream: the light subpath and the strategy choice (the first number
//!   of the connection stream) stay fixed. Light-tracing strategies (t = 1, "Handling Light
//!   Tracing" in section 5.1.2) are the exception: their camera stream holds only the raster
//!   position, which the connection overrides, so their second stage moves the camera *and*
//!   light streams ([`ByStrategy`], which reads the strategy of the current state through
//!   [`LightTracing`]; the second stage never moves the strategy coordinate, so the reverse
//!   path sees the same strategy and the choice is symmetric).
//!
//! Our reading where the paper fixes the MMLT strategy along the whole chain: by default the
//! bold first stage moves every stream, strategy coordinate included, so a first-stage
//! candidate may change strategy (an exact move of the MMLT target; it is then judged by the
//! usual acceptance), and only the second stage keeps the strategy. [`lazy_orbital_kernel`]
//! with `fixed_strategy` is the paper's chain: neither stage moves it, large steps draw it
//! afresh.

use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::DelayedRejection;
use pss::dr::{
    ByState, GaussianTimidStage, KelemenFirstStage, PerCoordinateParams, SecondStageStreams,
    StageChoice,
};
use pss::{
    LayoutGhost, LazyOrbital, LazyPairParams, LazyPairwise, OnLayout, Orbital, PairLayout,
    PairwiseKelemen, PairwiseMltProposal, PssState,
};

use super::PATH_STREAMS;
use crate::sampler::Stream;

/// The acceptance rule of the second stage, with its stages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DrVariant {
    /// Tierney & Mira 1999 (paper eq. 6-7) as the authors run it (Fig. 7): a 1-D Kelemen
    /// first stage on every coordinate of the layout, a Gaussian second stage of sigma 0.1/64
    /// ([`pss::dr::tierney_mira_kernel`]).
    TierneyMira,
    /// Green & Mira 2001 with the fictional state (eq. 12-14), the authors' stages as
    /// [`DrVariant::TierneyMira`] ([`pss::dr::green_mira_kernel`]).
    GreenMira,
    /// The pairwise orbital rule (eq. 11) — the paper's recommended variant — with stages
    /// that cost what a path reads ([`lazy_orbital_kernel`]).
    #[default]
    Orbital,
    /// Tierney & Mira over this crate's pairwise stages: the orbital variant's pairwise polar
    /// Kelemen first stage, a timid pairwise Kelemen second stage
    /// ([`pss::dr::pairwise_tierney_mira_kernel`]).
    TierneyMiraPairwise,
    /// Green & Mira over the pairwise stages of [`DrVariant::TierneyMiraPairwise`]
    /// ([`pss::dr::pairwise_green_mira_kernel`]).
    GreenMiraPairwise,
    /// Cheap then expensive (section 5.2, with MALA in place of H2MC): an isotropic Gaussian
    /// first stage and a MALA second stage under Green and Mira's rule, on MMLT
    /// ([`crate::mlt::mala::cheap_then_expensive_kernel`]).
    CheapThenExpensive,
}

impl DrVariant {
    /// The variants with their CLI names (the paper's Fig. 7 compares the first three).
    pub const ALL: [(&'static str, DrVariant); 6] = [
        ("tierney-mira", DrVariant::TierneyMira),
        ("green-mira", DrVariant::GreenMira),
        ("orbital", DrVariant::Orbital),
        ("cheap-then-expensive", DrVariant::CheapThenExpensive),
        ("tierney-mira-pairwise", DrVariant::TierneyMiraPairwise),
        ("green-mira-pairwise", DrVariant::GreenMiraPairwise),
    ];

    /// The CLI name.
    #[must_use]
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, v)| *v == self)
            .map_or("orbital", |(n, _)| n)
    }
}

/// The path sampler delayed rejection runs on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DrBase {
    /// PSSMLT over BDPT (section 5.1.1).
    #[default]
    Pssmlt,
    /// PSSMLT over the unidirectional path tracer with next-event estimation
    /// ([`crate::mlt::PtTarget`]; the paper's PSSMLT results ran "atop a PSSMLT path tracer",
    /// section 5.1.1). The second stage moves every stream, as on [`DrBase::Pssmlt`].
    PssmltPt,
    /// Multiplexed MLT (section 5.1.2): stage 2 on the camera subpath only.
    Mmlt,
}

/// Numbers per bounce the layout budgets (BDPT: 3, plus 1 for roulette).
const PER_BOUNCE: usize = 4;

/// The coordinates the pairwise stages move for paths of at most `D = max_depth` bounces —
/// what BDPT reads (crates/render/src/bdpt): camera stream raster 2 + lens 2 + time 1 + 4 per
/// scattering vertex (D + 1 of them); light stream light 1 + position 2 + direction 2 + 4 per
/// vertex (at most D + 1); connection stream 3 per s = 1 strategy (at most D + 1) and 2 per
/// t = 1 strategy (at most D), or MMLT's strategy choice plus one connection: `5 (D + 2)`
/// covers both. Sizes are rounded up to even so that the pairs stay (2k, 2k+1). Every
/// coordinate in the layout costs proposal time at every small step (a DR step moves them
/// all, unlike PSSMLT's lazy Kelemen step), so the layout is no larger than what is read.
#[must_use]
pub fn dr_layout(max_depth: u32) -> PairLayout {
    let d = max_depth.min(crate::bdpt::MAX_PATH_DEPTH) as usize;
    let even = |n: usize| n + n % 2;
    let camera = even(5 + PER_BOUNCE * (d + 1));
    let light = even(5 + PER_BOUNCE * (d + 1));
    let connection = even(5 * (d + 2));
    let mut dims = [0usize; PATH_STREAMS];
    dims[Stream::Camera.index()] = camera;
    dims[Stream::Light.index()] = light;
    dims[Stream::Connection.index()] = connection;
    PairLayout::new(PATH_STREAMS, &dims).unwrap_or_else(|_| unreachable!("valid dimensions"))
}

/// Numbers per scattering vertex MMLT's subpaths read (lobe 1, direction 2; no roulette).
const MMLT_PER_VERTEX: usize = 3;

/// The coordinates the pairwise stages move on the MMLT chain of depth `depth` (the chain's
/// target is fixed, so the layout is a per-chain constant and the stages stay symmetric):
/// what `crate::bdpt::sample_strategy` reads for any strategy `(s, t)`, `s + t = depth + 2`.
/// Camera stream: raster 2 + lens 2 + time 1 + 3 per vertex; light stream: light 1 +
/// position 2 + direction 2 + 3 per vertex; at most `depth + 1` vertices each; connection
/// stream: the strategy choice and one connection (at most 3). Sizes rounded up to even.
/// The DR authors size their vector per MMLT depth too, `(depth + 2) * 3`. A depth-1 chain
/// moves 28 coordinates, a depth-5 chain 52, where [`dr_layout`] moves 96 at max depth 5.
#[must_use]
pub fn mmlt_layout(depth: u32) -> PairLayout {
    let d = depth.min(crate::bdpt::MAX_PATH_DEPTH) as usize;
    let even = |n: usize| n + n % 2;
    let subpath = even(5 + MMLT_PER_VERTEX * (d + 1));
    let mut dims = [0usize; PATH_STREAMS];
    dims[Stream::Camera.index()] = subpath;
    dims[Stream::Light.index()] = subpath;
    dims[Stream::Connection.index()] = 4;
    PairLayout::new(PATH_STREAMS, &dims).unwrap_or_else(|_| unreachable!("valid dimensions"))
}

/// Numbers per bounce the path tracer reads (light choice 1, light position 2, lobe 1,
/// direction 2, roulette 1: `crate::integrator::pt`).
const PT_PER_BOUNCE: usize = 7;

/// The coordinates the pairwise stages move on PSSMLT over the path tracer
/// ([`crate::mlt::PtTarget`]): raster 2 + lens 2 + time 1 + 7 per bounce of the camera
/// stream, for paths of at most `max_depth` bounces (plus one for the last emitter hit);
/// rounded up to even.
#[must_use]
pub fn pt_layout(max_depth: u32) -> PairLayout {
    let d = max_depth.min(crate::bdpt::MAX_PATH_DEPTH) as usize;
    let camera = 5 + PT_PER_BOUNCE * (d + 1);
    let mut dims = [0usize; PATH_STREAMS];
    dims[Stream::Camera.index()] = camera + camera % 2;
    PairLayout::new(PATH_STREAMS, &dims).unwrap_or_else(|_| unreachable!("valid dimensions"))
}

/// The layout of a chain on `base` (for the rules with fixed layouts; the orbital rule needs
/// none, [`lazy_orbital_kernel`]): [`dr_layout`]`(max_depth)` on PSSMLT (one target of every
/// depth), [`pt_layout`]`(max_depth)` over the path tracer, [`mmlt_layout`]`(depth)` on MMLT
/// (the chain's depth).
#[must_use]
pub fn chain_layout(base: DrBase, max_depth: u32, depth: u32) -> PairLayout {
    match base {
        DrBase::Pssmlt => dr_layout(max_depth),
        DrBase::PssmltPt => pt_layout(max_depth),
        DrBase::Mmlt => mmlt_layout(depth),
    }
}

/// The radius scale of the timid second stage (moved to [`pss::dr`]).
pub use pss::dr::TIMID_SCALE;

/// Streams the second stage moves on `base`.
#[must_use]
pub fn second_stage_streams(base: DrBase) -> u8 {
    match base {
        DrBase::Pssmlt | DrBase::PssmltPt => pss::ALL_STREAMS,
        DrBase::Mmlt => 1 << Stream::Camera.index(),
    }
}

/// Streams the second stage moves for MMLT's light-tracing strategies (t = 1): camera and
/// light.
#[must_use]
pub fn light_tracing_streams() -> u8 {
    (1 << Stream::Camera.index()) | (1 << Stream::Light.index())
}

/// The light-tracing test of MMLT's strategy choice: true if the state `x` of an MMLT target
/// of depth `depth` samples a strategy with `t = 1`. It reads the first number of the
/// connection stream as `crate::bdpt::sample_strategy` does (`s = floor(u n)`, `n = depth + 2`,
/// in f32), from the stored value (up to date: the current state's evaluation read it).
#[must_use]
pub fn is_light_tracing(x: &PssState, depth: u32) -> bool {
    if depth == 0 {
        return false;
    }
    let Some(&u) = x.raw_values().get(Stream::Connection.index()) else {
        return false;
    };
    let n = depth as usize + 2;
    let u = (u as f32).min(1.0 - f32::EPSILON / 2.0);
    let s = ((u * n as f32) as usize).min(n - 1);
    n - s == 1
}

/// The MMLT strategy choice of the second stage (DR paper section 5.1.2, "Handling Light
/// Tracing"): picks the light-tracing states ([`is_light_tracing`]) of an MMLT target of depth
/// `depth`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightTracing {
    /// The MMLT depth of the chain's target.
    pub depth: u32,
}

impl StageChoice for LightTracing {
    #[inline]
    fn alternate(&self, x: &PssState) -> bool {
        is_light_tracing(x, self.depth)
    }
}

/// A second stage that depends on the MMLT strategy of the current state (DR paper section
/// 5.1.2, "Handling Light Tracing"): `alternate` (made for [`light_tracing_streams`]) for
/// `t = 1` states of an MMLT target of depth `depth`, `normal` otherwise (and always `normal`
/// without a depth: PSSMLT). The strategy coordinate is outside both stages' streams, so `z`
/// and the ghost keep `x`'s strategy and the reverse path makes the same choice.
pub type ByStrategy<P> = ByState<P, Option<LightTracing>>;

/// The second stage's streams on `base` for chains of MMLT depth `depth`
/// ([`second_stage_streams`], and [`light_tracing_streams`] for light-tracing states on MMLT).
#[must_use]
pub fn strategy_streams(base: DrBase, depth: u32) -> SecondStageStreams<Option<LightTracing>> {
    SecondStageStreams {
        normal: second_stage_streams(base),
        alternate: light_tracing_streams(),
        choice: (base == DrBase::Mmlt).then_some(LightTracing { depth }),
    }
}

/// The orbital kernel (`depth`: the MMLT depth of the chain's target; ignored on PSSMLT):
/// [`pss::dr::orbital_kernel`] with [`strategy_streams`].
#[must_use]
pub fn orbital_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<PairwiseMltProposal, ByStrategy<OnLayout<Orbital>>> {
    pss::dr::orbital_kernel(layout, p_large, strategy_streams(base, depth))
}

/// The orbital kernel at the cost of what a path reads (`depth` as [`orbital_kernel`]):
/// [`pss::dr::lazy_orbital_kernel`] with [`strategy_streams`]. No layout: every pair of every
/// stream moves, computed only where the path sampler reads ([`pss::LazyPairwise`]). What
/// [`DrVariant::Orbital`] runs.
///
/// With `fixed_strategy` on MMLT, the paper's chain (section 5.1.2; the authors' code mutates
/// the strategy number with the identity kernel): neither stage moves MMLT's strategy
/// choice, the first number of the connection stream ([`LazyPairParams::fixed_first`]);
/// large steps draw it afresh with everything else (the authors' large step resamples the
/// whole state). Exact: keeping a coordinate is its own reverse move in both stages, the
/// kept coordinate is fixed per stream (not per state), so the rest pairs up the same way
/// from every state, and eq. 11's `Q1(y | z) = Q1(y | x)` holds pair by pair as before; the
/// second stage's light-tracing choice reads the kept number, as it already must.
#[must_use]
pub fn lazy_orbital_kernel(
    base: DrBase,
    p_large: f64,
    depth: u32,
    fixed_strategy: bool,
) -> DelayedRejection<PairwiseMltProposal<LazyPairwise>, ByStrategy<LazyOrbital>> {
    let fixed = if fixed_strategy && base == DrBase::Mmlt {
        1 << Stream::Connection.index()
    } else {
        0
    };
    let params = LazyPairParams::default().with_fixed_first(fixed);
    pss::dr::lazy_orbital_kernel_with(params, p_large, strategy_streams(base, depth))
}

/// The authors' Tierney-Mira kernel (`depth` as [`orbital_kernel`]):
/// [`pss::dr::tierney_mira_kernel`] with the authors' stages
/// ([`PerCoordinateParams::rioux_lavoie2020`]) and [`strategy_streams`].
#[must_use]
pub fn tierney_mira_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<KelemenFirstStage, ByStrategy<GaussianTimidStage>> {
    pss::dr::tierney_mira_kernel(
        layout,
        p_large,
        strategy_streams(base, depth),
        PerCoordinateParams::rioux_lavoie2020(),
    )
}

/// The authors' Green-Mira kernel (`depth` as [`orbital_kernel`]):
/// [`pss::dr::green_mira_kernel`] with the authors' stages and [`strategy_streams`].
#[must_use]
pub fn green_mira_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<KelemenFirstStage, ByStrategy<GaussianTimidStage>, LayoutGhost> {
    pss::dr::green_mira_kernel(
        layout,
        p_large,
        strategy_streams(base, depth),
        PerCoordinateParams::rioux_lavoie2020(),
    )
}

/// The pairwise Tierney-Mira kernel (`depth` as [`orbital_kernel`]):
/// [`pss::dr::pairwise_tierney_mira_kernel`] with [`strategy_streams`].
#[must_use]
pub fn pairwise_tierney_mira_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<
    PairwiseMltProposal,
    ByStrategy<IndependentSecondStage<OnLayout<PairwiseKelemen>>>,
> {
    pss::dr::pairwise_tierney_mira_kernel(layout, p_large, strategy_streams(base, depth))
}

/// The pairwise Green-Mira kernel (`depth` as [`orbital_kernel`]):
/// [`pss::dr::pairwise_green_mira_kernel`] with [`strategy_streams`].
#[must_use]
pub fn pairwise_green_mira_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<
    PairwiseMltProposal,
    ByStrategy<IndependentSecondStage<OnLayout<PairwiseKelemen>>>,
    LayoutGhost,
> {
    pss::dr::pairwise_green_mira_kernel(layout, p_large, strategy_streams(base, depth))
}
