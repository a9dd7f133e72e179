//! Langevin MLT's chain kernel on primary sample space (Luan et al. 2020,
//! docs/methods/mala.md): MALA on a differentiable PSS target up to a path depth, Kelemen's
//! small step beyond, each mixed with large steps.
//!
//! - **Which chains run MALA** (the paper's section 7 rule, "MALA only for paths shorter than
//!   8 vertices, i.e. fewer than 16 primary-sample dimensions in their parameterisation,
//!   Kelemen/Gaussian mutations beyond"): stated by *path depth*, which the renderer supplies
//!   per chain (MMLT: the depth of the chain's target; a renderer with one target passes 0).
//!   Chains of depth `<= MalaParams::max_depth` use MALA, deeper ones PSSMLT's Kelemen small
//!   step. The depth is fixed per chain, so the choice is a fixed kernel per chain and needs
//!   no state-dependent selection term.
//! - **Coordinates.** MALA moves the continuous coordinates the current state read (not the
//!   ones the target tagged discrete with [`crate::PssState::next_discrete`]), in
//!   [`PssCoordinates`] order, which is the order the target's gradient must be written in;
//!   a candidate that reads another set of coordinates or tags others discrete is rejected.
//!   Discrete coordinates move by large steps and by the optional fallback step
//!   ([`MalaParams::fallback`], every coordinate).
//! - **Variants** ([`MalaVariant`]): plain (eq. 7), online (Alg. 2, diminishing adaptation),
//!   cache-driven (Alg. 3), hybrid (Alg. 4). Adaptation is kept per dimension
//!   ([`PerDimension`]); the caches of the cache-driven and hybrid variants are shared among
//!   the chains of a render loop by [`mcmc_core::langevin::CacheSharing`] as its controller,
//!   deterministically.
//! - **Cheap then expensive** (DR paper section 5.2, with MALA instead of H2MC):
//!   [`cheap_then_expensive_kernel`], an isotropic Gaussian first stage and a plain MALA
//!   second stage under Green and Mira's rule.
//!
//! # Example
//! ```
//! use pss::mala::{mala_kernel, MalaChainKernel, MalaParams};
//! use pss::{KelemenParams, SmallMutation};
//!
//! let (params, small) = (MalaParams::luan2020(), SmallMutation::Kelemen(KelemenParams::kelemen2002()));
//! let shallow = mala_kernel(&params, 0, small, 0.3);
//! let deep = mala_kernel(&params, params.max_depth + 1, small, 0.3);
//! assert!(matches!(shallow, MalaChainKernel::Mala(_)));
//! assert!(matches!(deep, MalaChainKernel::Kelemen(_)));
//! ```

use mcmc_core::controller::LargeStepTunable;
use mcmc_core::langevin::{
    Adaptation, AnyAdaptation, CacheDriven, CacheView, CheapThenExpensive, HasGradientCache,
    Hybrid, Langevin, LangevinParams, Online, PerDimension, Plain,
};
use mcmc_core::{DifferentiableTarget, Kernel, Mh, Observer, SampleOf, StepInfo};
use rand::Rng;

use crate::langevin::PssCoordinates;
use crate::mutation::SmallMutation;
use crate::proposal::{LargeStep, PssmltProposal, SmallStep};
use crate::state::PssState;

/// The adaptation of MALA's preconditioner (Luan et al. 2020, sections 4-6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MalaVariant {
    /// Plain MALA (eq. 7): no adaptation.
    Plain,
    /// Online adaptation with diminishing adaptation (Alg. 2).
    Online,
    /// Cache-driven adaptation (Alg. 3).
    Cache,
    /// Hybrid adaptation (Alg. 4) — the paper's main algorithm.
    #[default]
    Hybrid,
}

