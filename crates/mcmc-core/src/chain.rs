//! The chain driver: owns the current sample, the kernel, the controller and the RNG.

use rand::Rng;

use crate::controller::Controller;
use crate::kernel::{Kernel, Observer, StepInfo};
use crate::stats::AcceptanceStats;
use crate::target::{Sample, SampleOf, Target};
use crate::McmcError;

/// A Markov chain: current state with its cached evaluation (never evaluated twice), a kernel,
/// an adaptation controller and its own RNG. `step` runs the kernel, then the controller.
///
/// Chains are independent; run many in parallel (one per rayon task) with per-chain seeds
/// derived from (user seed, chain index), e.g. with [`crate::seed::chain_seed`].
pub struct Chain<'t, T: Target, K, C, R> {
    target: &'t T,
    kernel: K,
    controller: C,
    rng: R,
    current: SampleOf<T>,
    scratch: Vec<SampleOf<T>>,
    stats: AcceptanceStats,
}

impl<'t, T, K, C, R> Chain<'t, T, K, C, R>
where
    T: Target,
    K: Kernel<T>,
    C: Controller<K, T::State>,
    R: Rng,
{
    /// A chain started at `initial` (evaluated once here).
    ///
    /// # Errors
    /// [`McmcError::ZeroDensityStart`] if `initial` has zero density,
    /// [`McmcError::NonFiniteDensity`] if its log density is NaN or `+inf`.
    pub fn new(
        target: &'t T,
        kernel: K,
        controller: C,
        rng: R,
        initial: T::State,
    ) -> Result<Self, McmcError> {
        let current = Sample::evaluate(target, initial);
        Self::from_sample(target, kernel, controller, rng, current)
    }

    /// A chain started at an already evaluated sample (e.g. resampled from a bootstrap).
    ///
    /// # Errors
    /// As [`Chain::new`].
    pub fn from_sample(
        target: &'t T,
        kernel: K,
        controller: C,
        rng: R,
        current: SampleOf<T>,
    ) -> Result<Self, McmcError> {
        let ld = current.log_density;
        if ld.is_nan() || ld == f64::INFINITY {
            return Err(McmcError::NonFiniteDensity {
                value: ld,
                stage: 0,
            });
        }
        if ld == f64::NEG_INFINITY {
            return Err(McmcError::ZeroDensityStart);
        }
        let scratch = vec![current.clone(); kernel.stages().max(1) + 1];
        Ok(Self {
            target,
            kernel,
            controller,
            rng,
            current,
            scratch,
            stats: AcceptanceStats::default(),
        })
    }

    /// One transition: kernel step (reporting candidates to `observer`), statistics, then
    /// controller update.
    ///
    /// # Errors
    /// If a candidate had a NaN/+inf density or NaN Hastings term. The candidate was rejected
    /// and the chain is still valid; the error says the target or proposal has a bug.
    pub fn step<O>(&mut self, observer: &mut O) -> Result<StepInfo, McmcError>
    where
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        self.controller
            .before_step(&self.kernel, &self.current.state);
        let info = self.kernel.step(
            self.target,
            &mut self.current,
            &mut self.scratch,
            &mut self.rng,
            observer,
        );
        self.stats.record(&info);
        self.controller.after_step(&mut self.kernel, &info);
        if info.non_finite {
            let stage = info.stages_tried;
            let value = info.candidate_log_density[usize::from(stage.max(1)) - 1];
            return Err(if value.is_nan() || value == f64::INFINITY {
                McmcError::NonFiniteDensity { value, stage }
            } else {
                McmcError::NonFiniteHastings { stage }
            });
        }
        Ok(info)
    }

    /// Runs `n` steps, stopping at the first error.
    ///
    /// # Errors
    /// As [`Chain::step`].
    pub fn run<O>(&mut self, n: u64, observer: &mut O) -> Result<(), McmcError>
    where
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        for _ in 0..n {
            self.step(observer)?;
        }
        Ok(())
    }

    /// The current sample.
    pub fn current(&self) -> &SampleOf<T> {
        &self.current
    }

    /// The current state.
    pub fn state(&self) -> &T::State {
        &self.current.state
    }

    /// The kernel.
    pub fn kernel(&self) -> &K {
        &self.kernel
    }

    /// Mutable access to the kernel (e.g. to change a parameter between runs).
    pub fn kernel_mut(&mut self) -> &mut K {
        &mut self.kernel
    }

    /// The controller.
    pub fn controller(&self) -> &C {
        &self.controller
    }

    /// Mutable access to the controller.
    pub fn controller_mut(&mut self) -> &mut C {
        &mut self.controller
    }

    /// The kernel and the controller, both mutable (e.g. for a controller that tunes the
    /// kernel from statistics pooled over many chains).
    pub fn kernel_and_controller_mut(&mut self) -> (&mut K, &mut C) {
        (&mut self.kernel, &mut self.controller)
    }

    /// Acceptance statistics so far.
    pub fn stats(&self) -> &AcceptanceStats {
        &self.stats
    }

    /// The chain's RNG (e.g. to draw auxiliary numbers in the same stream).
    pub fn rng_mut(&mut self) -> &mut R {
        &mut self.rng
    }

    /// Consumes the chain, returning its current sample.
    pub fn into_current(self) -> SampleOf<T> {
        self.current
    }
}
