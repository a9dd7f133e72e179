//! The connection of a strategy's two subpaths in the differentiable evaluator, with its MIS
//! weight (`bdpt::connect` restated over [`Real`], area lights only).

use super::geometry::uniform_triangle;
use super::path::{Ctx, Replay, Stop, MAX_DIFF_VERTICES};
use super::vertex::Vertex;
use crate::autodiff::{Real, V3};
use crate::bdpt::{MisHeuristic, VertexKind};
use crate::material::TransportMode;

impl Ctx<'_> {
    /// `bdpt::connect` with MIS.
    pub(super) fn connect<T: Real>(
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
                l = pt.beta.mul_c(self.emitted_towards(pt, camera[t - 2].p));
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
                        let frame = self.camera.pose_at(qs.time).frame();
                        let w = importance / pdf;
                        let cam = Vertex::camera(p_lens, frame, V3::new(w, w, w), qs.time);
                        let mut contrib = qs
                            .f(&cam, TransportMode::Importance)
                            .apply(qs.beta)
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
            let pt = &camera[t - 1];
            if pt.is_connectible() {
                u.start(2);
                let u_light = u.next();
                let u_pos = u.next2();
                if let Some(v) = self.sample_li(pt, u_light, u_pos)? {
                    u.decide(u64::from(v.light.unwrap_or(u32::MAX)) << 32);
                    let wi = (v.p - pt.p).normalize_or_zero();
                    let mut contrib = pt
                        .f(&v, TransportMode::Radiance)
                        .apply(pt.beta)
                        .mul_v(v.beta);
                    if pt.kind == VertexKind::Surface {
                        contrib = contrib * wi.dot(pt.ns()).abs();
                    }
                    if !contrib.is_zero() && self.visible(pt, &v) {
                        l = contrib;
                        sampled = Some(v);
                    }
                }
            }
        } else {
            let (qs, pt) = (&light[s - 1], &camera[t - 1]);
            if qs.is_connectible() && pt.is_connectible() {
                let from_light = qs.f(pt, TransportMode::Importance).apply(qs.beta);
                let contrib = pt
                    .f(qs, TransportMode::Radiance)
                    .apply(from_light)
                    .mul_v(pt.beta);
                if !contrib.is_zero() {
                    l = contrib * self.geometry_term(qs, pt);
                }
            }
        }
        if l.is_zero() || !l.is_finite() {
            return Err(Stop::Zero);
        }
        let w = if self.constant_mis {
            // The weight from the values alone: the same function, without the lanes.
            let (n_light, n_camera) = (light.len(), camera.len());
            let lv: [Vertex<f64>; MAX_DIFF_VERTICES] =
                std::array::from_fn(|i| light.get(i).unwrap_or(&camera[0]).values());
            let cv: [Vertex<f64>; MAX_DIFF_VERTICES] =
                std::array::from_fn(|i| camera.get(i).unwrap_or(&camera[0]).values());
            let sv = sampled.as_ref().map(Vertex::values);
            let w = self.mis_weight(
                &lv[..n_light.min(MAX_DIFF_VERTICES)],
                &cv[..n_camera.min(MAX_DIFF_VERTICES)],
                sv.as_ref(),
                s,
                t,
                heuristic,
            )?;
            T::cst(w)
        } else {
            self.mis_weight(light, camera, sampled.as_ref(), s, t, heuristic)?
        };
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
        let [p0, p1, p2] = l.vertices.map(V3::<f64>::from_a);
        let p = p0.times(b0) + p1.times(b1) + p2.times(b2);
        let d = p - pt.p;
        let dist2 = d.length_squared();
        if !(dist2.value() > 0.0 && dist2.is_finite()) {
            return Ok(None);
        }
        let wi = d * dist2.sqrt().recip();
        let cos_light = wi.dot_c(V3::from_a(l.normal)).abs();
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
            radiance.times(pdf.recip()),
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
        // The connection's endpoints, borrowed: their new reverse densities are kept apart
        // (`pt_rev`, `qs_rev`) and both count as non-delta.
        let qs = (s > 0).then(|| {
            if s == 1 {
                sampled.unwrap_or(&light[0])
            } else {
                &light[s - 1]
            }
        });
        let pt = if t == 1 {
            sampled.unwrap_or(&camera[0])
        } else {
            &camera[t - 1]
        };
        let qs_minus = (s > 1).then(|| &light[s - 2]);
        let pt_minus = (t > 1).then(|| &camera[t - 2]);
        let pt_rev = match (qs, &pt_minus) {
            (Some(q), _) => self.pdf(q, qs_minus, pt)?,
            (None, Some(_)) => T::cst(match pt.light {
                Some(l) => self.pdf_light_origin(l)?,
                None => 0.0,
            }),
            (None, None) => T::cst(0.0),
        };
        let pt_minus_rev = match (pt_minus, qs) {
            (Some(pm), Some(q)) => Some(self.pdf(pt, Some(q), pm)?),
            (Some(pm), None) => Some(self.pdf_light(pt, pm)?),
            _ => None,
        };
        let qs_rev = match qs {
            Some(q) => Some(self.pdf(pt, pt_minus, q)?),
            None => None,
        };
        let qs_minus_rev = match (qs, qs_minus) {
            (Some(q), Some(qm)) => Some(self.pdf(q, Some(pt), qm)?),
            _ => None,
        };
        let remap0 = |f: T| if f.value() != 0.0 { f } else { one };
        let pow = |r: T| match heuristic {
            MisHeuristic::Balance => r,
            MisHeuristic::Power => r * r,
        };
        let mut sum = T::cst(0.0);
        let mut ri = one;
        for i in (1..t).rev() {
            let (fwd, rev, delta) = if i == t - 1 {
                (pt.pdf_fwd, pt_rev, false)
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
                qs.map_or((T::cst(0.0), T::cst(0.0), false), |q| {
                    (q.pdf_fwd, qs_rev.unwrap_or(q.pdf_rev), false)
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