impl MalaVariant {
    /// The variants with their short names (the chainlight CLI's `--integrator` values).
    pub const ALL: [(&'static str, MalaVariant); 4] = [
        ("mala", MalaVariant::Plain),
        ("mala-online", MalaVariant::Online),
        ("mala-cache", MalaVariant::Cache),
        ("mala-hybrid", MalaVariant::Hybrid),
    ];

    /// The short name.
    #[must_use]
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, v)| *v == self)
            .map_or("mala-hybrid", |(n, _)| n)
    }

    /// A fresh adaptation of this variant.
    #[must_use]
    pub fn adaptation(self, params: &LangevinParams) -> AnyAdaptation {
        match self {
            MalaVariant::Plain => AnyAdaptation::Plain(Plain),
            MalaVariant::Online => AnyAdaptation::Online(Online::new(true)),
            MalaVariant::Cache => AnyAdaptation::Cache(CacheDriven::new(params)),
            MalaVariant::Hybrid => AnyAdaptation::Hybrid(Hybrid::new(params)),
        }
    }

    /// True if the variant keeps a gradient cache (to share among chains with
    /// [`mcmc_core::langevin::CacheSharing`]).
    #[must_use]
    pub fn has_cache(self) -> bool {
        matches!(self, MalaVariant::Cache | MalaVariant::Hybrid)
    }
}

/// Settings of the Langevin MLT chain kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MalaParams {
    /// The adaptation (default [`MalaVariant::Hybrid`]).
    pub variant: MalaVariant,
    /// MALA's parameters (default [`LangevinParams::luan2020`]).
    pub langevin: LangevinParams,
    /// Chains of path depth up to this use MALA; deeper ones use Kelemen's small step
    /// (default 3: on render's MMLT at most about 20 moved coordinates, the paper's section 7
    /// rule stated by depth, docs/methods/mala.md).
    pub max_depth: u32,
    /// Standard deviation of the cheap first stage of [`cheap_then_expensive_kernel`]
    /// (default 1/64, Kelemen 2002's `s2`).
    pub cheap_sigma: f64,
    /// Probability of the plain fallback step in place of a MALA step: an isotropic
    /// Gaussian of standard deviation [`FALLBACK_SIGMA`] on *every* coordinate, the discrete
    /// ones included (the authors' code: `uniformmixprob` 0.1, `perturbStdDev` 0.01, to
    /// escape states where the gradient misleads). Default 0 (the paper's text has none);
    /// `p_large + fallback` is capped at 1.
    pub fallback: f64,
}

/// Standard deviation of the fallback step (the authors' code's `perturbStdDev`).
pub const FALLBACK_SIGMA: f64 = 0.01;

impl MalaParams {
    /// Luan et al. 2020: hybrid adaptation (Alg. 4) with section 7's parameters
    /// ([`LangevinParams::luan2020`]), MALA up to depth 3; the cheap stage of the DR paper's
    /// cheap-then-expensive with sigma 1/64.
    #[must_use]
    pub const fn luan2020() -> Self {
        Self {
            variant: MalaVariant::Hybrid,
            langevin: LangevinParams::luan2020(),
            max_depth: 3,
            cheap_sigma: 1.0 / 64.0,
            fallback: 0.0,
        }
    }

    /// The paper's values with the authors' code's semantics
    /// ([`LangevinParams::luan2020_values`]), hybrid adaptation, MALA up to depth 3, the
    /// code's fallback step (probability 0.1).
    #[must_use]
    pub const fn luan2020_values() -> Self {
        Self {
            langevin: LangevinParams::luan2020_values(),
            fallback: 0.1,
            ..Self::luan2020()
        }
    }

    /// The authors' code ([`LangevinParams::luan2020_code`]), hybrid adaptation, MALA up to
    /// depth 3, the code's fallback step (probability 0.1).
    #[must_use]
    pub const fn luan2020_code() -> Self {
        Self {
            langevin: LangevinParams::luan2020_code(),
            fallback: 0.1,
            ..Self::luan2020()
        }
    }
}

impl Default for MalaParams {
    /// [`MalaParams::luan2020`].
    fn default() -> Self {
        Self::luan2020()
    }
}

