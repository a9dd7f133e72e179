//! A path tracer that keeps its vertices: the camera sample, every surface vertex with its
//! BSDF, arriving throughput and outgoing BSDF sample, and every contribution ("event": an
//! emitter hit by BSDF sampling, the environment, or next-event estimation) with its MIS
//! weight. Local exploration (LQMC) re-traces prefixes and reconnects to these vertices;
//! path-space methods can read the same record.
//!
//! The numbers are drawn exactly as [`crate::integrator::pt`] draws them (pixel 2, lens 2,
//! time 1, then per bounce: light choice 1, light position 2, BSDF lobe 1, BSDF direction 2,
//! Russian roulette 1), so dimension `d` of a seed means the same decision in both. Unlike
//! `pt`, this tracer applies **no Russian roulette** (the roulette number is drawn and
//! ignored): a roulette decision depends on the throughput, which changes when a prefix is
//! perturbed, so a static suffix could not keep its survival probabilities. Paths end at the
//! maximum depth.

use glam::{UVec2, Vec2, Vec3, Vec3A};

use super::power_heuristic;
use crate::camera::{Camera, Ray};
use crate::film::pixel_sample_position;
use crate::frame::{shading_consistent, Frame};
use crate::light::LightSample;
use crate::material::{Bsdf, TransportMode};
use crate::sampler::{Sampler, Stream};
use crate::scene::{Scene, SurfaceInteraction};

/// Numbers drawn before the first bounce: pixel position 2, lens 2, time 1.
pub const CAMERA_DIMS: usize = 5;
/// Numbers drawn per bounce (see the module docs).
pub const BOUNCE_DIMS: usize = 7;

/// First dimension of the numbers drawn at surface vertex `k >= 1` (`z_k`): `+0` light
/// choice, `+1..=2` light position, `+3` BSDF lobe, `+4..=5` BSDF direction, `+6` roulette.
#[inline]
#[must_use]
pub const fn bounce_dim(k: usize) -> usize {
    CAMERA_DIMS + BOUNCE_DIMS * (k - 1)
}

/// The BSDF sample that continued the path at a vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    /// Outgoing direction (world space, unit).
    pub wi: Vec3A,
    /// Solid-angle pdf of `wi` (the lobe probability for delta lobes).
    pub pdf: f32,
    /// `f |cos| / pdf`: the throughput factor of this vertex.
    pub weight: Vec3,
    /// True if `wi` came from a delta lobe.
    pub is_specular: bool,
}

/// A surface vertex `z_k` of a traced path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathVertex {
    /// The intersection (its `wo` points back along the arriving ray).
    pub si: SurfaceInteraction,
    /// The BSDF at the vertex.
    pub bsdf: Bsdf,
    /// The shading frame.
    pub frame: Frame,
    /// Throughput arriving at the vertex (`f / p` of the path up to here; 1 at `z_1`).
    pub beta: Vec3,
    /// The BSDF sample leaving the vertex, if the path went on.
    pub out: Option<Scatter>,
}

/// What kind of contribution an event is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EventKind {
    /// An emitting surface `z_k` found by the camera ray or by BSDF sampling (path length
    /// `L = k`); `light_pdf` is the next-event density of `z_k` seen from `z_{k-1}` (its
    /// power-heuristic partner; 0 after a specular bounce or for the camera ray).
    Emission {
        /// Next-event solid-angle density of the hit point from the previous vertex.
        light_pdf: f32,
    },
    /// The environment seen along `dir` after `z_{k-1}` (`L = k`).
    Environment {
        /// Direction of the escaping ray (world space).
        dir: Vec3A,
        /// Next-event density of `dir` (0 after a specular bounce or for the camera ray).
        light_pdf: f32,
    },
    /// Next-event estimation at `z_k` towards a light sample (`L = k + 1`).
    Nee(LightSample),
}

/// One contribution of a traced path (the paper's "every time a complete path is found",
/// section 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathEvent {
    /// `k`: the emitting vertex (emission, environment: `z_k`, which for the environment is
    /// not stored) or the vertex that connected to the light (NEE).
    pub vertex: usize,
    /// The kind, with what reconnection needs.
    pub kind: EventKind,
    /// MIS-weighted contribution `w f / p` (RGB).
    pub value: Vec3,
    /// `value` divided by the throughput arriving at `z_k` (the emitted radiance times the
    /// MIS weight, or for NEE `f |cos| L_e w / pdf`).
    pub end: Vec3,
    /// The MIS weight of the event (power heuristic between BSDF and light sampling).
    pub mis: f32,
}

impl PathEvent {
    /// Number of path vertices after the camera, `L`: `k` for hits, `k + 1` for NEE.
    #[must_use]
    pub fn length(&self) -> usize {
        match self.kind {
            EventKind::Nee(_) => self.vertex + 1,
            _ => self.vertex,
        }
    }
}

