//! `pt`, `qmc` and `qmc-faure`: unidirectional path tracing with next-event estimation and
//! MIS, over a per-pixel sampler or Cranley-Patterson-rotated Halton points.

use lqmc::Scrambling;

use super::{
    emitter_notes, unsampled_note, IntegratorKind, Method, RenderOutput, RenderSettings, Run,
    Unsampled,
};
use crate::error::RenderError;
use crate::integrator::pt::ROULETTE_DEPTH;
use crate::integrator::pt_driver::{self, PtDriverSettings, PtOutput};
use crate::integrator::qmc;
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use crate::shard::{Component, Partial};

/// `pt`: path tracing over a per-pixel sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PtSettings {
    /// The per-pixel sampler (default Owen-scrambled Sobol points; docs/performance.md has
    /// the measurement behind the default).
    pub sampler: SamplerKind,
    /// Russian roulette from this bounce on (pbrt-v4's rule, [`crate::integrator::pt::li_with`];
    /// `None`: off). Default 5 (Mitsuba 3's `rr_depth`).
    pub roulette: Option<u32>,
}

impl Default for PtSettings {
    fn default() -> Self {
        Self {
            sampler: SamplerKind::Sobol,
            roulette: Some(5),
        }
    }
}

impl PtSettings {
    /// pbrt-v4's path tracer: independent samples, roulette from bounce
    /// [`ROULETTE_DEPTH`] (pbrt-v4 `PathIntegrator`).
    #[must_use]
    pub const fn pbrt_v4() -> Self {
        Self {
            sampler: SamplerKind::Independent,
            roulette: Some(ROULETTE_DEPTH),
        }
    }
}

/// `qmc` and `qmc-faure`: path tracing driven by per-pixel rotated Halton points (the "Halton
/// points" baseline of Tessari et al. 2020, section 6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QmcSettings {
    /// Digit scrambling of the Halton points (`qmc`: none; `qmc-faure`: Faure's
    /// permutations).
    pub scrambling: Scrambling,
    /// Russian roulette from this bounce on (`None`: off). Default pbrt-v4's
    /// [`ROULETTE_DEPTH`].
    pub roulette: Option<u32>,
}

impl Default for QmcSettings {
    fn default() -> Self {
        Self {
            scrambling: Scrambling::None,
            roulette: Some(ROULETTE_DEPTH),
        }
    }
}

impl QmcSettings {
    /// `qmc-faure`: Faure's digit permutations under the per-pixel rotation.
    #[must_use]
    pub const fn faure() -> Self {
        Self {
            scrambling: Scrambling::Faure,
            roulette: Some(ROULETTE_DEPTH),
        }
    }
}

/// The PT driver's settings for `common` with `sampler` and `roulette`.
fn driver_settings(
    common: &RenderSettings,
    sampler: SamplerKind,
    roulette: Option<u32>,
    run: &Run<'_>,
) -> PtDriverSettings {
    PtDriverSettings {
        width: common.width,
        height: common.height,
        max_depth: common.max_depth,
        budget: common.budget,
        seed: common.seed,
        sampler,
        roulette,
        shard: run.shard,
    }
}

/// A render output from the PT driver's.
fn output(scene: &Scene, out: PtOutput, run: &Run<'_>) -> RenderOutput {
    let mut notes = emitter_notes(scene);
    let pixels = (out.image.width * out.image.height) as u64;
    notes.extend(unsampled_note(
        out.unsampled_pixels,
        pixels,
        out.cancelled,
        Unsampled::Black,
    ));
    let partial = (!run.shard.is_whole()).then(|| {
        let (sum, weight) = out.film.sums();
        Partial {
            width: out.image.width,
            height: out.image.height,
            components: vec![Component::Film {
                sum: sum.to_vec(),
                weight: weight.to_vec(),
                light: None,
                light_samples: 0,
            }],
        }
    });
    RenderOutput {
        partial,
        samples: out.samples,
        dropped_nonfinite: out.dropped_nonfinite,
        cancelled: out.cancelled,
        unsampled_pixels: out.unsampled_pixels,
        notes,
        ..RenderOutput::new(out.image, run.start.elapsed())
    }
}

impl Method for PtSettings {
    fn kind(&self) -> IntegratorKind {
        IntegratorKind::Pt
    }

    fn sized_camera(&self) -> bool {
        false
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let settings = driver_settings(common, self.sampler, self.roulette, run);
        let out = pt_driver::render_pt(scene, &settings, run.progress, run.cancel);
        Ok(output(scene, out, run))
    }
}

impl Method for QmcSettings {
    fn kind(&self) -> IntegratorKind {
        if self.scrambling == Scrambling::Faure {
            IntegratorKind::QmcFaure
        } else {
            IntegratorKind::Qmc
        }
    }

    fn sized_camera(&self) -> bool {
        false
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let settings = driver_settings(common, SamplerKind::Independent, self.roulette, run);
        let out = qmc::render_qmc_with(scene, &settings, self.scrambling, run.progress, run.cancel);
        Ok(output(scene, out, run))
    }
}
