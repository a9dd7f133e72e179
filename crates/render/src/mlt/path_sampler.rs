//! The path samplers MCMC runs on: BDPT as a function of primary samples, exposed as
//! `mcmc_core::Target`s over `pss::PssState` (PSSMLT: all strategies; MMLT: one strategy).

use glam::Vec2;
use mcmc_core::Target;
use pss::PssState;

use mcmc_core::render_loop::{Splat, SplatPayload};

use crate::bdpt::{self, BdptParams, BdptScratch};
use crate::image::luminance;
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// Largest f32 below 1: primary samples are f64 in [0, 1) and must stay below 1 as f32.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A PSS state read as a renderer sampler: streams map to PSS streams (camera 0, light 1,
/// connection 2) and every number is a lazily mutated primary sample.
impl Sampler for PssState {
    #[inline]
    fn start_stream(&mut self, stream: Stream) {
        PssState::start_stream(self, stream.index());
    }
    #[inline]
    fn next_1d(&mut self) -> f32 {
        (self.next_sample() as f32).min(ONE_MINUS_EPSILON)
    }
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

/// Number of PSS streams the path samplers read.
pub const PATH_STREAMS: usize = 3;

/// What a path sample produced: its splats, plus reusable subpath storage.
#[derive(Clone, Debug, Default)]
pub struct PathPayload {
    /// The sample's splats.
    pub splats: Vec<Splat>,
    scratch: BdptScratch,
}

impl SplatPayload for PathPayload {
    fn splats(&self) -> &[Splat] {
        &self.splats
    }
}

fn log_of_total_luminance(splats: &[Splat]) -> f64 {
    let f: f64 = splats.iter().map(|s| f64::from(luminance(s.rgb))).sum();
    if f > 0.0 && f.is_finite() {
        f.ln()
    } else if f.is_nan() || f == f64::INFINITY {
        f64::NAN
    } else {
        f64::NEG_INFINITY
    }
}

/// Kelemen-style PSSMLT target (Kelemen et al. 2002 over BDPT): the raster position is the
/// first two numbers of the camera stream; one BDPT sample evaluates all strategies; the
/// target is the summed luminance of all MIS-weighted contributions, which are splatted where
/// they land (light tracing included).
#[derive(Clone, Copy, Debug)]
pub struct PssmltTarget<'s> {
    scene: &'s Scene,
    params: BdptParams,
    size: Vec2,
}

impl<'s> PssmltTarget<'s> {
    /// The target for `scene` rendered at `width` x `height`.
    pub fn new(scene: &'s Scene, params: BdptParams, width: u32, height: u32) -> Self {
        Self {
            scene,
            params,
            size: Vec2::new(width as f32, height as f32),
        }
    }
}

impl Target for PssmltTarget<'_> {
    type State = PssState;
    type Payload = PathPayload;

    fn evaluate(&self, x: &mut PssState, payload: &mut PathPayload) -> f64 {
        x.begin();
        let PathPayload { splats, scratch } = payload;
        splats.clear();
        Sampler::start_stream(x, Stream::Camera);
        let p_raster = x.next_2d() * self.size;
        bdpt::sample(self.scene, x, p_raster, &self.params, true, scratch, |sp| {
            splats.push(Splat {
                raster: sp.p_raster.to_array(),
                rgb: sp.l.to_array(),
            });
        });
        log_of_total_luminance(splats)
    }
}

/// Multiplexed MLT target for one path depth (Hachisuka et al. 2014, section 4): one strategy
/// per sample, chosen from the connection stream; `render_mlt` runs one such target per depth
/// `0..=max_depth` and distributes chains over depths in proportion to their bootstrap weight.
#[derive(Clone, Copy, Debug)]
pub struct MmltTarget<'s> {
    scene: &'s Scene,
    params: BdptParams,
    depth: u32,
    size: Vec2,
}

impl<'s> MmltTarget<'s> {
    /// The targets for every depth `0..=params.max_depth`.
    pub fn all_depths(scene: &'s Scene, params: BdptParams, width: u32, height: u32) -> Vec<Self> {
        (0..=params.max_depth)
            .map(|depth| Self {
                scene,
                params,
                depth,
                size: Vec2::new(width as f32, height as f32),
            })
            .collect()
    }
}

impl<'s> MmltTarget<'s> {
    /// The path depth this target samples.
    #[must_use]
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// The scene, BDPT parameters and image size (for the differentiable evaluator).
    pub(crate) fn parts(&self) -> (&'s Scene, BdptParams, Vec2) {
        (self.scene, self.params, self.size)
    }
}

impl Target for MmltTarget<'_> {
    type State = PssState;
    type Payload = PathPayload;

    fn evaluate(&self, x: &mut PssState, payload: &mut PathPayload) -> f64 {
        x.begin();
        let PathPayload { splats, scratch } = payload;
        splats.clear();
        if let Some(sp) =
            bdpt::sample_strategy(self.scene, x, self.depth, self.size, &self.params, scratch)
        {
            splats.push(Splat {
                raster: sp.p_raster.to_array(),
                rgb: sp.l.to_array(),
            });
        }
        log_of_total_luminance(splats)
    }
}
