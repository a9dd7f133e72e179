//! The sampler interface every integrator draws its random numbers from, the counter-based
//! independent sampler, and the Owen-scrambled Sobol sampler ([`sobol`]) PT and BDPT can use
//! instead ([`SamplerKind`]).
//!
//! An integrator is a deterministic function of the numbers it draws (pbrt's separation), so the
//! same path construction code runs under [`IndependentSampler`] and under primary-sample-space
//! Markov chains. Numbers are drawn in *streams* ([`Stream`]): a PSS sampler keeps them apart so
//! that, e.g., mutating the camera subpath does not shift the light subpath's numbers.

use std::fmt;
use std::str::FromStr;

use glam::Vec2;
use mcmc_core::seed::mix64;

pub mod sobol;
pub use sobol::SobolSampler;

/// A stream of primary samples. Bidirectional integrators draw camera-subpath numbers from
/// [`Stream::Camera`], light-subpath numbers from [`Stream::Light`] and connection / strategy
/// choices from [`Stream::Connection`] (pbrt-v4's `MLTSampler` streams).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stream {
    /// Camera subpath (pixel position, lens, time, camera-side bounces).
    Camera,
    /// Light subpath (light choice, emission position and direction, light-side bounces).
    Light,
    /// Connection and strategy choices.
    Connection,
}

impl Stream {
    /// All streams, in index order.
    pub const ALL: [Stream; 3] = [Stream::Camera, Stream::Light, Stream::Connection];

    /// The stream's index (0, 1, 2).
    #[inline]
    #[must_use]
    pub const fn index(self) -> usize {
        match self {
            Stream::Camera => 0,
            Stream::Light => 1,
            Stream::Connection => 2,
        }
    }
}

/// A source of uniform random numbers in `[0, 1)` for integrators.
///
/// Integrators are generic over `S: Sampler + ?Sized`, call [`Sampler::start_stream`] before
/// drawing from a stream, and never own a random number generator.
pub trait Sampler {
    /// Subsequent numbers come from `stream`, continuing where that stream left off for the
    /// current sample (a sampler may ignore streams and use one sequence).
    fn start_stream(&mut self, stream: Stream);
    /// The next uniform number in `[0, 1)`.
    fn next_1d(&mut self) -> f32;
    /// The next two uniform numbers in `[0, 1)^2`.
    fn next_2d(&mut self) -> Vec2;
    /// The next uniform number, which the caller consumes as a *discrete* choice (strategy,
    /// lobe, light, Russian roulette) or not at all (the lens of a pinhole camera, the time
    /// of a static scene). The same number as [`Sampler::next_1d`]; a primary-sample-space
    /// sampler tags it, so that Langevin steps keep it fixed and differentiate only the
    /// continuous numbers (`pss::PssState::next_discrete`).
    #[inline]
    fn next_1d_discrete(&mut self) -> f32 {
        self.next_1d()
    }
    /// The next two numbers as [`Sampler::next_2d`] (the same numbers: a stratified sampler
    /// keeps its 2-D pattern), consumed as [`Sampler::next_1d_discrete`] (an unused direction
    /// or lens sample).
    #[inline]
    fn next_2d_discrete(&mut self) -> Vec2 {
        self.next_2d()
    }
}

impl<S: Sampler + ?Sized> Sampler for &mut S {
    #[inline]
    fn start_stream(&mut self, stream: Stream) {
        (**self).start_stream(stream);
    }
    #[inline]
    fn next_1d(&mut self) -> f32 {
        (**self).next_1d()
    }
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        (**self).next_2d()
    }
    #[inline]
    fn next_1d_discrete(&mut self) -> f32 {
        (**self).next_1d_discrete()
    }
    #[inline]
    fn next_2d_discrete(&mut self) -> Vec2 {
        (**self).next_2d_discrete()
    }
}

/// A sampler that draws the numbers of one pixel sample at a time: the per-pixel samplers of
/// PT and BDPT ([`IndependentSampler`], [`SobolSampler`], the Halton samplers).
pub trait PixelSampler: Sampler {
    /// Starts sample `sample_index` of pixel `pixel_index` (e.g. `y * width + x`): resets every
    /// stream to its first number and selects [`Stream::Camera`].
    fn start_pixel_sample(&mut self, pixel_index: u64, sample_index: u64);
}

/// Which per-pixel sampler PT, BDPT and PSSMLT's direct-lighting pass draw from (`--sampler`).
///
/// ```
/// use render::sampler::SamplerKind;
/// assert_eq!("sobol".parse::<SamplerKind>(), Ok(SamplerKind::Sobol));
/// assert_eq!(SamplerKind::default(), SamplerKind::Independent);
/// assert!("halton".parse::<SamplerKind>().is_err());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// [`IndependentSampler`]: independent uniform numbers (the default).
    #[default]
    Independent,
    /// [`SobolSampler`]: Owen-scrambled Sobol points, stratified per pixel and per draw.
    Sobol,
}

impl SamplerKind {
    /// The command-line names, in order.
    pub const NAMES: [&'static str; 2] = ["independent", "sobol"];
}

impl fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Sobol => "sobol",
        })
    }
}

impl FromStr for SamplerKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "independent" => Ok(SamplerKind::Independent),
            "sobol" => Ok(SamplerKind::Sobol),
            _ => Err(format!(
                "unknown sampler '{s}' (allowed: {})",
                SamplerKind::NAMES.join(", ")
            )),
        }
    }
}

