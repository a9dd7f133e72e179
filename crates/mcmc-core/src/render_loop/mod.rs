//! The generic MCMC render loop: bootstrap, chain starts, many chains in fixed jobs, rounds
//! with shared statistics, budgets, cancellation, progress, expected-value splatting into the
//! caller's sink.
//!
//! Everything an MCMC renderer needs besides its path sampler lives here, generic over the
//! state type: primary sample space (`pss::FreshPss`), path space, or a renderer's own.
//!
//! 1. **Bootstrap** (pbrt-v3/v4's scheme): `bootstrap_samples` independent states per target,
//!    drawn through [`IndependentStates`] from keys; `b` = the sum over targets of the mean
//!    weight, with its standard error. Memory does not grow with the sample count (chunk sums;
//!    see [`bootstrap_key`]).
//! 2. **Chain starts** by systematic resampling in proportion to the weights, so chains start
//!    in the stationary distribution (no start-up bias, no burn-in). A chain keeps the target
//!    of its start (MMLT: one target per path depth). Over all targets jointly (pbrt), or
//!    with a fixed number of chains per target ([`ChainAllocation`]); a target's bootstrap
//!    may be stratified ([`IndependentStates::strata`]).
//! 3. **Chains in fixed jobs**, each job with its own sink, merged in job order; per-chain RNGs
//!    seeded from (seed, chain index): under a mutation budget the image is bit-identical for
//!    any thread count. A sink may also be a handle to one shared [`ExactSplatGrid`], whose
//!    sums do not depend on the order of the splats: one image of memory for every job.
//! 4. **Rounds**: every chain runs `round_mutations` steps, then the controllers' shared
//!    statistics are pooled in job order and handed back ([`SharedController`]). Time budget,
//!    cancellation and progress are checked inside rounds, so a cancel takes effect within a
//!    fraction of a second and the partial image is a correct estimate of the mutations done.
//!
//! 5. **Normalisation** after the chains ([`Normalization`]): by default the bootstrap's
//!    samples pooled with every large-step candidate of the chains, so the brightness error
//!    falls with the chains' time; or the bootstrap alone, or a caller's `b`
//!    ([`NormalizationMode`]).
//!
//! The pixel estimate is `I_j = (b / N) sum_i sum_splats w_i rgb / f(x_i)` per unit of the
//! sink's measure (Kelemen et al. 2002, eq. 5, with expected values): multiply the sink by
//! [`LoopOutput::splat_scale`] `= b / N` and by the inverse of the pixel's measure (for
//! primary sample space mapped onto a `W x H` image: `W * H`).

mod bootstrap;
mod exact_grid;
mod jobs;
mod large_step_mis;
mod normalization;
mod notes;
mod resample;
mod settings;
mod splat;

/// The shared-statistics controller interface, re-exported from [`crate::controller`] where
/// it lives.
pub use crate::controller::{Both, SharedController};
use bootstrap::TimeCap;
pub use bootstrap::{bootstrap_key, ChainAllocation, IndependentStates};
pub use exact_grid::{ExactSplatGrid, DEFAULT_FRACTION_BITS, EXACT_GRID_BYTES_PER_PIXEL};
#[cfg(feature = "testing")]
pub(crate) use large_step_mis::mis_step;
pub use large_step_mis::LargeStepMis;
pub use normalization::{LargeStepSums, Normalization, NormalizationEstimate, NormalizationMode};
use notes::{few_hits_note, missed_targets_note};
pub use settings::{
    LoopBudget, LoopSettings, Shard, MAX_BOOTSTRAP_SAMPLES, MAX_CHAINS, MIN_TIME_MUTATIONS,
};
pub use splat::{Splat, SplatGrid, SplatObserver, SplatPayload, SplatSink};

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rand::SeedableRng;

use crate::chain::Chain;
use crate::controller::Controller;
use crate::kernel::Kernel;
use crate::progress::Progress;
use crate::seed::chain_seed;
use crate::stats::AcceptanceStats;
use crate::target::Target;
use crate::{ChainRng, McmcError};

/// Samples with light a target's bootstrap should have before its `b_d`, and the standard
/// error of `b`, are trusted: a target with light that got fewer (and at least a hundredth of
/// `b`) gets a note, since rarely sampled light may as well have been missed entirely.
pub const FEW_BOOTSTRAP_HITS: u64 = 30;

