//! Ray queries on a [`Scene`]: the closest hit as a [`SurfaceInteraction`] (alpha cut-outs
//! skipped, normal maps applied), texture coordinates, the BSDF at a hit, and shadow-ray
//! visibility.

use glam::{Vec2, Vec3, Vec3A};

use super::{Scene, TextureRef};
use crate::bvh::{gamma, offset_ray_origin};
use crate::camera::Ray;
use crate::material::Bsdf;

/// A ray-surface intersection with everything shading needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceInteraction {
    /// Hit point.
    pub p: Vec3A,
    /// Conservative absolute error bound of `p` per axis (for ray offsetting).
    pub p_error: Vec3A,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Unit geometric normal of the triangle's front side (glTF counter-clockwise winding).
    pub ng: Vec3A,
    /// Unit shading normal: the interpolated vertex normals (`ng` when the mesh has none) in
    /// the hemisphere of `ng`, perturbed by the material's normal map if it has one (then kept
    /// at least [`MIN_SHADING_COS`] inside the hemisphere of `ng`).
    pub ns: Vec3A,
    /// Interpolated texture coordinates (`TEXCOORD_0`; see [`Scene::tex_coord`] for set 1).
    pub uv: Vec2,
    /// Barycentrics `(b1, b2)` of the hit.
    pub barycentrics: Vec2,
    /// Mesh triangle index.
    pub triangle: u32,
    /// Material index into [`Scene::materials`].
    pub material: u32,
    /// Unit direction back along the incoming ray (`-ray.dir`).
    pub wo: Vec3A,
}

impl SurfaceInteraction {
    /// A ray leaving the surface in direction `dir`, its origin offset to the side of `dir` so
    /// it cannot re-hit this surface.
    #[inline]
    #[must_use]
    pub fn spawn_ray(&self, dir: Vec3A, time: f32) -> Ray {
        Ray {
            origin: offset_ray_origin(self.p, self.p_error, self.ng, dir),
            dir,
            time,
        }
    }
}

/// Relative shortening of shadow rays at their far end (the end point is on another surface
/// whose error bound is unknown).
const SHADOW_EPSILON: f32 = 1e-4;

/// The smallest cosine a normal-mapped shading normal keeps with the geometric normal: a
/// normal map tilting it further is pulled back towards the geometric normal.
pub const MIN_SHADING_COS: f32 = 0.01;

/// Keeps a perturbed unit shading normal `n` usable: pushed (towards `ng`) back to at least
/// [`MIN_SHADING_COS`] inside the hemisphere of the geometric normal `ng`. The result depends
/// on the surface point only, not on the direction it is seen from, so every integrator and
/// every strategy of a bidirectional one sees the same shading frame at a point. (A view
/// direction below a strongly tilted shading horizon then sees a dark surface, as in pbrt.)
/// `None` if the result is not finite.
#[inline]
fn valid_shading_normal(n: Vec3A, ng: Vec3A) -> Option<Vec3A> {
    let d = n.dot(ng);
    let n = if d < MIN_SHADING_COS {
        (n + ng * (MIN_SHADING_COS - d)).try_normalize()?
    } else {
        n
    };
    n.is_finite().then_some(n)
}

