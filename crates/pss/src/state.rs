//! The primary-sample-space state: a lazily grown vector of primary samples in [0, 1).

use crate::lazy_pairs::{LazyPairParams, PairDraws};
use crate::mutation::SmallMutation;
use crate::noise::uniform;
use crate::pairwise::torus_displacement;

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
    /// The pairwise polar Kelemen step of delayed rejection on every pair `(2k, 2k + 1)` of
    /// every stream, applied pair by pair as the target reads ([`crate::LazyPairwise`]).
    Pairs(LazyPairParams),
    /// The orbital second stage after the rejected [`Pending::Pairs`] candidate of key
    /// `first_key`, on the streams of `stream_mask` ([`crate::LazyOrbital`]).
    Orbit {
        /// Radius and angle laws.
        params: LazyPairParams,
        /// The key of the rejected first-stage candidate (its moves are recomputed).
        first_key: u64,
        /// Streams moved; the others keep the parent's values.
        stream_mask: u8,
    },
}

impl Pending {
    /// The streams a candidate with this pending mutation moves, of `streams` streams.
    fn moved_streams(self, streams: usize) -> u8 {
        let all = ((1u16 << streams) - 1) as u8;
        match self {
            Pending::None => 0,
            Pending::Small { stream_mask, .. } | Pending::Orbit { stream_mask, .. } => {
                stream_mask & all
            }
            Pending::Large | Pending::Pairs(_) => all,
        }
    }
}

/// A point of primary sample space: the random numbers a path was built from.
///
/// Coordinates are grouped in `streams` (e.g. camera subpath, light subpath, connection), each
/// read sequentially by the target; stream `s`'s `k`-th number is stored at index
/// `s + streams * k` (pbrt-v3's interleaving), so each stream grows independently.
///
/// **Lazy mutation** (pbrt's `MLTSampler`, after Kelemen et al. 2002, section 5): a proposal
/// does not touch the coordinates; it increments the candidate's per-stream iteration counter
/// and records the mutation ([`Pending`]) and a fresh noise key. When the target reads
/// coordinate `i`, the coordinate is brought up to date. A coordinate nobody reads is never
/// mutated, so the state is as long as the longest path it has built, and evaluating a path
/// costs only what the path consumes. All random numbers are counter-based
/// ([`crate::noise`]), so the result does not depend on reading order.
///
/// # Why lazy equals eager, rejections included
///
/// Eagerly, every proposal perturbs every coordinate. Think of the current state `x` as that
/// eager vector. A coordinate `i` that no evaluation has read since it was last stored (its
/// *stamp*) has influenced no accept/reject decision since then, so, given everything the
/// chain has decided, its eager value is distributed as the stored value perturbed by the
/// `m` small steps accepted since (a fresh uniform if a large step intervened), independently
/// of everything else. By the principle of deferred decisions it may be drawn from that law at
/// the moment it is first needed — **provided the draw is then kept**. This type keeps it:
///
/// 1. A small-step candidate `y` that reads a stale coordinate first draws the *parent's*
///    value `x_i` (the catch-up, from a key derived from the candidate's key), records
///    `(i, x_i)` in an observation log, then applies its own perturbation to it.
/// 2. If `y` is accepted, `y` holds its own values. If `y` is rejected, the kernel calls
///    [`mcmc_core::Point::absorb_rejected`] on `x`, which stores the logged `x_i` in `x` with
///    `x`'s current stamp: from then on every candidate proposed from `x` sees the same `x_i`,
///    exactly as with an eager `x`, and `x`'s unread coordinates never change while the chain
///    stays at `x`.
/// 3. A large-step candidate ignores the parent (a fresh uniform), so it observes nothing.
///
/// Each coordinate of `x` is thus drawn once, from its correct conditional law, at its first
/// observation, and is fixed afterwards: the lazy chain and the eager chain have the same law
/// (docs/methods/pssmlt-mmlt.md has the longer argument). pbrt's `MLTSampler` instead discards
/// the caught-up values on rejection, so the current state's unread coordinates are re-drawn at
/// every proposal until one is accepted: a selection bias whenever the set of coordinates the
/// target reads depends on the state (Russian roulette, varying path length, MMLT strategies).
///
/// The catch-up uses the candidate's small-step kernel for all `m` missed steps. With a fixed
/// kernel this is exact; if a controller changes the kernel between steps (scale adaptation),
/// the missed steps are drawn with the current kernel rather than the historical ones (our
/// documented reading; the difference vanishes under diminishing adaptation).
///
/// Copying a state (`clone_from`) reuses its buffers: the chain's backup/restore on rejection
/// is "keep the old state", and acceptance is a swap.
#[derive(Debug, PartialEq)]
pub struct PssState {
    values: Vec<f64>,
    /// Per coordinate: the stream iteration at which it was last brought up to date
    /// (`NEVER` if never read).
    stamps: Vec<u64>,
    streams: usize,
    /// Per stream: number of mutations applied to that stream along this state's lineage.
    iteration: [u64; MAX_STREAMS],
    /// Per stream: iteration of the last large step.
    last_large: [u64; MAX_STREAMS],
    /// Per stream: accepted orbital second-stage steps along this state's lineage.
    orbits: [u64; MAX_STREAMS],
    /// Per coordinate: the stream's `orbits` when it was last brought up to date (empty, i.e.
    /// all 0, until a lineage takes an orbital step; see [`crate::lazy_pairs`]).
    orbit_stamps: Vec<u64>,
    /// [`LazyPairParams::log_radius_ratio`] of a pairwise pending mutation (computed once per
    /// candidate rather than once per pair).
    pair_log_ratio: f64,
    pending: Pending,
    key: u64,
    /// The key of the state this one was proposed from (to check `absorb_rejected` calls).
    parent_key: u64,
    /// Parent values this candidate's evaluation drew (index, value): see the type docs.
    observed: Vec<(usize, f64)>,
    cursor: [usize; MAX_STREAMS],
    /// Per stream: bit `k` set if the last evaluation consumed the stream's `k`-th number as
    /// a discrete choice or not at all ([`PssState::next_discrete`]).
    discrete: [u64; MAX_STREAMS],
    stream: usize,
}