/// The kernel of one chain of Langevin MLT: MALA with large steps for shallow depths, the
/// PSSMLT Kelemen mixture for deep ones, or the cheap-then-expensive delayed rejection. A
/// [`Kernel`] of every [`DifferentiableTarget`] over [`PssState`]; its large-step probability
/// is tunable and its gradient caches can be shared ([`HasGradientCache`]).
#[derive(Clone, Debug)]
pub enum MalaChainKernel {
    /// MALA with adaptation, mixed with large steps and the fallback step.
    Mala(Langevin<PerDimension<AnyAdaptation>, PssCoordinates, LargeStep, SmallStep>),
    /// Delayed rejection: isotropic Gaussian, then MALA (Green-Mira).
    CheapThenExpensive(CheapThenExpensive<PerDimension<AnyAdaptation>, PssCoordinates, LargeStep>),
    /// PSSMLT's Kelemen small step with large steps (deep chains).
    Kelemen(Mh<PssmltProposal>),
}

/// The kernel of a chain of path depth `depth`: MALA of `params` with large-step probability
/// `p_large` (clamped to `[0, 1]`) and the fallback step of probability `params.fallback`
/// (capped at `1 - p_large`) if `depth <= params.max_depth`, else Kelemen's small step
/// `small` (also where `params.langevin` is out of range).
#[must_use]
pub fn mala_kernel(
    params: &MalaParams,
    depth: u32,
    small: SmallMutation,
    p_large: f64,
) -> MalaChainKernel {
    let p = p_large.clamp(0.0, 1.0);
    if depth > params.max_depth {
        return kelemen(small, p);
    }
    let adaptation = PerDimension::new(params.variant.adaptation(&params.langevin));
    let fallback = SmallStep::new(SmallMutation::Gaussian {
        sigma: FALLBACK_SIGMA,
    });
    let p_fallback = if params.fallback.is_finite() {
        params.fallback.clamp(0.0, 1.0 - p)
    } else {
        0.0
    };
    match Langevin::new(params.langevin, adaptation, PssCoordinates)
        .and_then(|k| k.with_large_step(LargeStep, p))
        .and_then(|k| k.with_fallback(fallback, p_fallback))
    {
        Ok(k) => MalaChainKernel::Mala(k),
        Err(_) => kelemen(small, p),
    }
}

/// The cheap-then-expensive delayed-rejection kernel (DR paper section 5.2) of a chain of
/// depth `depth`: an isotropic Gaussian of `params.cheap_sigma`, then plain MALA, under Green
/// and Mira's rule (Kelemen's small step beyond `params.max_depth`, as [`mala_kernel`]).
#[must_use]
pub fn cheap_then_expensive_kernel(
    params: &MalaParams,
    depth: u32,
    small: SmallMutation,
    p_large: f64,
) -> MalaChainKernel {
    let p = p_large.clamp(0.0, 1.0);
    if depth > params.max_depth {
        return kelemen(small, p);
    }
    let adaptation = PerDimension::new(AnyAdaptation::Plain(Plain));
    match CheapThenExpensive::new(
        params.langevin,
        params.cheap_sigma,
        adaptation,
        PssCoordinates,
    )
    .and_then(|k| k.with_large_step(LargeStep, p))
    {
        Ok(k) => MalaChainKernel::CheapThenExpensive(k),
        Err(_) => kelemen(small, p),
    }
}

fn kelemen(small: SmallMutation, p: f64) -> MalaChainKernel {
    MalaChainKernel::Kelemen(Mh::new(
        PssmltProposal::new(SmallStep::new(small), p).unwrap_or_else(|_| unreachable!("clamped")),
    ))
}

impl<T: DifferentiableTarget<State = PssState>> Kernel<T> for MalaChainKernel {
    fn stages(&self) -> usize {
        match self {
            MalaChainKernel::Mala(k) => Kernel::<T>::stages(k),
            MalaChainKernel::CheapThenExpensive(k) => Kernel::<T>::stages(k),
            MalaChainKernel::Kelemen(k) => Kernel::<T>::stages(k),
        }
    }

