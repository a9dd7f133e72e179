//! Angular perturbation of a ray direction: a polar angle from a normal truncated to
//! `[-pi, pi]`, a uniform azimuth, and the resulting solid-angle density.

use std::f64::consts::{PI, TAU};

use mcmc_core::special::normal_interval;
use rand::{Rng, RngExt};

use crate::vec3::Vec3;

/// How a direction is perturbed around its current value: a law of the polar angle `θ`
/// (angle between old and new direction) at scale `sigma`, the azimuth uniform, and the
/// solid-angle density of the result.
///
/// The density must be the true density of `sample` on the sphere (a
/// [`TruncatedNormalDirection`] in production; tests substitute deliberately wrong densities
/// to show that the checks catch them).
pub trait DirectionKernel {
    /// Draws `(θ, φ)` with `θ` in `[0, pi]` and `φ` in `[0, 2 pi)`.
    fn sample_angles<R: Rng + ?Sized>(&self, sigma: f64, rng: &mut R) -> (f64, f64);

    /// Log solid-angle density of a new direction at polar angle `theta` in `[0, pi]` from the
    /// old one (it depends on nothing else: the kernel is isotropic).
    fn log_density(&self, theta: f64, sigma: f64) -> f64;
}

/// The regional-adaptive paper's kernel (section 3.3): `θ ~ N(0, sigma^2)` truncated to
/// `[-pi, pi]`, `φ ~ U[0, 2 pi)`; a negative `θ` folds onto `(|θ|, φ + pi)`.
///
/// The folded polar density is `p(θ) = 2 N(θ; 0, sigma) / Z` on `[0, pi]` with the truncation
/// normaliser `Z = Phi(pi / sigma) - Phi(-pi / sigma)`; with `φ` uniform and
/// `dω = sin θ dθ dφ`, the solid-angle density is
///
/// `p_ω(θ) = p(θ) / (2 pi sin θ)`
///
/// (the `sin θ` Jacobian is what a density "in θ" forgets; the reference-notes pitfall 5).
/// It is symmetric in old and new direction at equal `sigma`.
///
/// # Example
/// ```
/// use pathspace::perturb::{angle_between, rotate_direction, DirectionKernel};
/// use pathspace::{TruncatedNormalDirection, Vec3};
/// use rand::SeedableRng;
///
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
/// let w = Vec3::new(0.0, 0.0, 1.0);
/// let (theta, phi) = TruncatedNormalDirection.sample_angles(0.1, &mut rng);
/// let v = rotate_direction(w, theta, phi);
/// assert!((angle_between(w, v) - theta).abs() < 1e-12);
/// // Solid-angle density, including 1 / (2 pi sin theta).
/// assert!(TruncatedNormalDirection.log_density(theta, 0.1).is_finite());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TruncatedNormalDirection;

impl TruncatedNormalDirection {
    /// `ln p(θ)`, the folded polar-angle density on `[0, pi]` (no `sin θ`).
    #[must_use]
    pub fn log_polar_density(theta: f64, sigma: f64) -> f64 {
        if !(0.0..=PI).contains(&theta) || sigma.is_nan() || sigma <= 0.0 {
            return f64::NEG_INFINITY;
        }
        let t = theta / sigma;
        std::f64::consts::LN_2 - 0.5 * t * t - (sigma * (TAU).sqrt()).ln() - log_truncation(sigma)
    }
}

/// Largest `sigma` whose truncation normaliser `Z = Phi(pi / sigma) - Phi(-pi / sigma)` is
/// `1.0` in `f64`: `pi / sigma >= 9` puts each tail below `Phi(-9) < 2^-62`, far under half an
/// ulp of 1.
const UNTRUNCATED_SIGMA: f64 = PI / 9.0;

