//! PSSMLT over the unidirectional path tracer: the path tracer with next-event estimation
//! (`crate::integrator::pt`) as a function of primary samples. The delayed-rejection paper's
//! PSSMLT results ran on this target (Rioux-Lavoie et al. 2020, section 5.1.1: "atop a PSSMLT
//! path tracer"), and local QMC's KMLT baseline explores the same path-traced seeds as LQMC
//! (Tessari et al. 2020, section 4).

use glam::Vec2;
use mcmc_core::render_loop::Splat;
use mcmc_core::Target;
use pss::PssState;

use super::path_sampler::{log_of_total_luminance, PathPayload};
use crate::integrator::pt::li_depths;
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// The path tracer as a PSSMLT target: the raster position, lens and time are the first five
/// numbers of the camera stream ([`crate::integrator::pt::sample_pixel`]'s layout with the
/// raster position spread over the whole image), then the path reads five numbers per
/// bounce from the same stream (light choice and position for next-event estimation, lobe,
/// direction, roulette). The target is the luminance of the path's MIS-weighted estimate
/// (emitter hits weighted against next-event estimation, power heuristic), splatted at its
/// raster position.
#[derive(Clone, Copy, Debug)]
pub struct PtTarget<'s> {
    scene: &'s Scene,
    size: Vec2,
    min_depth: u32,
    max_depth: u32,
    roulette: Option<u32>,
}

impl<'s> PtTarget<'s> {
    /// The target for `scene` rendered at `width x height`, paths of at most `max_depth`
    /// bounces, Russian roulette from bounce `roulette` on (`None`: off).
    #[must_use]
    pub fn new(
        scene: &'s Scene,
        width: u32,
        height: u32,
        max_depth: u32,
        roulette: Option<u32>,
    ) -> Self {
        Self {
            scene,
            size: Vec2::new(width as f32, height as f32),
            min_depth: 0,
            max_depth,
            roulette,
        }
    }

    /// The same target counting only paths of at least `min_depth` bounces (for a separate
    /// direct-lighting pass that renders the shorter ones, [`super::direct`]).
    #[must_use]
    pub fn with_min_depth(mut self, min_depth: u32) -> Self {
        self.min_depth = min_depth;
        self
    }
}

impl Target for PtTarget<'_> {
    type State = PssState;
    type Payload = PathPayload;

    fn evaluate(&self, x: &mut PssState, payload: &mut PathPayload) -> f64 {
        x.begin();
        let splats = &mut payload.splats;
        splats.clear();
        Sampler::start_stream(x, Stream::Camera);
        let p_raster = x.next_2d() * self.size;
        let u_lens = x.next_2d();
        let u_time = x.next_1d();
        let ray = self.scene.camera().generate_ray(p_raster, u_lens, u_time);
        let l = li_depths(
            self.scene,
            ray,
            x,
            self.min_depth,
            self.max_depth,
            self.roulette,
        );
        if l != glam::Vec3::ZERO {
            splats.push(Splat {
                raster: p_raster.to_array(),
                rgb: l.to_array(),
            });
        }
        log_of_total_luminance(splats)
    }
}
