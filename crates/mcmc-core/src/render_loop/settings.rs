//! The render loop's settings: its budget, the part of the job list a shard renders, and
//! every field's range.

use std::time::Duration;

use super::{ChainAllocation, NormalizationMode};
use crate::McmcError;

/// How long a render loop runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LoopBudget {
    /// A total number of mutations over all chains (deterministic output).
    Mutations(u64),
    /// Wall-clock time from the call, bootstrap included (output depends on speed).
    Time(Duration),
}

/// Settings of a render loop. Plain data with documented defaults; check them with
/// [`LoopSettings::validate`] (the loop does).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopSettings {
    /// Number of Markov chains (default 256; 1..=1 048 576). Capped at the number of
    /// mutations under a mutation budget, and under a time budget at what the time left after
    /// the bootstrap affords (a round or [`LoopSettings::min_time_mutations`] mutations per
    /// chain at the bootstrap's rate), with a note.
    pub chains: usize,
    /// Independent samples per target in the bootstrap (default 100 000, pbrt's value;
    /// 1..=10^12).
    pub bootstrap_samples: u64,
    /// The budget (default 1 000 000 mutations).
    pub budget: LoopBudget,
    /// Master seed (default 0).
    pub seed: u64,
    /// Mutations per chain per round (default 1000; >= 1): how often shared statistics are
    /// pooled.
    pub round_mutations: u64,
    /// Number of fixed work units (default 32; 1..=4096). The image depends on it, not on the
    /// thread count.
    pub jobs: usize,
    /// Under a time budget, the share of the time the bootstrap may use (default 0.25, in
    /// (0, 1]); it stops early (with a note) when the share is spent.
    pub bootstrap_time_share: f64,
    /// Combine the large-step samples with the Metropolis estimator by multiple importance
    /// sampling (Kelemen et al. 2002, section 4; LuxCore's METROPOLIS sampler): see
    /// [`LargeStepMis`](super::LargeStepMis). Default **off** (the plain expected-value estimator, Kelemen eq. 5).
    /// The loop passes it, with the chain's target's bootstrap estimate `b_d`, to the kernel
    /// factory in [`ChainSlot`](super::ChainSlot); it takes effect for kernels made with
    /// [`LargeStepMis::for_slot`](super::LargeStepMis::for_slot) (others ignore it).
    pub large_step_mis: bool,
    /// How the chains are spread over the targets (default [`ChainAllocation::Joint`],
    /// pbrt's scheme; [`ChainAllocation::PerTarget`]: a fixed count per target, each target's
    /// splats scaled by `b_d / n_d`).
    pub chain_allocation: ChainAllocation,
    /// Which part of the fixed job list this run renders (default [`Shard::WHOLE`]): see
    /// [`Shard`].
    pub shard: Shard,
    /// Under a time budget, the fewest mutations the loop plans per chain (default
    /// [`MIN_TIME_MUTATIONS`]; >= 1; at least [`LoopSettings::round_mutations`] is planned
    /// in any case): the chains are capped at what the time left after the bootstrap affords
    /// at its rate. A controller whose first round is an estimation phase raises it so that
    /// the phase stays a bounded share of the run.
    pub min_time_mutations: u64,
    /// How `b` is estimated (default [`NormalizationMode::Pooled`]: the bootstrap with every
    /// large-step candidate; see [`Normalization`](super::Normalization)). A given `b` must be finite and positive.
    pub normalization: NormalizationMode,
}

/// A part of a render split over processes: shard `index` of `count` owns the contiguous
/// run of jobs `j` with `j * count / jobs == index`. Every shard draws the same bootstrap and
/// chain starts (they depend only on the seed); a shard runs only its own jobs' chains, or,
/// when the controllers couple the chains ([`SharedController::COUPLES_CHAINS`](super::SharedController::COUPLES_CHAINS)), every chain
/// with only its own jobs' splats kept, so the pooled statistics are those of the whole
/// render. Its sink then holds exactly its jobs' splats and [`LoopOutput::mutations`](super::LoopOutput::mutations) counts
/// exactly its jobs' mutations: with an order-independent sink ([`ExactSplatGrid`](super::ExactSplatGrid)) the sums
/// of all shards' sinks and mutation counts are bit for bit those of the whole render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This part, `0..count`.
    pub index: u32,
    /// Number of parts, at least 1.
    pub count: u32,
}

