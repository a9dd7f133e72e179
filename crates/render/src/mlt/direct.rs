//! A separate direct-lighting pass for the MCMC integrators (Mitsuba 0.6's
//! PSSMLT/MLT `directSamples`, and the DRMLT reference implementation, which builds on it).
//!
//! The image splits exactly by path depth: `I = I_{depth <= K} + I_{depth > K}`. Direct
//! lighting (depth 0, emitters seen directly, and depth 1) and, in most scenes, the
//! one-bounce paths are smooth and cheap, and a per-pixel estimator renders them with far less
//! noise per unit of time than a Markov chain, which spends its mutations in proportion to
//! brightness and so mostly on exactly these paths. With the pass on, the chains sample only
//! depths > K ([`super::PssmltTarget::with_min_depth`]) and the pass adds a BDPT render of
//! depths 0..=K whose budget follows [`DirectPass`]: by default [`DirectPass::Balanced`], a
//! share of the budget picked per scene from a pilot's estimate of how much of the light the
//! pass's depths carry ([`balanced_share`], a Neyman allocation between the two estimators).
//! `K` is the pass's depth, [`DIRECT_DEPTH_DEFAULT`] = 2 unless set (`--direct-depth`).
//!
//! Unbiasedness: BDPT's MIS weights of a path are computed over the strategies of that path's
//! own depth (`s + t = depth + 2`), never over other depths, so BDPT at maximum depth K
//! estimates exactly `I_{depth <= K}`, and the restricted chains estimate exactly
//! `I_{depth > K}` (their target, bootstrap and splats all drop the same strategies). The
//! two estimators are independent (different random numbers), and the sum is unbiased; a
//! budget split chosen from a pilot with numbers of its own ([`pilot_light_share`]) keeps
//! both unbiased, since neither estimator's numbers decide its own length;
//! `crates/render/tests/direct_pass.rs` checks it against BDPT, with negative controls (the
//! pass alone, and the pass added to unrestricted chains, which counts direct light twice).
//!
//! Reading chosen: Mitsuba 0.6 renders the direct pass with its own direct-illumination
//! integrator (depth 1 only); here it is the renderer's BDPT restricted to depth K, the same
//! estimator family the chains use (every strategy of depths 0..=K with MIS, light tracing
//! included), so the split needs no second light-transport code path. The default K = 2 (one
//! bounce of indirect light in the pass too) and its measurement against K = 1 and K = 3 are
//! on docs/methods/pssmlt-mmlt.md and docs/performance.md.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::bdpt::{render_bdpt_shard, BdptOutput, BdptParams};
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use mcmc_core::render_loop::Shard;
use mcmc_core::Progress;

/// The pass's default depth K (`--direct-depth`): paths up to K bounces are the pass's, the
/// chains take the deeper ones. 2: direct light and one bounce of indirect light (module
/// comment).
pub const DIRECT_DEPTH_DEFAULT: u32 = 2;

/// Under a time budget `T`, a [`DirectPass::Fixed`] pass stops after this share of `T` even if
/// it has not reached its samples per pixel (it always completes one pass), so a large count
/// cannot starve the chains.
pub const DIRECT_TIME_SHARE: f64 = 0.25;

/// A [`DirectPass::Proportional`] pass never takes more than this many samples per pixel
/// under a mutation budget: the pass runs before the chains, so a huge budget must not keep
/// them from starting for long (1024 samples per pixel of depths 0-1 leave a relMSE of about
/// 1e-5 on the bundled Cornell scenes, far below any chain's).
pub const DIRECT_MAX_SPP: u32 = 1024;

