//! The film: reconstruction filters, per-tile sample accumulation and full-image splat layers,
//! merged in a fixed order so that an image does not depend on the thread count.
//!
//! * **Pixel samples** (PT, BDPT's `t >= 2` strategies) go to a [`FilmTile`]: each sample is
//!   splatted to every pixel within the filter radius with weight `f(pixel centre - p)`, and
//!   the final pixel is `Σ w L / Σ w` (pbrt-v3's weighted reconstruction). A tile buffer covers
//!   its pixels plus a margin of the filter radius.
//! * **Splats** anywhere on the image (light tracing, MCMC) go to an
//!   `mcmc_core::render_loop::SplatGrid` (box filter: the pixel a splat lands in; one
//!   accumulation path for every splatting integrator and for outside renderers) and are added
//!   to the image as `scale · Σ L`.
//! * Work units (tiles, or a fixed number of jobs for splat layers) are merged with
//!   [`Film::merge_tile`] / [`Film::merge_splats`] in a fixed order by the caller. All sums
//!   are f64.
//! * Non-finite samples are counted and dropped, never splatted.

use glam::{UVec2, Vec2, Vec3};
use mcmc_core::render_loop::{ExactSplatGrid, SplatGrid, DEFAULT_FRACTION_BITS};

use crate::image::Image;

/// A pixel reconstruction filter, separable, with its support radius in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// `1` inside `|dx|, |dy| < radius`. `radius = 0.5` (the default) is one pixel: each
    /// sample contributes only to the pixel it falls in.
    Box {
        /// Half-width in pixels.
        radius: f32,
    },
    /// `(1 - |dx|/radius)(1 - |dy|/radius)`, zero outside. The usual radius is 1 pixel (a
    /// sample reaches the 2x2 pixels whose centres are within one pixel).
    Tent {
        /// Radius in pixels.
        radius: f32,
    },
}

impl Default for Filter {
    fn default() -> Self {
        Self::BOX
    }
}

impl Filter {
    /// One-pixel box filter (radius 0.5).
    pub const BOX: Filter = Filter::Box { radius: 0.5 };
    /// Tent filter of radius 1 pixel.
    pub const TENT: Filter = Filter::Tent { radius: 1.0 };

    /// The support radius in pixels (clamped to at least 1e-3).
    #[inline]
    #[must_use]
    pub fn radius(&self) -> f32 {
        match *self {
            Filter::Box { radius } | Filter::Tent { radius } => {
                if radius.is_finite() {
                    radius.max(1e-3)
                } else {
                    0.5
                }
            }
        }
    }

