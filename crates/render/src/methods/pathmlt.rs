//! `pathmlt`: path-space MLT (Veach & Guibas 1997) over `pathspace`: a lens or multi-chain
//! perturbation mixed with the bidirectional mutation, with the perturbation's scale fixed or
//! adapted per region (Otsu et al. 2018; [`crate::mlt::pathmlt`]).

use mcmc_core::render_loop::NormalizationMode;
use pathspace::regional::RegionalUpdateRule;
use pathspace::PerturbationKind;

use super::{
    emitter_notes, mcmc_output, mlt_budget, validate_normalization, IntegratorKind, Method,
    RenderOutput, RenderSettings, Run, MAX_BOOTSTRAP_SAMPLES, MAX_CHAINS,
};
use crate::error::RenderError;
use crate::mlt::pathmlt::{
    adapt_params, render_scaled, AdaptRender, PathAdapt, ADAPT_ROUND_MUTATIONS,
    PATHMLT_PAPER_SIGMA, PATHMLT_SIGMA,
};
use crate::mlt::{LargeStepMode, MltSettings};
use crate::scene::Scene;

/// `pathmlt`'s settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathMltSettings {
    /// Number of Markov chains (default 256; 1..=1 000 000).
    pub chains: usize,
    /// Independent paths in the bootstrap (default 100 000; 1..=100 000 000).
    pub bootstrap_samples: usize,
    /// The perturbation mixed with the bidirectional mutation, 0.5 each (default lens).
    pub perturbation: PerturbationKind,
    /// How the perturbation's angular scale is adapted (default fixed).
    pub adapt: PathAdapt,
    /// FIXED's angular scale and the adaptive variants' start (radians, the standard
    /// deviation of the perturbation's truncated-normal polar angle): [`PATHMLT_PAPER_SIGMA`]
    /// (`lambda = 1`, the paper's FIXED, section 8.1) in the `otsu2018` preset,
    /// [`PATHMLT_SIGMA`] (0.02 rad, "tuned FIXED") by default. `(0, pi]`.
    pub sigma: f64,
    /// The target acceptance `alpha*` of the adaptive variants (the paper's 0.5; 0.8 for its
    /// Necklace scene, section 8.1). `(0, 1)`.
    pub target_acceptance: f64,
    /// Mutations per chain between synchronisation points of the adaptive variants
    /// ([`ADAPT_ROUND_MUTATIONS`]; 1..=1000000).
    pub round_mutations: u64,
    /// When the adaptive variants' sign steps happen (the paper's one per `L` visits by
    /// default; `OncePerRound` is the slower rule kept for comparison).
    pub update_rule: RegionalUpdateRule,
    /// RA-QUADTREE: `M_split` instead of the scheduled one (`None`: the schedule's).
    pub split_after_visits: Option<u64>,
    /// How the image's normalisation `b` is estimated (as [`super::ChainSettings`]'s; path-space
    /// MLT makes no large steps, so the default is the bootstrap's estimate), or a given `b`.
    pub normalization: NormalizationMode,
}

/// chainlight's default: the `otsu2018` preset with the lens perturbation, FIXED, at the tuned
/// scale [`PATHMLT_SIGMA`].
impl Default for PathMltSettings {
    fn default() -> Self {
        Self {
            sigma: PATHMLT_SIGMA,
            ..Self::otsu2018(PerturbationKind::Lens, PathAdapt::Fixed)
        }
    }
}

impl PathMltSettings {
    /// Otsu et al. 2018, section 8.1: the perturbation (`Lens`: the 2-D partition of the
    /// primary ray's raster position; `MultiChain`: the 4-D partition) and the bidirectional
    /// mutation, 0.5 each, with scale adaptation `adapt` (FIXED, GLOBAL, RA-GRID,
    /// RA-QUADTREE) from the paper's `lambda = 1` ([`PATHMLT_PAPER_SIGMA`], also FIXED's
    /// scale) toward acceptance 0.5, one sign step per `L` visits, `M_split`, `M_refine` from
    /// the pixel count (docs/methods/regional-adaptive.md lists the readings).
    #[must_use]
    pub const fn otsu2018(perturbation: PerturbationKind, adapt: PathAdapt) -> Self {
        Self {
            chains: 256,
            bootstrap_samples: 100_000,
            perturbation,
            adapt,
            sigma: PATHMLT_PAPER_SIGMA,
            target_acceptance: 0.5,
            round_mutations: ADAPT_ROUND_MUTATIONS,
            update_rule: RegionalUpdateRule::EveryLVisits,
            split_after_visits: None,
            normalization: NormalizationMode::Pooled,
        }
    }

    /// [`Self::otsu2018`] at target acceptance 0.8, as the paper's Necklace scene (glossy
    /// and diffuse surfaces, section 8.1).
    #[must_use]
    pub const fn otsu2018_necklace(perturbation: PerturbationKind, adapt: PathAdapt) -> Self {
        let mut s = Self::otsu2018(perturbation, adapt);
        s.target_acceptance = 0.8;
        s
    }

