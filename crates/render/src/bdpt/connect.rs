//! Connecting a light subpath prefix to a camera subpath prefix: strategy (s, t) and its MIS
//! weight (Veach 1997, section 10.2-10.4; pbrt-v3 `ConnectBDPT` and `MISWeight`).

use glam::{Vec2, Vec3};

use super::scene_api::{self, SceneRef};
use super::vertex::{geometry_term, visible, Vertex, VertexKind};
use crate::material::TransportMode;
use crate::sampler::{Sampler, Stream};

/// The multiple importance sampling heuristic combining the strategies of one path length.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MisHeuristic {
    /// Balance heuristic (`beta = 1`).
    Balance,
    /// Power heuristic with exponent 2 (Veach 1997, section 9.2.4).
    #[default]
    Power,
}

/// The result of one connection strategy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Connection {
    /// MIS-weighted contribution (zero if the strategy produced nothing).
    pub l: Vec3,
    /// Raster position for light-tracing strategies (t = 1); `None`: the camera path's.
    pub p_raster: Option<Vec2>,
    /// The MIS weight that was applied.
    pub mis_weight: f32,
}

impl Connection {
    const ZERO: Connection = Connection {
        l: Vec3::ZERO,
        p_raster: None,
        mis_weight: 0.0,
    };
}

/// Evaluates strategy (s, t): `s` light vertices, `t` camera vertices. Random numbers are drawn
/// from [`Stream::Connection`] for `s = 1` (a fresh light sample) and `t = 1` (a lens sample).
#[allow(clippy::too_many_arguments)]
pub fn connect<S: Sampler + ?Sized>(
    scene: SceneRef<'_>,
    light: &mut [Vertex],
    camera: &mut [Vertex],
    s: usize,
    t: usize,
    sampler: &mut S,
    heuristic: MisHeuristic,
    apply_mis: bool,
) -> Connection {
    if t == 0 || (t > 1 && s != 0 && camera[t - 1].kind == VertexKind::Light) {
        return Connection::ZERO;
    }
    let mut sampled: Option<Vertex> = None;
    let mut p_raster = None;
    let mut l = Vec3::ZERO;
    if s == 0 {
        let pt = &camera[t - 1];
        if pt.is_emissive() && t >= 2 {
            l = pt.emitted_towards(scene, camera[t - 2].p) * pt.beta;
        }
    } else if t == 1 {
        let qs = &light[s - 1];
        if qs.is_connectible() {
            sampler.start_stream(Stream::Connection);
            let u = sampler.next_2d();
            if let Some(cs) = scene_api::camera_sample_wi(scene, qs.p, u, qs.time) {
                if cs.pdf > 0.0 && cs.importance > 0.0 {
                    let forward = scene_api::camera_forward(scene, qs.time);
                    let cam = Vertex::camera(
                        cs.p_lens,
                        forward,
                        Vec3::splat(cs.importance / cs.pdf),
                        qs.time,
                    );
                    let mut contrib = qs.beta * qs_f(qs, &cam) * cam.beta;
                    if qs.on_surface() && qs.kind == VertexKind::Surface {
                        contrib *= cs.wi.dot(qs.ns()).abs();
                    }
                    if contrib != Vec3::ZERO && visible(scene, qs, &cam) {
                        l = contrib;
                        p_raster = Some(cs.p_raster);
                        sampled = Some(cam);
                    }
                }
            }
        }
    } else if s == 1 {
        let pt = &camera[t - 1];
        if pt.is_connectible() {
            sampler.start_stream(Stream::Connection);
            let u_light = sampler.next_1d_discrete();
            let u_pos = sampler.next_2d();
            if let Some(ls) = scene_api::sample_li(scene, pt.p, u_light, u_pos) {
                if ls.radiance != Vec3::ZERO {
                    // ls.pdf: solid-angle density at pt (selection only for delta lights).
                    let mut v =
                        Vertex::light(ls.p, ls.n, ls.light, ls.radiance / ls.pdf, 0.0, pt.time);
                    v.barycentrics = ls.barycentrics;
                    v.infinite = ls.infinite;
                    v.delta_light = ls.delta;
                    v.pdf_fwd = v.pdf_light_origin(scene, pt);
                    let mut contrib = pt.beta * pt.f(&v, TransportMode::Radiance) * v.beta;
                    if pt.kind == VertexKind::Surface {
                        contrib *= ls.wi.dot(pt.ns()).abs();
                    }
                    if contrib != Vec3::ZERO && visible(scene, pt, &v) {
                        l = contrib;
                        sampled = Some(v);
                    }
                }
            }
        }
    } else {
        let (qs, pt) = (&light[s - 1], &camera[t - 1]);
        if qs.is_connectible() && pt.is_connectible() {
            let contrib = qs.beta * qs_f(qs, pt) * pt.f(qs, TransportMode::Radiance) * pt.beta;
            if contrib != Vec3::ZERO {
                l = contrib * geometry_term(scene, qs, pt);
            }
        }
    }
    if l == Vec3::ZERO || !l.is_finite() {
        return Connection::ZERO;
    }
    let w = if apply_mis {
        mis_weight(scene, light, camera, sampled.as_ref(), s, t, heuristic)
    } else {
        1.0
    };
    Connection {
        l: l * w,
        p_raster,
        mis_weight: w,
    }
}

