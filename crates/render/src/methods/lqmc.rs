//! `lqmc`: local quasi-Monte Carlo exploration (Tessari et al. 2020): Halton seed paths
//! explored by rank-1 lattices, prefixes re-traced and reconnected to the static suffix
//! ([`crate::integrator::lqmc`]).

use super::{
    unsampled_note, IntegratorKind, LqmcStats, Method, RenderOutput, RenderSettings, Run, Unsampled,
};
use crate::error::RenderError;
use crate::integrator::lqmc::{render_lqmc, LqmcParams};
use crate::integrator::pt::ROULETTE_DEPTH;
use crate::integrator::pt_driver::PtDriverSettings;
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use crate::shard::Partial;

/// `lqmc`'s settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LqmcSettings {
    /// Lattice sizes, tiles, classes ([`LqmcParams`]).
    pub params: LqmcParams,
}

impl Default for LqmcSettings {
    fn default() -> Self {
        Self::tessari2020()
    }
}

impl LqmcSettings {
    /// Tessari et al. 2020, section 4 "Parameters" ([`LqmcParams::tessari2020`]: lattices of
    /// 23 points for normal and depth-of-field paths and 97 for caustics, 24 image tiles
    /// across, 48 for caustics, 2 x 2 aperture tiles).
    #[must_use]
    pub const fn tessari2020() -> Self {
        Self {
            params: LqmcParams::tessari2020(),
        }
    }

    /// [`LqmcSettings::tessari2020`] with next-event-estimation paths explored as the authors'
    /// code explores them (corona-13 `lqmc.c`: lattices of 7 points for the NEE class, the
    /// normal class's tiles; [`LqmcParams::explore_nee`]). The paper's rule ("we are very
    /// careful not to explore the sample", section 4) splats NEE paths that are neither
    /// caustic nor out of focus unexplored. Only the NEE rule follows the code: its other
    /// departures from the paper (155 / 55 direction tiles, the breakup probability left out
    /// of the weights, which is biased) are not taken.
    #[must_use]
    pub const fn tessari2020_code() -> Self {
        let mut params = LqmcParams::tessari2020();
        params.explore_nee = true;
        Self { params }
    }
}

impl Method for LqmcSettings {
    fn kind(&self) -> IntegratorKind {
        IntegratorKind::Lqmc
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
        let pt = PtDriverSettings {
            width: common.width,
            height: common.height,
            max_depth: common.max_depth,
            budget: common.budget,
            seed: common.seed,
            sampler: SamplerKind::Independent,
            roulette: Some(ROULETTE_DEPTH),
            shard: run.shard,
        };
        let out = render_lqmc(scene, &pt, &self.params, run.progress, run.cancel);
        let stats = LqmcStats {
            seeds: out.seeds,
            progressions: out.progressions,
            explored: out.explored,
            direct: out.direct,
            explored_nee: out.explored_nee,
            direct_nee: out.direct_nee,
            members: out.members,
            rejected: out.rejected,
        };
        let mut notes = scene.notes.clone();
        notes.push(format!("lqmc: {stats}"));
        notes.extend(unsampled_note(
            out.unsampled_pixels,
            u64::from(common.width) * u64::from(common.height),
            out.cancelled,
            Unsampled::SeedPaths,
        ));
        let partial = out.component.map(|c| Partial {
            width: out.image.width,
            height: out.image.height,
            components: vec![c],
        });
        Ok(RenderOutput {
            partial,
            samples: out.seeds,
            dropped_nonfinite: out.dropped_nonfinite,
            cancelled: out.cancelled,
            unsampled_pixels: out.unsampled_pixels,
            notes,
            lqmc: Some(stats),
            ..RenderOutput::new(out.image, run.start.elapsed())
        })
    }
}