    /// [`Self::otsu2018`] at the tuned scale [`PATHMLT_SIGMA`] ("tuned FIXED", and the
    /// adaptive variants started there).
    #[must_use]
    pub const fn tuned(perturbation: PerturbationKind, adapt: PathAdapt) -> Self {
        let mut s = Self::otsu2018(perturbation, adapt);
        s.sigma = PATHMLT_SIGMA;
        s
    }
}

/// The refusal of a render whose bootstrap found no light-carrying path: its independent
/// sampler reaches every path a bidirectional path tracer reaches, so either the scene sends
/// no light to the camera within `--max-depth` or the light is too rare for the bootstrap;
/// either way a black image would not be an answer.
fn nothing_found(message: &str, max_depth: u32) -> RenderError {
    RenderError::Unrenderable {
        integrator: "pathmlt",
        reason: format!(
            "{message} (bidirectional paths of at most {} edges); raise \
             --bootstrap-samples or --max-depth, check that a light can reach the camera, or \
             render with --integrator bdpt",
            u64::from(max_depth) + 1
        ),
    }
}

impl Method for PathMltSettings {
    fn kind(&self) -> IntegratorKind {
        IntegratorKind::PathMlt
    }

    fn validate(&self, _common: &RenderSettings) -> Result<(), RenderError> {
        if !(1..=MAX_CHAINS).contains(&self.chains) {
            return Err(RenderError::setting("chains", self.chains, "1..=1000000"));
        }
        if !(1..=MAX_BOOTSTRAP_SAMPLES).contains(&self.bootstrap_samples) {
            return Err(RenderError::setting(
                "bootstrap-samples",
                self.bootstrap_samples,
                "1..=100000000",
            ));
        }
        if self.split_after_visits == Some(0) {
            return Err(RenderError::setting("split-after-visits", 0, ">= 1"));
        }
        if !(self.sigma > 0.0 && self.sigma <= std::f64::consts::PI) {
            return Err(RenderError::setting(
                "sigma",
                self.sigma,
                "(0, pi] radians, or paper|tuned",
            ));
        }
        if !(self.target_acceptance > 0.0 && self.target_acceptance < 1.0) {
            return Err(RenderError::setting(
                "target-acceptance",
                self.target_acceptance,
                "(0, 1)",
            ));
        }
        if !(1..=1_000_000).contains(&self.round_mutations) {
            return Err(RenderError::setting(
                "round-mutations",
                self.round_mutations,
                "1..=1000000",
            ));
        }
        validate_normalization(self.normalization)
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let mlt_settings = MltSettings {
            width: common.width as usize,
            height: common.height as usize,
            chains: self.chains,
            bootstrap_samples: self.bootstrap_samples,
            budget: mlt_budget(common.budget),
            large_step: LargeStepMode::Fixed(0.0),
            seed: common.seed,
            streams: 1,
            stage_map: false,
            shard: run.shard,
            normalization: self.normalization,
        };
        let mut params = adapt_params(self.adapt, self.perturbation, self.sigma, &mlt_settings);
        params.adapt.target_acceptance = self.target_acceptance;
        params.update_rule = self.update_rule;
        if self.adapt == PathAdapt::Quadtree {
            if let Some(m) = self.split_after_visits {
                params.split_after_visits = Some(m);
            }
        }
        let run_settings = AdaptRender {
            kind: self.perturbation,
            adapt: self.adapt,
            sigma: self.sigma,
            round_mutations: self.round_mutations,
            max_depth: common.max_depth,
            params,
        };
        let (out, sigma_map, summary) = render_scaled(
            scene,
            &run_settings,
            &mlt_settings,
            run.progress,
            run.cancel,
        )?;
        if let Some(message) = &out.message {
            return Err(nothing_found(message, common.max_depth));
        }
        let mut notes = emitter_notes(scene);
        notes.push(format!(
            "path-space MLT: {} perturbation (sigma {}) and the bidirectional mutation, 0.5 each; no large steps",
            match self.perturbation {
                PerturbationKind::Lens => "lens",
                PerturbationKind::MultiChain => "multi-chain",
            },
            match self.adapt {
                PathAdapt::Fixed => format!("{:.4} rad, fixed", self.sigma),
                a => format!(
                    "from {:.4} rad, adapted per region toward acceptance {}: --adapt {}",
                    self.sigma,
                    self.target_acceptance,
                    a.name()
                ),
            }
        ));
        let mut output = mcmc_output(out, notes, run.start.elapsed());
        if let Some(mcmc) = output.mcmc.as_mut() {
            mcmc.regional_adapt = summary;
        }
        output.sigma_map = sigma_map;
        Ok(output)
    }
}
