//! The render entry point shared by the CLI, examples and tests: settings in, image out.
//!
//! CONTRACT (kept stable for the CLI): `RenderSettings`, `IntegratorKind`, `Progress`,
//! `RenderOutput` and `render(scene, settings, progress, cancel)`.

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use crate::bdpt::{self, BdptParams};
use crate::error::RenderError;
use crate::image::Image;
use crate::integrator::pt_driver::{self, PtSettings};
use crate::mlt::{
    self, LargeStepMode, MltBudget, MltSettings, MmltTarget, PssmltTarget, PATH_STREAMS,
};
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use mcmc_core::Mh;
use pss::{KelemenParams, PssmltProposal, SmallMutation, SmallStep};

use crate::mlt::dr::{self, DrBase, DrVariant};
use crate::mlt::mala::{self, MalaConfig};
use mcmc_core::render_loop::ChainSlot;

/// Which integrator renders the image: defined with the integrator table.
pub use crate::integrator::IntegratorKind;

/// Settings of the Markov chain integrators (ignored by PT and BDPT).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McmcSettings {
    /// Large-step probability: fixed, or automatic (Zsolnai & Szirmay-Kalos 2013).
    /// Default: fixed 0.3 (pbrt-v3's and DRMLT's value).
    pub large_step: LargeStepMode,
    /// Number of Markov chains (default 256).
    pub chains: usize,
    /// Independent samples in the bootstrap that estimates `b` and seeds the chains
    /// (default 100 000).
    pub bootstrap_samples: usize,
    /// The small-step kernel (default Kelemen with s1 = 1/1024, s2 = 1/64).
    pub small_step: SmallMutation,
    /// Delayed-rejection MLT: the second-stage rule (default orbital).
    pub dr_variant: DrVariant,
    /// Delayed-rejection MLT: the path sampler (default PSSMLT).
    pub dr_on: DrBase,
    /// Langevin MLT (`mala*`, and `drmlt` with `cheap-then-expensive`): parameters, the
    /// depth rule, the finite-difference step (the variant comes from the integrator).
    pub mala: MalaConfig,
    /// Path-space MLT (`pathmlt`): the perturbation mixed with the bidirectional mutation
    /// (default lens).
    pub perturbation: pathspace::PerturbationKind,
    /// Path-space MLT: how the perturbation's scale is adapted (default fixed).
    pub adapt: crate::mlt::pathmlt::PathAdapt,
    /// PSSMLT and MMLT: combine the large-step samples with the Metropolis estimator by
    /// multiple importance sampling (Kelemen et al. 2002, section 4; LuxCore's METROPOLIS
    /// sampler; [`crate::mlt::MltEstimator::large_step_mis`]). `None` (default): the
    /// integrator's measured default, [`large_step_mis_default`] (on for PSSMLT, off for
    /// MMLT; docs/performance.md, "Equal-time efficiency (issue 17)"). Other integrators
    /// ignore it.
    pub large_step_mis: Option<bool>,
    /// PSSMLT and MMLT: raster (image-plane) mutation, LuxCore's image mutation read as a
    /// separate move ([`pss::RasterParams`], [`pss::RasterStep`]): with probability
    /// `raster.probability` a small step moves only the two raster numbers of the camera
    /// stream. `None` (default): the integrator's measured default,
    /// [`raster_mutation_default`] (docs/performance.md, "Raster mutation (issue 17, item
    /// 2)"). Other integrators ignore it.
    pub raster: Option<pss::RasterParams>,
    /// MMLT: how chains are spread over path depths (`--chain-allocation`;
    /// [`crate::mlt::MltEstimator::chain_allocation`]). Default: joint resampling (pbrt's
    /// scheme; docs/performance.md, "MMLT robustness (issue 17, item 3)"). Other integrators
    /// ignore it.
    pub mmlt_chain_allocation: mcmc_core::render_loop::ChainAllocation,
    /// MMLT: stratify the bootstrap over strategies (`--strategy-strata`;
    /// [`crate::mlt::MltEstimator::strategy_strata`]). Default off (docs/performance.md,
    /// "MMLT robustness (issue 17, item 3)"). Other integrators ignore it.
    pub mmlt_strategy_strata: bool,
    /// MMLT: estimate each depth's integral `b_d` from this many all-strategy BDPT samples
    /// (`--bdpt-normalization N`; [`crate::mlt::mmlt_depth_normalization`],
    /// [`crate::mlt::render_mlt_normalized`]) instead of from the bootstrap; 0 (default): the
    /// bootstrap's. Other integrators ignore it.
    pub mmlt_bdpt_normalization: u64,
    /// PSSMLT: a separate direct-lighting pass (`--direct-samples N`; [`crate::mlt::direct`],
    /// Mitsuba 0.6's `directSamples`): BDPT renders depths 0..=K (see `direct_depth`) at N
    /// samples per pixel and the chains only depths > K. `None` (default): the integrator's
    /// measured default, [`direct_pass_default`] (for PSSMLT a share of the budget balanced
    /// against the chains from a pilot, `--direct-share auto`). Other integrators ignore it.
    pub direct: Option<crate::mlt::direct::DirectPass>,
    /// PSSMLT: the direct pass's depth K (`--direct-depth K`, at least 1): the pass renders
    /// depths up to K, the chains the deeper ones; no pass if K >= the maximum depth.
    /// `None` (default): [`crate::mlt::direct::DIRECT_DEPTH_DEFAULT`] (2).
    pub direct_depth: Option<u32>,
}

