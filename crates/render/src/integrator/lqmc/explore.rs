//! One LQMC seed: trace a Halton-driven path with its vertices, and explore each of its
//! contributions with the lattice set of its class (Tessari et al., Alg. 1): re-trace the
//! prefix `z_1 .. z_b` from the member's numbers, reconnect `z_b` to the seed's static
//! `z_{b+1}`, and weight by eq. 8-9 with the breakup probability.

use glam::{UVec2, Vec2, Vec3, Vec3A};
use lqmc::{
    sample_breakup, ExploreScratch, LocalIntegrand, LocalQmc, Rank1Lattice, Rebuilt, Splat, Tiling,
};
use mcmc_core::seed::mix64;

use super::class::{
    breakup_weights, circle_of_confusion, classify, vertex_roughness, Layout, PathClass,
};
use super::LqmcParams;
use crate::camera::{Camera, Ray};
use crate::frame::shading_consistent;
use crate::integrator::halton_sampler::{HaltonSampler, ReplaySampler};
use crate::integrator::power_heuristic;
use crate::integrator::vertex_path::{
    bounce_dim, nee, nee_towards, positive, trace, EventKind, PathEvent, TraceLimit, VertexPath,
};
use crate::material::TransportMode;
use crate::scene::Scene;

/// Largest explored dimension count (the embedded lattice tables go to 21).
const MAX_EXPLORED: usize = lqmc::TABLE_MAX_DIMS;

/// Largest f32 below 1.
const ONE_MINUS_EPSILON_F32: f32 = 1.0 - f32::EPSILON / 2.0;

/// Receives the splats of a seed: raster position (pixels) and RGB value.
pub(crate) trait SplatTarget {
    /// Adds `value` at raster position `p`.
    fn splat(&mut self, p: Vec2, value: Vec3);
}

/// Counters of one work unit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct ExploreStats {
    /// Seed paths traced.
    pub seeds: u64,
    /// Contributions explored with a lattice set.
    pub explored: u64,
    /// Contributions splatted directly (NEE class, too short, or too many dimensions).
    pub direct: u64,
    /// NEE-class contributions explored (only with [`LqmcParams::explore_nee`]).
    pub explored_nee: u64,
    /// NEE-class contributions splatted unexplored by the paper's rule (part of `direct`).
    pub direct_nee: u64,
    /// Lattice members rebuilt in the seed's class (seeds included).
    pub members: u64,
    /// Lattice members rejected (left the class).
    pub rejected: u64,
    /// Non-finite splats dropped.
    pub nonfinite: u64,
}

/// The per-work-unit state of LQMC: samplers, path scratch, lattice sets of this progression.
pub(crate) struct Explorer<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    params: LqmcParams,
    max_depth: u32,
    seed: u64,
    replay: ReplaySampler<HaltonSampler>,
    path: VertexPath,
    member: VertexPath,
    rough: Vec<f32>,
    member_rough: Vec<f32>,
    weights: Vec<f64>,
    member_weights: Vec<f64>,
    layout: Layout,
    u_seed: Vec<f64>,
    seed_numbers: Vec<f32>,
    overrides: Vec<(usize, f32)>,
    splats: Vec<Splat<(Vec2, Vec3)>>,
    scratch: ExploreScratch,
    /// `(N, tiles, set)` of the current progression.
    sets: Vec<(u32, Vec<u32>, LocalQmc)>,
    progression: u32,
    /// Counters.
    pub stats: ExploreStats,
}

impl<'a> Explorer<'a> {
    /// A work unit's explorer for master seed `seed`.
    pub(crate) fn new(
        scene: &'a Scene,
        camera: &'a Camera,
        params: LqmcParams,
        max_depth: u32,
        seed: u64,
    ) -> Self {
        Self {
            scene,
            camera,
            params,
            max_depth,
            seed,
            replay: ReplaySampler::new(HaltonSampler::new(seed)),
            path: VertexPath::default(),
            member: VertexPath::default(),
            rough: Vec::new(),
            member_rough: Vec::new(),
            weights: Vec::new(),
            member_weights: Vec::new(),
            layout: Layout::default(),
            u_seed: Vec::new(),
            seed_numbers: Vec::new(),
            overrides: Vec::new(),
            splats: Vec::new(),
            scratch: ExploreScratch::default(),
            sets: Vec::new(),
            progression: u32::MAX,
            stats: ExploreStats::default(),
        }
    }

