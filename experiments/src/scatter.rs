//! Point sets of the unit square drawn as dots, panels side by side (an [`Image`] to save as
//! PNG), how evenly they cover a window ([`cells_hit`]), and a random walk on the torus
//! ([`torus_walk`]): the figures of sampling-pattern toys (a lattice against a Markov chain).

use mcmc_core::seed::mix64;
use render::image::Image;

use crate::table::Table;

/// A square window of the unit torus: `[origin, origin + side)^2`, wrapping around.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// The lower corner.
    pub origin: [f64; 2],
    /// The side.
    pub side: f64,
}

impl Window {
    /// The whole unit square.
    pub const UNIT: Window = Window {
        origin: [0.0, 0.0],
        side: 1.0,
    };

    /// The cell of the grid of `side`-sized cells of the unit square that holds `p`.
    ///
    /// # Example
    /// ```
    /// use experiments::scatter::Window;
    ///
    /// let w = Window::grid_cell([0.43, 0.61], 0.25);
    /// assert_eq!(w, Window { origin: [0.25, 0.5], side: 0.25 });
    /// ```
    #[must_use]
    pub fn grid_cell(p: [f64; 2], side: f64) -> Self {
        Self {
            origin: p.map(|c| (c / side).floor() * side),
            side,
        }
    }

    /// `p`'s coordinates in the window scaled to `[0, 1)^2`, `None` outside it.
    #[must_use]
    pub fn local(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        let t = [0, 1].map(|d| (p[d] - self.origin[d]).rem_euclid(1.0) / self.side);
        t.iter().all(|c| (0.0..1.0).contains(c)).then_some(t)
    }
}

/// A named point set of the unit torus: its points, their colour, and the window it lives in
/// (outlined in its panel; [`Window::UNIT`] for the whole torus).
#[derive(Clone, Debug, PartialEq)]
pub struct PointSet {
    /// The name (the row of [`coverage_table`]).
    pub label: String,
    /// The points (unit-square coordinates; `y` down).
    pub points: Vec<[f64; 2]>,
    /// Their colour (linear RGB).
    pub colour: [f32; 3],
    /// The window the set explores (e.g. a local lattice's tile).
    pub window: Window,
}

impl PointSet {
    /// The set `label` of `points` drawn in `colour`, living in `window`.
    #[must_use]
    pub fn new(
        label: impl Into<String>,
        points: Vec<[f64; 2]>,
        colour: [f32; 3],
        window: Window,
    ) -> Self {
        Self {
            label: label.into(),
            points,
            colour,
            window,
        }
    }
}

/// Margin around a panel's unit square, in pixels.
const MARGIN: usize = 10;
/// Frame and outline colour.
const GREY: [f32; 3] = [0.6, 0.6, 0.6];

/// `sets` side by side on white, each in a `side x side` panel: the unit square framed in grey
/// with a 10-pixel margin, the set's window outlined unless it is the whole square, every point
/// as a 3 x 3 dot in the set's colour.
///
/// # Example
/// ```
/// use experiments::scatter::{point_panels, PointSet, Window};
///
/// let red = PointSet::new("a", vec![[0.5, 0.5]], [1.0, 0.0, 0.0], Window::UNIT);
/// let img = point_panels(&[red.clone(), red], 100);
/// assert_eq!((img.width, img.height), (200, 100));
/// assert_eq!(img.get(50, 50), [1.0, 0.0, 0.0]);
/// assert_eq!(img.get(150, 50), [1.0, 0.0, 0.0]);
/// ```
#[must_use]
pub fn point_panels(sets: &[PointSet], side: usize) -> Image {
    let mut img = Image::new(side * sets.len(), side);
    let width = img.width as i64;
    fill(&mut img, [0, 0, width, side as i64], [1.0; 3]);
    let span = side.saturating_sub(2 * MARGIN) as f64;
    for (i, set) in sets.iter().enumerate() {
        let x0 = (i * side) as f64;
        let px = |p: [f64; 2]| {
            [
                x0 + MARGIN as f64 + p[0] * span,
                MARGIN as f64 + p[1] * span,
            ]
        };
        let mut square = |a: [f64; 2], b: [f64; 2]| {
            let (a, b) = (px(a), px(b));
            let [ax, ay, bx, by] = [a[0], a[1], b[0], b[1]].map(|v| v as i64);
            fill(&mut img, [ax, ay, bx + 1, ay + 1], GREY);
            fill(&mut img, [ax, by, bx + 1, by + 1], GREY);
            fill(&mut img, [ax, ay, ax + 1, by + 1], GREY);
            fill(&mut img, [bx, ay, bx + 1, by + 1], GREY);
        };
        square([0.0, 0.0], [1.0, 1.0]);
        let w = set.window;
        if w != Window::UNIT {
            square(w.origin, [w.origin[0] + w.side, w.origin[1] + w.side]);
        }
        for &p in &set.points {
            let [x, y] = px(p).map(|v| v as i64);
            fill(&mut img, [x - 1, y - 1, x + 2, y + 2], set.colour);
        }
    }
    img
}

