//! Samplers for the local quasi-Monte Carlo integrators: the per-pixel scrambled Halton
//! sampler of the Halton QMC baseline and of LQMC's seed paths, and a sampler that records a
//! seed path's numbers and replays them with chosen dimensions overridden.

use glam::Vec2;
use lqmc::{Halton, Scrambling};
use mcmc_core::seed::mix64;

use crate::sampler::{unit_f32, PixelSampler, Sampler, Stream};

/// Dimensions of [`Stream::Light`] and [`Stream::Connection`] start here in the Halton
/// sampler, beyond the Halton dimensions (they use its hash PRNG); the path tracers draw from
/// [`Stream::Camera`] only.
const OTHER_STREAM_OFFSET: usize = 1 << 20;

/// Cranley-Patterson-rotated Halton points per pixel (Tessari et al., section 3.4 "Seed
/// sampling": the Halton sequence up to 256 dimensions, then a PRNG, as in [`lqmc::Halton`];
/// "in the context of a Cranley-Patterson rotation").
///
/// Sample `i` of pixel `p` is point `i` of the Halton sequence (radical inverses in the first
/// primes), every dimension shifted modulo 1 by a uniform offset keyed by `(seed, p,
/// dimension)`: each pixel gets its own randomised QMC sequence, so its first two dimensions
/// (the position inside the pixel) and every other low dimension are stratified across the
/// pixel's samples, and every point is uniform, so the estimate is unbiased. Dimension `d`
/// of [`Stream::Camera`] is Halton dimension `d` (the path tracer's layout: pixel 2, lens 2,
/// time 1, then 7 per bounce). We do not use [`lqmc::Scrambling::Owen`] here: it scrambles
/// every digit down to `f64` resolution (about 50 hashes per number in base 2), which makes
/// the path tracer several times slower than with independent numbers (`docs/performance.md`,
/// "Halton QMC and LQMC"); the rotation costs one hash.
///
/// # Example
/// ```
/// use render::integrator::halton_sampler::HaltonSampler;
/// use render::sampler::Sampler;
/// let mut s = HaltonSampler::new(3);
/// s.start_pixel_sample(10, 0);
/// let a = s.next_1d();
/// s.start_pixel_sample(10, 0);
/// assert_eq!(a, s.next_1d());
/// ```
#[derive(Clone, Debug)]
pub struct HaltonSampler {
    seed_key: u64,
    halton: Halton,
    pixel_key: u64,
    index: u64,
    stream: usize,
    dimension: [usize; 3],
}

impl HaltonSampler {
    /// A sampler for master seed `seed`, at pixel 0, sample 0.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self::with_scrambling(seed, Scrambling::None)
    }

    /// The sampler for master seed `seed` over a Halton sequence with digit scrambling
    /// `scrambling` (still rotated per pixel). [`Scrambling::Faure`] costs a table lookup per
    /// digit and removes the clustering of plain Halton in bases larger than the pixel's
    /// sample count (docs/performance.md, "Halton samplers for PT").
    #[must_use]
    pub fn with_scrambling(seed: u64, scrambling: Scrambling) -> Self {
        let seed_key = mix64(seed ^ 0x4a1f_0c3b_9e77_d2a5);
        let mut s = Self {
            seed_key,
            halton: Halton::new(scrambling, seed_key),
            pixel_key: 0,
            index: 0,
            stream: 0,
            dimension: [0; 3],
        };
        s.start_pixel_sample(0, 0);
        s
    }

    /// Starts sample `sample_index` of pixel `pixel_index`: point `sample_index` of the
    /// pixel's rotated sequence, every stream at its first dimension, [`Stream::Camera`].
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel_index: u64, sample_index: u64) {
        self.pixel_key = mix64(self.seed_key ^ mix64(pixel_index.wrapping_add(0x9e37_79b9)));
        self.index = sample_index;
        self.stream = 0;
        self.dimension = [0; 3];
    }
}

impl PixelSampler for HaltonSampler {
    #[inline]
    fn start_pixel_sample(&mut self, pixel_index: u64, sample_index: u64) {
        HaltonSampler::start_pixel_sample(self, pixel_index, sample_index);
    }
}