/// `(k, s)` with `index = s + streams * k`, `s < streams` (interleaved numbering): stream
/// `s`'s `k`-th number. `streams` is 1..=4 ([`MAX_STREAMS`]), so each case divides by a
/// constant (a multiply, not a hardware division on the pair moves' critical path).
#[inline]
pub(crate) fn split_index(index: usize, streams: usize) -> (usize, usize) {
    match streams {
        1 => (index, 0),
        2 => (index >> 1, index & 1),
        3 => (index / 3, index % 3),
        4 => (index >> 2, index & 3),
        _ => (index / streams, index % streams),
    }
}

/// Reads per stream whose discrete tag is recorded (later reads count as continuous).
pub const TAGGED_READS: usize = 64;

/// Stamp of a coordinate that was never read.
const NEVER: u64 = u64::MAX;

/// Salt that separates the catch-up draws of a candidate from its own perturbation draws.
const CATCH_UP_SALT: u64 = 0x6361_7463_6875_7021;

impl Clone for PssState {
    fn clone(&self) -> Self {
        let mut s = Self::new(self.streams, self.key);
        s.clone_from(self);
        s
    }

    /// Copies `source` into `self` reusing `self`'s buffers: no allocation per proposal once
    /// the buffers have grown (`derive(Clone)` would allocate new vectors every time). The
    /// observation log is copied too (it is empty except on a candidate being evaluated).
    fn clone_from(&mut self, source: &Self) {
        self.values.clone_from(&source.values);
        self.stamps.clone_from(&source.stamps);
        self.streams = source.streams;
        self.iteration = source.iteration;
        self.last_large = source.last_large;
        self.orbits = source.orbits;
        self.orbit_stamps.clone_from(&source.orbit_stamps);
        self.pair_log_ratio = source.pair_log_ratio;
        self.pending = source.pending;
        self.key = source.key;
        self.parent_key = source.parent_key;
        self.observed.clone_from(&source.observed);
        self.cursor = source.cursor;
        self.discrete = source.discrete;
        self.stream = source.stream;
    }
}

