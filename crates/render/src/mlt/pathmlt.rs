//! Path-space MLT (`--integrator pathmlt`, Veach & Guibas 1997 as used by Otsu et al. 2018):
//! `pathspace`'s target and mutations over render's scenes ([`PathSpaceScene`]), run through
//! mcmc-core's generic render loop with independent paths and `f / p` bootstrap weights.

use std::sync::atomic::AtomicBool;

use mcmc_core::proposal::Mixture;
use mcmc_core::render_loop::{IndependentStates, Splat};
use mcmc_core::{ChainRng, Mh, NoAdaptation, Progress, Target};
use pathspace::regional::{
    DirectionPartition, PathPartition, PlanePartition, PooledRegionalStats, RegionalAdaptParams,
    RegionalSigmas, ScreenPartition, SharedRegionalAdaptation, SharedSigmas,
};
use pathspace::{
    BidirectionalMutation, BidirectionalParams, BidirectionalSampler, BidirectionalSamplerParams,
    FixedScale, IndependenceMutation, IndependentSampler, Path, PathContribution, PathMutation,
    PathTarget, PerturbOrGlobal, PerturbOrGlobalPair, Perturbation, PerturbationKind, ScaleSource,
    UnidirectionalParams, UnidirectionalSampler,
};
use rand::SeedableRng;

use super::run::{MltBudget, MltOutput, MltSettings};
use super::MltDriver;
use crate::error::RenderError;
use crate::pathspace_scene::PathSpaceScene;

/// Largest `--max-depth` pathmlt accepts: paths of at most 64 edges (`pathspace`'s limit).
pub const PATHMLT_MAX_DEPTH: u32 = 63;

/// The allowed `--max-depth` range, for error messages.
const DEPTH_RANGE: &str = "0..=63 with --integrator pathmlt";

/// The angular scale `sigma` (radians) of the lens and multi-chain perturbations (FIXED, and
/// the start of the adaptive variants), for both the camera chain and later chains. The RA
/// paper starts its adaptation at `e^{1/2}` rad (section 8.1), which suits an adapted kernel;
/// a fixed kernel needs a local scale: 0.02 rad is about a third of a pixel of a 40 degree,
/// 16-pixel image and a few pixels at 256 pixels.
pub const PATHMLT_SIGMA: f64 = 0.02;

/// How pathmlt adapts the perturbation's angular scale (`--adapt`; regional-adaptive paper,
/// section 8.1, and `docs/methods/regional-adaptive.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathAdapt {
    /// FIXED: [`PATHMLT_SIGMA`] everywhere, no adaptation (the default).
    #[default]
    Fixed,
    /// GLOBAL: one adapted scale for all of path space (`PathPartition::Single`).
    Global,
    /// RA-GRID: lens, an [`ADAPT_GRID_N`]`^2` screen grid; multi-chain, the 4-D partition with
    /// an [`ADAPT_GRID_N`]`^2` screen grid and an [`ADAPT_GRID_BOTTOM`]`^2` direction grid per
    /// cell.
    Grid,
    /// RA-QUADTREE: lens, a screen quadtree; multi-chain, an [`ADAPT_GRID_N`]`^2` screen grid
    /// with a direction quadtree per cell; refined by the budget-scaled `M_split`, `M_refine`.
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
/// (the loop's default is 1000): one `lambda` step per region per round, so rounds must be
/// small for the scales to settle within a render.
pub const ADAPT_ROUND_MUTATIONS: u64 = 50;

/// The MLT target of path-space MLT on render's film: `pathspace::PathTarget` (`luminance f`)
/// with its raster position mapped to pixels, one splat per path.
#[derive(Clone, Copy, Debug)]
pub struct PathMltTarget<'a> {
    inner: PathTarget<'a, PathSpaceScene<'a>>,
    width: f64,
    height: f64,
}

impl<'a> PathMltTarget<'a> {
    /// The target over `scene` for a `width x height` image (the scene's camera must have
    /// that size).
    #[must_use]
    pub fn new(scene: &'a PathSpaceScene<'a>, width: usize, height: usize) -> Self {
        Self {
            inner: PathTarget::new(scene),
            width: width as f64,
            height: height as f64,
        }
    }
}

