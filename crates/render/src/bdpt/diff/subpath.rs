//! Camera and light subpaths of the differentiable evaluator (`bdpt::{camera_subpath,
//! light_subpath, random_walk}` restated over [`Real`], area lights only, no roulette).

use glam::Vec2;

use super::bsdf;
use super::geometry::{
    cosine_hemisphere, cosine_hemisphere_pdf, intersect_triangle, shading_consistent,
    shading_normal_correction, uniform_triangle, Frame,
};
use super::path::{Ctx, Replay, Stop};
use super::texture::base_color;
use super::vertex::Vertex;
use crate::autodiff::{Real, V3};
use crate::bdpt::VertexKind;
use crate::material::TransportMode;

impl Ctx<'_> {
    /// `bdpt::random_walk` without roulette (MMLT): extends `path` from `path[0]`.
    #[allow(clippy::too_many_arguments)]
    fn random_walk<T: Real>(
        &self,
        mut dir: V3<T>,
        u: &mut Replay<'_, T>,
        mut beta: V3<T>,
        pdf_dir: T,
        max_new: usize,
        mode: TransportMode,
        path: &mut [Vertex<T>],
    ) -> Result<usize, Stop> {
        if max_new == 0 {
            return Ok(0);
        }
        let mut pdf_fwd = pdf_dir;
        let mut added = 0;
        loop {
            let idx = 1 + added;
            // Borrowed, not copied: a vertex of dual numbers is large.
            let prev = &path[idx - 1];
            let ray = prev.spawn_f32(dir);
            let Some(si) = self.scene.intersect(&ray) else {
                // Environment lights are not restated (the scene check excludes them).
                u.decide(u64::MAX);
                break;
            };
            u.decide(u64::from(si.triangle));
            let Some(hit) =
                intersect_triangle(self.scene.mesh(), si.triangle as usize, prev.p, dir)
            else {
                return Err(Stop::Zero);
            };
            let b = self.scene.bsdf(&si);
            if bsdf::support(&b) == bsdf::Support::Unsupported {
                return Err(Stop::Unsupported);
            }
            let surface = bsdf::Surface {
                bsdf: b,
                base: base_color(self.scene, si.triangle as usize, hit.bary),
            };
            let mut v = Vertex {
                kind: VertexKind::Surface,
                p: hit.p,
                p_error: si.p_error,
                ng: hit.ng,
                frame: Frame::from_normal(hit.ns),
                wo: -dir,
                bsdf: Some(surface),
                light: self.scene.lights().light_of_triangle(si.triangle),
                bary: hit.bary,
                beta,
                pdf_fwd: T::cst(0.0),
                pdf_rev: T::cst(0.0),
                delta: false,
                time: prev.time,
            };
            v.pdf_fwd = prev.convert_density(pdf_fwd, &v);
            path[idx] = v;
            added += 1;
            if added >= max_new {
                break;
            }
            let wo_local = v.frame.to_local(v.wo);
            let uc = u.next();
            let u2 = u.next2();
            let Some(bs) = bsdf::sample(&surface, wo_local, uc, u2, mode) else {
                break;
            };
            u.decide(u64::from(bs.wi.z.value() * wo_local.z.value() > 0.0));
            if bs.pdf.value() <= 0.0 || bs.f.is_zero() {
                break;
            }
            let wi = v.frame.to_world(bs.wi);
            if !shading_consistent(v.wo, wi, v.ng, v.ns()) {
                break;
            }
            let cos = bs.wi.z.abs();
            let mut factor = bs.f.times(cos / bs.pdf);
            if mode == TransportMode::Importance {
                factor = factor * shading_normal_correction(v.wo, wi, v.ng, v.ns());
            }
            beta = beta.mul_v(factor);
            pdf_fwd = bs.pdf;
            let mut pdf_rev = bsdf::pdf(&surface, bs.wi, wo_local);
            if bs.is_specular {
                path[idx].delta = true;
                // Delta lobes keep their discrete probability both ways
                // (`bdpt::subpath`, "Specular chains").
                pdf_rev = bs.pdf;
            }
            if !beta.is_finite() || beta.is_zero() {
                break;
            }
            let (before, here) = path.split_at_mut(idx);
            let rev = here[0].convert_density(pdf_rev, &before[idx - 1]);
            before[idx - 1].pdf_rev = rev;
            dir = wi;
        }
        Ok(added)
    }

    /// `bdpt::camera_subpath`.
    pub(super) fn camera_subpath<T: Real>(
        &self,
        u: &mut Replay<'_, T>,
        raster: (T, T),
        max_vertices: usize,
        path: &mut [Vertex<T>],
    ) -> Result<usize, Stop> {
        if max_vertices == 0 {
            return Ok(0);
        }
        u.start(0);
        let u_lens = u.next2();
        let u_time = u.next();
        let (origin, dir, time) = self.camera.generate_ray(raster, u_lens, u_time);
        let pdf_dir = self.camera.pdf_dir(origin, dir, time);
        path[0] = Vertex::camera(
            origin,
            self.camera.pose_at(time).frame(),
            V3::splat(1.0),
            time,
        );
        Ok(1 + self.random_walk(
            dir,
            u,
            V3::splat(1.0),
            pdf_dir,
            max_vertices - 1,
            TransportMode::Radiance,
            path,
        )?)
    }

    /// `bdpt::light_subpath` for area lights.
    pub(super) fn light_subpath<T: Real>(
        &self,
        u: &mut Replay<'_, T>,
        time: T,
        max_vertices: usize,
        path: &mut [Vertex<T>],
    ) -> Result<usize, Stop> {
        if max_vertices == 0 {
            return Ok(0);
        }
        u.start(1);
        let u_light = u.next();
        let u_pos = u.next2();
        let mut u_dir = u.next2();
        let f32u = |x: T| x.value() as f32;
        // The discrete choices and the (constant) radiance from the renderer's own sampler.
        let Some(le) = self.scene.sample_le(
            f32u(u_light),
            Vec2::new(f32u(u_pos.0), f32u(u_pos.1)),
            Vec2::new(f32u(u_dir.0), f32u(u_dir.1)),
        ) else {
            return Ok(0);
        };
        u.decide(u64::from(le.light) << 32);
        let l = self.area(le.light)?;
        let [b0, b1, b2] = uniform_triangle(u_pos);
        let [p0, p1, p2] = l.vertices.map(V3::<f64>::from_a);
        let p = p0.times(b0) + p1.times(b1) + p2.times(b2);
        let (mut n, mut side_pdf) = (l.normal, 1.0);
        if l.two_sided {
            side_pdf = 0.5;
            if f32u(u_dir.0) < 0.5 {
                u_dir.0 = u_dir.0 * 2.0;
            } else {
                u_dir.0 = (u_dir.0 - 0.5) * 2.0;
                n = -n;
            }
            u_dir.0 = u_dir.0.min_c(f64::from(1.0 - f32::EPSILON / 2.0));
        }
        let local = cosine_hemisphere(u_dir);
        let dir = Frame::<f64>::from_normal(V3::from_a(n))
            .to_world_c(local)
            .normalize_or_zero();
        let pdf_pos = self.pdf_light_origin(le.light)?;
        let pdf_dir = cosine_hemisphere_pdf(local.z) * side_pdf;
        let cos = dir.dot_c(V3::from_a(n)).abs();
        let radiance = V3::<f64>::from_rgb(le.radiance);
        if pdf_pos <= 0.0 || pdf_dir.value() <= 0.0 || radiance.is_zero() {
            return Ok(0);
        }
        let mut v = Vertex::light(
            p,
            l.normal,
            le.light,
            V3::cst(radiance),
            T::cst(pdf_pos),
            time,
        );
        v.bary = (b1, b2);
        path[0] = v;
        let beta = radiance.times(cos / (pdf_dir * pdf_pos));
        Ok(1 + self.random_walk(
            dir,
            u,
            beta,
            pdf_dir,
            max_vertices - 1,
            TransportMode::Importance,
            path,
        )?)
    }
}
