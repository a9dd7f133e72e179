//! A separate direct-lighting pass for the MCMC integrators (issue 17, item 2; Mitsuba 0.6's
//! PSSMLT/MLT `directSamples`, and the DRMLT reference implementation, which builds on it).
//!
//! The image splits exactly by path depth: `I = I_{depth <= K} + I_{depth > K}`. Direct
//! lighting (depth 0, emitters seen directly, and depth 1) and, in most scenes, the
//! one-bounce paths are smooth and cheap, and a per-pixel estimator renders them with far less
//! noise per unit of time than a Markov chain, which spends its mutations in proportion to
//! brightness and so mostly on exactly these paths. With the pass on, the chains sample only
//! depths > K ([`super::PssmltTarget::with_min_depth`]) and the pass adds a BDPT render of
//! depths 0..=K whose budget follows [`DirectPass`] (by default in proportion to the
//! chains'). `K` is the pass's depth, [`DIRECT_DEPTH_DEFAULT`] = 2 unless set
//! (`--direct-depth`).
//!
//! Unbiasedness: BDPT's MIS weights of a path are computed over the strategies of that path's
//! own depth (`s + t = depth + 2`), never over other depths, so BDPT at maximum depth K
//! estimates exactly `I_{depth <= K}`, and the restricted chains estimate exactly
//! `I_{depth > K}` (their target, bootstrap and splats all drop the same strategies). The
//! two estimators are independent (different random numbers), and the sum is unbiased;
//! `crates/render/tests/direct_pass.rs` checks it against BDPT, with negative controls (the
//! pass alone, and the pass added to unrestricted chains, which counts direct light twice).
//!
//! Reading chosen: Mitsuba 0.6 renders the direct pass with its own direct-illumination
//! integrator (depth 1 only); here it is the renderer's BDPT restricted to depth K, the same
//! estimator family the chains use (every strategy of depths 0..=K with MIS, light tracing
//! included), so the split needs no second light-transport code path. The default K = 2 (one
//! bounce of indirect light in the pass too) was measured at equal time (docs/performance.md,
//! "A deeper direct pass for PSSMLT"): against K = 1 it takes 16 % off PSSMLT's relMSE on
//! cornell-glass and 11 % on ajar-door (every seed), and is level on caustic-pool (median; two
//! seeds of six 20-26 % worse: there the depth-2 paths are caustics through the water, which
//! the chains sample better than BDPT). K = 3 is 5-9x worse on caustic-pool.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::bdpt::{render_bdpt_sampled, BdptOutput, BdptParams};
use crate::image::Image;
use crate::sampler::SamplerKind;
use crate::scene::Scene;
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
/// let pass = DirectPass::PSSMLT_DEFAULT;
/// assert!(pass.applies_to(5, 2));
/// assert_eq!(pass.chain_min_depth(5, 2), 3);
/// assert!(!pass.applies_to(2, 2)); // nothing deeper than depth 2 is left for the chains
/// // 64 mutations per pixel: 32 direct samples per pixel; 10 s: 1.5 s of direct pass.
/// assert_eq!(pass.budget(Some(64.0), None), (Some(32), None));
/// assert_eq!(
///     pass.budget(None, Some(Duration::from_secs(10))),
///     (None, Some(Duration::from_millis(1500)))
/// );
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
}

impl DirectPass {
    /// PSSMLT's default (`render::session::direct_pass_default`): half a direct sample per
    /// mutation, 15 % of a time budget. Measured (docs/performance.md, "Direct-lighting pass
    /// (issue 17, item 2)" and "A deeper direct pass for PSSMLT"): with the default depth 2,
    /// 15 % of 10 s was the only share of 10 %, 15 %, 20 % and 25 % better than the depth-1
    /// pass at every seed on two scenes (10 % is level on cornell-glass, 20-25 % on
    /// ajar-door), and made 48-72 samples per pixel at 93-146 mutations per pixel, about 0.5
    /// per mutation; a fixed count is a noise floor that longer renders cannot get below.
    pub const PSSMLT_DEFAULT: Self = Self::Proportional {
        per_mutation: 0.5,
        time_share: 0.15,
    };

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
    /// `mutations_per_pixel` chain mutations per pixel or of `time` (one of the two).
    #[must_use]
    pub fn budget(
        &self,
        mutations_per_pixel: Option<f64>,
        time: Option<Duration>,
    ) -> (Option<u32>, Option<Duration>) {
        match *self {
            DirectPass::Off => (Some(0), None),
            DirectPass::Fixed(n) => (Some(n), time.map(|t| t.mul_f64(DIRECT_TIME_SHARE))),
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
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> BdptOutput {
    let direct = BdptParams {
        max_depth: params.max_depth.min(depth),
        ..*params
    };
    render_bdpt_sampled(
        scene,
        &direct,
        sampler,
        spp.map(|n| n.max(1)),
        time,
        seed ^ 0xD1EC_7000_0000_0001,
        false,
        progress,
        cancel,
    )
}

/// Adds `other` into `image` pixel by pixel (same size; the direct pass plus the chains).
///
/// # Panics
/// If the sizes differ (both are rendered at the camera's size by construction).
pub fn add_into(image: &mut Image, other: &Image) {
    assert_eq!(
        (image.width, image.height),
        (other.width, other.height),
        "direct pass and chains must have the same image size"
    );
    for (a, b) in image.pixels.iter_mut().zip(&other.pixels) {
        for c in 0..3 {
            a[c] += b[c];
        }
    }
}

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
        let p = DirectPass::PSSMLT_DEFAULT;
        assert_eq!(p.budget(Some(3.0), None), (Some(2), None));
        assert_eq!(p.budget(Some(0.01), None), (Some(1), None));
        assert_eq!(p.budget(Some(1e9), None), (Some(DIRECT_MAX_SPP), None));
        assert_eq!(p.budget(None, Some(t)), (None, Some(t.mul_f64(0.15))));
    }

    #[test]
    fn add_into_sums_pixels() {
        let mut a = Image::new(2, 1);
        a.set(0, 0, [1.0, 2.0, 3.0]);
        let mut b = Image::new(2, 1);
        b.set(0, 0, [0.5, 0.5, 0.5]);
        b.set(1, 0, [1.0, 0.0, 0.0]);
        add_into(&mut a, &b);
        assert_eq!(a.get(0, 0), [1.5, 2.5, 3.5]);
        assert_eq!(a.get(1, 0), [1.0, 0.0, 0.0]);
    }
}