impl Shard {
    /// The whole render (shard 0 of 1).
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// True if work unit `unit` of `units` belongs to this shard.
    #[must_use]
    pub fn owns(&self, unit: usize, units: usize) -> bool {
        units == 0 || (unit as u64 * u64::from(self.count) / units as u64) == u64::from(self.index)
    }

    /// True for [`Shard::WHOLE`] (or any one-part split).
    #[must_use]
    pub fn is_whole(&self) -> bool {
        self.count == 1
    }
}

impl Default for Shard {
    fn default() -> Self {
        Self::WHOLE
    }
}

impl Default for LoopSettings {
    fn default() -> Self {
        Self {
            chains: 256,
            bootstrap_samples: 100_000,
            budget: LoopBudget::Mutations(1_000_000),
            seed: 0,
            round_mutations: 1000,
            jobs: 32,
            bootstrap_time_share: 0.25,
            large_step_mis: false,
            chain_allocation: ChainAllocation::Joint,
            shard: Shard::WHOLE,
            min_time_mutations: MIN_TIME_MUTATIONS,
            normalization: NormalizationMode::Pooled,
        }
    }
}

/// Largest accepted chain count.
pub const MAX_CHAINS: usize = 1 << 20;

/// Largest accepted bootstrap size per target.
pub const MAX_BOOTSTRAP_SAMPLES: u64 = 1_000_000_000_000;

/// Under a time budget, the default of [`LoopSettings::min_time_mutations`], the fewest
/// mutations the loop plans per chain (or one round,
/// [`LoopSettings::round_mutations`], if that is more: a job runs its chains one after the
/// other, a round each, so chains beyond what the time affords in the first round would never
/// run): the chains are capped at what the time left after the bootstrap affords at the
/// bootstrap's rate of target evaluations (starting a chain counted as well), with a note.
pub const MIN_TIME_MUTATIONS: u64 = 100;

impl LoopSettings {
    /// Checks every field against its documented range.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<(), McmcError> {
        let range = |name, v: f64, lo: f64, hi: f64, allowed| {
            McmcError::check_range(name, v, lo, hi, allowed)
        };
        range(
            "chains",
            self.chains as f64,
            1.0,
            MAX_CHAINS as f64,
            "1..=1048576",
        )?;
        range(
            "bootstrap_samples",
            self.bootstrap_samples as f64,
            1.0,
            MAX_BOOTSTRAP_SAMPLES as f64,
            "1..=10^12",
        )?;
        range(
            "round_mutations",
            self.round_mutations as f64,
            1.0,
            f64::MAX,
            ">= 1",
        )?;
        range("jobs", self.jobs as f64, 1.0, 4096.0, "1..=4096")?;
        range(
            "min_time_mutations",
            self.min_time_mutations as f64,
            1.0,
            f64::MAX,
            ">= 1",
        )?;
        if self.shard.count == 0 || self.shard.index >= self.shard.count {
            return Err(McmcError::InvalidParameter {
                name: "shard",
                value: f64::from(self.shard.index),
                allowed: "index in 0..count, count >= 1",
            });
        }
        if let NormalizationMode::Given(b) = self.normalization {
            if !(b.is_finite() && b > 0.0) {
                return Err(McmcError::InvalidParameter {
                    name: "normalization",
                    value: b,
                    allowed: "a finite b > 0",
                });
            }
        }
        if !(self.bootstrap_time_share > 0.0 && self.bootstrap_time_share <= 1.0) {
            return Err(McmcError::InvalidParameter {
                name: "bootstrap_time_share",
                value: self.bootstrap_time_share,
                allowed: "(0, 1]",
            });
        }
        match self.budget {
            LoopBudget::Mutations(0) => Err(McmcError::InvalidParameter {
                name: "budget",
                value: 0.0,
                allowed: ">= 1 mutation",
            }),
            LoopBudget::Time(t) if t.is_zero() => Err(McmcError::InvalidParameter {
                name: "budget",
                value: 0.0,
                allowed: "> 0 seconds",
            }),
            _ => Ok(()),
        }
    }
}
