//! Splats: where a sample's contribution lands on the image, the sink that accumulates them,
//! and the expected-value splatting observer.

use crate::kernel::Observer;
use crate::target::Sample;

/// One contribution of a sample to the image: a raster position and an RGB value (for a
/// renderer: the path's MIS-weighted contribution divided by its sampling density).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Splat {
    /// Raster position in pixels, (0, 0) = top-left corner of the image.
    pub raster: [f32; 2],
    /// The contribution.
    pub rgb: [f32; 3],
}

/// A target payload that says where the evaluated sample contributes: its splats. The MCMC
/// target's density is usually the summed luminance of these (Kelemen et al. 2002, section 3).
pub trait SplatPayload {
    /// The splats of this sample.
    fn splats(&self) -> &[Splat];
}

impl SplatPayload for Vec<Splat> {
    fn splats(&self) -> &[Splat] {
        self
    }
}

impl SplatPayload for Option<Splat> {
    fn splats(&self) -> &[Splat] {
        self.as_slice()
    }
}

/// Where a render loop's splats accumulate: the caller's film. The loop asks the sink factory
/// for one sink per job and merges them in job order, so a sink that owns its buffer (a
/// [`SplatGrid`]) needs no locks or atomics; a handle to one shared, order-independent grid
/// ([`super::ExactSplatGrid`]) keeps one image of memory for any number of jobs.
pub trait SplatSink: Send {
    /// Adds `weight * splat.rgb` where `splat.raster` lands; returns false if the splat was
    /// dropped (outside the image, or non-finite).
    fn add(&mut self, splat: &Splat, weight: f64) -> bool;
    /// Adds a splat of a candidate a multi-stage kernel proposed at stage `stage`
    /// ([`crate::Observer::splat_at_stage`]); the default is [`SplatSink::add`]. A sink that
    /// keeps a separate layer of second-stage splats (a delayed-rejection stage map) overrides
    /// it.
    fn add_at_stage(&mut self, splat: &Splat, weight: f64, stage: u8) -> bool {
        let _ = stage;
        self.add(splat, weight)
    }
    /// Adds everything `other` accumulated.
    fn merge(&mut self, other: &Self);
}

/// A full-image RGB accumulator in f64 with a one-pixel box filter: a ready [`SplatSink`] for
/// renderers that do not bring their own film (and the splat layer of `render`'s film).
#[derive(Clone, Debug, PartialEq)]
pub struct SplatGrid {
    width: usize,
    height: usize,
    data: Vec<[f64; 3]>,
}

impl SplatGrid {
    /// A zeroed `width` x `height` grid.
    #[must_use]
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![[0.0; 3]; width * height],
        }
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> usize {
        self.height
    }

    /// Adds `rgb * weight` to the pixel containing `raster`; splats outside the image, with
    /// a non-finite product (NaN or infinite), or that would make the pixel's sum overflow to
    /// infinity are ignored and return false (the caller counts them as dropped).
    #[inline]
    pub fn add_rgb(&mut self, raster: [f32; 2], rgb: [f32; 3], weight: f64) -> bool {
        let (x, y) = (raster[0].floor(), raster[1].floor());
        if !(x >= 0.0 && y >= 0.0 && (x as usize) < self.width && (y as usize) < self.height) {
            return false;
        }
        let v = rgb.map(|c| f64::from(c) * weight);
        if !v.iter().all(|c| c.is_finite()) {
            return false;
        }
        let px = &mut self.data[y as usize * self.width + x as usize];
        let sum = [px[0] + v[0], px[1] + v[1], px[2] + v[2]];
        if !sum.iter().all(|c| c.is_finite()) {
            return false;
        }
        *px = sum;
        true
    }

    /// The accumulated value of pixel `(x, y)` (row-major, top row first).
    #[must_use]
    pub fn get(&self, x: usize, y: usize) -> [f64; 3] {
        self.data[y * self.width + x]
    }

    /// All pixels, row-major, top row first.
    #[must_use]
    pub fn pixels(&self) -> &[[f64; 3]] {
        &self.data
    }

    /// The pixels multiplied by `scale`, as f32 RGB (row-major); see
    /// [`SplatGrid::to_rgb32_checked`] for pixels that do not fit an f32 (here: black).
    #[must_use]
    pub fn to_rgb32(&self, scale: f64) -> Vec<[f32; 3]> {
        self.to_rgb32_checked(scale).0
    }

    /// The pixels multiplied by `scale`, as f32 RGB (row-major), and the number of pixels
    /// dropped (made black) because a channel is not a finite f32: the scaled f64 value is
    /// NaN, infinite, or finite but above `f32::MAX` (about 3.4e38, which would turn into an
    /// infinity in f32 — e.g. an emitter of radiance 3e38 seen directly). Every pixel value
    /// returned is finite.
    #[must_use]
    pub fn to_rgb32_checked(&self, scale: f64) -> (Vec<[f32; 3]>, u64) {
        let mut dropped = 0;
        let pixels = self
            .data
            .iter()
            .map(|p| {
                let v = p.map(|c| (c * scale) as f32);
                if v.iter().all(|c| c.is_finite()) {
                    v
                } else {
                    dropped += 1;
                    [0.0; 3]
                }
            })
            .collect();
        (pixels, dropped)
    }
}

impl SplatSink for SplatGrid {
    #[inline]
    fn add(&mut self, splat: &Splat, weight: f64) -> bool {
        self.add_rgb(splat.raster, splat.rgb, weight)
    }

