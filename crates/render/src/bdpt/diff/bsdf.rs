//! The BSDFs of `crate::material` over [`Real`], in the local shading frame, with the same
//! branches as the f32 versions: Lambertian, GGX conductor (visible-normal sampling), smooth
//! conductor and smooth dielectric. The rough dielectric is not restated
//! ([`Support::Unsupported`]).

use std::f64::consts::{PI, TAU};

use super::geometry::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::autodiff::{Real, V3};
use crate::material::{Bsdf, TransportMode};

/// Whether a BSDF family is restated here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Support {
    /// Restated.
    Supported,
    /// Not restated (rough dielectric).
    Unsupported,
}

/// Whether `b`'s family is restated.
pub(super) fn support(b: &Bsdf) -> Support {
    match b {
        Bsdf::RoughDielectric(_) => Support::Unsupported,
        _ => Support::Supported,
    }
}

/// A BSDF at a surface point: the renderer's f32 BSDF, with the base colour (albedo, F0 or
/// transmission tint) over `T` where a texture makes it vary.
#[derive(Clone, Copy, Debug)]
pub(super) struct Surface<T> {
    pub(super) bsdf: Bsdf,
    pub(super) base: Option<V3<T>>,
}

impl<T: Real> Surface<T> {
    fn color(&self, constant: glam::Vec3) -> Rgb<T> {
        match self.base {
            Some(base) => Rgb::Varying(base),
            None => Rgb::Constant(V3::from_rgb(constant)),
        }
    }
}

/// An RGB factor of a path (a BSDF value): a constant (an untextured colour), whose products
/// with the path are mixed ([`V3::mul_c`], [`V3::times`]), or a colour over `T`.
#[derive(Clone, Copy, Debug)]
pub(super) enum Rgb<T> {
    /// No derivatives.
    Constant(V3<f64>),
    /// With derivatives.
    Varying(V3<T>),
}

impl<T: Real> Rgb<T> {
    /// True if every value is zero.
    pub(super) fn is_zero(self) -> bool {
        match self {
            Self::Constant(c) => c.is_zero(),
            Self::Varying(v) => v.is_zero(),
        }
    }

    /// The factor times the scalar `s`.
    pub(super) fn times(self, s: T) -> V3<T> {
        match self {
            Self::Constant(c) => c.times(s),
            Self::Varying(v) => v * s,
        }
    }

    /// `v` times the factor, component-wise.
    pub(super) fn apply(self, v: V3<T>) -> V3<T> {
        match self {
            Self::Constant(c) => v.mul_c(c),
            Self::Varying(f) => v.mul_v(f),
        }
    }

    /// The factor scaled by the constant `c`.
    fn scale(self, c: f64) -> Self {
        match self {
            Self::Constant(k) => Self::Constant(k.scale(c)),
            Self::Varying(v) => Self::Varying(v.scale(c)),
        }
    }

    /// The factor as a vector over `T`.
    fn over_t(self) -> V3<T> {
        match self {
            Self::Constant(c) => V3::cst(c),
            Self::Varying(v) => v,
        }
    }
}

/// A sampled direction (`crate::material::BsdfSample`).
pub(super) struct Sample<T> {
    pub(super) wi: V3<T>,
    pub(super) f: Rgb<T>,
    pub(super) pdf: T,
    pub(super) is_specular: bool,
}

fn same_hemisphere<T: Real>(a: V3<T>, b: V3<T>) -> bool {
    a.z.value() * b.z.value() > 0.0
}

fn fresnel_schlick<T: Real>(f0: V3<T>, cos: T) -> V3<T> {
    let m = (-cos.clamp_c(0.0, 1.0) + 1.0).max_c(0.0);
    let m2 = m * m;
    let w = m2 * m2 * m;
    f0 + (V3::splat(1.0) - f0) * w
}

fn fresnel_dielectric<T: Real>(cos_theta_i: T, eta: f64) -> T {
    let mut cos_i = cos_theta_i.clamp_c(-1.0, 1.0);
    let mut eta = eta;
    if cos_i.value() < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = -(cos_i * cos_i) + 1.0;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t.value() >= 1.0 {
        return T::cst(1.0);
    }
    let cos_t = (-sin2_t + 1.0).max_c(0.0).sqrt();
    let r_par = (cos_i * eta - cos_t) / (cos_i * eta + cos_t);
    let r_perp = (cos_i - cos_t * eta) / (cos_i + cos_t * eta);
    (r_par * r_par + r_perp * r_perp) * 0.5
}

fn reflect<T: Real>(wo: V3<T>, n: V3<T>) -> V3<T> {
    -wo + n * (wo.dot(n) * 2.0)
}