/// Fills the pixels `[x0, x1) x [y0, y1)` of `img` (clipped).
fn fill(img: &mut Image, [x0, y0, x1, y1]: [i64; 4], rgb: [f32; 3]) {
    let (w, h) = (img.width as i64, img.height as i64);
    for y in y0.max(0)..y1.min(h) {
        for x in x0.max(0)..x1.min(w) {
            img.set(x as usize, y as usize, rgb);
        }
    }
}

/// Cells of a `k x k` grid over `window` that hold at least one of `points` (a coverage
/// measure: a well-spread set of `k^2` or more points hits all of them).
///
/// # Example
/// ```
/// use experiments::scatter::{cells_hit, Window};
///
/// let corners = [[0.1, 0.1], [0.9, 0.9], [0.15, 0.1]];
/// assert_eq!(cells_hit(&corners, Window::UNIT, 2), 2);
/// ```
#[must_use]
pub fn cells_hit(points: &[[f64; 2]], window: Window, k: usize) -> usize {
    let mut hit = vec![false; k * k];
    for t in points.iter().filter_map(|&p| window.local(p)) {
        let cell = |c: f64| ((c * k as f64) as usize).min(k - 1);
        hit[cell(t[1]) * k + cell(t[0])] = true;
    }
    hit.iter().filter(|&&h| h).count()
}

/// A uniform number in `[0, 1)` keyed by `(seed, i)` (53 bits of
/// [`mcmc_core::seed::mix64`]): the same for a key on every machine.
#[must_use]
pub fn keyed_uniform(seed: u64, i: u64) -> f64 {
    (mix64(mix64(seed) ^ i) >> 11) as f64 / (1u64 << 53) as f64
}

/// `n` points of a random walk on the unit torus from `start` (its first point), each step
/// uniform in `[-radius, radius]^2` ([`keyed_uniform`]`(seed, 2 i + d)` for step `i`,
/// coordinate `d`): the Markov chain a QMC point set is compared with.
///
/// # Example
/// ```
/// let walk = experiments::scatter::torus_walk([0.5, 0.5], 0.1, 64, 7);
/// assert_eq!((walk.len(), walk[0]), (64, [0.5, 0.5]));
/// assert!(walk.windows(2).all(|w| (0..2).all(|d| {
///     let step = (w[1][d] - w[0][d]).abs();
///     step.min(1.0 - step) <= 0.1 + 1e-12
/// })));
/// ```
#[must_use]
pub fn torus_walk(start: [f64; 2], radius: f64, n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut x = start;
    let mut out = Vec::with_capacity(n);
    if n > 0 {
        out.push(x);
    }
    for i in 1..n as u64 {
        for (d, c) in x.iter_mut().enumerate() {
            let step = (2.0 * keyed_uniform(seed, 2 * i + d as u64) - 1.0) * radius;
            *c = (*c + step).rem_euclid(1.0);
        }
        out.push(x);
    }
    out
}

