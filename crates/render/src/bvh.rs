//! Ray queries against a triangle mesh through an obvhs compressed wide BVH (CWBVH):
//! closest hit with barycentrics, any hit for shadow rays, both optionally with a per-hit
//! acceptance filter (alpha-mask cut-outs), and robust ray-origin offsetting.

use std::time::Duration;

use glam::{Vec2, Vec3A};
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as BvhRay, RayHit};
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

use crate::mesh::Mesh;

/// The closest intersection of a ray with the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (distance, for a unit direction).
    pub t: f32,
    /// Index of the triangle in the mesh.
    pub triangle: u32,
    /// Barycentric coordinates `(b1, b2)` of the hit: the point is
    /// `(1 - b1 - b2) p0 + b1 p1 + b2 p2`.
    pub barycentrics: Vec2,
}

/// A CWBVH over the triangles of a [`Mesh`], with the triangles stored in BVH leaf order so a
/// leaf index addresses its triangle directly.
#[derive(Clone, Default)]
pub struct Bvh {
    bvh: Option<CwBvh>,
    /// Triangles in leaf order (precomputed edges for Möller-Trumbore).
    tris: Vec<RtTriangle>,
    /// Mesh triangle index of each leaf slot.
    tri_ids: Vec<u32>,
}

impl std::fmt::Debug for Bvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bvh")
            .field("nodes", &self.bvh.as_ref().map_or(0, |b| b.nodes.len()))
            .field("triangles", &self.tris.len())
            .finish()
    }
}

/// `gamma(n) = n eps / (1 - n eps)`: the relative error bound of `n` rounded f32 operations
/// (pbrt-v4, section 6.8.1).
#[inline]
#[must_use]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5 * n as f32;
    e / (1.0 - e)
}

impl Bvh {
    /// Builds the BVH over every triangle of `mesh` with obvhs' `medium_build` preset. The mesh
    /// should have been cleaned with [`Mesh::remove_invalid`]; degenerate triangles are skipped
    /// anyway, and an empty mesh gives a BVH that every ray misses.
    #[must_use]
    pub fn build(mesh: &Mesh) -> Self {
        let mut tris = Vec::with_capacity(mesh.triangle_count());
        let mut ids = Vec::with_capacity(mesh.triangle_count());
        for t in 0..mesh.triangle_count() {
            let [v0, v1, v2] = mesh.vertices(t);
            let area2 = (v1 - v0).cross(v2 - v0).length_squared();
            if v0.is_finite() && v1.is_finite() && v2.is_finite() && area2 > 0.0 {
                tris.push(Triangle { v0, v1, v2 });
                ids.push(t as u32);
            }
        }
        if tris.is_empty() {
            return Self::default();
        }
        let bvh = build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let rt = bvh
            .primitive_indices
            .iter()
            .map(|&i| RtTriangle::from(&tris[i as usize]))
            .collect();
        let tri_ids = bvh
            .primitive_indices
            .iter()
            .map(|&i| ids[i as usize])
            .collect();
        Self {
            bvh: Some(bvh),
            tris: rt,
            tri_ids,
        }
    }