impl Default for McmcSettings {
    fn default() -> Self {
        Self {
            large_step: LargeStepMode::Fixed(0.3),
            chains: 256,
            bootstrap_samples: 100_000,
            small_step: SmallMutation::Kelemen(KelemenParams::kelemen2002()),
            dr_variant: DrVariant::Orbital,
            dr_on: DrBase::Pssmlt,
            mala: MalaConfig::default(),
            perturbation: pathspace::PerturbationKind::Lens,
            adapt: crate::mlt::pathmlt::PathAdapt::Fixed,
            large_step_mis: None,
            raster: None,
            mmlt_chain_allocation: mcmc_core::render_loop::ChainAllocation::Joint,
            mmlt_strategy_strata: false,
            mmlt_bdpt_normalization: 0,
            direct: None,
            direct_depth: None,
        }
    }
}

/// Whether `integrator` combines its large steps with the Metropolis estimator by default
/// ([`McmcSettings::large_step_mis`]): on for PSSMLT, where it lowered the median equal-time
/// relMSE on three of four scenes (x0.66 cornell-glass, x0.77 glossy-highlight, x0.91
/// ajar-door, x1.00 caustic-pool); off for MMLT, where it won on two and lost on two (x0.94,
/// x0.91, x1.14, x1.07). docs/performance.md, "Equal-time efficiency (issue 17)".
#[must_use]
pub const fn large_step_mis_default(integrator: IntegratorKind) -> bool {
    matches!(integrator, IntegratorKind::Pssmlt)
}

/// The raster mutation `integrator` uses by default ([`McmcSettings::raster`]): for PSSMLT a
/// raster step in [`pss::RASTER_DEFAULT_PROBABILITY`] = 0.5 of the small steps, which lowered
/// the relMSE at equal mutations on all four scenes measured (x0.82 cornell-glass, x0.91
/// glossy-highlight, x0.66 caustic-pool, x0.82 ajar-door) at equal or lower CPU time per
/// mutation; off for MMLT (docs/performance.md, "Raster mutation (issue 17, item 2)").
#[must_use]
pub const fn raster_mutation_default(integrator: IntegratorKind) -> pss::RasterParams {
    if matches!(integrator, IntegratorKind::Pssmlt) {
        pss::RasterParams::with_probability(pss::RASTER_DEFAULT_PROBABILITY)
    } else {
        pss::RasterParams::off()
    }
}

/// The direct-lighting pass `integrator` uses by default ([`McmcSettings::direct`]): for
/// PSSMLT [`DirectPass::PSSMLT_DEFAULT`](crate::mlt::direct::DirectPass::PSSMLT_DEFAULT),
/// about what 64 BDPT samples per pixel were in the 10 s measurement that lowered the median
/// equal-time relMSE on two of three scenes and was even on the third (x0.53 cornell-glass,
/// x0.90 ajar-door, x0.90 caustic-pool with 1 of 3 seeds better; 128 x 128, max depth 10,
/// 2 threads), in proportion to the budget so longer renders do not hit the fixed pass's noise
/// floor; off for the others (docs/performance.md, "Direct-lighting pass (issue 17, item 2)").
/// Since the pass renders depths up to 2 by default ([`McmcSettings::direct_depth`]) its share
/// of the budget follows how much of the light those depths carry (about 25 % of a time budget
/// on cornell-glass, 10 % on ajar-door, 15 % on caustic-pool; "A deeper direct pass for
/// PSSMLT" and "Balancing the direct pass against the chains").
#[must_use]
pub const fn direct_pass_default(integrator: IntegratorKind) -> crate::mlt::direct::DirectPass {
    if matches!(integrator, IntegratorKind::Pssmlt) {
        crate::mlt::direct::DirectPass::PSSMLT_DEFAULT
    } else {
        crate::mlt::direct::DirectPass::Off
    }
}

/// The per-pixel sampler `integrator` uses by default ([`RenderSettings::sampler`]):
/// Owen-scrambled Sobol points for PT, which lowered its median equal-time relMSE on all three
/// measured scenes (x0.91 cornell-glass, x0.89 caustic-pool, x0.96 ajar-door; 10 s, 128 x 128,
/// 2 threads, 3 seeds), and for BDPT since its MIS weights keep the densities of delta-lobe
/// vertices (x0.98 cornell-glass, x0.93 caustic-pool, x0.97 ajar-door, the last two every
/// seed), and for PSSMLT's direct-lighting pass (x0.90 cornell-glass, x0.79 caustic-pool,
/// x0.91 ajar-door in PSSMLT's equal-time relMSE, 8 of 9 seeds better); independent numbers
/// for the others (docs/performance.md, "Owen-scrambled Sobol sampler for PT and BDPT",
/// "Specular chains in BDPT's MIS weights" and "Sobol points for PSSMLT's direct-lighting
/// pass", issue 17).
#[must_use]
pub const fn sampler_default(integrator: IntegratorKind) -> SamplerKind {
    if takes_sampler(integrator) {
        SamplerKind::Sobol
    } else {
        SamplerKind::Independent
    }
}