    /// The filter value at offset `d = pixel centre - sample position` (pixels). The box is
    /// half-open, `-r < d <= r` per axis, so that with `r = 0.5` a sample at `p` lands in
    /// exactly the pixel `floor(p)`, including on pixel boundaries.
    #[inline]
    #[must_use]
    pub fn evaluate(&self, d: Vec2) -> f32 {
        let r = self.radius();
        match self {
            Filter::Box { .. } => {
                let inside = |v: f32| -r < v && v <= r;
                if inside(d.x) && inside(d.y) {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Tent { .. } => {
                let d = d.abs();
                if d.x >= r || d.y >= r {
                    return 0.0;
                }
                (1.0 - d.x / r) * (1.0 - d.y / r)
            }
        }
    }

    /// `∫∫ f(x, y) dx dy` over the plane: `4 r²` (box) or `r²` (tent).
    #[must_use]
    pub fn integral(&self) -> f32 {
        let r = self.radius();
        match self {
            Filter::Box { .. } => 4.0 * r * r,
            Filter::Tent { .. } => r * r,
        }
    }

    /// The pixel index range `[lo, hi]` along one axis whose centres `c` satisfy
    /// `-r < c - p <= r` (a superset of the pixels with a nonzero weight).
    #[inline]
    fn pixel_range(&self, p: f32) -> (i64, i64) {
        let r = self.radius();
        let lo = (p - 0.5 - r).floor() as i64 + 1;
        let hi = (p - 0.5 + r).floor() as i64;
        (lo, hi)
    }
}

/// The raster position of a sample of pixel `pixel` drawn with `u` in `[0, 1)^2`: `pixel + u`,
/// kept inside the pixel. In f32, `x + u` rounds up to `x + 1` when `1 - u` is at most half an
/// ulp of `x`: with the samplers' 24-bit uniforms, for every `x >= 1` (probability about
/// `2^(e-24)` per axis, `2^e <= x < 2^(e+1)`); such a sample would land on the next pixel's
/// edge, or off the image, its tile or its band, where [`FilmTile::add_sample`] adds it
/// nowhere (a lost sample). The clamp moves it by less than one ulp.
#[inline]
#[must_use]
pub fn pixel_sample_position(pixel: UVec2, u: Vec2) -> Vec2 {
    let lo = pixel.as_vec2();
    // `lo + 1` is exact (pixel indices are far below 2^24); its predecessor floors to `lo`.
    let last = Vec2::new((lo.x + 1.0).next_down(), (lo.y + 1.0).next_down());
    (lo + u).min(last)
}

/// A rectangle of pixels `[x0, x1) x [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub x0: usize,
    /// First row.
    pub y0: usize,
    /// One past the last column.
    pub x1: usize,
    /// One past the last row.
    pub y1: usize,
}

impl PixelRect {
    /// Number of pixels.
    #[must_use]
    pub fn area(&self) -> usize {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }
}

/// The image's tiles of `tile_size x tile_size` pixels (smaller at the right and bottom
/// edges), in row-major order: the fixed work units and merge order of a render.
#[must_use]
pub fn tiles(width: usize, height: usize, tile_size: usize) -> Vec<PixelRect> {
    let t = tile_size.max(1);
    let mut out = Vec::new();
    for y0 in (0..height).step_by(t) {
        for x0 in (0..width).step_by(t) {
            out.push(PixelRect {
                x0,
                y0,
                x1: (x0 + t).min(width),
                y1: (y0 + t).min(height),
            });
        }
    }
    out
}

/// Accumulated pixel samples of one tile, including a margin of the filter radius.
#[derive(Clone, Debug)]
pub struct FilmTile {
    /// The pixels whose samples this tile takes.
    pub rect: PixelRect,
    /// The buffer's pixel rectangle (`rect` plus the filter margin, clipped to the image).
    buffer: PixelRect,
    filter: Filter,
    sum: Vec<[f64; 3]>,
    weight: Vec<f64>,
    /// Samples added (finite or not).
    pub samples: u64,
    /// Non-finite samples dropped.
    pub nonfinite: u64,
}

impl FilmTile {
    /// An empty tile for the pixels `rect` of a `width x height` film with `filter` (the same
    /// as [`Film::tile`], without borrowing the film).
    #[must_use]
    pub fn new(width: usize, height: usize, filter: Filter, rect: PixelRect) -> Self {
        let m = (filter.radius() - 0.5).max(0.0).ceil() as usize;
        let buffer = PixelRect {
            x0: rect.x0.saturating_sub(m).min(width),
            y0: rect.y0.saturating_sub(m).min(height),
            x1: (rect.x1 + m).min(width),
            y1: (rect.y1 + m).min(height),
        };
        let n = buffer.area();
        Self {
            rect,
            buffer,
            filter,
            sum: vec![[0.0; 3]; n],
            weight: vec![0.0; n],
            samples: 0,
            nonfinite: 0,
        }
    }

