//! The Owen-scrambled Sobol sampler: per pixel, every draw of a path is a stratified
//! low-discrepancy sequence over the pixel's samples (measured against independent numbers in
//! `docs/performance.md`, "Owen-scrambled Sobol sampler for PT and BDPT").
//!
//! Construction: Burley 2020, "Practical Hash-based Owen Scrambling" (JCGT 9(4)), section 3
//! (Laine-Karras-style hash as a nested uniform scramble) and section 4 ("padding" by shuffled
//! independent realisations of the first Sobol dimensions). Reading chosen: every *draw* of a
//! stream (one [`Sampler::next_1d`] or [`Sampler::next_2d`] call) is its own padded
//! dimension, keyed by `(seed, pixel, stream, draw index)`; a 2D draw takes Sobol dimensions 0
//! and 1 of one shuffled index, so its two numbers form a scrambled (0, 2)-sequence in base 2,
//! and a 1D draw takes dimension 0 (a scrambled van der Corput sequence). Different draws are
//! shuffled independently, so pairs across draws are only stratified one by one (Burley's
//! padding); that is what the path tracers need (pixel position, lens, light sample, each BSDF
//! sample are each one draw).

use glam::Vec2;
use mcmc_core::seed::mix64;

use super::{PixelSampler, Sampler, Stream};

/// Bit `k` (from the least significant) of `reverse_bits(i)` multiplied in: the generator
/// matrix of Sobol's second dimension (primitive polynomial `x + 1`, `m_1 = 1`, so direction
/// number `m_k = m_{k-1} xor 2 m_{k-1}`; Joe and Kuo's table, dimension 2) as byte tables,
/// `SOBOL1[b][x]` the xor of the direction numbers of the set bits of byte `b` of the index.
const SOBOL1: [[u32; 256]; 4] = sobol1_tables();

const fn sobol1_tables() -> [[u32; 256]; 4] {
    let mut v = [0u32; 32];
    let mut d = 1u32 << 31;
    let mut k = 0;
    while k < 32 {
        v[k] = d;
        d ^= d >> 1;
        k += 1;
    }
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut x = 0;
        while x < 256 {
            let mut r = 0u32;
            let mut j = 0;
            while j < 8 {
                if (x >> j) & 1 == 1 {
                    r ^= v[b * 8 + j];
                }
                j += 1;
            }
            t[b][x] = r;
            x += 1;
        }
        b += 1;
    }
    t
}

/// Sobol's second dimension of index `i`, as a 32-bit binary fraction.
#[inline]
#[must_use]
pub fn sobol_dim1(i: u32) -> u32 {
    let b = i.to_le_bytes();
    SOBOL1[0][b[0] as usize]
        ^ SOBOL1[1][b[1] as usize]
        ^ SOBOL1[2][b[2] as usize]
        ^ SOBOL1[3][b[3] as usize]
}

/// A bijection of `u32` in which output bit `k` depends only on input bits `0..=k` (Burley
/// 2020, section 3, the improved Laine-Karras hash): applied to a bit-reversed binary fraction
/// it is a nested (Owen) scramble keyed by `seed`.
#[inline]
#[must_use]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen scramble of the 32-bit binary fraction `x` keyed by `seed` (Burley 2020,
/// `nested_uniform_scramble`): each bit is flipped by a function of the more significant bits,
/// so every elementary interval maps onto one of its own size.
#[inline]
#[must_use]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// Sample `i` of a 2D scrambled, shuffled Sobol sequence keyed by `key`: Sobol dimensions 0
/// and 1 of the Owen-shuffled index, each Owen-scrambled with its own seed, as 32-bit
/// fractions. For every `m`, samples `0..2^m` form a (0, m, 2)-net in base 2.
#[inline]
#[must_use]
pub fn sobol_2d(i: u32, key: u64) -> (u32, u32) {
    let j = owen_scramble(i, key as u32);
    // Dimension 0 is the bit reversal of the index: scrambling it is `laine_karras` of `j`.
    let x = laine_karras(j, (key >> 32) as u32).reverse_bits();
    // A third seed from the same key: the high half of an odd multiple (every bit of `key`
    // reaches it), not equal to either half in general.
    let y = owen_scramble(
        sobol_dim1(j),
        (key.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 32) as u32,
    );
    (x, y)
}

/// Sample `i` of a 1D scrambled, shuffled van der Corput sequence keyed by `key` (a 32-bit
/// fraction): samples `0..2^m` fall one in each interval `[k / 2^m, (k + 1) / 2^m)`.
#[inline]
#[must_use]
pub fn sobol_1d(i: u32, key: u64) -> u32 {
    let j = owen_scramble(i, key as u32);
    laine_karras(j, (key >> 32) as u32).reverse_bits()
}

