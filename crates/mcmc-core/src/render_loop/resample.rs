//! The bootstrap's bookkeeping for chain starts: chunk sums of the weight stream, chains per
//! target, and systematic resampling over the chunk sums with re-evaluation of the chosen
//! chunks.

use std::sync::atomic::Ordering;

use rayon::prelude::*;

use super::bootstrap::{weight_of, BootstrapPlan, IndependentStates};
use crate::target::Target;

/// Maximum number of chunk sums kept by the bootstrap (128 KiB of memory); with one set of
/// chunk sums per target ([`super::ChainAllocation::PerTarget`]) each target keeps
/// `MAX_CHUNKS / targets` of them (at least [`MIN_CHUNKS`]).
pub(super) const MAX_CHUNKS: usize = 1 << 14;

/// Fewest chunk sums a target keeps under [`super::ChainAllocation::PerTarget`].
pub(super) const MIN_CHUNKS: usize = 16;

/// Sums of a stream of weights over chunks of `chunk` consecutive samples; when the chunk
/// count reaches `max`, neighbouring chunks are merged and the chunk size doubles, so
/// memory stays bounded whatever the number of samples.
#[derive(Clone, Debug)]
pub(super) struct ChunkSums {
    chunk: u64,
    sums: Vec<f64>,
    open: f64,
    in_open: u64,
    max: usize,
}

impl ChunkSums {
    /// Empty sums keeping at most `max` chunks (rounded down to even, at least 2).
    pub(super) fn new(max: usize) -> Self {
        Self {
            chunk: 1,
            sums: Vec::new(),
            open: 0.0,
            in_open: 0,
            max: max.max(2) & !1,
        }
    }

    /// Adds the next weight of the stream.
    pub(super) fn push(&mut self, w: f64) {
        self.open += w;
        self.in_open += 1;
        if self.in_open == self.chunk {
            self.sums.push(self.open);
            self.open = 0.0;
            self.in_open = 0;
            if self.sums.len() == self.max {
                for j in 0..self.max / 2 {
                    self.sums[j] = self.sums[2 * j] + self.sums[2 * j + 1];
                }
                self.sums.truncate(self.max / 2);
                self.chunk *= 2;
            }
        }
    }

    /// Closes the last (partial) chunk.
    pub(super) fn finish(mut self) -> (u64, Vec<f64>) {
        if self.in_open > 0 {
            self.sums.push(self.open);
        }
        (self.chunk, self.sums)
    }
}

/// Chains per target: proportional to `target_b` by largest remainders, at least one per
/// target with positive `b_d` if `chains` allows (ties go to the lower index).
pub(super) fn allocate(target_b: &[f64], chains: usize) -> Vec<usize> {
    let positive = |b: f64| b.is_finite() && b > 0.0;
    let total: f64 = target_b.iter().copied().filter(|&b| positive(b)).sum();
    let quota: Vec<f64> = target_b
        .iter()
        .map(|&b| {
            if positive(b) && total > 0.0 {
                chains as f64 * b / total
            } else {
                0.0
            }
        })
        .collect();
    let mut n: Vec<usize> = quota.iter().map(|q| q.floor() as usize).collect();
    let n_positive = target_b.iter().filter(|&&b| positive(b)).count();
    if n_positive == 0 {
        return n;
    }
    if n_positive <= chains {
        for (k, &b) in n.iter_mut().zip(target_b) {
            if positive(b) && *k == 0 {
                *k = 1;
            }
        }
    }
    let mut assigned: usize = n.iter().sum();
    while assigned < chains {
        let best = (0..n.len())
            .filter(|&t| positive(target_b[t]))
            .max_by(|&a, &c| {
                (quota[a] - n[a] as f64)
                    .total_cmp(&(quota[c] - n[c] as f64))
                    .then(c.cmp(&a))
            })
            .unwrap_or_else(|| unreachable!("n_positive > 0"));
        n[best] += 1;
        assigned += 1;
    }
    while assigned > chains {
        let Some(best) = (0..n.len())
            .filter(|&t| n[t] > 1 || (n_positive > chains && n[t] > 0))
            .max_by(|&a, &c| {
                (n[a] as f64 - quota[a])
                    .total_cmp(&(n[c] as f64 - quota[c]))
                    .then(c.cmp(&a))
            })
        else {
            break;
        };
        n[best] -= 1;
        assigned -= 1;
    }
    n
}

