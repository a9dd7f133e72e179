//! Materials of the analytic scene: Lambertian, modified Phong, mirror, smooth dielectric.

use std::f64::consts::{FRAC_1_PI, TAU};

use crate::lightside::cosine_hemisphere;
use crate::scene::{BsdfSample, SpecularLobe};
use crate::vec3::{Rgb, Vec3};

/// A material of the analytic scene. Diffuse and Phong are two-sided (they reflect on the
/// side `wo` is on); the dielectric's interior is the side opposite its normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian: `f = albedo / pi`, cosine-weighted sampling.
    Diffuse {
        /// Reflectance in `[0, 1]`.
        albedo: Rgb,
    },
    /// Energy-conserving modified Phong (Lafortune and Willems 1994):
    /// `f = kd / pi + ks (e + 2) / (2 pi) max(0, cos α)^e` with `α` the angle between `wi` and
    /// the mirror direction of `wo`; sampling picks the diffuse lobe with probability
    /// `lum(kd) / (lum(kd) + lum(ks))`, else `cos α = u^{1/(e+1)}` (exact mixture pdf;
    /// samples below the surface are absorbed).
    Phong {
        /// Diffuse reflectance.
        diffuse: Rgb,
        /// Glossy reflectance.
        specular: Rgb,
        /// Phong exponent `e >= 0`.
        exponent: f64,
    },
    /// A perfect mirror (specular reflection, coefficient `reflectance`).
    Mirror {
        /// Reflectance.
        reflectance: Rgb,
    },
    /// A smooth dielectric interface: reflection with probability and coefficient `F`
    /// (unpolarised Fresnel), refraction with `1 - F` (times `tint`). Transport is symmetric
    /// (no `1/eta^2` radiance scaling, i.e. it carries basic radiance `L / eta^2`, the same
    /// measurement when camera and lights are in air).
    Dielectric {
        /// Index of refraction of the interior (behind the normal).
        ior: f64,
        /// Multiplies both lobes.
        tint: Rgb,
    },
    /// Absorbs everything (emitters in the test scenes).
    Black,
}

