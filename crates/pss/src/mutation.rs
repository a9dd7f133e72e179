//! One-dimensional mutation kernels on the unit circle [0, 1) used by small steps.

use std::f64::consts::PI;

use crate::PssError;

/// Wraps a real number into [0, 1) (re-exported from [`mcmc_core::torus`], where it lives).
pub use mcmc_core::torus::wrap;

/// Parameters of Kelemen's exponential perturbation (Kelemen et al. 2002, section 4.1; DR paper
/// eq. 9): the displacement magnitude is log-uniform on `[s1, s2]`, the sign is uniform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KelemenParams {
    /// Smallest displacement `s1` (default 1/1024).
    pub s1: f64,
    /// Largest displacement `s2` (default 1/64).
    pub s2: f64,
}

impl KelemenParams {
    /// Kelemen et al. 2002's values, `s1 = 1/1024`, `s2 = 1/64` (also the DRMLT defaults).
    #[must_use]
    pub const fn kelemen2002() -> Self {
        Self {
            s1: 1.0 / 1024.0,
            s2: 1.0 / 64.0,
        }
    }
}

impl Default for KelemenParams {
    fn default() -> Self {
        Self::kelemen2002()
    }
}

/// A symmetric one-dimensional perturbation of a coordinate on the unit circle (the torus
/// [0, 1) with wrap-around), applied independently to every primary sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SmallMutation {
    /// Kelemen's exponential perturbation: `|d| = s2 (s1/s2)^u`, log-uniform on `[s1, s2]`.
    Kelemen(KelemenParams),
    /// Isotropic Gaussian perturbation with standard deviation `sigma` (wrapped normal).
    Gaussian {
        /// Standard deviation.
        sigma: f64,
    },
    /// Uniform box perturbation `x + amount (2u - 1)`, wrapped: the displacement is uniform on
    /// `[-amount, amount]` (the small step of the KMLT baseline in Tessari et al. 2020's
    /// renderer, corona-13's `kmlt.c`).
    Uniform {
        /// Half-width of the box (`0 < amount <= 0.5`).
        amount: f64,
    },
}

impl SmallMutation {
    /// Kelemen's perturbation with validated parameters (`0 < s1 < s2 <= 0.5`).
    pub fn kelemen(params: KelemenParams) -> Result<Self, PssError> {
        if !(params.s1 > 0.0 && params.s1 < params.s2 && params.s2 <= 0.5) {
            return Err(PssError::InvalidParameter {
                name: "KelemenParams (s1, s2)",
                value: format!("({}, {})", params.s1, params.s2),
                allowed: "0 < s1 < s2 <= 0.5",
            });
        }
        Ok(SmallMutation::Kelemen(params))
    }

    /// A Gaussian perturbation with `0 < sigma <= 10`.
    pub fn gaussian(sigma: f64) -> Result<Self, PssError> {
        if !(sigma > 0.0 && sigma <= 10.0) {
            return Err(PssError::InvalidParameter {
                name: "sigma",
                value: sigma.to_string(),
                allowed: "(0, 10]",
            });
        }
        Ok(SmallMutation::Gaussian { sigma })
    }

    /// A uniform box perturbation with `0 < amount <= 0.5`.
    pub fn uniform(amount: f64) -> Result<Self, PssError> {
        if !(amount > 0.0 && amount <= 0.5) {
            return Err(PssError::InvalidParameter {
                name: "amount",
                value: amount.to_string(),
                allowed: "(0, 0.5]",
            });
        }
        Ok(SmallMutation::Uniform { amount })
    }

    /// Mean squared displacement of one (unwrapped) perturbation.
    #[must_use]
    pub fn mean_square_step(&self) -> f64 {
        match *self {
            SmallMutation::Kelemen(KelemenParams { s1, s2 }) => {
                (s2 * s2 - s1 * s1) / (2.0 * (s2 / s1).ln())
            }
            SmallMutation::Gaussian { sigma } => sigma * sigma,
            SmallMutation::Uniform { amount } => amount * amount / 3.0,
        }
    }

    /// Applies `count` independent perturbations to `x` using the uniforms `u(draw)`, and wraps
    /// the result into [0, 1).
    ///
    /// Gaussian: the sum of `count` perturbations is one Gaussian with `sqrt(count) sigma`
    /// (exact). Kelemen: `count` individual draws, except that once the accumulated variance
    /// `count E[d^2]` reaches 1 the wrapped distribution is uniform to within `2 exp(-2 pi^2)`
    /// ~ 5e-9 in density (Fourier series of the wrapped sum), and one fresh uniform is returned.
    /// Uniform: as Kelemen, one draw per perturbation.
    #[inline]
    pub fn apply(&self, x: f64, count: u64, mut u: impl FnMut(u64) -> f64) -> f64 {
        if count == 0 {
            return x;
        }
        match *self {
            SmallMutation::Gaussian { sigma } => {
                let s = sigma * (count as f64).sqrt();
                wrap(x + s * standard_normal_quantile(u(0)))
            }
            SmallMutation::Kelemen(KelemenParams { s1, s2 }) => {
                if count as f64 * self.mean_square_step() >= 1.0 {
                    return u(0);
                }
                let log_ratio = (s1 / s2).ln();
                let mut y = x;
                for k in 0..count {
                    let v = u(2 * k);
                    let d = s2 * (log_ratio * v).exp();
                    y = if u(2 * k + 1) < 0.5 { y + d } else { y - d };
                }
                wrap(y)
            }
            SmallMutation::Uniform { amount } => {
                if count as f64 * self.mean_square_step() >= 1.0 {
                    return u(0);
                }
                let mut y = x;
                for k in 0..count {
                    y += amount * (2.0 * u(k) - 1.0);
                }
                wrap(y)
            }
        }
    }

