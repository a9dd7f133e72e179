//! Path-space MLT (`--integrator pathmlt`, Veach & Guibas 1997 as used by Otsu et al. 2018):
//! `pathspace`'s target and mutations over render's scenes ([`PathSpaceScene`]), run through
//! mcmc-core's generic render loop with independent paths and `f / p` bootstrap weights.

use std::sync::atomic::AtomicBool;

use mcmc_core::proposal::Mixture;
use mcmc_core::render_loop::{IndependentStates, Splat};
use mcmc_core::{ChainRng, Mh, NoAdaptation, Progress, Target};
use pathspace::{
    BidirectionalMutation, BidirectionalParams, BidirectionalSampler, BidirectionalSamplerParams,
    FixedScale, IndependenceMutation, IndependentSampler, Path, PathContribution, PathMutation,
    PathTarget, PerturbOrGlobal, PerturbOrGlobalPair, Perturbation, PerturbationKind, ScaleSource,
    UnidirectionalParams, UnidirectionalSampler,
};
use rand::SeedableRng;

use super::run::{MltOutput, MltSettings};
use super::MltDriver;
use crate::error::RenderError;
use crate::pathspace_scene::PathSpaceScene;

mod adapt;
mod summary;

pub use adapt::{
    adapt_params, adapt_partition, render_adaptive, render_adaptive_with_params, render_scaled,
    AdaptPartition, AdaptRender, AdaptiveMutation, AdaptiveRender, PathAdapt, ADAPT_GRID_BOTTOM,
    ADAPT_GRID_N, ADAPT_QUADTREE_DEPTH, ADAPT_ROUND_MUTATIONS,
};
pub use summary::{AdaptSummary, ACCEPTANCE_TOLERANCE, VISITED_PROPOSALS};

/// Largest `--max-depth` pathmlt accepts: paths of at most 64 edges (`pathspace`'s limit).
pub const PATHMLT_MAX_DEPTH: u32 = 63;

/// The allowed `--max-depth` range, for error messages.
const DEPTH_RANGE: &str = "0..=63 with --integrator pathmlt";

/// The tuned angular scale `sigma` (radians) of the lens and multi-chain perturbations
/// ("tuned FIXED", `--sigma tuned`, and the CLI's FIXED default), for both the camera chain
/// and later chains: 0.02 rad is about a third of a pixel of a 40 degree, 16-pixel image and
/// a few pixels at 256 pixels. Chosen by a sweep, not from the paper (see
/// [`PATHMLT_PAPER_SIGMA`]).
pub const PATHMLT_SIGMA: f64 = 0.02;

/// The regional-adaptive paper's FIXED scale and the adaptive variants' start (section 8.1,
/// "Parameters": `lambda = 1` with `lambda = log sigma^2`, section 5.2): `sigma = e^{1/2}`
/// = 1.6487 rad, the standard deviation of the truncated normal of the polar angle
/// `theta in [0, pi]` between the old and new direction (section 3.3), the unit
/// `pathspace`'s perturbations use. At this scale most perturbations leave the pixel's
/// neighbourhood (the paper: "the mutation size is configured to be large", section 8.2).
pub const PATHMLT_PAPER_SIGMA: f64 = 1.648_721_270_700_128_2;

/// `lambda = log sigma^2` of a scale `sigma` (section 5.2).
#[must_use]
pub fn lambda_of_sigma(sigma: f64) -> f64 {
    (sigma * sigma).ln()
}

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

/// The mutation of pathmlt with the perturbation's scales from `Sc`.
pub(crate) type ScaledMutation<'a, Sc> = Mixture<
    PathMutation<Perturbation<'a, PathSpaceScene<'a>, Sc>, GlobalMutation<'a>>,
    PerturbOrGlobalPair,
>;

/// The mutation of pathmlt with `kind` of perturbation whose scales come from `scale`.
pub(crate) fn mutation_with_scale<'a, Sc: ScaleSource>(
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
/// Metropolis-Hastings with [`mutation`] at [`PATHMLT_SIGMA`], expected-value splats.
/// `settings.streams` and `settings.large_step` are not used (no primary sample space).
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
    render_fixed(
        scene,
        kind,
        PATHMLT_SIGMA,
        max_depth,
        settings,
        progress,
        cancel,
    )
}

/// As [`render`] with the perturbation's fixed scale `sigma` (radians; FIXED of the
/// regional-adaptive paper at [`PATHMLT_PAPER_SIGMA`], section 8.1).
///
/// # Errors
/// As [`render`], and for `sigma` not finite and positive.
pub fn render_fixed(
    scene: &crate::scene::Scene,
    kind: PerturbationKind,
    sigma: f64,
    max_depth: u32,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<MltOutput, RenderError> {
    let view = PathSpaceScene::new(scene)?;
    let sampler = independent_sampler(&view, max_depth)?;
    let kernel_proto = mutation(&view, kind, sigma, max_depth)?;
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