    /// The jitter of explored dimension `d` in progression `progression` (section 3.4: one
    /// global offset per progression, shared by every set).
    fn jitter(seed: u64, progression: u32, d: usize) -> f64 {
        let h = mix64(
            mix64(seed ^ 0x1b87_3593_c2b2_ae3d) ^ mix64((u64::from(progression) << 32) | d as u64),
        );
        (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Sample `sample` of `pixel`: traces the seed and splats every contribution, explored
    /// or directly.
    pub(crate) fn sample<T: SplatTarget>(&mut self, pixel: UVec2, sample: u32, out: &mut T) {
        if sample != self.progression {
            self.progression = sample;
            self.sets.clear();
        }
        let w = self.camera.width() as u64;
        self.replay.inner_mut().start_pixel_sample(
            u64::from(pixel.y) * w + u64::from(pixel.x),
            u64::from(sample),
        );
        self.replay.record();
        let limit = TraceLimit {
            max_depth: self.max_depth,
            stop_at_vertex: usize::MAX,
            events: true,
        };
        trace(
            self.scene,
            self.camera,
            pixel,
            &mut self.replay,
            limit,
            &mut self.path,
        );
        self.seed_numbers.clear();
        self.seed_numbers.extend_from_slice(self.replay.recorded());
        self.stats.seeds += 1;
        for e in 0..self.path.events.len() {
            let event = self.path.events[e];
            if event.value == Vec3::ZERO {
                continue;
            }
            if !self.explore_event(&event, pixel, sample, e, out) {
                self.stats.direct += 1;
                splat_checked(out, self.path.raster, event.value, &mut self.stats);
            }
        }
    }

    /// Explores one contribution; false if it is to be splatted directly.
    fn explore_event<T: SplatTarget>(
        &mut self,
        event: &PathEvent,
        pixel: UVec2,
        sample: u32,
        index: usize,
        out: &mut T,
    ) -> bool {
        let length = event.length();
        let is_nee = matches!(event.kind, EventKind::Nee(_));
        self.rough.clear();
        for k in 1..length {
            self.rough.push(vertex_roughness(self.path.z(k)));
        }
        let coc = self.seed_coc();
        let class = classify(&self.params, &self.rough, is_nee, coc);
        if class == PathClass::Nee && !self.params.explore_nee {
            self.stats.direct_nee += 1;
            return false;
        }
        if class == PathClass::Direct {
            return false;
        }
        breakup_weights(&self.params, &self.rough, class, &mut self.weights);
        let u_b = {
            let h = mix64(
                mix64(self.seed ^ 0x7f4a_7c15_9e37_79b9)
                    ^ mix64((u64::from(pixel.y) << 40) ^ (u64::from(pixel.x) << 20) ^ index as u64)
                    ^ mix64(u64::from(sample)),
            );
            (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        };
        let Some((b_index, _)) = sample_breakup(&self.weights, u_b) else {
            return false;
        };
        let b = b_index;
        self.layout
            .build(&self.params, self.camera, class, event, b);
        if self.layout.dims.len() > MAX_EXPLORED {
            return false;
        }
        let n = match class {
            PathClass::Caustic => self.params.n_caustic,
            PathClass::DepthOfField => self.params.n_depth_of_field,
            PathClass::Nee => self.params.n_nee,
            _ => self.params.n_normal,
        };
        let Some(set_index) = self.set_for(n) else {
            return false;
        };
        // The seed's explored numbers (image dimensions as global image coordinates).
        let (width, height) = (
            f64::from(self.camera.width()),
            f64::from(self.camera.height()),
        );
        let rec = &self.seed_numbers;
        self.u_seed.clear();
        for &(d, _) in &self.layout.dims {
            let u = match d {
                0 => (f64::from(pixel.x) + f64::from(rec[0])) / width,
                1 => (f64::from(pixel.y) + f64::from(rec[1])) / height,
                _ => f64::from(rec[d]),
            };
            self.u_seed.push(u.min(lqmc::ONE_MINUS_EPSILON));
        }
        let p_seed = self.weights[b] / self.weights.iter().sum::<f64>();
        let ctx = Context {
            scene: self.scene,
            camera: self.camera,
            params: &self.params,
            max_depth: self.max_depth,
            seed: &self.path,
            recorded: &self.seed_numbers,
            event,
            class,
            b,
            p_seed,
        };
        // The seed reconnected to itself: the same formulas as every member.
        let evaluated = if b == 0 {
            let u_lens = Vec2::new(self.seed_numbers[2], self.seed_numbers[3]);
            ctx.evaluate_lens(u_lens)
        } else {
            ctx.evaluate(&self.path)
                .map(|(value, q)| (value, q, self.path.raster))
        };
        let Some((value, q, raster)) = evaluated else {
            return false;
        };
        let seed_rebuilt = rebuilt(&self.params, raster, value, q, p_seed);
        let mut member = Member {
            ctx,
            overrides: &mut self.overrides,
            layout: &self.layout,
            member: &mut self.member,
            rough: &mut self.member_rough,
            weights: &mut self.member_weights,
            width,
            height,
            replay: &mut self.replay,
        };
        self.splats.clear();
        let lqmc = &self.sets[set_index].2;
        let stats = lqmc.explore_with(
            &self.u_seed,
            seed_rebuilt,
            &mut member,
            &mut self.splats,
            &mut self.scratch,
        );
        self.stats.explored += 1;
        self.stats.explored_nee += u64::from(class == PathClass::Nee);
        self.stats.members += u64::from(stats.members);
        self.stats.rejected += u64::from(stats.rejected);
        for s in &self.splats {
            let (p, rgb) = s.payload;
            splat_checked(out, p, rgb * s.weight as f32, &mut self.stats);
        }
        true
    }

    /// Circle of confusion of the seed's first vertex (pixels).
    fn seed_coc(&self) -> f32 {
        match (self.path.vertices.first(), self.path.ray) {
            (Some(v), Some(ray)) => circle_of_confusion(self.camera, v.si.p, ray.time),
            _ => 0.0,
        }
    }

    /// The lattice set with `N = n` and the layout's tiles in this progression (built once
    /// per progression and work unit).
    fn set_for(&mut self, n: u32) -> Option<usize> {
        let layout = &self.layout;
        if let Some(i) = self
            .sets
            .iter()
            .position(|(m, t, _)| *m == n && t.iter().copied().eq(layout.tiles()))
        {
            return Some(i);
        }
        let tiles: Vec<u32> = self.layout.tiles().collect();
        let lattice = Rank1Lattice::from_table(n, tiles.len()).ok()?;
        let jitter: Vec<f64> = (0..tiles.len())
            .map(|d| Self::jitter(self.seed, self.progression, d))
            .collect();
        let tiling = Tiling::new(tiles.clone()).ok()?.with_jitter(&jitter).ok()?;
        let set = LocalQmc::new(lattice, tiling).ok()?;
        self.sets.push((n, tiles, set));
        Some(self.sets.len() - 1)
    }
}

/// Adds a splat unless it is not finite.
fn splat_checked<T: SplatTarget>(out: &mut T, p: Vec2, v: Vec3, stats: &mut ExploreStats) {
    if v.is_finite() && p.is_finite() {
        out.splat(p, v);
    } else {
        stats.nonfinite += 1;
    }
}

/// The [`Rebuilt`] of a path with contribution `value` (`w f / p`), suffix density ratio
/// `q = p_t(X) / J` and breakup probability `p_b` (see [`Context::evaluate`]).
fn rebuilt(
    params: &LqmcParams,
    raster: Vec2,
    value: Vec3,
    q: f64,
    p_b: f64,
) -> Rebuilt<(Vec2, Vec3)> {
    let q = if params.suffix_density_in_weights {
        q
    } else {
        1.0
    };
    let p_b = if params.breakup_probability_in_weights {
        p_b
    } else {
        1.0
    };
    // The estimator's contribution is w f / J = (w f / p) q; with J := 1 its weight becomes
    // P(b|X_j) / sum_k P(b|X_k) q_k (eq. 8-9 with common factors of q cancelled).
    Rebuilt {
        payload: (raster, value * q as f32),
        contribution: 1.0,
        prefix_jacobian: 1.0,
        density: q,
        breakup_probability: p_b,
    }
}

/// What a member's evaluation needs of the seed.
struct Context<'s> {
    scene: &'s Scene,
    camera: &'s Camera,
    params: &'s LqmcParams,
    max_depth: u32,
    seed: &'s VertexPath,
    recorded: &'s [f32],
    event: &'s PathEvent,
    class: PathClass,
    b: usize,
    /// `P(b|X)` of the seed (that of every `b = 0` member: nothing it depends on moves).
    p_seed: f64,
}

impl Context<'_> {
    /// `b = 0`: the lens point of `u_lens` reconnected to the seed's static `z_1`
    /// ([`Camera::sample_wi`]): contribution, `q` and raster position. The camera factor
    /// `W_e G / p` of a camera-sampled `z_1` is 1; `q` is the density of `z_1` given the lens
    /// point, `pdf_dir |cos_1| / d^2` (`pdf_dir = 1 / (A cos^3)`, [`Camera::pdf_we`]), times
    /// `z_1`'s outgoing density with its new `wo`.
    fn evaluate_lens(&self, u_lens: Vec2) -> Option<(Vec3, f64, Vec2)> {
        let ray = self.seed.ray?;
        let z1 = self.seed.vertices.first()?;
        let cs = self.camera.sample_wi(z1.si.p, u_lens, ray.time)?;
        if !self
            .scene
            .unoccluded_between(cs.p_lens, Vec3A::ZERO, z1.si.p, z1.si.ng)
        {
            return None;
        }
        let d = z1.si.p - cs.p_lens;
        let dist2 = d.length_squared();
        let dir = d.try_normalize()?;
        let (_, pdf_dir) = self.camera.pdf_we(&Ray::new(cs.p_lens, dir, ray.time));
        let cos1 = z1.si.ng.dot(dir).abs();
        if !positive(pdf_dir) || !positive(dist2) || !positive(cos1) {
            return None;
        }
        let q = f64::from(pdf_dir) * f64::from(cos1) / f64::from(dist2);
        let (value, q) = self.continue_from(1, -dir, Vec3::ONE, q)?;
        Some((value, q, cs.p_raster))
    }

    /// The contribution `w f / p` of the path "`path`'s prefix `z_1..z_b`, reconnected to
    /// the seed's static suffix `z_{b+1}..z_L`" and `q = p_t(X) / J`, the density of the
    /// static suffix given the prefix, up to factors common to every member (they cancel in
    /// eq. 9). `None` if the technique cannot produce the path (occluded or impossible
    /// reconnection, a specular `z_b`). For `b = L` (full re-trace) `path` is a whole
    /// member path and `q = 1`.
    fn evaluate(&self, path: &VertexPath) -> Option<(Vec3, f64)> {
        let event = self.event;
        let length = event.length();
        let b = self.b;
        if b == length {
            // Full re-trace: the member's own event at the same vertex.
            let found = path.events.iter().find(|e| {
                e.vertex == event.vertex
                    && std::mem::discriminant(&e.kind) == std::mem::discriminant(&event.kind)
            })?;
            return Some((found.value, 1.0));
        }
        let zb = path.vertices.get(b - 1)?;
        if zb.bsdf.is_specular() {
            return None;
        }
        let lights = self.scene.lights();
        // NEE from z_b itself: the light vertex is static (same light numbers).
        if let EventKind::Nee(_) = event.kind {
            if b == event.vertex {
                let d = bounce_dim(b);
                let (u_light, u_pos) = (
                    self.recorded[d],
                    Vec2::new(self.recorded[d + 1], self.recorded[d + 2]),
                );
                let (end, _, _) = nee(
                    self.scene, &zb.si, &zb.bsdf, &zb.frame, zb.si.wo, u_light, u_pos,
                )?;
                return Some((zb.beta * end, 1.0));
            }
        }
        // Connection z_b -> z_{b+1} (a surface point, or a direction for the environment).
        let (dir, dist2, cos_next, next) = if b + 1 == length {
            match event.kind {
                EventKind::Environment { dir, .. } => (dir, 1.0, 1.0, None),
                _ => {
                    let z = self.seed.z(b + 1);
                    let d = z.si.p - zb.si.p;
                    let dist2 = d.length_squared();
                    let dir = d.try_normalize()?;
                    (dir, dist2, z.si.ng.dot(dir).abs(), Some(z))
                }
            }
        } else {
            let z = self.seed.z(b + 1);
            let d = z.si.p - zb.si.p;
            let dist2 = d.length_squared();
            let dir = d.try_normalize()?;
            (dir, dist2, z.si.ng.dot(dir).abs(), Some(z))
        };
        if !shading_consistent(zb.si.wo, dir, zb.si.ng, zb.si.ns) {
            return None;
        }
        let wo_b = zb.frame.to_local(zb.si.wo);
        let wi_b = zb.frame.to_local(dir);
        let f_b = zb.bsdf.eval(wo_b, wi_b, TransportMode::Radiance) * wi_b.z.abs();
        let pdf_b = zb.bsdf.pdf(wo_b, wi_b, TransportMode::Radiance);
        if !positive(pdf_b) || f_b == Vec3::ZERO || !positive(dist2) || !positive(cos_next) {
            return None;
        }
        let visible = match next {
            Some(z) => self.scene.unoccluded(&zb.si, z.si.p),
            None => self.scene.unoccluded_towards(&zb.si, dir),
        };
        if !visible {
            return None;
        }
        let ratio_b = f_b / pdf_b;
        let q = f64::from(pdf_b) * f64::from(cos_next) / f64::from(dist2);
        if b + 1 == length {
            // z_{b+1} is the emitter (or the environment direction).
            let (le, light_pdf) = match (event.kind, next) {
                (EventKind::Environment { dir, .. }, _) => {
                    (lights.environment_le(dir), lights.pdf_environment(dir))
                }
                (_, Some(z)) => {
                    let light = lights.light_of_triangle(z.si.triangle)?;
                    (
                        self.scene.emitted(&z.si, -dir),
                        lights.pdf_li(zb.si.p, light, z.si.p),
                    )
                }
                _ => return None,
            };
            let w = power_heuristic(pdf_b, light_pdf);
            return Some((zb.beta * ratio_b * le * w, q));
        }
        let _ = next?;
        self.continue_from(b + 1, -dir, zb.beta * ratio_b, q)
    }

    /// The static suffix from `z_k` on, `z_k` now seen along `wo_world` (towards the moved
    /// `z_{k-1}`), after a prefix of throughput `prefix` and suffix density `q` so far: NEE at
    /// `z_k`, or `z_k`'s scatter with its new `wo`, the static middle, and the end term.
    fn continue_from(
        &self,
        k: usize,
        wo_world: Vec3A,
        prefix: Vec3,
        q: f64,
    ) -> Option<(Vec3, f64)> {
        let event = self.event;
        let z1 = self.seed.vertices.get(k - 1)?;
        let mut q = q;
        if let EventKind::Nee(ls) = event.kind {
            if event.vertex == k {
                // z_k connects to the light: its NEE term with the new wo, the light
                // sample and its visibility static.
                let (end, _) = nee_towards(
                    self.scene, &z1.si, &z1.bsdf, &z1.frame, wo_world, &ls, false,
                )?;
                return Some((prefix * end, q));
            }
        }
        let out = z1.out?;
        if out.is_specular || z1.bsdf.is_specular() {
            return None;
        }
        if !shading_consistent(wo_world, out.wi, z1.si.ng, z1.si.ns) {
            return None;
        }
        let wo1 = z1.frame.to_local(wo_world);
        let wi1 = z1.frame.to_local(out.wi);
        let f1 = z1.bsdf.eval(wo1, wi1, TransportMode::Radiance) * wi1.z.abs();
        let pdf1 = z1.bsdf.pdf(wo1, wi1, TransportMode::Radiance);
        if !positive(pdf1) {
            return None;
        }
        q *= f64::from(pdf1);
        let mut value = prefix * (f1 / pdf1);
        // The static middle z_{k+1} .. z_{m-1}, m the event's vertex.
        for i in k + 1..event.vertex {
            value *= self.seed.z(i).out?.weight;
        }
        // The end term; the hit's MIS weight depends on z_k's pdf if it is the last
        // scattering vertex.
        let end = match event.kind {
            EventKind::Emission { light_pdf } | EventKind::Environment { light_pdf, .. }
                if event.vertex == k + 1 =>
            {
                let w_old = event.mis;
                if w_old > 0.0 {
                    event.end * (power_heuristic(pdf1, light_pdf) / w_old)
                } else {
                    return None;
                }
            }
            _ => event.end,
        };
        Some((value * end, q))
    }
}

/// A lattice member: replay the seed with the explored numbers overridden, re-trace the
/// prefix, check the class, reconnect (the [`LocalIntegrand`] of Alg. 1 lines 9-11).
struct Member<'s, 'r> {
    ctx: Context<'s>,
    overrides: &'r mut Vec<(usize, f32)>,
    layout: &'r Layout,
    member: &'r mut VertexPath,
    rough: &'r mut Vec<f32>,
    weights: &'r mut Vec<f64>,
    width: f64,
    height: f64,
    replay: &'r mut ReplaySampler<HaltonSampler>,
}

/// `x` in `[0, 1)` as a sampler number (rounded down to the 24-bit grid of the samplers).
fn to_f32_unit(x: f64) -> f32 {
    (((x * (1u64 << 24) as f64) as u64) as f32 * (1.0 / (1u64 << 24) as f32))
        .min(ONE_MINUS_EPSILON_F32)
}

impl LocalIntegrand for Member<'_, '_> {
    type Payload = (Vec2, Vec3);

