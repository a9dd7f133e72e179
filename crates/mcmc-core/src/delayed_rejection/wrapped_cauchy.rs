//! The wrapped Cauchy distribution on the circle: the angle law of the orbital second stage
//! (one implementation for the toy stages here and the primary-sample-space stages of `pss`).

use std::f64::consts::{PI, TAU};

use rand::{Rng, RngExt};

use crate::McmcError;

/// `exp(-1/4)`: the concentration the delayed-rejection MLT paper uses in all its orbital
/// experiments (section 5.1.1), also the authors' code default.
pub const RIOUX_LAVOIE2020_RHO: f64 = 0.778_800_783_071_404_9;

/// The wrapped Cauchy distribution of an angle `theta` on the circle, with concentration
/// `rho` in `[0, 1)` (delayed-rejection MLT paper, eq. 10):
///
/// `p(theta) = (1 - rho^2) / (2 pi (1 + rho^2 - 2 rho cos theta))`,
///
/// with respect to the angle measure `d theta` on `[-pi, pi)`. It is the uniform law for
/// `rho = 0` and concentrates at `theta = 0` as `rho -> 1` (a Dirac at `rho = 1`, which is
/// not allowed). Symmetric: `p(-theta) = p(theta)`.
///
/// Sampling inverts the closed-form CDF (the reason the paper picks this law):
/// `F(theta) = 1/2 + atan(k tan(theta / 2)) / pi` on `[-pi, pi)` with
/// `k = (1 + rho) / (1 - rho)`, so `theta = 2 atan(tan(pi (u - 1/2)) / k)` for one uniform `u`
/// (for `rho = exp(-kappa)`, `1 / k = tanh(kappa / 2)`). The authors' code instead draws
/// `|theta| = acos((v + c) / (1 + c v))` with `v = cos(2 pi u)`, `c = 2 rho / (1 + rho^2)`,
/// and a random sign: the same law from two uniforms.
///
/// # Example
/// ```
/// use mcmc_core::delayed_rejection::WrappedCauchy;
///
/// let wc = WrappedCauchy::rioux_lavoie2020();
/// assert!((wc.cdf(wc.quantile(0.3)) - 0.3).abs() < 1e-12);
/// assert!(wc.pdf(0.0) > wc.pdf(3.0));
/// assert!(WrappedCauchy::new(1.0).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrappedCauchy {
    rho: f64,
    /// `(1 - rho) / (1 + rho)`: the scale of the tangent in the quantile.
    inverse_k: f64,
    /// `log((1 - rho^2) / (2 pi))`.
    log_numerator: f64,
}

impl WrappedCauchy {
    /// The distribution with concentration `rho` in `[0, 1)`.
    ///
    /// # Errors
    /// [`McmcError::InvalidSetting`] if `rho` is outside `[0, 1)` or not finite.
    pub fn new(rho: f64) -> Result<Self, McmcError> {
        if !(0.0..1.0).contains(&rho) {
            return Err(McmcError::InvalidSetting {
                name: "rho",
                value: rho.to_string(),
                allowed: "[0, 1)",
            });
        }
        Ok(Self {
            rho,
            inverse_k: (1.0 - rho) / (1.0 + rho),
            log_numerator: ((1.0 - rho * rho) / TAU).ln(),
        })
    }

    /// `rho = exp(-1/4)` ([`RIOUX_LAVOIE2020_RHO`]), the paper's value (section 5.1.1).
    #[must_use]
    pub fn rioux_lavoie2020() -> Self {
        Self::new(RIOUX_LAVOIE2020_RHO).expect("valid constant")
    }

    /// The concentration `rho`.
    #[must_use]
    pub fn rho(&self) -> f64 {
        self.rho
    }

    /// The density at angle `theta` (any real number; the density is `2 pi`-periodic), eq. 10.
    #[must_use]
    pub fn pdf(&self, theta: f64) -> f64 {
        self.log_pdf(theta).exp()
    }

    /// The log density at angle `theta`.
    #[must_use]
    pub fn log_pdf(&self, theta: f64) -> f64 {
        let r = self.rho;
        self.log_numerator - (1.0 + r * r - 2.0 * r * theta.cos()).ln()
    }

    /// `P(Theta < theta)` for `theta` in `[-pi, pi)` (other angles are first wrapped into
    /// that interval).
    #[must_use]
    pub fn cdf(&self, theta: f64) -> f64 {
        let t = wrap_angle(theta);
        let f = 0.5 + ((t * 0.5).tan() / self.inverse_k).atan() / PI;
        f.clamp(0.0, 1.0)
    }

    /// The angle in `[-pi, pi]` with `cdf(angle) = u`, for `u` in `[0, 1)`: inversion
    /// sampling. Increasing in `u`; `quantile(1/2) = 0`.
    #[inline]
    #[must_use]
    pub fn quantile(&self, u: f64) -> f64 {
        2.0 * (self.inverse_k * (PI * (u - 0.5)).tan()).atan()
    }