    fn merge(&mut self, other: &Self) {
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
    }
}

/// An [`Observer`] doing expected-value splatting (Veach 1997, section 11.3.3) into a
/// [`SplatSink`]: a sample with target density `f` reported with weight `w` adds
/// `w * rgb / f` for each of its splats. The global factor `b / mutations` (and the caller's
/// pixel measure) is applied when the image is made.
#[derive(Debug)]
pub struct SplatObserver<'a, K> {
    /// The sink receiving the splats.
    pub sink: &'a mut K,
    /// Splats the sink dropped (non-finite or outside the image).
    pub dropped: u64,
    /// Extra factor of every splat (1 unless set: the per-target chain weight of
    /// [`super::ChainAllocation::PerTarget`]).
    weight: f64,
}

impl<'a, K> SplatObserver<'a, K> {
    /// An observer splatting into `sink`.
    pub fn new(sink: &'a mut K) -> Self {
        Self {
            sink,
            dropped: 0,
            weight: 1.0,
        }
    }

    /// Multiplies every following splat by `weight` (the render loop sets it per chain).
    pub fn set_weight(&mut self, weight: f64) {
        self.weight = weight;
    }
}

impl<S, P: SplatPayload, K: SplatSink> Observer<S, P> for SplatObserver<'_, K> {
    #[inline]
    fn splat(&mut self, sample: &Sample<S, P>, weight: f64) {
        self.splat_at_stage(sample, weight, 1);
    }

    #[inline]
    fn splat_at_stage(&mut self, sample: &Sample<S, P>, weight: f64, stage: u8) {
        if weight == 0.0 || sample.log_density == f64::NEG_INFINITY {
            return;
        }
        // `* 1.0` is exact: the joint allocation's images are unchanged bit for bit.
        let inv_f = (-sample.log_density).exp() * self.weight;
        for s in sample.payload.splats() {
            let added = if stage == 1 {
                self.sink.add(s, weight * inv_f)
            } else {
                self.sink.add_at_stage(s, weight * inv_f, stage)
            };
            if !added {
                self.dropped += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_ignores_outside_and_nonfinite() {
        let mut g = SplatGrid::new(2, 2);
        assert!(g.add_rgb([0.5, 1.5], [1.0, 2.0, 3.0], 0.5));
        assert!(!g.add_rgb([2.0, 0.0], [1.0; 3], 1.0));
        assert!(!g.add_rgb([-0.1, 0.0], [1.0; 3], 1.0));
        assert!(!g.add_rgb([0.0, 0.0], [f32::NAN, 0.0, 0.0], 1.0));
        assert_eq!(g.get(0, 1), [0.5, 1.0, 1.5]);
        assert_eq!(g.to_rgb32(2.0)[2], [1.0, 2.0, 3.0]);
        let mut h = SplatGrid::new(2, 2);
        h.merge(&g);
        h.merge(&g);
        assert_eq!(h.get(0, 1), [1.0, 2.0, 3.0]);
    }

    /// Infinite values never reach the image: an infinite splat, a sum that would overflow
    /// f64, and a finite f64 pixel above `f32::MAX` are all dropped and counted.
    #[test]
    fn infinite_values_are_dropped_and_counted() {
        let mut g = SplatGrid::new(3, 1);
        assert!(!g.add_rgb([0.5, 0.5], [f32::INFINITY, 0.0, 0.0], 1.0));
        // Finite f32 times a finite weight that overflows f64.
        assert!(!g.add_rgb([0.5, 0.5], [f32::MAX; 3], f64::MAX));
        assert_eq!(g.get(0, 0), [0.0; 3]);
        // Two finite splats whose sum would be infinite: the second is dropped.
        assert!(g.add_rgb([1.5, 0.5], [1.0; 3], 1e308));
        assert!(!g.add_rgb([1.5, 0.5], [1.0; 3], 1e308));
        assert_eq!(g.get(1, 0), [1e308; 3]);
        // A finite f64 above f32::MAX: pixel 2 holds 3e38 * 2 = 6e38 after scaling.
        assert!(g.add_rgb([2.5, 0.5], [3e38, 1.0, 1.0], 1.0));
        let (px, dropped) = g.to_rgb32_checked(2.0);
        assert_eq!(dropped, 2, "pixels 1 and 2 do not fit an f32");
        assert!(px.iter().flatten().all(|c| c.is_finite()), "{px:?}");
        assert_eq!(px[1], [0.0; 3]);
        assert_eq!(px[2], [0.0; 3]);
        // Control: at scale 1, pixel 2 fits (3e38 < f32::MAX).
        let (px, dropped) = g.to_rgb32_checked(1e-300);
        assert_eq!(dropped, 0);
        assert!(px[1][0] > 0.0);
        let (px, dropped) = g.to_rgb32_checked(1.0);
        assert_eq!(dropped, 1);
        assert_eq!(px[2], [3e38, 1.0, 1.0]);
        assert_eq!(g.to_rgb32(1.0), px);
    }

    #[test]
    fn observer_divides_by_the_density() {
        let mut g = SplatGrid::new(1, 1);
        let mut obs = SplatObserver::new(&mut g);
        let sample = Sample {
            state: 0.0f64,
            log_density: 2.0f64.ln(),
            payload: Some(Splat {
                raster: [0.5, 0.5],
                rgb: [4.0; 3],
            }),
        };
        Observer::<f64, Option<Splat>>::splat(&mut obs, &sample, 0.25);
        assert_eq!(g.get(0, 0), [0.5; 3]);
    }
}
