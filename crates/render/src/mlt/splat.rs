//! A full-image f64 RGB accumulator (BDPT's light-tracing splats).


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