    /// True if the BVH holds no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.bvh.is_none()
    }

    /// The closest hit of the ray `origin + t dir`, `0 <= t <= t_max`, or `None`.
    /// Non-finite rays miss.
    #[inline]
    #[must_use]
    pub fn intersect(&self, origin: Vec3A, dir: Vec3A, t_max: f32) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        if !(origin.is_finite() && dir.is_finite()) || dir == Vec3A::ZERO || t_max.is_nan() {
            return None;
        }
        let (traversal, exact) = query_rays(origin, dir, t_max);
        let mut hit = RayHit::none();
        // The triangle test uses the exact ray (so ray offsetting stays valid); its distance
        // is shifted into the backed-off traversal ray's parametrisation.
        let found = bvh.ray_traverse(traversal, &mut hit, |_, id| {
            self.tris[id].intersect(&exact) + BACKOFF
        });
        if !found {
            return None;
        }
        let slot = hit.primitive_id as usize;
        let tri = &self.tris[slot];
        Some(Hit {
            t: (hit.t - BACKOFF).max(0.0),
            triangle: self.tri_ids[slot],
            barycentrics: barycentrics(tri, origin, dir),
        })
    }

    /// True if any triangle intersects the segment `origin + t dir`, `0 <= t <= t_max`.
    /// Non-finite rays are reported as occluded (nothing is transported along them).
    #[inline]
    #[must_use]
    pub fn occluded(&self, origin: Vec3A, dir: Vec3A, t_max: f32) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        if !(origin.is_finite() && dir.is_finite()) || dir == Vec3A::ZERO || t_max.is_nan() {
            return true;
        }
        let (traversal, exact) = query_rays(origin, dir, t_max);
        !bvh.ray_traverse_miss(traversal, |_, id| {
            if self.tris[id].intersect(&exact).is_finite() {
                0.0
            } else {
                f32::INFINITY
            }
        })
    }

    /// As [`Bvh::intersect`], but a triangle hit counts only if `accept(triangle, barycentrics)`
    /// is true (an any-hit filter: alpha-mask cut-outs let rays through). `accept` is called
    /// only for hits closer than the closest accepted hit so far, so the result is the closest
    /// accepted hit in one traversal.
    #[inline]
    #[must_use]
    pub fn intersect_filtered(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        t_max: f32,
        mut accept: impl FnMut(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        if !(origin.is_finite() && dir.is_finite()) || dir == Vec3A::ZERO || t_max.is_nan() {
            return None;
        }
        let (traversal, exact) = query_rays(origin, dir, t_max);
        let mut hit = RayHit::none();
        let found = bvh.ray_traverse(traversal, &mut hit, |ray, id| {
            let t = self.tris[id].intersect(&exact) + BACKOFF;
            if t < ray.tmax && accept(self.tri_ids[id], barycentrics(&self.tris[id], origin, dir)) {
                t
            } else {
                f32::INFINITY
            }
        });
        if !found {
            return None;
        }
        let slot = hit.primitive_id as usize;
        let tri = &self.tris[slot];
        Some(Hit {
            t: (hit.t - BACKOFF).max(0.0),
            triangle: self.tri_ids[slot],
            barycentrics: barycentrics(tri, origin, dir),
        })
    }

    /// As [`Bvh::occluded`], but only triangle hits with `accept(triangle, barycentrics)` true
    /// block the segment.
    #[inline]
    #[must_use]
    pub fn occluded_filtered(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        t_max: f32,
        mut accept: impl FnMut(u32, Vec2) -> bool,
    ) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        if !(origin.is_finite() && dir.is_finite()) || dir == Vec3A::ZERO || t_max.is_nan() {
            return true;
        }
        let (traversal, exact) = query_rays(origin, dir, t_max);
        !bvh.ray_traverse_miss(traversal, |_, id| {
            let tri = &self.tris[id];
            if tri.intersect(&exact).is_finite()
                && accept(self.tri_ids[id], barycentrics(tri, origin, dir))
            {
                0.0
            } else {
                f32::INFINITY
            }
        })
    }
}

/// How far (in units of `t`) a query ray starts behind its true origin.
///
/// obvhs 0.4's CWBVH traversal clamps node entry distances to at least `1e-4`
/// (`cwbvh/node.rs`, `EPSILON`), so a triangle closer than that to the ray origin is never
/// tested: rays leaving a point near an inside corner passed through the neighbouring wall
/// (found by `tests/mlt_convergence.rs`: light leaking out of a closed box). The *traversal*
/// ray therefore starts `BACKOFF > 1e-4` behind the origin, so the clamp lands before the
/// true origin. Triangles are still tested against the exact ray (`tmin = 0` at the true
/// origin): testing them against the backed-off ray with `tmin = BACKOFF` puts the rounding
/// error of the test at the scale of the scene's coordinates, above the ray-origin offsets of
/// [`offset_ray_origin`], and shadow rays then hit their own surface (found by
/// `tests/bdpt_vs_pt.rs`: PT's direct light came out far too dark on the Cornell box floor).
const BACKOFF: f32 = 2.5e-4;