/// The top 24 bits of a 32-bit fraction as an `f32` in `[0, 1)`.
#[inline]
fn unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Owen-scrambled Sobol points per pixel, every draw its own shuffled, scrambled sequence
/// (see the module documentation; Burley 2020).
///
/// Sample `i` of pixel `p` is point `i` of each draw's sequence, keyed by `(seed, p, stream,
/// draw)`: the first `2^m` samples of a pixel put one point in every elementary interval of
/// area `2^-m` of each 2D draw (the pixel position, the lens, a light sample, a BSDF sample),
/// and every point is uniform on its own, so every estimator stays unbiased. A pure function
/// of its keys, like [`super::IndependentSampler`], so images do not depend on the thread
/// count. Costs one `mix64`, three Laine-Karras hashes and four table lookups per 2D draw.
/// Sample indices wrap at `2^32`.
///
/// # Example
/// ```
/// use render::sampler::{PixelSampler, Sampler, SobolSampler};
/// let mut s = SobolSampler::new(1);
/// // The first four samples of a pixel: one pixel position in each quarter of the pixel.
/// let mut quarters = [0; 4];
/// for i in 0..4 {
///     s.start_pixel_sample(42, i);
///     let p = s.next_2d();
///     quarters[(p.x * 2.0) as usize * 2 + (p.y * 2.0) as usize] += 1;
/// }
/// assert_eq!(quarters, [1, 1, 1, 1]);
/// ```
#[derive(Clone, Debug)]
pub struct SobolSampler {
    seed_key: u64,
    pixel_key: u64,
    index: u32,
    stream: usize,
    dimension: [u64; 3],
}

impl SobolSampler {
    /// A sampler for master seed `seed`, positioned at pixel 0, sample 0.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        let mut s = Self {
            seed_key: mix64(seed ^ 0x2545_f491_4f6c_dd1d),
            pixel_key: 0,
            index: 0,
            stream: 0,
            dimension: [0; 3],
        };
        s.start_pixel_sample(0, 0);
        s
    }

    /// The key of the next draw of the current stream.
    #[inline]
    fn next_key(&mut self) -> u64 {
        let d = self.dimension[self.stream];
        self.dimension[self.stream] = d + 1;
        let draw = (((self.stream as u64) << 56) ^ d).wrapping_add(1);
        mix64(self.pixel_key ^ draw.wrapping_mul(0xd134_2543_de82_ef95))
    }
}