    /// One draw from one uniform of `rng`.
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.quantile(rng.random())
    }

    /// `(cos theta, sin theta)` of `theta = quantile(u)`, without the angle: with
    /// `tau = tan(theta / 2) = tan(pi (u - 1/2)) / k` (the quantile's inner term), the
    /// half-angle identities give `cos theta = (1 - tau^2) / (1 + tau^2)` and
    /// `sin theta = 2 tau / (1 + tau^2)`. The same law as [`WrappedCauchy::quantile`] (the
    /// same map of `u`, to rounding), at one tangent instead of a tangent, an arctangent and
    /// a sine-cosine. `u = 0` gives the rotation by `pi`.
    #[inline]
    #[must_use]
    pub fn rotation(&self, u: f64) -> (f64, f64) {
        let tau = self.inverse_k * (PI * (u - 0.5)).tan();
        if !tau.is_finite() || tau.abs() > 1e150 {
            return (-1.0, 0.0);
        }
        let t2 = tau * tau;
        let inv = 1.0 / (1.0 + t2);
        ((1.0 - t2) * inv, 2.0 * tau * inv)
    }

    /// `(cos theta, sin theta)` with `tan(theta / 2) = tan(phi) / k`, `phi` the angle of the
    /// point `(x, y)` (not the origin): [`WrappedCauchy::rotation`] with the angle
    /// `pi (u - 1/2)` replaced by `phi`. A point whose angle is uniform on the circle (a
    /// uniform point of a disc) gives the law of eq. 10, since `tan(phi)` is then standard
    /// Cauchy like `tan(pi (u - 1/2))`; no trigonometry: with `t = y / k`,
    /// `cos theta = (x^2 - t^2) / (x^2 + t^2)`, `sin theta = 2 x t / (x^2 + t^2)`.
    #[inline]
    #[must_use]
    pub fn rotation_of_point(&self, x: f64, y: f64) -> (f64, f64) {
        let t = self.inverse_k * y;
        let norm = x * x + t * t;
        if norm.is_nan() || norm <= 0.0 {
            return (1.0, 0.0);
        }
        let inv = 1.0 / norm;
        ((x * x - t * t) * inv, 2.0 * x * t * inv)
    }

    /// `|sin(theta / 2)|` of [`WrappedCauchy::rotation_of_point`]`(x, y)`, `|t| / sqrt(x^2 +
    /// t^2)`: half the length of `d - R(theta) d` for a unit `d`.
    #[inline]
    #[must_use]
    pub fn half_angle_sine_of_point(&self, x: f64, y: f64) -> f64 {
        let t = self.inverse_k * y;
        let norm = x * x + t * t;
        if norm.is_nan() || norm <= 0.0 {
            return 0.0;
        }
        t.abs() / norm.sqrt()
    }

    /// One rotation ([`WrappedCauchy::rotation`]) from one uniform of `rng`.
    #[inline]
    pub fn sample_rotation<R: Rng + ?Sized>(&self, rng: &mut R) -> (f64, f64) {
        self.rotation(rng.random())
    }

    /// The log density (eq. 10) of an angle given by its cosine: `log_pdf(theta)` for
    /// `cos_theta = cos(theta)` (clamped to `[-1, 1]`), without the angle.
    #[inline]
    #[must_use]
    pub fn log_pdf_cos(&self, cos_theta: f64) -> f64 {
        let r = self.rho;
        self.log_numerator - (1.0 + r * r - 2.0 * r * cos_theta.clamp(-1.0, 1.0)).ln()
    }
}

impl Default for WrappedCauchy {
    /// [`WrappedCauchy::rioux_lavoie2020`].
    fn default() -> Self {
        Self::rioux_lavoie2020()
    }
}

