//! Camera and light subpaths: random walks driven by a sampler (pbrt-v3 section 16.3.1).
//!
//! # Specular chains
//!
//! Every vertex stores the area density with which the walk reached it (`pdf_fwd`) and the
//! density with which a walk from the other end would reach it (`pdf_rev`); the MIS weights
//! ([`super::connect`]) are products of their ratios (Veach 1997, section 10.2). At a vertex
//! sampled from a delta lobe (smooth glass, mirror) this crate keeps the lobe's discrete
//! probability `P` as the density in both directions and converts it to area with the next
//! segment's `|cos| / d^2`, exactly as for a rough lobe. The reading behind it: along a chain
//! `x1 - S ... S - x4` of delta vertices, the strategies that can sample the path all sample
//! the chain by BSDF sampling from one end, so the delta distributions cancel between them,
//! and with the per-segment conversions kept the `d^2` of every segment cancels too: the
//! ratio of the densities of `x4` reached from `x1` and of `x1` reached from `x4` is
//! `p_w(x1) cos(x4) / (p_w(x4) cos(x1))` (times the lobe probabilities, which are equal both
//! ways because the mirror's is 1 and the dielectric's Fresnel `R`, `T` are reciprocal) —
//! the ratio the generalized geometric term of the chain gives, which is symmetric
//! (conservation of etendue, Veach 1997 section 5.2; endpoints in media of different index
//! add a constant `n^2` ratio that this reading drops, which only makes the weights slightly
//! less optimal, never biased: every stored density is a function of the path alone, so the
//! weights of one path still sum to one).
//!
//! pbrt-v3's `RandomWalk` instead sets both densities of a delta vertex to zero, and the
//! ratios skip zeros (`remap0`). What is left of the chain in the ratio is then the
//! conversion of the first segment from each non-delta end into the chain,
//! `cos(x2) / d(x1, x2)^2` against `cos(x3) / d(x4, x3)^2`, which no longer cancel. For a
//! caustic seen directly on the floor next to a glass sphere, `d(x1, x2)` (floor to glass) is
//! short, and those weights hand almost all of the caustic to the camera path that happens to
//! hit the light (strategy `s = 0`) instead of to light tracing (`t = 1`). On
//! `scenes/cornell-glass` keeping the densities lowers BDPT's relMSE per sample (measured in
//! `docs/performance.md`, "Specular chains in BDPT's MIS weights").

use glam::{Vec2, Vec3, Vec3A};

use super::scene_api::{self, SceneRef};
use super::vertex::{shading_normal_correction, Vertex, VertexKind};
use crate::camera::Ray;
use crate::frame::{shading_consistent, Frame};
use crate::material::TransportMode;
use crate::sampler::{Sampler, Stream};

/// Russian roulette: from this many vertices on, a walk continues with probability
/// `q = min(0.95, max component of f |cos| / pdf)` of the last bounce. Roulette only divides
/// the throughput by `q`; MIS weights are computed from roulette-free densities, which keeps
/// every strategy unbiased (the weights still sum to one over the strategies that can
/// sample a path) at a small cost in MIS optimality.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roulette {
    /// First subpath vertex index (bounce count) where roulette may stop the walk; `None`
    /// disables roulette (MMLT, whose path length is fixed, disables it).
    pub start: Option<u32>,
}

/// How a subpath vertex sampled from a delta lobe (smooth glass, mirror) stores its
/// densities for the MIS weights (module docs, "Specular chains"). Both are unbiased; they
/// differ in how well the weights split paths through glass between the strategies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpecularDensities {
    /// The lobe's discrete probability both ways, converted to area like any density: the
    /// ratios through a specular chain reduce to its symmetric generalized geometry (the
    /// default).
    #[default]
    Kept,
    /// pbrt-v3's `RandomWalk`: both densities zero, skipped by the ratios. Kept for
    /// comparison (`docs/performance.md`, "Specular chains in BDPT's MIS weights") and as the
    /// tests' negative control.
    Zeroed,
}

/// Max component of an RGB value.
#[inline]
fn max_component(v: Vec3) -> f32 {
    v.x.max(v.y).max(v.z)
}

