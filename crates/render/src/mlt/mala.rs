//! Langevin MLT (Luan et al. 2020, docs/methods/mala.md) on the
//! multiplexed path sampler: MMLT's one-strategy-per-sample targets made differentiable, the
//! kernels of `mcmc_core::langevin` moving their primary samples (`pss::langevin`), chains
//! sharing their gradient caches through the render loop.
//!
//! - **Targets.** [`DifferentiableMmlt`]: an [`MmltTarget`] whose log luminance is
//!   differentiated with respect to the coordinates the path read, by forward-mode dual
//!   numbers through the differentiable path evaluator [`crate::bdpt::diff`] (finite
//!   differences of the f32 evaluator as the fallback and as an option).
//! - **Chain kernels.** `pss`'s renderer-agnostic recipe ([`pss::mala`]): MALA on chains of
//!   MMLT depth `<= MalaConfig::max_depth`, PSSMLT's Kelemen small step beyond (the paper's
//!   section 7 rule stated by path depth: our layout reads about 4 numbers per vertex — camera
//!   stream: raster 2 + lens 2 + time 1 + 4 per bounce; light stream: 5 + 4 per bounce;
//!   connection stream: the strategy choice plus up to 3 — so the default depth 3 moves at
//!   most about 20 coordinates; docs/methods/mala.md has the measured dimensions). The path
//!   evaluator tags the numbers it consumes as discrete choices or not at all (strategy,
//!   light and lobe choices, a delta BSDF's direction numbers, a pinhole's lens, a static
//!   camera's time: `Sampler::next_1d_discrete`); MALA moves and differentiates only the
//!   others. A MALA candidate that reads a different set of coordinates than the current
//!   state (another strategy, a path that ends early) or tags others discrete is rejected
//!   ([`pss::langevin::PssCoordinates`]).
//! - **Variants** (`--integrator`, [`MalaVariant`]): `mala` (plain, eq. 7), `mala-online`
//!   (Alg. 2, diminishing adaptation), `mala-cache` (Alg. 3), `mala-hybrid` (Alg. 4); each
//!   mixed with the large step of the MCMC settings. The caches of `mala-cache` and
//!   `mala-hybrid` are shared by all chains ([`mcmc_core::langevin::CacheSharing`]),
//!   deterministically.
//! - **Delayed rejection, cheap then expensive** (DR paper section 5.2, with MALA instead of
//!   H2MC): [`cheap_then_expensive_kernel`], an isotropic Gaussian first stage and a plain MALA
//!   second stage under Green and Mira's rule.

use std::cell::RefCell;

use mcmc_core::langevin::{CacheSharing, LangevinParams};
use mcmc_core::{DifferentiableTarget, Target};
use pss::langevin::{moved_count, moved_indices};
use pss::{Pending, PssState, SmallMutation};

pub use pss::mala::{MalaChainKernel, MalaParams, MalaVariant};

use super::{MmltTarget, PathPayload, PATH_STREAMS};
use crate::autodiff::Lane;
use crate::bdpt::diff::{DiffScene, Dual, Evaluation};

/// How [`DifferentiableMmlt`] computes the gradient of the log luminance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum GradientMethod {
    /// Forward-mode dual numbers through the differentiable path evaluator
    /// ([`crate::bdpt::diff`]), falling back to finite differences where it does not apply
    /// (unsupported lights or materials, more than 32 coordinates, a decision that flips
    /// between the f32 and f64 arithmetic).
    #[default]
    Dual,
    /// As [`GradientMethod::Dual`], with the strategy's MIS weight held constant (computed
    /// from the values, not differentiated): the gradient of the log of the unweighted
    /// contribution. Cheaper; still exact, as every deterministic gradient function is.
    DualConstantMis,
    /// Central finite differences of the f32 evaluator (one-sided near a structure change).
    FiniteDifference,
}