/// A traced camera path: its camera sample, vertices `z_1, z_2, ...` and contributions.
/// Reused across samples (clear-and-refill, no allocation once grown).
#[derive(Clone, Debug, Default)]
pub struct VertexPath {
    /// The pixel the sample belongs to.
    pub pixel: UVec2,
    /// Raster position of the camera ray.
    pub raster: Vec2,
    /// The camera ray.
    pub ray: Option<Ray>,
    /// Surface vertices: `vertices[k - 1]` is `z_k`.
    pub vertices: Vec<PathVertex>,
    /// Contributions, in the order the tracer found them.
    pub events: Vec<PathEvent>,
}

impl VertexPath {
    /// Vertex `z_k` (`k >= 1`).
    #[must_use]
    pub fn z(&self, k: usize) -> &PathVertex {
        &self.vertices[k - 1]
    }

    /// The sum of the event values: the path tracer's estimate for this sample.
    #[must_use]
    pub fn radiance(&self) -> Vec3 {
        self.events.iter().map(|e| e.value).sum()
    }
}

/// True if `x > 0` (false for NaN): the test every density and cosine passes before use.
#[inline]
#[must_use]
pub fn positive<T: PartialOrd + Default>(x: T) -> bool {
    x > T::default()
}

/// How far [`trace`] goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceLimit {
    /// Maximum number of bounces (as `pt`'s `max_depth`).
    pub max_depth: u32,
    /// Stop once vertex `z_k` with `k = stop_at_vertex` is found (its emission is still
    /// recorded, no next-event estimation or BSDF sample there); `usize::MAX` for none.
    pub stop_at_vertex: usize,
    /// Record events (false: vertices only, no shadow rays; for prefix re-tracing).
    pub events: bool,
}

/// Traces one path-traced sample of `pixel` with the numbers of `sampler`, recording its
/// vertices and MIS-weighted events into `path` (cleared first). The estimate
/// ([`VertexPath::radiance`]) is that of [`crate::integrator::pt::sample_pixel`] without
/// Russian roulette (pbrt-v4 `PathIntegrator`, Pharr et al. 2023, section 13.4; power
/// heuristic between NEE and BSDF sampling).
pub fn trace<S: Sampler + ?Sized>(
    scene: &Scene,
    camera: &Camera,
    pixel: UVec2,
    sampler: &mut S,
    limit: TraceLimit,
    path: &mut VertexPath,
) {
    path.vertices.clear();
    path.events.clear();
    path.pixel = pixel;
    sampler.start_stream(Stream::Camera);
    let raster = pixel_sample_position(pixel, sampler.next_2d());
    let u_lens = sampler.next_2d();
    let u_time = sampler.next_1d();
    let mut ray = camera.generate_ray(raster, u_lens, u_time);
    path.raster = raster;
    path.ray = Some(ray);
    let lights = scene.lights();
    let mut beta = Vec3::ONE;
    let mut specular_bounce = true; // the camera ray counts emission fully
    let mut prev_pdf = 0.0f32;
    let mut prev_p = ray.origin;
    let mut k = 0usize;
    loop {
        k += 1;
        let Some(si) = scene.intersect(&ray) else {
            let le = lights.environment_le(ray.dir);
            if limit.events && le != Vec3::ZERO {
                let (w, light_pdf) = if specular_bounce {
                    (1.0, 0.0)
                } else {
                    let light_pdf = lights.pdf_environment(ray.dir);
                    (power_heuristic(prev_pdf, light_pdf), light_pdf)
                };
                path.events.push(PathEvent {
                    vertex: k,
                    kind: EventKind::Environment {
                        dir: ray.dir,
                        light_pdf,
                    },
                    value: beta * le * w,
                    end: le * w,
                    mis: w,
                });
            }
            break;
        };
        let bsdf = scene.bsdf(&si);
        let frame = Frame::from_normal(si.ns);
        path.vertices.push(PathVertex {
            si,
            bsdf,
            frame,
            beta,
            out: None,
        });
        if limit.events {
            let le = scene.emitted(&si, si.wo);
            if le != Vec3::ZERO {
                let (w, light_pdf) = if specular_bounce {
                    (1.0, 0.0)
                } else if let Some(light) = lights.light_of_triangle(si.triangle) {
                    let light_pdf = lights.pdf_li(prev_p, light, si.p);
                    (power_heuristic(prev_pdf, light_pdf), light_pdf)
                } else {
                    (0.0, 0.0)
                };
                if w > 0.0 {
                    path.events.push(PathEvent {
                        vertex: k,
                        kind: EventKind::Emission { light_pdf },
                        value: beta * le * w,
                        end: le * w,
                        mis: w,
                    });
                }
            }
        }
        if k >= limit.stop_at_vertex || k > limit.max_depth as usize {
            break;
        }
        let u_light = sampler.next_1d();
        let u_light_pos = sampler.next_2d();
        let u_lobe = sampler.next_1d();
        let u_bsdf = sampler.next_2d();
        let _u_roulette = sampler.next_1d();
        let wo = frame.to_local(si.wo);
        if wo.z == 0.0 {
            break;
        }
        if limit.events && !bsdf.is_specular() {
            if let Some((end, mis, ls)) =
                nee(scene, &si, &bsdf, &frame, si.wo, u_light, u_light_pos)
            {
                path.events.push(PathEvent {
                    vertex: k,
                    kind: EventKind::Nee(ls),
                    value: beta * end,
                    end,
                    mis,
                });
            }
        }
        let Some(bs) = bsdf.sample(wo, u_lobe, u_bsdf, TransportMode::Radiance) else {
            break;
        };
        if bs.pdf.is_nan() || bs.pdf <= 0.0 {
            break;
        }
        let Some(dir) = frame.to_world(bs.wi).try_normalize() else {
            break;
        };
        let weight = bs.f * (bs.wi.z.abs() / bs.pdf);
        if let Some(v) = path.vertices.last_mut() {
            v.out = Some(Scatter {
                wi: dir,
                pdf: bs.pdf,
                weight,
                is_specular: bs.is_specular,
            });
        }
        if !shading_consistent(si.wo, dir, si.ng, si.ns) {
            break;
        }
        beta *= weight;
        specular_bounce = bs.is_specular;
        prev_pdf = bs.pdf;
        prev_p = si.p;
        ray = si.spawn_ray(dir, ray.time);
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            break;
        }
    }
}

