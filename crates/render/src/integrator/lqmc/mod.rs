//! Local quasi-Monte Carlo rendering (`--integrator lqmc`; Tessari, Hanika & Dachsbacher,
//! "Local Quasi-Monte Carlo Exploration"): Halton-driven seed paths ([`super::halton_sampler::HaltonSampler`]), each contribution
//! explored by a rank-1 lattice set in its class's tiles ([`lqmc::LocalQmc`]), prefixes
//! re-traced and reconnected to the seed's static suffix.
//!
//! Per seed (one sample of one pixel, numbers from the per-pixel scrambled Halton sampler):
//!
//! 1. trace a path with its vertices ([`crate::integrator::vertex_path`]); every contribution
//!    (emitter hit, environment, next-event estimation; section 5 "we perform the
//!    perturbations every time a complete path is found") is handled separately;
//! 2. classify it ([`PathClass`]): caustic (`N = 97`), depth of field (`N = 23`), normal
//!    (`N = 23`), NEE that is neither (splatted unexplored: "we are very careful not to
//!    explore the sample"; [`LqmcParams::explore_nee`] explores it with `N = 7`, as the
//!    authors' code does), or too short (`L < 2`, splatted directly);
//! 3. draw the breakup point `b` from the CDF over `min(roughness(z_b), roughness(z_{b+1}))`
//!    (section 3.3; `b = 0`, the lens, with weight 80 for depth of field), its probability
//!    `P(b|X)` going into the weights;
//! 4. explore the image plane (global image coordinates), the aperture, the time and the
//!    BSDF directions at `z_1 .. z_{b-1}` in the class's tiles (section 4 "Parameters"), or
//!    for `b = 0` the aperture alone;
//! 5. for each member: re-trace `z_1 .. z_b` (for `b = 0`: sample the new lens point),
//!    reject it if its class (or `P(b|.) = 0`, or a zero contribution) differs, reconnect
//!    `z_b` to the static `z_{b+1}`, and report its
//!    contribution and the density of the static suffix given its prefix
//!    (`p_t(X_j) / J_j`, eq. 8 and 11);
//! 6. splat every member with the weight of eq. 9 times `P(b|X_j)`.
//!
//! The image is the sum of splats divided by the number of completed progressions (one
//! sample per pixel each): a progression that a time budget or Ctrl-C interrupted is
//! dropped (its splats cross work-unit borders), unless it is the first.

mod class;
mod explore;

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{UVec2, Vec2, Vec3};
use mcmc_core::Progress;

use self::explore::{ExploreStats, Explorer, SplatTarget};
use super::pt_driver::{render_passes, PtDriverSettings};
use crate::film::{exact_splat_grid, PixelRect};
use crate::image::Image;
use crate::scene::Scene;
use crate::shard::Component;
use mcmc_core::render_loop::ExactSplatGrid;

pub use self::class::PathClass;