/// Per set the cells of a `k x k` grid over its window that it hits ([`cells_hit`]): columns
/// `point set` and `cells hit of the kxk grid (of k^2)`.
#[must_use]
pub fn coverage_table(sets: &[PointSet], k: usize) -> Table {
    let mut table = Table::new([
        "point set".to_owned(),
        format!("cells hit of the {k}x{k} grid (of {})", k * k),
    ]);
    for set in sets {
        let hit = cells_hit(&set.points, set.window, k);
        table.push_row([set.label.clone(), hit.to_string()]);
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_wrap_around_the_torus() {
        let w = Window {
            origin: [0.9, 0.0],
            side: 0.25,
        };
        let t = w.local([0.05, 0.125]).unwrap();
        assert!((t[0] - 0.6).abs() < 1e-12 && (t[1] - 0.5).abs() < 1e-12);
        assert_eq!(w.local([0.5, 0.1]), None);
        assert_eq!(cells_hit(&[[0.05, 0.125], [0.5, 0.1]], w, 4), 1);
    }

    #[test]
    fn walks_are_reproducible_and_local() {
        let a = torus_walk([0.1, 0.9], 0.05, 100, 3);
        assert_eq!(a, torus_walk([0.1, 0.9], 0.05, 100, 3));
        assert!(a.iter().all(|p| p.iter().all(|c| (0.0..1.0).contains(c))));
        // A short-step walk covers few cells; negative control: another seed, another walk.
        assert!(cells_hit(&a, Window::UNIT, 8) < 32);
        assert_ne!(a, torus_walk([0.1, 0.9], 0.05, 100, 4));
        assert!(torus_walk([0.1, 0.9], 0.05, 0, 3).is_empty());
        let u: Vec<f64> = (0..1000).map(|i| keyed_uniform(9, i)).collect();
        assert!(u.iter().all(|v| (0.0..1.0).contains(v)));
        assert!((u.iter().sum::<f64>() / 1000.0 - 0.5).abs() < 0.05);
    }

    #[test]
    fn a_lattice_covers_more_cells_than_a_clump() {
        let lattice: Vec<[f64; 2]> = (0..16)
            .map(|i| {
                [
                    (f64::from(i % 4) + 0.5) / 4.0,
                    (f64::from(i / 4) + 0.5) / 4.0,
                ]
            })
            .collect();
        assert_eq!(cells_hit(&lattice, Window::UNIT, 4), 16);
        // Negative control: sixteen points in one corner hit one cell.
        let clump: Vec<[f64; 2]> = (0..16).map(|i| [0.01 * f64::from(i), 0.05]).collect();
        assert_eq!(cells_hit(&clump, Window::UNIT, 4), 1);
        assert_eq!(cells_hit(&[], Window::UNIT, 4), 0);
    }

    #[test]
    fn panels_draw_frames_outlines_and_dots() {
        let tile = Window::grid_cell([0.6, 0.6], 0.25);
        let set = PointSet::new("s", vec![[0.25, 0.75]], [0.0, 0.0, 1.0], tile);
        let img = point_panels(std::slice::from_ref(&set), 100);
        assert_eq!(img.get(0, 0), [1.0; 3], "margin is white");
        assert_eq!(img.get(10, 50), GREY, "frame");
        assert_eq!(img.get(50, 60), GREY, "outline");
        assert_eq!(img.get(30, 70), [0.0, 0.0, 1.0], "dot");
        // Negative controls: no dot where there is no point, no outline for the whole square.
        assert_eq!(img.get(70, 30), [1.0; 3]);
        let whole = PointSet::new("w", Vec::new(), [0.0; 3], Window::UNIT);
        assert_eq!(point_panels(&[whole], 100).get(50, 60), [1.0; 3]);
    }

    #[test]
    fn coverage_table_has_a_row_per_set() {
        let tile = Window::grid_cell([0.6, 0.6], 0.25);
        let sets = [
            PointSet::new("inside", vec![[0.51, 0.51], [0.74, 0.74]], [0.0; 3], tile),
            PointSet::new("outside", vec![[0.1, 0.1]], [0.0; 3], tile),
        ];
        let t = coverage_table(&sets, 2);
        assert_eq!(t.headers()[1], "cells hit of the 2x2 grid (of 4)");
        assert_eq!(t.rows()[0], ["inside", "2"]);
        assert_eq!(t.rows()[1], ["outside", "0"]);
    }
}