/// Russian roulette of the path tracers by default ([`RenderSettings::roulette`] `None`): for
/// `pt` from bounce 5 on (Mitsuba 3's `rr_depth`; at the usual max depth 5 no roulette at all),
/// which lowered PT's equal-time relMSE on all three measured scenes, every seed (x0.82
/// cornell-glass, x0.92 caustic-pool, x0.72 ajar-door; 10 s, 128 x 128, 2 threads, with the
/// Sobol sampler); `qmc` and `qmc-faure` keep pbrt-v4's [`crate::integrator::pt::ROULETTE_DEPTH`]
/// (3), as measured in their documentation (docs/performance.md, "PT Russian roulette").
#[must_use]
pub const fn pt_roulette_default(integrator: IntegratorKind) -> Option<u32> {
    if matches!(integrator, IntegratorKind::Pt) {
        Some(5)
    } else {
        Some(crate::integrator::pt::ROULETTE_DEPTH)
    }
}

/// Whether `integrator` takes a [`RenderSettings::sampler`] (PT and BDPT, and PSSMLT for its
/// direct-lighting pass; the Halton, other MCMC and LQMC integrators own their numbers).
#[must_use]
pub const fn takes_sampler(integrator: IntegratorKind) -> bool {
    matches!(
        integrator,
        IntegratorKind::Pt | IntegratorKind::Bdpt | IntegratorKind::Pssmlt
    )
}

/// The per-pixel sampler `settings` asks for: [`RenderSettings::sampler`], or
/// [`sampler_default`] of its integrator.
const fn sampler_of(settings: &RenderSettings) -> SamplerKind {
    match settings.sampler {
        Some(kind) => kind,
        None => sampler_default(settings.integrator),
    }
}

/// Default mutations per chain in the estimation phase of automatic large-step control.
pub const AUTO_LARGE_STEP_ESTIMATION: u64 = 1_000;

/// How long to render: defined in its own leaf module, shared with the drivers.
pub use crate::budget::Budget;

/// Everything a render needs besides the scene.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Image width in pixels (>= 1).
    pub width: u32,
    /// Image height in pixels (>= 1).
    pub height: u32,
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Sample or time budget.
    pub budget: Budget,
    /// Worker threads (>= 1). The image does not depend on it.
    pub threads: usize,
    /// Master seed; the same seed gives a bit-identical image under a sample budget.
    pub seed: u64,
    /// Maximum path depth (number of bounces).
    pub max_depth: u32,
    /// Settings of the MCMC integrators.
    pub mcmc: McmcSettings,
    /// BDPT only: also return the MIS-weighted image of every strategy `(s, t)`.
    pub strategy_images: bool,
    /// Russian roulette of the path tracers (`pt`, `qmc`, `qmc-faure`: pbrt-v4's rule,
    /// [`crate::integrator::pt::li_with`]), of BDPT and of the MCMC samplers whose subpaths use
    /// it (`bdpt`, `pssmlt`, `drmlt` over PSSMLT): `None` (default) keeps each one's default
    /// ([`pt_roulette_default`]: from bounce 5 for `pt`, 3 for `qmc`; from 3 bounces on for
    /// BDPT, [`BdptParams::default`]); MMLT-based samplers never use roulette (fixed path
    /// length).
    /// docs/performance.md, "Equal-time efficiency (issue 17)", has the measurements.
    pub roulette: Option<bdpt::Roulette>,
    /// PT and BDPT: the per-pixel sampler; PSSMLT: its direct-lighting pass's
    /// ([`McmcSettings::direct`]). `None` (default) is [`sampler_default`]. Other integrators
    /// reject `Some` ([`validate`]).
    pub sampler: Option<SamplerKind>,
}

impl Default for RenderSettings {
    /// 256 x 256, PT, 16 samples per pixel, 1 thread, seed 0, max depth 5.
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            integrator: IntegratorKind::Pt,
            budget: Budget::SamplesPerPixel(16),
            threads: 1,
            seed: 0,
            max_depth: 5,
            mcmc: McmcSettings::default(),
            strategy_images: false,
            roulette: None,
            sampler: None,
        }
    }
}

/// Progress reports of a running render: mcmc-core's trait (one copy across the crates).
pub use mcmc_core::{NoProgress, Progress};

/// The result of a render.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The rendered (possibly partial, if cancelled) image.
    pub image: Image,
    /// Number of samples (or mutations) evaluated.
    pub samples: u64,
    /// Samples whose radiance was NaN or infinite; they were dropped, not splatted.
    pub dropped_nonfinite: u64,
    /// True if the render stopped early because `cancel` was set.
    pub cancelled: bool,
    /// Wall-clock time spent.
    pub elapsed: Duration,
    /// Human-readable notes about the run (e.g. the bootstrap's `b`, the automatic
    /// large-step statistics, or why an image is black).
    pub notes: Vec<String>,
    /// BDPT with `strategy_images`: the MIS-weighted image of each strategy `(s, t)`.
    pub strategy_images: Vec<((u8, u8), Image)>,
    /// Delayed-rejection MLT: the stage map, per pixel the share of the estimate contributed
    /// by second-stage candidates (`render::mlt::StagedSplats`; paper Fig. 1 and 9).
    pub stage_map: Option<Image>,
}