impl GradientMethod {
    /// The methods with their `--mala-gradient` names.
    pub const ALL: [(&'static str, GradientMethod); 3] = [
        ("dual", GradientMethod::Dual),
        ("dual-constant-mis", GradientMethod::DualConstantMis),
        ("fd", GradientMethod::FiniteDifference),
    ];
}

/// Settings of Langevin MLT.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MalaConfig {
    /// The variant.
    pub variant: MalaVariant,
    /// MALA's parameters (default [`LangevinParams::luan2020`]).
    pub params: LangevinParams,
    /// Chains of MMLT depth up to this use MALA; deeper ones use the Kelemen small step
    /// (default 3, see the module docs).
    pub max_depth: u32,
    /// How gradients are computed (default [`GradientMethod::Dual`]).
    pub gradient: GradientMethod,
    /// Finite-difference step of the gradient in primary sample space (default `1e-4`; also
    /// the fallback of [`GradientMethod::Dual`]).
    pub fd_step: f64,
    /// Standard deviation of the cheap first stage of `--dr-variant cheap-then-expensive`
    /// (default 1/64, Kelemen 2002's `s2`).
    pub cheap_sigma: f64,
    /// Probability of the fallback step ([`MalaParams::fallback`]; default 0, the paper's
    /// text).
    pub fallback: f64,
    /// Mutations per chain between two poolings of the gradient caches of `mala-cache` and
    /// `mala-hybrid` (the render loop's round length; default [`CACHE_ROUND_MUTATIONS`]).
    /// Short rounds let the shared cache fill within short renders; the pooling order is
    /// fixed, so the image stays identical for any thread count.
    pub cache_round: u64,
}

/// Default [`MalaConfig::cache_round`]: 64 mutations per chain (like path-space MLT's
/// adaptation rounds; the render loop's default round is 1000, which pools a 3 s render's
/// caches about once).
pub const CACHE_ROUND_MUTATIONS: u64 = 64;

impl Default for MalaConfig {
    fn default() -> Self {
        let p = MalaParams::luan2020();
        Self {
            variant: p.variant,
            params: p.langevin,
            max_depth: p.max_depth,
            gradient: GradientMethod::Dual,
            fd_step: 1e-4,
            cheap_sigma: p.cheap_sigma,
            fallback: p.fallback,
            cache_round: CACHE_ROUND_MUTATIONS,
        }
    }
}

impl MalaConfig {
    /// The chain-kernel settings of `pss` ([`pss::mala::MalaParams`]): variant, MALA's
    /// parameters, depth rule and cheap stage.
    #[must_use]
    pub const fn mala_params(&self) -> MalaParams {
        MalaParams {
            variant: self.variant,
            langevin: self.params,
            max_depth: self.max_depth,
            cheap_sigma: self.cheap_sigma,
            fallback: self.fallback,
        }
    }
}

thread_local! {
    /// Probe state, payload and index list of the finite-difference gradient (reused: no
    /// allocation per gradient once grown).
    static PROBE: RefCell<(PssState, PathPayload, Vec<usize>)> =
        RefCell::new((PssState::new(1, 0), PathPayload::default(), Vec::new()));
}

/// The multiplexed path sampler of one depth as a differentiable target: the gradient of the
/// log luminance of the strategy's contribution with respect to the primary samples the path
/// read ([`pss::langevin::PssCoordinates`] order).
///
/// - [`GradientMethod::Dual`] (default): the f32 evaluator gives the value
///   the chain uses; the differentiable evaluator [`crate::bdpt::diff`] replays the same path
///   in forward-mode dual numbers (one lane per *continuous* coordinate read, 4, 8, 10, 12,
///   16, 24 or 32 lanes; discrete numbers are constants of the replay) and gives
///   `d ln L / du = (dL/du) / L`. The value of each dual number is `f64`, its derivative
///   lanes `f32` (half the lane arithmetic of `f64` lanes; relative rounding about `1e-7` per
///   operation in the derivatives only), replayed with `f64` lanes where an `f32` lane
///   overflows. Where the evaluator does not apply it falls back to finite differences.
/// - [`GradientMethod::FiniteDifference`]: central differences of the f32 evaluator with step
///   `h` (one-sided where one side changes the read set or carries no light; 0 where both do),
///   `2 d + 1` evaluations per gradient and accuracy about `1e-7 / h` relative.
///
/// Either way MALA stays exact: forward and reverse moves use the same deterministic gradient
/// function of the state, whatever its accuracy.
#[derive(Clone, Copy, Debug)]
pub struct DifferentiableMmlt<'s> {
    target: MmltTarget<'s>,
    h: f64,
    method: GradientMethod,
    /// The scene for the dual evaluator, if it supports it (checked once).
    diff: Option<DiffScene<'s>>,
}