/// A uniform number in [0, 1) from 64 random bits.
pub(super) fn unit(bits: u64) -> f64 {
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

/// What resampling needs to re-evaluate samples.
pub(super) struct Resampling<'a, 'p, T, Src: ?Sized> {
    pub(super) targets: &'a [T],
    pub(super) source: &'a Src,
    pub(super) plan: &'a BootstrapPlan<'p>,
    pub(super) limits: &'a [u64],
}

impl<T, Src> Resampling<'_, '_, T, Src>
where
    T: Target,
    Src: IndependentStates<T::State> + ?Sized,
{
    /// Systematic resampling of `chains` positions over the chunk sums of a sequence of
    /// `count` positions (position `p` is stream sample `to_sample(p)`), then within the
    /// chosen chunks by re-evaluating them. Returns the chosen stream samples in position
    /// order, or `None` if cancelled.
    pub(super) fn resample(
        &self,
        chunk: u64,
        chunk_sums: &[f64],
        count: u64,
        chains: usize,
        u: f64,
        to_sample: impl Fn(u64) -> u64 + Sync,
    ) -> Option<Vec<u64>> {
        let (targets, source, plan) = (self.targets, self.source, self.plan);
        let total: f64 = chunk_sums.iter().sum();
        let step = total / chains as f64;
        // (chunk index, offset of the position inside the chunk) per chain, in chain order.
        let mut located = Vec::with_capacity(chains);
        let (mut j, mut cumulative) = (0usize, 0.0f64);
        for c in 0..chains {
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
                    let hi = (lo + chunk).min(count);
                    let mut prefix = Vec::with_capacity((hi - lo) as usize);
                    let mut acc = 0.0;
                    for p in lo..hi {
                        let s = to_sample(p);
                        let w =
                            weight_of(targets, source, plan.seed, self.limits, s, state, payload);
                        if w > 0.0 {
                            acc += w;
                            prefix.push((acc, s));
                        }
                    }
                    Some(prefix)
                },
            )
            .collect();
        let mut starts = Vec::with_capacity(chains);
        let mut k = 0;
        for (j, offset) in located {
            while chosen[k] != j {
                k += 1;
            }
            let prefix = picks[k].as_ref()?;
            // The first sample whose cumulative weight exceeds the offset; rounding differences
            // between the chunk sum and the re-summed weights fall back to the chunk's last
            // sample.
            let i = prefix.partition_point(|&(acc, _)| acc <= offset);
            let sample = prefix
                .get(i)
                .or(prefix.last())
                .map_or_else(|| to_sample(j as u64 * chunk), |p| p.1);
            starts.push(sample);
        }
        Some(starts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunk_sums_stay_bounded_and_exact() {
        let mut c = ChunkSums::new(MAX_CHUNKS);
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
    fn allocation_is_proportional_with_one_chain_per_positive_target() {
        assert_eq!(allocate(&[0.5, 0.3, 0.2], 10), [5, 3, 2]);
        // Largest remainders: quotas 6.67, 3.33 -> 7, 3.
        assert_eq!(allocate(&[2.0, 1.0], 10), [7, 3]);
        // At least one chain for a target with light, taken from the largest.
        assert_eq!(allocate(&[1.0, 0.001, 0.0], 10), [9, 1, 0]);
        assert_eq!(allocate(&[1.0, 1e-9, 1e-9, 1e-9], 4), [1, 1, 1, 1]);
        // More targets with light than chains: proportional, no minimum.
        assert_eq!(allocate(&[3.0, 2.0, 1.0], 2), [1, 1, 0]);
        assert_eq!(allocate(&[0.0, 0.0], 5), [0, 0]);
        assert_eq!(allocate(&[f64::NAN, 1.0], 3), [0, 3]);
        for chains in 1..40 {
            let n = allocate(&[0.7, 0.01, 0.2, 0.0, 0.09], chains);
            assert_eq!(n.iter().sum::<usize>(), chains, "{chains}: {n:?}");
        }
    }
}