/// LQMC's parameters (section 4 "Parameters"; [`LqmcParams::tessari2020`] is the paper's
/// set, with the choices where it is silent documented per field and in
/// docs/methods/lqmc.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LqmcParams {
    /// Lattice size of normal paths (paper: 23).
    pub n_normal: u32,
    /// Lattice size of caustic paths (paper: 97).
    pub n_caustic: u32,
    /// Lattice size of depth-of-field paths (paper: 23).
    pub n_depth_of_field: u32,
    /// Lattice size of NEE paths when they are explored (authors' code: 7).
    pub n_nee: u32,
    /// Explore NEE paths that are neither caustic nor out of focus (false: the paper
    /// splats them unexplored; the authors' code explores them with `N = 7`).
    pub explore_nee: bool,
    /// Image-plane tiles across the width, normal and depth-of-field paths (paper: 24; the
    /// height gets `round(24 H / W)`).
    pub image_tiles: u32,
    /// Image-plane tiles across the width for caustics (paper: 48).
    pub image_tiles_caustic: u32,
    /// Aperture tiles per axis (paper: 2).
    pub aperture_tiles: u32,
    /// Aperture tiles per axis for caustics (authors' code: 4).
    pub aperture_tiles_caustic: u32,
    /// Time tiles (the paper treats wavelength with one tile; we do the same for time).
    pub time_tiles: u32,
    /// Tiles per BSDF-direction dimension, non-caustic (paper "50-150"; authors' code 155
    /// for non-caustic paths): 150.
    pub direction_tiles: u32,
    /// Tiles per BSDF-direction dimension for caustics (authors' code 55): 50.
    pub direction_tiles_caustic: u32,
    /// Tiles per light-position dimension (explored only by a full re-trace of an NEE path;
    /// not in the paper): 50.
    pub light_tiles: u32,
    /// Roughness (GGX alpha) below which a vertex counts as near specular for the caustic
    /// class (not given in the paper): 0.1.
    pub specular_roughness: f32,
    /// Circle of confusion (pixels, at the first vertex) above which a path is depth of
    /// field (the paper: "a threshold value"): 1 pixel.
    pub dof_coc_pixels: f32,
    /// Breakup weight of `b = 0` (a new lens point reconnected to the static `z_1`) for
    /// depth-of-field paths; 0 for the other classes (the authors' code: 80, against
    /// weights of at most 1 for the other `b`).
    pub dof_lens_weight: f64,
    /// Include `P(b|X)` in the weights (true; false is the authors' code, biased whenever
    /// `P(b|.)` varies inside a set).
    pub breakup_probability_in_weights: bool,
    /// Include the static suffix's density `p_t(X_j) / J_j` in the weights (true; false is a
    /// deliberately wrong estimator, the negative control of the convergence tests).
    pub suffix_density_in_weights: bool,
}

impl LqmcParams {
    /// The paper's parameters (Tessari et al. 2020, section 4).
    #[must_use]
    pub const fn tessari2020() -> Self {
        Self {
            n_normal: 23,
            n_caustic: 97,
            n_depth_of_field: 23,
            n_nee: 7,
            explore_nee: false,
            image_tiles: 24,
            image_tiles_caustic: 48,
            aperture_tiles: 2,
            aperture_tiles_caustic: 4,
            time_tiles: 1,
            direction_tiles: 150,
            direction_tiles_caustic: 50,
            light_tiles: 50,
            specular_roughness: 0.1,
            dof_coc_pixels: 1.0,
            dof_lens_weight: 80.0,
            breakup_probability_in_weights: true,
            suffix_density_in_weights: true,
        }
    }
}

impl Default for LqmcParams {
    /// [`LqmcParams::tessari2020`].
    fn default() -> Self {
        Self::tessari2020()
    }
}

/// The result of [`render_lqmc`].
#[derive(Clone, Debug)]
pub struct LqmcOutput {
    /// The image.
    pub image: Image,
    /// A shard's accumulators (`None` for the whole image; [`crate::shard`]).
    pub component: Option<Component>,
    /// Seed paths traced.
    pub seeds: u64,
    /// Progressions (samples per pixel) in the image.
    pub progressions: u32,
    /// Contributions explored with a lattice set.
    pub explored: u64,
    /// Contributions splatted unexplored.
    pub direct: u64,
    /// NEE-class contributions explored (only with [`LqmcParams::explore_nee`]; part of
    /// `explored`).
    pub explored_nee: u64,
    /// NEE-class contributions splatted unexplored by the paper's rule (part of `direct`).
    pub direct_nee: u64,
    /// Lattice members in their seed's class (seeds included).
    pub members: u64,
    /// Lattice members rejected (left the class).
    pub rejected: u64,
    /// Non-finite splats dropped.
    pub dropped_nonfinite: u64,
    /// True if `cancel` stopped the render.
    pub cancelled: bool,
    /// Pixels whose tile a cancel or the time budget stopped before its first seed path
    /// (only lattice members of neighbouring tiles' seeds land there).
    pub unsampled_pixels: u64,
}

