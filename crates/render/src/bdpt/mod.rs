//! Bidirectional path tracing with multiple importance sampling (Veach & Guibas 1995; Veach
//! 1997, chapter 10), driven entirely by a [`Sampler`] so that PSS Markov chains can mutate
//! its random numbers (PSSMLT, MMLT).
//!
//! Strategies `(s, t)`: `s` light-subpath vertices joined to `t` camera-subpath vertices,
//! including `s = 0` (the camera path hits an emitter) and `t = 1` (light tracing, splatted at
//! the raster position the connection projects to). MIS weights (balance or power heuristic)
//! are computed from per-vertex forward/reverse area densities without re-tracing.

mod connect;
pub mod diff;
mod render;
mod scene_api;
mod subpath;
mod vertex;

pub use connect::{connect, Connection, MisHeuristic};
pub use render::{render_bdpt, render_bdpt_sampled, render_bdpt_shard, strategy_list, BdptOutput};
pub use scene_api::SceneRef;
pub use subpath::{camera_subpath, light_subpath, random_walk, Roulette, SpecularDensities};
pub use vertex::{geometry_term, Vertex, VertexKind, MAX_PATH_DEPTH, MAX_VERTICES};

use glam::{Vec2, Vec3};

use crate::sampler::{Sampler, Stream};

/// Parameters of BDPT.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdptParams {
    /// Maximum path depth: a path of depth `d` has `d + 2` vertices (camera and light
    /// endpoints included) and `d + 1` segments, so `s + t = d + 2`; depth 0 is an emitter
    /// seen directly, depth 1 direct lighting (default 5).
    pub max_depth: u32,
    /// MIS heuristic (default power).
    pub heuristic: MisHeuristic,
    /// Russian roulette (default from 3 bounces on).
    pub roulette: Roulette,
    /// Densities of vertices on delta lobes for the MIS weights (default
    /// [`SpecularDensities::Kept`]).
    pub specular: SpecularDensities,
}

impl Default for BdptParams {
    fn default() -> Self {
        Self {
            max_depth: 5,
            heuristic: MisHeuristic::Power,
            roulette: Roulette { start: Some(3) },
            specular: SpecularDensities::Kept,
        }
    }
}

/// Subpath storage, grown once to the needed length and reused: no allocation per sample.
#[derive(Clone, Debug, Default)]
pub struct BdptScratch {
    camera: Vec<Vertex>,
    light: Vec<Vertex>,
}

impl BdptScratch {
    /// Makes room for subpaths of `vertices` vertices.
    fn reserve(&mut self, vertices: usize) -> (&mut [Vertex], &mut [Vertex]) {
        if self.camera.len() < vertices {
            let v = Vertex::camera(glam::Vec3A::ZERO, glam::Vec3A::Z, Vec3::ZERO, 0.0);
            self.camera.resize(vertices, v);
            self.light.resize(vertices, v);
        }
        (&mut self.camera, &mut self.light)
    }
}

/// One contribution of a BDPT sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrategySplat {
    /// Raster position.
    pub p_raster: Vec2,
    /// MIS-weighted contribution.
    pub l: Vec3,
    /// Light-subpath vertices.
    pub s: u8,
    /// Camera-subpath vertices.
    pub t: u8,
}

/// Traces one BDPT sample through `p_raster` and reports every nonzero strategy contribution
/// to `sink` (camera-path strategies at `p_raster`, light-tracing ones where they land).
/// With `apply_mis = false` the contributions are unweighted (each strategy's own estimator;
/// for tests and strategy images).
pub fn sample<S, F>(
    scene: SceneRef<'_>,
    sampler: &mut S,
    p_raster: Vec2,
    params: &BdptParams,
    apply_mis: bool,
    scratch: &mut BdptScratch,
    mut sink: F,
) where
    S: Sampler + ?Sized,
    F: FnMut(StrategySplat),
{
    let max_depth = (params.max_depth as usize).min(MAX_VERTICES - 2);
    let (camera, light) = scratch.reserve(max_depth + 2);
    let n_camera = camera_subpath(
        scene,
        sampler,
        p_raster,
        max_depth + 2,
        params.roulette,
        params.specular,
        camera,
    );
    let time = camera[0].time;
    let n_light = light_subpath(
        scene,
        sampler,
        time,
        max_depth + 1,
        params.roulette,
        params.specular,
        light,
    );
    // Strategy s = 1 samples its own light point (next-event estimation): it needs no light
    // subpath, so it runs even when the subpath's origin was rejected (e.g. it landed on a
    // black texel of an emissive texture) — requiring one biased it (pbrt-v3 does).
    for t in 1..=n_camera {
        for s in 0..=n_light.max(1) {
            let depth = s as isize + t as isize - 2;
            if (s == 1 && t == 1) || depth < 0 || depth > max_depth as isize {
                continue;
            }
            let c = connect(
                scene,
                light,
                camera,
                s,
                t,
                sampler,
                params.heuristic,
                apply_mis,
            );
            if c.l != Vec3::ZERO {
                sink(StrategySplat {
                    p_raster: c.p_raster.unwrap_or(p_raster),
                    l: c.l,
                    s: s as u8,
                    t: t as u8,
                });
            }
        }
    }
}

/// Multiplexed MLT's path sampler (Hachisuka et al. 2014; pbrt-v3 `MLTIntegrator::L`): for a
/// path of exactly `depth` bounces, choose one strategy `(s, t)` with `s + t = depth + 2`
/// uniformly from the connection stream, build subpaths of exactly `t` and `s` vertices and
/// return the MIS-weighted contribution times the number of strategies, with its raster
/// position. The raster position is drawn from the camera stream (2 numbers, scaled to the
/// image) before the subpath.
pub fn sample_strategy<S: Sampler + ?Sized>(
    scene: SceneRef<'_>,
    sampler: &mut S,
    depth: u32,
    image_size: Vec2,
    params: &BdptParams,
    scratch: &mut BdptScratch,
) -> Option<StrategySplat> {
    let depth = (depth as usize).min(MAX_VERTICES - 2);
    sampler.start_stream(Stream::Connection);
    let (n_strategies, s, t) = if depth == 0 {
        (1usize, 0usize, 2usize)
    } else {
        let n = depth + 2;
        let s = ((sampler.next_1d_discrete() * n as f32) as usize).min(n - 1);
        (n, s, n - s)
    };
    sampler.start_stream(Stream::Camera);
    let p_raster = sampler.next_2d() * image_size;
    let no_roulette = Roulette { start: None };
    let (camera, light) = scratch.reserve(depth + 2);
    if camera_subpath(
        scene,
        sampler,
        p_raster,
        t,
        no_roulette,
        params.specular,
        camera,
    ) != t
    {
        return None;
    }
    let time = camera[0].time;
    // s = 1 resamples its light point in `connect`: no light subpath needed (requiring one
    // would reject paths whose unused subpath origin had no emission).
    if s != 1 && light_subpath(scene, sampler, time, s, no_roulette, params.specular, light) != s {
        return None;
    }
    let c = connect(scene, light, camera, s, t, sampler, params.heuristic, true);
    if c.l == Vec3::ZERO {
        return None;
    }
    Some(StrategySplat {
        p_raster: c.p_raster.unwrap_or(p_raster),
        l: c.l * n_strategies as f32,
        s: s as u8,
        t: t as u8,
    })
}
