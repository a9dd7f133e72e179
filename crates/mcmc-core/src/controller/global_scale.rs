//! Global scale adaptation by the sign rule of the regional-adaptive paper (Alg. 1, eq. 4-6).

use super::Controller;
use crate::kernel::StepInfo;
use crate::tunable::ScaleTunable;
use crate::McmcError;

/// Parameters of the sign-rule scale adaptation (regional-adaptive paper, section 4.2 and
/// section 8; Andrieu & Thoms 2008, section 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleAdaptParams {
    /// Target acceptance rate `alpha*` (paper default 0.5).
    pub target_acceptance: f64,
    /// Visits between updates `L` (default 10).
    pub updates_every: u64,
    /// `gamma_max` (default 1).
    pub gamma_max: f64,
    /// `gamma_scale` (default 5).
    pub gamma_scale: f64,
    /// Initial `lambda_0 = log sigma^2` (default 1).
    pub lambda_initial: f64,
    /// Lower bound `lambda_min` (default -30).
    pub lambda_min: f64,
    /// Stop adapting after this many updates (finite adaptation); `None` keeps diminishing
    /// adaptation forever.
    pub freeze_after_updates: Option<u64>,
}

impl ScaleAdaptParams {
    /// The values of the regional-adaptive paper, section 8: `L = 10`, `gamma_max = 1`,
    /// `gamma_scale = 5`, `lambda_0 = 1`, `lambda_min = -30`, target acceptance 0.5.
    #[must_use]
    pub const fn otsu2018() -> Self {
        Self {
            target_acceptance: 0.5,
            updates_every: 10,
            gamma_max: 1.0,
            gamma_scale: 5.0,
            lambda_initial: 1.0,
            lambda_min: -30.0,
            freeze_after_updates: None,
        }
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), McmcError> {
        McmcError::check_range(
            "target_acceptance",
            self.target_acceptance,
            1e-9,
            1.0 - 1e-9,
            "(0, 1)",
        )?;
        McmcError::check_range(
            "updates_every",
            self.updates_every as f64,
            1.0,
            f64::MAX,
            ">= 1",
        )?;
        McmcError::check_range(
            "gamma_max",
            self.gamma_max,
            f64::MIN_POSITIVE,
            f64::MAX,
            "(0, inf)",
        )?;
        McmcError::check_range(
            "gamma_scale",
            self.gamma_scale,
            f64::MIN_POSITIVE,
            f64::MAX,
            "(0, inf)",
        )?;
        McmcError::check_range(
            "lambda_initial",
            self.lambda_initial,
            self.lambda_min,
            f64::MAX,
            "[lambda_min, inf)",
        )?;
        McmcError::check_range("lambda_min", self.lambda_min, f64::MIN, f64::MAX, "finite")?;
        Ok(())
    }

    /// Step size `gamma_n = min(gamma_max, gamma_scale * n^(-1/2))` (eq. 6).
    #[must_use]
    pub fn gamma(&self, n: u64) -> f64 {
        self.gamma_max
            .min(self.gamma_scale / (n.max(1) as f64).sqrt())
    }
}

impl Default for ScaleAdaptParams {
    fn default() -> Self {
        Self::otsu2018()
    }
}

/// Accumulated acceptance of one adapted scale: the state `(i, A, n)` of Alg. 1.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct AdaptState {
    /// Visits since the last update, `i`.
    pub visits: u64,
    /// Summed acceptance probability since the last update, `A`.
    pub accepted: f64,
    /// Update counter `n` (starts at 1).
    pub updates: u64,
}

impl AdaptState {
    /// A fresh state (`n = 1`).
    #[must_use]
    pub const fn new() -> Self {
        Self {
            visits: 0,
            accepted: 0.0,
            updates: 1,
        }
    }

    /// Records one proposal with acceptance probability `a`; every `L` visits returns the new
    /// `lambda`: `lambda += gamma_n sgn(A/L - alpha*)` (eq. 5), clamped to `lambda_min`.
    ///
    /// The paper's Alg. 1 tests `i_k > L`, which accumulates L+1 samples but divides by L; we
    /// update when `i_k == L` and divide by the number of visits accumulated.
    pub fn record(&mut self, a: f64, lambda: f64, p: &ScaleAdaptParams) -> Option<f64> {
        self.visits += 1;
        self.accepted += a;
        if self.visits < p.updates_every {
            return None;
        }
        Some(self.update(lambda, p))
    }

    /// The update of Alg. 1 from the visits accumulated so far (at least one): returns
    /// `max(lambda + gamma_n sgn(A/i - alpha*), lambda_min)` (eq. 5) and starts the next
    /// accumulation (`i = 0`, `A = 0`, `n += 1`).
    pub fn update(&mut self, lambda: f64, p: &ScaleAdaptParams) -> f64 {
        let rate = self.accepted / self.visits as f64;
        let sign = if rate > p.target_acceptance {
            1.0
        } else if rate < p.target_acceptance {
            -1.0
        } else {
            0.0
        };
        let new = (lambda + p.gamma(self.updates) * sign).max(p.lambda_min);
        self.visits = 0;
        self.accepted = 0.0;
        self.updates += 1;
        new
    }
}

/// Global scale adaptation (regional-adaptive paper Alg. 1 with a single region; eq. 4-6):
/// `lambda = log sigma^2`, `lambda += gamma_n sgn(acc_hat - acc*)` every `L` proposals.
///
/// Diminishing adaptation (`gamma_n -> 0`); with `freeze_after_updates` it becomes finite
/// adaptation and [`Controller::is_frozen`] turns true. The acceptance probability used is
/// that of the first stage (the proposal being tuned).
#[derive(Clone, Debug)]
pub struct GlobalScale {
    params: ScaleAdaptParams,
    state: AdaptState,
}

impl GlobalScale {
    /// A controller with validated parameters. Set the kernel's initial scale to
    /// `params.lambda_initial` yourself (or use [`GlobalScale::init`]).
    pub fn new(params: ScaleAdaptParams) -> Result<Self, McmcError> {
        params.validate()?;
        Ok(Self {
            params,
            state: AdaptState::new(),
        })
    }

    /// Sets the kernel's scale to `lambda_initial`.
    pub fn init<K: ScaleTunable + ?Sized>(&self, kernel: &mut K) {
        kernel.set_log_scale(self.params.lambda_initial);
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &ScaleAdaptParams {
        &self.params
    }

    /// Number of updates performed so far (`n - 1`).
    #[must_use]
    pub fn updates(&self) -> u64 {
        self.state.updates - 1
    }
}

impl<K: ScaleTunable + ?Sized, S> Controller<K, S> for GlobalScale {
    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        if Controller::<K, S>::is_frozen(self) {
            return;
        }
        if let Some(lambda) =
            self.state
                .record(info.accept_prob[0], kernel.log_scale(), &self.params)
        {
            kernel.set_log_scale(lambda);
        }
    }

    fn is_frozen(&self) -> bool {
        self.params
            .freeze_after_updates
            .is_some_and(|n| self.updates() >= n)
    }
}