/// Chain starts between two checks of the cancel flag and the deadline while the chains are
/// set up.
const SETUP_POLL: usize = 256;

/// Which chain a kernel or controller is made for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainSlot {
    /// Chain index (0-based, fixed for a seed).
    pub chain: usize,
    /// Index of the target the chain samples (its start's target).
    pub target: usize,
    /// The bootstrap estimate `b_d` of the integral of that target (MMLT: of its depth).
    pub target_b: f64,
    /// [`LoopSettings::large_step_mis`]: the kernel should splat with the large-step MIS
    /// estimator ([`LargeStepMis::for_slot`]).
    pub large_step_mis: bool,
}

/// What a render loop produced.
#[derive(Clone, Debug)]
pub struct LoopOutput<K, Sh> {
    /// The job sinks merged in job order. Multiply by [`LoopOutput::splat_scale`].
    pub sink: K,
    /// `b / mutations`: the factor that turns the sink's accumulated `w rgb / f` into the
    /// estimate per unit of the sink's measure (0 when nothing ran).
    pub splat_scale: f64,
    /// The normalisation `b` the image is scaled with, the integral of the target (summed
    /// over targets): [`Normalization::estimate`] of [`LoopOutput::normalization`].
    pub b: f64,
    /// Standard error of `b` (0 for a given `b`).
    pub b_standard_error: f64,
    /// The bootstrap's estimate of `b` (or the sum of a per-target normalisation given to
    /// [`RenderLoop::run_normalized`]).
    pub bootstrap_b: f64,
    /// The bootstrap's standard error of its estimate.
    pub bootstrap_standard_error: f64,
    /// Large-step candidates pooled into `b` ([`NormalizationMode::Pooled`]).
    pub large_step_samples: u64,
    /// What `b` rests on (a sharded render's part carries it: [`Normalization::add`]).
    pub normalization: Normalization,
    /// The bootstrap estimate `b_d` of each target's integral (they sum to `bootstrap_b`;
    /// the chains' allocation and per-target splat weights use them).
    pub target_b: Vec<f64>,
    /// Chains started per target (their starts; chains whose start failed to re-evaluate
    /// are included).
    pub target_chains: Vec<usize>,
    /// Bootstrap samples with positive weight per target (how well each `b_d` is known:
    /// see [`FEW_BOOTSTRAP_HITS`]).
    pub target_hits: Vec<u64>,
    /// Bootstrap samples evaluated (over all targets).
    pub bootstrap_samples: u64,
    /// Chains that ran.
    pub chains: usize,
    /// Mutations performed (all chains).
    pub mutations: u64,
    /// Acceptance statistics pooled over chains.
    pub stats: AcceptanceStats,
    /// The controllers' shared statistics at the end (pooled over all chains).
    pub shared: Sh,
    /// Splats the sinks dropped (non-finite or outside the image).
    pub dropped_splats: u64,
    /// Candidates with a non-finite density or Hastings term (rejected; a target bug).
    pub non_finite: u64,
    /// True if cancelled before the budget was used.
    pub cancelled: bool,
    /// True if no bootstrap sample had positive weight: nothing carries light, the sink is
    /// empty (see `notes`).
    pub found_nothing: bool,
    /// Human-readable notes (warnings, early stops, why the image is black).
    pub notes: Vec<String>,
    /// Wall-clock time of the bootstrap (independent samples, chain starts).
    pub bootstrap_time: std::time::Duration,
    /// Wall-clock time of the chains (all rounds).
    pub chains_time: std::time::Duration,
    /// Wall-clock time of the first round: with a controller that estimates in its first
    /// round (automatic large-step control), the estimation phase.
    pub first_round_time: std::time::Duration,
}

