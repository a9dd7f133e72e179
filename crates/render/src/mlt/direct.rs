//! A separate direct-lighting pass for the MCMC integrators (issue 17, item 2; Mitsuba 0.6's
//! PSSMLT/MLT `directSamples`, and the DRMLT reference implementation, which builds on it).
//!
//! The image splits exactly by path depth: `I = I_{depth <= 1} + I_{depth >= 2}`. Direct
//! lighting (depth 0, emitters seen directly, and depth 1) is smooth and cheap, and a
//! per-pixel estimator with next-event estimation renders it with far less noise per unit of
//! time than a Markov chain, which spends its mutations in proportion to brightness and so
//! mostly on exactly these paths. With the pass on, the chains sample only depths >= 2
//! ([`super::PssmltTarget::with_min_depth`]; MMLT: only the targets of depth >= 2) and the
//! pass adds a BDPT render of depths 0 and 1 at [`DirectPass::samples_per_pixel`].
//!
//! Unbiasedness: BDPT's MIS weights of a path are computed over the strategies of that path's
//! own depth (`s + t = depth + 2`), never over other depths, so BDPT at maximum depth 1
//! estimates exactly `I_{depth <= 1}`, and the restricted chains estimate exactly
//! `I_{depth >= 2}` (their target, bootstrap and splats all drop the same strategies). The
//! two estimators are independent (different random numbers), and the sum is unbiased;
//! `crates/render/tests/direct_pass.rs` checks it against BDPT, with negative controls (the
//! pass alone, and the pass added to unrestricted chains, which counts direct light twice).
//!
//! Reading chosen: Mitsuba 0.6 renders the direct pass with its own direct-illumination
//! integrator; here it is the renderer's BDPT restricted to depth 1, which is the same
//! estimator family the chains use (every strategy of depths 0 and 1 with MIS, light tracing
//! included), so the split needs no second light-transport code path.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::bdpt::{render_bdpt, BdptOutput, BdptParams};
use crate::image::Image;
use crate::scene::Scene;
use mcmc_core::Progress;

/// Paths up to this depth (bounces) are the direct pass's; the chains take the deeper ones.
pub const DIRECT_MAX_DEPTH: u32 = 1;

/// The direct-lighting pass's settings.
///
/// ```
/// use render::mlt::direct::DirectPass;
/// let pass = DirectPass { samples_per_pixel: 16 };
/// assert!(pass.applies_to(5));
/// assert!(!pass.applies_to(1)); // nothing deeper than depth 1 is left for the chains
/// assert!(!DirectPass::OFF.applies_to(5));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DirectPass {
    /// BDPT samples per pixel of the depth-0 and depth-1 image (0: no separate pass, the
    /// chains sample every depth). Mitsuba 0.6's PSSMLT default is 16.
    pub samples_per_pixel: u32,
}

impl DirectPass {
    /// No separate pass.
    pub const OFF: Self = Self {
        samples_per_pixel: 0,
    };

    /// Whether the pass is used at maximum path depth `max_depth`: on, and the chains have
    /// depths beyond [`DIRECT_MAX_DEPTH`] left to sample.
    #[must_use]
    pub fn applies_to(&self, max_depth: u32) -> bool {
        self.samples_per_pixel > 0 && max_depth > DIRECT_MAX_DEPTH
    }

    /// The smallest depth the chains sample: `DIRECT_MAX_DEPTH + 1` when the pass applies
    /// at `max_depth`, else 0 (every depth).
    #[must_use]
    pub fn chain_min_depth(&self, max_depth: u32) -> u32 {
        if self.applies_to(max_depth) {
            DIRECT_MAX_DEPTH + 1
        } else {
            0
        }
    }
}

impl Default for DirectPass {
    /// Off.
    fn default() -> Self {
        Self::OFF
    }
}

/// Under a time budget `T`, the direct pass stops after `DIRECT_TIME_SHARE * T` even if it
/// has not reached its samples per pixel (it always completes one pass), so a large
/// `samples_per_pixel` cannot starve the chains.
pub const DIRECT_TIME_SHARE: f64 = 0.25;

/// Renders the direct pass: BDPT at maximum depth [`DIRECT_MAX_DEPTH`] (the other
/// parameters, roulette included, from `params`), `pass.samples_per_pixel` samples per pixel,
/// on the camera's image size, stopping early after `time` if given (every pixel is the mean
/// of its own samples, so a shortened pass stays unbiased). The seed is mixed so the pass
/// draws other numbers than a BDPT render of the same seed (not needed for unbiasedness, only
/// for independence from anything else the caller renders with `seed`).
pub fn render_direct(
    scene: &Scene,
    params: &BdptParams,
    pass: DirectPass,
    seed: u64,
    time: Option<Duration>,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> BdptOutput {
    let direct = BdptParams {
        max_depth: params.max_depth.min(DIRECT_MAX_DEPTH),
        ..*params
    };
    render_bdpt(
        scene,
        &direct,
        Some(pass.samples_per_pixel.max(1)),
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
    fn min_depth_follows_the_pass() {
        let on = DirectPass {
            samples_per_pixel: 4,
        };
        assert_eq!(on.chain_min_depth(5), 2);
        assert_eq!(on.chain_min_depth(1), 0);
        assert_eq!(DirectPass::OFF.chain_min_depth(5), 0);
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