/// The direct-lighting pass's settings.
///
/// ```
/// use render::mlt::direct::DirectPass;
/// use std::time::Duration;
/// // PSSMLT's default picks its share per scene; resolved for a scene whose depths 0-2 carry
/// // 60 % of the light it is about 15 % of the time, half a sample per mutation.
/// let pass = DirectPass::PSSMLT_DEFAULT.resolve(0.6);
/// assert!(pass.applies_to(5, 2));
/// assert_eq!(pass.chain_min_depth(5, 2), 3);
/// assert!(!pass.applies_to(2, 2)); // nothing deeper than depth 2 is left for the chains
/// // 64 mutations per pixel: 32 direct samples per pixel; 10 s: about 1.5 s of direct pass.
/// assert_eq!(pass.budget(Some(64.0), None), (Some(32), None));
/// let (_, t) = pass.budget(None, Some(Duration::from_secs(10)));
/// assert!((t.unwrap().as_secs_f64() - 1.5).abs() < 0.05);
/// assert!(!DirectPass::Off.applies_to(5, 2));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DirectPass {
    /// No separate pass: the chains sample every depth.
    Off,
    /// A fixed number of BDPT samples per pixel (`--direct-samples N`; Mitsuba 0.6's
    /// `directSamples`, whose default is 16); under a time budget at most
    /// [`DIRECT_TIME_SHARE`] of it.
    Fixed(u32),
    /// In proportion to the render's budget, so the pass's error shrinks with the chains':
    /// `ceil(per_mutation * M)` samples per pixel (at most [`DIRECT_MAX_SPP`]) under a budget
    /// of `M` mutations per pixel, `time_share` of the time under a time budget (at least one
    /// pass either way).
    Proportional {
        /// Direct samples per pixel per chain mutation per pixel.
        per_mutation: f64,
        /// Share of a time budget.
        time_share: f64,
    },
    /// The share chosen per scene from how the light divides between the pass's depths and
    /// the chains' ([`DirectPass::resolve`]; PSSMLT's default): before the pass, a pilot of
    /// [`BALANCE_SAMPLES`] all-strategy BDPT samples estimates the share `phi` of the image's
    /// luminance at depths `0..=K`, and the pass gets the [`balanced_share`] of the budget.
    /// `kappa` is the pass's error per unit of light and time relative to the chains'
    /// ([`BALANCE_KAPPA`] by default).
    Balanced {
        /// Relative error constant of the pass (`kappa` of [`balanced_share`]).
        kappa: f64,
    },
}

/// [`DirectPass::Balanced`]'s default `kappa` (module comment of [`balanced_share`]), fitted
/// at equal time on two bundled scenes (docs/performance.md, "The current defaults and why").
pub const BALANCE_KAPPA: f64 = 0.02;

/// All-strategy BDPT samples of [`DirectPass::Balanced`]'s pilot (resolution-independent:
/// about 0.15 s on two cores for the bundled scenes at depth 10).
pub const BALANCE_SAMPLES: u64 = 16_384;

/// The range [`balanced_share`] keeps a time share in: the pass never gets less than 2 % nor
/// more than 75 % of the budget, whatever the pilot says (a pilot that found no light in one
/// of the two parts must not starve the other).
pub const BALANCE_SHARE_RANGE: (f64, f64) = (0.02, 0.75);

/// Direct samples per pixel per mutation per pixel that correspond to time odds of 1 (pass
/// time = chain time) under a mutation budget, from the measured cost of a depth-2 pass
/// sample relative to a PSSMLT mutation at depth 10 on the bundled scenes
/// (docs/performance.md), so `per_mutation = PER_MUTATION_PER_ODDS * s / (1 - s)` for a time
/// share `s`; 15 % gives half a sample per mutation.
pub const PER_MUTATION_PER_ODDS: f64 = 0.5 * 0.85 / 0.15;

/// The time share of a direct pass that minimises the relMSE of pass plus chains, when the
/// pass's depths carry the share `phi` of the image's light (`0..=1`) and the pass's error
/// per unit of light and time is `kappa` times the chains'.
///
/// Model (Neyman allocation between two independent estimators): over a budget `T` split
/// `sT` / `(1 - s)T`, `E = A_d / (sT) + A_c / ((1 - s)T)`, minimised at
/// `s / (1 - s) = sqrt(A_d / A_c)`. With each part's error constant in proportion to its
/// light, `A_d / A_c = kappa phi / (1 - phi)`, so `s = q / (1 + q)` with
/// `q = sqrt(kappa phi / (1 - phi))`, kept in [`BALANCE_SHARE_RANGE`]. The proportionality is
/// the reading chosen here, not a law: measured (two seeds per scene, 128 x 128, 10 s) it gave
/// `kappa` 0.022 on cornell-glass and 0.017 on ajar-door, and the measured best shares (25 %
/// and 10 %) are the model's; where the pass's depths hold caustics (caustic-pool) the pass's
/// error per unit of light is larger and the share from this `kappa` (about 15 %) is level
/// with the others measured there.
///
/// ```
/// use render::mlt::direct::{balanced_share, BALANCE_KAPPA};
/// let cornell = balanced_share(BALANCE_KAPPA, 0.85);
/// assert!((cornell - 0.25).abs() < 0.01, "{cornell}");
/// let ajar = balanced_share(BALANCE_KAPPA, 0.36);
/// assert!((ajar - 0.10).abs() < 0.01, "{ajar}");
/// assert_eq!(balanced_share(BALANCE_KAPPA, 1.0), 0.75);
/// ```
#[must_use]
pub fn balanced_share(kappa: f64, phi: f64) -> f64 {
    let (lo, hi) = BALANCE_SHARE_RANGE;
    let phi = if phi.is_nan() {
        0.5
    } else {
        phi.clamp(0.0, 1.0)
    };
    if phi >= 1.0 {
        return hi;
    }
    let q = (kappa.max(0.0) * phi / (1.0 - phi)).sqrt();
    (q / (1.0 + q)).clamp(lo, hi)
}