impl Target for PathMltTarget<'_> {
    type State = Path;
    type Payload = Option<Splat>;

    fn evaluate(&self, x: &mut Path, payload: &mut Option<Splat>) -> f64 {
        let mut c = PathContribution::default();
        let log_density = self.inner.evaluate(x, &mut c);
        *payload = log_density.is_finite().then(|| Splat {
            raster: [
                (c.raster[0] * self.width) as f32,
                (c.raster[1] * self.height) as f32,
            ],
            rgb: c.rgb.0.map(|v| v as f32),
        });
        log_density
    }
}

/// The render loop's independent states for path space: a path drawn by an independent
/// sampler from the key's RNG (an empty path, weight 0, if the draw fails), with bootstrap
/// weight `f(x) / p(x)` (an unbiased estimate of `b = int luminance(f) dmu`).
#[derive(Clone, Copy, Debug)]
pub struct IndependentPaths<Smp> {
    /// The sampler.
    pub sampler: Smp,
}

impl<Smp: IndependentSampler + Sync> IndependentStates<Path> for IndependentPaths<Smp> {
    fn empty(&self) -> Path {
        Path::new()
    }

    fn independent(&self, key: u64, state: &mut Path) {
        let mut rng = ChainRng::seed_from_u64(key);
        if !self.sampler.sample(&mut rng, state) {
            state.vertices.clear();
        }
    }

    fn weight(&self, state: &Path, log_density: f64) -> f64 {
        if !log_density.is_finite() {
            return 0.0;
        }
        let log_p = self.sampler.log_density(state);
        if log_p.is_finite() {
            (log_density - log_p).exp()
        } else {
            0.0
        }
    }
}

/// The global moves of pathmlt, components 1 and 2 of its mixture: Veach and Guibas'
/// bidirectional mutation (section 5.2) with eye-side and light-side regeneration, and the
/// independence mutation drawing from [`independent_sampler`]. Either reaches, in one step,
/// every path a bidirectional path tracer reaches; the independence mutation proposes small
/// isolated features (a light seen through two mirrors) in proportion to the sampler's
/// density rather than only through deletions of the whole path.
pub type GlobalMutation<'a> = PathMutation<
    BidirectionalMutation<'a, PathSpaceScene<'a>>,
    IndependenceMutation<BidirectionalSampler<'a, PathSpaceScene<'a>>>,
>;

/// Share of the global probability given to the independence mutation (component 2).
pub const GLOBAL_INDEPENDENCE_PROBABILITY: f64 = 0.5;

/// The mutation of pathmlt: a perturbation (component 0) with probability 0.5 where it
/// applies, the rest split between the bidirectional mutation (component 1) and the
/// independence mutation (component 2), each with its own Hastings term (RA paper, section
/// 8.1, with the global move split).
pub type PathMltMutation<'a> = Mixture<
    PathMutation<Perturbation<'a, PathSpaceScene<'a>, FixedScale>, GlobalMutation<'a>>,
    PerturbOrGlobalPair,
>;

/// Path lengths of pathmlt for render's `max_depth` (bounces): at most `max_depth + 1` edges,
/// the same paths as BDPT's.
///
/// # Errors
/// [`RenderError::InvalidSetting`] for `max_depth > 63`.
pub fn max_segments(max_depth: u32) -> Result<usize, RenderError> {
    if max_depth > PATHMLT_MAX_DEPTH {
        return Err(RenderError::setting("max-depth", max_depth, DEPTH_RANGE));
    }
    Ok(max_depth as usize + 1)
}

/// The independent sampler of the bootstrap and of the independence mutation:
/// `pathspace::BidirectionalSampler` with paths of `1..=max_segments` edges, every strategy of
/// a bidirectional path tracer (eye and light subpaths of every length, joined by an edge or
/// by hitting the emitter), so `f / p` is BDPT's balance-heuristic estimate.
///
/// # Errors
/// As [`max_segments`].
pub fn independent_sampler<'a>(
    scene: &'a PathSpaceScene<'a>,
    max_depth: u32,
) -> Result<BidirectionalSampler<'a, PathSpaceScene<'a>>, RenderError> {
    let params = BidirectionalSamplerParams {
        max_segments: max_segments(max_depth)?,
    };
    BidirectionalSampler::new(scene, params)
        .map_err(|_| RenderError::setting("max-depth", max_depth, DEPTH_RANGE))
}