impl mcmc_core::Point for PssState {
    /// Keeps the values of `self`'s coordinates that the rejected candidate's evaluation drew
    /// (its catch-up of stale coordinates), so that they do not change with the candidate's
    /// fate: the step that makes lazy mutation exact (see the type docs).
    fn absorb_rejected(&mut self, rejected: &Self) {
        if rejected.parent_key != self.key || rejected.streams != self.streams {
            debug_assert!(
                rejected.observed.is_empty(),
                "absorb_rejected: the candidate was not proposed from this state"
            );
            return;
        }
        for &(index, value) in &rejected.observed {
            self.store(index, value);
        }
    }

    /// A candidate of a lazy small step (a [`Pending::Small`] on some stream) extends itself
    /// to what is known of its parent: from the parent, the coordinates it stores beyond the
    /// candidate's length (with their stamps); from a sibling, the parent values its
    /// evaluation drew there (its observation log). The candidate is one step ahead of those,
    /// as of every coordinate it inherited; it then brings every stored coordinate up to date
    /// ([`PssState::materialize`]): the eager candidate, as far as the parent is known. Other
    /// candidates (large steps, the identity-pending candidates of the layout stages, MALA's)
    /// write the coordinates their densities read when they are proposed and are left as
    /// they are.
    fn catch_up_with(&mut self, known: &Self) {
        let Pending::Small { stream_mask, .. } = self.pending else {
            return;
        };
        if stream_mask == 0 || known.streams != self.streams {
            return;
        }
        let len = self.values.len();
        if known.key == self.parent_key {
            if known.values.len() > len {
                self.values.extend_from_slice(&known.values[len..]);
                self.stamps.extend_from_slice(&known.stamps[len..]);
            }
        } else if known.parent_key == self.parent_key {
            for &(index, value) in &known.observed {
                if index < len {
                    continue;
                }
                if index >= self.values.len() {
                    self.values.resize(index + 1, 0.0);
                    self.stamps.resize(index + 1, NEVER);
                }
                let stream = index % self.streams;
                let mutated = stream_mask & (1 << stream) != 0;
                self.values[index] = value;
                self.stamps[index] = self.iteration[stream] - u64::from(mutated);
            }
        }
        self.materialize();
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
            orbits: [0; MAX_STREAMS],
            orbit_stamps: Vec::new(),
            pair_log_ratio: 0.0,
            pending: Pending::None,
            key,
            parent_key: key,
            observed: Vec::new(),
            cursor: [0; MAX_STREAMS],
            discrete: [0; MAX_STREAMS],
            stream: 0,
        }
    }

    /// Turns `self` into `PssState::new(streams, key)` keeping its buffers (no allocation once
    /// they have grown): how a render loop's bootstrap reuses one state per thread.
    pub fn reset(&mut self, streams: usize, key: u64) {
        self.values.clear();
        self.stamps.clear();
        self.observed.clear();
        self.streams = streams.clamp(1, MAX_STREAMS);
        self.iteration = [0; MAX_STREAMS];
        self.last_large = [0; MAX_STREAMS];
        self.orbits = [0; MAX_STREAMS];
        self.orbit_stamps.clear();
        self.pair_log_ratio = 0.0;
        self.pending = Pending::None;
        self.key = key;
        self.parent_key = key;
        self.cursor = [0; MAX_STREAMS];
        self.discrete = [0; MAX_STREAMS];
        self.stream = 0;
    }

    /// A fully materialised single-stream state with the given coordinates (each wrapped
    /// into [0, 1)): for tests and for targets of fixed dimension.
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

    /// The noise key of the mutation that produced this state (or of the fresh state).
    #[must_use]
    pub fn key(&self) -> u64 {
        self.key
    }

    /// The key of the state this one was proposed from (its own key for a fresh state).
    #[must_use]
    pub fn parent_key(&self) -> u64 {
        self.parent_key
    }

    /// Attaches a mutation for the next evaluation: increments the iteration of the mutated
    /// streams (all streams for a large step) and sets the noise key. Called by proposals on
    /// the candidate (a copy of the current state); clears the candidate's observation log.
    pub fn set_pending(&mut self, pending: Pending, key: u64) {
        let moved = pending.moved_streams(self.streams);
        for s in 0..self.streams {
            if moved & (1 << s) != 0 {
                self.iteration[s] += 1;
                match pending {
                    Pending::Large => self.last_large[s] = self.iteration[s],
                    Pending::Orbit { .. } => self.orbits[s] += 1,
                    _ => {}
                }
            }
        }
        if let Pending::Pairs(params) | Pending::Orbit { params, .. } = pending {
            self.pair_log_ratio = params.log_radius_ratio();
        }
        self.pending = pending;
        self.parent_key = self.key;
        self.key = key;
        self.observed.clear();
    }

    /// How many primary samples of each stream the last evaluation read through
    /// [`PssState::next_sample`] (the stream cursors; entries beyond
    /// [`PssState::streams`] are 0). With a target that reads sequentially, the read set of
    /// the last evaluation is the prefix `0..read_counts()[s]` of each stream `s`: what
    /// MALA moves ([`crate::langevin::PssCoordinates`]).
    #[must_use]
    pub fn read_counts(&self) -> [usize; MAX_STREAMS] {
        self.cursor
    }

    /// Which numbers of each stream the last evaluation tagged discrete
    /// ([`PssState::next_discrete`]): bit `k` of entry `s` for the `k`-th number of stream `s`
    /// (the first [`TAGGED_READS`] numbers of a stream; later ones are untagged). MALA keeps
    /// tagged coordinates fixed ([`crate::langevin::PssCoordinates`]).
    #[must_use]
    pub fn discrete_mask(&self) -> [u64; MAX_STREAMS] {
        self.discrete
    }

    /// True if the `k`-th number of stream `s` was tagged discrete by the last evaluation.
    #[inline]
    #[must_use]
    pub fn is_discrete(&self, s: usize, k: usize) -> bool {
        s < MAX_STREAMS && k < TAGGED_READS && self.discrete[s] & (1u64 << k) != 0
    }

    /// Rewinds all stream cursors and clears the discrete tags; targets call this before
    /// reading a path.
    pub fn begin(&mut self) {
        self.cursor = [0; MAX_STREAMS];
        self.discrete = [0; MAX_STREAMS];
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

    /// As [`PssState::next_sample`], for a number the target consumes as a *discrete* choice
    /// (a strategy, a lobe, a light, a Russian-roulette decision) or does not use at all (the
    /// lens of a pinhole camera, the time of a static scene): its derivative is zero almost
    /// everywhere, so differentiating or moving it in a Langevin step only wastes the step.
    /// The read is tagged ([`PssState::discrete_mask`]) and MALA keeps it fixed; large steps
    /// and the other proposals move it like any number. Tagging is a question of efficiency,
    /// never of exactness: MALA is exact for any tags that are a function of the state
    /// (docs/methods/mala.md, "Continuous coordinates").
    #[inline]
    pub fn next_discrete(&mut self) -> f64 {
        let s = self.stream;
        let k = self.cursor[s];
        if k < TAGGED_READS {
            self.discrete[s] |= 1u64 << k;
        }
        self.next_sample()
    }

    /// Coordinate `index` (interleaved numbering), brought up to date; grows the state with
    /// fresh uniforms if needed.
    #[inline]
    pub fn get(&mut self, index: usize) -> f64 {
        if index >= self.values.len() {
            self.values.resize(index + 1, 0.0);
            self.stamps.resize(index + 1, NEVER);
        }
        let stream = index % self.streams;
        let now = self.iteration[stream];
        if self.stamps[index] == now {
            return self.values[index];
        }
        if matches!(self.pending, Pending::Pairs(_) | Pending::Orbit { .. }) {
            return self.catch_up_pair(index, None);
        }
        let value = self.catch_up(index, stream, now);
        self.store(index, value);
        value
    }

    /// The up-to-date value of a stale coordinate (see the type docs for why this is exact).
    #[cold]
    fn catch_up(&mut self, index: usize, stream: usize, now: u64) -> f64 {
        let stamp = self.stamps[index];
        let coordinate = index as u64;
        // Last read before the latest large step of this stream (or never): the large step
        // made it a fresh uniform, and perturbing a uniform on the circle leaves it uniform.
        let refreshed = stamp == NEVER || stamp < self.last_large[stream];
        match self.pending {
            Pending::Large => uniform(self.key, coordinate, u64::MAX),
            Pending::None => {
                // A state nobody mutated (fresh from a key): a deferred draw of its own value.
                if refreshed {
                    uniform(self.key, coordinate, u64::MAX)
                } else {
                    self.values[index]
                }
            }
            Pending::Small {
                mutation,
                stream_mask,
            } => {
                let mutated = stream_mask & (1 << stream) != 0;
                let parent_now = if mutated { now - 1 } else { now };
                // The parent's value of this coordinate, drawn now from its law given the
                // chain's history (deferred decision), and logged so that a rejection keeps it.
                let parent = if refreshed {
                    let k = mcmc_core::seed::mix64(self.key ^ CATCH_UP_SALT);
                    Some(uniform(k, coordinate, u64::MAX))
                } else if stamp < parent_now {
                    let k = mcmc_core::seed::mix64(self.key ^ CATCH_UP_SALT);
                    Some(mutation.apply(self.values[index], parent_now - stamp, |d| {
                        uniform(k, coordinate, d)
                    }))
                } else {
                    None // stored and up to date in the parent: nothing new was observed
                };
                let base = match parent {
                    Some(v) => {
                        self.observed.push((index, v));
                        v
                    }
                    None => self.values[index],
                };
                if mutated {
                    let key = self.key;
                    mutation.apply(base, 1, |d| uniform(key, coordinate, d))
                } else {
                    base
                }
            }
            Pending::Pairs(_) | Pending::Orbit { .. } => {
                unreachable!("pairwise pending mutations catch up by pairs")
            }
        }
    }

    /// Stores `value` (wrapped into `[0, 1)`) as coordinate `index` (interleaved numbering),
    /// up to date at the state's current iteration, growing the state if needed: for
    /// proposals that compute whole coordinates rather than attach a lazy mutation (the
    /// pairwise stages of delayed rejection, which first read the parent's value with
    /// [`PssState::get`] on the candidate, so that catch-up draws are logged as usual).
    pub fn set(&mut self, index: usize, value: f64) {
        self.store(index, crate::mutation::wrap(value));
    }

    /// Stores `value` as coordinate `index`, stamped up to date (both stamps).
    fn store(&mut self, index: usize, value: f64) {
        if index >= self.values.len() {
            self.values.resize(index + 1, 0.0);
            self.stamps.resize(index + 1, NEVER);
        }
        self.store_stored(index, index % self.streams, value);
    }

    /// [`PssState::store`] for a stored coordinate `index` of stream `stream`.
    #[inline]
    fn store_stored(&mut self, index: usize, stream: usize, value: f64) {
        self.values[index] = value;
        self.stamps[index] = self.iteration[stream];
        if self.orbits[stream] != 0 || index < self.orbit_stamps.len() {
            if index >= self.orbit_stamps.len() {
                self.orbit_stamps.resize(index + 1, 0);
            }
            self.orbit_stamps[index] = self.orbits[stream];
        }
    }

    /// The `orbits` count stamped on coordinate `index`.
    fn orbit_stamp(&self, index: usize) -> u64 {
        self.orbit_stamps.get(index).copied().unwrap_or(0)
    }

    /// Catches up and moves the pair holding coordinate `index` under a pending
    /// [`Pending::Pairs`] or [`Pending::Orbit`] (see [`crate::lazy_pairs`] for why this is
    /// exact); returns coordinate `index`. `first_pair`, under a [`Pending::Orbit`]: the
    /// rejected first-stage candidate's values of the pair if it read the pair (its parent,
    /// this state's parent, then holds the pair up to date: `absorb_rejected` stored what
    /// the candidate drew).
    #[cold]
    fn catch_up_pair(&mut self, index: usize, first_pair: Option<[f64; 2]>) -> f64 {
        let streams = self.streams;
        let (k, stream) = split_index(index, streams);
        let (params, moved) = match self.pending {
            Pending::Pairs(params) => (params, true),
            Pending::Orbit {
                params,
                stream_mask,
                ..
            } => (params, stream_mask & (1 << stream) != 0),
            _ => unreachable!("called for pairwise pending mutations only"),
        };
        let now = self.iteration[stream];
        let parent_now = now - u64::from(moved);
        let Some(pair) = params.pair_at(k, stream, streams) else {
            // A kept first number: only large steps renew it.
            let stamp = self.stamps[index];
            let value = if stamp == NEVER || stamp < self.last_large[stream] {
                let k = mcmc_core::seed::mix64(self.key ^ CATCH_UP_SALT);
                let v = uniform(k, index as u64, u64::MAX);
                self.observed.push((index, v));
                v
            } else {
                self.values[index]
            };
            self.store(index, value);
            return value;
        };
        let a = pair[0];
        if pair[1] >= self.values.len() {
            self.values.resize(pair[1] + 1, 0.0);
            self.stamps.resize(pair[1] + 1, NEVER);
        }
        let orbit_step = moved && matches!(self.pending, Pending::Orbit { .. });
        let parent_orbits = self.orbits[stream] - u64::from(orbit_step);
        // The rejected candidate's pair gives its move only against the parent's pair it
        // moved, which the parent then holds up to date.
        let first_pair = first_pair.filter(|_| pair.iter().all(|&i| self.stamps[i] == parent_now));
        let catch_up_key = mcmc_core::seed::mix64(self.key ^ CATCH_UP_SALT);
        let log_ratio = self.pair_log_ratio;
        // The parent's pair, each coordinate drawn from its law given the history (logged).
        // The two coordinates of a pair share their stamps, so their missed steps are drawn
        // once (kept with the counts they were drawn for).
        let mut parent = [0.0; 2];
        let mut missed: Option<(u64, u64, [f64; 2])> = None;
        for (c, &i) in pair.iter().enumerate() {
            let stamp = self.stamps[i];
            if stamp == now {
                continue; // already computed in this candidate
            }
            parent[c] = if stamp == parent_now {
                self.values[i]
            } else if stamp == NEVER || stamp < self.last_large[stream] {
                uniform(catch_up_key, i as u64, u64::MAX)
            } else {
                let second = parent_orbits - self.orbit_stamp(i);
                let first = (parent_now - stamp).saturating_sub(second);
                let d = match missed {
                    Some((f, s, d)) if (f, s) == (first, second) => d,
                    _ => {
                        let d =
                            params.missed_steps(log_ratio, catch_up_key, a as u64, first, second);
                        missed = Some((first, second, d));
                        d
                    }
                };
                crate::mutation::wrap(self.values[i] + d[c])
            };
            if stamp != parent_now {
                self.observed.push((i, parent[c]));
            }
        }
        let d = if !moved {
            [0.0, 0.0]
        } else if let Pending::Orbit { first_key, .. } = self.pending {
            // The rejected candidate's move: its pair minus the parent's where it read the
            // pair (the same `d` to rounding, without redrawing it), else redrawn.
            let d = match first_pair {
                Some(y) => [
                    torus_displacement(parent[0], y[0]),
                    torus_displacement(parent[1], y[1]),
                ],
                None => params
                    .step_displacement_with(log_ratio, &mut PairDraws::new(first_key, a as u64)),
            };
            params.orbit_displacement(d, params.rotation(&mut PairDraws::new(self.key, a as u64)))
        } else {
            params.step_displacement_with(log_ratio, &mut PairDraws::new(self.key, a as u64))
        };
        for (c, &i) in pair.iter().enumerate() {
            if self.stamps[i] != now {
                self.store_stored(i, stream, crate::mutation::wrap(parent[c] + d[c]));
            }
        }
        self.values[index]
    }

    /// Brings up to date every coordinate `other` (a sibling candidate of the same parent)
    /// brought up to date, in the streams of `stream_mask`: the orbital stage computes `z` on
    /// the pairs the rejected `y` read ([`crate::LazyOrbital`]).
    pub fn materialize_read_by(&mut self, other: &Self, stream_mask: u8) {
        if other.streams != self.streams {
            return;
        }
        let streams = self.streams;
        let pairs = matches!(self.pending, Pending::Orbit { .. });
        for stream in (0..streams).filter(|s| stream_mask & (1 << s) != 0) {
            let now = other.iteration[stream];
            for i in (stream..other.values.len()).step_by(streams) {
                if other.stamps[i] != now || self.stamps.get(i) == Some(&self.iteration[stream]) {
                    continue;
                }
                match self.params_pair(i).filter(|_| pairs) {
                    Some([a, b]) if b < other.values.len() && other.stamps[b] == now => {
                        let first = [other.values[a], other.values[b]];
                        if !self.orbit_pair_from_first(a, b, stream, first) {
                            self.catch_up_pair(i, Some(first));
                        }
                    }
                    _ => {
                        self.get(i);
                    }
                }
            }
        }
    }

    /// The common case of [`PssState::catch_up_pair`] under a [`Pending::Orbit`] on a moved
    /// stream, for a pair `(a, b)` of `stream` the rejected first-stage candidate read
    /// (values `first`) and the parent holds up to date (stamped `now - 1`, as it does after
    /// absorbing that candidate): `z = x + d - R(theta) d` with `d = first - x`, the same
    /// arithmetic bit for bit, without the catch-up's bookkeeping (nothing is missed or
    /// observed). Returns false, touching nothing, where that case does not apply.
    #[inline]
    fn orbit_pair_from_first(
        &mut self,
        a: usize,
        b: usize,
        stream: usize,
        first: [f64; 2],
    ) -> bool {
        let Pending::Orbit {
            params,
            stream_mask,
            ..
        } = self.pending
        else {
            return false;
        };
        let now = self.iteration[stream];
        if stream_mask & (1 << stream) == 0
            || b >= self.values.len()
            || self.stamps[a] != now - 1
            || self.stamps[b] != now - 1
        {
            return false;
        }
        let parent = [self.values[a], self.values[b]];
        let d = [
            torus_displacement(parent[0], first[0]),
            torus_displacement(parent[1], first[1]),
        ];
        let rotation = params.rotation(&mut PairDraws::new(self.key, a as u64));
        let m = params.orbit_displacement(d, rotation);
        self.store_stored(a, stream, crate::mutation::wrap(parent[0] + m[0]));
        self.store_stored(b, stream, crate::mutation::wrap(parent[1] + m[1]));
        true
    }

    /// The pair holding coordinate `index` under a pairwise pending mutation.
    fn params_pair(&self, index: usize) -> Option<[usize; 2]> {
        match self.pending {
            Pending::Pairs(params) | Pending::Orbit { params, .. } => {
                params.pair_of(index, self.streams)
            }
            _ => None,
        }
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
#[path = "state_tests.rs"]
mod tests;
