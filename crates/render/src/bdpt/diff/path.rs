//! One MMLT strategy `(s, t)` over [`Real`]: subpaths, the connection and its MIS weight,
//! restating `bdpt::{subpath, connect, vertex}` line by line. Discrete decisions (which
//! triangle a ray hits, visibility, which light, which lobe) are taken by the f32 renderer's
//! own queries on the rounded values; everything continuous is recomputed in `T`.

use glam::{Vec2, Vec3A};

use super::bsdf;
use super::geometry::{
    cosine_hemisphere, cosine_hemisphere_pdf, intersect_triangle, shading_consistent,
    shading_normal_correction, uniform_triangle, Camera, Frame,
};
use super::texture::base_color;
use crate::autodiff::{Real, V3};
use crate::bdpt::{MisHeuristic, VertexKind};
use crate::bvh::offset_ray_origin;
use crate::camera::Ray;
use crate::light::{AreaLight, LightRef};
use crate::material::TransportMode;
use crate::scene::Scene;

/// Replays the primary samples of one state: stream `s`'s `k`-th number is
/// `values[s + streams k]` (the interleaved layout of `pss::PssState`), made a variable of
/// lane `lanes[s] + k`.
pub(super) struct Replay<'a, T> {
    pub(super) values: &'a [f64],
    pub(super) streams: usize,
    pub(super) lanes: [usize; 3],
    pub(super) make: fn(f64, usize) -> T,
    pub(super) stream: usize,
    pub(super) cursor: [usize; 3],
    /// Set when a number beyond `values` was requested.
    pub(super) overrun: bool,
    /// A hash of the discrete decisions taken (triangles hit, lights chosen, lobes).
    pub(super) decisions: u64,
}

impl<T: Real> Replay<'_, T> {
    pub(super) fn start(&mut self, stream: usize) {
        self.stream = stream.min(self.streams.saturating_sub(1)).min(2);
    }

    pub(super) fn next(&mut self) -> T {
        let s = self.stream;
        let k = self.cursor[s];
        self.cursor[s] += 1;
        match self.values.get(s + self.streams * k) {
            Some(&v) => (self.make)(v, self.lanes[s] + k),
            None => {
                self.overrun = true;
                T::cst(0.5)
            }
        }
    }

    /// Records a discrete decision.
    pub(super) fn decide(&mut self, what: u64) {
        self.decisions = mcmc_core::seed::mix64(self.decisions ^ what);
    }

    pub(super) fn next2(&mut self) -> (T, T) {
        let a = self.next();
        (a, self.next())
    }
}

/// Most vertices of a path the evaluator handles (depth 4): the subpaths live on the stack.
pub(super) const MAX_DIFF_VERTICES: usize = 6;

/// Why the evaluation gave no value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Stop {
    /// The strategy carries no light.
    Zero,
    /// The path meets something the evaluator does not restate.
    Unsupported,
}

/// A path vertex (`bdpt::Vertex`) over `T`; area lights only.
#[derive(Clone, Copy, Debug)]
pub(super) struct Vertex<T> {
    kind: VertexKind,
    p: V3<T>,
    /// f32 error bound of `p` for ray offsets.
    p_error: Vec3A,
    ng: V3<T>,
    frame: Frame<T>,
    wo: V3<T>,
    bsdf: Option<bsdf::Surface<T>>,
    light: Option<u32>,
    bary: (T, T),
    beta: V3<T>,
    pdf_fwd: T,
    pdf_rev: T,
    delta: bool,
    time: T,
}

impl<T: Real> Vertex<T> {
    fn camera(p: V3<T>, forward: V3<T>, beta: V3<T>, time: T) -> Self {
        let zero = T::cst(0.0);
        Self {
            kind: VertexKind::Camera,
            p,
            p_error: Vec3A::ZERO,
            ng: V3::zero(),
            frame: Frame::from_normal(forward),
            wo: V3::zero(),
            bsdf: None,
            light: None,
            bary: (zero, zero),
            beta,
            pdf_fwd: zero,
            pdf_rev: zero,
            delta: false,
            time,
        }
    }

    fn light(p: V3<T>, n: Vec3A, light: u32, beta: V3<T>, pdf_fwd: T, time: T) -> Self {
        let zero = T::cst(0.0);
        let n3 = V3::from_a(n);
        Self {
            kind: VertexKind::Light,
            p,
            p_error: p.to_a().abs() * 1e-6,
            ng: n3,
            frame: Frame::from_normal(if n == Vec3A::ZERO {
                V3::from_a(Vec3A::Z)
            } else {
                n3
            }),
            wo: V3::zero(),
            bsdf: None,
            light: Some(light),
            bary: (zero, zero),
            beta,
            pdf_fwd,
            pdf_rev: zero,
            delta: false,
            time,
        }
    }