/// Edge length of PT's square tiles: defined with the PT driver.
pub use crate::integrator::pt_driver::TILE_SIZE;

/// Largest accepted image side.
pub const MAX_RESOLUTION: u32 = 1 << 16;

/// Largest accepted thread count.
pub const MAX_THREADS: usize = 1024;

/// Largest accepted path depth.
pub const MAX_DEPTH: u32 = 1 << 16;

/// Checks every setting against its allowed range.
///
/// # Errors
/// [`RenderError::InvalidSetting`] naming the first offending setting (by its CLI flag name)
/// and the allowed range.
pub fn validate(settings: &RenderSettings) -> Result<(), RenderError> {
    if !(1..=MAX_RESOLUTION).contains(&settings.width) {
        return Err(RenderError::setting("width", settings.width, "1..=65536"));
    }
    if !(1..=MAX_RESOLUTION).contains(&settings.height) {
        return Err(RenderError::setting("height", settings.height, "1..=65536"));
    }
    if u64::from(settings.width) * u64::from(settings.height) > 1 << 28 {
        return Err(RenderError::setting(
            "width",
            format!("{}x{}", settings.width, settings.height),
            "width * height <= 268435456 pixels",
        ));
    }
    if !(1..=MAX_THREADS).contains(&settings.threads) {
        return Err(RenderError::setting(
            "threads",
            settings.threads,
            "1..=1024",
        ));
    }
    if settings.max_depth > MAX_DEPTH {
        return Err(RenderError::setting(
            "max-depth",
            settings.max_depth,
            "0..=65536",
        ));
    }
    if let Some(kind) = settings.sampler {
        if !takes_sampler(settings.integrator) {
            return Err(RenderError::setting(
                "sampler",
                kind,
                "independent or sobol with --integrator pt, bdpt or pssmlt only",
            ));
        }
    }
    match settings.budget {
        Budget::SamplesPerPixel(0) => Err(RenderError::setting("spp", 0, ">= 1")),
        Budget::Time(d) if d.is_zero() => Err(RenderError::setting(
            "time",
            format!("{}s", d.as_secs_f64()),
            "> 0 seconds",
        )),
        _ => Ok(()),
    }
}

/// Renders `scene` with `settings` on a pool of `settings.threads` rayon threads: validates
/// the settings and dispatches to the integrator's driver (PT:
/// [`render_pt`](crate::integrator::pt_driver::render_pt), BDPT:
/// [`render_bdpt`](crate::bdpt::render_bdpt), PSSMLT and MMLT: the MCMC render loop).
///
/// Under [`Budget::SamplesPerPixel`] the image is bit-identical for any thread count. Setting
/// `cancel` stops the render within a fraction of a second (PT and BDPT check it between two
/// samples of a work unit) and returns the samples taken so far, each pixel normalised by
/// its own samples, with `cancelled: true`.
///
/// # Errors
/// [`RenderError::InvalidSetting`] for out-of-range settings, [`RenderError::ThreadPool`] if
/// the threads cannot be started, [`RenderError::UnsupportedIntegrator`] for integrators this
/// function does not run.
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<RenderOutput, RenderError> {
    let start = Instant::now();
    validate(settings)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| RenderError::ThreadPool {
            threads: settings.threads,
            reason: e.to_string(),
        })?;
    match settings.integrator {
        IntegratorKind::Pt | IntegratorKind::Qmc | IntegratorKind::QmcFaure => {
            Ok(pool.install(|| render_pt(scene, settings, start, progress, cancel)))
        }
        IntegratorKind::Lqmc => Ok(pool.install(|| {
            crate::integrator::lqmc::render_session(scene, settings, start, progress, cancel)
        })),
        IntegratorKind::Bdpt
        | IntegratorKind::Pssmlt
        | IntegratorKind::Mmlt
        | IntegratorKind::Drmlt
        | IntegratorKind::Mala
        | IntegratorKind::MalaOnline
        | IntegratorKind::MalaCache
        | IntegratorKind::MalaHybrid
        | IntegratorKind::PathMlt => {
            // BDPT and the MCMC targets use the scene's camera: set it to the image size.
            let mut sized;
            let scene = if (scene.camera().width(), scene.camera().height())
                == (settings.width, settings.height)
            {
                scene
            } else {
                sized = scene.clone();
                sized.set_resolution(settings.width, settings.height);
                &sized
            };
            pool.install(|| match settings.integrator {
                IntegratorKind::Bdpt => Ok(render_bdpt(scene, settings, start, progress, cancel)),
                IntegratorKind::PathMlt => {
                    mlt::pathmlt::render_session(scene, settings, start, progress, cancel)
                }
                _ => Ok(render_bidirectional(
                    scene, settings, start, progress, cancel,
                )),
            })
        }
    }
}

/// The scene's notes (e.g. the default environment), and one if it has no light at all.
fn emitter_notes(scene: &Scene) -> Vec<String> {
    let mut notes = scene.notes.clone();
    if scene.lights().is_empty() {
        notes.push("the scene has no light (and no environment): the image is black".to_owned());
    }
    notes
}