/// Extends `path` (which already holds the walk's origin at `path[origin]`) by tracing `ray`
/// and sampling BSDFs, up to `max_new` new vertices. Returns the number of vertices added.
///
/// `pdf_dir` is the solid-angle density with which `ray.dir` was sampled at the origin.
#[allow(clippy::too_many_arguments)]
pub fn random_walk<S: Sampler + ?Sized>(
    scene: SceneRef<'_>,
    mut ray: Ray,
    sampler: &mut S,
    mut beta: Vec3,
    pdf_dir: f32,
    max_new: usize,
    mode: TransportMode,
    roulette: Roulette,
    specular: SpecularDensities,
    path: &mut [Vertex],
    origin: usize,
) -> usize {
    if max_new == 0 {
        return 0;
    }
    let mut pdf_fwd = pdf_dir;
    let mut added = 0;
    loop {
        let Some(hit) = scene_api::intersect(scene, &ray) else {
            // A camera ray leaving the scene ends on the environment: a light endpoint at
            // infinity (pbrt-v3 `RandomWalk`), whose density stays in solid angle.
            if mode == TransportMode::Radiance {
                if let Some(env) = scene_api::environment_index(scene) {
                    let idx = origin + 1 + added;
                    let far = scene_api::far_distance(scene, ray.origin);
                    let mut v = Vertex::light(
                        ray.origin + ray.dir * far,
                        Vec3A::ZERO,
                        env,
                        beta,
                        0.0,
                        ray.time,
                    );
                    v.infinite = true;
                    v.wo = -ray.dir;
                    v.pdf_fwd = path[idx - 1].convert_density(pdf_fwd, &v);
                    path[idx] = v;
                    added += 1;
                }
            }
            break;
        };
        let idx = origin + 1 + added;
        let prev = path[idx - 1];
        let mut v = Vertex {
            kind: VertexKind::Surface,
            p: hit.p,
            p_error: hit.p_error,
            ng: hit.ng,
            frame: Frame::from_normal(hit.ns),
            wo: -ray.dir,
            bsdf: Some(hit.bsdf),
            light: hit.light,
            barycentrics: hit.barycentrics,
            infinite: false,
            delta_light: false,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            time: ray.time,
        };
        v.pdf_fwd = prev.convert_density(pdf_fwd, &v);
        path[idx] = v;
        added += 1;
        if added >= max_new {
            break;
        }
        let wo_local = v.frame.to_local(v.wo);
        // The lobe choice is discrete; a delta BSDF does not use the direction numbers.
        let u = sampler.next_1d_discrete();
        let u2 = if hit.bsdf.is_specular() {
            sampler.next_2d_discrete()
        } else {
            sampler.next_2d()
        };
        let Some(bs) = hit.bsdf.sample(wo_local, u, u2, mode) else {
            break;
        };
        if bs.pdf <= 0.0 || bs.f == Vec3::ZERO {
            break;
        }
        let wi = v.frame.to_world(bs.wi);
        if !shading_consistent(v.wo, wi, v.ng, v.ns()) {
            break;
        }
        let cos = bs.wi.z.abs();
        let mut factor = bs.f * (cos / bs.pdf);
        if mode == TransportMode::Importance {
            factor *= shading_normal_correction(v.wo, wi, v.ng, v.ns());
        }
        beta *= factor;
        pdf_fwd = bs.pdf;
        let mut pdf_rev = hit.bsdf.pdf(bs.wi, wo_local, TransportMode::Radiance);
        if bs.is_specular {
            // A delta lobe keeps its discrete probability as the density both ways (the
            // lobe choice is reciprocal: mirror 1, Fresnel R or T from either side), and
            // `convert_density` turns it into an area density with the adjacent segment, as
            // for any other vertex (module docs, "Specular chains").
            path[idx].delta = true;
            match specular {
                SpecularDensities::Kept => pdf_rev = bs.pdf,
                SpecularDensities::Zeroed => {
                    pdf_rev = 0.0;
                    pdf_fwd = 0.0;
                }
            }
        }
        if let Some(start) = roulette.start {
            if added as u32 >= start {
                let q = max_component(factor).min(0.95);
                if q <= 0.0 || sampler.next_1d_discrete() >= q {
                    break;
                }
                beta /= q;
            }
        }
        if !beta.is_finite() || beta == Vec3::ZERO {
            break;
        }
        let here = path[idx];
        path[idx - 1].pdf_rev = here.convert_density(pdf_rev, &path[idx - 1]);
        ray = here.spawn_ray(wi);
    }
    added
}