/// Wraps an angle into `[-pi, pi)`.
#[inline]
#[must_use]
pub(crate) fn wrap_angle(theta: f64) -> f64 {
    let t = theta - TAU * ((theta + PI) / TAU).floor();
    if t >= PI {
        t - TAU
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_is_exp_minus_quarter() {
        assert!((RIOUX_LAVOIE2020_RHO - (-0.25f64).exp()).abs() < 1e-16);
        let wc = WrappedCauchy::rioux_lavoie2020();
        assert!((wc.inverse_k - (0.125f64).tanh()).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_rho() {
        for rho in [-0.1, 1.0, 1.5, f64::NAN, f64::INFINITY] {
            assert!(WrappedCauchy::new(rho).is_err(), "{rho}");
        }
        assert!(WrappedCauchy::new(0.0).is_ok());
        assert!(WrappedCauchy::new(0.999).is_ok());
    }

    #[test]
    fn density_integrates_to_one_and_is_the_cdf_derivative() {
        for rho in [0.0, 0.3, RIOUX_LAVOIE2020_RHO, 0.95] {
            let wc = WrappedCauchy::new(rho).unwrap();
            let n = 200_000;
            let h = TAU / n as f64;
            let total: f64 = (0..n).map(|i| wc.pdf(-PI + (i as f64 + 0.5) * h) * h).sum();
            assert!((total - 1.0).abs() < 1e-9, "rho {rho}: {total}");
            for theta in [-2.5, -0.4, 0.0, 0.1, 1.0, 3.0] {
                let d = 1e-6;
                let numeric = (wc.cdf(theta + d) - wc.cdf(theta - d)) / (2.0 * d);
                assert!(
                    (numeric - wc.pdf(theta)).abs() < 1e-6 * (1.0 + wc.pdf(theta)),
                    "rho {rho}, theta {theta}: {numeric} vs {}",
                    wc.pdf(theta)
                );
            }
            assert!((wc.pdf(0.7) - wc.pdf(-0.7)).abs() < 1e-15);
            assert!((wc.pdf(0.7) - wc.pdf(0.7 + TAU)).abs() < 1e-12);
        }
    }

    #[test]
    fn quantile_inverts_cdf() {
        for rho in [0.0, 0.5, RIOUX_LAVOIE2020_RHO, 0.99] {
            let wc = WrappedCauchy::new(rho).unwrap();
            assert_eq!(wc.quantile(0.5), 0.0);
            let mut last = -PI - 1e-9;
            for i in 0..1000 {
                let u = (i as f64 + 0.5) / 1000.0;
                let t = wc.quantile(u);
                assert!(t > last && (-PI..=PI).contains(&t));
                last = t;
                assert!((wc.cdf(t) - u).abs() < 1e-12, "rho {rho}, u {u}");
            }
            assert!(wc.quantile(0.0).is_finite());
        }
        let uniform = WrappedCauchy::new(0.0).unwrap();
        assert!((uniform.quantile(0.75) - PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn rotation_of_a_point_is_the_rotation_of_its_angle() {
        for rho in [0.0, 0.5, RIOUX_LAVOIE2020_RHO, 0.99] {
            let wc = WrappedCauchy::new(rho).unwrap();
            for i in 1..1000 {
                // The angle phi = pi (u - 1/2) in (-pi/2, pi/2), at radii 0.3 and 1, and the
                // opposite point (angle phi + pi, the same tangent).
                let u = i as f64 / 1000.0;
                let phi = PI * (u - 0.5);
                let (c, s) = wc.rotation(u);
                for (x, y) in [(phi.cos(), phi.sin()), (-0.3 * phi.cos(), -0.3 * phi.sin())] {
                    let (pc, ps) = wc.rotation_of_point(x, y);
                    assert!(
                        (pc - c).abs() < 1e-12 && (ps - s).abs() < 1e-12,
                        "rho {rho} u {u}"
                    );
                    let half = wc.half_angle_sine_of_point(x, y);
                    assert!(
                        (half - (0.5 * (1.0 - c)).sqrt()).abs() < 1e-12,
                        "rho {rho} u {u}"
                    );
                }
            }
        }
    }

    #[test]
    fn rotation_is_the_quantile_without_the_angle() {
        for rho in [0.0, 0.5, RIOUX_LAVOIE2020_RHO, 0.99] {
            let wc = WrappedCauchy::new(rho).unwrap();
            for i in 0..=1000 {
                let u = i as f64 / 1000.0;
                let theta = wc.quantile(u);
                let (c, s) = wc.rotation(u);
                assert!((c - theta.cos()).abs() < 1e-12, "rho {rho} u {u}");
                assert!((s - theta.sin()).abs() < 1e-12, "rho {rho} u {u}");
                assert!((c * c + s * s - 1.0).abs() < 1e-14);
                assert!((wc.log_pdf_cos(c) - wc.log_pdf(theta)).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn angles_wrap_into_half_open_interval() {
        for t in [-PI, PI, 3.0 * PI, -7.0, 0.0, 10.0] {
            let w = wrap_angle(t);
            assert!((-PI..PI).contains(&w), "{t} -> {w}");
            assert!(((t - w) / TAU - ((t - w) / TAU).round()).abs() < 1e-12);
        }
    }

    /// The wrapped Cauchy density integrates to 1, and inverse-CDF samples follow it: the
    /// fraction of `angle(u)` below `t` is `F(t)`, checked on a fine `u` grid (deterministic).
    #[test]
    fn wrapped_cauchy_is_normalised_and_inverts_its_cdf() {
        let wc = WrappedCauchy::new(0.7).unwrap();
        let n = 200_000;
        let h = TAU / n as f64;
        let total: f64 = (0..n)
            .map(|i| wc.log_pdf(-PI + (i as f64 + 0.5) * h).exp() * h)
            .sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        // CDF by quadrature at a few points vs the sampler's quantiles.
        for &u in &[0.05, 0.3, 0.5, 0.77, 0.99] {
            let t = wc.quantile(u);
            let m = 100_000;
            let w = (t + PI) / m as f64;
            let cdf: f64 = (0..m)
                .map(|i| wc.log_pdf(-PI + (i as f64 + 0.5) * w).exp() * w)
                .sum();
            assert!((cdf - u).abs() < 1e-8, "u {u}: F(angle(u)) = {cdf}");
        }
    }
}
