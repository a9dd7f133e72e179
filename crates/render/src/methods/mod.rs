//! Every integrator as a method that owns itself: one module per family holds its settings
//! (documented fields, validation, `Default` = the command line's defaults), the `const fn`
//! presets of the papers it implements, and its render function; the table
//! ([`INTEGRATORS`]) names each row and its default settings. [`crate::session`] validates
//! the common settings and calls [`Method::render`] of the chosen method.
//!
//! | module | rows | settings | paper presets |
//! |---|---|---|---|
//! | [`pt`] | `pt`, `qmc`, `qmc-faure` | [`PtSettings`], [`QmcSettings`] | |
//! | [`bdpt`] | `bdpt` | [`BdptSettings`] | |
//! | [`pssmlt`] | `pssmlt`, `pssmlt-pt` | [`PssmltSettings`] ([`PathBase`]) | `kelemen2002`, `zsolnai2013` |
//! | [`mmlt`] | `mmlt` | [`MmltSettings`] | `hachisuka2014` |
//! | [`drmlt`] | `drmlt` | [`DrmltSettings`] | `rioux_lavoie2020` |
//! | [`mala`] | `mala`, `mala-online`, `mala-cache`, `mala-hybrid` | [`MalaSettings`] | `luan2020`, `luan2020_code` |
//! | [`pathmlt`] | `pathmlt` | [`PathMltSettings`] | `otsu2018` |
//! | [`lqmc`] | `lqmc` | [`LqmcSettings`] | `tessari2020` |
//!
//! Adding an integrator: a module here (settings, presets, `impl Method`), a variant of
//! [`IntegratorKind`] and of [`MethodSettings`], a row of [`INTEGRATORS`], and its flags in
//! the CLI (`src/cli/render_cmd.rs`, `src/cli/method_flags.rs`).

use std::fmt;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use mcmc_core::{Mh, Progress};
use pss::{PssmltProposal, RasterParams, RasterStep, SmallMutation, SmallStep};

use crate::bdpt::{BdptParams, Roulette};
use crate::error::RenderError;
use crate::scene::Scene;
use crate::shard::Shard;

pub mod bdpt;
pub mod direct_pass;
pub mod drmlt;
pub mod lqmc;
pub mod mala;
pub mod memory;
pub mod mmlt;
mod output;
pub mod pathmlt;
pub mod pssmlt;
pub mod pt;
mod settings;
mod table;

pub use bdpt::BdptSettings;
pub use drmlt::DrmltSettings;
pub use lqmc::LqmcSettings;
pub use mala::MalaSettings;
pub use mmlt::MmltSettings;
pub use output::{
    mcmc_notes, mcmc_output, relative_error, unsampled_note, DirectParts, DirectPassStats,
    LqmcStats, McmcStats, PhaseTimes, RenderOutput, Unsampled, BRIGHTNESS_TARGET,
};
pub use pathmlt::PathMltSettings;
pub use pssmlt::{
    PathBase, PssmltSettings, CORONA13_BOOTSTRAP, CORONA13_LARGE_STEP, CORONA13_SMALL_STEP,
};
pub use pt::{PtSettings, QmcSettings};
pub use settings::{
    mlt_budget, remaining, validate_normalization, ChainSettings, MethodSettings, RenderSettings,
    AUTO_LARGE_STEP_ESTIMATION, MAX_BOOTSTRAP_SAMPLES, MAX_CHAINS,
};
pub use table::{IntegratorInfo, IntegratorKind, INTEGRATORS};

/// What a running render reports to and listens to.
#[derive(Clone, Copy)]
pub struct Run<'a> {
    /// When the render started (the session's clock: validation and set-up included).
    pub start: Instant,
    /// Progress reports.
    pub progress: &'a dyn Progress,
    /// Set (e.g. by a Ctrl-C handler) to stop early with the partial image.
    pub cancel: &'a AtomicBool,
    /// The part of the render's fixed work list to render ([`Shard::WHOLE`]: all of it);
    /// a sharded render returns its accumulators in [`RenderOutput::partial`].
    pub shard: Shard,
}

