//! The path samplers MCMC runs on: BDPT as a function of primary samples, exposed as
//! `mcmc_core::Target`s over `pss::PssState` (PSSMLT: all strategies; MMLT: one strategy).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

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
    #[inline]
    fn next_1d_discrete(&mut self) -> f32 {
        (self.next_discrete() as f32).min(ONE_MINUS_EPSILON)
    }
    #[inline]
    fn next_2d_discrete(&mut self) -> Vec2 {
        let x = self.next_1d_discrete();
        Vec2::new(x, self.next_1d_discrete())
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

/// `ln` of the summed luminance of `splats` (`-inf` for none, NaN for a non-finite sum).
pub(super) fn log_of_total_luminance(splats: &[Splat]) -> f64 {
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
    min_depth: u32,
}

impl<'s> PssmltTarget<'s> {
    /// The target for `scene` rendered at `width` x `height`.
    pub fn new(scene: &'s Scene, params: BdptParams, width: u32, height: u32) -> Self {
        Self {
            scene,
            params,
            size: Vec2::new(width as f32, height as f32),
            min_depth: 0,
        }
    }

    /// The same target restricted to paths of at least `min_depth` bounces: strategies
    /// `(s, t)` with `s + t - 2 < min_depth` are neither splatted nor counted in the target
    /// (for a separate direct-lighting pass that renders the shorter paths, as Mitsuba 0.6's
    /// PSSMLT `directSamples` and the DRMLT reference implementation do; [`super::direct`]).
    #[must_use]
    pub fn with_min_depth(mut self, min_depth: u32) -> Self {
        self.min_depth = min_depth;
        self
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
        let min_vertices = self.min_depth.saturating_add(2);
        bdpt::sample(self.scene, x, p_raster, &self.params, true, scratch, |sp| {
            if u32::from(sp.s) + u32::from(sp.t) >= min_vertices {
                splats.push(Splat {
                    raster: sp.p_raster.to_array(),
                    rgb: sp.l.to_array(),
                });
            }
        });
        log_of_total_luminance(splats)
    }
}

/// Multiplexed MLT target for one path depth (Hachisuka et al. 2014, section 4): one strategy
/// per sample, chosen from the connection stream; `MltDriver` runs one such target per depth
/// `0..=max_depth` and distributes chains over depths in proportion to their bootstrap weight.
#[derive(Clone, Copy, Debug)]
pub struct MmltTarget<'s> {
    scene: &'s Scene,
    params: BdptParams,
    depth: u32,
    size: Vec2,
}

impl<'s> MmltTarget<'s> {
    /// The targets for every depth `0..=params.max_depth`, at most
    /// [`bdpt::MAX_PATH_DEPTH`] (BDPT's deepest path; a deeper target would sample that depth
    /// again and count its light twice).
    pub fn all_depths(scene: &'s Scene, params: BdptParams, width: u32, height: u32) -> Vec<Self> {
        Self::depths_from(scene, params, width, height, 0)
    }