impl Scene {
    /// The closest surface hit by `ray` (any `t > 0`).
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let hit = if self.has_cutouts {
            self.bvh
                .intersect_filtered(ray.origin, ray.dir, f32::INFINITY, |tri, b| {
                    self.surface_exists(tri, b)
                })
        } else {
            self.bvh.intersect(ray.origin, ray.dir, f32::INFINITY)
        }?;
        let tri = hit.triangle as usize;
        let [i0, i1, i2] = self.mesh.triangles[tri].map(|i| i as usize);
        let [p0, p1, p2] = [
            self.mesh.positions[i0],
            self.mesh.positions[i1],
            self.mesh.positions[i2],
        ];
        let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
        let b0 = (1.0 - b1 - b2).max(0.0);
        let p = p0 * b0 + p1 * b1 + p2 * b2;
        let p_error = ((p0 * b0).abs() + (p1 * b1).abs() + (p2 * b2).abs()) * gamma(7);
        let ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let n = &self.mesh.normals;
        let ns = n[i0] * b0 + n[i1] * b1 + n[i2] * b2;
        let ns = match ns.try_normalize() {
            Some(ns) if ns.dot(ng) < 0.0 => -ns,
            Some(ns) => ns,
            None => ng,
        };
        let uv = self.mesh.uvs[i0] * b0 + self.mesh.uvs[i1] * b1 + self.mesh.uvs[i2] * b2;
        let material = self.mesh.material_ids[tri];
        let ns = if self.has_normal_maps {
            match &self.materials[material as usize].normal_texture {
                Some(map) => self.normal_mapped(map, material, tri, hit.barycentrics, ng, ns),
                None => ns,
            }
        } else {
            ns
        };
        Some(SurfaceInteraction {
            p,
            p_error,
            t: hit.t,
            ng,
            ns,
            uv,
            barycentrics: hit.barycentrics,
            triangle: hit.triangle,
            material,
            wo: -ray.dir,
        })
    }

    /// False if triangle `tri` is cut out (alpha mask) at barycentrics `b`.
    #[inline]
    pub(super) fn surface_exists(&self, tri: u32, b: Vec2) -> bool {
        let id = self.mesh.material_ids[tri as usize] as usize;
        if !self.cutout[id] {
            return true;
        }
        let m = &self.materials[id];
        let tri = tri as usize;
        let alpha = m.alpha_at(
            &self.textures,
            self.mesh.tex_coords(tri, b),
            self.mesh.color_at(tri, b).w,
        );
        m.is_opaque_at(alpha)
    }

    /// The shading normal `ns` of triangle `tri` at barycentrics `b` perturbed by the normal
    /// map `map` of material `material` (glTF: tangent-space normal `(2 rgb - 1) x (scale,
    /// scale, 1)`, +X along the tangent, +Y along the bitangent, +Z along `ns`), then kept
    /// valid by [`valid_shading_normal`]. `ns` unchanged when no tangent frame exists.
    #[allow(clippy::too_many_arguments)]
    fn normal_mapped(
        &self,
        map: &TextureRef,
        material: u32,
        tri: usize,
        b: Vec2,
        ng: Vec3A,
        ns: Vec3A,
    ) -> Vec3A {
        let Some(texture) = self.textures.get(map.texture as usize) else {
            return ns;
        };
        let c = texture.sample(map.uv(self.mesh.tex_coords(tri, b)));
        let scale = self.materials[material as usize].normal_scale;
        let local = Vec3A::new(
            (2.0 * c.x - 1.0) * scale,
            (2.0 * c.y - 1.0) * scale,
            2.0 * c.z - 1.0,
        );
        let Some((t, bt)) = self.tangent_frame(tri, b, ns, map.tex_coord) else {
            return ns;
        };
        match (t * local.x + bt * local.y + ns * local.z).try_normalize() {
            Some(n) => valid_shading_normal(n, ng).unwrap_or(ns),
            None => ns,
        }
    }

    /// Unit tangent and bitangent at barycentrics `b` of triangle `tri`, orthogonal to the
    /// unit shading normal `ns`: from the vertex `TANGENT`s if all three vertices have one
    /// (bitangent `= w (ns x tangent)`, glTF), otherwise generated for the triangle from the
    /// UV set `set` (tangent along increasing `u`, bitangent along decreasing `v`, i.e. up in
    /// the image, as glTF normal maps expect). `None` if the UVs are degenerate.
    fn tangent_frame(&self, tri: usize, b: Vec2, ns: Vec3A, set: u32) -> Option<(Vec3A, Vec3A)> {
        let [i0, i1, i2] = self.mesh.triangles[tri].map(|i| i as usize);
        let tangents = &self.mesh.tangents;
        if !tangents.is_empty()
            && [i0, i1, i2]
                .iter()
                .all(|&i| tangents[i].truncate() != Vec3::ZERO)
        {
            let b0 = (1.0 - b.x - b.y).max(0.0);
            let t4 = tangents[i0] * b0 + tangents[i1] * b.x + tangents[i2] * b.y;
            let t = Vec3A::from(t4.truncate());
            if let Some(t) = (t - ns * ns.dot(t)).try_normalize() {
                let w = if t4.w < 0.0 { -1.0 } else { 1.0 };
                return Some((t, ns.cross(t) * w));
            }
        }
        let uvs = if set == 1 && !self.mesh.uvs1.is_empty() {
            &self.mesh.uvs1
        } else {
            &self.mesh.uvs
        };
        let (d1, d2) = (uvs[i1] - uvs[i0], uvs[i2] - uvs[i0]);
        let det = d1.x * d2.y - d1.y * d2.x;
        let p = &self.mesh.positions;
        let (e1, e2) = (p[i1] - p[i0], p[i2] - p[i0]);
        let dpdu = (e1 * d2.y - e2 * d1.y) / det;
        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
        let t = (dpdu - ns * ns.dot(dpdu)).try_normalize()?;
        let bt = ns.cross(t);
        let w = if bt.dot(dpdv) > 0.0 { -1.0 } else { 1.0 };
        Some((t, bt * w))
    }

    /// The texture coordinates of UV set `set` at `si`: `si.uv` for 0, `TEXCOORD_1` for 1
    /// (`TEXCOORD_0` if the mesh has no second set). For
    /// [`Material::emission_at`](super::Material::emission_at) and other
    /// texture lookups by a [`TextureRef::tex_coord`].
    #[inline]
    #[must_use]
    pub fn tex_coord(&self, si: &SurfaceInteraction, set: u32) -> Vec2 {
        if set == 0 {
            si.uv
        } else {
            self.mesh.uv1_at(si.triangle as usize, si.barycentrics)
        }
    }

    /// True if a triangle that is not cut out intersects the segment `origin + t dir`,
    /// `0 <= t <= t_max`.
    #[inline]
    fn segment_blocked(&self, origin: Vec3A, dir: Vec3A, t_max: f32) -> bool {
        if self.has_cutouts {
            self.bvh
                .occluded_filtered(origin, dir, t_max, |tri, b| self.surface_exists(tri, b))
        } else {
            self.bvh.occluded(origin, dir, t_max)
        }
    }

    /// True if nothing blocks the segment from surface point `from` to the point `to` (which
    /// is assumed to lie on a surface: the far end is shortened by a relative epsilon).
    #[inline]
    #[must_use]
    pub fn unoccluded(&self, from: &SurfaceInteraction, to: Vec3A) -> bool {
        let dir = to - from.p;
        let origin = offset_ray_origin(from.p, from.p_error, from.ng, dir);
        let d = to - origin;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return false;
        }
        !self.segment_blocked(origin, d / dist, dist * (1.0 - SHADOW_EPSILON))
    }

    /// True if nothing blocks the segment between two points on surfaces, both ends offset
    /// along their geometric normals (`n_a`, `n_b`; zero for points not on a surface, e.g. a
    /// camera lens).
    #[inline]
    #[must_use]
    pub fn unoccluded_between(&self, a: Vec3A, n_a: Vec3A, b: Vec3A, n_b: Vec3A) -> bool {
        let err = |p: Vec3A| p.abs() * gamma(7) + Vec3A::splat(1e-6);
        let oa = offset_ray_origin(a, err(a), n_a, b - a);
        let ob = offset_ray_origin(b, err(b), n_b, a - b);
        let d = ob - oa;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return false;
        }
        !self.segment_blocked(oa, d / dist, dist * (1.0 - SHADOW_EPSILON))
    }

    /// The BSDF at a surface point (in the local frame of its shading normal): the material's
    /// factors times its textures and the vertex colour
    /// ([`Material::bsdf_at`](super::Material::bsdf_at)).
    #[inline]
    #[must_use]
    pub fn bsdf(&self, si: &SurfaceInteraction) -> Bsdf {
        let id = si.material as usize;
        if let Some(b) = self.bsdfs[id] {
            return b;
        }
        let tri = si.triangle as usize;
        let uvs = [si.uv, self.tex_coord(si, 1)];
        let color = self.mesh.color_at(tri, si.barycentrics).truncate();
        self.materials[id].bsdf_at(&self.textures, uvs, color)
    }

    /// True if nothing blocks the ray from surface point `from` in direction `dir` to
    /// infinity (shadow rays towards infinite lights).
    #[inline]
    #[must_use]
    pub fn unoccluded_towards(&self, from: &SurfaceInteraction, dir: Vec3A) -> bool {
        let origin = offset_ray_origin(from.p, from.p_error, from.ng, dir);
        !self.segment_blocked(origin, dir, f32::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{CameraSpec, Material, Mesh};

    /// Shadow rays from surface points to an unblocked light are never occluded by the surface
    /// they start on (Cornell-box scale, where offsets are ~1e-7), nor rays leaving it.
    #[test]
    fn no_self_shadowing() {
        use crate::sampler::{IndependentSampler, Sampler};
        let mut m = Mesh::new();
        let q = |y: f32, s: f32| {
            [
                Vec3A::new(0.0, y, 0.0),
                Vec3A::new(0.0, y, s),
                Vec3A::new(s, y, s),
                Vec3A::new(s, y, 0.0),
            ]
        };
        m.add_quad(q(0.0, 0.5559), 0); // floor, facing +y
        let mut light = q(0.5487, 0.5559);
        light.reverse(); // facing -y
        m.add_quad(light, 1);
        let scene = Scene::new(
            m,
            vec![
                Material::default(),
                Material::diffuse("light", Vec3::ZERO, Vec3::ONE),
            ],
            vec![],
            CameraSpec::look_at(
                Vec3A::new(0.278, 0.45, 0.278),
                Vec3A::new(0.278, 0.0, 0.279),
                Vec3A::Z,
                60.0,
            ),
            64,
            64,
        );
        let mut s = IndependentSampler::new(4);
        let (mut tested, mut blocked, mut rehit) = (0, 0, 0);
        for i in 0..20_000u64 {
            s.start_pixel_sample(i, 0);
            let p = s.next_2d() * 64.0;
            let ray = scene.camera().generate_ray(p, Vec2::ZERO, 0.0);
            let Some(si) = scene.intersect(&ray) else {
                continue;
            };
            if si.material != 0 {
                continue;
            }
            let ls = scene
                .lights()
                .sample_li(si.p, s.next_1d(), s.next_2d())
                .unwrap();
            tested += 1;
            if !scene.unoccluded(&si, ls.p) {
                blocked += 1;
            }
            // A grazing ray leaving the floor must not hit the floor again.
            let d = s.next_2d();
            let dir = Vec3A::new(d.x - 0.5, 1e-3 + 0.01 * d.y, 0.5 - d.y).normalize();
            if let Some(h) = scene.intersect(&si.spawn_ray(dir, 0.0)) {
                if h.material == 0 {
                    rehit += 1;
                }
            }
        }
        assert!(tested > 10_000, "{tested}");
        assert_eq!((blocked, rehit), (0, 0), "of {tested} shadow rays");
    }

    /// Perturbed normals far outside the geometric hemisphere are pulled back into it; the
    /// result is unit and finite, and normals inside it are unchanged.
    #[test]
    fn shading_normals_stay_valid() {
        use crate::sampler::{IndependentSampler, Sampler};
        let ng = Vec3A::new(0.3, -0.4, 0.5).normalize();
        let mut s = IndependentSampler::new(9);
        for i in 0..20_000 {
            s.start_pixel_sample(i, 0);
            let u = s.next_2d();
            let z = 1.0 - 2.0 * u.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u.y;
            let n = Vec3A::new(r * phi.cos(), r * phi.sin(), z);
            let m = valid_shading_normal(n, ng).unwrap_or_else(|| panic!("{n}"));
            assert!((m.length() - 1.0).abs() < 1e-4);
            assert!(m.dot(ng) > 0.5 * MIN_SHADING_COS, "{n} -> {m}");
            if n.dot(ng) >= MIN_SHADING_COS {
                assert_eq!(m, n);
            }
        }
        // Exactly opposite the geometric normal.
        assert!(valid_shading_normal(-ng, ng).is_some());
    }
}