impl<'s> DifferentiableMmlt<'s> {
    /// `target` differentiated by dual numbers, finite differences with step `h` (clamped to
    /// `[1e-7, 1e-2]`) as the fallback.
    #[must_use]
    pub fn new(target: MmltTarget<'s>, h: f64) -> Self {
        Self {
            target,
            h: h.clamp(1e-7, 1e-2),
            method: GradientMethod::Dual,
            diff: DiffScene::new(target.parts().0),
        }
    }

    /// The same target with gradient method `method`.
    #[must_use]
    pub fn with_method(mut self, method: GradientMethod) -> Self {
        self.method = method;
        self.diff = self
            .diff
            .map(|d| d.with_constant_mis(method == GradientMethod::DualConstantMis));
        self
    }

    /// The MMLT depth of the target.
    #[must_use]
    pub fn depth(&self) -> u32 {
        self.target.depth()
    }

    /// The dual-number gradient of `ln L` at `x` (already evaluated) into `grad`, one entry
    /// per continuous read ([`pss::langevin::PssCoordinates`] order), or false where the
    /// evaluator does not apply.
    fn dual_gradient(&self, x: &PssState, grad: &mut Vec<f64>) -> bool {
        let counts = x.read_counts();
        if x.streams() != PATH_STREAMS || counts[PATH_STREAMS..].iter().any(|&c| c != 0) {
            return false;
        }
        let continuous = continuous_counts(x);
        let n: usize = continuous.iter().sum();
        match n {
            0..=4 => self.dual_lanes::<4>(x, continuous, grad),
            5..=8 => self.dual_lanes::<8>(x, continuous, grad),
            9..=10 => self.dual_lanes::<10>(x, continuous, grad),
            11..=12 => self.dual_lanes::<12>(x, continuous, grad),
            13..=16 => self.dual_lanes::<16>(x, continuous, grad),
            17..=24 => self.dual_lanes::<24>(x, continuous, grad),
            25..=32 => self.dual_lanes::<32>(x, continuous, grad),
            _ => false,
        }
    }

    /// The gradient in `N` lanes: first with `f32` derivative lanes (half the lane
    /// arithmetic), and again with `f64` lanes where a lane of the `f32` pass is not finite
    /// (an intermediate derivative beyond `f32`'s range). Which pass answers is decided by the
    /// state alone, so the gradient stays one deterministic function of the state.
    fn dual_lanes<const N: usize>(
        &self,
        x: &PssState,
        continuous: [usize; PATH_STREAMS],
        grad: &mut Vec<f64>,
    ) -> bool {
        match self.dual_pass::<N, f32>(x, continuous, grad) {
            LanePass::Done(ok) => ok,
            LanePass::Overflow => matches!(
                self.dual_pass::<N, f64>(x, continuous, grad),
                LanePass::Done(true)
            ),
        }
    }

