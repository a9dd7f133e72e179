//! Parameters of MALA with adaptation, with the paper's and the authors' code's presets.

use crate::McmcError;

/// How the Adam-like accumulators of online adaptation (`G`, `d`; Luan et al. 2020, Alg. 2)
/// start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AdamStart {
    /// At zero, without bias correction (the paper's text, footnote 2). With `beta = 0.999`,
    /// `G` is about `0.001 t g^2` after `t` steps, which inflates `M` by about `31 / sqrt(t)`
    /// early on.
    #[default]
    Zero,
    /// At the first gradient (`G = g (.) g`, `d = g`) at the first step after a restart, and
    /// restarted whenever a large step is accepted (the authors' code: an implicit bias
    /// correction, statistics local to the region the chain explores).
    FirstVisit,
}

/// How the step size and the preconditioner make the proposal covariance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Covariance {
    /// `Sigma = epsilon M` (the paper's eq. 7, 9, 18, 28: `epsilon` is a variance; with
    /// `epsilon = 0.01` a standard deviation of 0.1 per coordinate where `M = 1`).
    #[default]
    EpsilonM,
    /// `Sigma = epsilon^2 (M + 1)` (the authors' code, `ComputeGaussian`: `epsilon` is a
    /// standard deviation, and the `+ 1` is a floor, so no coordinate moves by less than
    /// `epsilon` however small `M` is).
    EpsilonSquaredMPlusOne,
}