    /// Adds radiance `l` sampled at raster position `p` (pixels, `(0, 0)` top-left). A
    /// non-finite `l` is counted and dropped (returns false).
    #[inline]
    pub fn add_sample(&mut self, p: Vec2, l: Vec3) -> bool {
        self.samples += 1;
        if !(l.is_finite() && p.is_finite()) {
            self.nonfinite += 1;
            return false;
        }
        let b = self.buffer;
        let (xlo, xhi) = self.filter.pixel_range(p.x);
        let (ylo, yhi) = self.filter.pixel_range(p.y);
        let bw = b.x1 - b.x0;
        for y in ylo.max(b.y0 as i64)..=yhi.min(b.y1 as i64 - 1) {
            for x in xlo.max(b.x0 as i64)..=xhi.min(b.x1 as i64 - 1) {
                let d = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - p;
                let w = self.filter.evaluate(d);
                if w == 0.0 {
                    continue;
                }
                let i = (y as usize - b.y0) * bw + (x as usize - b.x0);
                let w = f64::from(w);
                let s = &mut self.sum[i];
                s[0] += w * f64::from(l.x);
                s[1] += w * f64::from(l.y);
                s[2] += w * f64::from(l.z);
                self.weight[i] += w;
            }
        }
        true
    }
}

/// A shared exact splat grid for splats in radiance units (light tracing): its resolution is
/// set from `emission_bound` (`render::light::Lights::emission_bound`), so that a splat of
/// the scene's brightest emission uses about 56 bits below the point of the 128-bit sums:
/// relative resolution about `1e-17` of that emission, pixel sums up to about `1e21` times it.
/// The sums do not depend on the order of the splats (the same bits for any thread count and
/// any split of the work).
#[must_use]
pub fn exact_splat_grid(width: usize, height: usize, emission_bound: f32) -> ExactSplatGrid {
    let e = if emission_bound.is_finite() && emission_bound > 0.0 {
        f64::from(emission_bound).log2().ceil() as i64
    } else {
        0
    };
    let bits = (i64::from(DEFAULT_FRACTION_BITS) - e).clamp(0, 120) as u32;
    ExactSplatGrid::with_fraction_bits(width, height, bits)
}

/// The image being rendered: weighted pixel-sample sums plus splat sums.
#[derive(Clone, Debug)]
pub struct Film {
    width: usize,
    height: usize,
    filter: Filter,
    sum: Vec<[f64; 3]>,
    weight: Vec<f64>,
    /// Splat sums, allocated by the first splat merge (PT needs none).
    splat: Option<Vec<[f64; 3]>>,
    /// Pixel samples merged.
    pub samples: u64,
    /// Splats merged.
    pub splats: u64,
    /// Non-finite samples and splats dropped.
    pub nonfinite: u64,
}

impl Film {
    /// A black film of `width x height` pixels.
    #[must_use]
    pub fn new(width: usize, height: usize, filter: Filter) -> Self {
        let n = width * height;
        Self {
            width,
            height,
            filter,
            sum: vec![[0.0; 3]; n],
            weight: vec![0.0; n],
            splat: None,
            samples: 0,
            splats: 0,
            nonfinite: 0,
        }
    }

    /// A film holding given pixel-sample sums (`Σ w L` and `Σ w` per pixel, row-major; e.g.
    /// read back from a partial render), no splats; `None` if the lengths are not
    /// `width * height`.
    #[must_use]
    pub fn from_sums(
        width: usize,
        height: usize,
        filter: Filter,
        sum: Vec<[f64; 3]>,
        weight: Vec<f64>,
    ) -> Option<Self> {
        let n = width * height;
        (sum.len() == n && weight.len() == n).then(|| Self {
            sum,
            weight,
            ..Self::new_empty(width, height, filter)
        })
    }

    fn new_empty(width: usize, height: usize, filter: Filter) -> Self {
        Self {
            width,
            height,
            filter,
            sum: Vec::new(),
            weight: Vec::new(),
            splat: None,
            samples: 0,
            splats: 0,
            nonfinite: 0,
        }
    }