/// A render loop over a set of targets: what to sample (`targets`, one per chain family), how
/// to draw independent states (`states`), and factories for each chain's kernel and
/// controller and for each job's sink.
///
/// # Example
/// ```
/// use std::sync::atomic::AtomicBool;
/// use mcmc_core::render_loop::{
///     IndependentStates, LoopBudget, LoopSettings, RenderLoop, Splat, SplatGrid,
/// };
/// use mcmc_core::{GaussianRandomWalk, Mh, NoAdaptation, NoProgress, Target};
///
/// /// f(u) = 1 + u0 on the unit square, splatted at (u0, u1) on a 4 x 1 image.
/// struct Ramp;
/// impl Target for Ramp {
///     type State = Vec<f64>;
///     type Payload = Option<Splat>;
///     fn evaluate(&self, u: &mut Vec<f64>, out: &mut Option<Splat>) -> f64 {
///         if !u.iter().all(|v| (0.0..1.0).contains(v)) {
///             *out = None;
///             return f64::NEG_INFINITY;
///         }
///         let f = 1.0 + u[0];
///         *out = Some(Splat { raster: [4.0 * u[0] as f32, 0.5], rgb: [f as f32; 3] });
///         f.ln()
///     }
/// }
/// struct Uniform;
/// impl IndependentStates<Vec<f64>> for Uniform {
///     fn empty(&self) -> Vec<f64> { vec![0.0; 2] }
///     fn independent(&self, key: u64, u: &mut Vec<f64>) {
///         let h = |k: u64| (mcmc_core::seed::mix64(k) >> 11) as f64 / (1u64 << 53) as f64;
///         u.clear();
///         u.extend([h(key), h(key ^ 7)]);
///     }
/// }
/// let settings = LoopSettings {
///     chains: 8,
///     bootstrap_samples: 1000,
///     budget: LoopBudget::Mutations(20_000),
///     ..LoopSettings::default()
/// };
/// let out = RenderLoop {
///     targets: &[Ramp],
///     states: &Uniform,
///     kernel: |_| Mh::new(GaussianRandomWalk::new(0.2).unwrap()),
///     controller: |_| NoAdaptation,
///     sink: || SplatGrid::new(4, 1),
/// }
/// .run(&settings, &NoProgress, &AtomicBool::new(false))
/// .unwrap();
/// // Pixel x covers u0 in [x/4, (x+1)/4): its value is 4 * integral of (1 + u0) there.
/// let px0 = out.sink.get(0, 0)[0] * out.splat_scale * 4.0;
/// assert!((px0 - 1.125).abs() < 0.1, "{px0}");
/// ```
pub struct RenderLoop<'a, T, Src: ?Sized, FK, FC, FS> {
    /// The targets (PSSMLT: one; MMLT: one per path depth).
    pub targets: &'a [T],
    /// Independent states for the bootstrap and chain starts.
    pub states: &'a Src,
    /// Makes the kernel of a chain.
    pub kernel: FK,
    /// Makes the controller of a chain.
    pub controller: FC,
    /// Makes an empty sink (one per job, plus the merged result).
    pub sink: FS,
}