/// The share of the light at depths `0..=depth` from per-depth luminance estimates
/// (`per_depth[d]`, e.g. [`super::mmlt_depth_normalization`]); `None` if they hold no light.
#[must_use]
pub fn pass_light_share(per_depth: &[f64], depth: u32) -> Option<f64> {
    let k = (depth as usize + 1).min(per_depth.len());
    let finite = |v: &&f64| v.is_finite() && **v > 0.0;
    let pass: f64 = per_depth[..k].iter().filter(finite).sum();
    let total: f64 = pass + per_depth[k..].iter().filter(finite).sum::<f64>();
    (total > 0.0).then(|| pass / total)
}

impl DirectPass {
    /// PSSMLT's default (`render::methods::PssmltSettings::default`): [`DirectPass::Balanced`]
    /// with [`BALANCE_KAPPA`], so the pass's share follows the scene's light. A fixed 15 % is
    /// `DirectPass::with_time_share(0.15)` (`--direct-share 0.15`); the measurement is on
    /// docs/methods/pssmlt-mmlt.md.
    pub const PSSMLT_DEFAULT: Self = Self::Balanced {
        kappa: BALANCE_KAPPA,
    };

    /// A [`DirectPass::Proportional`] pass with the time share `share` (clamped to `0..=1`)
    /// and the samples per mutation that cost the same share of a mutation budget
    /// ([`PER_MUTATION_PER_ODDS`]).
    ///
    /// ```
    /// use render::mlt::direct::DirectPass;
    /// let p = DirectPass::with_time_share(0.15);
    /// let DirectPass::Proportional { per_mutation, time_share } = p else { unreachable!() };
    /// assert!((per_mutation - 0.5).abs() < 1e-12 && time_share == 0.15);
    /// ```
    #[must_use]
    pub fn with_time_share(share: f64) -> Self {
        let share = if share.is_nan() {
            0.0
        } else {
            share.clamp(0.0, 1.0)
        };
        let per_mutation = if share >= 1.0 {
            f64::from(DIRECT_MAX_SPP)
        } else {
            PER_MUTATION_PER_ODDS * share / (1.0 - share)
        };
        Self::Proportional {
            per_mutation,
            time_share: share,
        }
    }

    /// The pass for a scene whose pass depths carry the share `phi` of the light: a
    /// [`DirectPass::Balanced`] pass becomes the [`DirectPass::Proportional`] pass of its
    /// [`balanced_share`]; the others are returned unchanged.
    #[must_use]
    pub fn resolve(&self, phi: f64) -> Self {
        match *self {
            DirectPass::Balanced { kappa } => Self::with_time_share(balanced_share(kappa, phi)),
            other => other,
        }
    }

    /// Whether there is a pass at all.
    #[must_use]
    pub fn is_on(&self) -> bool {
        match *self {
            DirectPass::Off | DirectPass::Fixed(0) => false,
            DirectPass::Fixed(_) => true,
            DirectPass::Proportional {
                per_mutation,
                time_share,
            } => per_mutation > 0.0 && time_share > 0.0,
            DirectPass::Balanced { kappa } => kappa > 0.0 && kappa.is_finite(),
        }
    }

    /// Whether a pass of depth `depth` is used at maximum path depth `max_depth`: on, and the
    /// chains have depths beyond `depth` left to sample.
    #[must_use]
    pub fn applies_to(&self, max_depth: u32, depth: u32) -> bool {
        self.is_on() && max_depth > depth
    }

