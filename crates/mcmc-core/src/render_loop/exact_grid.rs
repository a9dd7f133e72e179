//! A shared full-image splat accumulator whose sums do not depend on the order of the adds:
//! one image of memory for any number of jobs and threads, and the same bits for any split
//! of the work (threads, jobs, processes).
//!
//! Each channel of each pixel is a 128-bit two's-complement fixed-point number with
//! [`ExactSplatGrid::fraction_bits`] fractional bits. A splat value `v` is rounded once to
//! a multiple of `2^-fraction_bits` (the nearest, to within one unit) and added as an integer. Integer addition is
//! associative and commutative, so the final sums are the same whatever order the splats
//! arrive in: the grid can be shared by every job of a render (no per-job film), and the sums
//! of two grids that received disjoint parts of the work add up to exactly the grid that
//! received all of it.
//!
//! The 128-bit add is two relaxed atomic 64-bit adds with the carry of the low word passed
//! to the high word (the sum modulo `2^128` is exact whatever the interleaving, because the
//! low word wraps exactly once per carry it reports). No locks; a splat whose value is
//! non-negative and below `2^(64 - fraction_bits)` touches the high word only on a carry.
//! Read the sums after the writers are done (a read during writes may see a torn value).

use std::sync::atomic::{AtomicU64, Ordering};

use super::splat::{Splat, SplatSink};

/// Default fractional bits of [`ExactSplatGrid`]: resolution `2^-56` (about `1.4e-17`, the
/// spacing of f64 values near `0.25`), largest pixel sum `2^71` (about `2.4e21`). Suits the
/// render loop's splats, which are scale-free (`w rgb / f(x)`: a weight in `[0, 1]` times a
/// colour over its own luminance, so mostly between `1e-3` and `20`); a splat below `256`
/// changes only the low word of the sum.
pub const DEFAULT_FRACTION_BITS: u32 = 56;

/// One channel: the low and high words of a 128-bit fixed-point sum.
#[derive(Debug, Default)]
struct Cell {
    lo: AtomicU64,
    hi: AtomicU64,
}

impl Cell {
    #[inline]
    fn add(&self, x: i128) {
        let lo = x as u64;
        let hi = (x >> 64) as u64;
        let carry = if lo == 0 {
            0
        } else {
            let before = self.lo.fetch_add(lo, Ordering::Relaxed);
            u64::from(before.overflowing_add(lo).1)
        };
        let hi = hi.wrapping_add(carry);
        if hi != 0 {
            self.hi.fetch_add(hi, Ordering::Relaxed);
        }
    }

    #[inline]
    fn get(&self) -> i128 {
        let lo = self.lo.load(Ordering::Relaxed);
        let hi = self.hi.load(Ordering::Relaxed);
        (i128::from(hi as i64) << 64) | i128::from(lo)
    }
}

/// A `width` x `height` RGB splat accumulator in exact 128-bit fixed point, shared by
/// reference between the jobs of a render (see the module documentation). `&ExactSplatGrid`
/// is a [`SplatSink`].
#[derive(Debug)]
pub struct ExactSplatGrid {
    width: usize,
    height: usize,
    fraction_bits: u32,
    scale: f64,
    cells: Vec<[Cell; 3]>,
}

/// Bytes of memory per pixel of an [`ExactSplatGrid`] (48: three 128-bit sums).
pub const EXACT_GRID_BYTES_PER_PIXEL: usize = std::mem::size_of::<[Cell; 3]>();

impl ExactSplatGrid {
    /// A zeroed grid with [`DEFAULT_FRACTION_BITS`].
    #[must_use]
    pub fn new(width: usize, height: usize) -> Self {
        Self::with_fraction_bits(width, height, DEFAULT_FRACTION_BITS)
    }

