//! The bootstrap of a render loop: estimate the normalisation `b` from independent samples and
//! pick chain starts by systematic resampling, in memory that does not grow with the sample
//! count.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use crate::progress::Progress;
use crate::seed::{chain_seed, mix64};
use crate::target::Target;

/// The source of independent states of a render loop: "the i-th independent state from a key,
/// and its bootstrap weight". Primary sample space implements it with fresh uniform points
/// (`pss::FreshPss`); path space with independently sampled paths.
///
/// # Example
/// ```
/// use mcmc_core::render_loop::IndependentStates;
///
/// /// Independent uniform points of [0, 1)^2, drawn from the key by a hash.
/// struct Uniform2;
/// impl IndependentStates<Vec<f64>> for Uniform2 {
///     fn empty(&self) -> Vec<f64> { vec![0.0; 2] }
///     fn independent(&self, key: u64, state: &mut Vec<f64>) {
///         let h = |k: u64| (mcmc_core::seed::mix64(k) >> 11) as f64 / (1u64 << 53) as f64;
///         state.clear();
///         state.extend([h(key), h(key ^ 1)]);
///     }
/// }
/// ```
pub trait IndependentStates<S>: Sync {
    /// A state buffer that [`IndependentStates::independent`] may overwrite.
    fn empty(&self) -> S;

    /// Writes the independent state drawn with `key` into `state` (reusing its buffers). The
    /// same key must give the same state: the loop re-creates chain starts from their keys
    /// instead of storing bootstrap states.
    fn independent(&self, key: u64, state: &mut S);

    /// The bootstrap weight of an independent state whose target log density is
    /// `log_density`: an unbiased estimate of `b`, the integral of the target, i.e.
    /// `f(x) / p(x)` with `p` the density the state was drawn from. The default,
    /// `exp(log_density)`, is right for uniform points of the unit hypercube (primary sample
    /// space, `p = 1`).
    fn weight(&self, state: &S, log_density: f64) -> f64 {
        let _ = state;
        log_density.exp()
    }
}

/// The key of bootstrap sample `index` of target `target` under master seed `seed`:
/// `IndependentStates::independent(bootstrap_key(..))` re-creates the sample exactly.
#[must_use]
pub fn bootstrap_key(seed: u64, target: usize, index: u64) -> u64 {
    let per_target = mix64(seed ^ 0xb007_5724_7000_0001 ^ mix64(target as u64 ^ 0x51_7cc1_b727));
    chain_seed(per_target, index)
}

/// Maximum number of chunk sums kept by the bootstrap (128 KiB of memory).
const MAX_CHUNKS: usize = 1 << 14;

/// Samples evaluated per parallel batch (rounded to whole rows of all targets).
const BATCH: u64 = 8192;

/// Sums of a stream of weights over chunks of `chunk` consecutive samples; when the chunk
/// count reaches [`MAX_CHUNKS`], neighbouring chunks are merged and the chunk size doubles, so
/// memory stays bounded whatever the number of samples.
#[derive(Clone, Debug)]
struct ChunkSums {
    chunk: u64,
    sums: Vec<f64>,
    open: f64,
    in_open: u64,
}

impl ChunkSums {
    fn new() -> Self {
        Self {
            chunk: 1,
            sums: Vec::new(),
            open: 0.0,
            in_open: 0,
        }
    }

    fn push(&mut self, w: f64) {
        self.open += w;
        self.in_open += 1;
        if self.in_open == self.chunk {
            self.sums.push(self.open);
            self.open = 0.0;
            self.in_open = 0;
            if self.sums.len() == MAX_CHUNKS {
                for j in 0..MAX_CHUNKS / 2 {
                    self.sums[j] = self.sums[2 * j] + self.sums[2 * j + 1];
                }
                self.sums.truncate(MAX_CHUNKS / 2);
                self.chunk *= 2;
            }
        }
    }

    /// Closes the last (partial) chunk.
    fn finish(mut self) -> (u64, Vec<f64>) {
        if self.in_open > 0 {
            self.sums.push(self.open);
        }
        (self.chunk, self.sums)
    }
}

/// What the bootstrap found.
#[derive(Clone, Debug)]
pub(crate) struct BootstrapOutcome {
    /// Estimate of `b` (sum over targets of the mean weight).
    pub b: f64,
    /// Estimate of each target's integral `b_d` (its mean weight; they sum to `b`).
    pub target_b: Vec<f64>,
    /// Standard error of `b` (from the per-row sums, rows being independent).
    pub standard_error: f64,
    /// Samples evaluated (over all targets).
    pub evaluated: u64,
    /// Chain starts: (target index, sample index), one per requested chain; empty if no
    /// sample had positive weight.
    pub starts: Vec<(usize, u64)>,
    /// True if the time share of the budget ran out before all samples were evaluated.
    pub stopped_early: bool,
    /// True if cancelled.
    pub cancelled: bool,
}

