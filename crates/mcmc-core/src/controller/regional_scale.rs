//! Regional scale adaptation over a partition, with optional refinement (regional-adaptive
//! paper, section 4-5, Alg. 1).

use super::global_scale::{AdaptState, ScaleAdaptParams};
use super::{Controller, RegionalTunable};
use crate::kernel::StepInfo;
use crate::McmcError;

/// Parameters of regional adaptation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionalScaleParams {
    /// The per-region sign rule (same meaning as for the global controller).
    pub adapt: ScaleAdaptParams,
    /// Split a region once it has been visited this many times since the last refinement
    /// (`M_split`, paper default 5000); `None` never refines.
    pub split_after_visits: Option<u64>,
    /// Check for refinement every this many steps (`M_refine`, paper default 10^7 over all
    /// threads).
    pub refine_every: u64,
}

impl RegionalScaleParams {
    /// The paper's values (section 8): sign rule of [`ScaleAdaptParams::otsu2018`],
    /// `M_split = 5000`, `M_refine = 10^7`.
    #[must_use]
    pub const fn otsu2018() -> Self {
        Self {
            adapt: ScaleAdaptParams::otsu2018(),
            split_after_visits: Some(5000),
            refine_every: 10_000_000,
        }
    }
}

impl Default for RegionalScaleParams {
    fn default() -> Self {
        Self::otsu2018()
    }
}

/// The adaptation state of one region: Alg. 1's `(i_k, A_k, n_k)` and the visits counted for
/// refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionStats {
    /// Sign-rule state.
    pub adapt: AdaptState,
    /// Visits since the last refinement pass.
    pub visits_since_refine: u64,
}

/// Regional scale adaptation: each region `k` of the kernel's partition has its own
/// `lambda_k`, updated by the sign rule from the acceptance of proposals made *from* region
/// `k` (the region of the current state; Alg. 1).
///
/// Diminishing adaptation per region. On refinement (every `refine_every` steps, regions
/// visited more than `split_after_visits` times split once per pass) children inherit the
/// parent's `lambda` and get `n = max(1, n_parent / 4)` (paper section 5.2); visit counters for
/// refinement are reset after each pass (our reading: the paper leaves it open).
#[derive(Clone, Debug)]
pub struct RegionalScale {
    params: RegionalScaleParams,
    regions: Vec<(AdaptState, u64)>,
    current_region: usize,
    steps: u64,
}

impl RegionalScale {
    /// A controller for a kernel with `num_regions` regions.
    pub fn new(params: RegionalScaleParams, num_regions: usize) -> Result<Self, McmcError> {
        params.adapt.validate()?;
        McmcError::check_range(
            "refine_every",
            params.refine_every as f64,
            1.0,
            f64::MAX,
            ">= 1",
        )?;
        Ok(Self {
            params,
            regions: vec![(AdaptState::new(), 0); num_regions.max(1)],
            current_region: 0,
            steps: 0,
        })
    }

    /// Sets every region's scale to `lambda_initial`.
    pub fn init<S, K: RegionalTunable<S> + ?Sized>(&self, kernel: &mut K) {
        for k in 0..kernel.num_regions() {
            kernel.set_log_scale_of(k, self.params.adapt.lambda_initial);
        }
    }

    /// Statistics of region `k`.
    #[must_use]
    pub fn region_stats(&self, k: usize) -> Option<RegionStats> {
        self.regions
            .get(k)
            .map(|&(adapt, visits_since_refine)| RegionStats {
                adapt,
                visits_since_refine,
            })
    }

    /// Number of regions tracked.
    #[must_use]
    pub fn num_regions(&self) -> usize {
        self.regions.len()
    }

    fn refine<S, K: RegionalTunable<S> + ?Sized>(&mut self, kernel: &mut K, threshold: u64) {
        let n = self.regions.len();
        for k in 0..n {
            if self.regions[k].1 <= threshold {
                continue;
            }
            if let Some(children) = kernel.split_region(k) {
                let parent = self.regions[k].0;
                let child = AdaptState {
                    visits: 0,
                    accepted: 0.0,
                    updates: (parent.updates / 4).max(1),
                };
                self.regions.resize(kernel.num_regions(), (child, 0));
                // `k` itself is the first child (see `Partition::split`).
                self.regions[k] = (child, 0);
                for c in children {
                    self.regions[c] = (child, 0);
                }
            }
        }
        for r in &mut self.regions {
            r.1 = 0;
        }
    }
}

impl<S, K: RegionalTunable<S> + ?Sized> Controller<K, S> for RegionalScale {
    fn before_step(&mut self, kernel: &K, x: &S) {
        self.current_region = kernel.region_of(x);
    }

    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        let k = self.current_region;
        if k >= self.regions.len() {
            self.regions
                .resize(kernel.num_regions().max(k + 1), (AdaptState::new(), 0));
        }
        let lambda = kernel.log_scale_of(k);
        let (state, visits) = &mut self.regions[k];
        *visits += 1;
        if let Some(new) = state.record(info.accept_prob[0], lambda, &self.params.adapt) {
            kernel.set_log_scale_of(k, new);
        }
        self.steps += 1;
        if let Some(threshold) = self.params.split_after_visits {
            if self.steps.is_multiple_of(self.params.refine_every) {
                self.refine(kernel, threshold);
            }
        }
    }

    fn is_frozen(&self) -> bool {
        false
    }
}