    /// One replay in `Dual<N, L>`: the gradient of `ln L` into `grad`.
    fn dual_pass<const N: usize, L: Lane>(
        &self,
        x: &PssState,
        continuous: [usize; PATH_STREAMS],
        grad: &mut Vec<f64>,
    ) -> LanePass {
        let Some(diff) = &self.diff else {
            return LanePass::Done(false);
        };
        let (_, params, size) = self.target.parts();
        let counts = x.read_counts();
        let mask = x.discrete_mask();
        let lanes = [0, continuous[0], continuous[0] + continuous[1]];
        let n = lanes[2] + continuous[2];
        let e = diff.evaluate_continuous::<Dual<N, L>>(
            self.target.depth(),
            size,
            params.heuristic,
            x.raw_values(),
            PATH_STREAMS,
            lanes,
            [mask[0], mask[1], mask[2]],
            Dual::variable,
        );
        let (Evaluation::Contribution { reads, .. }, Some(lum)) = (&e, e.luminance()) else {
            return LanePass::Done(false);
        };
        if reads[..] != counts[..PATH_STREAMS] || !(lum.v > 0.0 && lum.v.is_finite()) {
            return LanePass::Done(false);
        }
        if lum.d[..n].iter().any(|d| !d.to_f64().is_finite()) {
            return LanePass::Overflow;
        }
        grad.clear();
        grad.extend(lum.d[..n].iter().map(|d| {
            let g = d.to_f64() / lum.v;
            if g.is_finite() {
                g
            } else {
                0.0
            }
        }));
        LanePass::Done(true)
    }
}

/// The outcome of one dual-number pass of [`DifferentiableMmlt`].
enum LanePass {
    /// A gradient was written (`true`), or the evaluator does not apply (`false`).
    Done(bool),
    /// A derivative lane is not finite: retry with wider lanes.
    Overflow,
}

/// Per path stream, the number of continuous reads of `x`'s last evaluation (the read
/// counts less the reads tagged discrete): the dual lanes the gradient of `x` needs per
/// stream.
#[must_use]
pub fn continuous_counts(x: &PssState) -> [usize; PATH_STREAMS] {
    let counts = x.read_counts();
    let mask = x.discrete_mask();
    std::array::from_fn(|s| {
        let below = if counts[s] >= 64 {
            u64::MAX
        } else {
            (1u64 << counts[s]) - 1
        };
        counts[s] - (mask[s] & below).count_ones() as usize
    })
}

impl Target for DifferentiableMmlt<'_> {
    type State = PssState;
    type Payload = PathPayload;

    fn evaluate(&self, x: &mut PssState, payload: &mut PathPayload) -> f64 {
        self.target.evaluate(x, payload)
    }
}

impl DifferentiableTarget for DifferentiableMmlt<'_> {
    fn evaluate_with_grad(
        &self,
        x: &mut PssState,
        payload: &mut PathPayload,
        grad: &mut Vec<f64>,
    ) -> f64 {
        let value = self.target.evaluate(x, payload);
        grad.clear();
        let dual = matches!(
            self.method,
            GradientMethod::Dual | GradientMethod::DualConstantMis
        );
        if value.is_finite() && dual && self.dual_gradient(x, grad) {
            return value;
        }
        grad.clear();
        if !value.is_finite() {
            grad.resize(moved_count(x), 0.0);
            return value;
        }
        PROBE.with(|cell| {
            let (probe, probe_payload, indices) = &mut *cell.borrow_mut();
            moved_indices(x, indices);
            let (counts, mask) = (x.read_counts(), x.discrete_mask());
            let key = mcmc_core::seed::mix64(x.key() ^ 0x4644_4752_4144_2121);
            let mut side = |i: usize, v: f64| -> Option<f64> {
                probe.clone_from(x);
                probe.set_pending(Pending::None, key);
                probe.set(i, v);
                let lp = self.target.evaluate(probe, probe_payload);
                (lp.is_finite() && probe.read_counts() == counts && probe.discrete_mask() == mask)
                    .then_some(lp)
            };
            let values = x.raw_values();
            for &i in indices.iter() {
                let u = values[i];
                let plus = side(i, pss::wrap(u + self.h));
                let minus = side(i, pss::wrap(u - self.h));
                let g = match (plus, minus) {
                    (Some(p), Some(m)) => (p - m) / (2.0 * self.h),
                    (Some(p), None) => (p - value) / self.h,
                    (None, Some(m)) => (value - m) / self.h,
                    (None, None) => 0.0,
                };
                grad.push(if g.is_finite() { g } else { 0.0 });
            }
        });
        value
    }
}

