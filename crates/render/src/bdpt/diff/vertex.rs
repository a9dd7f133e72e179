//! A path vertex of the differentiable evaluator over [`Real`] (`bdpt::Vertex` restated for
//! area lights): its densities, the BSDF towards a neighbour and the f32 ray it spawns.

use glam::Vec3A;

use super::bsdf::{self, Rgb};
use super::geometry::{shading_consistent, shading_normal_correction, Frame};
use crate::autodiff::{Real, V3};
use crate::bdpt::VertexKind;
use crate::bvh::offset_ray_origin;
use crate::camera::Ray;
use crate::material::TransportMode;

/// A path vertex (`bdpt::Vertex`) over `T`; area lights only.
#[derive(Clone, Copy, Debug)]
pub(super) struct Vertex<T> {
    pub(super) kind: VertexKind,
    pub(super) p: V3<T>,
    /// f32 error bound of `p` for ray offsets.
    pub(super) p_error: Vec3A,
    /// The geometric normal: a constant (a triangle's, a light's; zero at the camera).
    pub(super) ng: V3<f64>,
    pub(super) frame: Frame<T>,
    pub(super) wo: V3<T>,
    pub(super) bsdf: Option<bsdf::Surface<T>>,
    pub(super) light: Option<u32>,
    pub(super) bary: (T, T),
    pub(super) beta: V3<T>,
    pub(super) pdf_fwd: T,
    pub(super) pdf_rev: T,
    pub(super) delta: bool,
    pub(super) time: T,
}

/// `v` without its derivatives.
fn values3<T: Real>(v: V3<T>) -> V3<f64> {
    V3::new(v.x.value(), v.y.value(), v.z.value())
}

impl<T: Real> Vertex<T> {
    /// The vertex's values without their derivatives (for quantities the gradient treats as
    /// constants, such as the MIS weight).
    pub(super) fn values(&self) -> Vertex<f64> {
        Vertex {
            kind: self.kind,
            p: values3(self.p),
            p_error: self.p_error,
            ng: self.ng,
            frame: super::geometry::Frame {
                s: values3(self.frame.s),
                t: values3(self.frame.t),
                n: values3(self.frame.n),
            },
            wo: values3(self.wo),
            bsdf: self.bsdf.map(|b| bsdf::Surface {
                bsdf: b.bsdf,
                base: b.base.map(values3),
            }),
            light: self.light,
            bary: (self.bary.0.value(), self.bary.1.value()),
            beta: values3(self.beta),
            pdf_fwd: self.pdf_fwd.value(),
            pdf_rev: self.pdf_rev.value(),
            delta: self.delta,
            time: self.time.value(),
        }
    }

    pub(super) fn camera(p: V3<T>, frame: Frame<T>, beta: V3<T>, time: T) -> Self {
        let zero = T::cst(0.0);
        Self {
            kind: VertexKind::Camera,
            p,
            p_error: Vec3A::ZERO,
            ng: V3::zero(),
            frame,
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

    pub(super) fn light(p: V3<T>, n: Vec3A, light: u32, beta: V3<T>, pdf_fwd: T, time: T) -> Self {
        let zero = T::cst(0.0);
        let ng = V3::from_a(n);
        Self {
            kind: VertexKind::Light,
            p,
            p_error: p.to_a().abs() * 1e-6,
            ng,
            frame: Frame::from_normal(if n == Vec3A::ZERO {
                V3::from_a(Vec3A::Z)
            } else {
                ng
            })
            .over_t(),
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

    pub(super) fn on_surface(&self) -> bool {
        self.kind != VertexKind::Camera && !self.ng.is_zero()
    }

    pub(super) fn ns(&self) -> V3<T> {
        self.frame.n
    }

    pub(super) fn is_connectible(&self) -> bool {
        match self.kind {
            VertexKind::Camera | VertexKind::Light => true,
            VertexKind::Surface => self.bsdf.is_some_and(|b| !b.bsdf.is_specular()),
        }
    }

    /// The f32 ray the renderer spawns from here towards `dir` (`Vertex::spawn_ray`).
    pub(super) fn spawn_f32(&self, dir: V3<T>) -> Ray {
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
    pub(super) fn f(&self, next: &Self, mode: TransportMode) -> Rgb<T> {
        let zero = Rgb::Constant(V3::zero());
        let Some(b) = self.bsdf else {
            return zero;
        };
        let wi = (next.p - self.p).normalize_or_zero();
        if !shading_consistent(self.wo, wi, self.ng, self.ns()) {
            return zero;
        }
        let f = bsdf::eval(&b, self.frame.to_local(self.wo), self.frame.to_local(wi));
        if mode == TransportMode::Importance && !f.is_zero() {
            Rgb::Varying(f.times(shading_normal_correction(self.wo, wi, self.ng, self.ns())))
        } else {
            f
        }
    }

    /// `Vertex::convert_density`.
    pub(super) fn convert_density(&self, pdf: T, next: &Self) -> T {
        let w = next.p - self.p;
        let d2 = w.length_squared();
        if d2.value() == 0.0 {
            return T::cst(0.0);
        }
        let inv_d2 = d2.recip();
        let mut pdf = pdf;
        if next.on_surface() {
            pdf *= (w * inv_d2.sqrt()).dot_c(next.ng).abs();
        }
        pdf * inv_d2
    }
}