/// Splat sums of one work unit, sparse: the splats that land in its pixels plus the margin
/// its lattice sets can reach, summed per pixel in arrival order when the unit ends
/// ([`SplatTile::finish`]); splats beyond the margin (sets in the jittered tile that wraps
/// around the image border) are kept in a list, merged in order. Memory follows the splats
/// a unit makes, not the area its sets could reach (a dense buffer over the margin would be
/// a large fraction of the image per unit).
struct SplatTile {
    buffer: PixelRect,
    width: usize,
    height: usize,
    /// Splats inside the buffer as (pixel index, value), in arrival order until
    /// [`SplatTile::finish`], then one sum per pixel in pixel order.
    inside: Vec<(u32, [f64; 3])>,
    wrapped: Vec<(usize, [f64; 3])>,
}

impl SplatTile {
    fn new(rect: PixelRect, width: usize, height: usize, mx: usize, my: usize) -> Self {
        let buffer = PixelRect {
            x0: rect.x0.saturating_sub(mx),
            y0: rect.y0.saturating_sub(my),
            x1: (rect.x1 + mx).min(width),
            y1: (rect.y1 + my).min(height),
        };
        Self {
            buffer,
            width,
            height,
            inside: Vec::new(),
            wrapped: Vec::new(),
        }
    }

    /// Sums the inside splats per pixel: a stable sort keeps each pixel's splats in arrival
    /// order, so every sum is the one a dense buffer would hold.
    fn finish(&mut self) {
        self.inside.sort_by_key(|&(i, _)| i);
        let mut sums: Vec<(u32, [f64; 3])> = Vec::new();
        for &(i, v) in &self.inside {
            match sums.last_mut() {
                Some((j, s)) if *j == i => {
                    for c in 0..3 {
                        s[c] += v[c];
                    }
                }
                _ => sums.push((i, v)),
            }
        }
        self.inside = sums;
    }

    /// Adds the unit's sums to `image`; returns the number of sums too large for it.
    fn merge_into(&self, image: &ExactSplatGrid) -> u64 {
        let inside = self.inside.iter().map(|&(i, s)| (i as usize, s));
        inside
            .chain(self.wrapped.iter().copied())
            .filter(|&(i, s)| !image.add_f64(i, s))
            .count() as u64
    }
}

impl SplatTarget for SplatTile {
    #[inline]
    fn splat(&mut self, p: Vec2, value: Vec3) {
        let (x, y) = (p.x.floor(), p.y.floor());
        let b = self.buffer;
        let v = [f64::from(value.x), f64::from(value.y), f64::from(value.z)];
        if x < b.x0 as f32 || y < b.y0 as f32 || x >= b.x1 as f32 || y >= b.y1 as f32 {
            if x >= 0.0 && y >= 0.0 && (x as usize) < self.width && (y as usize) < self.height {
                self.wrapped.push((y as usize * self.width + x as usize, v));
            }
            return;
        }
        self.inside
            .push(((y as usize * self.width + x as usize) as u32, v));
    }
}

