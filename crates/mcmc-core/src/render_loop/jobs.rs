//! Fixed work units of the render loop: chains grouped in jobs, run in rounds in parallel,
//! with the controllers' shared statistics pooled in job order between rounds.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::normalization::LargeStepSums;
use super::splat::{SplatObserver, SplatPayload, SplatSink};
use crate::chain::Chain;
use crate::controller::Controller;
use crate::controller::SharedController;
use crate::kernel::{Kernel, Observer};
use crate::progress::Progress;
use crate::target::Target;
use crate::ChainRng;

/// Mutations of a job between two checks of the cancel flag and the deadline (counted across
/// its chains and rounds, so that short synchronisation rounds do not read the clock once per
/// chain).
const POLL_EVERY: u64 = 64;

/// A chain of a job with its remaining mutations.
pub(crate) type JobChain<'t, T, K, C> = (Chain<'t, T, K, C, ChainRng>, u64);

/// One work unit: its chains (each with its remaining mutations) and its own sink.
pub(crate) struct Job<'t, T: Target, K, C, Sk> {
    pub(crate) chains: Vec<JobChain<'t, T, K, C>>,
    /// Per chain: the extra factor of its splats ([`super::ChainAllocation`]).
    pub(crate) weights: Vec<f64>,
    /// Per chain: the index of its target.
    pub(crate) targets: Vec<usize>,
    /// Per target: the job's large-step candidates ([`super::Normalization`]), counted by
    /// an owned job only.
    pub(crate) large_steps: Vec<LargeStepSums>,
    pub(crate) sink: Sk,
    pub(crate) dropped: u64,
    pub(crate) non_finite: u64,
    /// Another shard's job run only for the pooled statistics of coupled controllers
    /// ([`super::Shard`]): its chains step without splatting.
    pub(crate) muted: bool,
    /// Mutations since the job last polled its clocks (below [`POLL_EVERY`]).
    pub(crate) since_poll: u64,
}

impl<T: Target, K, C, Sk> Job<'_, T, K, C, Sk> {
    pub(crate) fn new(sink: Sk, targets: usize) -> Self {
        Self {
            chains: Vec::new(),
            weights: Vec::new(),
            targets: Vec::new(),
            large_steps: vec![LargeStepSums::default(); targets],
            sink,
            dropped: 0,
            non_finite: 0,
            muted: false,
            since_poll: 0,
        }
    }
}

/// How a job's round reports its chains' steps: the splat observer of an owned job (with
/// the per-chain weight and progress), or nothing for a muted one.
trait RoundObserver<S, P>: Observer<S, P> {
    /// Sets the extra factor of the following chain's splats.
    fn set_weight(&mut self, weight: f64);
    /// True if the steps count towards this process's progress.
    fn reports_progress(&self) -> bool;
}

impl<S, P: SplatPayload, K: SplatSink> RoundObserver<S, P> for SplatObserver<'_, K> {
    fn set_weight(&mut self, weight: f64) {
        SplatObserver::set_weight(self, weight);
    }
    fn reports_progress(&self) -> bool {
        true
    }
}

/// A muted job ([`super::Shard`]): the same steps, no splats, no progress (the shard that
/// owns the job reports them).
impl<S, P> RoundObserver<S, P> for () {
    fn set_weight(&mut self, _weight: f64) {}
    fn reports_progress(&self) -> bool {
        false
    }
}

/// The clocks a round polls: `cancelled` always, `late` (the deadline) except in the first
/// block of a job's first chain in the first round.
struct Stops<'a> {
    cancelled: &'a (dyn Fn() -> bool + Sync),
    late: &'a (dyn Fn() -> bool + Sync),
    first_round: bool,
}

/// Where a round counts its chains' large-step candidates: per chain its target, per target
/// the job's sums (`None`: not counted, a muted job).
struct Tally<'a> {
    targets: &'a [usize],
    sums: &'a mut [LargeStepSums],
}