/// Parameters of the Metropolis-adjusted Langevin algorithm with adaptation (Luan et al.
/// 2020, Alg. 1-4). Plain data with
/// documented defaults ([`LangevinParams::luan2020`]); [`LangevinParams::validate`] checks
/// the ranges.
///
/// The proposal from a point `u` with (truncated) gradient `g` is the Gaussian
/// `N(u + Sigma m / 2, Sigma)` with `Sigma = epsilon M` (eq. 9, 18, 28): `M` is the
/// preconditioner and `m` the drift vector of the adaptation in use. Two safeguards that the
/// paper does not have are off in the paper preset: [`LangevinParams::preconditioner_range`]
/// clamps the diagonal of `M`, and [`LangevinParams::max_std`] adds a Gaussian "shrink prior"
/// of that standard deviation to the proposal's precision, `Sigma^-1 + I / max_std^2`
/// (the authors' code does both; docs/methods/mala.md, "Readings and deliberate departures").
///
/// # Presets
/// Three readings of the same method, named for what they read how:
///
/// | preset | values | covariance | `M` clamp | drift clamp | prior | radius | Adam start |
/// |---|---|---|---|---|---|---|---|
/// | [`LangevinParams::luan2020`] (paper's text) | `eps` 0.01, `K` 30, `H` 10 000, `r` 0.01 | `eps M` | none | none | none | `r` | zero |
/// | [`LangevinParams::luan2020_values`] (paper's values, code's semantics) | as the text | `eps^2 (M + 1)` | `[0.01, 100]` | 5 | none | `r sqrt(d)` | first visit |
/// | [`LangevinParams::luan2020_code`] (the code) | `eps` 0.005, `K` 5, `H` 3000, `r` 0.01 | `eps^2 (M + 1)` | `[0.01, 100]` | 5 | 0.005 | `r sqrt(d)` | first visit |
///
/// # Example
/// ```
/// use mcmc_core::langevin::LangevinParams;
///
/// let paper = LangevinParams::luan2020();
/// assert_eq!((paper.epsilon, paper.neighbours, paper.cache_size), (0.01, 30, 10_000));
/// let code = LangevinParams::luan2020_code();
/// assert_eq!((code.epsilon, code.neighbours, code.cache_size), (0.005, 5, 3000));
/// assert!(paper.validate().is_ok() && code.validate().is_ok());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LangevinParams {
    /// Step size `epsilon` (eq. 6-9): the proposal covariance is `epsilon M`. Paper: 0.01.
    pub epsilon: f64,
    /// Gradient truncation: every component of the gradient is clamped to
    /// `[-max_gradient, max_gradient]` (section 7, "Truncated gradients"). Paper: 100.
    pub max_gradient: f64,
    /// Momentum decay `alpha` (eq. 14, Alg. 2). Paper: 0.9.
    pub alpha: f64,
    /// Accumulation decay `beta` (eq. 10, Alg. 2). Paper: 0.999.
    pub beta: f64,
    /// Uniform preconditioning weight `delta` (eq. 11, 24). Paper: 0.001.
    pub delta: f64,
    /// Diminishing-adaptation exponent `c1` of the preconditioner (eq. 19). The paper gives no
    /// value; ours: 0.5, the usual stochastic-approximation rate (Andrieu & Thoms 2008). See
    /// [`crate::langevin::Online`] for the reading of eq. 19.
    pub c1: f64,
    /// Diminishing-adaptation exponent `c2` of the momentum (eq. 20). The paper gives no value;
    /// ours: 0.5.
    pub c2: f64,
    /// Cache query radius `r` (eq. 22). Paper: 0.01. See
    /// [`LangevinParams::radius_per_dimension`].
    pub radius: f64,
    /// If true, a query in `d` dimensions uses the radius `r sqrt(d)` (the authors' code:
    /// nanoflann's squared radius `d r^2`, i.e. `r` per coordinate); if false, `r` (the
    /// paper's text). In 13-16 dimensions a radius of 0.01 finds almost only exact revisits.
    pub radius_per_dimension: bool,
    /// How `epsilon` and `M` make the covariance ([`Covariance`]). Paper:
    /// [`Covariance::EpsilonM`]; the authors' code: [`Covariance::EpsilonSquaredMPlusOne`].
    pub covariance: Covariance,
    /// Every component of the drift vector `m` is clamped to `[-drift_clamp, drift_clamp]`
    /// (`INFINITY`: none). Paper: none; the authors' code clamps its drift (the momentum) to
    /// `[-5, 5]` (`MTM_MIN`, `MTM_MAX`).
    pub drift_clamp: f64,
    /// Cache query neighbours `K`: the query keeps the `K` nearest entries within `r`
    /// (section 7). Paper: 30.
    pub neighbours: usize,
    /// Cache size `H`: the cache stops growing at `H` entries (finite adaptation, section 6).
    /// Paper: 10 000.
    pub cache_size: usize,
    /// Clamp `[lo, hi]` of the diagonal of the preconditioner `M`. Paper: none
    /// (`[0, inf]`); the authors' code: `[0.01, 100]`.
    pub preconditioner_range: [f64; 2],
    /// Standard deviation of the isotropic shrink prior whose precision is added to the
    /// proposal's (`INFINITY`: none). Paper: none; the authors' code: 0.005.
    pub max_std: f64,
    /// How online adaptation's accumulators start ([`AdamStart`]). Paper:
    /// [`AdamStart::Zero`]; the authors' code: [`AdamStart::FirstVisit`].
    pub adam_start: AdamStart,
}

impl LangevinParams {
    /// The paper's settings (section 7, "Parameter settings"): `alpha = 0.9`,
    /// `beta = 0.999`, `delta = 0.001`, `epsilon = 0.01`, `r = 0.01`, `K = 30`, `H = 10 000`,
    /// truncation 100; `c1 = c2 = 0.5` (not given in the paper); no clamp, no shrink prior.
    #[must_use]
    pub const fn luan2020() -> Self {
        Self {
            epsilon: 0.01,
            max_gradient: 100.0,
            alpha: 0.9,
            beta: 0.999,
            delta: 0.001,
            c1: 0.5,
            c2: 0.5,
            radius: 0.01,
            radius_per_dimension: false,
            covariance: Covariance::EpsilonM,
            drift_clamp: f64::INFINITY,
            neighbours: 30,
            cache_size: 10_000,
            preconditioner_range: [0.0, f64::INFINITY],
            max_std: f64::INFINITY,
            adam_start: AdamStart::Zero,
        }
    }