/// The bootstrap's parameters.
pub(crate) struct BootstrapPlan<'a> {
    pub per_target: u64,
    pub chains: usize,
    pub seed: u64,
    pub deadline: Option<Instant>,
    pub progress: &'a dyn Progress,
    pub cancel: &'a AtomicBool,
}

fn weight_of<T, Src>(
    targets: &[T],
    source: &Src,
    seed: u64,
    sample: u64,
    state: &mut T::State,
    payload: &mut T::Payload,
) -> f64
where
    T: Target,
    Src: IndependentStates<T::State> + ?Sized,
{
    let d = targets.len() as u64;
    let (target, index) = ((sample % d) as usize, sample / d);
    source.independent(bootstrap_key(seed, target, index), state);
    let log_density = targets[target].evaluate(state, payload);
    if log_density == f64::NEG_INFINITY || log_density.is_nan() {
        return 0.0;
    }
    let w = source.weight(state, log_density);
    if w.is_finite() && w > 0.0 {
        w
    } else {
        0.0
    }
}

/// Runs the bootstrap: `per_target` independent samples of every target, sample `i` of target
/// `d` being number `i * D + d` of one stream, evaluated in parallel batches and reduced in
/// stream order (bit-identical for any thread count), then systematic resampling (Veach's
/// thesis, p. 340; Kitagawa 1996) of `chains` starts in proportion to the weights.
///
/// Memory: one batch of weights plus at most [`MAX_CHUNKS`] chunk sums. Resampling finds the
/// chunk of each start from the chunk sums and re-evaluates only those chunks (at most
/// `chains` chunks, i.e. a few percent of the samples).
pub(crate) fn run<T, Src>(targets: &[T], source: &Src, plan: &BootstrapPlan<'_>) -> BootstrapOutcome
where
    T: Target,
    Src: IndependentStates<T::State> + ?Sized,
{
    let d = targets.len().max(1) as u64;
    let total = plan.per_target.saturating_mul(d);
    let batch = (BATCH / d).max(1) * d;
    let mut weights = vec![0.0; batch.min(total) as usize];
    let mut sums = ChunkSums::new();
    let (mut sum, mut sum_sq_rows, mut evaluated) = (0.0f64, 0.0f64, 0u64);
    let mut target_sums = vec![0.0f64; d as usize];
    let (mut stopped_early, mut cancelled) = (false, false);
    let init = || (source.empty(), T::Payload::default());
    while evaluated < total {
        if plan.cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        if evaluated > 0 && plan.deadline.is_some_and(|t| Instant::now() >= t) {
            stopped_early = true;
            break;
        }
        let len = batch.min(total - evaluated) as usize;
        let first = evaluated;
        weights[..len].par_iter_mut().enumerate().for_each_init(
            init,
            |(state, payload), (k, w)| {
                *w = weight_of(targets, source, plan.seed, first + k as u64, state, payload);
            },
        );
        for row in weights[..len].chunks(d as usize) {
            let mut r = 0.0;
            for (&w, t) in row.iter().zip(target_sums.iter_mut()) {
                sums.push(w);
                r += w;
                *t += w;
            }
            sum += r;
            sum_sq_rows += r * r;
        }
        evaluated += len as u64;
        plan.progress.advance(len as u64);
    }
    let rows = (evaluated / d) as f64;
    let b = if rows > 0.0 { sum / rows } else { 0.0 };
    let standard_error = if rows > 1.0 {
        ((sum_sq_rows / rows - b * b).max(0.0) / (rows - 1.0)).sqrt()
    } else {
        f64::INFINITY
    };
    let target_b = target_sums
        .iter()
        .map(|&s| if rows > 0.0 { s / rows } else { 0.0 })
        .collect();
    let mut outcome = BootstrapOutcome {
        b,
        target_b,
        standard_error,
        evaluated,
        starts: Vec::new(),
        stopped_early,
        cancelled,
    };
    if cancelled || sum.is_nan() || sum <= 0.0 || plan.chains == 0 {
        return outcome;
    }
    let (chunk, chunk_sums) = sums.finish();
    let u = (mix64(plan.seed ^ 0x5e1f_c4a1) >> 11) as f64 / (1u64 << 53) as f64;
    match resample(targets, source, plan, chunk, &chunk_sums, evaluated, u) {
        Some(starts) => outcome.starts = starts,
        None => outcome.cancelled = true,
    }
    outcome
}

/// Systematic resampling over the chunk sums, then within the chosen chunks by re-evaluating
/// them. Returns `None` if cancelled.
fn resample<T, Src>(
    targets: &[T],
    source: &Src,
    plan: &BootstrapPlan<'_>,
    chunk: u64,
    chunk_sums: &[f64],
    evaluated: u64,
    u: f64,
) -> Option<Vec<(usize, u64)>>
where
    T: Target,
    Src: IndependentStates<T::State> + ?Sized,
{
    let d = targets.len() as u64;
    let total: f64 = chunk_sums.iter().sum();
    let step = total / plan.chains as f64;
    // (chunk index, offset of the position inside the chunk) per chain, in chain order.
    let mut located = Vec::with_capacity(plan.chains);
    let (mut j, mut cumulative) = (0usize, 0.0f64);
    for c in 0..plan.chains {
        let position = (c as f64 + u.clamp(0.0, 1.0 - f64::EPSILON)) * step;
        while j + 1 < chunk_sums.len() && cumulative + chunk_sums[j] <= position {
            cumulative += chunk_sums[j];
            j += 1;
        }
        let (mut jj, mut offset) = (j, position - cumulative);
        // Rounding at the very end can land in an empty chunk: use the last non-empty one.
        while chunk_sums[jj] == 0.0 && jj > 0 {
            jj -= 1;
            offset = f64::INFINITY;
        }
        located.push((jj, offset));
    }
    // Re-evaluate each chosen chunk once (in parallel) and pick the samples inside it.
    let mut chosen: Vec<usize> = located.iter().map(|l| l.0).collect();
    chosen.dedup();
    let picks: Vec<Option<Vec<(f64, u64)>>> = chosen
        .par_iter()
        .map_init(
            || (source.empty(), T::Payload::default()),
            |(state, payload), &j| {
                if plan.cancel.load(Ordering::Relaxed) {
                    return None;
                }
                let lo = j as u64 * chunk;
                let hi = (lo + chunk).min(evaluated);
                let mut prefix = Vec::with_capacity((hi - lo) as usize);
                let mut acc = 0.0;
                for s in lo..hi {
                    let w = weight_of(targets, source, plan.seed, s, state, payload);
                    if w > 0.0 {
                        acc += w;
                        prefix.push((acc, s));
                    }
                }
                Some(prefix)
            },
        )
        .collect();
    let mut starts = Vec::with_capacity(plan.chains);
    let mut k = 0;
    for (j, offset) in located {
        while chosen[k] != j {
            k += 1;
        }
        let prefix = picks[k].as_ref()?;
        // The first sample whose cumulative weight exceeds the offset; rounding differences
        // between the chunk sum and the re-summed weights fall back to the chunk's last sample.
        let i = prefix.partition_point(|&(acc, _)| acc <= offset);
        let sample = prefix
            .get(i)
            .or(prefix.last())
            .map_or(j as u64 * chunk, |p| p.1);
        starts.push(((sample % d) as usize, sample / d));
    }
    Some(starts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    /// Weight = a fixed table indexed by the key's sample number (states carry the index).
    struct Table(Vec<f64>);
    struct Indexed;
    impl IndependentStates<Vec<f64>> for Indexed {
        fn empty(&self) -> Vec<f64> {
            vec![0.0]
        }
        fn independent(&self, key: u64, state: &mut Vec<f64>) {
            state[0] = key as f64;
        }
    }
    impl Target for Table {
        type State = Vec<f64>;
        type Payload = ();
        fn evaluate(&self, x: &mut Vec<f64>, _: &mut ()) -> f64 {
            // Find the index whose key this is (small tables only).
            let i = (0..self.0.len() as u64)
                .find(|&i| bootstrap_key(1, 0, i) as f64 == x[0])
                .unwrap();
            self.0[i as usize].ln()
        }
    }

    fn plan(chains: usize, per_target: u64, cancel: &AtomicBool) -> BootstrapPlan<'_> {
        BootstrapPlan {
            per_target,
            chains,
            seed: 1,
            deadline: None,
            progress: &NoProgress,
            cancel,
        }
    }

    #[test]
    fn resampling_is_proportional_and_skips_zero_weights() {
        let no = AtomicBool::new(false);
        let t = [Table(vec![0.0, 1.0, 3.0, 0.0])];
        let out = run(&t, &Indexed, &plan(4, 4, &no));
        assert_eq!(out.b, 1.0);
        let picked: Vec<u64> = out.starts.iter().map(|s| s.1).collect();
        assert_eq!(picked.iter().filter(|&&i| i == 1).count(), 1, "{picked:?}");
        assert_eq!(picked.iter().filter(|&&i| i == 2).count(), 3, "{picked:?}");
    }

    #[test]
    fn chunk_sums_stay_bounded_and_exact() {
        let mut c = ChunkSums::new();
        let n = 3 * MAX_CHUNKS as u64 + 5;
        for i in 0..n {
            c.push(i as f64);
        }
        let (chunk, sums) = c.finish();
        assert!(sums.len() <= MAX_CHUNKS);
        assert_eq!(chunk, 4);
        let expected: f64 = (0..chunk).map(|i| i as f64).sum();
        assert_eq!(sums[0], expected);
        assert_eq!(sums.iter().sum::<f64>(), (n * (n - 1) / 2) as f64);
    }

    #[test]
    fn all_zero_gives_no_starts() {
        let no = AtomicBool::new(false);
        let t = [Table(vec![0.0; 3])];
        let out = run(&t, &Indexed, &plan(5, 3, &no));
        assert!(out.starts.is_empty());
        assert_eq!(out.b, 0.0);
    }
}