/// BSDF at the end of a light subpath towards `next` (light vertices are never connected
/// through `f`: strategies with s = 1 resample the light point).
#[inline]
fn qs_f(qs: &Vertex, next: &Vertex) -> Vec3 {
    qs.f(next, TransportMode::Importance)
}

#[inline]
fn remap0(f: f32) -> f32 {
    if f != 0.0 {
        f
    } else {
        1.0
    }
}

/// The MIS weight of strategy (s, t) for the path formed by the two prefixes, computed from
/// the stored forward/reverse area densities without re-tracing (pbrt-v3 `MISWeight`, with
/// the power heuristic as an option). `sampled` replaces the connection endpoint drawn afresh
/// for s = 1 or t = 1. Vertices on delta lobes carry their discrete lobe probability as
/// densities unless the subpaths were built with [`super::SpecularDensities::Zeroed`]
/// (pbrt-v3's convention, whose zeros `remap0` skips; `bdpt::subpath`, "Specular chains").
fn mis_weight(
    scene: SceneRef<'_>,
    light: &mut [Vertex],
    camera: &mut [Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
    heuristic: MisHeuristic,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    // Work on copies of the four vertices whose densities depend on the strategy.
    let mut qs = if s > 0 {
        Some(if s == 1 {
            *sampled.unwrap_or(&light[0])
        } else {
            light[s - 1]
        })
    } else {
        None
    };
    let mut pt = if t == 1 {
        *sampled.unwrap_or(&camera[0])
    } else {
        camera[t - 1]
    };
    let qs_minus = if s > 1 { Some(light[s - 2]) } else { None };
    let pt_minus = if t > 1 { Some(camera[t - 2]) } else { None };

    pt.delta = false;
    if let Some(q) = qs.as_mut() {
        q.delta = false;
    }
    // pt's reverse density: sampled from qs (or as a light origin when s = 0).
    pt.pdf_rev = match (&qs, &pt_minus) {
        (Some(q), _) => q.pdf(scene, qs_minus.as_ref(), &pt),
        (None, Some(pm)) => pt.pdf_light_origin(scene, pm),
        (None, None) => 0.0,
    };
    let pt_minus_rev = pt_minus.map(|pm| match &qs {
        Some(q) => pt.pdf(scene, Some(q), &pm),
        None => pt.pdf_light(scene, &pm),
    });
    let qs_rev = qs.map(|q| pt.pdf(scene, pt_minus.as_ref(), &q));
    let qs_minus_rev = match (&qs, &qs_minus) {
        (Some(q), Some(qm)) => Some(q.pdf(scene, Some(&pt), qm)),
        _ => None,
    };
    if let (Some(q), Some(r)) = (qs.as_mut(), qs_rev) {
        q.pdf_rev = r;
    }

    let pow = |r: f32| match heuristic {
        MisHeuristic::Balance => r,
        MisHeuristic::Power => r * r,
    };
    let mut sum = 0.0f32;
    // Camera side: vertices t-1 .. 1.
    let mut ri = 1.0f32;
    for i in (1..t).rev() {
        let (fwd, rev, delta) = if i == t - 1 {
            (pt.pdf_fwd, pt.pdf_rev, pt.delta)
        } else if i == t - 2 {
            let v = &camera[i];
            (v.pdf_fwd, pt_minus_rev.unwrap_or(v.pdf_rev), v.delta)
        } else {
            let v = &camera[i];
            (v.pdf_fwd, v.pdf_rev, v.delta)
        };
        let prev_delta = camera[i - 1].delta;
        ri *= remap0(rev) / remap0(fwd);
        if !delta && !prev_delta {
            sum += pow(ri);
        }
    }
    // Light side: vertices s-1 .. 0.
    ri = 1.0;
    for i in (0..s).rev() {
        let (fwd, rev, delta) = if i == s - 1 {
            qs.as_ref()
                .map_or((0.0, 0.0, false), |q| (q.pdf_fwd, q.pdf_rev, q.delta))
        } else if i + 2 == s {
            let v = &light[i];
            (v.pdf_fwd, qs_minus_rev.unwrap_or(v.pdf_rev), v.delta)
        } else {
            let v = &light[i];
            (v.pdf_fwd, v.pdf_rev, v.delta)
        };
        // The strategy with i light vertices is impossible if the vertex before is delta,
        // or, for i = 0 (the camera path hits the light), if the light is a delta light.
        let prev_delta = if i > 0 {
            light[i - 1].delta
        } else if s == 1 {
            qs.as_ref().is_some_and(|q| q.delta_light)
        } else {
            light[0].delta_light
        };
        ri *= remap0(rev) / remap0(fwd);
        if !delta && !prev_delta {
            sum += pow(ri);
        }
    }
    1.0 / (1.0 + sum)
}