/// One round of a job's chains (`round` mutations each, fewer if a chain's budget is
/// nearly used), polling `stops` every [`POLL_EVERY`] mutations of the job (`since_poll`
/// carries the count from round to round); returns the steps whose
/// candidate had a non-finite density. With a `tally`, every step whose candidate came from
/// an independent component ([`Kernel::independent_density`]) adds `f / q` to its target's
/// sums (in the job's fixed order of steps).
#[allow(clippy::too_many_arguments)]
fn step_round<T, K, C, O>(
    chains: &mut [JobChain<'_, T, K, C>],
    weights: &[f64],
    mut tally: Option<Tally<'_>>,
    round: u64,
    stops: &Stops<'_>,
    since_poll: &mut u64,
    observer: &mut O,
    progress: &dyn Progress,
) -> u64
where
    T: Target,
    K: Kernel<T>,
    C: Controller<K, T::State>,
    O: RoundObserver<T::State, T::Payload>,
{
    let mut non_finite = 0;
    'chains: for (i, ((chain, remaining), &weight)) in chains.iter_mut().zip(weights).enumerate() {
        observer.set_weight(weight);
        let mut left = round.min(*remaining);
        // The first block of a job's first chain in the first round ignores the deadline.
        let mut guaranteed = stops.first_round && i == 0;
        while left > 0 {
            if (*since_poll == 0 || guaranteed)
                && ((stops.cancelled)() || (!guaranteed && (stops.late)()))
            {
                break 'chains;
            }
            guaranteed = false;
            let n = left.min(POLL_EVERY - *since_poll);
            for _ in 0..n {
                match chain.step(observer) {
                    Ok(info) => {
                        if let Some(t) = tally.as_mut() {
                            if let Some(q) = chain.kernel().independent_density(info.component) {
                                // An invalid candidate lies outside the support: f = 0.
                                let f = info.candidate_log_density[0].exp();
                                t.sums[t.targets[i]].push(f / q);
                            }
                        }
                    }
                    Err(_) => non_finite += 1,
                }
            }
            left -= n;
            *remaining -= n;
            *since_poll = (*since_poll + n) % POLL_EVERY;
            if observer.reports_progress() {
                progress.advance(n);
            }
        }
    }
    non_finite
}

/// What the rounds ended with.
pub(crate) struct RoundsSummary<Sh> {
    pub(crate) cancelled: bool,
    pub(crate) shared: Sh,
    /// Wall-clock time of the first round (zero if no round ran).
    pub(crate) first_round: std::time::Duration,
}

/// Runs rounds of `round` mutations per chain until every chain's budget is used, the
/// deadline passes or `cancel` is set; pools the controllers' shared statistics after every
/// round, in job order. With `count_large_steps`, owned jobs count their chains' large-step
/// candidates ([`Job::large_steps`]).
///
/// A deadline that has already passed when the rounds start (the chains' set-up took the
/// budget) still lets the first chain of every job run its first [`POLL_EVERY`] mutations,
/// so that a time budget never ends with chains but no mutation (a black image); `cancel`
/// stops even those.
pub(crate) fn run_rounds<T, K, C, Sk>(
    jobs: &mut [Job<'_, T, K, C, Sk>],
    count_large_steps: bool,
    round: u64,
    deadline: Option<Instant>,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> RoundsSummary<C::Shared>
where
    T: Target,
    T::Payload: SplatPayload,
    K: Kernel<T> + Send,
    C: Controller<K, T::State> + SharedController<K> + Send,
    Sk: SplatSink,
{
    let mut pooled = C::Shared::default();
    let mut first_round = None;
    let cancelled = || cancel.load(Ordering::Relaxed);
    let late = || deadline.is_some_and(|t| Instant::now() >= t);
    let started = Instant::now();
    loop {
        let first = first_round.is_none();
        if cancelled()
            || (!first && late())
            || !jobs.iter().any(|j| j.chains.iter().any(|c| c.1 > 0))
        {
            break;
        }
        jobs.par_iter_mut().for_each(|job| {
            let Job {
                chains,
                weights,
                targets,
                large_steps,
                sink,
                dropped,
                non_finite,
                muted,
                since_poll,
            } = job;
            let stops = Stops {
                cancelled: &cancelled,
                late: &late,
                first_round: first,
            };
            if *muted {
                step_round(
                    chains,
                    weights,
                    None,
                    round,
                    &stops,
                    since_poll,
                    &mut (),
                    progress,
                );
                return;
            }
            let tally = count_large_steps.then_some(Tally {
                targets,
                sums: large_steps,
            });
            let mut observer = SplatObserver::new(sink);
            *non_finite += step_round(
                chains,
                weights,
                tally,
                round,
                &stops,
                since_poll,
                &mut observer,
                progress,
            );
            *dropped += observer.dropped;
        });
        for job in jobs.iter_mut() {
            for (chain, _) in &mut job.chains {
                let (kernel, controller) = chain.kernel_and_controller_mut();
                controller.contribute(kernel, &mut pooled);
            }
        }
        <C as SharedController<K>>::end_round(&mut pooled);
        for job in jobs.iter_mut() {
            for (chain, _) in &mut job.chains {
                let (kernel, controller) = chain.kernel_and_controller_mut();
                controller.receive(kernel, &pooled);
            }
        }
        first_round.get_or_insert_with(|| started.elapsed());
    }
    RoundsSummary {
        cancelled: cancel.load(Ordering::Relaxed),
        shared: pooled,
        first_round: first_round.unwrap_or_default(),
    }
}