/// The kernel of a chain of MMLT depth `depth`: [`pss::mala::mala_kernel`] with the settings
/// of `config` (MALA with large-step probability `p_large` if `depth <= config.max_depth`,
/// else Kelemen's small step `small`).
#[must_use]
pub fn mala_kernel(
    config: &MalaConfig,
    depth: u32,
    small: SmallMutation,
    p_large: f64,
) -> MalaChainKernel {
    pss::mala::mala_kernel(&config.mala_params(), depth, small, p_large)
}

/// The cheap-then-expensive delayed-rejection kernel of a chain of depth `depth`:
/// [`pss::mala::cheap_then_expensive_kernel`] with the settings of `config` (Kelemen's small
/// step beyond `config.max_depth`, as [`mala_kernel`]).
#[must_use]
pub fn cheap_then_expensive_kernel(
    config: &MalaConfig,
    depth: u32,
    small: SmallMutation,
    p_large: f64,
) -> MalaChainKernel {
    pss::mala::cheap_then_expensive_kernel(&config.mala_params(), depth, small, p_large)
}

/// Renders Langevin MLT over the differentiable MMLT targets of `scene` (depths
/// `0..=params.max_depth`): per chain [`mala_kernel`] (or, with `cheap_then_expensive`,
/// [`cheap_then_expensive_kernel`]) for the chain's depth, gradient caches shared through the
/// render loop's round hook ([`CacheSharing`]), so the image is identical for any thread count
/// under a mutation budget. The large-step probability is `settings.large_step`'s (fixed).
#[allow(clippy::too_many_arguments)]
pub fn render(
    scene: &crate::scene::Scene,
    params: crate::bdpt::BdptParams,
    config: &MalaConfig,
    cheap_then_expensive: bool,
    settings: &super::MltSettings,
    small: SmallMutation,
    progress: &dyn mcmc_core::Progress,
    cancel: &std::sync::atomic::AtomicBool,
) -> super::MltOutput {
    render_from_depth(
        scene,
        params,
        config,
        cheap_then_expensive,
        settings,
        small,
        0,
        progress,
        cancel,
    )
}

/// [`render`] over the depths `min_depth..=params.max_depth` only
/// ([`MmltTarget::depths_from`]; a separate direct-lighting pass renders the shallower ones,
/// as the authors' code renders paths of up to two segments by a separate pass).
#[allow(clippy::too_many_arguments)]
pub fn render_from_depth(
    scene: &crate::scene::Scene,
    params: crate::bdpt::BdptParams,
    config: &MalaConfig,
    cheap_then_expensive: bool,
    settings: &super::MltSettings,
    small: SmallMutation,
    min_depth: u32,
    progress: &dyn mcmc_core::Progress,
    cancel: &std::sync::atomic::AtomicBool,
) -> super::MltOutput {
    let (w, h) = (settings.width as u32, settings.height as u32);
    let targets: Vec<_> = MmltTarget::depths_from(scene, params, w, h, min_depth)
        .into_iter()
        .map(|t| DifferentiableMmlt::new(t, config.fd_step).with_method(config.gradient))
        .collect();
    let mut driver = super::MltDriver::new(&targets, settings).first_depth(min_depth);
    if config.variant.has_cache() && !cheap_then_expensive {
        driver = driver.round_mutations(config.cache_round);
    }
    driver.run_with_controller(
        super::PerChain(|slot: mcmc_core::render_loop::ChainSlot, p| {
            let depth = targets[slot.target].depth();
            if cheap_then_expensive {
                cheap_then_expensive_kernel(config, depth, small, p)
            } else {
                mala_kernel(config, depth, small, p)
            }
        }),
        |_| CacheSharing,
        progress,
        cancel,
    )
}
