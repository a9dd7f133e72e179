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
    /// A black image of the given size.
    #[must_use]
    pub fn new(width: usize, height: usize) -> Self {
        Self { width, height, pixels: vec![[0.0; 3]; width * height] }
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    #[must_use]
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }
}