/// Next-event estimation at a surface point seen from `wo_world` with the light numbers
/// `u_light`, `u_pos`: `(f |cos| L_e w / pdf, w, light sample)` if the light is visible and
/// contributes. The light sample depends on the reference point only through its direction
/// and pdf (area lights are sampled uniformly by area), so the same numbers give the same
/// light point from a moved reference point: the static light vertex of a reconnection.
#[inline]
pub fn nee(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    frame: &Frame,
    wo_world: Vec3A,
    u_light: f32,
    u_pos: Vec2,
) -> Option<(Vec3, f32, LightSample)> {
    let ls = scene.sample_li(si.p, u_light, u_pos)?;
    let (end, w) = nee_towards(scene, si, bsdf, frame, wo_world, &ls, true)?;
    Some((end, w, ls))
}

/// The NEE term `f |cos| L_e w / pdf` and MIS weight `w` of the light sample `ls` seen from
/// `si` along `wo_world`; with `check_visibility` a shadow ray is cast. `None` if it carries
/// nothing.
#[inline]
pub fn nee_towards(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    frame: &Frame,
    wo_world: Vec3A,
    ls: &LightSample,
    check_visibility: bool,
) -> Option<(Vec3, f32)> {
    if ls.radiance == Vec3::ZERO || !positive(ls.pdf) {
        return None;
    }
    if !shading_consistent(wo_world, ls.wi, si.ng, si.ns) {
        return None;
    }
    let wo = frame.to_local(wo_world);
    let wi = frame.to_local(ls.wi);
    let f = bsdf.eval(wo, wi, TransportMode::Radiance) * wi.z.abs();
    if f == Vec3::ZERO {
        return None;
    }
    if check_visibility {
        let visible = if ls.infinite {
            scene.unoccluded_towards(si, ls.wi)
        } else {
            scene.unoccluded(si, ls.p)
        };
        if !visible {
            return None;
        }
    }
    let w = if ls.delta {
        1.0
    } else {
        power_heuristic(ls.pdf, bsdf.pdf(wo, wi, TransportMode::Radiance))
    };
    Some((f * ls.radiance * (w / ls.pdf), w))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::IndependentSampler;

    /// Without roulette (depth 3 < ROULETTE_DEPTH + 1), the recorded events sum to `pt`'s
    /// estimate for the same numbers, and each vertex's throughput is the product of the
    /// previous scatter weights.
    #[test]
    fn events_sum_to_the_path_tracer_estimate() {
        let scene = Scene::cornell_box(16, 16);
        let camera = *scene.camera();
        let mut s = IndependentSampler::new(5);
        let mut path = VertexPath::default();
        let limit = TraceLimit {
            max_depth: 3,
            stop_at_vertex: usize::MAX,
            events: true,
        };
        let mut nonzero = 0;
        for i in 0..512u32 {
            let pixel = UVec2::new(i % 16, (i / 16) % 16);
            s.start_pixel_sample(u64::from(i), 0);
            trace(&scene, &camera, pixel, &mut s, limit, &mut path);
            s.start_pixel_sample(u64::from(i), 0);
            let (p, l) = crate::integrator::pt::sample_pixel(&scene, &camera, pixel, &mut s, 3);
            assert_eq!(p, path.raster);
            let r = path.radiance();
            assert!(
                (r - l).abs().max_element() <= 1e-4 * (1.0 + l.max_element()),
                "{r} {l}"
            );
            nonzero += usize::from(l != Vec3::ZERO);
            let mut beta = Vec3::ONE;
            for v in &path.vertices {
                assert!((v.beta - beta).abs().max_element() <= 1e-5 * beta.max_element());
                if let Some(out) = v.out {
                    beta *= out.weight;
                }
            }
        }
        assert!(nonzero > 100);
    }
}
