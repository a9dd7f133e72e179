//! The MCMC render driver shared by PSSMLT and MMLT: bootstrap, chain starts, many chains in
//! fixed jobs, expected-value splatting, automatic large-step control, budgets.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use mcmc_core::controller::{LargeStepEstimate, LargeStepStats, LargeStepTunable};
use mcmc_core::seed::{chain_seed, mix64};
use mcmc_core::stats::AcceptanceStats;
use mcmc_core::{Chain, Kernel, NoAdaptation, Target};
use pss::PssState;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use rayon::prelude::*;

use super::bootstrap::{bootstrap_key, Bootstrap};
use super::splat::{SplatBuffer, SplatObserver, SplatPayload};
use crate::image::Image;
use crate::session::Progress;

/// How the large-step probability is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LargeStepMode {
    /// A fixed probability in `[0, 1]`.
    Fixed(f64),
    /// Automatic control (Zsolnai & Szirmay-Kalos 2013): every chain first runs
    /// `estimation_steps` mutations (at most a tenth of its budget) with `initial`
    /// large-step probability; `eta_s`, `eta_l`, `eta_0` are pooled over all chains and `p_l`
    /// is set for the rest of the render (finite adaptation: the kernel is fixed afterwards).
    Auto {
        /// Large-step probability during the estimation phase.
        initial: f64,
        /// Mutations per chain in the estimation phase.
        estimation_steps: u64,
    },
}

/// Budget of an MCMC render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MltBudget {
    /// Mutations per pixel (deterministic output).
    MutationsPerPixel(f64),
    /// Wall-clock time (output depends on speed).
    Time(Duration),
}

/// Settings of the MCMC render driver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MltSettings {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// Number of Markov chains (default 256).
    pub chains: usize,
    /// Independent samples in the bootstrap (default 100 000, pbrt's value).
    pub bootstrap_samples: usize,
    /// Budget.
    pub budget: MltBudget,
    /// Large-step probability.
    pub large_step: LargeStepMode,
    /// Master seed.
    pub seed: u64,
    /// Number of PSS streams the target reads.
    pub streams: usize,
}

/// What an MCMC render produced.
#[derive(Clone, Debug)]
pub struct MltOutput {
    /// The image (black if nothing carried light).
    pub image: Image,
    /// The normalisation `b` from the bootstrap.
    pub b: f64,
    /// Mutations performed (all chains).
    pub mutations: u64,
    /// Acceptance statistics pooled over chains.
    pub stats: AcceptanceStats,
    /// The automatic large-step estimate, if automatic control ran.
    pub large_step: Option<LargeStepEstimate>,
    /// The large-step probability used after the estimation phase.
    pub final_large_step_probability: f64,
    /// Splats dropped (non-finite or outside the image).
    pub dropped: u64,
    /// Non-finite target values met by chains (rejected candidates).
    pub non_finite: u64,
    /// True if cancelled before the budget was used.
    pub cancelled: bool,
    /// A human-readable note (e.g. "no light-carrying path found").
    pub message: Option<String>,
}

/// Number of fixed work units; the image depends on it, not on the thread count.
const JOBS: usize = 32;

struct Job<'t, T: Target, K> {
    chains: Vec<(Chain<'t, T, K, NoAdaptation, Pcg64>, u64)>,
    buffer: SplatBuffer,
    dropped: u64,
    large: LargeStepStats,
    non_finite: u64,
}