    /// The pixel-sample sums: `Σ w L` and `Σ w` per pixel, row-major.
    #[must_use]
    pub fn sums(&self) -> (&[[f64; 3]], &[f64]) {
        (&self.sum, &self.weight)
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

    /// The filter.
    #[must_use]
    pub fn filter(&self) -> Filter {
        self.filter
    }

    /// An empty accumulation tile for the pixels `rect`.
    #[must_use]
    pub fn tile(&self, rect: PixelRect) -> FilmTile {
        FilmTile::new(self.width, self.height, self.filter, rect)
    }

    /// Adds a tile's sums. Merging the same tiles in the same order gives the same bits.
    pub fn merge_tile(&mut self, tile: &FilmTile) {
        let b = tile.buffer;
        let bw = b.x1 - b.x0;
        for y in b.y0..b.y1 {
            for x in b.x0..b.x1 {
                let i = (y - b.y0) * bw + (x - b.x0);
                let j = y * self.width + x;
                for c in 0..3 {
                    self.sum[j][c] += tile.sum[i][c];
                }
                self.weight[j] += tile.weight[i];
            }
        }
        self.samples += tile.samples;
        self.nonfinite += tile.nonfinite;
    }

    /// An empty full-image splat grid for one work unit (light tracing, MCMC); merge it with
    /// [`Film::merge_splats`].
    #[must_use]
    pub fn splat_grid(&self) -> SplatGrid {
        SplatGrid::new(self.width, self.height)
    }

    /// Adds a work unit's splat sums (`splats` counts the grids' contributions merged).
    pub fn merge_splats(&mut self, grid: &SplatGrid) {
        self.add_splat_sums(grid.pixels());
    }

    /// Adds the sums of a shared exact splat grid ([`exact_splat_grid`]); counts as one
    /// merged grid.
    pub fn merge_exact_splats(&mut self, grid: &ExactSplatGrid) {
        self.add_splat_sums(&grid.pixels());
    }

    fn add_splat_sums(&mut self, sums: &[[f64; 3]]) {
        let n = self.width * self.height;
        let layer = self.splat.get_or_insert_with(|| vec![[0.0; 3]; n]);
        for (a, b) in layer.iter_mut().zip(sums) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
        self.splats += 1;
    }

    /// The image: `Σ w L / Σ w` per pixel (0 where no sample landed) plus
    /// `splat_scale · Σ L` of the splats. See [`Film::image_checked`].
    #[must_use]
    pub fn image(&self, splat_scale: f64) -> Image {
        self.image_checked(splat_scale).0
    }

    /// [`Film::image`] and the number of pixels dropped (made black) because a channel is not
    /// a finite f32: finite f64 sums above `f32::MAX` (about 3.4e38, e.g. an emitter of
    /// radiance 3e38 seen directly) would otherwise become infinities. Every pixel returned is
    /// finite.
    #[must_use]
    pub fn image_checked(&self, splat_scale: f64) -> (Image, u64) {
        let mut img = Image::new(self.width, self.height);
        let mut dropped = 0;
        for (i, px) in img.pixels.iter_mut().enumerate() {
            let w = self.weight[i];
            let splat = self.splat.as_ref().map_or([0.0; 3], |s| s[i]);
            let v: [f32; 3] = std::array::from_fn(|c| {
                let mean = if w > 0.0 { self.sum[i][c] / w } else { 0.0 };
                (mean + splat[c] * splat_scale) as f32
            });
            *px = if v.iter().all(|c| c.is_finite()) {
                v
            } else {
                dropped += 1;
                [0.0; 3]
            };
        }
        (img, dropped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Splat sums above f32::MAX become black, counted pixels, never inf; finite ones stay.
    #[test]
    fn overflowing_pixels_are_dropped_and_counted() {
        let mut film = Film::new(2, 1, Filter::BOX);
        let mut grid = SplatGrid::new(2, 1);
        assert!(grid.add_rgb([0.5, 0.5], [3e38, 0.0, 0.0], 1.0));
        assert!(grid.add_rgb([0.5, 0.5], [3e38, 0.0, 0.0], 1.0));
        assert!(grid.add_rgb([1.5, 0.5], [1.0, 2.0, 3.0], 1.0));
        film.merge_splats(&grid);
        let (img, dropped) = film.image_checked(1.0);
        assert_eq!(dropped, 1);
        assert_eq!(img.pixels[0], [0.0; 3]);
        assert_eq!(img.pixels[1], [1.0, 2.0, 3.0]);
        // Control: at half the scale nothing overflows.
        let (img, dropped) = film.image_checked(0.5);
        assert_eq!(dropped, 0);
        assert!(img.pixels[0][0] > 2.9e38 && img.pixels[0][0].is_finite());
    }

    #[test]
    fn tiles_cover_the_image_once() {
        let t = tiles(37, 20, 16);
        assert_eq!(t.len(), 3 * 2);
        assert_eq!(t.iter().map(PixelRect::area).sum::<usize>(), 37 * 20);
        assert_eq!(
            t[2],
            PixelRect {
                x0: 32,
                y0: 0,
                x1: 37,
                y1: 16
            }
        );
    }

    #[test]
    fn box_filter_averages_within_pixels() {
        let mut film = Film::new(4, 4, Filter::BOX);
        let mut tile = film.tile(PixelRect {
            x0: 0,
            y0: 0,
            x1: 4,
            y1: 4,
        });
        tile.add_sample(Vec2::new(1.2, 2.7), Vec3::new(1.0, 2.0, 3.0));
        tile.add_sample(Vec2::new(1.9, 2.1), Vec3::new(3.0, 2.0, 1.0));
        assert!(!tile.add_sample(Vec2::new(0.5, 0.5), Vec3::new(f32::NAN, 0.0, 0.0)));
        assert!(!tile.add_sample(Vec2::new(0.5, 0.5), Vec3::splat(f32::INFINITY)));
        // On a pixel corner: belongs to the pixel whose top-left corner it is.
        tile.add_sample(Vec2::new(3.0, 1.0), Vec3::ONE);
        film.merge_tile(&tile);
        let img = film.image(1.0);
        assert_eq!(img.get(1, 2), [2.0, 2.0, 2.0]);
        assert_eq!(img.get(0, 0), [0.0; 3]);
        assert_eq!(img.get(3, 1), [1.0; 3]);
        assert_eq!(img.get(2, 1), [0.0; 3]);
        assert_eq!(img.get(3, 0), [0.0; 3]);
        assert_eq!(film.nonfinite, 2);
        assert_eq!(film.samples, 5);
    }

    #[test]
    fn tent_filter_reaches_neighbours_across_tiles() {
        let mut film = Film::new(4, 2, Filter::TENT);
        // The sample at the tile border (x = 2) also lands in the left tile's pixel 1.
        let mut right = film.tile(PixelRect {
            x0: 2,
            y0: 0,
            x1: 4,
            y1: 2,
        });
        right.add_sample(Vec2::new(2.1, 1.0), Vec3::ONE);
        film.merge_tile(&right);
        let img = film.image(1.0);
        assert_eq!(img.get(1, 0), [1.0; 3]);
        assert_eq!(img.get(2, 1), [1.0; 3]);
        assert_eq!(img.get(0, 0), [0.0; 3]);
        assert!((Filter::TENT.evaluate(Vec2::new(0.5, 0.0)) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn splats_add_to_the_filtered_samples() {
        let mut film = Film::new(4, 4, Filter::TENT);
        let mut grid = film.splat_grid();
        let n = 16 * 16;
        for i in 0..n {
            let p = [
                4.0 * ((i % 16) as f32 + 0.5) / 16.0,
                4.0 * ((i / 16) as f32 + 0.5) / 16.0,
            ];
            assert!(grid.add_rgb(p, [1.0; 3], 1.0));
        }
        assert!(!grid.add_rgb([0.0, 0.0], [f32::NAN; 3], 1.0));
        assert!(!grid.add_rgb([-50.0, 3.0], [1.0; 3], 1.0)); // off-image: ignored
        film.merge_splats(&grid);
        // 256 splats on 16 pixels, scale 1/16: every pixel is 1.
        let img = film.image(1.0 / 16.0);
        assert!(img.pixels.iter().all(|p| (p[0] - 1.0).abs() < 1e-6));
    }
}
