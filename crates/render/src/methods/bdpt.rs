//! `bdpt`: bidirectional path tracing with MIS over every strategy (Veach 1997, chapter 10),
//! the reference renderer.

use super::{
    bdpt_params, depth_note, emitter_notes, unsampled_note, IntegratorKind, Method, RenderOutput,
    RenderSettings, Run, Unsampled,
};
use crate::bdpt::{self, BdptParams, Roulette};
use crate::budget::Budget;
use crate::error::RenderError;
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use crate::shard::Partial;

/// `bdpt`'s settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdptSettings {
    /// The per-pixel sampler (default Owen-scrambled Sobol points; docs/performance.md).
    pub sampler: SamplerKind,
    /// Russian roulette of both subpaths (default from 3 bounces on,
    /// [`BdptParams::default`]).
    pub roulette: Roulette,
    /// Also return the MIS-weighted image of every strategy `(s, t)`.
    pub strategy_images: bool,
}

impl Default for BdptSettings {
    fn default() -> Self {
        Self {
            sampler: SamplerKind::Sobol,
            roulette: BdptParams::default().roulette,
            strategy_images: false,
        }
    }
}

impl BdptSettings {
    /// Veach 1997's BDPT (chapter 10, power heuristic with exponent 2, eq. 9.13) over
    /// independent samples, as pbrt-v3 runs it.
    #[must_use]
    pub const fn veach1997() -> Self {
        Self {
            sampler: SamplerKind::Independent,
            roulette: Roulette { start: Some(3) },
            strategy_images: false,
        }
    }
}

impl Method for BdptSettings {
    fn kind(&self) -> IntegratorKind {
        IntegratorKind::Bdpt
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let params = bdpt_params(common, self.roulette);
        let (spp, time) = match common.budget {
            Budget::SamplesPerPixel(n) => (Some(n), None),
            Budget::Time(t) => (None, Some(t)),
        };
        let out = bdpt::render_bdpt_shard(
            scene,
            &params,
            self.sampler,
            (spp, time),
            common.seed,
            self.strategy_images,
            run.shard,
            run.progress,
            run.cancel,
        );
        let mut notes = emitter_notes(scene);
        notes.extend(depth_note(common));
        let pixels = u64::from(common.width) * u64::from(common.height);
        notes.extend(unsampled_note(
            out.unsampled_pixels,
            pixels,
            out.cancelled,
            Unsampled::CameraSamples,
        ));
        let partial = out.component.map(|c| Partial {
            width: out.image.width,
            height: out.image.height,
            components: vec![c],
        });
        Ok(RenderOutput {
            partial,
            samples: out.samples,
            dropped_nonfinite: out.dropped,
            cancelled: out.cancelled,
            unsampled_pixels: out.unsampled_pixels,
            notes,
            strategy_images: out.strategy_images,
            ..RenderOutput::new(out.image, run.start.elapsed())
        })
    }
}