    /// The smallest depth the chains sample: `depth + 1` when a pass of depth `depth`
    /// applies at `max_depth`, else 0 (every depth).
    #[must_use]
    pub fn chain_min_depth(&self, max_depth: u32, depth: u32) -> u32 {
        if self.applies_to(max_depth, depth) {
            depth + 1
        } else {
            0
        }
    }

    /// The pass's own budget `(samples per pixel, time)` for a render of
    /// `mutations_per_pixel` chain mutations per pixel or of `time` (one of the two). A
    /// [`DirectPass::Balanced`] pass should be [resolved](DirectPass::resolve) first;
    /// unresolved it is budgeted as if half the light were the pass's.
    #[must_use]
    pub fn budget(
        &self,
        mutations_per_pixel: Option<f64>,
        time: Option<Duration>,
    ) -> (Option<u32>, Option<Duration>) {
        match *self {
            DirectPass::Off => (Some(0), None),
            DirectPass::Fixed(n) => (Some(n), time.map(|t| t.mul_f64(DIRECT_TIME_SHARE))),
            DirectPass::Balanced { .. } => self.resolve(0.5).budget(mutations_per_pixel, time),
            DirectPass::Proportional {
                per_mutation,
                time_share,
            } => match (mutations_per_pixel, time) {
                (Some(m), _) => {
                    let n = (per_mutation * m)
                        .ceil()
                        .clamp(1.0, f64::from(DIRECT_MAX_SPP));
                    (Some(n as u32), None)
                }
                (None, Some(t)) => (None, Some(t.mul_f64(time_share.clamp(0.0, 1.0)))),
                (None, None) => (Some(1), None),
            },
        }
    }
}

impl Default for DirectPass {
    /// Off.
    fn default() -> Self {
        Self::Off
    }
}

