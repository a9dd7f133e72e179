//! Geometric optics at a smooth interface: mirror reflection, Snell refraction and the Fresnel
//! reflectances (exact dielectric, Schlick's approximation for conductors).
//!
//! Conventions: every direction points *away* from the surface; the normal `n` defines the
//! "outside" (`n . w > 0`), and `eta = n_inside / n_outside` is the relative index of refraction
//! of the medium on the `-n` side over the `+n` side.

use glam::{Vec3, Vec3A};

/// Mirror reflection of `wo` about the unit normal `n`: `-wo + 2 (wo . n) n`.
#[must_use]
#[inline]
pub fn reflect(wo: Vec3A, n: Vec3A) -> Vec3A {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refraction of `wi` through an interface with unit normal `n` and relative IOR
/// `eta = n_inside / n_outside` (Snell's law; PBR 4th ed. §9.3.2, pbrt-v4 `Refract`).
///
/// `wi` may lie on either side of the interface: if `wi . n < 0` the roles of the two media are
/// swapped. Returns the transmitted direction and `etap`, the relative IOR actually crossed
/// (`n_transmitted_side / n_incident_side`), or `None` at total internal reflection.
#[must_use]
#[inline]
pub fn refract(wi: Vec3A, n: Vec3A, eta: f32) -> Option<(Vec3A, f32)> {
    let mut cos_i = n.dot(wi);
    let (mut etap, mut n) = (eta, n);
    if cos_i < 0.0 {
        etap = 1.0 / etap;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (etap * etap);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wi / etap + (cos_i / etap - cos_t) * n, etap))
}

/// Unpolarised Fresnel reflectance of a dielectric interface (PBR 4th ed. eq. 9.5-9.6; Born &
/// Wolf). `cos_theta_i` is the cosine between the incident direction and the normal; a negative
/// value means the direction is inside (the `-n` side), which swaps the media. Returns 1 at
/// total internal reflection.
#[must_use]
#[inline]
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)
}

/// Schlick's approximation of the Fresnel reflectance, `F0 + (1 - F0) (1 - cos)^5` per RGB
/// channel (Schlick 1994, "An Inexpensive BRDF Model for Physically-based Rendering", eq. 15),
/// as used for glTF metals (glTF 2.0 spec, Appendix B). `cos_theta` is clamped to `[0, 1]`.
#[must_use]
#[inline]
pub fn fresnel_schlick(f0: Vec3, cos_theta: f32) -> Vec3 {
    let m = (1.0 - cos_theta.clamp(0.0, 1.0)).max(0.0);
    let m2 = m * m;
    f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_and_refract_obey_snell() {
        let n = Vec3A::Z;
        let wo = Vec3A::new(0.6, 0.0, 0.8);
        assert!((reflect(wo, n) - Vec3A::new(-0.6, 0.0, 0.8)).length() < 1e-6);

        let (wt, etap) = refract(wo, n, 1.5).expect("no TIR entering glass");
        assert_eq!(etap, 1.5);
        assert!((wt.length() - 1.0).abs() < 1e-6 && wt.z < 0.0);
        // n_i sin_i = n_t sin_t, with the tangential component flipped.
        assert!((0.6 - 1.5 * (-wt.x)).abs() < 1e-6);
        // Refracting back out recovers wo.
        let (back, etap_back) = refract(wt, n, 1.5).expect("reverse path exists");
        assert!((back - wo).length() < 1e-5);
        assert!((etap_back - 1.0 / 1.5).abs() < 1e-6);
        // Total internal reflection from inside at grazing angles.
        assert!(refract(Vec3A::new(0.9, 0.0, -0.435_889_9), n, 1.5).is_none());
    }

    #[test]
    fn dielectric_fresnel_known_values() {
        // Normal incidence: ((eta - 1) / (eta + 1))^2 = 0.04 for glass.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything.
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        // Brewster's angle: the parallel component vanishes, R = r_perp^2 / 2.
        let theta_b = 1.5f32.atan();
        let r = fresnel_dielectric(theta_b.cos(), 1.5);
        assert!(r > 0.0 && r < 0.08);
        // Matched media do not reflect.
        assert!(fresnel_dielectric(0.3, 1.0).abs() < 1e-7);
        // Inside beyond the critical angle: total internal reflection.
        assert_eq!(fresnel_dielectric(-0.2, 1.5), 1.0);
        // Reciprocity: the same for the incident and refracted angle.
        let wo = Vec3A::new(0.5, 0.0, 0.75f32.sqrt());
        let (wt, _) = refract(wo, Vec3A::Z, 1.33).expect("entering water");
        assert!((fresnel_dielectric(wo.z, 1.33) - fresnel_dielectric(wt.z, 1.33)).abs() < 1e-5);
    }

    #[test]
    fn schlick_limits() {
        let f0 = Vec3::new(0.9, 0.6, 0.1);
        assert_eq!(fresnel_schlick(f0, 1.0), f0);
        assert!((fresnel_schlick(f0, 0.0) - Vec3::ONE).abs().max_element() < 1e-6);
        assert_eq!(fresnel_schlick(Vec3::ONE, 0.3), Vec3::ONE);
    }
}