/// Runs an MCMC render over one or more targets (PSSMLT: one; MMLT: one per path depth).
///
/// The bootstrap draws `bootstrap_samples` independent samples of every target; `b` is the
/// summed mean. Chain starts are resampled from all of them in proportion to their value, so
/// there is no start-up bias (pbrt-v3/v4 scheme); a chain keeps the target (depth) of its start.
/// Chains are split into 32 fixed jobs, each with its own image buffer, merged in job order:
/// the same seed gives the same image with any thread count (under a mutation budget).
///
/// Pixel estimate: `I_j = (b W H / N) sum_i sum_splats w_i rgb / f(u_i)` with `N` the total
/// number of mutations (PSSMLT, Kelemen et al. 2002, eq. 5 with expected values).
pub fn render_mlt<T, K>(
    targets: &[T],
    make_kernel: impl Fn(f64) -> K + Sync,
    settings: &MltSettings,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> MltOutput
where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
    K: Kernel<T> + LargeStepTunable + Send,
{
    let (w, h) = (settings.width, settings.height);
    let pixels = (w * h) as f64;
    let n_targets = targets.len().max(1);
    let total_mutations = match settings.budget {
        MltBudget::MutationsPerPixel(m) => Some((m * pixels).round().max(1.0) as u64),
        MltBudget::Time(_) => None,
    };
    progress.set_total(
        settings.bootstrap_samples as u64 * n_targets as u64 + total_mutations.unwrap_or(0),
    );

    // Bootstrap: sample i of target d has key bootstrap_key(seed, i * D + d).
    let mut weights = vec![0.0; settings.bootstrap_samples * n_targets];
    let mut b = 0.0;
    for (d, target) in targets.iter().enumerate() {
        let seed_d = mix64(settings.seed ^ (d as u64).wrapping_mul(0x51_7cc1_b727_220a));
        let bs = Bootstrap::run(target, settings.streams, settings.bootstrap_samples, seed_d);
        b += bs.b;
        for (i, wgt) in bs.weights.iter().enumerate() {
            weights[i * n_targets + d] = *wgt;
        }
        progress.advance(settings.bootstrap_samples as u64);
    }
    let all = Bootstrap { weights, b };
    let black = |message: String| MltOutput {
        image: Image::new(w, h),
        b: 0.0,
        mutations: 0,
        stats: AcceptanceStats::default(),
        large_step: None,
        final_large_step_probability: 0.0,
        dropped: 0,
        non_finite: 0,
        cancelled: false,
        message: Some(message),
    };
    if all.found_nothing() || targets.is_empty() {
        return black(format!(
            "the bootstrap's {} independent samples found no light-carrying path: the image is black \
             (is there an emitter visible to the camera through the scene?)",
            settings.bootstrap_samples * n_targets
        ));
    }
    let n_chains = settings.chains.max(1);
    let u = (mix64(settings.seed ^ 0x5e1f_c4a1) >> 11) as f64 / (1u64 << 53) as f64;
    let starts = all.resample(n_chains, u);

    let initial_p = match settings.large_step {
        LargeStepMode::Fixed(p) => p,
        LargeStepMode::Auto { initial, .. } => initial,
    };
    let steps_for = |c: usize| -> u64 {
        match total_mutations {
            Some(n) => n / n_chains as u64 + u64::from((c as u64) < n % n_chains as u64),
            None => u64::MAX,
        }
    };
    let mut jobs: Vec<Job<'_, T, K>> = (0..JOBS.min(n_chains))
        .map(|j| {
            let lo = j * n_chains / JOBS.min(n_chains);
            let hi = (j + 1) * n_chains / JOBS.min(n_chains);
            let chains = (lo..hi)
                .filter_map(|c| {
                    let entry = starts[c];
                    let (i, d) = (entry / n_targets, entry % n_targets);
                    let seed_d =
                        mix64(settings.seed ^ (d as u64).wrapping_mul(0x51_7cc1_b727_220a));
                    let state = PssState::new(settings.streams, bootstrap_key(seed_d, i as u64));
                    let rng = Pcg64::seed_from_u64(chain_seed(settings.seed, c as u64));
                    Chain::new(
                        &targets[d],
                        make_kernel(initial_p),
                        NoAdaptation,
                        rng,
                        state,
                    )
                    .ok()
                    .map(|chain| (chain, steps_for(c)))
                })
                .collect();
            Job {
                chains,
                buffer: SplatBuffer::new(w, h),
                dropped: 0,
                large: LargeStepStats::default(),
                non_finite: 0,
            }
        })
        .collect();

    let start = Instant::now();
    let deadline = match settings.budget {
        MltBudget::Time(t) => Some(start + t),
        MltBudget::MutationsPerPixel(_) => None,
    };
    let mut estimate = None;
    let mut p_final = initial_p;
    let mut cancelled = false;

    // Phase 1 (automatic large-step control): estimation steps on every chain.
    if let LargeStepMode::Auto {
        estimation_steps, ..
    } = settings.large_step
    {
        run_round(&mut jobs, estimation_steps, true, progress, cancel);
        let mut pooled = LargeStepStats::default();
        for job in &jobs {
            pooled.merge(&job.large);
        }
        let e = pooled.estimate();
        p_final = e.large_step_probability;
        estimate = Some(e);
        for job in &mut jobs {
            for (chain, _) in &mut job.chains {
                chain.kernel_mut().set_large_step_probability(p_final);
            }
        }
        cancelled = cancel.load(Ordering::Relaxed);
    }
    // Phase 2: the rest of the budget, in rounds so that time and cancellation are checked.
    let round = match deadline {
        Some(_) => 2_000,
        None => 20_000,
    };
    while !cancelled {
        if !jobs.iter().any(|j| j.chains.iter().any(|c| c.1 > 0)) {
            break;
        }
        run_round(&mut jobs, round, false, progress, cancel);
        cancelled = cancel.load(Ordering::Relaxed);
        if deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
    }

    let mut buffer = SplatBuffer::new(w, h);
    let mut stats = AcceptanceStats::default();
    let (mut dropped, mut non_finite) = (0, 0);
    for job in &jobs {
        buffer.merge(&job.buffer);
        dropped += job.dropped;
        non_finite += job.non_finite;
        for (chain, _) in &job.chains {
            stats.merge(chain.stats());
        }
    }
    let mutations = stats.steps;
    let scale = if mutations == 0 {
        0.0
    } else {
        b * pixels / mutations as f64
    };
    MltOutput {
        image: buffer.to_image(scale),
        b,
        mutations,
        stats,
        large_step: estimate,
        final_large_step_probability: p_final,
        dropped,
        non_finite,
        cancelled,
        message: None,
    }
}

/// Runs up to `steps` mutations on every chain (bounded by each chain's remaining budget).
fn run_round<T, K>(
    jobs: &mut [Job<'_, T, K>],
    steps: u64,
    record_large: bool,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) where
    T: Target<State = PssState>,
    T::Payload: SplatPayload,
    K: Kernel<T> + LargeStepTunable + Send,
{
    jobs.par_iter_mut().for_each(|job| {
        let Job {
            chains,
            buffer,
            dropped,
            large,
            non_finite,
        } = job;
        let mut observer = SplatObserver { buffer, dropped: 0 };
        for (chain, remaining) in chains.iter_mut() {
            if cancel.load(Ordering::Relaxed) {
                break;
            }
            let n = steps.min(*remaining);
            for _ in 0..n {
                match chain.step(&mut observer) {
                    Ok(info) => {
                        if record_large {
                            large.record(&info, chain.kernel().is_large_step(info.component));
                        }
                    }
                    Err(_) => *non_finite += 1,
                }
            }
            *remaining -= n;
            progress.advance(n);
        }
        *dropped += observer.dropped;
    });
}
