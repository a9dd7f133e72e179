//! What every render needs besides the scene: the common settings (size, budget, threads,
//! seed, depth) and the chosen method's own settings.

use std::time::Duration;

use mcmc_core::render_loop::NormalizationMode;
use pss::{KelemenParams, SmallMutation};

use super::{
    BdptSettings, DrmltSettings, IntegratorKind, LqmcSettings, MalaSettings, Method, MmltSettings,
    PathMltSettings, PssmltSettings, PtSettings, QmcSettings,
};
use crate::budget::Budget;
use crate::error::RenderError;
use crate::mlt::{LargeStepMode, MltBudget, MltSettings};

/// The settings of one method: which integrator renders, with its own options. Each variant's
/// settings live in the method's module ([`super::pssmlt`], [`super::drmlt`], ...), with the
/// presets of the papers it implements.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum MethodSettings {
    /// `pt`: unidirectional path tracing.
    Pt(PtSettings),
    /// `qmc`, `qmc-faure`: path tracing over per-pixel Halton points.
    Qmc(QmcSettings),
    /// `bdpt`: bidirectional path tracing.
    Bdpt(BdptSettings),
    /// `pssmlt`: primary-sample-space MLT over BDPT.
    Pssmlt(PssmltSettings),
    /// `mmlt`: multiplexed MLT.
    Mmlt(MmltSettings),
    /// `drmlt`: delayed-rejection MLT.
    Drmlt(DrmltSettings),
    /// `mala`, `mala-online`, `mala-cache`, `mala-hybrid`: Langevin MLT.
    Mala(MalaSettings),
    /// `pathmlt`: path-space MLT.
    PathMlt(PathMltSettings),
    /// `lqmc`: local quasi-Monte Carlo exploration.
    Lqmc(LqmcSettings),
}

impl MethodSettings {
    /// The method as a trait object: its row, validation and render function.
    #[must_use]
    pub fn method(&self) -> &dyn Method {
        match self {
            Self::Pt(s) => s,
            Self::Qmc(s) => s,
            Self::Bdpt(s) => s,
            Self::Pssmlt(s) => s,
            Self::Mmlt(s) => s,
            Self::Drmlt(s) => s,
            Self::Mala(s) => s,
            Self::PathMlt(s) => s,
            Self::Lqmc(s) => s,
        }
    }

    /// The integrator these settings run (its row of [`super::INTEGRATORS`]).
    #[must_use]
    pub fn kind(&self) -> IntegratorKind {
        self.method().kind()
    }

    /// The Markov chain settings of PSSMLT, MMLT, DRMLT and Langevin MLT (`None` for the
    /// others).
    pub fn chain_mut(&mut self) -> Option<&mut ChainSettings> {
        match self {
            Self::Pssmlt(s) => Some(&mut s.chain),
            Self::Mmlt(s) => Some(&mut s.chain),
            Self::Drmlt(s) => Some(&mut s.chain),
            Self::Mala(s) => Some(&mut s.chain),
            _ => None,
        }
    }

    /// Sets the chain count and the bootstrap size of any Markov chain method, path-space MLT
    /// included (nothing for the others): what a sweep over methods varies together.
    pub fn set_chains(&mut self, chains: usize, bootstrap_samples: usize) {
        if let Self::PathMlt(s) = self {
            (s.chains, s.bootstrap_samples) = (chains, bootstrap_samples);
        } else if let Some(c) = self.chain_mut() {
            (c.chains, c.bootstrap_samples) = (chains, bootstrap_samples);
        }
    }

    /// These settings with [`MethodSettings::set_chains`] applied.
    #[must_use]
    pub fn with_chains(mut self, chains: usize, bootstrap_samples: usize) -> Self {
        self.set_chains(chains, bootstrap_samples);
        self
    }
}

impl Default for MethodSettings {
    /// PT with its defaults (the first row of the table).
    fn default() -> Self {
        Self::Pt(PtSettings::default())
    }
}

macro_rules! into_method {
    ($($ty:ident => $variant:ident),* $(,)?) => {$(
        impl From<$ty> for MethodSettings {
            fn from(settings: $ty) -> Self {
                Self::$variant(settings)
            }
        }
    )*};
}
into_method!(
    PtSettings => Pt, QmcSettings => Qmc, BdptSettings => Bdpt, PssmltSettings => Pssmlt,
    MmltSettings => Mmlt, DrmltSettings => Drmlt, MalaSettings => Mala,
    PathMltSettings => PathMlt, LqmcSettings => Lqmc,
);

/// Everything a render needs besides the scene: the settings every method shares, and the
/// method's own ([`RenderSettings::method`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels (>= 1).
    pub width: u32,
    /// Image height in pixels (>= 1).
    pub height: u32,
    /// Sample or time budget (Markov chain methods: mutations per pixel).
    pub budget: Budget,
    /// Worker threads (>= 1). The image does not depend on it.
    pub threads: usize,
    /// Master seed; the same seed gives a bit-identical image under a sample budget.
    pub seed: u64,
    /// Maximum path depth (number of bounces).
    pub max_depth: u32,
    /// The integrator and its own settings.
    pub method: MethodSettings,
}

impl Default for RenderSettings {
    /// 256 x 256, PT, 16 samples per pixel, 1 thread, seed 0, max depth 5.
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            budget: Budget::SamplesPerPixel(16),
            threads: 1,
            seed: 0,
            max_depth: 5,
            method: MethodSettings::default(),
        }
    }
}

impl RenderSettings {
    /// The integrator of [`RenderSettings::method`].
    #[must_use]
    pub fn integrator(&self) -> IntegratorKind {
        self.method.kind()
    }
}