    /// Log density of moving `from -> to` on the unit circle by ONE perturbation (sum over
    /// the wrapped images of the displacement).
    #[must_use]
    pub fn log_density(&self, from: f64, to: f64) -> f64 {
        let d = to - from;
        let d = d - d.round(); // principal displacement in [-0.5, 0.5]
        match *self {
            SmallMutation::Kelemen(KelemenParams { s1, s2 }) => {
                let norm = 2.0 * (s2 / s1).ln();
                let mut p = 0.0;
                for k in -1..=1 {
                    let r = (d + f64::from(k)).abs();
                    if r >= s1 && r <= s2 {
                        p += 1.0 / (r * norm);
                    }
                }
                p.ln()
            }
            SmallMutation::Gaussian { sigma } => {
                let images = (6.0 * sigma).ceil() as i64 + 1;
                let mut p = 0.0;
                for k in -images..=images {
                    let z = (d + k as f64) / sigma;
                    p += (-0.5 * z * z).exp();
                }
                (p / (sigma * (2.0 * PI).sqrt())).ln()
            }
            SmallMutation::Uniform { amount } => {
                let mut p = 0.0;
                for k in -1..=1 {
                    if (d + f64::from(k)).abs() <= amount {
                        p += 0.5 / amount;
                    }
                }
                p.ln()
            }
        }
    }
}

/// The standard normal quantile function `Phi^-1(p)` for `p` in [0, 1) (0 maps to a finite
/// value), by Acklam's rational approximation (relative error below 1.15e-9 over the whole
/// range: far below what any statistical test of a chain can resolve). One uniform per
/// Gaussian draw, and no logarithm or cosine in the central 95% of the range, where almost all
/// draws fall: it replaced Box-Muller, whose `ln` and `cos` were a large share of an MMLT
/// mutation's cost (`docs/performance.md`, "Against the peer: rs_pbrt's MLT").
#[inline]
#[must_use]
pub fn standard_normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const LOW: f64 = 0.024_25;
    let p = p.clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON / 2.0);
    if p < LOW {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - LOW {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (1.0 - p).ln()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn integrate(m: SmallMutation, from: f64) -> f64 {
        let n = 200_000;
        (0..n)
            .map(|i| m.log_density(from, (i as f64 + 0.5) / n as f64).exp() / n as f64)
            .sum()
    }

    #[test]
    fn densities_are_normalised_and_symmetric() {
        for m in [
            SmallMutation::Kelemen(KelemenParams::kelemen2002()),
            SmallMutation::Gaussian { sigma: 0.05 },
            SmallMutation::Gaussian { sigma: 0.7 },
            SmallMutation::Uniform { amount: 0.01 },
            SmallMutation::Uniform { amount: 0.3 },
        ] {
            for from in [0.0, 0.3, 0.999] {
                let total = integrate(m, from);
                assert!((total - 1.0).abs() < 2e-3, "{m:?} {from}: {total}");
            }
            for (a, b) in [(0.001, 0.995), (0.5, 0.51), (0.2, 0.19), (0.5, 0.505)] {
                let (forward, backward) = (m.log_density(a, b), m.log_density(b, a));
                // Outside a box's support both are -inf.
                assert!(
                    forward == backward || (forward - backward).abs() < 1e-12,
                    "{m:?} {a} {b}: {forward} vs {backward}"
                );
            }
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(SmallMutation::kelemen(KelemenParams { s1: 0.1, s2: 0.01 }).is_err());
        assert!(SmallMutation::kelemen(KelemenParams { s1: 0.0, s2: 0.01 }).is_err());
        assert!(SmallMutation::gaussian(0.0).is_err());
        assert!(SmallMutation::gaussian(f64::NAN).is_err());
        assert!(SmallMutation::uniform(0.0).is_err());
        assert!(SmallMutation::uniform(0.6).is_err());
        assert!(SmallMutation::uniform(f64::NAN).is_err());
        assert!(SmallMutation::uniform(0.01).is_ok());
        assert!(SmallMutation::kelemen(KelemenParams::kelemen2002()).is_ok());
    }

    #[test]
    fn normal_quantile_matches_known_values() {
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959_963_984_540_054),
            (0.025, -1.959_963_984_540_054),
            (0.841_344_746_068_542_9, 1.0),
            (1e-6, -4.753_424_308_822_899),
            (0.999, 3.090_232_306_167_813_5),
        ] {
            let got = standard_normal_quantile(p);
            assert!(
                (got - z).abs() < 1e-8 * (1.0 + z.abs()),
                "p = {p}: {got} vs {z}"
            );
        }
        assert!(standard_normal_quantile(0.0).is_finite());
    }
}