/// `ln Z` of [`TruncatedNormalDirection`]: exactly `0` for `sigma <= pi / 9` (the value
/// [`normal_interval`] returns there is `1.0`, so this is the same number without the
/// incomplete-gamma evaluation the perturbations would otherwise pay twice per step).
#[inline]
fn log_truncation(sigma: f64) -> f64 {
    if sigma <= UNTRUNCATED_SIGMA {
        0.0
    } else {
        normal_interval(-PI / sigma, PI / sigma).ln()
    }
}

impl DirectionKernel for TruncatedNormalDirection {
    fn sample_angles<R: Rng + ?Sized>(&self, sigma: f64, rng: &mut R) -> (f64, f64) {
        let theta = if sigma <= PI {
            // Rejection from the untruncated normal: acceptance >= Z(1) = 0.9983.
            loop {
                let t = sigma * standard_normal(rng);
                if t.abs() <= PI {
                    break t;
                }
            }
        } else {
            // Rejection from the uniform on [-pi, pi]: acceptance >= exp(-1/2).
            loop {
                let t = PI * (2.0 * rng.random::<f64>() - 1.0);
                let u: f64 = rng.random();
                if u < (-0.5 * (t / sigma) * (t / sigma)).exp() {
                    break t;
                }
            }
        };
        let phi = TAU * rng.random::<f64>();
        if theta < 0.0 {
            let phi = phi + PI;
            (-theta, if phi >= TAU { phi - TAU } else { phi })
        } else {
            (theta, phi)
        }
    }

    fn log_density(&self, theta: f64, sigma: f64) -> f64 {
        Self::log_polar_density(theta, sigma) - TAU.ln() - theta.sin().ln()
    }
}

/// A standard normal variate (Box-Muller; one of the pair is used).
fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    let u1 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

/// The direction at polar angle `theta` and azimuth `phi` around the unit vector `w`.
#[must_use]
pub fn rotate_direction(w: Vec3, theta: f64, phi: f64) -> Vec3 {
    let (t, b) = w.orthonormal_basis();
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    (t * (st * cp) + b * (st * sp) + w * ct).normalize()
}

/// The angle in `[0, pi]` between two unit vectors (accurate for small and large angles).
#[must_use]
pub fn angle_between(a: Vec3, b: Vec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn polar_density_integrates_to_one() {
        for sigma in [0.01, 0.3, 1.65, 5.0, 100.0] {
            let n = 200_000;
            let h = PI / n as f64;
            let s: f64 = (0..n)
                .map(|i| {
                    TruncatedNormalDirection::log_polar_density((i as f64 + 0.5) * h, sigma).exp()
                        * h
                })
                .sum();
            assert!((s - 1.0).abs() < 1e-6, "sigma {sigma}: {s}");
        }
    }

    #[test]
    fn untruncated_shortcut_is_the_same_number() {
        // Every sigma up to the shortcut's bound (log-spaced, and the bound itself): the
        // normaliser the shortcut skips is exactly 1.
        let n = 10_000;
        for i in 0..=n {
            let sigma = UNTRUNCATED_SIGMA * (1e-6f64).powf(i as f64 / n as f64);
            assert_eq!(
                normal_interval(-PI / sigma, PI / sigma),
                1.0,
                "sigma {sigma}"
            );
            assert_eq!(log_truncation(sigma).to_bits(), 0.0f64.to_bits());
        }
        // Negative control: at the larger scales the adaptive variants can reach the
        // normaliser is below 1, so a shortcut without the bound would change the density.
        for sigma in [0.5, 1.0, PI, 10.0] {
            let z = normal_interval(-PI / sigma, PI / sigma);
            assert!(z < 1.0, "sigma {sigma}: {z}");
            assert_eq!(log_truncation(sigma), z.ln());
        }
    }

    #[test]
    fn rotation_has_the_requested_angle() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let w = Vec3::new(0.2, -0.5, 0.7).normalize();
        for _ in 0..100 {
            let (theta, phi) = TruncatedNormalDirection.sample_angles(1.0, &mut rng);
            let v = rotate_direction(w, theta, phi);
            assert!((angle_between(w, v) - theta).abs() < 1e-9);
        }
    }
}
