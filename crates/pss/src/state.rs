//! The primary-sample-space state: a lazily grown vector of primary samples in [0, 1).

use crate::mutation::SmallMutation;
use crate::noise::uniform;

/// Maximum number of streams (camera, light, connection, and one spare).
pub const MAX_STREAMS: usize = 4;

/// The mutation a proposal attached to a state, applied lazily when the target reads
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pending {
    /// No mutation: reading returns the stored values (a freshly constructed state reads
    /// fresh uniforms for coordinates that do not exist yet).
    None,
    /// A small step with this kernel on the streams in `stream_mask` (bit s = stream s).
    Small {
        /// The per-coordinate kernel.
        mutation: SmallMutation,
        /// Streams being mutated; coordinates of other streams keep their values.
        stream_mask: u8,
    },
    /// A large step: every coordinate is a fresh uniform.
    Large,
}

/// A point of primary sample space: the random numbers a path was built from.
///
/// Coordinates are grouped in `streams` (e.g. camera subpath, light subpath, connection), each
/// read sequentially by the target; stream `s`'s `k`-th number is stored at index
/// `s + streams * k` (pbrt-v3's interleaving), so each stream grows independently.
///
/// **Lazy mutation** (pbrt's `MLTSampler`, after Kelemen et al. 2002, section 5): a proposal
/// does not touch the coordinates; it increments the state's per-stream iteration counter and
/// records the mutation ([`Pending`]) and a fresh noise key. When the target reads coordinate
/// `i`, the coordinate is brought up to date: if it predates the last large step it becomes a
/// fresh uniform; then it receives one small perturbation per iteration it missed. A
/// coordinate nobody reads is never mutated, so the state is as long as the longest path it
/// has built, and evaluating a path costs only what the path consumes. All random numbers are
/// counter-based ([`crate::noise`]), so the result does not depend on reading order.
///
/// Copying a state (`clone_from`) reuses its buffers: the chain's backup/restore on rejection
/// is "keep the old state", and acceptance is a swap.
///
/// Missed iterations are caught up with the *current* small-step kernel; if a controller
/// changes the kernel between steps, catch-up differs slightly from eager mutation with the
/// historical kernels (documented reading; the stationary distribution of unread coordinates
/// is uniform either way).
#[derive(Debug, PartialEq)]
pub struct PssState {
    values: Vec<f64>,
    /// Per coordinate: the stream iteration at which it was last brought up to date.
    stamps: Vec<u64>,
    streams: usize,
    /// Per stream: number of accepted mutations applied to that stream.
    iteration: [u64; MAX_STREAMS],
    /// Per stream: iteration of the last large step.
    last_large: [u64; MAX_STREAMS],
    pending: Pending,
    key: u64,
    cursor: [usize; MAX_STREAMS],
    stream: usize,
}

impl Clone for PssState {
    fn clone(&self) -> Self {
        let mut s = Self::new(self.streams, self.key);
        s.clone_from(self);
        s
    }

    /// Copies `source` into `self` reusing `self`'s buffers: no allocation per proposal once
    /// the buffers have grown (`derive(Clone)` would allocate new vectors every time).
    fn clone_from(&mut self, source: &Self) {
        self.values.clone_from(&source.values);
        self.stamps.clone_from(&source.stamps);
        self.streams = source.streams;
        self.iteration = source.iteration;
        self.last_large = source.last_large;
        self.pending = source.pending;
        self.key = source.key;
        self.cursor = source.cursor;
        self.stream = source.stream;
    }
}

impl PssState {
    /// An empty state with `streams` (1..=4) streams whose coordinates will be fresh
    /// uniforms drawn from `key` when first read.
    #[must_use]
    pub fn new(streams: usize, key: u64) -> Self {
        let streams = streams.clamp(1, MAX_STREAMS);
        Self {
            values: Vec::new(),
            stamps: Vec::new(),
            streams,
            iteration: [0; MAX_STREAMS],
            last_large: [0; MAX_STREAMS],
            pending: Pending::None,
            key,
            cursor: [0; MAX_STREAMS],
            stream: 0,
        }
    }

    /// A fully materialised single-stream state with the given coordinates (each in [0, 1)):
    /// for tests and for targets of fixed dimension.
    #[must_use]
    pub fn from_values(values: &[f64]) -> Self {
        let mut s = Self::new(1, 0);
        s.values = values.iter().map(|&v| crate::mutation::wrap(v)).collect();
        s.stamps = vec![0; values.len()];
        s
    }

    /// Number of streams.
    #[must_use]
    pub fn streams(&self) -> usize {
        self.streams
    }

    /// Number of stored coordinates (over all streams, interleaved).
    #[must_use]
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True if no coordinate has been materialised.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The stored coordinates, interleaved by stream. Coordinates not read since the last
    /// mutation are stale (not yet brought up to date).
    #[must_use]
    pub fn raw_values(&self) -> &[f64] {
        &self.values
    }

    /// The pending mutation.
    #[must_use]
    pub fn pending(&self) -> Pending {
        self.pending
    }

