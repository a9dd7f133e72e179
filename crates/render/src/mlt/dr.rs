//! Delayed-rejection MLT (Rioux-Lavoie et al. 2020, docs/methods/drmlt.md)
//! on the path samplers: the kernels of `mcmc_core::delayed_rejection` with the pairwise
//! primary-sample-space stages of `pss` ([`pss::OnLayout`]).
//!
//! Every variant is *bold then timid* (section 5.1) and runs its second stage only after a
//! rejected small step, never after a large step (the authors' implementation; the mixture
//! terms are component-labelled, docs/methods/drmlt.md):
//! - `orbital` (section 4.4, eq. 11): a pairwise polar Kelemen first stage (radii x 1.9, the
//!   authors' preset) and the orbital second stage (wrapped Cauchy, rho = exp(-1/4));
//! - `tierney-mira` (eq. 6-7): the same bold first stage, then a timid pairwise Kelemen step
//!   from `x` with radii / 10 (independent of the rejected `y`; symmetric);
//! - `green-mira` (eq. 12-14): the same stages with the fictional state `y* = z - (y - x)`
//!   on the torus ([`pss::LayoutGhost`]).
//!
//! On MMLT (`DrBase::Mmlt`, section 5.1.2) the second stage moves only the camera stream:
//! the light subpath and the strategy choice (the first number of the connection stream) stay
//! fixed. Light-tracing strategies (t = 1, "Handling Light Tracing" in section 5.1.2) are the
//! exception: their camera stream holds only the raster position, which the connection
//! overrides, so their second stage moves the camera *and* light streams ([`ByStrategy`],
//! which reads the strategy of the current state; the second stage never moves the strategy
//! coordinate, so the reverse path sees the same strategy and the choice is symmetric).
//!
//! Our reading where the paper fixes the MMLT strategy along the whole chain: the bold first
//! stage here moves every stream's layout, strategy coordinate included, so a first-stage
//! candidate may change strategy (an exact move of the MMLT target; it is then judged by the
//! usual acceptance). Only the second stage keeps the strategy.
//!
//! The pairwise stages move a fixed layout of coordinates per stream, sized from the maximum
//! path depth to cover what BDPT reads ([`dr_layout`]); coordinates beyond it are renewed by
//! large steps only (exact, see [`pss::OnLayout`]).

use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::{DelayedRejection, Proposed};
use pss::{
    LayoutGhost, OnLayout, Orbital, PairLayout, PairwiseKelemen, PairwiseKelemenParams,
    PairwiseMltProposal, PssState, WrappedCauchy,
};

use super::PATH_STREAMS;
use crate::sampler::Stream;

/// The acceptance rule of the second stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DrVariant {
    /// Tierney & Mira 1999 (paper eq. 6-7).
    TierneyMira,
    /// Green & Mira 2001 with the fictional state (eq. 12-14).
    GreenMira,
    /// The pairwise orbital rule (eq. 11) — the paper's recommended variant.
    #[default]
    Orbital,
    /// Cheap then expensive (section 5.2, with MALA in place of H2MC): an isotropic Gaussian
    /// first stage and a MALA second stage under Green and Mira's rule, on MMLT
    /// ([`crate::mlt::mala::cheap_then_expensive_kernel`]).
    CheapThenExpensive,
}