    fn on_surface(&self) -> bool {
        self.kind != VertexKind::Camera && !self.ng.is_zero()
    }

    fn ns(&self) -> V3<T> {
        self.frame.n
    }

    fn is_connectible(&self) -> bool {
        match self.kind {
            VertexKind::Camera | VertexKind::Light => true,
            VertexKind::Surface => self.bsdf.is_some_and(|b| !b.bsdf.is_specular()),
        }
    }

    /// The f32 ray the renderer spawns from here towards `dir` (`Vertex::spawn_ray`).
    fn spawn_f32(&self, dir: V3<T>) -> Ray {
        let p = self.p.to_a();
        let d = dir.to_a();
        let origin = if self.on_surface() {
            offset_ray_origin(p, self.p_error, self.ng.to_a(), d)
        } else {
            p
        };
        Ray {
            origin,
            dir: d,
            time: self.time.value() as f32,
        }
    }

    /// `Vertex::f`.
    fn f(&self, next: &Self, mode: TransportMode) -> V3<T> {
        let Some(b) = self.bsdf else {
            return V3::zero();
        };
        let wi = (next.p - self.p).normalize_or_zero();
        if !shading_consistent(self.wo, wi, self.ng, self.ns()) {
            return V3::zero();
        }
        let f = bsdf::eval(&b, self.frame.to_local(self.wo), self.frame.to_local(wi));
        if mode == TransportMode::Importance && !f.is_zero() {
            f * shading_normal_correction(self.wo, wi, self.ng, self.ns())
        } else {
            f
        }
    }

    /// `Vertex::convert_density`.
    fn convert_density(&self, pdf: T, next: &Self) -> T {
        let w = next.p - self.p;
        let d2 = w.length_squared();
        if d2.value() == 0.0 {
            return T::cst(0.0);
        }
        let inv_d2 = d2.recip();
        let mut pdf = pdf;
        if next.on_surface() {
            pdf *= next.ng.dot(w * inv_d2.sqrt()).abs();
        }
        pdf * inv_d2
    }
}

/// The scene as the evaluator sees it.
#[derive(Clone, Copy)]
pub(super) struct Ctx<'s> {
    pub(super) scene: &'s Scene,
    pub(super) camera: Camera,
}