/// The obvhs rays for the segment `origin + t dir`, `0 <= t <= t_max`: the traversal ray,
/// started [`BACKOFF`] behind `origin` (so its parameter is `t + BACKOFF`), and the exact ray
/// for the triangle tests.
#[inline]
fn query_rays(origin: Vec3A, dir: Vec3A, t_max: f32) -> (BvhRay, BvhRay) {
    let dir = positive_zeros(dir);
    // `tmin` just above zero: a ray leaving a surface that lies exactly in a coordinate plane
    // through 0 (zero error bound, offset by one ulp) re-hits it at `t = ±0`, which
    // `t >= 0` would accept.
    let exact = BvhRay::new(origin, dir, f32::MIN_POSITIVE, t_max);
    let mut traversal = exact;
    traversal.origin = origin - dir * BACKOFF;
    traversal.tmax = t_max + BACKOFF;
    (traversal, exact)
}

/// Replaces `-0.0` components by `+0.0`: obvhs 0.4 derives the traversal octant from
/// `d < 0` but the inverse direction from the sign bit, so a `-0.0` component makes an
/// axis-aligned ray miss everything.
#[inline]
fn positive_zeros(d: Vec3A) -> Vec3A {
    d + Vec3A::ZERO
}

/// Barycentrics `(b1, b2)` of the ray's intersection with the triangle's plane, in the same
/// arithmetic as obvhs' Möller-Trumbore test (`e1 = v0 - v1`, `e2 = v2 - v0`).
#[inline]
fn barycentrics(tri: &RtTriangle, origin: Vec3A, dir: Vec3A) -> Vec2 {
    let c = tri.v0 - origin;
    let r = dir.cross(c);
    let inv_det = 1.0 / tri.ng.dot(dir);
    let b1 = r.dot(tri.e2) * inv_det;
    let b2 = r.dot(tri.e1) * inv_det;
    let b = Vec2::new(b1, b2);
    if b.is_finite() {
        b.clamp(Vec2::ZERO, Vec2::ONE)
    } else {
        Vec2::splat(1.0 / 3.0)
    }
}

/// Offsets a surface point `p` (absolute error bound `p_error` per axis) along the geometric
/// normal `n` to the side of direction `w`, so a ray leaving in direction `w` cannot re-hit the
/// surface it starts on (pbrt-v4 `OffsetRayOrigin`, section 6.8.6). Every component is then
/// rounded one ulp away from `p`.
#[inline]
#[must_use]
pub fn offset_ray_origin(p: Vec3A, p_error: Vec3A, n: Vec3A, w: Vec3A) -> Vec3A {
    let d = n.abs().dot(p_error);
    let mut offset = n * d;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let po = p + offset;
    let step = |v: f32, o: f32| {
        if o > 0.0 {
            next_float_up(v)
        } else if o < 0.0 {
            next_float_down(v)
        } else {
            v
        }
    };
    Vec3A::new(
        step(po.x, offset.x),
        step(po.y, offset.y),
        step(po.z, offset.z),
    )
}

/// The smallest f32 greater than `v` (`v` itself for +inf and NaN).
#[inline]
#[must_use]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    f32::from_bits(if v >= 0.0 { bits + 1 } else { bits - 1 })
}