/// The eye-side sampler pathmlt used before [`independent_sampler`]:
/// `pathspace::UnidirectionalSampler` with paths of `1..=max_segments` edges and connection
/// probability 1/2. It cannot reach paths whose light arrives only through specular vertices
/// seen from a diffuse one (`L S+ D E` with a small light): kept for comparisons.
///
/// # Errors
/// As [`max_segments`].
pub fn unidirectional_sampler<'a>(
    scene: &'a PathSpaceScene<'a>,
    max_depth: u32,
) -> Result<UnidirectionalSampler<'a, PathSpaceScene<'a>>, RenderError> {
    let params = UnidirectionalParams {
        max_segments: max_segments(max_depth)?,
        connect_probability: 0.5,
    };
    UnidirectionalSampler::new(scene, params)
        .map_err(|_| RenderError::setting("max-depth", max_depth, DEPTH_RANGE))
}

/// The mutation of pathmlt with `kind` of perturbation at scale `sigma` (radians).
///
/// # Errors
/// As [`max_segments`], and for `sigma` not finite and positive.
pub fn mutation<'a>(
    scene: &'a PathSpaceScene<'a>,
    kind: PerturbationKind,
    sigma: f64,
    max_depth: u32,
) -> Result<PathMltMutation<'a>, RenderError> {
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(RenderError::setting("perturbation sigma", sigma, "> 0"));
    }
    mutation_with_scale(scene, kind, FixedScale::uniform(sigma), max_depth)
}

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

/// The mutation of pathmlt with the perturbation's scales from `Sc`.
type ScaledMutation<'a, Sc> = Mixture<
    PathMutation<Perturbation<'a, PathSpaceScene<'a>, Sc>, GlobalMutation<'a>>,
    PerturbOrGlobalPair,
>;

/// The mutation of pathmlt with `kind` of perturbation whose scales come from `scale`.
fn mutation_with_scale<'a, Sc: ScaleSource>(
    scene: &'a PathSpaceScene<'a>,
    kind: PerturbationKind,
    scale: Sc,
    max_depth: u32,
) -> Result<ScaledMutation<'a, Sc>, RenderError> {
    let bidirectional = BidirectionalMutation::new(
        scene,
        BidirectionalParams {
            max_segments: max_segments(max_depth)?,
            ..BidirectionalParams::default()
        },
    )
    .map_err(|_| RenderError::setting("max-depth", max_depth, DEPTH_RANGE))?;
    let independence = IndependenceMutation::new(independent_sampler(scene, max_depth)?);
    let selection = PerturbOrGlobalPair {
        perturb: PerturbOrGlobal::otsu2018(kind),
        second_share: GLOBAL_INDEPENDENCE_PROBABILITY,
    };
    Mixture::new(
        vec![
            PathMutation::Perturb(Perturbation::new(scene, kind, scale)),
            PathMutation::Global(PathMutation::Perturb(bidirectional)),
            PathMutation::Global(PathMutation::Global(independence)),
        ],
        selection,
    )
    .map_err(|e| RenderError::setting("perturbation", e, "lens|multichain"))
}