    /// The targets for depths `min_depth..=params.max_depth` (at most
    /// [`bdpt::MAX_PATH_DEPTH`]): the chains' share when a separate pass renders the shallower
    /// depths ([`super::direct`]); empty if `min_depth` is beyond them.
    pub fn depths_from(
        scene: &'s Scene,
        params: BdptParams,
        width: u32,
        height: u32,
        min_depth: u32,
    ) -> Vec<Self> {
        (min_depth..=params.max_depth.min(bdpt::MAX_PATH_DEPTH))
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

/// Samples per block of [`mmlt_depth_normalization`] (summed in order: bit-identical for any
/// thread count).
const NORMALIZATION_BLOCK: u64 = 4096;

/// An estimate of every MMLT target's integral `b_d` (depths `0..=params.max_depth`) from
/// `samples` all-strategy BDPT samples: the luminance of each sample's MIS-weighted
/// contributions, summed per path depth `s + t - 2` and averaged (pbrt's BDPT over primary
/// sample space, as [`PssmltTarget`] evaluates it; keys independent of the MMLT bootstrap's).
///
/// Each BDPT sample evaluates every strategy of every depth, so a strategy that alone finds
/// some light (a camera path hitting a small light through glass: `s = 0`) is tried once per
/// sample instead of once per `d + 2` MMLT bootstrap samples of its depth (Hachisuka et al.
/// 2014, section 4, picks one strategy per sample): the heavy tail of MMLT's per-depth
/// bootstrap is what makes the default MMLT miss such light in most runs. Both estimate the
/// same integral (the MIS weights of a depth's strategies sum to one), so the result can
/// replace the bootstrap's `b_d` (`mcmc_core::render_loop::RenderLoop::run_normalized`).
/// Returns `None` if cancelled.
#[must_use]
pub fn mmlt_depth_normalization(
    scene: &Scene,
    params: BdptParams,
    width: u32,
    height: u32,
    samples: u64,
    seed: u64,
    cancel: &AtomicBool,
) -> Option<Vec<f64>> {
    mmlt_depth_normalization_until(scene, params, width, height, samples, seed, None, cancel)
        .map(|n| n.b)
}

/// One block's per-depth luminance sums and its sample count.
type BlockSums = (Vec<f64>, u64);

/// What [`mmlt_depth_normalization_until`] estimated.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthNormalization {
    /// The estimate of each depth's integral `b_d`.
    pub b: Vec<f64>,
    /// All-strategy samples it rests on (all that were asked for unless the deadline
    /// stopped it).
    pub samples: u64,
}

/// [`mmlt_depth_normalization`] that also stops at `deadline`: blocks of samples not started
/// by then are skipped (the first block always runs) and `b_d` is the mean over the blocks
/// that ran, still unbiased (which blocks run depends on the clock, not on their values).
/// Without a deadline the result is [`mmlt_depth_normalization`]'s, bit for bit. Returns
/// `None` if cancelled.
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn mmlt_depth_normalization_until(
    scene: &Scene,
    params: BdptParams,
    width: u32,
    height: u32,
    samples: u64,
    seed: u64,
    deadline: Option<Instant>,
    cancel: &AtomicBool,
) -> Option<DepthNormalization> {
    use rayon::prelude::*;
    let depths = params.max_depth.min(bdpt::MAX_PATH_DEPTH) as usize + 1;
    let size = Vec2::new(width as f32, height as f32);
    let key_seed = mcmc_core::seed::mix64(seed ^ 0xbd97_a11d_e97b_0001);
    let blocks = samples.div_ceil(NORMALIZATION_BLOCK);
    // Per block: its sums and sample count; `Some(None)` for a block the deadline skipped,
    // `None` if cancelled.
    let sums: Vec<Option<Option<BlockSums>>> = (0..blocks)
        .into_par_iter()
        .map_init(
            || (PssState::new(PATH_STREAMS, 0), BdptScratch::default()),
            |(state, scratch), block| {
                if cancel.load(Ordering::Relaxed) {
                    return None;
                }
                if block > 0 && deadline.is_some_and(|t| Instant::now() >= t) {
                    return Some(None);
                }
                let mut sums = vec![0.0f64; depths];
                let lo = block * NORMALIZATION_BLOCK;
                let hi = (lo + NORMALIZATION_BLOCK).min(samples);
                for i in lo..hi {
                    state.reset(PATH_STREAMS, mcmc_core::seed::chain_seed(key_seed, i));
                    state.begin();
                    Sampler::start_stream(state, Stream::Camera);
                    let p_raster = state.next_2d() * size;
                    bdpt::sample(scene, state, p_raster, &params, true, scratch, |sp| {
                        let depth = usize::from(sp.s) + usize::from(sp.t) - 2;
                        let y = f64::from(luminance(sp.l.to_array()));
                        if depth < depths && y.is_finite() {
                            sums[depth] += y;
                        }
                    });
                }
                Some(Some((sums, hi - lo)))
            },
        )
        .collect();
    let mut total = vec![0.0f64; depths];
    let mut taken = 0u64;
    for block in sums {
        if let Some((block, n)) = block? {
            for (t, s) in total.iter_mut().zip(block) {
                *t += s;
            }
            taken += n;
        }
    }
    let n = taken.max(1) as f64;
    Some(DepthNormalization {
        b: total.into_iter().map(|s| s / n).collect(),
        samples: taken,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_depth_normalization_stops_at_its_deadline() {
        let scene = Scene::cornell_box(8, 8);
        let params = BdptParams::default();
        let no = AtomicBool::new(false);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let until = |samples, deadline| {
            pool.install(|| {
                mmlt_depth_normalization_until(&scene, params, 8, 8, samples, 1, deadline, &no)
            })
            .unwrap()
        };
        // A deadline that has passed: only the first block runs, and its mean is the estimate.
        let stopped = until(100_000, Some(Instant::now()));
        assert_eq!(stopped.samples, NORMALIZATION_BLOCK);
        let first_block = until(NORMALIZATION_BLOCK, None);
        assert_eq!(stopped, first_block);
        assert!(stopped.b.iter().sum::<f64>() > 0.0);
        // Control: without a deadline every sample is taken, bit for bit as before.
        let all = until(3 * NORMALIZATION_BLOCK, None);
        assert_eq!(all.samples, 3 * NORMALIZATION_BLOCK);
        let plain = mmlt_depth_normalization(&scene, params, 8, 8, 3 * NORMALIZATION_BLOCK, 1, &no);
        assert_eq!(Some(all.b), plain);
    }
}
