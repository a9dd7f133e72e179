//! Parameters of shared regional scale adaptation (regional-adaptive paper, Alg. 1, sections
//! 6.2 and 8.1): the sign rule, when `lambda` steps, and the quadtree's refinement schedule.

use super::ScaleAdaptParams;
use crate::McmcError;

/// When the pooled statistics of a region make their sign steps (Alg. 1 lines 13-18).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RegionalUpdateRule {
    /// Alg. 1 as written: one step for every `L` proposals from the region, at the paper's
    /// speed. The visits of a round are replayed at the synchronisation point in job and
    /// chain order, each completed block of `L` making its step with `gamma_{n_k}` and
    /// `n_k += 1`: exactly what the sequential rule does on the same acceptance record, so
    /// the learned scales equal a single thread's replay of that record (and are the same for
    /// any thread count).
    #[default]
    EveryLVisits,
    /// At most one step per region per synchronisation point, from all of the region's
    /// visits of the round (at least `L`), `n_k` counting synchronisation points: slow when
    /// rounds are long. Kept as a comparison and as the negative control of the paper-speed
    /// tests.
    OncePerRound,
}

/// Parameters of shared regional adaptation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionalScaleParams {
    /// The sign rule of Alg. 1 per region: target acceptance `alpha*`, `L`, `gamma_max`,
    /// `gamma_scale`, `lambda_0`, `lambda_min` (its `freeze_after_updates` is not used here;
    /// see `freeze_after_mutations`).
    pub adapt: ScaleAdaptParams,
    /// `M_split`: at a refinement, split every region visited at least this many times since
    /// the previous refinement (section 6.2); `None` never refines (grids, or a frozen tree).
    pub split_after_visits: Option<u64>,
    /// `M_refine`: refine at the first synchronisation point after every this many mutations
    /// over all chains (section 6.2, 7).
    pub refine_every: u64,
    /// Refinement never makes the partition larger than this many regions (`None`: no cap;
    /// the paper has none).
    pub max_regions: Option<usize>,
    /// The mixture component that is the regionally scaled proposal: only its proposals
    /// update `lambda` (Alg. 1 is about that proposal); visits for refinement count every
    /// step. `None`: every step is one (a kernel that is only the scaled proposal).
    pub perturbation_component: Option<usize>,
    /// Finite adaptation: stop adapting and refining at the first synchronisation point after
    /// this many mutations over all chains; `None` adapts forever (diminishing adaptation).
    /// `Some(0)` never adapts (the FIXED variant with the same code path).
    pub freeze_after_mutations: Option<u64>,
    /// When the sign steps happen (default: every `L` visits, as Alg. 1).
    pub update_rule: RegionalUpdateRule,
}

/// `M_split` of [`RegionalScaleParams::otsu2018_for_pixels`] in units of `L`: a leaf splits
/// once its visits since the last pass would have made 50 sign steps.
pub const SPLIT_UPDATES: u64 = 50;

/// Pixels per leaf of [`RegionalScaleParams::otsu2018_for_pixels`]: at most one leaf per this
/// many pixels.
pub const PIXELS_PER_LEAF: u64 = 16;

impl RegionalScaleParams {
    /// The paper's values (section 8.1): `L = 10`, `gamma_max = 1`, `gamma_scale = 5`,
    /// `lambda_0 = 1`, `lambda_min = -30`, target acceptance 0.5 (the default of section 8.1;
    /// 0.8 for the Necklace scene), `M_split = 5000`, `M_refine = 10^7`; the scaled proposal is
    /// mixture component 0; one step per `L` visits (Alg. 1); diminishing adaptation (no
    /// freeze); no cap on the regions.
    #[must_use]
    pub const fn otsu2018() -> Self {
        Self {
            adapt: ScaleAdaptParams::otsu2018(),
            split_after_visits: Some(5000),
            refine_every: 10_000_000,
            max_regions: None,
            perturbation_component: Some(0),
            freeze_after_mutations: None,
            update_rule: RegionalUpdateRule::EveryLVisits,
        }
    }

    /// The paper's parameters with the refinement schedule derived from the image size
    /// (`pixels`) instead of the paper's `M_split = 5000`, `M_refine = 10^7` (tuned for
    /// 10^9-10^10 mutations of 720p images, section 8). Our reading, the paper gives no rule:
    ///
    /// - `M_split = 50 L` (= 500): a leaf splits once it holds enough visits for 50 sign steps,
    ///   so its children start from a settled scale.
    /// - `M_refine = M_split * pixels / 16`: a leaf splits when its share of a pass's visits
    ///   is at least `M_split / M_refine = 16 / pixels`, i.e. when it receives at least the
    ///   visits of 16 average pixels. On a screen partition that bounds a pass's splits by
    ///   `pixels / 16`.
    /// - `max_regions = pixels / 16` (at least 1): at the end of a render there is at most one
    ///   leaf per 16 pixels. A partition with fixed top cells (the 4-D one) adds their number
    ///   itself.
    ///
    /// # Example
    /// ```
    /// use mcmc_core::controller::RegionalScaleParams;
    ///
    /// let p = RegionalScaleParams::otsu2018_for_pixels(64 * 64);
    /// assert_eq!(p.split_after_visits, Some(500));
    /// assert_eq!(p.refine_every, 500 * 256);
    /// assert_eq!(p.max_regions, Some(256));
    /// ```
    #[must_use]
    pub const fn otsu2018_for_pixels(pixels: u64) -> Self {
        let p = Self::otsu2018();
        let split = SPLIT_UPDATES * p.adapt.updates_every;
        let leaves = pixels / PIXELS_PER_LEAF;
        let leaves = if leaves < 1 { 1 } else { leaves };
        Self {
            split_after_visits: Some(split),
            refine_every: split * leaves,
            max_regions: Some(leaves as usize),
            ..p
        }
    }

    /// Checks every field's range.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<(), McmcError> {
        self.adapt.validate()?;
        McmcError::check_range(
            "refine_every",
            self.refine_every as f64,
            1.0,
            f64::MAX,
            ">= 1",
        )?;
        if let Some(m) = self.split_after_visits {
            McmcError::check_range("split_after_visits", m as f64, 1.0, f64::MAX, ">= 1")?;
        }
        if let Some(m) = self.max_regions {
            McmcError::check_range("max_regions", m as f64, 1.0, f64::MAX, ">= 1")?;
        }
        Ok(())
    }
}

impl Default for RegionalScaleParams {
    fn default() -> Self {
        Self::otsu2018()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_schedule_bounds_the_leaves() {
        let p = RegionalScaleParams::otsu2018_for_pixels(128 * 128);
        assert_eq!(p.max_regions, Some(1024));
        assert_eq!(p.split_after_visits, Some(500));
        assert_eq!(p.refine_every, 512_000);
        assert!(p.validate().is_ok());
        let tiny = RegionalScaleParams::otsu2018_for_pixels(4);
        assert_eq!(tiny.max_regions, Some(1));
        assert!(tiny.validate().is_ok());
        let bad = RegionalScaleParams {
            max_regions: Some(0),
            ..p
        };
        assert!(bad.validate().is_err());
    }
}
