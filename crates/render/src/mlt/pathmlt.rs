//! Path-space MLT (`--integrator pathmlt`, Veach & Guibas 1997 as used by Otsu et al. 2018):
//! `pathspace`'s target and mutations over render's scenes ([`PathSpaceScene`]), run through
//! mcmc-core's generic render loop with independent paths and `f / p` bootstrap weights.

use std::sync::atomic::AtomicBool;

use mcmc_core::proposal::Mixture;
use mcmc_core::render_loop::{IndependentStates, Splat};
use mcmc_core::{ChainRng, Mh, NoAdaptation, Progress, Target};
use pathspace::{
    ra_mixture, BidirectionalMutation, BidirectionalParams, FixedScale, IndependentSampler, Path,
    PathContribution, PathMutation, PathTarget, PerturbOrGlobal, Perturbation, PerturbationKind,
    UnidirectionalParams, UnidirectionalSampler,
};
use rand::SeedableRng;

use super::run::{render_mlt_with_states, MltOutput, MltSettings};
use crate::error::RenderError;
use crate::pathspace_scene::PathSpaceScene;

/// Largest `--max-depth` pathmlt accepts: paths of at most 64 edges (`pathspace`'s limit).
pub const PATHMLT_MAX_DEPTH: u32 = 63;

/// The allowed `--max-depth` range, for error messages.
const DEPTH_RANGE: &str = "0..=63 with --integrator pathmlt";

/// The angular scale `sigma` (radians) of the lens and multi-chain perturbations: fixed (no
/// regional adaptation yet, issue 13), for both the camera chain and later chains. The RA
/// paper starts its adaptation at `e^{1/2}` rad (section 8.1), which suits an adapted kernel;
/// a fixed kernel needs a local scale: 0.02 rad is about a third of a pixel of a 40 degree,
/// 16-pixel image and a few pixels at 256 pixels.
pub const PATHMLT_SIGMA: f64 = 0.02;

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

/// The mutation of pathmlt: a perturbation and the bidirectional mutation, 0.5 each, the
/// bidirectional mutation where the perturbation cannot apply (RA paper, section 8.1).
pub type PathMltMutation<'a> = Mixture<
    PathMutation<
        Perturbation<'a, PathSpaceScene<'a>, FixedScale>,
        BidirectionalMutation<'a, PathSpaceScene<'a>>,
    >,
    PerturbOrGlobal,
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

/// The independent sampler of the bootstrap: `pathspace::UnidirectionalSampler` with paths of
/// `1..=max_segments` edges and connection probability 1/2.
///
/// # Errors
/// As [`max_segments`].
pub fn independent_sampler<'a>(
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
    let bidirectional = BidirectionalMutation::new(
        scene,
        BidirectionalParams {
            max_segments: max_segments(max_depth)?,
        },
    )
    .map_err(|_| RenderError::setting("max-depth", max_depth, DEPTH_RANGE))?;
    let perturbation = Perturbation::new(scene, kind, FixedScale::uniform(sigma));
    ra_mixture(kind, perturbation, bidirectional)
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
    Ok(render_mlt_with_states(
        &targets,
        &states,
        |_| Mh::new(kernel_proto.clone()),
        |_| NoAdaptation,
        settings,
        progress,
        cancel,
    ))
}

/// The render session's pathmlt (`--integrator pathmlt`): [`render`] with the session's MCMC
/// settings (chains, bootstrap samples, seed, budget, `--perturbation`), its notes in the
/// output. `scene` must already be at the image size.
///
/// # Errors
/// As [`render`].
pub fn render_session(
    scene: &crate::scene::Scene,
    settings: &crate::session::RenderSettings,
    start: std::time::Instant,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<crate::session::RenderOutput, RenderError> {
    use super::run::{LargeStepMode, MltBudget};
    use crate::budget::Budget;
    let m = &settings.mcmc;
    let mlt_settings = MltSettings {
        width: settings.width as usize,
        height: settings.height as usize,
        chains: m.chains,
        bootstrap_samples: m.bootstrap_samples,
        budget: match settings.budget {
            Budget::SamplesPerPixel(n) => MltBudget::MutationsPerPixel(f64::from(n)),
            Budget::Time(t) => MltBudget::Time(t),
        },
        large_step: LargeStepMode::Fixed(0.0),
        seed: settings.seed,
        streams: 1,
        stage_map: false,
    };
    let out = render(
        scene,
        m.perturbation,
        settings.max_depth,
        &mlt_settings,
        progress,
        cancel,
    )?;
    let mut notes = scene.notes.clone();
    notes.push(format!(
        "path-space MLT: {} perturbation (sigma {PATHMLT_SIGMA} rad) and the bidirectional mutation, 0.5 each; no large steps (--large-step is ignored)",
        match m.perturbation {
            PerturbationKind::Lens => "lens",
            PerturbationKind::MultiChain => "multi-chain",
        }
    ));
    notes.extend(out.notes.iter().cloned());
    if let Some(msg) = &out.message {
        notes.push(msg.clone());
    } else {
        notes.push(format!(
            "bootstrap: b = {:.6} (standard error {:.2e}) from {} samples",
            out.b, out.b_standard_error, out.bootstrap_samples
        ));
        notes.push(format!(
            "acceptance rate {:.3} over {} mutations",
            out.stats.acceptance_rate(),
            out.mutations
        ));
    }
    Ok(crate::session::RenderOutput {
        image: out.image,
        samples: out.mutations,
        dropped_nonfinite: out.dropped + out.non_finite,
        cancelled: out.cancelled,
        elapsed: start.elapsed(),
        notes,
        strategy_images: Vec::new(),
        stage_map: None,
    })
}