    /// Attaches a mutation for the next evaluation: increments the iteration of the mutated
    /// streams (all streams for a large step) and sets the noise key. Called by proposals on
    /// the candidate (a copy of the current state).
    pub fn set_pending(&mut self, pending: Pending, key: u64) {
        match pending {
            Pending::None => {}
            Pending::Small { stream_mask, .. } => {
                for s in 0..self.streams {
                    if stream_mask & (1 << s) != 0 {
                        self.iteration[s] += 1;
                    }
                }
            }
            Pending::Large => {
                for s in 0..self.streams {
                    self.iteration[s] += 1;
                    self.last_large[s] = self.iteration[s];
                }
            }
        }
        self.pending = pending;
        self.key = key;
    }

    /// Rewinds all stream cursors; targets call this before reading a path.
    pub fn begin(&mut self) {
        self.cursor = [0; MAX_STREAMS];
        self.stream = 0;
    }

    /// Subsequent [`PssState::next_sample`] calls read from `stream` (clamped to the stream count).
    pub fn start_stream(&mut self, stream: usize) {
        self.stream = stream.min(self.streams - 1);
    }

    /// The next primary sample of the current stream, brought up to date.
    #[inline]
    pub fn next_sample(&mut self) -> f64 {
        let s = self.stream;
        let index = s + self.streams * self.cursor[s];
        self.cursor[s] += 1;
        self.get(index)
    }

    /// Coordinate `index` (interleaved numbering), brought up to date; grows the state with
    /// fresh uniforms if needed.
    #[inline]
    pub fn get(&mut self, index: usize) -> f64 {
        if index >= self.values.len() {
            // Coordinates never read before are fresh uniforms at the time of the last large
            // step; they then need the small steps since.
            let old = self.values.len();
            self.values.resize(index + 1, 0.0);
            self.stamps.resize(index + 1, u64::MAX);
            for i in old..=index {
                self.stamps[i] = u64::MAX;
            }
        }
        let stream = index % self.streams;
        let now = self.iteration[stream];
        let stamp = self.stamps[index];
        if stamp == now {
            return self.values[index];
        }
        let key = self.key;
        let coordinate = index as u64;
        let value = if stamp == u64::MAX || stamp < self.last_large[stream] {
            // Never read, or last read before the latest large step: the large step made it a
            // fresh uniform, and perturbing a uniform on the circle leaves it uniform, so the
            // small steps since need not be applied.
            uniform(key, coordinate, u64::MAX)
        } else {
            match self.pending {
                Pending::Small { mutation, .. } => {
                    mutation.apply(self.values[index], now - stamp, |d| {
                        uniform(key, coordinate, d)
                    })
                }
                _ => self.values[index],
            }
        };
        self.values[index] = value;
        self.stamps[index] = now;
        value
    }

    /// Brings every stored coordinate up to date (eager evaluation of the pending mutation).
    pub fn materialize(&mut self) {
        for i in 0..self.values.len() {
            self.get(i);
        }
    }

    /// Up-to-date coordinates of stream `stream`, `count` of them (growing the state).
    pub fn stream_values(&mut self, stream: usize, count: usize) -> Vec<f64> {
        let stream = stream.min(self.streams - 1);
        (0..count)
            .map(|k| self.get(stream + self.streams * k))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresh_state_reads_stable_uniforms() {
        let mut a = PssState::new(3, 9);
        a.begin();
        let first: Vec<f64> = (0..5).map(|_| a.next_sample()).collect();
        a.begin();
        let again: Vec<f64> = (0..5).map(|_| a.next_sample()).collect();
        assert_eq!(first, again);
        assert!(first.iter().all(|u| (0.0..1.0).contains(u)));
    }

    #[test]
    fn streams_are_interleaved_and_independent() {
        let mut a = PssState::new(2, 1);
        a.begin();
        a.start_stream(1);
        let light = a.next_sample();
        a.start_stream(0);
        let cam = a.next_sample();
        assert_eq!(a.len(), 2);
        assert_eq!(a.raw_values(), &[cam, light]);
    }

    #[test]
    fn small_step_moves_only_masked_streams() {
        let mut x = PssState::new(2, 5);
        x.get(3);
        x.materialize();
        let before = x.raw_values().to_vec();
        let mut y = x.clone();
        let m = SmallMutation::Gaussian { sigma: 0.01 };
        y.set_pending(
            Pending::Small {
                mutation: m,
                stream_mask: 0b01,
            },
            77,
        );
        y.materialize();
        assert_ne!(y.raw_values()[0], before[0]);
        assert_ne!(y.raw_values()[2], before[2]);
        assert_eq!(y.raw_values()[1], before[1]);
        assert_eq!(y.raw_values()[3], before[3]);
    }

    #[test]
    fn large_step_resamples_everything() {
        let mut x = PssState::from_values(&[0.1, 0.2, 0.3]);
        x.set_pending(Pending::Large, 3);
        x.materialize();
        assert!(x
            .raw_values()
            .iter()
            .zip([0.1, 0.2, 0.3])
            .all(|(a, b)| *a != b));
    }
}