/// Generates a camera subpath of at most `max_vertices` vertices (including the camera
/// vertex) for the raster position `p_raster` into `path`; returns its length. Random numbers:
/// stream [`Stream::Camera`]: lens (2), time (1), then 3 per bounce (+1 with roulette).
pub fn camera_subpath<S: Sampler + ?Sized>(
    scene: SceneRef<'_>,
    sampler: &mut S,
    p_raster: Vec2,
    max_vertices: usize,
    roulette: Roulette,
    specular: SpecularDensities,
    path: &mut [Vertex],
) -> usize {
    if max_vertices == 0 {
        return 0;
    }
    sampler.start_stream(Stream::Camera);
    // A pinhole does not use the lens numbers, a static camera not the time.
    let u_lens = if scene_api::lens_is_inert(scene) {
        sampler.next_2d_discrete()
    } else {
        sampler.next_2d()
    };
    let u_time = if scene_api::time_is_inert(scene) {
        sampler.next_1d_discrete()
    } else {
        sampler.next_1d()
    };
    let ray = scene_api::generate_ray(scene, p_raster, u_lens, u_time);
    let pdf_dir = scene_api::camera_pdf_dir(scene, &ray);
    path[0] = Vertex::camera(
        ray.origin,
        scene_api::camera_forward(scene, ray.time),
        Vec3::ONE,
        ray.time,
    );
    1 + random_walk(
        scene,
        ray,
        sampler,
        Vec3::ONE,
        pdf_dir,
        max_vertices - 1,
        TransportMode::Radiance,
        roulette,
        specular,
        path,
        0,
    )
}

/// Generates a light subpath of at most `max_vertices` vertices: a point on an emitter chosen
/// in proportion to power and uniformly by area, a cosine-weighted emission direction, then a
/// random walk in importance mode. Random numbers: stream [`Stream::Light`]: light choice (1),
/// position (2), direction (2), then 3 per bounce (+1 with roulette).
pub fn light_subpath<S: Sampler + ?Sized>(
    scene: SceneRef<'_>,
    sampler: &mut S,
    time: f32,
    max_vertices: usize,
    roulette: Roulette,
    specular: SpecularDensities,
    path: &mut [Vertex],
) -> usize {
    if max_vertices == 0 {
        return 0;
    }
    sampler.start_stream(Stream::Light);
    let u_light = sampler.next_1d_discrete();
    let u_pos = sampler.next_2d();
    let u_dir = sampler.next_2d();
    let Some(le) = scene_api::sample_le(scene, u_light, u_pos, u_dir) else {
        return 0;
    };
    if le.pdf_pos <= 0.0 || le.pdf_dir <= 0.0 || le.radiance == Vec3::ZERO {
        return 0;
    }
    let infinite = scene_api::light_is_infinite(scene, le.light);
    // Area lights keep their front normal (offsets, cosines); other lights have none.
    let n = if le.n == Vec3A::ZERO {
        Vec3A::ZERO
    } else {
        scene.lights().lights()[le.light as usize].normal
    };
    let mut v = Vertex::light(le.p, n, le.light, le.radiance, le.pdf_pos, time);
    v.barycentrics = le.barycentrics;
    v.infinite = infinite;
    v.delta_light = scene_api::light_is_delta(scene, le.light);
    path[0] = v;
    let beta = le.radiance * (le.cos / (le.pdf_pos * le.pdf_dir));
    let pdf_dir = le.pdf_dir;
    let ray = path[0].spawn_ray(le.dir);
    let added = random_walk(
        scene,
        ray,
        sampler,
        beta,
        pdf_dir,
        max_vertices - 1,
        TransportMode::Importance,
        roulette,
        specular,
        path,
        0,
    );
    if infinite {
        // pbrt-v3 `GenerateLightSubpath`: the first hit's density is the disc's area density
        // projected onto the surface; the origin's is the density of the direction.
        if added > 0 {
            let mut pdf = scene_api::infinite_disc_pdf(scene);
            if path[1].on_surface() {
                pdf *= le.dir.dot(path[1].ng).abs();
            }
            path[1].pdf_fwd = pdf;
        }
        path[0].pdf_fwd = scene_api::infinite_origin_pdf(scene, le.light, le.dir);
    }
    1 + added
}
