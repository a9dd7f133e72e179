//! pathmlt's regional adaptation (Otsu et al. 2018): the `--adapt` variants, their
//! partitions and parameters, and the render with per-region scales.

use std::sync::atomic::AtomicBool;

use mcmc_core::proposal::Mixture;
use mcmc_core::{Mh, Progress};
use pathspace::regional::{
    DirectionPartition, PathPartition, PlanePartition, RegionalAdaptParams, RegionalSigmas,
    ScreenPartition, SharedRegionalAdaptation, SharedSigmas,
};
use pathspace::{PathMutation, PerturbOrGlobalPair, Perturbation, PerturbationKind};

use super::summary::AdaptSummary;
use super::{
    independent_sampler, lambda_of_sigma, mutation_with_scale, render_fixed, GlobalMutation,
    IndependentPaths, PathMltTarget, PATHMLT_SIGMA,
};
use crate::error::RenderError;
use crate::mlt::run::{MltOutput, MltSettings};
use crate::mlt::MltDriver;
use crate::pathspace_scene::PathSpaceScene;

/// How pathmlt adapts the perturbation's angular scale (`--adapt`; regional-adaptive paper,
/// section 8.1, and `docs/methods/regional-adaptive.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathAdapt {
    /// FIXED: one scale everywhere, no adaptation (the default).
    #[default]
    Fixed,
    /// GLOBAL: one adapted scale for all of path space (`PathPartition::Single`).
    Global,
    /// RA-GRID: lens, an [`ADAPT_GRID_N`]`^2` screen grid; multi-chain, the 4-D partition with
    /// an [`ADAPT_GRID_N`]`^2` screen grid and an [`ADAPT_GRID_BOTTOM`]`^2` direction grid per
    /// cell.
    Grid,
    /// RA-QUADTREE: lens, a screen quadtree; multi-chain, an [`ADAPT_GRID_N`]`^2` screen grid
    /// with a direction quadtree per cell; refined by `M_split`, `M_refine` from the pixel count
    /// (mcmc-core's `RegionalScaleParams::otsu2018_for_pixels`).
    Quadtree,
}

impl PathAdapt {
    /// The command-line name.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Fixed => "fixed",
            Self::Global => "global",
            Self::Grid => "grid",
            Self::Quadtree => "quadtree",
        }
    }
}

/// `N` of the lens screen grid and `N_top` of the 4-D partition (the paper's `N_top = 20`,
/// section 8.1, used for both).
pub const ADAPT_GRID_N: usize = 20;

/// `N_bottom` of the multi-chain direction grid (the paper's 50).
pub const ADAPT_GRID_BOTTOM: usize = 50;

/// Deepest quadtree level (screen or direction): cells of `2^-10` of the unit square.
pub const ADAPT_QUADTREE_DEPTH: u8 = 10;

/// Mutations per chain between two synchronisation points of the render loop when adapting
/// (the loop's default is 1000). Every `L` proposals from a region make one step, replayed at
/// the synchronisation point (mcmc-core's `RegionalUpdateRule::EveryLVisits`); a round's
/// proposals all use the scales published at its start, so short rounds keep that lag to a
/// few steps per region.
pub const ADAPT_ROUND_MUTATIONS: u64 = 2;

/// The partition of pathmlt's regional adaptation.
pub type AdaptPartition<'a> = PathPartition<&'a PathSpaceScene<'a>>;

/// The mutation of pathmlt with per-region scales (`--adapt global|grid|quadtree`).
pub type AdaptiveMutation<'a> = Mixture<
    PathMutation<
        Perturbation<'a, PathSpaceScene<'a>, SharedSigmas<AdaptPartition<'a>>>,
        GlobalMutation<'a>,
    >,
    PerturbOrGlobalPair,
>;