/// Renders the direct pass: BDPT at maximum depth `depth` (at most `params.max_depth`; the
/// other parameters, roulette included, from `params`) drawing from the per-pixel `sampler`
/// (stratified Sobol points suit smooth direct light; PSSMLT's default), on the camera's
/// image size, `spp` samples per pixel or until `time` has passed (at least one pass; every
/// pixel is the mean of its own samples, so a pass stopped by time stays unbiased) —
/// [`DirectPass::budget`] gives both. The seed is mixed so the pass draws other numbers than
/// a BDPT render of the same seed (not needed for unbiasedness, only for independence from
/// anything else the caller renders with `seed`).
#[allow(clippy::too_many_arguments)]
pub fn render_direct(
    scene: &Scene,
    params: &BdptParams,
    depth: u32,
    sampler: SamplerKind,
    (spp, time): (Option<u32>, Option<Duration>),
    seed: u64,
    shard: Shard,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> BdptOutput {
    let direct = BdptParams {
        max_depth: params.max_depth.min(depth),
        ..*params
    };
    render_bdpt_shard(
        scene,
        &direct,
        sampler,
        (spp.map(|n| n.max(1)), time),
        seed ^ 0xD1EC_7000_0000_0001,
        false,
        shard,
        progress,
        cancel,
    )
}

/// [`DirectPass::Balanced`]'s pilot: the share of the image's light at depths `0..=depth`,
/// from `samples` all-strategy BDPT samples at `params.max_depth`
/// ([`super::mmlt_depth_normalization`], with keys of its own: the pass and the chains never
/// see these numbers, so their estimates stay independent of the share they were given).
/// `None` if cancelled or if the samples found no light. Bit-identical for any thread count.
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn pilot_light_share(
    scene: &Scene,
    params: &BdptParams,
    width: u32,
    height: u32,
    depth: u32,
    samples: u64,
    seed: u64,
    cancel: &AtomicBool,
) -> Option<f64> {
    let per_depth = super::mmlt_depth_normalization(
        scene,
        *params,
        width,
        height,
        samples.max(1),
        seed ^ 0xBA1A_2CED_0000_0001,
        cancel,
    )?;
    pass_light_share(&per_depth, depth)
}

/// Adds `other` into `image` pixel by pixel ([`crate::image::add_into`]).
pub use crate::image::add_into;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_depth_and_budget_follow_the_pass() {
        let fixed = DirectPass::Fixed(4);
        assert_eq!(fixed.chain_min_depth(5, 1), 2);
        assert_eq!(fixed.chain_min_depth(5, 2), 3);
        assert_eq!(fixed.chain_min_depth(1, 1), 0);
        assert_eq!(fixed.chain_min_depth(2, 2), 0);
        assert_eq!(DirectPass::Off.chain_min_depth(5, 2), 0);
        assert_eq!(DirectPass::Fixed(0).chain_min_depth(5, 2), 0);
        let t = Duration::from_secs(8);
        assert_eq!(
            fixed.budget(None, Some(t)),
            (Some(4), Some(Duration::from_secs(2)))
        );
        assert_eq!(fixed.budget(Some(100.0), None), (Some(4), None));
        let p = DirectPass::with_time_share(0.15);
        assert_eq!(p.budget(Some(3.0), None), (Some(2), None));
        assert_eq!(p.budget(Some(0.01), None), (Some(1), None));
        assert_eq!(p.budget(Some(1e9), None), (Some(DIRECT_MAX_SPP), None));
        assert_eq!(p.budget(None, Some(t)), (None, Some(t.mul_f64(0.15))));
    }

    #[test]
    fn balanced_share_follows_the_light() {
        let k = BALANCE_KAPPA;
        // Monotone in phi, inside the range, at the ends too.
        let mut last = 0.0;
        for i in 0..=100 {
            let s = balanced_share(k, f64::from(i) / 100.0);
            assert!(s >= last, "not monotone at phi {i}%");
            assert!((BALANCE_SHARE_RANGE.0..=BALANCE_SHARE_RANGE.1).contains(&s));
            last = s;
        }
        assert_eq!(balanced_share(k, 0.0), BALANCE_SHARE_RANGE.0);
        assert_eq!(balanced_share(k, 1.0), BALANCE_SHARE_RANGE.1);
        assert_eq!(balanced_share(k, f64::NAN), balanced_share(k, 0.5));
        // The optimum of A_d / s + A_c / (1 - s) with A_d / A_c = kappa phi / (1 - phi).
        for phi in [0.2, 0.5, 0.85] {
            let ratio = k * phi / (1.0 - phi);
            let error = |s: f64| ratio / s + 1.0 / (1.0 - s);
            let s = balanced_share(k, phi);
            for d in [-0.01, 0.01] {
                assert!(error(s) <= error(s + d), "phi {phi}: not the minimum");
            }
        }
        // kappa 0: no pass is worth anything; the floor stays.
        assert_eq!(balanced_share(0.0, 0.9), BALANCE_SHARE_RANGE.0);
    }

    #[test]
    fn resolve_turns_balanced_into_proportional() {
        let b = DirectPass::Balanced { kappa: 0.02 };
        assert!(b.is_on());
        assert!(!DirectPass::Balanced { kappa: 0.0 }.is_on());
        assert!(!DirectPass::Balanced { kappa: f64::NAN }.is_on());
        let DirectPass::Proportional {
            per_mutation,
            time_share,
        } = b.resolve(0.85)
        else {
            panic!("not resolved")
        };
        assert_eq!(time_share, balanced_share(0.02, 0.85));
        assert!(
            (per_mutation - PER_MUTATION_PER_ODDS * time_share / (1.0 - time_share)).abs() < 1e-12
        );
        for other in [
            DirectPass::Off,
            DirectPass::Fixed(3),
            DirectPass::with_time_share(0.3),
        ] {
            assert_eq!(other.resolve(0.85), other);
        }
        // Unresolved, as if phi were 0.5.
        let t = Some(Duration::from_secs(10));
        assert_eq!(b.budget(None, t), b.resolve(0.5).budget(None, t));
        assert_eq!(
            DirectPass::with_time_share(1.0).budget(Some(4.0), None),
            (Some(DIRECT_MAX_SPP), None)
        );
        assert_eq!(
            DirectPass::with_time_share(f64::NAN),
            DirectPass::with_time_share(0.0)
        );
        assert!(!DirectPass::with_time_share(0.0).is_on());
    }

    #[test]
    fn pass_light_share_splits_at_the_depth() {
        assert_eq!(pass_light_share(&[1.0, 2.0, 1.0, 4.0], 1), Some(3.0 / 8.0));
        assert_eq!(pass_light_share(&[1.0, 2.0, 1.0, 4.0], 2), Some(0.5));
        assert_eq!(pass_light_share(&[1.0, 2.0], 5), Some(1.0));
        assert_eq!(pass_light_share(&[0.0, 0.0, 0.0], 1), None);
        assert_eq!(pass_light_share(&[], 1), None);
        // Non-finite entries are ignored, not propagated.
        assert_eq!(pass_light_share(&[f64::NAN, 1.0, 1.0], 1), Some(0.5));
    }
}