/// Renders `scene` with local quasi-Monte Carlo exploration (see the module docs) through
/// the PT driver's passes, tiles, budgets, progress and cancellation
/// ([`render_passes`]); progressions are one sample per pixel and re-draw the tiling
/// jitter (section 3.4). Under a sample budget the image is bit-identical for any thread
/// count: every number is keyed by (seed, pixel, sample), each work unit splats into its
/// own buffer, and buffers are merged in tile order.
pub fn render_lqmc(
    scene: &Scene,
    settings: &PtDriverSettings,
    params: &LqmcParams,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> LqmcOutput {
    let (w, h) = (settings.width as usize, settings.height as usize);
    let camera = scene.camera_spec().build(settings.width, settings.height);
    // A set stays in its image tile: width / image_tiles pixels (the coarsest tiles).
    let kx = params.image_tiles.min(params.image_tiles_caustic).max(1) as usize;
    let ky = ((kx * h) as f64 / w as f64).round().max(1.0) as usize;
    let (mx, my) = (w.div_ceil(kx) + 1, h.div_ceil(ky) + 1);
    let render_tile = |rect: PixelRect, first: u32, count: u32| {
        let mut tile = SplatTile::new(rect, w, h, mx, my);
        let mut explorer =
            Explorer::new(scene, &camera, *params, settings.max_depth, settings.seed);
        for s in first..first + count {
            if cancel.load(Ordering::Relaxed) {
                tile.finish();
                return ((tile, explorer.stats), false);
            }
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    explorer.sample(UVec2::new(x as u32, y as u32), s, &mut tile);
                }
            }
            progress.advance(rect.area() as u64);
        }
        tile.finish();
        ((tile, explorer.stats), true)
    };
    // Splat sums in exact fixed point: sets splat across tiles, and exact sums do not depend
    // on the order tiles are merged in (the same bits for any thread count and any split of
    // the tiles over shards).
    let bound = scene.lights().emission_bound();
    let image = exact_splat_grid(w, h, bound);
    let mut partial: Option<ExactSplatGrid> = None;
    let mut progressions = 0u32;
    let mut totals = ExploreStats::default();
    let mut too_large = 0u64;
    let shard = settings.shard;
    let outcome = render_passes(
        settings.width,
        settings.height,
        settings.budget,
        shard,
        progress,
        cancel,
        render_tile,
        |_, count, done| {
            let units = done.len();
            let complete = done
                .iter()
                .enumerate()
                .all(|(i, t)| !shard.owns(i, units) || matches!(t, Some((_, true))));
            let pass = (!complete).then(|| exact_splat_grid(w, h, bound));
            for ((tile, stats), _) in done.iter().flatten() {
                too_large += tile.merge_into(pass.as_ref().unwrap_or(&image));
                if complete || progressions == 0 {
                    add_stats(&mut totals, stats);
                }
            }
            if complete {
                progressions += count;
            } else if progressions == 0 && partial.is_none() {
                partial = pass;
            }
        },
    );
    let (grid, n) = match (progressions, partial) {
        (0, Some(p)) => (p, 1),
        _ => (image, progressions.max(1)),
    };
    let component = Component::Mean { grid, divisor: n };
    let (out, overflowed) = component.image(w, h);
    let dropped = totals.nonfinite + overflowed + too_large;
    LqmcOutput {
        image: out,
        component: (!shard.is_whole()).then_some(component),
        seeds: totals.seeds,
        progressions,
        explored: totals.explored,
        direct: totals.direct,
        explored_nee: totals.explored_nee,
        direct_nee: totals.direct_nee,
        members: totals.members,
        rejected: totals.rejected,
        dropped_nonfinite: dropped,
        cancelled: outcome.cancelled,
        unsampled_pixels: outcome.unsampled_pixels,
    }
}

fn add_stats(a: &mut ExploreStats, b: &ExploreStats) {
    a.seeds += b.seeds;
    a.explored += b.explored;
    a.direct += b.direct;
    a.explored_nee += b.explored_nee;
    a.direct_nee += b.direct_nee;
    a.members += b.members;
    a.rejected += b.rejected;
    a.nonfinite += b.nonfinite;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::budget::Budget;
    use mcmc_core::NoProgress;

    #[test]
    fn cornell_renders_finite_and_explores() {
        let scene = Scene::cornell_box(24, 24);
        let settings = PtDriverSettings {
            width: 24,
            height: 24,
            max_depth: 3,
            budget: Budget::SamplesPerPixel(2),
            seed: 1,
            sampler: crate::sampler::SamplerKind::Independent,
            roulette: Some(crate::integrator::pt::ROULETTE_DEPTH),
            shard: mcmc_core::render_loop::Shard::WHOLE,
        };
        let out = render_lqmc(
            &scene,
            &settings,
            &LqmcParams::default(),
            &NoProgress,
            &AtomicBool::new(false),
        );
        assert_eq!(out.image.count_nonfinite(), 0);
        assert_eq!(out.progressions, 2);
        assert_eq!(out.seeds, 24 * 24 * 2);
        assert!(out.explored > 0 && out.members > out.explored, "{out:?}");
        assert!(out.image.mean_luminance() > 0.0);
    }
}