impl Sampler for HaltonSampler {
    #[inline]
    fn start_stream(&mut self, stream: Stream) {
        self.stream = stream.index();
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        let d = self.dimension[self.stream];
        self.dimension[self.stream] = d + 1;
        let dim = if self.stream == 0 {
            d
        } else {
            OTHER_STREAM_OFFSET * self.stream + d
        };
        // The Cranley-Patterson offset of this (pixel, dimension), added modulo 1 on the
        // 2^-53 grid; then rounded down to a float in [0, 1) (f64 -> f32 rounding could
        // give 1.0).
        let x = self.halton.sample(self.index, dim);
        let offset = mix64(self.pixel_key ^ mix64(dim as u64 ^ 0x2545_f491_4f6c_dd1d)) >> 11;
        let fixed = ((x * (1u64 << 53) as f64) as u64).wrapping_add(offset) & ((1u64 << 53) - 1);
        unit_f32(fixed << 11)
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

/// Records the [`Stream::Camera`] numbers another sampler produces (a seed path), then
/// replays them with chosen dimensions overridden (a lattice member's explored numbers):
/// LQMC's "rebuild the prefix from these random numbers" (Alg. 1, lines 7-9).
///
/// In [`ReplaySampler::record`] mode every number is drawn from the inner sampler and kept;
/// in [`ReplaySampler::replay`] mode dimension `d` returns the override if one is set, else
/// the recorded value, else (past the recording) `0.5`. The buffers are reused across seeds:
/// no allocation once they have grown.
#[derive(Clone, Debug, Default)]
pub struct ReplaySampler<S> {
    inner: S,
    recorded: Vec<f32>,
    overrides: Vec<(usize, f32)>,
    recording: bool,
    cursor: usize,
}

impl<S: Sampler> ReplaySampler<S> {
    /// A replay sampler around `inner`.
    #[must_use]
    pub fn new(inner: S) -> Self {
        Self {
            inner,
            recorded: Vec::new(),
            overrides: Vec::new(),
            recording: false,
            cursor: 0,
        }
    }

    /// The inner sampler (to position it before [`ReplaySampler::record`]).
    pub fn inner_mut(&mut self) -> &mut S {
        &mut self.inner
    }

    /// Starts recording a new seed: subsequent numbers come from the inner sampler.
    pub fn record(&mut self) {
        self.recorded.clear();
        self.overrides.clear();
        self.recording = true;
        self.cursor = 0;
    }

    /// Starts replaying the recording with `overrides` (`(dimension, value)` pairs, values in
    /// `[0, 1)`) in place of the recorded numbers.
    pub fn replay(&mut self, overrides: impl IntoIterator<Item = (usize, f32)>) {
        self.overrides.clear();
        self.overrides.extend(overrides);
        self.recording = false;
        self.cursor = 0;
    }

    /// The recorded numbers of the seed.
    #[must_use]
    pub fn recorded(&self) -> &[f32] {
        &self.recorded
    }
}

impl<S: Sampler> Sampler for ReplaySampler<S> {
    #[inline]
    fn start_stream(&mut self, stream: Stream) {
        // The path tracers use one stream; a second one would break the dimension layout.
        debug_assert_eq!(stream, Stream::Camera);
        if self.recording {
            self.inner.start_stream(stream);
        }
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        let d = self.cursor;
        self.cursor += 1;
        if self.recording {
            let x = self.inner.next_1d();
            self.recorded.push(x);
            return x;
        }
        if let Some(&(_, v)) = self.overrides.iter().find(|(dim, _)| *dim == d) {
            return v;
        }
        self.recorded.get(d).copied().unwrap_or(0.5)
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::IndependentSampler;

    #[test]
    fn halton_pixel_sequences_are_stratified_and_keyed() {
        let mut s = HaltonSampler::new(1);
        // Base 2 in dimension 0: the first 8 points of a pixel fall one in each eighth
        // (of the torus: a rotation keeps that).
        let mut seen = [false; 8];
        for i in 0..8 {
            s.start_pixel_sample(5, i);
            let x = s.next_1d();
            assert!((0.0..1.0).contains(&x));
            seen[(x * 8.0) as usize] = true;
        }
        assert!(seen.iter().all(|&b| b));
        s.start_pixel_sample(5, 3);
        let a = s.next_2d();
        s.start_pixel_sample(6, 3);
        assert_ne!(a, s.next_2d());
    }

    /// The first `n` values of dimension `dim` (camera stream) of pixel `pixel`.
    fn pixel_values(s: &mut HaltonSampler, pixel: u64, dim: usize, n: u64) -> Vec<f64> {
        (0..n)
            .map(|i| {
                s.start_pixel_sample(pixel, i);
                let mut x = 0.0;
                for _ in 0..=dim {
                    x = f64::from(s.next_1d());
                }
                x
            })
            .collect()
    }

    /// pbrt-v4's elementary-interval test restated for Halton (bases 2 and 3 in dimensions 0
    /// and 1): for every `2^a 3^b <= 72`, the first `2^a 3^b` points of a pixel, taken relative
    /// to point 0 (Halton's point 0 is the origin for plain and Faure digits, so this undoes
    /// the pixel's rotation), put exactly one point in each `2^-a x 3^-b` box.
    #[test]
    fn first_points_of_a_pixel_fill_the_elementary_intervals() {
        for scrambling in [Scrambling::None, Scrambling::Faure] {
            let mut s = HaltonSampler::with_scrambling(7, scrambling);
            for pixel in [0u64, 17, 123_456] {
                let xs = pixel_values(&mut s, pixel, 0, 72);
                let ys = pixel_values(&mut s, pixel, 1, 72);
                for (a, b) in [(0u32, 0u32), (3, 0), (0, 2), (1, 1), (2, 2), (3, 2), (1, 3)] {
                    let (na, nb) = (2u64.pow(a), 3u64.pow(b));
                    let n = (na * nb) as usize;
                    let mut count = vec![0u32; n];
                    for i in 0..n {
                        let rel = |v: f64, v0: f64| (v - v0).rem_euclid(1.0);
                        // A relative tolerance of 1e-5 for the f32 rounding of points that
                        // lie on a box's lower edge.
                        let bx = ((rel(xs[i], xs[0]) + 1e-5) * na as f64) as u64 % na;
                        let by = ((rel(ys[i], ys[0]) + 1e-5) * nb as f64) as u64 % nb;
                        count[(by * na + bx) as usize] += 1;
                    }
                    assert!(
                        count.iter().all(|&c| c == 1),
                        "{scrambling:?} pixel {pixel}: 2^{a} x 3^{b} boxes {count:?}"
                    );
                }
            }
        }
    }

    /// What `qmc-faure` is for: in a dimension whose prime base (47, dimension 14) exceeds the
    /// pixel's 16 samples, plain Halton points cluster on an arc of length 16/47 (a circular
    /// gap of at least 31/47), Faure-permuted ones spread over the whole interval.
    #[test]
    fn faure_digits_spread_the_large_bases_plain_ones_cluster() {
        let max_gap = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            let wrap = v[0] + 1.0 - v[v.len() - 1];
            v.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max)
        };
        for pixel in [3u64, 99] {
            let plain = max_gap(pixel_values(&mut HaltonSampler::new(5), pixel, 14, 16));
            let faure = max_gap(pixel_values(
                &mut HaltonSampler::with_scrambling(5, Scrambling::Faure),
                pixel,
                14,
                16,
            ));
            assert!(plain >= 31.0 / 47.0 - 1e-6, "plain gap {plain}");
            assert!(faure < 0.25, "Faure gap {faure}");
        }
    }

    #[test]
    fn replay_returns_recording_with_overrides() {
        let mut r = ReplaySampler::new(IndependentSampler::new(4));
        r.inner_mut().start_pixel_sample(1, 2);
        r.record();
        let xs: Vec<f32> = (0..6).map(|_| r.next_1d()).collect();
        assert_eq!(r.recorded(), &xs[..]);
        r.replay([(2, 0.25), (4, 0.75)]);
        let ys: Vec<f32> = (0..7).map(|_| r.next_1d()).collect();
        assert_eq!(ys, [xs[0], xs[1], 0.25, xs[3], 0.75, xs[5], 0.5]);
    }
}