/// BDPT's parameters (shared by BDPT and the MCMC path samplers) for `settings`.
fn bdpt_params(settings: &RenderSettings) -> BdptParams {
    let defaults = BdptParams::default();
    BdptParams {
        max_depth: settings.max_depth,
        roulette: settings.roulette.unwrap_or(defaults.roulette),
        ..defaults
    }
}

/// PT and Halton QMC through the PT driver.
fn render_pt(
    scene: &Scene,
    settings: &RenderSettings,
    start: Instant,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> RenderOutput {
    let pt_settings = PtSettings {
        width: settings.width,
        height: settings.height,
        max_depth: settings.max_depth,
        budget: settings.budget,
        seed: settings.seed,
        sampler: sampler_of(settings),
        roulette: settings
            .roulette
            .map_or(pt_roulette_default(settings.integrator), |r| r.start),
    };
    let out = if settings.integrator == IntegratorKind::Qmc {
        crate::integrator::qmc::render_qmc(scene, &pt_settings, progress, cancel)
    } else if settings.integrator == IntegratorKind::QmcFaure {
        crate::integrator::qmc::render_qmc_with(
            scene,
            &pt_settings,
            lqmc::Scrambling::Faure,
            progress,
            cancel,
        )
    } else {
        pt_driver::render_pt(scene, &pt_settings, progress, cancel)
    };
    RenderOutput {
        image: out.image,
        samples: out.samples,
        dropped_nonfinite: out.dropped_nonfinite,
        cancelled: out.cancelled,
        elapsed: start.elapsed(),
        notes: emitter_notes(scene),
        strategy_images: Vec::new(),
        stage_map: None,
    }
}

/// BDPT through its driver (`scene` already at the image size).
fn render_bdpt(
    scene: &Scene,
    settings: &RenderSettings,
    start: Instant,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> RenderOutput {
    let params = bdpt_params(settings);
    let (spp, time) = match settings.budget {
        Budget::SamplesPerPixel(n) => (Some(n), None),
        Budget::Time(t) => (None, Some(t)),
    };
    let out = bdpt::render_bdpt_sampled(
        scene,
        &params,
        sampler_of(settings),
        spp,
        time,
        settings.seed,
        settings.strategy_images,
        progress,
        cancel,
    );
    RenderOutput {
        samples: out.samples,
        image: out.image,
        dropped_nonfinite: out.dropped,
        cancelled: out.cancelled,
        elapsed: start.elapsed(),
        notes: emitter_notes(scene),
        strategy_images: out.strategy_images,
        stage_map: None,
    }
}

/// The most all-strategy samples a balanced direct pass's pilot may take: under a mutation
/// budget an eighth of the mutations (at least 1024), so a tiny render is not dominated by
/// its pilot; under a time budget [`mlt::direct::BALANCE_SAMPLES`].
fn pilot_cap(settings: &RenderSettings) -> u64 {
    match settings.budget {
        Budget::SamplesPerPixel(n) => {
            let mutations = u64::from(n) * u64::from(settings.width) * u64::from(settings.height);
            (mutations / 8).max(1024)
        }
        Budget::Time(_) => mlt::direct::BALANCE_SAMPLES,
    }
}

/// PSSMLT and MMLT.
fn render_bidirectional(
    scene: &Scene,
    settings: &RenderSettings,
    start: Instant,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> RenderOutput {
    let params = bdpt_params(settings);
    let (w, h) = (settings.width, settings.height);
    let mut notes = emitter_notes(scene);
    let m = &settings.mcmc;
    let mlt_settings = MltSettings {
        width: w as usize,
        height: h as usize,
        chains: m.chains,
        bootstrap_samples: m.bootstrap_samples,
        budget: match settings.budget {
            Budget::SamplesPerPixel(n) => MltBudget::MutationsPerPixel(f64::from(n)),
            Budget::Time(t) => MltBudget::Time(t),
        },
        large_step: m.large_step,
        seed: settings.seed,
        streams: PATH_STREAMS,
        stage_map: settings.integrator == IntegratorKind::Drmlt,
    };
    let small = SmallStep::new(m.small_step);
    let raster_params = m
        .raster
        .unwrap_or(raster_mutation_default(settings.integrator));
    let raster = pss::RasterStep::for_image(&raster_params, w, h, m.small_step);
    let raster_probability = if raster_params.is_off() {
        0.0
    } else {
        raster_params.probability.min(1.0)
    };
    let kernel = |p: f64| {
        Mh::new(
            PssmltProposal::new(small, p.clamp(0.0, 1.0))
                .and_then(|k| k.with_raster(raster, raster_probability))
                .unwrap_or_else(|_| unreachable!("clamped")),
        )
    };
    // PSSMLT's separate direct-lighting pass (`mlt::direct`), rendered first; under a time
    // budget the chains get what is left.
    let direct_pass = m.direct.unwrap_or(direct_pass_default(settings.integrator));
    let pass_depth = m
        .direct_depth
        .unwrap_or(mlt::direct::DIRECT_DEPTH_DEFAULT)
        .max(1);
    let direct = (settings.integrator == IntegratorKind::Pssmlt
        && direct_pass.applies_to(settings.max_depth, pass_depth))
    .then(|| {
        let t0 = Instant::now();
        // A balanced pass takes its share from a pilot's estimate of how the light divides.
        let direct_pass = if let mlt::direct::DirectPass::Balanced { .. } = direct_pass {
            let pilot = mlt::direct::BALANCE_SAMPLES.min(pilot_cap(settings));
            let phi = mlt::direct::pilot_light_share(
                scene,
                &params,
                w,
                h,
                pass_depth,
                pilot,
                settings.seed,
                cancel,
            );
            let resolved = direct_pass.resolve(phi.unwrap_or(f64::NAN));
            if let mlt::direct::DirectPass::Proportional { time_share, .. } = resolved {
                notes.push(match phi {
                    Some(phi) => format!(
                        "direct-lighting pass balanced against the chains: depths 0-{pass_depth} carry {:.0} % of the light ({pilot} BDPT samples, {:.2} s) -> {:.0} % of the budget",
                        phi * 100.0,
                        t0.elapsed().as_secs_f64(),
                        time_share * 100.0
                    ),
                    None if cancel.load(std::sync::atomic::Ordering::Relaxed) => {
                        "cancelled during the direct-lighting pass's pilot".to_owned()
                    }
                    None => format!(
                        "direct-lighting pass: the pilot found no light ({pilot} BDPT samples); {:.0} % of the budget",
                        time_share * 100.0
                    ),
                });
            }
            resolved
        } else {
            direct_pass
        };
        let budget = match settings.budget {
            Budget::SamplesPerPixel(n) => direct_pass.budget(Some(f64::from(n)), None),
            // The pilot's time is the pass's.
            Budget::Time(t) => match direct_pass.budget(None, Some(t)) {
                (spp, Some(share)) => (
                    spp,
                    Some(
                        share
                            .saturating_sub(t0.elapsed())
                            .max(Duration::from_millis(1)),
                    ),
                ),
                other => other,
            },
        };
        let pass = mlt::direct::render_direct(
            scene,
            &params,
            pass_depth,
            sampler_of(settings),
            budget,
            settings.seed,
            progress,
            cancel,
        );
        notes.push(format!(
            "direct-lighting pass: depths 0-{} by BDPT at {} spp ({:.2} s); the chains sample depths >= {}",
            pass_depth,
            pass.spp,
            t0.elapsed().as_secs_f64(),
            pass_depth + 1
        ));
        (pass, t0.elapsed())
    });
    let min_depth = if direct.is_some() {
        direct_pass.chain_min_depth(settings.max_depth, pass_depth)
    } else {
        0
    };
    let mut mlt_settings = mlt_settings;
    if let (Some((_, spent)), MltBudget::Time(t)) = (&direct, mlt_settings.budget) {
        mlt_settings.budget =
            MltBudget::Time(t.saturating_sub(*spent).max(Duration::from_millis(1)));
    }
    let out = if let Some(variant) = settings.integrator.mala_variant() {
        let config = MalaConfig { variant, ..m.mala };
        notes.push(mala_note(&config));
        mala::render(
            scene,
            params,
            &config,
            false,
            &mlt_settings,
            m.small_step,
            progress,
            cancel,
        )
    } else if settings.integrator == IntegratorKind::Drmlt
        && m.dr_variant == DrVariant::CheapThenExpensive
    {
        notes.push(format!(
            "delayed rejection: cheap-then-expensive (Gaussian sigma {} then MALA, Green-Mira) on MMLT{}; {}",
            m.mala.cheap_sigma,
            if m.dr_on == DrBase::Pssmlt { " (it needs one strategy per sample: --dr-on pssmlt is ignored)" } else { "" },
            mala_note(&m.mala)
        ));
        mala::render(
            scene,
            params,
            &m.mala,
            true,
            &mlt_settings,
            m.small_step,
            progress,
            cancel,
        )
    } else if settings.integrator == IntegratorKind::Drmlt {
        let layout = dr::dr_layout(settings.max_depth);
        let base = m.dr_on;
        notes.push(format!(
            "delayed rejection: {} second stage on {}",
            m.dr_variant.name(),
            match base {
                DrBase::Pssmlt => "PSSMLT",
                DrBase::Mmlt => "MMLT (camera subpath only)",
            }
        ));
        match base {
            DrBase::Mmlt => {
                let targets = MmltTarget::all_depths(scene, params, w, h);
                render_dr(
                    &targets,
                    m.dr_variant,
                    layout,
                    base,
                    &mlt_settings,
                    progress,
                    cancel,
                )
            }
            DrBase::Pssmlt => {
                let targets = [PssmltTarget::new(scene, params, w, h)];
                render_dr(
                    &targets,
                    m.dr_variant,
                    layout,
                    base,
                    &mlt_settings,
                    progress,
                    cancel,
                )
            }
        }
    } else {
        let large_step_mis = m
            .large_step_mis
            .unwrap_or(large_step_mis_default(settings.integrator));
        let mmlt = settings.integrator == IntegratorKind::Mmlt;
        let estimator = mlt::MltEstimator {
            large_step_mis,
            chain_allocation: if mmlt {
                m.mmlt_chain_allocation
            } else {
                mcmc_core::render_loop::ChainAllocation::Joint
            },
            strategy_strata: mmlt && m.mmlt_strategy_strata,
        };
        if large_step_mis {
            notes.push(
                "large-step MIS (Kelemen et al. 2002, section 4): large steps also weighted as independent samples"
                    .to_owned(),
            );
        }
        if raster_probability > 0.0 {
            notes.push(format!(
                "raster mutation: {raster_probability} of the small steps move only the raster position ({} px to {} of the image; LuxCore's image mutation)",
                raster_params.min_pixels, raster_params.max_fraction
            ));
        }
        let normalization = if mmlt && m.mmlt_bdpt_normalization > 0 {
            let t0 = Instant::now();
            let nb = mlt::mmlt_depth_normalization(
                scene,
                params,
                w,
                h,
                m.mmlt_bdpt_normalization,
                settings.seed,
                cancel,
            );
            if let Some(nb) = &nb {
                notes.push(format!(
                    "MMLT depth normalisation from {} all-strategy BDPT samples ({:.2} s): b = {:.6}",
                    m.mmlt_bdpt_normalization,
                    t0.elapsed().as_secs_f64(),
                    nb.iter().sum::<f64>()
                ));
            }
            nb.map(|nb| (nb, t0.elapsed()))
        } else {
            None
        };
        if let Some((nb, spent)) = normalization {
            let targets = MmltTarget::all_depths(scene, params, w, h);
            let mut budgeted = mlt_settings;
            if let MltBudget::Time(t) = budgeted.budget {
                budgeted.budget =
                    MltBudget::Time(t.saturating_sub(spent).max(Duration::from_millis(1)));
            }
            mlt::render_mlt_normalized(
                &targets, kernel, &budgeted, estimator, &nb, progress, cancel,
            )
        } else if settings.integrator == IntegratorKind::Mmlt {
            let targets = MmltTarget::all_depths(scene, params, w, h);
            mlt::render_mlt_with_estimator(
                &targets,
                kernel,
                &mlt_settings,
                estimator,
                progress,
                cancel,
            )
        } else {
            let targets = [PssmltTarget::new(scene, params, w, h).with_min_depth(min_depth)];
            mlt::render_mlt_with_estimator(
                &targets,
                kernel,
                &mlt_settings,
                estimator,
                progress,
                cancel,
            )
        }
    };
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
    if let Some(e) = out.large_step {
        notes.push(format!(
            "automatic large-step control: eta_s = {:.4}, eta_l = {:.4}, eta_0 = {:.4} ({} small, {} large steps) -> p_large = {:.4}",
            e.eta_s, e.eta_l, e.eta_0, e.small_steps, e.large_steps, e.large_step_probability
        ));
    }
    let mut image = out.image;
    let (mut dropped, mut cancelled) = (out.dropped + out.non_finite, out.cancelled);
    if let Some((pass, _)) = &direct {
        if out.mutations == 0 {
            notes.push(format!(
                "cancelled before the chains ran: the image holds only the direct-lighting pass (path depths 0-{pass_depth})"
            ));
        }
        mlt::direct::add_into(&mut image, &pass.image);
        dropped += pass.dropped;
        cancelled |= pass.cancelled;
    }
    RenderOutput {
        image,
        samples: out.mutations,
        dropped_nonfinite: dropped,
        cancelled,
        elapsed: start.elapsed(),
        notes,
        strategy_images: Vec::new(),
        stage_map: out.stage_map,
    }
}

/// Renders the built-in Cornell box at `size x size` with `spp` samples per pixel on one
/// thread: a convenience for examples and doc tests.
///
/// # Errors
/// As [`render`].
pub fn render_cornell_box(size: u32, spp: u32, seed: u64) -> Result<Image, RenderError> {
    let scene = Scene::cornell_box(size, size);
    let settings = RenderSettings {
        width: size,
        height: size,
        integrator: IntegratorKind::Pt,
        budget: Budget::SamplesPerPixel(spp),
        threads: 1,
        seed,
        max_depth: 5,
        ..RenderSettings::default()
    };
    Ok(render(&scene, &settings, &NoProgress, &AtomicBool::new(false))?.image)
}

/// One line on the Langevin settings for the render notes.
fn mala_note(config: &MalaConfig) -> String {
    format!(
        "Langevin MLT: {} (epsilon {}, truncation {}), MALA on MMLT depths <= {} and Kelemen beyond; gradients by central finite differences (h = {:e})",
        config.variant.name(),
        config.params.epsilon,
        config.params.max_gradient,
        config.max_depth,
        config.fd_step
    )
}

/// Delayed-rejection MLT over `targets` with the kernel of `variant` (`mlt::dr`).
fn render_dr<T>(
    targets: &[T],
    variant: DrVariant,
    layout: pss::PairLayout,
    base: DrBase,
    mlt_settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> mlt::MltOutput
where
    T: mcmc_core::Target<State = pss::PssState>,
    T::Payload: mcmc_core::render_loop::SplatPayload,
{
    match variant {
        DrVariant::Orbital => mlt::render_mlt(
            targets,
            mlt::PerChain(|slot: ChainSlot, p| {
                dr::orbital_kernel(layout, base, p, slot.target as u32)
            }),
            mlt_settings,
            progress,
            cancel,
        ),
        DrVariant::TierneyMira => mlt::render_mlt(
            targets,
            mlt::PerChain(|slot: ChainSlot, p| {
                dr::tierney_mira_kernel(layout, base, p, slot.target as u32)
            }),
            mlt_settings,
            progress,
            cancel,
        ),
        DrVariant::GreenMira => mlt::render_mlt(
            targets,
            mlt::PerChain(|slot: ChainSlot, p| {
                dr::green_mira_kernel(layout, base, p, slot.target as u32)
            }),
            mlt_settings,
            progress,
            cancel,
        ),
        DrVariant::CheapThenExpensive => {
            unreachable!("cheap-then-expensive is dispatched to render_langevin")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::Ordering;

    fn settings() -> RenderSettings {
        RenderSettings {
            width: 8,
            height: 8,
            integrator: IntegratorKind::Pt,
            budget: Budget::SamplesPerPixel(2),
            threads: 1,
            seed: 0,
            max_depth: 3,
            ..RenderSettings::default()
        }
    }

    #[test]
    fn settings_are_validated() {
        let scene = Scene::cornell_box(8, 8);
        let no = AtomicBool::new(false);
        type Edit = fn(&mut RenderSettings);
        let cases: [(Edit, &str); 5] = [
            (|s| s.width = 0, "width"),
            (|s| s.height = 70_000, "height"),
            (|s| s.threads = 0, "threads"),
            (|s| s.budget = Budget::SamplesPerPixel(0), "spp"),
            (|s| s.budget = Budget::Time(Duration::ZERO), "time"),
        ];
        for (edit, field) in cases {
            let mut s = settings();
            edit(&mut s);
            let err = render(&scene, &s, &NoProgress, &no).unwrap_err();
            assert!(
                matches!(err, RenderError::InvalidSetting { field: f, .. } if f == field),
                "{err}"
            );
        }
    }

    #[test]
    fn cancel_mid_render_returns_the_partial_image() {
        let scene = Scene::cornell_box(48, 48);
        let mut s = settings();
        (s.width, s.height, s.threads) = (48, 48, 2);
        s.budget = Budget::SamplesPerPixel(64);
        let full = render(&scene, &s, &NoProgress, &AtomicBool::new(false)).unwrap();
        let flag = AtomicBool::new(false);
        let progress = crate::test_util::CancelAfter::new(&flag, 12);
        let out = render(&scene, &s, &progress, &flag).unwrap();
        assert!(out.cancelled);
        assert!(
            out.samples > 0 && out.samples < full.samples,
            "{}",
            out.samples
        );
        // Every pixel is normalised by its own samples: the partial image has the full
        // image's brightness where it was rendered (loosely: fewer samples, more noise).
        let lit = out.image.pixels.iter().filter(|p| p[0] > 0.0).count();
        assert!(lit > 0);
        let partial_mean: f64 = out
            .image
            .pixels
            .iter()
            .map(|p| f64::from(p[0]))
            .sum::<f64>()
            / lit as f64;
        let full_lit: Vec<f64> = full
            .image
            .pixels
            .iter()
            .zip(&out.image.pixels)
            .filter(|(_, q)| q[0] > 0.0)
            .map(|(p, _)| f64::from(p[0]))
            .collect();
        let full_mean = full_lit.iter().sum::<f64>() / full_lit.len() as f64;
        assert!(
            (partial_mean - full_mean).abs() < 0.25 * full_mean,
            "{partial_mean} vs {full_mean}"
        );
        assert_eq!(out.image.count_nonfinite(), 0);
    }

    #[test]
    fn cancelled_before_start_gives_black_cancelled_image() {
        let scene = Scene::cornell_box(8, 8);
        let out = render(&scene, &settings(), &NoProgress, &AtomicBool::new(true)).unwrap();
        assert!(out.cancelled);
        assert_eq!(out.samples, 0);
        assert_eq!(out.image.mean(), [0.0; 3]);
    }

    #[test]
    fn time_budget_renders_at_least_one_pass() {
        let scene = Scene::cornell_box(8, 8);
        let mut s = settings();
        s.budget = Budget::Time(Duration::from_millis(1));
        let out = render(&scene, &s, &NoProgress, &AtomicBool::new(false)).unwrap();
        assert!(out.samples >= 64);
        assert!(!out.cancelled);
    }

    #[test]
    fn progress_reaches_total() {
        use std::sync::atomic::AtomicU64;
        #[derive(Default)]
        struct Count(AtomicU64, AtomicU64);
        impl Progress for Count {
            fn set_total(&self, total: u64) {
                self.0.store(total, Ordering::Relaxed);
            }
            fn advance(&self, done: u64) {
                self.1.fetch_add(done, Ordering::Relaxed);
            }
        }
        let scene = Scene::cornell_box(20, 20);
        let mut s = settings();
        s.width = 20;
        s.height = 20;
        let c = Count::default();
        let out = render(&scene, &s, &c, &AtomicBool::new(false)).unwrap();
        assert_eq!(c.0.load(Ordering::Relaxed), 800);
        assert_eq!(c.1.load(Ordering::Relaxed), 800);
        assert_eq!(out.samples, 800);
    }
}