impl DrVariant {
    /// The variants with their CLI names.
    pub const ALL: [(&'static str, DrVariant); 4] = [
        ("tierney-mira", DrVariant::TierneyMira),
        ("green-mira", DrVariant::GreenMira),
        ("orbital", DrVariant::Orbital),
        ("cheap-then-expensive", DrVariant::CheapThenExpensive),
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
    let d = max_depth.min(62) as usize;
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

/// The radius scale of the timid second stage of Tierney-Mira and Green-Mira (the authors'
/// sigma / 10).
pub const TIMID_SCALE: f64 = 0.1;

/// The bold first stage with large steps of probability `p_large`.
fn first_stage(layout: PairLayout, p_large: f64) -> PairwiseMltProposal {
    let small = OnLayout::new(
        PairwiseKelemen {
            params: PairwiseKelemenParams::drmlt2020(),
        },
        layout,
    );
    PairwiseMltProposal::new(small, p_large.clamp(0.0, 1.0))
        .unwrap_or_else(|_| unreachable!("clamped"))
}

/// The timid second stage (Tierney-Mira, Green-Mira): a pairwise Kelemen step from `x` with
/// radii scaled by [`TIMID_SCALE`].
fn timid_stage(
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

/// Streams the second stage moves on `base`.
#[must_use]
pub fn second_stage_streams(base: DrBase) -> u8 {
    match base {
        DrBase::Pssmlt => pss::ALL_STREAMS,
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

/// A second stage that depends on the MMLT strategy of the current state (DR paper section
/// 5.1.2, "Handling Light Tracing"): `light_tracing` for `t = 1` states of an MMLT target of
/// depth `depth`, `normal` otherwise (and always `normal` without a depth: PSSMLT). The
/// strategy coordinate is outside both stages' streams, so `z` and the ghost keep `x`'s
/// strategy and the reverse path makes the same choice.
#[derive(Clone, Copy, Debug)]
pub struct ByStrategy<P> {
    /// The MMLT depth of the chain's target, or `None` (PSSMLT: one stage).
    pub depth: Option<u32>,
    /// The stage of every other state.
    pub normal: P,
    /// The stage of light-tracing states.
    pub light_tracing: P,
}

impl<P> ByStrategy<P> {
    fn pick(&self, x: &PssState) -> &P {
        match self.depth {
            Some(d) if is_light_tracing(x, d) => &self.light_tracing,
            _ => &self.normal,
        }
    }
}

impl<P: ConditionalProposal<PssState>> ConditionalProposal<PssState> for ByStrategy<P> {
    fn propose<R: rand::Rng + ?Sized>(
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

/// The strategy-aware second stage made by `stage(stream_mask)` for `base` and `depth`.
fn by_strategy<P>(base: DrBase, depth: u32, stage: impl Fn(u8) -> P) -> ByStrategy<P> {
    ByStrategy {
        depth: (base == DrBase::Mmlt).then_some(depth),
        normal: stage(second_stage_streams(base)),
        light_tracing: stage(light_tracing_streams()),
    }
}

/// The orbital kernel (`depth`: the MMLT depth of the chain's target; ignored on PSSMLT).
#[must_use]
pub fn orbital_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<PairwiseMltProposal, ByStrategy<OnLayout<Orbital>>> {
    let second = by_strategy(base, depth, |mask| {
        OnLayout::new(
            Orbital {
                angle: WrappedCauchy::default(),
            },
            layout,
        )
        .with_stream_mask(mask)
    });
    DelayedRejection::orbital(first_stage(layout, p_large), second).second_stage_after_small_steps()
}

/// The Tierney-Mira kernel (`depth` as [`orbital_kernel`]).
#[must_use]
pub fn tierney_mira_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<
    PairwiseMltProposal,
    ByStrategy<IndependentSecondStage<OnLayout<PairwiseKelemen>>>,
> {
    DelayedRejection::tierney_mira(
        first_stage(layout, p_large),
        by_strategy(base, depth, |mask| timid_stage(layout, mask)),
    )
    .with_symmetric_second_stage()
    .second_stage_after_small_steps()
}

/// The Green-Mira kernel (`depth` as [`orbital_kernel`]).
#[must_use]
pub fn green_mira_kernel(
    layout: PairLayout,
    base: DrBase,
    p_large: f64,
    depth: u32,
) -> DelayedRejection<
    PairwiseMltProposal,
    ByStrategy<IndependentSecondStage<OnLayout<PairwiseKelemen>>>,
    LayoutGhost,
> {
    DelayedRejection::green_mira(
        first_stage(layout, p_large),
        by_strategy(base, depth, |mask| timid_stage(layout, mask)),
        LayoutGhost {
            layout,
            stream_mask: pss::ALL_STREAMS,
        },
    )
    .with_symmetric_second_stage()
    .second_stage_after_small_steps()
}