    /// A zeroed grid with `fraction_bits` fractional bits (clamped to `0..=120`): splat
    /// values are rounded to multiples of `2^-fraction_bits`, pixel sums must stay below
    /// `2^(127 - fraction_bits)`.
    #[must_use]
    pub fn with_fraction_bits(width: usize, height: usize, fraction_bits: u32) -> Self {
        let fraction_bits = fraction_bits.min(120);
        let mut cells = Vec::new();
        cells.resize_with(width * height, Default::default);
        Self {
            width,
            height,
            fraction_bits,
            scale: 2f64.powi(fraction_bits as i32),
            cells,
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

    /// The fractional bits of the fixed-point sums.
    #[must_use]
    pub fn fraction_bits(&self) -> u32 {
        self.fraction_bits
    }

    /// The fixed-point integer of `v` (rounded to nearest, to within one unit), or `None` if
    /// it is not finite or too large: a single splat must stay below `2^106` units (`2^50`,
    /// about `1.1e15`, at the default resolution), so that `2^20` of them at that bound still
    /// fit a pixel's 127 bits.
    #[inline]
    fn fixed(&self, v: f64) -> Option<i128> {
        let x = v * self.scale;
        // The common case (non-negative, below 2^63 units) through the hardware's 64-bit
        // conversion; `round` and `as i128` are library calls on baseline x86-64.
        if (0.0..9.2e18).contains(&x) {
            return Some(i128::from((x + 0.5) as i64));
        }
        let x = x.round();
        if x.is_finite() && x.abs() < 2f64.powi(106) {
            Some(x as i128)
        } else {
            None
        }
    }

    /// Adds `rgb * weight` to the pixel containing `raster`; splats outside the image or with
    /// a non-finite or too large product are ignored and return false (the caller counts them
    /// as dropped). Values below half the resolution round to zero.
    #[inline]
    pub fn add_rgb(&self, raster: [f32; 2], rgb: [f32; 3], weight: f64) -> bool {
        let (x, y) = (raster[0].floor(), raster[1].floor());
        if !(x >= 0.0 && y >= 0.0 && (x as usize) < self.width && (y as usize) < self.height) {
            return false;
        }
        let i = y as usize * self.width + x as usize;
        self.add_f64(i, rgb.map(|c| f64::from(c) * weight))
    }

    /// Adds f64 values to pixel index `i` (row-major), each rounded to the grid's resolution
    /// as a splat is; returns false (adding nothing) for an index outside the grid or a
    /// non-finite or too large value.
    #[inline]
    pub fn add_f64(&self, i: usize, v: [f64; 3]) -> bool {
        if i >= self.cells.len() {
            return false;
        }
        let mut fixed = [0i128; 3];
        for (f, &c) in fixed.iter_mut().zip(&v) {
            match self.fixed(c) {
                Some(x) => *f = x,
                None => return false,
            }
        }
        for (cell, x) in self.cells[i].iter().zip(fixed) {
            if x != 0 {
                cell.add(x);
            }
        }
        true
    }

    /// The raw fixed-point sums of pixel index `i` (row-major): for saving a partial result
    /// and adding it to another grid with [`ExactSplatGrid::add_raw`].
    #[must_use]
    pub fn raw(&self, i: usize) -> [i128; 3] {
        let px = &self.cells[i];
        [px[0].get(), px[1].get(), px[2].get()]
    }

    /// Adds raw fixed-point sums (from [`ExactSplatGrid::raw`] of a grid with the same
    /// fractional bits) to pixel index `i`.
    pub fn add_raw(&self, i: usize, sums: [i128; 3]) {
        for (cell, v) in self.cells[i].iter().zip(sums) {
            cell.add(v);
        }
    }

    /// Adds everything `other` accumulated (same size and fractional bits; otherwise nothing
    /// is added and false is returned).
    pub fn add_grid(&self, other: &ExactSplatGrid) -> bool {
        if std::ptr::eq(self, other) {
            return true;
        }
        if (other.width, other.height, other.fraction_bits)
            != (self.width, self.height, self.fraction_bits)
        {
            return false;
        }
        for i in 0..self.cells.len() {
            self.add_raw(i, other.raw(i));
        }
        true
    }

    /// The accumulated value of pixel `(x, y)` (row-major, top row first), rounded to f64.
    #[must_use]
    pub fn get(&self, x: usize, y: usize) -> [f64; 3] {
        self.value(y * self.width + x)
    }

    /// The value of pixel index `i`, rounded to f64.
    #[inline]
    fn value(&self, i: usize) -> [f64; 3] {
        self.raw(i).map(|v| v as f64 / self.scale)
    }

    /// All pixels as f64 RGB, row-major, top row first.
    #[must_use]
    pub fn pixels(&self) -> Vec<[f64; 3]> {
        (0..self.cells.len()).map(|i| self.value(i)).collect()
    }

    /// The pixels multiplied by `scale`, as f32 RGB (row-major), and the number of pixels
    /// dropped (made black) because a channel is not a finite f32 (as
    /// [`super::SplatGrid::to_rgb32_checked`]).
    #[must_use]
    pub fn to_rgb32_checked(&self, scale: f64) -> (Vec<[f32; 3]>, u64) {
        let mut dropped = 0;
        let pixels = (0..self.cells.len())
            .map(|i| {
                let v = self.value(i).map(|c| (c * scale) as f32);
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

impl Clone for ExactSplatGrid {
    /// A grid with the same size, resolution and sums (read them after the writers are done).
    fn clone(&self) -> Self {
        let copy = Self::with_fraction_bits(self.width, self.height, self.fraction_bits);
        for i in 0..self.cells.len() {
            copy.add_raw(i, self.raw(i));
        }
        copy
    }
}

impl SplatSink for &ExactSplatGrid {
    #[inline]
    fn add(&mut self, splat: &Splat, weight: f64) -> bool {
        self.add_rgb(splat.raster, splat.rgb, weight)
    }

    /// Adds `other`'s sums unless it is the same grid (the usual case: every job holds a
    /// reference to one shared grid, so there is nothing to merge).
    fn merge(&mut self, other: &Self) {
        self.add_grid(other);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_do_not_depend_on_the_order_of_adds() {
        let values: Vec<f64> = (0..1000)
            .map(|i| {
                let h = crate::seed::mix64(i);
                (h >> 11) as f64 / (1u64 << 53) as f64 * 10f64.powi((i % 13) as i32 - 6)
            })
            .collect();
        let forward = ExactSplatGrid::new(1, 1);
        let backward = ExactSplatGrid::new(1, 1);
        for &v in &values {
            assert!(forward.add_rgb([0.5, 0.5], [1.0, 2.0, 0.5], v));
        }
        for &v in values.iter().rev() {
            assert!(backward.add_rgb([0.5, 0.5], [1.0, 2.0, 0.5], v));
        }
        assert_eq!(forward.raw(0), backward.raw(0));
        // Negative control: plain f64 sums in the two orders differ in the last bits.
        let f: f64 = values.iter().sum();
        let b: f64 = values.iter().rev().sum();
        assert_ne!(f.to_bits(), b.to_bits());
        // The fixed-point sum is the f64 sum to within rounding.
        assert!((forward.get(0, 0)[0] - f).abs() <= 1e-12 * f);
    }

    #[test]
    fn two_halves_add_up_to_the_whole() {
        let whole = ExactSplatGrid::new(2, 1);
        let (a, b) = (ExactSplatGrid::new(2, 1), ExactSplatGrid::new(2, 1));
        for i in 0..200u64 {
            let v = (crate::seed::mix64(i) >> 11) as f64 / (1u64 << 40) as f64;
            let raster = [(i % 2) as f32 + 0.5, 0.5];
            whole.add_rgb(raster, [1.0; 3], v);
            if i < 77 { &a } else { &b }.add_rgb(raster, [1.0; 3], v);
        }
        assert!(a.add_grid(&b));
        for i in 0..2 {
            assert_eq!(a.raw(i), whole.raw(i));
        }
        assert!(!a.add_grid(&ExactSplatGrid::new(3, 1)));
    }

    #[test]
    fn carries_and_negative_values_are_exact() {
        let g = ExactSplatGrid::with_fraction_bits(1, 1, 60);
        // 40 adds of 0.9 * 2^4 each cross the low word (2^64 units = 2^4) many times.
        for _ in 0..40 {
            g.add_rgb([0.0, 0.0], [14.4, -14.4, 0.0], 1.0);
        }
        let v = g.get(0, 0);
        let expected = 40.0 * f64::from(14.4f32);
        assert!((v[0] - expected).abs() < 1e-9, "{v:?}");
        assert!((v[1] + expected).abs() < 1e-9, "{v:?}");
        assert_eq!(v[2], 0.0);
    }

    #[test]
    fn drops_outside_nonfinite_and_huge() {
        let g = ExactSplatGrid::new(2, 2);
        assert!(!g.add_rgb([2.0, 0.0], [1.0; 3], 1.0));
        assert!(!g.add_rgb([-0.1, 0.0], [1.0; 3], 1.0));
        assert!(!g.add_rgb([0.0, 0.0], [f32::NAN, 1.0, 1.0], 1.0));
        assert!(!g.add_rgb([0.0, 0.0], [1.0; 3], 1e40));
        assert_eq!(g.get(0, 0), [0.0; 3]);
    }

    #[test]
    fn shared_by_threads_gives_the_serial_sums() {
        let serial = ExactSplatGrid::new(4, 1);
        let shared = ExactSplatGrid::new(4, 1);
        let value = |i: u64| (crate::seed::mix64(i) >> 11) as f64 / (1u64 << 50) as f64;
        for i in 0..40_000u64 {
            serial.add_rgb([(i % 4) as f32, 0.0], [1.0, 0.5, 0.25], value(i));
        }
        std::thread::scope(|s| {
            for t in 0..4u64 {
                let g = &shared;
                s.spawn(move || {
                    for i in (t..40_000).step_by(4) {
                        g.add_rgb([(i % 4) as f32, 0.0], [1.0, 0.5, 0.25], value(i));
                    }
                });
            }
        });
        for i in 0..4 {
            assert_eq!(serial.raw(i), shared.raw(i));
        }
    }
}