/// Settings every primary-sample-space Markov chain method shares (PSSMLT, MMLT, DRMLT,
/// Langevin MLT).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainSettings {
    /// Number of Markov chains (default 256; 1..=1 000 000).
    pub chains: usize,
    /// Independent samples in the bootstrap that estimates `b` and seeds the chains
    /// (default 100 000, pbrt's value; 1..=100 000 000).
    pub bootstrap_samples: usize,
    /// Large-step probability: fixed, or automatic (Zsolnai & Szirmay-Kalos 2013). Default
    /// fixed 0.3 (pbrt-v3's and DRMLT's value).
    pub large_step: LargeStepMode,
    /// The small-step kernel (default Kelemen with s1 = 1/1024, s2 = 1/64).
    pub small_step: SmallMutation,
    /// How the image's normalisation `b` is estimated: the bootstrap pooled with every
    /// large-step candidate (the default), the bootstrap alone, or a given `b` (the mean
    /// luminance the chains' image should have: comparisons on one footing). See
    /// `mcmc_core::render_loop::Normalization`.
    pub normalization: NormalizationMode,
}

impl Default for ChainSettings {
    fn default() -> Self {
        Self::kelemen2002()
    }
}

/// Mutations per chain in the estimation phase of automatic large-step control.
pub const AUTO_LARGE_STEP_ESTIMATION: u64 = 1_000;

/// Largest accepted chain count.
pub const MAX_CHAINS: usize = 1_000_000;

/// Largest accepted bootstrap sample count.
pub const MAX_BOOTSTRAP_SAMPLES: usize = 100_000_000;

impl ChainSettings {
    /// Kelemen et al. 2002's mutations (section 3: small steps with s1 = 1/1024, s2 = 1/64;
    /// large steps with probability 0.3, pbrt-v3's value) with 256 chains and a bootstrap of
    /// 100 000 samples (pbrt-v3).
    #[must_use]
    pub const fn kelemen2002() -> Self {
        Self {
            chains: 256,
            bootstrap_samples: 100_000,
            large_step: LargeStepMode::Fixed(0.3),
            small_step: SmallMutation::Kelemen(KelemenParams::kelemen2002()),
            normalization: NormalizationMode::Pooled,
        }
    }

    /// These settings with automatic large-step control (Zsolnai & Szirmay-Kalos 2013,
    /// section 2): [`AUTO_LARGE_STEP_ESTIMATION`] mutations per chain at probability
    /// `initial`, then the estimated probability.
    #[must_use]
    pub const fn with_auto_large_step(self, initial: f64) -> Self {
        Self {
            large_step: LargeStepMode::Auto {
                initial,
                estimation_steps: AUTO_LARGE_STEP_ESTIMATION,
            },
            ..self
        }
    }

    /// Checks the ranges.
    ///
    /// # Errors
    /// [`RenderError::InvalidSetting`] naming the flag (`chains`, `bootstrap-samples`,
    /// `large-step`) and the allowed range.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(1..=MAX_CHAINS).contains(&self.chains) {
            return Err(RenderError::setting("chains", self.chains, "1..=1000000"));
        }
        if !(1..=MAX_BOOTSTRAP_SAMPLES).contains(&self.bootstrap_samples) {
            return Err(RenderError::setting(
                "bootstrap-samples",
                self.bootstrap_samples,
                "1..=100000000",
            ));
        }
        let (p, then) = match self.large_step {
            LargeStepMode::Fixed(p) | LargeStepMode::Auto { initial: p, .. } => (p, p),
            LargeStepMode::Schedule { initial, then } => (initial, then),
        };
        for p in [p, then] {
            if !(0.0..=1.0).contains(&p) {
                return Err(RenderError::setting(
                    "large-step",
                    p,
                    "auto, 0..=1, or P1,P2 both in 0..=1",
                ));
            }
        }
        validate_normalization(self.normalization)
    }

    /// The MCMC driver's settings for shard `shard` of a render of `common`'s size, budget
    /// and seed.
    #[must_use]
    pub fn mlt_settings(
        &self,
        common: &RenderSettings,
        streams: usize,
        stage_map: bool,
        shard: crate::shard::Shard,
    ) -> MltSettings {
        MltSettings {
            width: common.width as usize,
            height: common.height as usize,
            chains: self.chains,
            bootstrap_samples: self.bootstrap_samples,
            budget: mlt_budget(common.budget),
            large_step: self.large_step,
            seed: common.seed,
            streams,
            normalization: self.normalization,
            stage_map,
            shard,
        }
    }
}

/// Checks a given normalisation.
///
/// # Errors
/// [`RenderError::InvalidSetting`] naming `normalization` for a given `b` that is not finite
/// and positive.
pub fn validate_normalization(mode: NormalizationMode) -> Result<(), RenderError> {
    match mode {
        NormalizationMode::Given(b) if !(b.is_finite() && b > 0.0) => Err(RenderError::setting(
            "normalization",
            b,
            "pooled, bootstrap, a number > 0 or an image with a positive mean",
        )),
        _ => Ok(()),
    }
}

/// A render budget as the MCMC driver's: samples per pixel become mutations per pixel.
#[must_use]
pub fn mlt_budget(budget: Budget) -> MltBudget {
    match budget {
        Budget::SamplesPerPixel(n) => MltBudget::MutationsPerPixel(f64::from(n)),
        Budget::Time(t) => MltBudget::Time(t),
    }
}

/// What is left of a time budget after `spent` (at least a millisecond); sample budgets are
/// unchanged.
#[must_use]
pub fn remaining(budget: MltBudget, spent: Duration) -> MltBudget {
    match budget {
        MltBudget::Time(t) => {
            MltBudget::Time(t.saturating_sub(spent).max(Duration::from_millis(1)))
        }
        other => other,
    }
}
