//! A large-step probability that changes once, after a fixed number of each chain's own steps:
//! the warm-up schedule of the Langevin MLT authors' code (a low probability while a chain
//! learns its preconditioner, then the working one).
//!
//! Not adaptation: the switch depends only on the chain's step count, never on its states or
//! acceptances, so the chain is a time-inhomogeneous sequence of kernels that each leave the
//! target invariant, and so does their composition. Nothing is pooled, chains stay
//! independent, and the schedule is the same for any thread count.

use super::{Controller, LargeStepTunable, SharedController};
use crate::error::McmcError;
use crate::kernel::StepInfo;

/// Sets the kernel's large-step probability to `then` after the chain's first `warm_up`
/// steps (the kernel starts with whatever probability it was made with).
///
/// # Example
/// ```
/// use mcmc_core::controller::LargeStepSchedule;
///
/// let schedule = LargeStepSchedule::new(100, 0.2).unwrap();
/// assert_eq!(schedule.warm_up(), 100);
/// assert!(LargeStepSchedule::new(100, 1.5).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LargeStepSchedule {
    warm_up: u64,
    then: f64,
    steps: u64,
}

impl LargeStepSchedule {
    /// Switches to probability `then` after `warm_up` steps of the chain.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] for `then` outside `[0, 1]`.
    pub fn new(warm_up: u64, then: f64) -> Result<Self, McmcError> {
        McmcError::check_range("then", then, 0.0, 1.0, "0..=1")?;
        Ok(Self {
            warm_up,
            then,
            steps: 0,
        })
    }

    /// Steps of the chain before the switch.
    #[must_use]
    pub fn warm_up(&self) -> u64 {
        self.warm_up
    }

    /// The probability after the switch.
    #[must_use]
    pub fn then(&self) -> f64 {
        self.then
    }
}

impl<K: LargeStepTunable + ?Sized, S> Controller<K, S> for LargeStepSchedule {
    fn after_step(&mut self, kernel: &mut K, _info: &StepInfo) {
        if self.steps < self.warm_up {
            self.steps += 1;
            if self.steps == self.warm_up {
                kernel.set_large_step_probability(self.then);
            }
        }
    }

    fn is_frozen(&self) -> bool {
        self.steps >= self.warm_up
    }
}

/// Nothing is pooled: each chain switches on its own count.
impl<K: ?Sized> SharedController<K> for LargeStepSchedule {
    type Shared = ();
    const COUPLES_CHAINS: bool = false;
    fn contribute(&mut self, _kernel: &mut K, _pooled: &mut ()) {}
    fn receive(&mut self, _kernel: &mut K, _pooled: &()) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Probe(f64);

    impl LargeStepTunable for Probe {
        fn large_step_probability(&self) -> f64 {
            self.0
        }
        fn set_large_step_probability(&mut self, p: f64) {
            self.0 = p;
        }
        fn is_large_step(&self, component: usize) -> bool {
            component == 0
        }
    }

    #[test]
    fn switches_exactly_after_the_warm_up() {
        let mut kernel = Probe(0.05);
        let mut schedule = LargeStepSchedule::new(3, 0.2).unwrap();
        let info = StepInfo::new(0);
        for step in 1..=5u64 {
            Controller::<Probe, ()>::after_step(&mut schedule, &mut kernel, &info);
            let expected = if step < 3 { 0.05 } else { 0.2 };
            assert_eq!(kernel.0, expected, "after step {step}");
            assert_eq!(
                Controller::<Probe, ()>::is_frozen(&schedule),
                step >= 3,
                "after step {step}"
            );
        }
        // A zero warm-up is frozen from the start and never touches the kernel.
        let mut none = LargeStepSchedule::new(0, 0.9).unwrap();
        assert!(Controller::<Probe, ()>::is_frozen(&none));
        Controller::<Probe, ()>::after_step(&mut none, &mut kernel, &info);
        assert_eq!(kernel.0, 0.2);
    }
}