    fn rebuild(&mut self, u_bar: &[f64]) -> Option<Rebuilt<(Vec2, Vec3)>> {
        let ctx = &self.ctx;
        if ctx.b == 0 {
            // Only the aperture moves: no re-trace, class and P(b|X) are the seed's.
            let u_lens = Vec2::new(to_f32_unit(u_bar[0]), to_f32_unit(u_bar[1]));
            let (value, q, raster) = ctx.evaluate_lens(u_lens)?;
            if value == Vec3::ZERO || !positive(q) {
                return None;
            }
            return Some(rebuilt(ctx.params, raster, value, q, ctx.p_seed));
        }
        let replay = &mut *self.replay;
        self.overrides.clear();
        let mut pixel = UVec2::ZERO;
        for (&(d, _), &u) in self.layout.dims.iter().zip(u_bar) {
            match d {
                0 | 1 => {
                    let extent = if d == 0 { self.width } else { self.height };
                    let x = u * extent;
                    let p = (x.floor().max(0.0) as u32).min(extent as u32 - 1);
                    if d == 0 {
                        pixel.x = p;
                    } else {
                        pixel.y = p;
                    }
                    self.overrides.push((d, to_f32_unit(x - f64::from(p))));
                }
                _ => self.overrides.push((d, to_f32_unit(u))),
            }
        }
        replay.replay(self.overrides.iter().copied());
        let length = ctx.event.length();
        let full = ctx.b == length;
        let limit = TraceLimit {
            max_depth: ctx.max_depth,
            stop_at_vertex: if full { length } else { ctx.b },
            events: full,
        };
        trace(ctx.scene, ctx.camera, pixel, replay, limit, self.member);
        // The member's class and breakup probability, from its own vertices (re-traced
        // prefix) and the seed's static suffix.
        let traced = if full {
            length - 1
        } else {
            ctx.b.min(length - 1)
        };
        if self.member.vertices.len() < traced.max(1) {
            return None;
        }
        self.rough.clear();
        for k in 1..length {
            let v = if k <= traced {
                self.member.z(k)
            } else {
                ctx.seed.z(k)
            };
            self.rough.push(vertex_roughness(v));
        }
        let coc = match (self.member.vertices.first(), self.member.ray) {
            (Some(v), Some(ray)) => circle_of_confusion(ctx.camera, v.si.p, ray.time),
            _ => 0.0,
        };
        let is_nee = matches!(ctx.event.kind, EventKind::Nee(_));
        if classify(ctx.params, self.rough, is_nee, coc) != ctx.class {
            return None;
        }
        breakup_weights(ctx.params, self.rough, ctx.class, self.weights);
        let total: f64 = self.weights.iter().sum();
        let p_b = self.weights[ctx.b] / total;
        if !positive(p_b) {
            return None;
        }
        let (value, q) = ctx.evaluate(self.member)?;
        if value == Vec3::ZERO || !positive(q) {
            return None;
        }
        Some(rebuilt(ctx.params, self.member.raster, value, q, p_b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::IndependentSampler;

    /// Reconnecting a seed to its own suffix reproduces its contribution, for every breakup
    /// point, on a scene with diffuse, glossy and glass vertices.
    #[test]
    fn self_reconnection_reproduces_the_seed_contribution() {
        let glass = Scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/cornell-glass.gltf"
        )))
        .unwrap();
        let mut glass16 = glass.clone();
        glass16.set_resolution(16, 16);
        let mut dof16 = Scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/dof.gltf"
        )))
        .unwrap();
        dof16.set_resolution(16, 16);
        let mut lens_checked = 0;
        for scene in [Scene::cornell_box(16, 16), glass16, dof16] {
            let camera = *scene.camera();
            let params = LqmcParams::default();
            let mut sampler = ReplaySampler::new(IndependentSampler::new(9));
            let mut path = VertexPath::default();
            let limit = TraceLimit {
                max_depth: 4,
                stop_at_vertex: usize::MAX,
                events: true,
            };
            let mut checked = 0;
            for i in 0..400u32 {
                sampler.inner_mut().start_pixel_sample(u64::from(i), 0);
                sampler.record();
                let pixel = UVec2::new(i % 16, (i / 16) % 16);
                trace(&scene, &camera, pixel, &mut sampler, limit, &mut path);
                let recorded = sampler.recorded().to_vec();
                for event in &path.events {
                    let ctx = |b| Context {
                        scene: &scene,
                        camera: &camera,
                        params: &params,
                        max_depth: 4,
                        seed: &path,
                        recorded: &recorded,
                        event,
                        class: PathClass::DepthOfField,
                        b,
                        p_seed: 1.0,
                    };
                    if camera.lens_radius() > 0.0 && event.length() >= 2 {
                        // b = 0: the seed's own lens point reconnected to z_1.
                        let u_lens = Vec2::new(recorded[2], recorded[3]);
                        if let Some((value, q, raster)) = ctx(0).evaluate_lens(u_lens) {
                            let err = (value - event.value).abs().max_element();
                            assert!(
                                err <= 1e-3 * (1e-3 + event.value.max_element()),
                                "b 0 of {event:?}: {value} vs {}",
                                event.value
                            );
                            assert!((raster - path.raster).length() < 1e-2, "{raster}");
                            assert!(q > 0.0 && q.is_finite());
                            lens_checked += 1;
                        } else {
                            assert!(path.z(1).bsdf.is_specular(), "b 0 of {event:?}");
                        }
                    }
                    for b in 1..=event.length() {
                        let ctx = Context {
                            scene: &scene,
                            camera: &camera,
                            params: &params,
                            max_depth: 4,
                            seed: &path,
                            recorded: &recorded,
                            event,
                            class: PathClass::Normal,
                            b,
                            p_seed: 1.0,
                        };
                        let length = event.length();
                        let specular = b < length
                            && (path.z(b).bsdf.is_specular()
                                || (b + 1 < length && path.z(b + 1).bsdf.is_specular()));
                        if let Some((value, q)) = ctx.evaluate(&path) {
                            let err = (value - event.value).abs().max_element();
                            assert!(
                                err <= 1e-3 * (1e-3 + event.value.max_element()),
                                "b {b} of {event:?}: {value} vs {}",
                                event.value
                            );
                            assert!(q > 0.0 && q.is_finite());
                            checked += 1;
                        } else {
                            // Only impossible reconnections (specular ends) fail.
                            assert!(specular, "b {b} of {event:?}");
                        }
                    }
                }
            }
            assert!(checked > 200, "{checked}");
        }
        assert!(lens_checked > 100, "{lens_checked}");
    }
}