/// The largest f32 smaller than `v` (`v` itself for -inf and NaN).
#[inline]
#[must_use]
pub fn next_float_down(v: f32) -> f32 {
    if v.is_infinite() && v < 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == 0.0 { -0.0 } else { v };
    let bits = v.to_bits();
    f32::from_bits(if v > 0.0 { bits - 1 } else { bits + 1 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::{IndependentSampler, Sampler};

    fn quad_mesh() -> Mesh {
        let mut m = Mesh::new();
        m.add_quad(
            [
                Vec3A::new(-1.0, -1.0, 0.0),
                Vec3A::new(1.0, -1.0, 0.0),
                Vec3A::new(1.0, 1.0, 0.0),
                Vec3A::new(-1.0, 1.0, 0.0),
            ],
            0,
        );
        m
    }

    #[test]
    fn closest_hit_and_barycentrics() {
        let m = quad_mesh();
        let bvh = Bvh::build(&m);
        let o = Vec3A::new(0.3, -0.2, 2.0);
        let hit = bvh.intersect(o, -Vec3A::Z, f32::INFINITY).unwrap();
        assert!((hit.t - 2.0).abs() < 1e-6);
        let [p0, p1, p2] = m.vertices(hit.triangle as usize);
        let b = hit.barycentrics;
        let p = p0 * (1.0 - b.x - b.y) + p1 * b.x + p2 * b.y;
        assert!((p - (o - Vec3A::Z * 2.0)).length() < 1e-5, "{p}");
        assert!(bvh.intersect(o, Vec3A::Z, f32::INFINITY).is_none());
        assert!(bvh.intersect(o, -Vec3A::Z, 1.5).is_none());
        assert!(bvh.occluded(o, -Vec3A::Z, 2.5));
        assert!(!bvh.occluded(o, -Vec3A::Z, 1.5));
        assert!(bvh
            .intersect(Vec3A::splat(f32::NAN), -Vec3A::Z, 9.0)
            .is_none());
    }

    /// Hits closer than obvhs' internal 1e-4 entry clamp are still found (and occlusion too):
    /// without [`BACKOFF`] rays from near an inside corner passed through the adjacent wall.
    #[test]
    fn very_close_hits_are_found() {
        let bvh = Bvh::build(&quad_mesh());
        for t in [1e-3f32, 1.25e-4, 6.25e-5, 1.25e-5, 1e-6] {
            let o = Vec3A::new(0.3, -0.2, t);
            let hit = bvh
                .intersect(o, -Vec3A::Z, f32::INFINITY)
                .expect("close hit");
            assert!((hit.t - t).abs() < 1e-6, "t = {t}: got {}", hit.t);
            assert!(bvh.occluded(o, -Vec3A::Z, 1.0), "t = {t}");
        }
        // Nothing behind the origin is reported.
        assert!(bvh
            .intersect(Vec3A::new(0.3, -0.2, -1e-5), -Vec3A::Z, f32::INFINITY)
            .is_none());
    }

    #[test]
    fn empty_and_degenerate_meshes() {
        let empty = Bvh::build(&Mesh::new());
        assert!(empty.is_empty());
        assert!(empty.intersect(Vec3A::ZERO, Vec3A::X, 1.0).is_none());
        assert!(!empty.occluded(Vec3A::ZERO, Vec3A::X, 1.0));
        let mut m = Mesh::new();
        let a = m.add_vertex(Vec3A::ZERO, Vec3A::ZERO, Vec2::ZERO);
        let b = m.add_vertex(Vec3A::X, Vec3A::ZERO, Vec2::ZERO);
        m.add_triangle([a, b, b], 0);
        assert!(Bvh::build(&m).is_empty());
    }

    #[test]
    fn offset_origins_do_not_self_intersect() {
        // A tilted, far-from-origin quad: rays leaving it in random directions of the normal's
        // hemisphere must never hit it again.
        let mut m = Mesh::new();
        let base = Vec3A::new(1000.0, -500.0, 250.0);
        let (u, v) = (Vec3A::new(3.0, 1.0, 0.5), Vec3A::new(-0.5, 2.0, 3.0));
        m.add_quad([base, base + u, base + u + v, base + v], 0);
        let bvh = Bvh::build(&m);
        let n = u.cross(v).normalize();
        let mut s = IndependentSampler::new(5);
        let mut self_hits = 0;
        for i in 0..20_000 {
            s.start_pixel_sample(i, 0);
            let (a, b) = (s.next_1d(), s.next_1d());
            let o = base + n * 10.0 + u * a + v * b;
            let hit = bvh.intersect(o, -n, f32::INFINITY).unwrap();
            let [p0, p1, p2] = m.vertices(hit.triangle as usize);
            let bc = hit.barycentrics;
            let w0 = 1.0 - bc.x - bc.y;
            let p = p0 * w0 + p1 * bc.x + p2 * bc.y;
            let err = (p0 * w0).abs() + (p1 * bc.x).abs() + (p2 * bc.y).abs();
            let err = err * gamma(7);
            let d = s.next_2d();
            let dir = (n + Vec3A::new(d.x - 0.5, d.y - 0.5, 0.3) * 1.9).normalize();
            let dir = if dir.dot(n) <= 0.0 { n } else { dir };
            let po = offset_ray_origin(p, err, n, dir);
            if bvh.intersect(po, dir, f32::INFINITY).is_some() {
                self_hits += 1;
            }
        }
        assert_eq!(self_hits, 0);
    }

    /// The filter removes hits: the closest accepted hit is found behind rejected ones, a
    /// rejected hit does not occlude, and an accept-all filter equals the unfiltered query.
    #[test]
    fn filtered_queries_skip_rejected_hits() {
        let mut m = quad_mesh(); // z = 0, triangles 0 and 1
        let q = |z: f32| {
            [
                Vec3A::new(-1.0, -1.0, z),
                Vec3A::new(1.0, -1.0, z),
                Vec3A::new(1.0, 1.0, z),
                Vec3A::new(-1.0, 1.0, z),
            ]
        };
        m.add_quad(q(1.0), 1); // triangles 2 and 3, in front
        let bvh = Bvh::build(&m);
        let o = Vec3A::new(0.3, -0.2, 2.0);
        let all = bvh.intersect_filtered(o, -Vec3A::Z, f32::INFINITY, |_, _| true);
        assert_eq!(all, bvh.intersect(o, -Vec3A::Z, f32::INFINITY));
        assert!(all.unwrap().triangle >= 2);
        // Reject the front quad: the back one is hit, at t = 2.
        let mut calls = Vec::new();
        let back = bvh
            .intersect_filtered(o, -Vec3A::Z, f32::INFINITY, |t, b| {
                calls.push((t, b));
                t < 2
            })
            .unwrap();
        assert!(back.triangle < 2 && (back.t - 2.0).abs() < 1e-6);
        // The filter saw the front triangle with its barycentrics.
        let (front_tri, front_b) = *calls.iter().find(|(t, _)| *t >= 2).unwrap();
        let [p0, p1, p2] = m.vertices(front_tri as usize);
        let p = p0 * (1.0 - front_b.x - front_b.y) + p1 * front_b.x + p2 * front_b.y;
        assert!((p - Vec3A::new(0.3, -0.2, 1.0)).length() < 1e-5, "{p}");
        // Rejecting everything: a miss, not occluded.
        assert!(bvh
            .intersect_filtered(o, -Vec3A::Z, f32::INFINITY, |_, _| false)
            .is_none());
        assert!(!bvh.occluded_filtered(o, -Vec3A::Z, 5.0, |_, _| false));
        assert!(bvh.occluded_filtered(o, -Vec3A::Z, 5.0, |t, _| t < 2));
        assert!(!bvh.occluded_filtered(o, -Vec3A::Z, 1.5, |t, _| t < 2));
        assert!(bvh.occluded_filtered(o, -Vec3A::Z, 1.5, |_, _| true));
    }

    #[test]
    fn next_float() {
        assert!(next_float_up(1.0) > 1.0);
        assert!(next_float_down(1.0) < 1.0);
        assert!(next_float_up(0.0) > 0.0);
        assert!(next_float_down(0.0) < 0.0);
        assert!(next_float_up(-1.0) > -1.0);
        assert_eq!(next_float_up(f32::INFINITY), f32::INFINITY);
    }
}
