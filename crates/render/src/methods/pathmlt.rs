//! `pathmlt`: path-space MLT (Veach & Guibas 1997) over `pathspace`: a lens or multi-chain
//! perturbation mixed with the bidirectional mutation, with the perturbation's scale fixed or
//! adapted per region (Otsu et al. 2018; [`crate::mlt::pathmlt`]).

use mcmc_core::render_loop::NormalizationMode;
use pathspace::regional::RegionalAdaptParams;
use pathspace::PerturbationKind;

use super::{
    emitter_notes, mcmc_output, mlt_budget, validate_normalization, IntegratorKind, Method,
    RenderOutput, RenderSettings, Run, MAX_BOOTSTRAP_SAMPLES, MAX_CHAINS,
};
use crate::error::RenderError;
use crate::mlt::pathmlt::{adapt_params, render_adaptive_with_params, PathAdapt, PATHMLT_SIGMA};
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
    /// RA-QUADTREE: scale `M_refine` and `M_split` to this many mutations over all chains
    /// (`RegionalAdaptParams::otsu2018_for_budget`), e.g. the count FIXED reached in the same
    /// time. `None` (the preset): scaled to the mutation budget under equal samples, the
    /// paper's `M_refine = 10^7`, `M_split = 5000` under a time budget
    /// ([`crate::mlt::pathmlt::adapt_params`]).
    pub refine_for_mutations: Option<u64>,
    /// RA-QUADTREE: `M_split` instead of the scheduled one (`None`: the schedule's).
    pub split_after_visits: Option<u64>,
    /// How the image's normalisation `b` is estimated (as [`super::ChainSettings`]'s; path-space
    /// MLT makes no large steps, so the default is the bootstrap's estimate), or a given `b`.
    pub normalization: NormalizationMode,
}

impl Default for PathMltSettings {
    fn default() -> Self {
        Self::otsu2018(PerturbationKind::Lens, PathAdapt::Fixed)
    }
}

impl PathMltSettings {
    /// Otsu et al. 2018, section 8.1: the perturbation (`Lens`: the 2-D partition of the
    /// primary ray's raster position; `MultiChain`: the 4-D partition) and the bidirectional
    /// mutation, 0.5 each, with scale adaptation `adapt` (FIXED, GLOBAL, RA-GRID,
    /// RA-QUADTREE) from [`PATHMLT_SIGMA`] toward acceptance 0.5 (docs/methods/
    /// regional-adaptive.md lists the readings).
    #[must_use]
    pub const fn otsu2018(perturbation: PerturbationKind, adapt: PathAdapt) -> Self {
        Self {
            chains: 256,
            bootstrap_samples: 100_000,
            perturbation,
            adapt,
            refine_for_mutations: None,
            split_after_visits: None,
            normalization: NormalizationMode::Pooled,
        }
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
        let mut params = adapt_params(self.adapt, &mlt_settings);
        if self.adapt == PathAdapt::Quadtree {
            if let Some(m) = self.refine_for_mutations {
                let scaled = RegionalAdaptParams::otsu2018_for_budget(m);
                params.split_after_visits = scaled.split_after_visits;
                params.refine_every = scaled.refine_every;
            }
            if let Some(m) = self.split_after_visits {
                params.split_after_visits = Some(m);
            }
        }
        let (out, sigma_map, summary) = render_adaptive_with_params(
            scene,
            self.perturbation,
            self.adapt,
            common.max_depth,
            &mlt_settings,
            &params,
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
                PathAdapt::Fixed => format!("{PATHMLT_SIGMA} rad, fixed"),
                a => format!(
                    "from {PATHMLT_SIGMA} rad, adapted per region: --adapt {}",
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