/// Unpolarised Fresnel reflectance of a dielectric interface for `cos_i = |cos θ_i|` and
/// relative index `eta = eta_t / eta_i`; 1 under total internal reflection.
#[must_use]
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> f64 {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

fn phong_lobe(axis: Vec3, exponent: f64, u: [f64; 2]) -> Vec3 {
    let (t, b) = axis.orthonormal_basis();
    let cos_a = u[0].powf(1.0 / (exponent + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = TAU * u[1];
    (t * (sin_a * phi.cos()) + b * (sin_a * phi.sin()) + axis * cos_a).normalize()
}

impl Material {
    /// True for Dirac-only materials.
    #[must_use]
    pub fn is_specular(&self) -> bool {
        matches!(self, Material::Mirror { .. } | Material::Dielectric { .. })
    }

    fn phong_diffuse_probability(diffuse: Rgb, specular: Rgb) -> f64 {
        let (d, s) = (diffuse.luminance(), specular.luminance());
        if d + s > 0.0 {
            d / (d + s)
        } else {
            1.0
        }
    }

    /// `f_s(wo, wi)` for non-specular materials (0 for specular ones), `n` the shading normal.
    #[must_use]
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Rgb {
        let n = if wo.dot(n) < 0.0 { -n } else { n };
        if wi.dot(n) <= 0.0 || wo.dot(n) <= 0.0 {
            return Rgb::BLACK;
        }
        match *self {
            Material::Diffuse { albedo } => albedo * FRAC_1_PI,
            Material::Phong {
                diffuse,
                specular,
                exponent,
            } => {
                let cos_a = wi.dot(Vec3::reflect(wo, n)).max(0.0);
                diffuse * FRAC_1_PI + specular * ((exponent + 2.0) / TAU * cos_a.powf(exponent))
            }
            _ => Rgb::BLACK,
        }
    }

    /// Solid-angle pdf of [`Material::sample`] for non-specular materials.
    #[must_use]
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f64 {
        let n = if wo.dot(n) < 0.0 { -n } else { n };
        let cos_i = wi.dot(n);
        if cos_i <= 0.0 || wo.dot(n) <= 0.0 {
            return 0.0;
        }
        match *self {
            Material::Diffuse { .. } => cos_i * FRAC_1_PI,
            Material::Phong {
                diffuse,
                specular,
                exponent,
            } => {
                let pd = Self::phong_diffuse_probability(diffuse, specular);
                let cos_a = wi.dot(Vec3::reflect(wo, n)).max(0.0);
                pd * cos_i * FRAC_1_PI + (1.0 - pd) * (exponent + 1.0) / TAU * cos_a.powf(exponent)
            }
            _ => 0.0,
        }
    }

    /// Samples `wi` from uniform numbers (see [`crate::Bsdfs::sample`]).
    #[must_use]
    pub fn sample(&self, n: Vec3, wo: Vec3, u: [f64; 3]) -> Option<BsdfSample> {
        match *self {
            Material::Diffuse { .. } | Material::Phong { .. } => {
                let ns = if wo.dot(n) < 0.0 { -n } else { n };
                if wo.dot(ns) <= 0.0 {
                    return None;
                }
                let wi = match *self {
                    Material::Phong {
                        diffuse,
                        specular,
                        exponent,
                    } if u[0] >= Self::phong_diffuse_probability(diffuse, specular) => {
                        phong_lobe(Vec3::reflect(wo, ns), exponent, [u[1], u[2]])
                    }
                    _ => cosine_hemisphere(ns, [u[1], u[2]]),
                };
                let pdf = self.pdf(n, wo, wi);
                (pdf > 0.0 && wi.dot(ns) > 0.0).then_some(BsdfSample {
                    wi,
                    pdf,
                    lobe: None,
                })
            }
            Material::Mirror { .. } => Some(BsdfSample {
                wi: self.specular_direction(n, wo, SpecularLobe::Reflection)?,
                pdf: 1.0,
                lobe: Some(SpecularLobe::Reflection),
            }),
            Material::Dielectric { .. } => {
                let f = self.specular_pdf(n, wo, SpecularLobe::Reflection);
                let lobe = if u[0] < f {
                    SpecularLobe::Reflection
                } else {
                    SpecularLobe::Refraction
                };
                Some(BsdfSample {
                    wi: self.specular_direction(n, wo, lobe)?,
                    pdf: self.specular_pdf(n, wo, lobe),
                    lobe: Some(lobe),
                })
            }
            Material::Black => None,
        }
    }

    fn dielectric_fresnel(ior: f64, n: Vec3, wo: Vec3) -> f64 {
        let cos_o = wo.dot(n);
        let eta = if cos_o > 0.0 { ior } else { 1.0 / ior };
        fresnel_dielectric(cos_o.abs(), eta)
    }

    /// The direction of a specular lobe (see [`crate::Bsdfs::specular_direction`]).
    #[must_use]
    pub fn specular_direction(&self, n: Vec3, wo: Vec3, lobe: SpecularLobe) -> Option<Vec3> {
        match (*self, lobe) {
            (Material::Mirror { .. } | Material::Dielectric { .. }, SpecularLobe::Reflection) => {
                Some(Vec3::reflect(wo, n).normalize())
            }
            (Material::Dielectric { ior, .. }, SpecularLobe::Refraction) => {
                let cos_o = wo.dot(n);
                let (eta, nn, cos_o) = if cos_o > 0.0 {
                    (ior, n, cos_o)
                } else {
                    (1.0 / ior, -n, -cos_o)
                };
                let sin2_t = (1.0 - cos_o * cos_o).max(0.0) / (eta * eta);
                if sin2_t >= 1.0 {
                    return None;
                }
                let cos_t = (1.0 - sin2_t).sqrt();
                Some((-wo / eta + nn * (cos_o / eta - cos_t)).normalize())
            }
            _ => None,
        }
    }

    /// The coefficient of a specular lobe (see [`crate::Bsdfs::specular_weight`]).
    #[must_use]
    pub fn specular_weight(&self, n: Vec3, wo: Vec3, lobe: SpecularLobe) -> Rgb {
        match (*self, lobe) {
            (Material::Mirror { reflectance }, SpecularLobe::Reflection) => reflectance,
            (Material::Dielectric { ior, tint }, lobe) => {
                let f = Self::dielectric_fresnel(ior, n, wo);
                tint * if lobe == SpecularLobe::Reflection {
                    f
                } else {
                    1.0 - f
                }
            }
            _ => Rgb::BLACK,
        }
    }

    /// The solid-angle Jacobian `dω_i / dω_o` of a specular lobe (see
    /// [`crate::Bsdfs::specular_jacobian`]): 1 for reflection, `cos θ_o / (η^2 cos θ_t)` for
    /// refraction with `η = η_t / η_o`.
    #[must_use]
    pub fn specular_jacobian(&self, n: Vec3, wo: Vec3, lobe: SpecularLobe) -> f64 {
        let Some(wi) = self.specular_direction(n, wo, lobe) else {
            return 0.0;
        };
        match (*self, lobe) {
            (Material::Dielectric { ior, .. }, SpecularLobe::Refraction) => {
                let cos_o = wo.dot(n);
                let eta = if cos_o > 0.0 { ior } else { 1.0 / ior };
                let cos_t = wi.dot(n).abs();
                if cos_t > 0.0 {
                    cos_o.abs() / (eta * eta * cos_t)
                } else {
                    0.0
                }
            }
            _ => 1.0,
        }
    }

    /// The lobe-selection probability (see [`crate::Bsdfs::specular_pdf`]).
    #[must_use]
    pub fn specular_pdf(&self, n: Vec3, wo: Vec3, lobe: SpecularLobe) -> f64 {
        match (*self, lobe) {
            (Material::Mirror { .. }, SpecularLobe::Reflection) => 1.0,
            (Material::Dielectric { ior, .. }, lobe) => {
                let f = Self::dielectric_fresnel(ior, n, wo);
                if lobe == SpecularLobe::Reflection {
                    f
                } else {
                    1.0 - f
                }
            }
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The sampling pdf integrates to at most 1 and matches a Monte Carlo estimate of the
    /// sample distribution's mass (sum of 1/pdf over samples estimates the solid angle).
    #[test]
    fn phong_pdf_is_normalised_over_the_sphere() {
        let m = Material::Phong {
            diffuse: Rgb::gray(0.3),
            specular: Rgb::gray(0.5),
            exponent: 15.0,
        };
        let n = Vec3::new(0.0, 0.0, 1.0);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        // Quadrature of the pdf over the upper hemisphere.
        let (nt, np) = (800, 800);
        let mut total = 0.0;
        for i in 0..nt {
            let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * TAU;
                let wi = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                total += m.pdf(n, wo, wi) * theta.sin();
            }
        }
        total *= std::f64::consts::FRAC_PI_2 / nt as f64 * TAU / np as f64;
        // Mass of accepted samples.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
        let trials = 200_000;
        let accepted = (0..trials)
            .filter(|_| {
                m.sample(n, wo, [rng.random(), rng.random(), rng.random()])
                    .is_some()
            })
            .count();
        let frac = accepted as f64 / trials as f64;
        assert!(
            (total - frac).abs() < 4e-3,
            "pdf mass {total} vs accepted {frac}"
        );
    }

    #[test]
    fn refraction_round_trip_and_fresnel_symmetry() {
        let m = Material::Dielectric {
            ior: 1.5,
            tint: Rgb::gray(1.0),
        };
        let n = Vec3::new(0.0, 0.0, 1.0);
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let wi = m
            .specular_direction(n, wo, SpecularLobe::Refraction)
            .unwrap();
        assert!(wi.z < 0.0);
        let back = m
            .specular_direction(n, wi, SpecularLobe::Refraction)
            .unwrap();
        assert!((back - wo).length() < 1e-12);
        let f1 = m.specular_pdf(n, wo, SpecularLobe::Reflection);
        let f2 = m.specular_pdf(n, wi, SpecularLobe::Reflection);
        assert!((f1 - f2).abs() < 1e-12);
    }
}
