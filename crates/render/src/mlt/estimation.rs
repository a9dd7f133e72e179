//! The estimation phase of automatic large-step control (Zsolnai & Szirmay-Kalos 2013,
//! section 2): how many mutations per chain it runs under each kind of budget.
//!
//! The paper measures `eta_s`, `eta_l` and `eta_0` "at the start of the rendering" without
//! saying for how long or at which `p_l`; our reading runs every chain's first round at the
//! initial probability and sets `p_l` from the statistics pooled over all chains at the end
//! of that round. The rule below keeps that phase a bounded share of the run:
//!
//! - **Mutation budget** (deterministic): `min(estimation_steps, n / chains / 10)` mutations
//!   per chain, at least 1: at most a tenth of every chain's budget
//!   ([`ESTIMATION_SHARE_DIVISOR`]).
//! - **Time budget**: `min(estimation_steps, TIME_BUDGET_ESTIMATION_STEPS)` mutations per
//!   chain, a fixed count that does not depend on the clock, and the loop plans at least ten
//!   times as many mutations per chain (`LoopSettings::min_time_mutations`): it starts only
//!   the chains that the time left after the bootstrap affords at the bootstrap's rate with
//!   that many mutations each. At the bootstrap's rate the phase is therefore at most a tenth
//!   of the chains' mutations; the realised share exceeds that only as far as the chains run
//!   slower than the bootstrap's evaluations (a mutation costs a little more than an
//!   independent sample: a proposal and a second splat). The run's typed statistics report
//!   the phase's mutations (`LargeStepEstimate::steps`).
//!
//! Why 100 for a time budget: with the default 256 chains the pooled phase then holds 25 600
//! mutations, about 12 800 of each kind at `p_l = 0.5`, so each acceptance mean has a binomial
//! standard error of at most `0.5 / sqrt(12 800) = 0.0044`; and ten times 100 is the loop's
//! default round of 1000 mutations, the fewest a time budget plans per chain for a fixed
//! `p_l`, so automatic control starts as many chains as a fixed `p_l` does.

use mcmc_core::controller::AutoLargeStep;
use mcmc_core::render_loop::{LoopBudget, LoopSettings};

/// Largest estimation phase, in mutations per chain, under a time budget.
pub const TIME_BUDGET_ESTIMATION_STEPS: u64 = 100;

/// The estimation phase is at most `1 / ESTIMATION_SHARE_DIVISOR` of each chain's mutations:
/// of its budget under a mutation budget, of what the loop plans for it under a time budget.
pub const ESTIMATION_SHARE_DIVISOR: u64 = 10;

/// Sets up the estimation phase in `loop_settings` for a request of `estimation_steps`
/// mutations per chain: the rounds are as long as the phase (the first round ends exactly
/// when every chain has run it) and, under a time budget, the loop plans at least
/// [`ESTIMATION_SHARE_DIVISOR`] times as many mutations per chain. Returns the phase's
/// mutations per chain (at least 1).
pub(super) fn set_up_estimation(loop_settings: &mut LoopSettings, estimation_steps: u64) -> u64 {
    let chains = loop_settings.chains.max(1) as u64;
    let steps = match loop_settings.budget {
        LoopBudget::Mutations(n) => estimation_steps.min(n / chains / ESTIMATION_SHARE_DIVISOR),
        LoopBudget::Time(_) => estimation_steps.min(TIME_BUDGET_ESTIMATION_STEPS),
    }
    .max(1);
    loop_settings.round_mutations = steps;
    if let LoopBudget::Time(_) = loop_settings.budget {
        loop_settings.min_time_mutations = loop_settings
            .min_time_mutations
            .max(steps.saturating_mul(ESTIMATION_SHARE_DIVISOR));
    }
    steps
}

/// Warm-up of [`crate::mlt::LargeStepMode::Schedule`] under a time budget, in mutations per
/// chain: a chain's length is not known in advance there, so the warm-up is a fixed count.
pub const TIME_BUDGET_WARM_UP_STEPS: u64 = 1000;

/// Mutations per chain of a [`crate::mlt::LargeStepMode::Schedule`] warm-up: the first
/// [`ESTIMATION_SHARE_DIVISOR`]-th of each chain's mutations under a mutation budget (the
/// authors' code: `LS_RATIO`, 10 % of a chain's samples), [`TIME_BUDGET_WARM_UP_STEPS`]
/// under a time budget; at least 1.
pub(super) fn warm_up_steps(loop_settings: &LoopSettings) -> u64 {
    let chains = loop_settings.chains.max(1) as u64;
    match loop_settings.budget {
        LoopBudget::Mutations(n) => n / chains / ESTIMATION_SHARE_DIVISOR,
        LoopBudget::Time(_) => TIME_BUDGET_WARM_UP_STEPS,
    }
    .max(1)
}

/// The pooled controller of every chain: it records during the first round and freezes with
/// the statistics of all chains at its end (one step pooled suffices, since the loop pools
/// only at round boundaries). Freezing at the first boundary rather than at a count of
/// `steps x chains` keeps it right when the loop starts fewer chains than requested.
pub(super) fn auto_large_step() -> AutoLargeStep {
    AutoLargeStep::pooled(1).unwrap_or_else(|_| unreachable!("1 >= 1"))
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    fn settings(chains: usize, budget: LoopBudget) -> LoopSettings {
        LoopSettings {
            chains,
            budget,
            ..LoopSettings::default()
        }
    }

    #[test]
    fn a_mutation_budget_keeps_a_tenth_of_each_chain() {
        let mut s = settings(256, LoopBudget::Mutations(256 * 1024));
        assert_eq!(set_up_estimation(&mut s, 1000), 102);
        assert_eq!(s.round_mutations, 102);
        // Unchanged for mutation budgets: the chain cap only applies to time budgets.
        assert_eq!(
            s.min_time_mutations,
            LoopSettings::default().min_time_mutations
        );
        let mut long = settings(256, LoopBudget::Mutations(256 * 100_000));
        assert_eq!(set_up_estimation(&mut long, 1000), 1000);
        let mut tiny = settings(256, LoopBudget::Mutations(100));
        assert_eq!(set_up_estimation(&mut tiny, 1000), 1);
    }

    #[test]
    fn a_warm_up_is_a_tenth_of_each_chain_or_fixed_under_a_time_budget() {
        assert_eq!(
            warm_up_steps(&settings(256, LoopBudget::Mutations(256 * 1024))),
            102
        );
        assert_eq!(warm_up_steps(&settings(256, LoopBudget::Mutations(100))), 1);
        assert_eq!(
            warm_up_steps(&settings(256, LoopBudget::Time(Duration::from_secs(30)))),
            TIME_BUDGET_WARM_UP_STEPS
        );
    }

    #[test]
    fn a_time_budget_caps_the_phase_and_plans_ten_times_as_much() {
        let mut s = settings(256, LoopBudget::Time(Duration::from_secs(3)));
        assert_eq!(
            set_up_estimation(&mut s, 1000),
            TIME_BUDGET_ESTIMATION_STEPS
        );
        assert_eq!(s.round_mutations, TIME_BUDGET_ESTIMATION_STEPS);
        assert_eq!(
            s.min_time_mutations,
            TIME_BUDGET_ESTIMATION_STEPS * ESTIMATION_SHARE_DIVISOR
        );
        let mut short = settings(256, LoopBudget::Time(Duration::from_secs(3)));
        assert_eq!(set_up_estimation(&mut short, 20), 20);
        assert_eq!(short.min_time_mutations, 200);
    }
}