/// `crate::material::refract` about `+z`: `(wi, etap)`.
fn refract_z<T: Real>(wi: V3<T>, eta: f64) -> Option<(V3<T>, f64)> {
    let mut cos_i = wi.z;
    let (mut etap, mut n) = (eta, V3::new(T::cst(0.0), T::cst(0.0), T::cst(1.0)));
    if cos_i.value() < 0.0 {
        etap = 1.0 / etap;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (-(cos_i * cos_i) + 1.0).max_c(0.0);
    let sin2_t = sin2_i / (etap * etap);
    if sin2_t.value() >= 1.0 {
        return None;
    }
    let cos_t = (-sin2_t + 1.0).sqrt();
    Some((-wi.scale(1.0 / etap) + n * (cos_i / etap - cos_t), etap))
}

/// The GGX distribution (`crate::material::Ggx`).
#[derive(Clone, Copy)]
struct Ggx {
    alpha: f64,
}

impl Ggx {
    fn d<T: Real>(self, wm: V3<T>) -> T {
        if wm.z.value() <= 0.0 {
            return T::cst(0.0);
        }
        let a2 = self.alpha * self.alpha;
        let t = wm.z * wm.z * a2 + (wm.x * wm.x + wm.y * wm.y);
        (t * t * PI).recip() * a2
    }

    fn lambda<T: Real>(self, w: V3<T>) -> T {
        let z2 = w.z * w.z;
        if z2.value() == 0.0 {
            return T::cst(f64::INFINITY);
        }
        let a2_tan2 = (w.x * w.x + w.y * w.y) * (self.alpha * self.alpha) / z2;
        a2_tan2 / (((a2_tan2 + 1.0).sqrt() + 1.0) * 2.0)
    }

    fn g1<T: Real>(self, w: V3<T>) -> T {
        (self.lambda(w) + 1.0).recip()
    }

    fn g<T: Real>(self, wo: V3<T>, wi: V3<T>) -> T {
        (self.lambda(wo) + self.lambda(wi) + 1.0).recip()
    }

    fn pdf_visible<T: Real>(self, w: V3<T>, wm: V3<T>) -> T {
        let w = if w.z.value() < 0.0 { -w } else { w };
        if w.z.value() == 0.0 {
            return T::cst(0.0);
        }
        self.g1(w) * w.dot(wm).max_c(0.0) * self.d(wm) / w.z
    }

    fn sample_visible<T: Real>(self, w: V3<T>, u: (T, T)) -> V3<T> {
        let a = self.alpha;
        let w = if w.z.value() < 0.0 { -w } else { w };
        let z = V3::new(T::cst(0.0), T::cst(0.0), T::cst(1.0));
        let vh = V3::new(w.x * a, w.y * a, w.z).try_normalize().unwrap_or(z);
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2.value() > 0.0 {
            V3::new(-vh.y, vh.x, T::cst(0.0)) * len2.sqrt().recip()
        } else {
            V3::new(T::cst(1.0), T::cst(0.0), T::cst(0.0))
        };
        let t2 = vh.cross(t1);
        let r = u.0.sqrt();
        let (sin_phi, cos_phi) = (u.1 * TAU).sin_cos();
        let p1 = r * cos_phi;
        let p2 = r * sin_phi;
        let s = (vh.z + 1.0) * 0.5;
        let p2 = (-s + 1.0) * (-(p1 * p1) + 1.0).max_c(0.0).sqrt() + s * p2;
        let nh = t1 * p1 + t2 * p2 + vh * (-(p1 * p1) - p2 * p2 + 1.0).max_c(0.0).sqrt();
        V3::new(nh.x * a, nh.y * a, nh.z.max_c(1e-6))
            .try_normalize()
            .unwrap_or(z)
    }
}

fn conductor_upper<T: Real>(wo: V3<T>, wi: V3<T>) -> Option<(V3<T>, V3<T>, V3<T>)> {
    if wo.z.value() * wi.z.value() <= 0.0 {
        return None;
    }
    let (wo, wi) = if wo.z.value() < 0.0 {
        (-wo, -wi)
    } else {
        (wo, wi)
    };
    let wm = (wo + wi).try_normalize()?;
    Some((wo, wi, wm))
}

fn conductor_f<T: Real>(f0: V3<T>, ggx: Ggx, wo: V3<T>, wi: V3<T>, wm: V3<T>) -> V3<T> {
    let d = ggx.d(wm);
    let g = ggx.g(wo, wi);
    fresnel_schlick(f0, wo.dot(wm)) * (d * g / (wo.z * wi.z * 4.0))
}

/// `Bsdf::eval` (no cosine; 0 for delta lobes).
pub(super) fn eval<T: Real>(sf: &Surface<T>, wo: V3<T>, wi: V3<T>) -> Rgb<T> {
    match &sf.bsdf {
        Bsdf::Lambertian(l) if same_hemisphere(wo, wi) => sf.color(l.albedo()).scale(1.0 / PI),
        Bsdf::RoughConductor(c) => {
            let ggx = Ggx {
                alpha: f64::from(c.distribution().alpha()),
            };
            match conductor_upper(wo, wi) {
                Some((wo, wi, wm)) => {
                    Rgb::Varying(conductor_f(sf.color(c.f0()).over_t(), ggx, wo, wi, wm))
                }
                None => Rgb::Constant(V3::zero()),
            }
        }
        _ => Rgb::Constant(V3::zero()),
    }
}

/// `Bsdf::pdf` (0 for delta lobes).
pub(super) fn pdf<T: Real>(sf: &Surface<T>, wo: V3<T>, wi: V3<T>) -> T {
    match &sf.bsdf {
        Bsdf::Lambertian(_) if same_hemisphere(wo, wi) => cosine_hemisphere_pdf(wi.z.abs()),
        Bsdf::RoughConductor(c) => {
            let ggx = Ggx {
                alpha: f64::from(c.distribution().alpha()),
            };
            match conductor_upper(wo, wi) {
                Some((wo, _, wm)) => ggx.pdf_visible(wo, wm) / (wo.dot(wm) * 4.0),
                None => T::cst(0.0),
            }
        }
        _ => T::cst(0.0),
    }
}

/// `Bsdf::sample`.
pub(super) fn sample<T: Real>(
    sf: &Surface<T>,
    wo: V3<T>,
    u: T,
    u2: (T, T),
    mode: TransportMode,
) -> Option<Sample<T>> {
    if wo.z.value() == 0.0 {
        return None;
    }
    match &sf.bsdf {
        Bsdf::Lambertian(l) => {
            let mut wi = cosine_hemisphere(u2);
            if wo.z.value() < 0.0 {
                wi.z = -wi.z;
            }
            let pdf = cosine_hemisphere_pdf(wi.z.abs());
            (pdf.value() > 0.0).then(|| Sample {
                wi,
                f: sf.color(l.albedo()).scale(1.0 / PI),
                pdf,
                is_specular: false,
            })
        }
        Bsdf::SmoothConductor(c) => {
            let wi = V3::new(-wo.x, -wo.y, wo.z);
            let cos = wi.z.abs();
            Some(Sample {
                wi,
                f: Rgb::Varying(fresnel_schlick(sf.color(c.f0()).over_t(), cos) * cos.recip()),
                pdf: T::cst(1.0),
                is_specular: true,
            })
        }
        Bsdf::RoughConductor(c) => {
            let ggx = Ggx {
                alpha: f64::from(c.distribution().alpha()),
            };
            let flip = wo.z.value() < 0.0;
            let wo_up = if flip { -wo } else { wo };
            let wm = ggx.sample_visible(wo_up, u2);
            let wi_up = reflect(wo_up, wm);
            let cos_om = wo_up.dot(wm);
            if wi_up.z.value() <= 0.0 || cos_om.value() <= 0.0 {
                return None;
            }
            let pdf = ggx.pdf_visible(wo_up, wm) / (cos_om * 4.0);
            if !(pdf.value() > 0.0 && pdf.is_finite()) {
                return None;
            }
            Some(Sample {
                wi: if flip { -wi_up } else { wi_up },
                f: Rgb::Varying(conductor_f(
                    sf.color(c.f0()).over_t(),
                    ggx,
                    wo_up,
                    wi_up,
                    wm,
                )),
                pdf,
                is_specular: false,
            })
        }
        Bsdf::SmoothDielectric(d) => {
            let eta = f64::from(d.eta());
            let r = fresnel_dielectric(wo.z, eta);
            let t = -r + 1.0;
            // The lobe choice compares the f32 numbers, as the renderer does.
            if (u.value() as f32) < (r.value() as f32) || t.value() <= 0.0 {
                let wi = V3::new(-wo.x, -wo.y, wo.z);
                return Some(Sample {
                    wi,
                    f: Rgb::Varying(V3::new(r, r, r) * wi.z.abs().recip()),
                    pdf: r,
                    is_specular: true,
                });
            }
            let (wi, etap) = refract_z(wo, eta)?;
            if wi.z.value() == 0.0 {
                return None;
            }
            let scale = match mode {
                TransportMode::Radiance => 1.0 / (etap * etap),
                TransportMode::Importance => 1.0,
            };
            let f = Rgb::Varying(sf.color(d.tint()).times(t * scale / wi.z.abs()));
            Some(Sample {
                wi,
                f,
                pdf: t,
                is_specular: true,
            })
        }
        Bsdf::RoughDielectric(_) => None,
    }
}