/// Maps the top 24 bits of `bits` to a float in `[0, 1)` (exactly representable, never 1).
#[inline]
#[must_use]
pub fn unit_f32(bits: u64) -> f32 {
    (bits >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// A counter-based independent sampler: the number of dimension `d` of stream `s` of sample
/// `i` of pixel `p` is a hash of `(seed, p, i, s, d)`.
///
/// Because every number is a pure function of its key, the image does not depend on which
/// thread renders which pixel, nor on the order in which pixels are rendered.
///
/// # Example
/// ```
/// use render::sampler::{IndependentSampler, Sampler, Stream};
/// let mut a = IndependentSampler::new(7);
/// a.start_pixel_sample(12, 3);
/// let x = a.next_1d();
/// let mut b = IndependentSampler::new(7);
/// b.start_pixel_sample(12, 3);
/// assert_eq!(x, b.next_1d());
/// b.start_stream(Stream::Light);
/// assert!((0.0..1.0).contains(&b.next_1d()));
/// ```
#[derive(Clone, Debug)]
pub struct IndependentSampler {
    seed_key: u64,
    sample_key: u64,
    stream: usize,
    dimension: [u64; 3],
}

impl IndependentSampler {
    /// A sampler for master seed `seed`, positioned at pixel 0, sample 0.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        let seed_key = mix64(seed ^ 0x5851_f42d_4c95_7f2d);
        let mut s = Self {
            seed_key,
            sample_key: 0,
            stream: 0,
            dimension: [0; 3],
        };
        s.start_pixel_sample(0, 0);
        s
    }

    /// Starts sample `sample_index` of pixel `pixel_index` (e.g. `y * width + x`): resets every
    /// stream to its first dimension and selects [`Stream::Camera`].
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel_index: u64, sample_index: u64) {
        self.sample_key = mix64(
            self.seed_key
                ^ mix64(pixel_index.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ mix64(sample_index)),
        );
        self.stream = 0;
        self.dimension = [0; 3];
    }

    #[inline]
    fn next_bits(&mut self) -> u64 {
        let d = self.dimension[self.stream];
        self.dimension[self.stream] = d + 1;
        let key = ((self.stream as u64) << 56) ^ d;
        mix64(self.sample_key ^ mix64(key.wrapping_add(0x632b_e59b_d9b4_e019)))
    }
}

impl PixelSampler for IndependentSampler {
    #[inline]
    fn start_pixel_sample(&mut self, pixel_index: u64, sample_index: u64) {
        IndependentSampler::start_pixel_sample(self, pixel_index, sample_index);
    }
}

impl Sampler for IndependentSampler {
    #[inline]
    fn start_stream(&mut self, stream: Stream) {
        self.stream = stream.index();
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        unit_f32(self.next_bits())
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        // One hash gives both numbers: 24 bits each from the two halves.
        let bits = self.next_bits();
        Vec2::new(unit_f32(bits), unit_f32(bits << 24))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_numbers_different_key_different_numbers() {
        let mut a = IndependentSampler::new(1);
        let mut b = IndependentSampler::new(1);
        a.start_pixel_sample(5, 9);
        b.start_pixel_sample(5, 9);
        for _ in 0..10 {
            assert_eq!(a.next_1d(), b.next_1d());
            assert_eq!(a.next_2d(), b.next_2d());
        }
        let mut c = IndependentSampler::new(2);
        c.start_pixel_sample(5, 9);
        a.start_pixel_sample(5, 9);
        assert_ne!(a.next_1d(), c.next_1d());
        a.start_pixel_sample(6, 9);
        b.start_pixel_sample(5, 10);
        assert_ne!(a.next_1d(), b.next_1d());
    }

    #[test]
    fn streams_are_independent_of_interleaving() {
        let mut a = IndependentSampler::new(3);
        a.start_pixel_sample(0, 0);
        let cam0 = a.next_1d();
        a.start_stream(Stream::Light);
        let light0 = a.next_1d();
        a.start_stream(Stream::Camera);
        let cam1 = a.next_1d();

        let mut b = IndependentSampler::new(3);
        b.start_pixel_sample(0, 0);
        b.start_stream(Stream::Light);
        assert_eq!(b.next_1d(), light0);
        b.start_stream(Stream::Camera);
        assert_eq!(b.next_1d(), cam0);
        assert_eq!(b.next_1d(), cam1);
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut s = IndependentSampler::new(11);
        let n = 100_000;
        let mut sum = 0.0f64;
        let mut sum2 = [0.0f64; 2];
        for i in 0..n {
            s.start_pixel_sample(i, 0);
            let x = s.next_1d();
            let v = s.next_2d();
            assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&v.x));
            assert!((0.0..1.0).contains(&v.y));
            sum += f64::from(x);
            sum2[0] += f64::from(v.x);
            sum2[1] += f64::from(v.y);
        }
        // Standard error of the mean of U(0,1) over 1e5 draws is 0.29/316 = 9e-4: 5 sigma.
        for m in [sum, sum2[0], sum2[1]] {
            assert!((m / n as f64 - 0.5).abs() < 5e-3, "{m}");
        }
    }

    #[test]
    fn value_stability() {
        let mut s = IndependentSampler::new(0);
        s.start_pixel_sample(0, 0);
        let first = s.next_1d();
        let mut t = IndependentSampler::new(0);
        assert_eq!(first, t.next_1d());
    }
}