/// Renders `scene` (its camera at `settings.width x settings.height`) with path-space MLT:
/// bootstrap of `settings.bootstrap_samples` independent paths, `settings.chains` chains of
/// Metropolis-Hastings with [`mutation`], expected-value splats. `settings.streams` and
/// `settings.large_step` are not used (no primary sample space).
///
/// # Errors
/// The scene features pathmlt does not support ([`PathSpaceScene::new`]) and a max depth out
/// of range ([`max_segments`]).
pub fn render(
    scene: &crate::scene::Scene,
    kind: PerturbationKind,
    max_depth: u32,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<MltOutput, RenderError> {
    let view = PathSpaceScene::new(scene)?;
    let sampler = independent_sampler(&view, max_depth)?;
    let kernel_proto = mutation(&view, kind, PATHMLT_SIGMA, max_depth)?;
    let targets = [PathMltTarget::new(&view, settings.width, settings.height)];
    let states = IndependentPaths { sampler };
    let (out, _) = MltDriver::new(&targets, settings).states(&states).run(
        |_| Mh::new(kernel_proto.clone()),
        |_| NoAdaptation,
        progress,
        cancel,
    );
    Ok(out)
}

/// The regional-adaptation parameters of `--adapt` for a render of `settings`: the paper's
/// values with `M_refine`, `M_split` scaled to the mutation budget
/// ([`RegionalAdaptParams::otsu2018_for_budget`]; the paper's own `otsu2018` under a time
/// budget, whose mutation count is unknown in advance), `lambda_0 = ln(`[`PATHMLT_SIGMA`]`^2)`
/// (the paper starts every adaptive variant at FIXED's scale, section 8.1; our FIXED is
/// 0.02 rad, not the paper's `e^{1/2}`), and no refinement except for the quadtree.
#[must_use]
pub fn adapt_params(adapt: PathAdapt, settings: &MltSettings) -> RegionalAdaptParams {
    let mut params = match settings.budget {
        MltBudget::MutationsPerPixel(m) => {
            let pixels = (settings.width * settings.height) as f64;
            RegionalAdaptParams::otsu2018_for_budget((m * pixels).round().max(1.0) as u64)
        }
        MltBudget::Time(_) => RegionalAdaptParams::otsu2018(),
    };
    params.adapt.lambda_initial = (PATHMLT_SIGMA * PATHMLT_SIGMA).ln();
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

/// As [`render`] with the perturbation's scale adapted by `adapt`: FIXED is [`render`];
/// the others run [`SharedRegionalAdaptation`] with [`adapt_params`] over
/// [`adapt_partition`], every chain's perturbation holding a clone of one [`SharedSigmas`],
/// statistics pooled in job order at the render loop's synchronisation points every
/// [`ADAPT_ROUND_MUTATIONS`] mutations per chain (bit-identical images for any thread count
/// under a mutation budget). Notes summarise the learned scales.
///
/// # Errors
/// As [`render`].
pub fn render_adaptive(
    scene: &crate::scene::Scene,
    kind: PerturbationKind,
    adapt: PathAdapt,
    max_depth: u32,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<MltOutput, RenderError> {
    let params = adapt_params(adapt, settings);
    render_adaptive_with_params(
        scene, kind, adapt, max_depth, settings, &params, progress, cancel,
    )
    .map(|(out, _, _)| out)
}

/// What [`render_adaptive_with_params`] returns: the render, the learned `sigma_1` per pixel
/// (row-major) and the adaptation's [`AdaptSummary`].
pub type AdaptiveRender = (MltOutput, Option<Vec<f64>>, Option<AdaptSummary>);

/// As [`render_adaptive`] with the given regional-adaptation `params` (used as given, e.g.
/// [`adapt_params`] with `M_refine`, `M_split` scaled to an expected mutation count under a
/// time budget), also returning the learned scale over the screen: `sigma_1` per pixel of the
/// `settings.width x settings.height` image (`RegionalSigmas::screen_sigma_map`, row-major;
/// `None` for FIXED or if no synchronisation point was reached), and the adaptation's
/// [`AdaptSummary`] (`None` for FIXED; its [`AdaptSummary::note`] is the output's note).
///
/// # Errors
/// As [`render`], and for invalid `params`.
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
    let view = PathSpaceScene::new(scene)?;
    let Some(partition) = adapt_partition(&view, kind, adapt)? else {
        return render(scene, kind, max_depth, settings, progress, cancel)
            .map(|out| (out, None, None));
    };
    let sampler = independent_sampler(&view, max_depth)?;
    let bad = |e: pathspace::PathspaceError| RenderError::setting("adapt", e, "valid parameters");
    let sigmas = SharedSigmas::new(
        RegionalSigmas::new(partition, params.adapt.lambda_initial, 1.0).map_err(bad)?,
    );
    let kernel_proto: AdaptiveMutation<'_> = mutation_with_scale(&view, kind, sigmas, max_depth)?;
    let controller = SharedRegionalAdaptation::new(*params).map_err(bad)?;
    let targets = [PathMltTarget::new(&view, settings.width, settings.height)];
    let states = IndependentPaths { sampler };
    let (mut out, pooled) = MltDriver::new(&targets, settings)
        .states(&states)
        .round_mutations(ADAPT_ROUND_MUTATIONS)
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
    let summary = pooled.map(|pooled| AdaptSummary::of(adapt, &pooled));
    if let Some(summary) = &summary {
        out.notes.push(summary.note());
    }
    Ok((out, map, summary))
}

/// What regional adaptation did in one render (Otsu et al. 2018, section 6): its regions,
/// rounds, refinements and the learned `sigma_1` over the regions that were updated.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdaptSummary {
    /// The adaptation variant.
    pub adapt: PathAdapt,
    /// False if no synchronisation point was reached (nothing was learned).
    pub synchronised: bool,
    /// Regions of the final partition.
    pub regions: usize,
    /// Regions whose scale was updated more than once.
    pub updated: usize,
    /// Synchronisation rounds (one `lambda` step per region per round).
    pub rounds: u64,
    /// Refinement passes (RA-QUADTREE, section 6.2).
    pub refinements: u64,
    /// Leaves split over all refinements.
    pub splits: u64,
    /// The learned `sigma_1` (radians) over the updated regions: minimum, median (the
    /// nearest-rank one) and maximum; NaN when no region was updated.
    pub sigma_min: f64,
    /// See [`AdaptSummary::sigma_min`].
    pub sigma_median: f64,
    /// See [`AdaptSummary::sigma_min`].
    pub sigma_max: f64,
}

impl AdaptSummary {
    /// The summary of the pooled statistics of `adapt`.
    fn of(adapt: PathAdapt, pooled: &PooledRegionalStats<AdaptPartition<'_>>) -> Self {
        let mut summary = Self {
            adapt,
            synchronised: false,
            regions: pooled.num_regions(),
            updated: 0,
            rounds: pooled.rounds(),
            refinements: pooled.refinements(),
            splits: pooled.splits(),
            sigma_min: f64::NAN,
            sigma_median: f64::NAN,
            sigma_max: f64::NAN,
        };
        let Some(sigmas) = pooled.sigmas() else {
            return summary;
        };
        let mut updated: Vec<f64> = (0..pooled.num_regions())
            .filter(|&k| pooled.region_stats(k).is_some_and(|r| r.adapt.updates > 1))
            .map(|k| sigmas.get().sigmas_of_region(k)[0])
            .collect();
        updated.sort_by(f64::total_cmp);
        let q = |f: f64| {
            updated
                .get(((updated.len().max(1) - 1) as f64 * f).round() as usize)
                .copied()
                .unwrap_or(f64::NAN)
        };
        summary.synchronised = true;
        summary.updated = updated.len();
        (summary.sigma_min, summary.sigma_median, summary.sigma_max) = (q(0.0), q(0.5), q(1.0));
        summary
    }

    /// One line for people on the learned scales: regions, refinements, and `sigma` over the
    /// regions that were updated at least once (the render's note).
    #[must_use]
    pub fn note(&self) -> String {
        let name = self.adapt.name();
        if !self.synchronised {
            return format!("--adapt {name}: no synchronisation point reached");
        }
        if self.updated == 0 {
            return format!(
                "--adapt {name}: {} regions, none updated in {} rounds (sigma stays {PATHMLT_SIGMA} rad)",
                self.regions, self.rounds
            );
        }
        format!(
            "--adapt {name}: {} regions ({} updated), {} rounds, {} refinements, {} splits; learned sigma (rad) min {:.3e}, median {:.3e}, max {:.3e}",
            self.regions,
            self.updated,
            self.rounds,
            self.refinements,
            self.splits,
            self.sigma_min,
            self.sigma_median,
            self.sigma_max
        )
    }
}