impl fmt::Debug for Run<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Run")
            .field("start", &self.start)
            .finish_non_exhaustive()
    }
}

/// A method: settings that know their integrator, check themselves and render.
pub trait Method: fmt::Debug + Send + Sync {
    /// The integrator (row of [`INTEGRATORS`]) these settings run.
    fn kind(&self) -> IntegratorKind;

    /// Checks the method's own settings against their ranges (the session checks the common
    /// ones first).
    ///
    /// # Errors
    /// [`RenderError::InvalidSetting`] naming the flag and the allowed range.
    fn validate(&self, _common: &RenderSettings) -> Result<(), RenderError> {
        Ok(())
    }

    /// True if the method renders through the scene's camera at the image size (BDPT and the
    /// Markov chain targets): the session then resizes the camera first.
    fn sized_camera(&self) -> bool {
        true
    }

    /// Renders `scene` with `common`'s size, budget, seed and depth. Runs on the session's
    /// thread pool.
    ///
    /// # Errors
    /// Method-specific refusals (e.g. a scene the method cannot render).
    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<super::RenderOutput, RenderError>;
}

/// The scene's notes (e.g. the default environment), and one if it has no light at all.
#[must_use]
pub fn emitter_notes(scene: &Scene) -> Vec<String> {
    let mut notes = scene.notes.clone();
    if scene.lights().is_empty() {
        notes.push("the scene has no light (and no environment): the image is black".to_owned());
    }
    notes
}

/// A note if `common.max_depth` is deeper than BDPT's paths go ([`crate::bdpt::MAX_PATH_DEPTH`]):
/// BDPT and the Markov chain methods over it render depths up to that limit only.
#[must_use]
pub fn depth_note(common: &RenderSettings) -> Option<String> {
    (common.max_depth > crate::bdpt::MAX_PATH_DEPTH).then(|| {
        format!(
            "--max-depth {}: paths of more than {} bounces are not rendered (the bidirectional path sampler's limit)",
            common.max_depth,
            crate::bdpt::MAX_PATH_DEPTH
        )
    })
}

/// BDPT's parameters (shared by BDPT and the MCMC path samplers) at `common`'s depth.
#[must_use]
pub fn bdpt_params(common: &RenderSettings, roulette: Roulette) -> BdptParams {
    BdptParams {
        max_depth: common.max_depth,
        roulette,
        ..BdptParams::default()
    }
}

/// The Metropolis-Hastings kernel of PSSMLT and MMLT for large-step probability `p`: the
/// small step, and with probability `raster.probability` of the small steps a raster step
/// ([`pss::RasterStep`]: only the two raster numbers move).
#[derive(Clone, Copy, Debug)]
pub struct PssKernel {
    small: SmallStep,
    raster: RasterStep,
    raster_probability: f64,
}

impl PssKernel {
    /// The kernel of `small_step` with `raster` on a `width x height` image.
    #[must_use]
    pub fn new(small_step: SmallMutation, raster: &RasterParams, width: u32, height: u32) -> Self {
        Self {
            small: SmallStep::new(small_step),
            raster: RasterStep::for_image(raster, width, height, small_step),
            raster_probability: if raster.is_off() {
                0.0
            } else {
                raster.probability.min(1.0)
            },
        }
    }

    /// The share of small steps that are raster steps.
    #[must_use]
    pub const fn raster_probability(&self) -> f64 {
        self.raster_probability
    }

    /// The kernel with large-step probability `p` (clamped to `[0, 1]`).
    #[must_use]
    pub fn with_large_step(&self, p: f64) -> Mh<PssmltProposal> {
        Mh::new(
            PssmltProposal::new(self.small, p.clamp(0.0, 1.0))
                .and_then(|k| k.with_raster(self.raster, self.raster_probability))
                .unwrap_or_else(|_| unreachable!("clamped")),
        )
    }
}