    /// The paper's values (section 7: `epsilon = 0.01`, `K = 30`, `H = 10 000`, `r = 0.01`,
    /// no shrink prior) read with the authors' code's semantics: covariance
    /// `epsilon^2 (M + 1)` (a standard deviation from 0.01 to about 0.1), `M` clamped to
    /// `[0.01, 100]`, drift clamped to `+-5`, query radius `r sqrt(d)`, Adam moments started
    /// at the first visit and restarted on an accepted large step.
    #[must_use]
    pub const fn luan2020_values() -> Self {
        Self {
            radius_per_dimension: true,
            covariance: Covariance::EpsilonSquaredMPlusOne,
            drift_clamp: 5.0,
            preconditioner_range: [0.01, 100.0],
            adam_start: AdamStart::FirstVisit,
            ..Self::luan2020()
        }
    }

    /// The authors' public code (`dptoptions.h`, `global_cache.h`, `mala.cpp`;
    /// docs/methods/mala.md): `epsilon = 0.005` as a standard deviation (covariance
    /// `epsilon^2 (M + 1)`), shrink prior 0.005 (precision `1 / (epsilon^2 (M + 1)) +
    /// 1 / 0.005^2`), `M` clamped to `[0.01, 100]`, drift clamped to `+-5`, `K = 5`,
    /// `H = 3000`, query radius `0.01 sqrt(d)`, Adam moments started at the first visit and
    /// restarted on an accepted large step; the other values as [`LangevinParams::luan2020`].
    /// The drift vector itself stays the paper's (eq. 14, 20: the gradient plus the
    /// momentum; the code's drift is the momentum alone).
    #[must_use]
    pub const fn luan2020_code() -> Self {
        Self {
            epsilon: 0.005,
            neighbours: 5,
            cache_size: 3000,
            max_std: 0.005,
            ..Self::luan2020_values()
        }
    }

    /// The query radius in `dim` dimensions ([`LangevinParams::radius_per_dimension`]).
    #[must_use]
    pub fn query_radius(&self, dim: usize) -> f64 {
        if self.radius_per_dimension {
            self.radius * (dim as f64).sqrt()
        } else {
            self.radius
        }
    }

    /// Checks every parameter's range.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] naming the first parameter out of range.
    pub fn validate(&self) -> Result<(), McmcError> {
        let positive = |name, v: f64| {
            if v > 0.0 && !v.is_nan() {
                Ok(())
            } else {
                Err(McmcError::InvalidParameter {
                    name,
                    value: v,
                    allowed: "> 0",
                })
            }
        };
        McmcError::check_range("epsilon", self.epsilon, 1e-12, 1e6, "[1e-12, 1e6]")?;
        positive("max_gradient", self.max_gradient)?;
        McmcError::check_range("alpha", self.alpha, 0.0, 1.0, "[0, 1]")?;
        McmcError::check_range("beta", self.beta, 0.0, 1.0, "[0, 1]")?;
        McmcError::check_range("delta", self.delta, 1e-12, 1e12, "[1e-12, 1e12]")?;
        McmcError::check_range("c1", self.c1, 0.0, 10.0, "[0, 10]")?;
        McmcError::check_range("c2", self.c2, 0.0, 10.0, "[0, 10]")?;
        positive("radius", self.radius)?;
        McmcError::check_range(
            "neighbours",
            self.neighbours as f64,
            1.0,
            1024.0,
            "1..=1024",
        )?;
        McmcError::check_range(
            "cache_size",
            self.cache_size as f64,
            1.0,
            1e7,
            "1..=10 000 000",
        )?;
        let [lo, hi] = self.preconditioner_range;
        if !(lo >= 0.0 && hi > 0.0 && lo <= hi) {
            return Err(McmcError::InvalidParameter {
                name: "preconditioner_range",
                value: lo,
                allowed: "0 <= lo <= hi, hi > 0",
            });
        }
        positive("drift_clamp", self.drift_clamp)?;
        positive("max_std", self.max_std)
    }

    /// Clamps every gradient component to `[-max_gradient, max_gradient]` in place; NaN
    /// components become 0 (section 7; the authors' code also zeroes non-finite gradients).
    pub fn truncate(&self, gradient: &mut [f64]) {
        for g in gradient {
            *g = if g.is_nan() {
                0.0
            } else {
                g.clamp(-self.max_gradient, self.max_gradient)
            };
        }
    }
}

impl Default for LangevinParams {
    /// [`LangevinParams::luan2020`].
    fn default() -> Self {
        Self::luan2020()
    }
}
