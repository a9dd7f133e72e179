//! `pathmlt`: path-space MLT (Veach & Guibas 1997) over `pathspace`: a lens or multi-chain
//! perturbation mixed with the bidirectional mutation, with the perturbation's scale fixed or
//! adapted per region (Otsu et al. 2018; [`crate::mlt::pathmlt`]).

use pathspace::PerturbationKind;

use super::{
    emitter_notes, mcmc_output, mlt_budget, IntegratorKind, Method, RenderOutput, RenderSettings,
    Run, MAX_BOOTSTRAP_SAMPLES, MAX_CHAINS,
};
use crate::error::RenderError;
use crate::mlt::pathmlt::{render_adaptive, PathAdapt, PATHMLT_SIGMA};
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
        }
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
        Ok(())
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
        };
        let out = render_adaptive(
            scene,
            self.perturbation,
            self.adapt,
            common.max_depth,
            &mlt_settings,
            run.progress,
            run.cancel,
        )?;
        let mut notes = emitter_notes(scene);
        notes.push(format!(
            "path-space MLT: {} perturbation (sigma {}) and the bidirectional mutation, 0.5 each; no large steps (--large-step is ignored)",
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
        Ok(mcmc_output(out, notes, run.start.elapsed()))
    }
}