/// The regional-adaptation parameters of `--adapt` for `kind` of perturbation on a render of
/// `settings`, starting at scale `sigma` (radians; `lambda_0 = log sigma^2`, the paper starts
/// every adaptive variant at FIXED's scale, section 8.1): the paper's values with `M_split`,
/// `M_refine` and a cap on the leaves from the pixel count
/// ([`RegionalAdaptParams::otsu2018_for_pixels`]: at most one leaf per 16 pixels; the 4-D
/// partition's [`ADAPT_GRID_N`]`^2` top cells come on top), and no refinement except for the
/// quadtree.
#[must_use]
pub fn adapt_params(
    adapt: PathAdapt,
    kind: PerturbationKind,
    sigma: f64,
    settings: &MltSettings,
) -> RegionalAdaptParams {
    let pixels = (settings.width * settings.height) as u64;
    let mut params = RegionalAdaptParams::otsu2018_for_pixels(pixels);
    if kind == PerturbationKind::MultiChain {
        params.max_regions = params
            .max_regions
            .map(|m| m.saturating_add(ADAPT_GRID_N * ADAPT_GRID_N));
    }
    params.adapt.lambda_initial = lambda_of_sigma(sigma);
    if adapt != PathAdapt::Quadtree {
        params.split_after_visits = None;
    }
    params
}

/// The partition of `--adapt` for `kind` of perturbation (`None` for FIXED).
///
/// # Errors
/// Never for the constants used (the partitions' own range checks).
pub fn adapt_partition<'a>(
    scene: &'a PathSpaceScene<'a>,
    kind: PerturbationKind,
    adapt: PathAdapt,
) -> Result<Option<AdaptPartition<'a>>, RenderError> {
    let bad = |e: pathspace::PathspaceError| RenderError::setting("adapt", e, "a valid partition");
    let plane = match adapt {
        PathAdapt::Fixed => return Ok(None),
        PathAdapt::Global => return Ok(Some(PathPartition::Single)),
        PathAdapt::Grid => match kind {
            PerturbationKind::Lens => PlanePartition::grid(ADAPT_GRID_N),
            PerturbationKind::MultiChain => PlanePartition::grid(ADAPT_GRID_BOTTOM),
        },
        PathAdapt::Quadtree => PlanePartition::quadtree(ADAPT_QUADTREE_DEPTH),
    }
    .map_err(bad)?;
    Ok(Some(match kind {
        PerturbationKind::Lens => PathPartition::Screen(ScreenPartition::new(scene, plane)),
        PerturbationKind::MultiChain => PathPartition::Direction(
            DirectionPartition::new(scene, ADAPT_GRID_N, plane).map_err(bad)?,
        ),
    }))
}

/// One pathmlt render with its scale settings: the perturbation, `--adapt`, the fixed or
/// initial scale, the synchronisation rounds and the regional-adaptation parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptRender {
    /// The perturbation.
    pub kind: PerturbationKind,
    /// The adaptation variant.
    pub adapt: PathAdapt,
    /// FIXED's scale (radians); the adaptive variants start at `params.adapt.lambda_initial`.
    pub sigma: f64,
    /// Mutations per chain between synchronisation points when adapting
    /// ([`ADAPT_ROUND_MUTATIONS`] by default).
    pub round_mutations: u64,
    /// Maximum path depth (bounces).
    pub max_depth: u32,
    /// The regional-adaptation parameters ([`adapt_params`]).
    pub params: RegionalAdaptParams,
}