impl PixelSampler for SobolSampler {
    #[inline]
    fn start_pixel_sample(&mut self, pixel_index: u64, sample_index: u64) {
        self.pixel_key = mix64(self.seed_key ^ pixel_index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        self.index = sample_index as u32;
        self.stream = 0;
        self.dimension = [0; 3];
    }
}

impl Sampler for SobolSampler {
    #[inline]
    fn start_stream(&mut self, stream: Stream) {
        self.stream = stream.index();
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        let key = self.next_key();
        unit(sobol_1d(self.index, key))
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let key = self.next_key();
        let (x, y) = sobol_2d(self.index, key);
        Vec2::new(unit(x), unit(y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::IndependentSampler;

    /// Unscrambled Sobol dimension 1 of the first indices (Joe and Kuo's second dimension:
    /// 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8).
    #[test]
    fn second_dimension_matches_the_published_sequence() {
        let want = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, w) in want.iter().enumerate() {
            let x = f64::from(sobol_dim1(i as u32)) / 2f64.powi(32);
            assert_eq!(x, *w, "index {i}");
        }
    }

    #[test]
    fn the_scramble_is_a_bijection_that_keeps_elementary_intervals() {
        // Owen scrambling maps each interval [k 2^-m, (k+1) 2^-m) onto one of the same
        // size: the top m bits of the output depend only on the top m bits of the input.
        for seed in [1u32, 0xdead_beef, 7] {
            for m in [1u32, 4, 9] {
                let shift = 32 - m;
                let mut seen = vec![false; 1 << m];
                for k in 0..(1u32 << m) {
                    let lo = owen_scramble(k << shift, seed) >> shift;
                    let hi = owen_scramble((k << shift) | ((1 << shift) - 1), seed) >> shift;
                    assert_eq!(lo, hi, "seed {seed} m {m} k {k}");
                    assert!(!seen[lo as usize]);
                    seen[lo as usize] = true;
                }
            }
        }
    }

    /// pbrt-v4's elementary-interval test: the first `2^m` points of a pixel's draw put
    /// exactly one point in every box `2^-a x 2^-b`, `a + b = m`.
    fn elementary_intervals_hold<S: PixelSampler>(
        sampler: &mut S,
        pixel: u64,
        draw: usize,
        m: u32,
    ) -> bool {
        let n = 1usize << m;
        let points: Vec<Vec2> = (0..n)
            .map(|i| {
                sampler.start_pixel_sample(pixel, i as u64);
                for _ in 0..draw {
                    sampler.next_2d();
                }
                sampler.next_2d()
            })
            .collect();
        (0..=m).all(|a| {
            let b = m - a;
            let mut count = vec![0u32; n];
            for p in &points {
                let x = (p.x * (1u32 << a) as f32) as usize;
                let y = (p.y * (1u32 << b) as f32) as usize;
                count[(x << b) | y] += 1;
            }
            count.iter().all(|&c| c == 1)
        })
    }

    #[test]
    fn every_2d_draw_of_a_pixel_fills_the_elementary_intervals() {
        let mut s = SobolSampler::new(3);
        for pixel in [0u64, 17, 12_345] {
            for draw in [0usize, 1, 7] {
                for m in 0..=10 {
                    assert!(
                        elementary_intervals_hold(&mut s, pixel, draw, m),
                        "pixel {pixel} draw {draw} m {m}"
                    );
                }
            }
        }
    }

    #[test]
    fn negative_control_independent_numbers_fail_the_elementary_interval_test() {
        let mut s = IndependentSampler::new(3);
        let failed = (2..=8)
            .filter(|&m| !elementary_intervals_hold(&mut s, 5, 0, m))
            .count();
        // Independent points fill all 2^m boxes of one shape with probability n!/n^n.
        assert_eq!(failed, 7);
    }

    #[test]
    fn every_1d_draw_is_stratified_and_streams_are_separate() {
        let mut s = SobolSampler::new(9);
        let m = 8;
        for stream in Stream::ALL {
            let mut seen = vec![0u32; 1 << m];
            for i in 0..(1u64 << m) {
                s.start_pixel_sample(3, i);
                s.start_stream(stream);
                s.next_2d();
                let x = s.next_1d();
                seen[(x * (1 << m) as f32) as usize] += 1;
            }
            assert!(seen.iter().all(|&c| c == 1), "{stream:?}");
        }
        // Streams and draws are keyed apart: the same index gives different numbers.
        s.start_pixel_sample(3, 0);
        let cam = s.next_1d();
        s.start_stream(Stream::Light);
        assert_ne!(cam, s.next_1d());
    }

    #[test]
    fn pixels_and_seeds_get_different_point_sets() {
        let first = |seed: u64, pixel: u64| {
            let mut s = SobolSampler::new(seed);
            s.start_pixel_sample(pixel, 0);
            s.next_2d()
        };
        assert_ne!(first(1, 0), first(1, 1));
        assert_ne!(first(1, 0), first(2, 0));
        assert_eq!(first(1, 5), first(1, 5));
    }

    /// Randomised QMC is unbiased: over independently scrambled pixels, the mean of a
    /// 16-point estimate of a discontinuous integral (a quarter disc, area pi/4) matches the
    /// integral within 5 standard errors of the mean across pixels.
    fn unbiased(estimates: &[f64], truth: f64) -> bool {
        let n = estimates.len() as f64;
        let mean = estimates.iter().sum::<f64>() / n;
        let var = estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean - truth).abs() <= 5.0 * (var / n).sqrt()
    }

    fn quarter_disc_estimates(mut draw: impl FnMut(u64, u64) -> Vec2) -> Vec<f64> {
        (0..4000u64)
            .map(|pixel| {
                let hits = (0..16u64)
                    .filter(|&i| draw(pixel, i).length_squared() < 1.0)
                    .count();
                hits as f64 / 16.0
            })
            .collect()
    }

    #[test]
    fn scrambled_estimates_are_unbiased_and_less_noisy_than_independent_ones() {
        let truth = std::f64::consts::FRAC_PI_4;
        let mut s = SobolSampler::new(11);
        let sobol = quarter_disc_estimates(|p, i| {
            s.start_pixel_sample(p, i);
            s.next_2d()
        });
        assert!(unbiased(&sobol, truth));
        let mut r = IndependentSampler::new(11);
        let independent = quarter_disc_estimates(|p, i| {
            r.start_pixel_sample(p, i);
            r.next_2d()
        });
        assert!(unbiased(&independent, truth));
        let var = |e: &[f64]| {
            let m = e.iter().sum::<f64>() / e.len() as f64;
            e.iter().map(|x| (x - m).powi(2)).sum::<f64>() / e.len() as f64
        };
        // Independent: p(1-p)/16 = 0.0105. A scrambled (0, 4, 2)-net's variance on an
        // indicator with a smooth boundary falls as n^(-3/2) instead of n^(-1) (Owen 1997), an
        // extra factor of about n^(-1/2) = 1/4 at the 16 samples here; each variance has a
        // relative standard error of sqrt(2 / 4000) = 2.2 %, so half is far outside the noise
        // on both sides.
        assert!(
            var(&sobol) < 0.5 * var(&independent),
            "{} vs {}",
            var(&sobol),
            var(&independent)
        );
    }

    #[test]
    fn negative_control_unscrambled_points_are_biased() {
        // The same points in every pixel (plain Sobol, no scrambling) give the same biased
        // estimate everywhere: the unbiasedness check must reject them.
        let truth = std::f64::consts::FRAC_PI_4;
        let plain = quarter_disc_estimates(|_, i| {
            let i = i as u32;
            let x = f64::from(i.reverse_bits()) / 2f64.powi(32);
            let y = f64::from(sobol_dim1(i)) / 2f64.powi(32);
            Vec2::new(x as f32, y as f32)
        });
        assert!(!unbiased(&plain, truth));
    }
}
