//! Float RGB images: the common currency of film output, EXR/PNG I/O and error metrics.

/// A linear float RGB image stored row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height` linear RGB pixels, row-major, top row first.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// The image box-downsampled to `width x height` (each output pixel the mean of its
    /// `(self.width / width) x (self.height / height)` block), or `None` unless both sides
    /// divide exactly — e.g. a 256 x 256 reference compared with a 64 x 64 render.
    #[must_use]
    pub fn box_downsample(&self, width: usize, height: usize) -> Option<Image> {
        if width == 0
            || height == 0
            || !self.width.is_multiple_of(width)
            || !self.height.is_multiple_of(height)
        {
            return None;
        }
        let (fx, fy) = (self.width / width, self.height / height);
        let n = (fx * fy) as f64;
        let mut out = Image::new(width, height);
        for y in 0..height {
            for x in 0..width {
                let mut acc = [0.0f64; 3];
                for dy in 0..fy {
                    for dx in 0..fx {
                        let p = self.pixels[(y * fy + dy) * self.width + x * fx + dx];
                        for c in 0..3 {
                            acc[c] += f64::from(p[c]);
                        }
                    }
                }
                out.pixels[y * width + x] = acc.map(|a| (a / n) as f32);
            }
        }
        Some(out)
    }

    /// A black image of the given size.
    #[must_use]
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    #[must_use]
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }
}

impl Image {
    /// Wraps `pixels` (row-major, top row first) as an image, or `None` if
    /// `pixels.len() != width * height`.
    #[must_use]
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<[f32; 3]>) -> Option<Self> {
        (width.checked_mul(height) == Some(pixels.len())).then_some(Self {
            width,
            height,
            pixels,
        })
    }

    /// Sets the pixel at column `x`, row `y` (row 0 is the top).
    pub fn set(&mut self, x: usize, y: usize, rgb: [f32; 3]) {
        self.pixels[y * self.width + x] = rgb;
    }

    /// Multiplies every channel of every pixel by `factor`.
    pub fn scale(&mut self, factor: f32) {
        for p in &mut self.pixels {
            for c in p.iter_mut() {
                *c *= factor;
            }
        }
    }

    /// The mean RGB over all pixels, accumulated in f64 (`[0; 3]` for an empty image).
    #[must_use]
    pub fn mean(&self) -> [f64; 3] {
        if self.pixels.is_empty() {
            return [0.0; 3];
        }
        let mut sum = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                sum[c] += f64::from(p[c]);
            }
        }
        let n = self.pixels.len() as f64;
        sum.map(|s| s / n)
    }

    /// The Rec. 709 luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B` of the pixel at (`x`, `y`).
    #[must_use]
    pub fn luminance(&self, x: usize, y: usize) -> f32 {
        luminance(self.get(x, y))
    }

    /// The mean Rec. 709 luminance over all pixels (0 for an empty image).
    #[must_use]
    pub fn mean_luminance(&self) -> f64 {
        let [r, g, b] = self.mean();
        0.2126 * r + 0.7152 * g + 0.0722 * b
    }

    /// The number of pixels with at least one NaN or infinite channel.
    #[must_use]
    pub fn count_nonfinite(&self) -> usize {
        self.pixels
            .iter()
            .filter(|p| !p.iter().all(|c| c.is_finite()))
            .count()
    }
}

/// The Rec. 709 luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B` of a linear RGB triple.
#[must_use]
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// Adds `other` into `image` pixel by pixel (same size: e.g. PSSMLT's direct pass plus its chains).
///
/// # Panics
/// If the sizes differ (both are rendered at the camera's size by construction).
pub fn add_into(image: &mut Image, other: &Image) {
    assert_eq!(
        (image.width, image.height),
        (other.width, other.height),
        "images added must have the same size"
    );
    for (a, b) in image.pixels.iter_mut().zip(&other.pixels) {
        for c in 0..3 {
            a[c] += b[c];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn add_into_sums_pixels() {
        let mut a = Image::new(2, 1);
        a.set(0, 0, [1.0, 2.0, 3.0]);
        let mut b = Image::new(2, 1);
        b.set(0, 0, [0.5, 0.5, 0.5]);
        b.set(1, 0, [1.0, 0.0, 0.0]);
        add_into(&mut a, &b);
        assert_eq!(a.get(0, 0), [1.5, 2.5, 3.5]);
        assert_eq!(a.get(1, 0), [1.0, 0.0, 0.0]);
    }

    #[test]
    fn box_downsample_averages_blocks() {
        let mut img = Image::new(4, 2);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [i as f32, 0.0, 1.0];
        }
        let d = img.box_downsample(2, 1).unwrap();
        assert_eq!(
            d.pixels,
            vec![[(0.0 + 1.0 + 4.0 + 5.0) / 4.0, 0.0, 1.0], [4.5, 0.0, 1.0]]
        );
        assert!(img.box_downsample(3, 1).is_none() && img.box_downsample(0, 1).is_none());
    }

    #[test]
    fn accessors_and_statistics() {
        assert!(Image::from_pixels(2, 2, vec![[0.0; 3]; 3]).is_none());
        let mut image = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [3.0, 2.0, 1.0]]).unwrap();
        assert_eq!(image.mean(), [2.0, 2.0, 2.0]);
        assert!((image.mean_luminance() - 2.0).abs() < 1e-12);
        assert!((image.luminance(0, 0) - (0.2126 + 1.4304 + 0.2166)).abs() < 1e-6);
        image.scale(0.5);
        assert_eq!(image.get(1, 0), [1.5, 1.0, 0.5]);
        assert_eq!(image.count_nonfinite(), 0);
        image.set(0, 0, [0.0, f32::NAN, 0.0]);
        assert_eq!(image.count_nonfinite(), 1);
        assert_eq!(Image::new(0, 3).mean(), [0.0; 3]);
    }
}