/// As [`super::render`] with the perturbation's scale adapted by `adapt`: FIXED is
/// [`super::render`] (at [`PATHMLT_SIGMA`]); the others run [`SharedRegionalAdaptation`] with
/// [`adapt_params`] from [`PATHMLT_SIGMA`] over [`adapt_partition`] (see [`render_scaled`]).
///
/// # Errors
/// As [`super::render`].
pub fn render_adaptive(
    scene: &crate::scene::Scene,
    kind: PerturbationKind,
    adapt: PathAdapt,
    max_depth: u32,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<MltOutput, RenderError> {
    let params = adapt_params(adapt, kind, PATHMLT_SIGMA, settings);
    render_adaptive_with_params(
        scene, kind, adapt, max_depth, settings, &params, progress, cancel,
    )
    .map(|(out, _, _)| out)
}

/// What [`render_scaled`] returns: the render, the learned `sigma_1` per pixel (row-major)
/// and the adaptation's [`AdaptSummary`].
pub type AdaptiveRender = (MltOutput, Option<Vec<f64>>, Option<AdaptSummary>);

/// As [`render_scaled`] with FIXED at [`PATHMLT_SIGMA`] and [`ADAPT_ROUND_MUTATIONS`].
///
/// # Errors
/// As [`render_scaled`].
#[allow(clippy::too_many_arguments)]
pub fn render_adaptive_with_params(
    scene: &crate::scene::Scene,
    kind: PerturbationKind,
    adapt: PathAdapt,
    max_depth: u32,
    settings: &MltSettings,
    params: &RegionalAdaptParams,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<AdaptiveRender, RenderError> {
    let run = AdaptRender {
        kind,
        adapt,
        sigma: PATHMLT_SIGMA,
        round_mutations: ADAPT_ROUND_MUTATIONS,
        max_depth,
        params: *params,
    };
    render_scaled(scene, &run, settings, progress, cancel)
}

/// Renders `scene` with pathmlt as `run` says: FIXED is [`render_fixed`] at `run.sigma`; the
/// others run [`SharedRegionalAdaptation`] with `run.params` over [`adapt_partition`], every
/// chain's perturbation holding a clone of one [`SharedSigmas`], statistics pooled in job
/// order at the render loop's synchronisation points every `run.round_mutations` mutations
/// per chain (bit-identical images for any thread count under a mutation budget). Also
/// returns the learned scale over the screen (`RegionalSigmas::screen_sigma_map`, row-major;
/// `None` for FIXED or if no synchronisation point was reached) and the adaptation's
/// [`AdaptSummary`] (`None` for FIXED; its [`AdaptSummary::note`] is the output's note).
///
/// # Errors
/// As [`render_fixed`], and for invalid `run.params` or `run.round_mutations == 0`.
pub fn render_scaled(
    scene: &crate::scene::Scene,
    run: &AdaptRender,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<AdaptiveRender, RenderError> {
    let view = PathSpaceScene::new(scene)?;
    let Some(partition) = adapt_partition(&view, run.kind, run.adapt)? else {
        return render_fixed(
            scene,
            run.kind,
            run.sigma,
            run.max_depth,
            settings,
            progress,
            cancel,
        )
        .map(|out| (out, None, None));
    };
    if run.round_mutations == 0 {
        return Err(RenderError::setting("round-mutations", 0, ">= 1"));
    }
    let params = &run.params;
    let sampler = independent_sampler(&view, run.max_depth)?;
    let bad = |e: pathspace::PathspaceError| RenderError::setting("adapt", e, "valid parameters");
    let sigmas = SharedSigmas::new(
        RegionalSigmas::new(partition, params.adapt.lambda_initial, 1.0).map_err(bad)?,
    );
    let kernel_proto: AdaptiveMutation<'_> =
        mutation_with_scale(&view, run.kind, sigmas, run.max_depth)?;
    let controller = SharedRegionalAdaptation::new(*params).map_err(bad)?;
    let targets = [PathMltTarget::new(&view, settings.width, settings.height)];
    let states = IndependentPaths { sampler };
    let (mut out, pooled) = MltDriver::new(&targets, settings)
        .states(&states)
        .round_mutations(run.round_mutations)
        .run(
            |_| Mh::new(kernel_proto.clone()),
            |_| controller.clone(),
            progress,
            cancel,
        );
    let map = pooled.as_ref().and_then(|p| {
        p.sigmas()
            .map(|s| s.get().screen_sigma_map(settings.width, settings.height))
    });
    let summary = pooled.map(|pooled| AdaptSummary::of(run.adapt, params, &pooled));
    if let Some(summary) = &summary {
        out.notes.push(summary.note());
    }
    Ok((out, map, summary))
}