impl<T, Src, K, C, FK, FC, Sk, FS> RenderLoop<'_, T, Src, FK, FC, FS>
where
    T: Target,
    T::Payload: SplatPayload,
    Src: IndependentStates<T::State> + ?Sized,
    K: Kernel<T> + Send,
    C: Controller<K, T::State> + SharedController<K> + Send,
    FK: Fn(ChainSlot) -> K + Sync,
    FC: Fn(ChainSlot) -> C + Sync,
    Sk: SplatSink,
    FS: Fn() -> Sk + Sync,
{
    /// Runs the loop on the current rayon pool (install it in a pool of your size).
    ///
    /// Progress is reported in bootstrap samples plus mutations. `cancel` is polled during the
    /// bootstrap (between batches of 8192 samples) and every 64 mutations; a cancelled run
    /// returns what it has, with `cancelled: true`.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] for settings out of range or an empty target list.
    pub fn run(
        &self,
        settings: &LoopSettings,
        progress: &dyn Progress,
        cancel: &AtomicBool,
    ) -> Result<LoopOutput<Sk, C::Shared>, McmcError> {
        self.run_inner(settings, None, progress, cancel)
    }

    /// As [`RenderLoop::run`], with each target's integral `b_d` given by the caller
    /// (`normalization[d]`, e.g. a cheaper or lower-variance independent estimate: MMLT's
    /// depths from all-strategy BDPT samples) instead of the bootstrap's: the chains are
    /// allocated per target ([`ChainAllocation::PerTarget`], whatever
    /// `settings.chain_allocation` says) in proportion to `normalization`, each target's
    /// splats scaled by `normalization[d] / n_d`; the bootstrap only picks the starts (a
    /// target whose bootstrap found nothing gets no chain, with a note). `LoopOutput::b` and
    /// `target_b` report `normalization`.
    ///
    /// # Notes
    /// Consistent, not exactly unbiased for finite runs: with `b_d` independent of the
    /// chains, `E[image] = sum_d b_d E[H_d]`, where `H_d`, the chains' normalised splat
    /// histogram, carries the start bias of importance resampling (`O(1 / bootstrap
    /// samples)`, decaying with the chain length). [`RenderLoop::run`] is exact because its
    /// `b_d` and its starts come from the same samples (Hachisuka et al. 2014, section 4).
    ///
    /// # Errors
    /// As [`RenderLoop::run`]; also [`McmcError::InvalidParameter`] if `normalization` has
    /// not one finite non-negative value per target.
    pub fn run_normalized(
        &self,
        settings: &LoopSettings,
        normalization: &[f64],
        progress: &dyn Progress,
        cancel: &AtomicBool,
    ) -> Result<LoopOutput<Sk, C::Shared>, McmcError> {
        if normalization.len() != self.targets.len()
            || !normalization.iter().all(|b| b.is_finite() && *b >= 0.0)
        {
            return Err(McmcError::InvalidParameter {
                name: "normalization",
                value: normalization.len() as f64,
                allowed: "one finite non-negative value per target",
            });
        }
        let settings = LoopSettings {
            chain_allocation: ChainAllocation::PerTarget,
            ..*settings
        };
        self.run_inner(&settings, Some(normalization), progress, cancel)
    }

    fn run_inner(
        &self,
        settings: &LoopSettings,
        normalization: Option<&[f64]>,
        progress: &dyn Progress,
        cancel: &AtomicBool,
    ) -> Result<LoopOutput<Sk, C::Shared>, McmcError> {
        settings.validate()?;
        if self.targets.is_empty() {
            return Err(McmcError::InvalidParameter {
                name: "targets",
                value: 0.0,
                allowed: "at least one target",
            });
        }
        let start = Instant::now();
        let deadline = match settings.budget {
            LoopBudget::Time(t) => Some(start + t),
            LoopBudget::Mutations(_) => None,
        };
        let mut notes = Vec::new();
        let mut chains = settings.chains;
        if let LoopBudget::Mutations(n) = settings.budget {
            if (chains as u64) > n {
                notes.push(format!(
                    "{chains} chains requested for {n} mutations: using {n} chains (each needs at least one mutation)"
                ));
                chains = n as usize;
            }
        }
        let targets_count = self.targets.len() as u64;
        let bootstrap_total = settings.bootstrap_samples.saturating_mul(targets_count);
        progress.set_total(match settings.budget {
            LoopBudget::Mutations(n) => bootstrap_total.saturating_add(n),
            LoopBudget::Time(_) => bootstrap_total,
        });
        let bootstrap_deadline = match settings.budget {
            LoopBudget::Time(t) => Some(start + t.mul_f64(settings.bootstrap_time_share)),
            LoopBudget::Mutations(_) => None,
        };
        // A stratified target counts whole groups only: a time-limited bootstrap takes at
        // least one group of every target, or that target's `b_d` would be 0.
        let min_rows = (0..self.targets.len())
            .map(|t| self.states.strata(t).max(1))
            .max()
            .unwrap_or(1)
            .min(settings.bootstrap_samples);
        let min_chain_mutations = settings.min_time_mutations.max(settings.round_mutations);
        let boot = bootstrap::run(
            self.targets,
            self.states,
            &bootstrap::BootstrapPlan {
                per_target: settings.bootstrap_samples,
                chains,
                seed: settings.seed,
                allocation: settings.chain_allocation,
                allocation_b: normalization,
                deadline: bootstrap_deadline,
                min_rows,
                time_cap: deadline.map(|deadline| TimeCap {
                    deadline,
                    min_mutations: min_chain_mutations,
                }),
                progress,
                cancel,
            },
        );
        if boot.stopped_early {
            notes.push(format!(
                "the bootstrap stopped after {} of {} samples ({} per target) to stay within {:.0}% of the time budget",
                boot.evaluated,
                bootstrap_total,
                boot.evaluated / targets_count,
                settings.bootstrap_time_share * 100.0
            ));
        }
        if normalization.is_none() {
            notes.extend(few_hits_note(&boot.target_b, &boot.target_hits, boot.b));
        }
        if let Some(capped) = boot.time_capped {
            notes.push(format!(
                "{chains} chains requested: using {capped}, what the time left after the bootstrap affords at its rate ({:.0} samples/s) with at least {min_chain_mutations} mutations per chain",
                boot.evaluated as f64 / start.elapsed().as_secs_f64().max(1e-9)
            ));
        }
        let mut boot = boot;
        let mut normalization_note = None;
        if let Some(nb) = normalization {
            normalization_note = Some(format!(
                "normalisation given per target (sum {:.6}); the bootstrap's estimate was {:.6}",
                nb.iter().sum::<f64>(),
                boot.b
            ));
            boot.target_b = nb.to_vec();
            boot.b = nb.iter().sum();
        }
        let n_jobs = settings.jobs.min(boot.starts.len().max(1));
        let mode = match (settings.normalization, normalization) {
            (NormalizationMode::Given(b), _) => NormalizationMode::Given(b),
            (_, Some(nb)) => NormalizationMode::Given(nb.iter().sum()),
            (mode, None) => mode,
        };
        let mut norm = Normalization::new(
            mode,
            boot.target_b.clone(),
            boot.target_variance.clone(),
            boot.target_samples.clone(),
            boot.standard_error,
            n_jobs,
        );
        if let NormalizationMode::Given(b) = settings.normalization {
            notes.push(format!(
                "normalisation given: b = {b:.6} (the bootstrap's estimate was {:.6} +- {:.6})",
                boot.b, boot.standard_error
            ));
        }
        let first = norm.estimate();
        let mut out = LoopOutput {
            sink: (self.sink)(),
            splat_scale: 0.0,
            b: first.b,
            b_standard_error: first.standard_error,
            bootstrap_b: boot.b,
            bootstrap_standard_error: boot.standard_error,
            large_step_samples: 0,
            normalization: norm.clone(),
            target_b: boot.target_b.clone(),
            target_chains: boot.target_chains.clone(),
            target_hits: boot.target_hits.clone(),
            bootstrap_samples: boot.evaluated,
            chains: 0,
            mutations: 0,
            stats: AcceptanceStats::default(),
            shared: C::Shared::default(),
            dropped_splats: 0,
            non_finite: 0,
            cancelled: boot.cancelled,
            found_nothing: false,
            notes,
            bootstrap_time: start.elapsed(),
            chains_time: std::time::Duration::ZERO,
            first_round_time: std::time::Duration::ZERO,
        };
        out.notes.extend(normalization_note);
        if boot.cancelled {
            out.notes.push(
                "cancelled during the bootstrap, before any chain ran: the chains' image is black"
                    .to_owned(),
            );
            return Ok(out);
        }
        if boot.starts.is_empty() {
            out.found_nothing = true;
            out.notes.push(format!(
                "the bootstrap's {} independent samples found nothing with positive weight (no light-carrying path): the image is black",
                boot.evaluated
            ));
            return Ok(out);
        }
        // The chains that were resampled (fewer than requested if the time budget capped them).
        let chains = boot.starts.len();

        // Chains, split into fixed jobs.
        let per_chain = |c: usize| -> u64 {
            match settings.budget {
                LoopBudget::Mutations(n) => {
                    n / chains as u64 + u64::from((c as u64) < n % chains as u64)
                }
                LoopBudget::Time(_) => u64::MAX,
            }
        };
        // The extra splat factor of a chain of each target: 1 for the joint allocation, whose
        // image is `b / N` times the splat sums; `(b_d / n_d) / (b / C)` per target
        // (ChainAllocation::PerTarget), so that the same `b / N` makes it `b_d / (n_d m)`.
        let target_weight: Vec<f64> = match settings.chain_allocation {
            ChainAllocation::Joint => vec![1.0; self.targets.len()],
            #[cfg(feature = "testing")]
            ChainAllocation::PerTargetWithJointScale => vec![1.0; self.targets.len()],
            ChainAllocation::PerTarget => {
                let per_chain_b = boot.b / boot.starts.len() as f64;
                boot.target_b
                    .iter()
                    .zip(&boot.target_chains)
                    .map(|(&b_d, &n_d)| {
                        if n_d == 0 {
                            0.0
                        } else {
                            b_d / n_d as f64 / per_chain_b
                        }
                    })
                    .collect()
            }
        };
        out.notes.extend(missed_targets_note(
            &boot.target_b,
            &boot.target_chains,
            settings.chain_allocation,
        ));
        let mut skipped = 0usize;
        let shard = settings.shard;
        let mut setup_stopped = None;
        let mut job_list: Vec<jobs::Job<'_, T, K, C, Sk>> = Vec::with_capacity(n_jobs);
        // The index of each listed job in the fixed job list (a shard lists only its own).
        let mut job_index: Vec<usize> = Vec::with_capacity(n_jobs);
        'jobs: for j in 0..n_jobs {
            if !(shard.owns(j, n_jobs) || C::COUPLES_CHAINS) {
                continue;
            }
            let (lo, hi) = (j * chains / n_jobs, (j + 1) * chains / n_jobs);
            let mut job = jobs::Job::new((self.sink)(), self.targets.len());
            job.muted = !shard.owns(j, n_jobs);
            for c in lo..hi {
                if c % SETUP_POLL == 0 && c > 0 {
                    if cancel.load(Ordering::Relaxed) {
                        setup_stopped = Some((c, "cancelled"));
                    } else if deadline.is_some_and(|t| Instant::now() >= t) {
                        setup_stopped = Some((c, "the time budget ran out"));
                    }
                    if setup_stopped.is_some() {
                        job_list.push(job);
                        job_index.push(j);
                        break 'jobs;
                    }
                }
                let (target, index) = boot.starts[c];
                let slot = ChainSlot {
                    chain: c,
                    target,
                    target_b: boot.target_b[target],
                    large_step_mis: settings.large_step_mis,
                };
                let mut state = self.states.empty();
                bootstrap::draw(self.states, settings.seed, target, index, &mut state);
                let rng = ChainRng::seed_from_u64(chain_seed(settings.seed, c as u64));
                match Chain::new(
                    &self.targets[target],
                    (self.kernel)(slot),
                    (self.controller)(slot),
                    rng,
                    state,
                ) {
                    Ok(chain) => {
                        job.chains.push((chain, per_chain(c)));
                        job.weights.push(target_weight[target]);
                        job.targets.push(target);
                    }
                    Err(_) => skipped += 1,
                }
            }
            job_list.push(job);
            job_index.push(j);
        }
        if let Some((started, why)) = setup_stopped {
            out.notes.push(format!(
                "{why} while the chains were being started: {started} of {chains} chains run"
            ));
        }
        if skipped > 0 {
            out.notes.push(format!(
                "{skipped} chain starts re-evaluated to zero or non-finite density and were skipped (a target that is not a deterministic function of its state?)"
            ));
        }
        let chains_start = Instant::now();
        let summary = jobs::run_rounds(
            &mut job_list,
            matches!(norm.mode, NormalizationMode::Pooled),
            settings.round_mutations,
            deadline,
            progress,
            cancel,
        );
        out.cancelled = summary.cancelled;
        out.shared = summary.shared;
        out.chains_time = chains_start.elapsed();
        out.first_round_time = summary.first_round;
        for (j, job) in job_list.iter().enumerate().filter(|(_, j)| !j.muted) {
            out.sink.merge(&job.sink);
            norm.job_mut(job_index[j]).copy_from_slice(&job.large_steps);
            out.dropped_splats += job.dropped;
            out.non_finite += job.non_finite;
            for (chain, _) in &job.chains {
                out.stats.merge(chain.stats());
            }
            out.chains += job.chains.len();
        }
        out.mutations = out.stats.steps;
        let estimate = norm.estimate();
        out.b = estimate.b;
        out.b_standard_error = estimate.standard_error;
        out.large_step_samples = estimate.large_steps;
        out.normalization = norm;
        out.splat_scale = if out.mutations == 0 {
            0.0
        } else {
            estimate.b / out.mutations as f64
        };
        if out.mutations == 0 {
            out.notes.push(
                if out.cancelled {
                    "cancelled before the chains' first mutation: the chains' image is black"
                } else {
                    "no chain ran a mutation: the chains' image is black"
                }
                .to_owned(),
            );
        }
        Ok(out)
    }
}
