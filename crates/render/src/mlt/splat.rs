//! Splats: the (raster position, RGB) contributions one path sample makes to the image, and
//! the per-job accumulation buffers MCMC integrators splat into.

use mcmc_core::{Observer, Sample};

/// One contribution of a path sample to the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Raster position in pixels, (0, 0) = top-left corner of the image.
    pub raster: [f32; 2],
    /// Radiance contribution (already MIS-weighted and divided by the sampling pdf).
    pub rgb: [f32; 3],
}

/// Rec. 709 luminance of a linear RGB triple.
#[inline]
#[must_use]
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// What a path sample evaluation produced: its splats. The MCMC target's scalar is the sum of
/// their luminances (Kelemen et al. 2002, section 3: `I(u)` = luminance of the contribution).
pub trait SplatPayload {
    /// The splats of this sample.
    fn splats(&self) -> &[Splat];
}

/// A full-image RGB accumulator in f64, one per work unit (job), merged in a fixed order so
/// the final image does not depend on the thread count.
#[derive(Clone, Debug)]
pub struct SplatBuffer {
    width: usize,
    height: usize,
    data: Vec<[f64; 3]>,
}

impl SplatBuffer {
    /// A zeroed buffer.
    #[must_use]
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![[0.0; 3]; width * height],
        }
    }

    /// Adds `rgb * weight` to the pixel containing `raster` (box filter of one pixel); splats
    /// outside the image or non-finite are ignored and return false.
    #[inline]
    pub fn add(&mut self, raster: [f32; 2], rgb: [f32; 3], weight: f64) -> bool {
        let (x, y) = (raster[0].floor(), raster[1].floor());
        if !(x >= 0.0 && y >= 0.0 && (x as usize) < self.width && (y as usize) < self.height) {
            return false;
        }
        let px = &mut self.data[y as usize * self.width + x as usize];
        for c in 0..3 {
            let v = f64::from(rgb[c]) * weight;
            if !v.is_finite() {
                return false;
            }
            px[c] += v;
        }
        true
    }

    /// Adds another buffer.
    pub fn merge(&mut self, other: &SplatBuffer) {
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
    }

    /// The accumulated values scaled by `scale`, as an image.
    #[must_use]
    pub fn to_image(&self, scale: f64) -> crate::image::Image {
        let mut img = crate::image::Image::new(self.width, self.height);
        for (p, d) in img.pixels.iter_mut().zip(&self.data) {
            *p = [
                (d[0] * scale) as f32,
                (d[1] * scale) as f32,
                (d[2] * scale) as f32,
            ];
        }
        img
    }
}

/// An [`Observer`] doing expected-value splatting (Veach 1997, section 11.3.3) into a
/// [`SplatBuffer`]: a sample with target value `f` and weight `w` adds `w * rgb / f` for each of
/// its splats. The global factor `b / mutations_per_pixel` is applied when the image is made.
#[derive(Debug)]
pub struct SplatObserver<'a> {
    /// The buffer receiving the splats.
    pub buffer: &'a mut SplatBuffer,
    /// Splats dropped because they were non-finite or outside the image.
    pub dropped: u64,
}

impl<S, P: SplatPayload> Observer<S, P> for SplatObserver<'_> {
    #[inline]
    fn splat(&mut self, sample: &Sample<S, P>, weight: f64) {
        if weight <= 0.0 || sample.log_density == f64::NEG_INFINITY {
            return;
        }
        let inv_f = (-sample.log_density).exp();
        for s in sample.payload.splats() {
            if !self.buffer.add(s.raster, s.rgb, weight * inv_f) {
                self.dropped += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buffer_ignores_outside_and_nonfinite() {
        let mut b = SplatBuffer::new(2, 2);
        assert!(b.add([0.5, 1.5], [1.0, 2.0, 3.0], 0.5));
        assert!(!b.add([2.0, 0.0], [1.0; 3], 1.0));
        assert!(!b.add([-0.1, 0.0], [1.0; 3], 1.0));
        assert!(!b.add([0.0, 0.0], [f32::NAN, 0.0, 0.0], 1.0));
        let img = b.to_image(2.0);
        assert_eq!(img.get(0, 1), [1.0, 2.0, 3.0]);
        assert_eq!(img.get(0, 0), [0.0, 0.0, 0.0]);
    }
}