impl Ctx<'_> {
    fn area(&self, light: u32) -> Result<&AreaLight, Stop> {
        match self.scene.lights().get(light) {
            Some(LightRef::Area(l)) => Ok(l),
            _ => Err(Stop::Unsupported),
        }
    }

    fn visible<T: Real>(&self, a: &Vertex<T>, b: &Vertex<T>) -> bool {
        let n = |v: &Vertex<T>| {
            if v.on_surface() {
                v.ng.to_a()
            } else {
                Vec3A::ZERO
            }
        };
        self.scene
            .unoccluded_between(a.p.to_a(), n(a), b.p.to_a(), n(b))
    }

    /// Radiance light `l` emits at barycentrics `bary` towards `dir` (`Scene::area_le`): a
    /// constant (texture lookups do not carry derivatives), zero behind one-sided lights.
    fn area_le<T: Real>(&self, l: u32, bary: (T, T), dir: V3<T>) -> V3<T> {
        let b = Vec2::new(bary.0.value() as f32, bary.1.value() as f32);
        V3::from_rgb(self.scene.area_le(l, b, dir.to_a()))
    }

    /// `Vertex::emitted_towards` for area lights.
    fn emitted_towards<T: Real>(&self, v: &Vertex<T>, towards: V3<T>) -> V3<T> {
        match v.light {
            Some(l) => self.area_le(l, v.bary, (towards - v.p).normalize_or_zero()),
            None => V3::zero(),
        }
    }

    /// `Vertex::pdf_light` for area lights.
    fn pdf_light<T: Real>(&self, v: &Vertex<T>, next: &Vertex<T>) -> Result<T, Stop> {
        let Some(light) = v.light else {
            return Ok(T::cst(0.0));
        };
        let w = next.p - v.p;
        let d2 = w.length_squared();
        if d2.value() == 0.0 {
            return Ok(T::cst(0.0));
        }
        let w = w * d2.sqrt().recip();
        let mut pdf = self.light_pdf_dir(light, w)? / d2;
        if next.on_surface() {
            pdf *= next.ng.dot(w).abs();
        }
        Ok(pdf)
    }

    /// `Lights::pdf_le`'s directional density for an area light.
    fn light_pdf_dir<T: Real>(&self, light: u32, dir: V3<T>) -> Result<T, Stop> {
        let l = self.area(light)?;
        let cos = V3::from_a(l.normal).dot(dir);
        Ok(if l.two_sided {
            cos.abs() * (0.5 / std::f64::consts::PI)
        } else {
            cos.max_c(0.0) / std::f64::consts::PI
        })
    }

    /// `Vertex::pdf_light_origin` for area lights: selection probability over area.
    fn pdf_light_origin(&self, light: u32) -> Result<f64, Stop> {
        let l = self.area(light)?;
        Ok(f64::from(self.scene.lights().selection_pmf(light)) / f64::from(l.area))
    }

    /// `Vertex::pdf`.
    fn pdf<T: Real>(
        &self,
        v: &Vertex<T>,
        prev: Option<&Vertex<T>>,
        next: &Vertex<T>,
    ) -> Result<T, Stop> {
        if v.kind == VertexKind::Light {
            return self.pdf_light(v, next);
        }
        let wn = next.p - v.p;
        if wn.length_squared().value() == 0.0 {
            return Ok(T::cst(0.0));
        }
        let wn = wn.normalize_or_zero();
        let pdf = match v.kind {
            VertexKind::Camera => self.camera.pdf_dir(v.p, wn, v.time),
            _ => {
                let (Some(b), Some(prev)) = (v.bsdf, prev) else {
                    return Ok(T::cst(0.0));
                };
                let wp = (prev.p - v.p).normalize_or_zero();
                bsdf::pdf(&b, v.frame.to_local(wp), v.frame.to_local(wn))
            }
        };
        Ok(v.convert_density(pdf, next))
    }

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
            let prev = path[idx - 1];
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
            let mut factor = bs.f * (cos / bs.pdf);
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
            let here = path[idx];
            path[idx - 1].pdf_rev = here.convert_density(pdf_rev, &path[idx - 1]);
            dir = wi;
        }
        Ok(added)
    }

    /// `bdpt::camera_subpath`.
    fn camera_subpath<T: Real>(
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
            self.camera.pose_at(time).forward,
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
    fn light_subpath<T: Real>(
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
        let [p0, p1, p2] = l.vertices.map(V3::<T>::from_a);
        let p = p0 * b0 + p1 * b1 + p2 * b2;
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
        let dir = Frame::from_normal(V3::from_a(n))
            .to_world(local)
            .normalize_or_zero();
        let pdf_pos = self.pdf_light_origin(le.light)?;
        let pdf_dir = cosine_hemisphere_pdf(local.z) * side_pdf;
        let cos = V3::from_a(n).dot(dir).abs();
        let radiance = V3::<T>::from_rgb(le.radiance);
        if pdf_pos <= 0.0 || pdf_dir.value() <= 0.0 || radiance.is_zero() {
            return Ok(0);
        }
        let mut v = Vertex::light(p, l.normal, le.light, radiance, T::cst(pdf_pos), time);
        v.bary = (b1, b2);
        path[0] = v;
        let beta = radiance * (cos / (pdf_dir * pdf_pos));
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

    /// `bdpt::sample_strategy` for a fixed depth: the MIS-weighted contribution times the
    /// number of strategies, or why there is none.
    pub(super) fn sample_strategy<T: Real>(
        &self,
        u: &mut Replay<'_, T>,
        depth: usize,
        image_size: Vec2,
        heuristic: MisHeuristic,
    ) -> Result<(V3<T>, usize, usize), Stop> {
        if depth + 2 > MAX_DIFF_VERTICES {
            return Err(Stop::Unsupported);
        }
        u.start(2);
        let (n_strategies, s, t) = if depth == 0 {
            (1usize, 0usize, 2usize)
        } else {
            let n = depth + 2;
            let x = u.next().value() as f32;
            let s = ((x * n as f32) as usize).min(n - 1);
            (n, s, n - s)
        };
        u.start(0);
        let raster = u.next2();
        let raster = (
            raster.0 * f64::from(image_size.x),
            raster.1 * f64::from(image_size.y),
        );
        let blank = Vertex::camera(V3::zero(), V3::from_a(Vec3A::Z), V3::zero(), T::cst(0.0));
        let mut camera = [blank; MAX_DIFF_VERTICES];
        let mut light = [blank; MAX_DIFF_VERTICES];
        if self.camera_subpath(u, raster, t, &mut camera)? != t {
            return Err(Stop::Zero);
        }
        let time = camera[0].time;
        if s != 1 && self.light_subpath(u, time, s, &mut light)? != s {
            return Err(Stop::Zero);
        }
        let l = self.connect(&mut light, &mut camera, s, t, u, heuristic)?;
        Ok((l.scale(n_strategies as f64), s, t))
    }

    /// `bdpt::connect` with MIS.
    fn connect<T: Real>(
        &self,
        light: &mut [Vertex<T>],
        camera: &mut [Vertex<T>],
        s: usize,
        t: usize,
        u: &mut Replay<'_, T>,
        heuristic: MisHeuristic,
    ) -> Result<V3<T>, Stop> {
        if t == 0 || (t > 1 && s != 0 && camera[t - 1].kind == VertexKind::Light) {
            return Err(Stop::Zero);
        }
        let mut sampled = None;
        let mut l = V3::zero();
        if s == 0 {
            let pt = &camera[t - 1];
            if pt.light.is_some() && t >= 2 {
                l = self.emitted_towards(pt, camera[t - 2].p).mul_v(pt.beta);
            }
        } else if t == 1 {
            let qs = &light[s - 1];
            if qs.is_connectible() {
                u.start(2);
                let uu = u.next2();
                if let Some((wi, pdf, p_lens, _raster, importance)) =
                    self.camera.sample_wi(qs.p, uu, qs.time)
                {
                    if pdf.value() > 0.0 && importance.value() > 0.0 {
                        let forward = self.camera.pose_at(qs.time).forward;
                        let w = importance / pdf;
                        let cam = Vertex::camera(p_lens, forward, V3::new(w, w, w), qs.time);
                        let mut contrib = qs
                            .beta
                            .mul_v(qs.f(&cam, TransportMode::Importance))
                            .mul_v(cam.beta);
                        if qs.on_surface() && qs.kind == VertexKind::Surface {
                            contrib = contrib * wi.dot(qs.ns()).abs();
                        }
                        if !contrib.is_zero() && self.visible(qs, &cam) {
                            l = contrib;
                            sampled = Some(cam);
                        }
                    }
                }
            }
        } else if s == 1 {
            let pt = camera[t - 1];
            if pt.is_connectible() {
                u.start(2);
                let u_light = u.next();
                let u_pos = u.next2();
                if let Some(v) = self.sample_li(&pt, u_light, u_pos)? {
                    u.decide(u64::from(v.light.unwrap_or(u32::MAX)) << 32);
                    let wi = (v.p - pt.p).normalize_or_zero();
                    let mut contrib = pt
                        .beta
                        .mul_v(pt.f(&v, TransportMode::Radiance))
                        .mul_v(v.beta);
                    if pt.kind == VertexKind::Surface {
                        contrib = contrib * wi.dot(pt.ns()).abs();
                    }
                    if !contrib.is_zero() && self.visible(&pt, &v) {
                        l = contrib;
                        sampled = Some(v);
                    }
                }
            }
        } else {
            let (qs, pt) = (&light[s - 1], &camera[t - 1]);
            if qs.is_connectible() && pt.is_connectible() {
                let contrib = qs
                    .beta
                    .mul_v(qs.f(pt, TransportMode::Importance))
                    .mul_v(pt.f(qs, TransportMode::Radiance))
                    .mul_v(pt.beta);
                if !contrib.is_zero() {
                    l = contrib * self.geometry_term(qs, pt);
                }
            }
        }
        if l.is_zero() || !l.is_finite() {
            return Err(Stop::Zero);
        }
        let w = self.mis_weight(light, camera, sampled.as_ref(), s, t, heuristic)?;
        Ok(l * w)
    }

    /// `Scene::sample_li` for area lights, as the light vertex of a strategy with `s = 1`.
    fn sample_li<T: Real>(
        &self,
        pt: &Vertex<T>,
        u_light: T,
        u_pos: (T, T),
    ) -> Result<Option<Vertex<T>>, Stop> {
        let Some((index, pmf)) = self.scene.lights().select(u_light.value() as f32) else {
            return Ok(None);
        };
        let l = self.area(index)?;
        let [b0, b1, b2] = uniform_triangle(u_pos);
        let [p0, p1, p2] = l.vertices.map(V3::<T>::from_a);
        let p = p0 * b0 + p1 * b1 + p2 * b2;
        let d = p - pt.p;
        let dist2 = d.length_squared();
        if !(dist2.value() > 0.0 && dist2.is_finite()) {
            return Ok(None);
        }
        let wi = d * dist2.sqrt().recip();
        let cos_light = V3::from_a(l.normal).dot(wi).abs();
        if cos_light.value() <= 0.0 {
            return Ok(None);
        }
        let pdf = dist2 * f64::from(pmf) / (cos_light * f64::from(l.area));
        if !(pdf.value() > 0.0 && pdf.is_finite()) {
            return Ok(None);
        }
        let radiance = self.area_le(index, (b1, b2), -wi);
        if radiance.is_zero() {
            return Ok(None);
        }
        let mut v = Vertex::light(
            p,
            l.normal,
            index,
            radiance * pdf.recip(),
            T::cst(0.0),
            pt.time,
        );
        v.bary = (b1, b2);
        v.pdf_fwd = T::cst(self.pdf_light_origin(index)?);
        Ok(Some(v))
    }

    /// `bdpt::geometry_term`.
    fn geometry_term<T: Real>(&self, v0: &Vertex<T>, v1: &Vertex<T>) -> T {
        let d = v0.p - v1.p;
        let d2 = d.length_squared();
        if d2.value() == 0.0 {
            return T::cst(0.0);
        }
        let dn = d * d2.sqrt().recip();
        let mut g = d2.recip();
        if v0.on_surface() {
            g *= v0.ns().dot(dn).abs();
        }
        if v1.on_surface() {
            g *= v1.ns().dot(dn).abs();
        }
        if g.value() == 0.0 || !self.visible(v0, v1) {
            return T::cst(0.0);
        }
        g
    }

    /// `bdpt::connect::mis_weight`.
    fn mis_weight<T: Real>(
        &self,
        light: &[Vertex<T>],
        camera: &[Vertex<T>],
        sampled: Option<&Vertex<T>>,
        s: usize,
        t: usize,
        heuristic: MisHeuristic,
    ) -> Result<T, Stop> {
        let one = T::cst(1.0);
        if s + t == 2 {
            return Ok(one);
        }
        let mut qs = (s > 0).then(|| {
            if s == 1 {
                *sampled.unwrap_or(&light[0])
            } else {
                light[s - 1]
            }
        });
        let mut pt = if t == 1 {
            *sampled.unwrap_or(&camera[0])
        } else {
            camera[t - 1]
        };
        let qs_minus = (s > 1).then(|| light[s - 2]);
        let pt_minus = (t > 1).then(|| camera[t - 2]);
        pt.delta = false;
        if let Some(q) = qs.as_mut() {
            q.delta = false;
        }
        pt.pdf_rev = match (&qs, &pt_minus) {
            (Some(q), _) => self.pdf(q, qs_minus.as_ref(), &pt)?,
            (None, Some(_)) => T::cst(match pt.light {
                Some(l) => self.pdf_light_origin(l)?,
                None => 0.0,
            }),
            (None, None) => T::cst(0.0),
        };
        let pt_minus_rev = match (&pt_minus, &qs) {
            (Some(pm), Some(q)) => Some(self.pdf(&pt, Some(q), pm)?),
            (Some(pm), None) => Some(self.pdf_light(&pt, pm)?),
            _ => None,
        };
        let qs_rev = match &qs {
            Some(q) => Some(self.pdf(&pt, pt_minus.as_ref(), q)?),
            None => None,
        };
        let qs_minus_rev = match (&qs, &qs_minus) {
            (Some(q), Some(qm)) => Some(self.pdf(q, Some(&pt), qm)?),
            _ => None,
        };
        if let (Some(q), Some(r)) = (qs.as_mut(), qs_rev) {
            q.pdf_rev = r;
        }
        let remap0 = |f: T| if f.value() != 0.0 { f } else { one };
        let pow = |r: T| match heuristic {
            MisHeuristic::Balance => r,
            MisHeuristic::Power => r * r,
        };
        let mut sum = T::cst(0.0);
        let mut ri = one;
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
            ri *= remap0(rev) / remap0(fwd);
            if !delta && !camera[i - 1].delta {
                sum += pow(ri);
            }
        }
        ri = one;
        for i in (0..s).rev() {
            let (fwd, rev, delta) = if i == s - 1 {
                qs.as_ref().map_or((T::cst(0.0), T::cst(0.0), false), |q| {
                    (q.pdf_fwd, q.pdf_rev, q.delta)
                })
            } else if i + 2 == s {
                let v = &light[i];
                (v.pdf_fwd, qs_minus_rev.unwrap_or(v.pdf_rev), v.delta)
            } else {
                let v = &light[i];
                (v.pdf_fwd, v.pdf_rev, v.delta)
            };
            // Area lights are never delta lights.
            let prev_delta = i > 0 && light[i - 1].delta;
            ri *= remap0(rev) / remap0(fwd);
            if !delta && !prev_delta {
                sum += pow(ri);
            }
        }
        Ok((sum + 1.0).recip())
    }
}