    fn step<R, O>(
        &mut self,
        target: &T,
        current: &mut SampleOf<T>,
        scratch: &mut [SampleOf<T>],
        rng: &mut R,
        observer: &mut O,
    ) -> StepInfo
    where
        R: Rng + ?Sized,
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        match self {
            MalaChainKernel::Mala(k) => k.step(target, current, scratch, rng, observer),
            MalaChainKernel::CheapThenExpensive(k) => {
                k.step(target, current, scratch, rng, observer)
            }
            MalaChainKernel::Kelemen(k) => k.step(target, current, scratch, rng, observer),
        }
    }

    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        match self {
            MalaChainKernel::Mala(k) => k.log_flow(target, path),
            MalaChainKernel::CheapThenExpensive(k) => k.log_flow(target, path),
            MalaChainKernel::Kelemen(k) => k.log_flow(target, path),
        }
    }

    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        match self {
            MalaChainKernel::Mala(k) => k.reverse_path(target, path),
            MalaChainKernel::CheapThenExpensive(k) => k.reverse_path(target, path),
            MalaChainKernel::Kelemen(k) => k.reverse_path(target, path),
        }
    }
}

impl LargeStepTunable for MalaChainKernel {
    fn large_step_probability(&self) -> f64 {
        match self {
            MalaChainKernel::Mala(k) => k.large_step_probability(),
            MalaChainKernel::CheapThenExpensive(k) => k.large_step_probability(),
            MalaChainKernel::Kelemen(k) => k.large_step_probability(),
        }
    }
    fn set_large_step_probability(&mut self, p: f64) {
        match self {
            MalaChainKernel::Mala(k) => k.set_large_step_probability(p),
            MalaChainKernel::CheapThenExpensive(k) => k.set_large_step_probability(p),
            MalaChainKernel::Kelemen(k) => k.set_large_step_probability(p),
        }
    }
    fn is_large_step(&self, component: usize) -> bool {
        match self {
            MalaChainKernel::Mala(k) => k.is_large_step(component),
            MalaChainKernel::CheapThenExpensive(k) => k.is_large_step(component),
            MalaChainKernel::Kelemen(k) => k.is_large_step(component),
        }
    }
}

impl HasGradientCache for MalaChainKernel {
    fn for_each_gradient_cache(&mut self, f: &mut dyn FnMut(&mut CacheView)) {
        match self {
            MalaChainKernel::Mala(k) => k.adaptation.for_each_cache(f),
            MalaChainKernel::CheapThenExpensive(k) => k.adaptation.for_each_cache(f),
            MalaChainKernel::Kelemen(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_depth_rule_and_the_variants_pick_the_kernel() {
        let params = MalaParams::default();
        let small = SmallMutation::Kelemen(crate::KelemenParams::kelemen2002());
        for depth in 0..=params.max_depth {
            assert!(matches!(
                mala_kernel(&params, depth, small, 0.3),
                MalaChainKernel::Mala(_)
            ));
            assert!(matches!(
                cheap_then_expensive_kernel(&params, depth, small, 0.3),
                MalaChainKernel::CheapThenExpensive(_)
            ));
        }
        let deep = mala_kernel(&params, params.max_depth + 1, small, 2.0);
        assert!(matches!(deep, MalaChainKernel::Kelemen(_)));
        assert_eq!(deep.large_step_probability(), 1.0);
        // Parameters out of range fall back to Kelemen's step.
        let mut bad = params;
        bad.cheap_sigma = -1.0;
        assert!(matches!(
            cheap_then_expensive_kernel(&bad, 0, small, 0.3),
            MalaChainKernel::Kelemen(_)
        ));
        for (name, v) in MalaVariant::ALL {
            assert_eq!(v.name(), name);
            assert_eq!(
                v.has_cache(),
                matches!(v, MalaVariant::Cache | MalaVariant::Hybrid)
            );
        }
    }
}
