//! The delayed-rejection "stage map" (Rioux-Lavoie et al. 2020, Fig. 1 and 9): per pixel, the
//! share of the image's splat mass that comes from second-stage candidates.
//!
//! With the unbiased splatting of `mcmc_core::DelayedRejection` a second-stage candidate `z`
//! is splatted with weight `a2`; [`StagedSplats`] adds those splats to the image *and* to a
//! second layer, so `stage map = second-stage layer / image` (luminance) is the expected
//! fraction of each pixel's estimate contributed by stage-2 moves: 0 where the first stage
//! does all the work, larger where delayed rejection rescues rejected small steps (glossy
//! highlights and caustics in the paper). The ratio is scale-free, so it needs no `b`.

use std::sync::Arc;

use mcmc_core::render_loop::{ExactSplatGrid, Splat, SplatSink};

use crate::image::{luminance, Image};

/// The render loop's sink for MCMC integrators: the image's splat sums and, optionally, the
/// sums of second-stage splats (allocated only when a stage map is asked for).
///
/// The layers are [`ExactSplatGrid`]s shared by every job of a render (a clone shares them):
/// one image of memory per layer for any number of jobs and threads, and sums that do not
/// depend on the order of the splats (the same bits for any thread count, and for a render
/// split into parts that are added up later).
#[derive(Clone, Debug)]
pub struct StagedSplats {
    /// All splats.
    pub image: Arc<ExactSplatGrid>,
    /// Second-stage splats only (`None`: no stage map).
    pub stage2: Option<Arc<ExactSplatGrid>>,
}

impl StagedSplats {
    /// A zeroed sink; `stage_map` allocates the second-stage layer.
    #[must_use]
    pub fn new(width: usize, height: usize, stage_map: bool) -> Self {
        Self {
            image: Arc::new(ExactSplatGrid::new(width, height)),
            stage2: stage_map.then(|| Arc::new(ExactSplatGrid::new(width, height))),
        }
    }

    /// The stage map: per pixel `lum(stage2) / lum(image)` as grey (0 where the image is 0);
    /// `None` without the second-stage layer.
    #[must_use]
    pub fn stage_map(&self) -> Option<Image> {
        let stage2 = self.stage2.as_ref()?;
        let (w, h) = (self.image.width(), self.image.height());
        let mut img = Image::new(w, h);
        let all = self.image.pixels();
        let second = stage2.pixels();
        for (i, px) in img.pixels.iter_mut().enumerate() {
            let l = |p: [f64; 3]| f64::from(luminance(p.map(|c| c as f32)));
            let (a, s) = (l(all[i]), l(second[i]));
            let v = if a > 0.0 && a.is_finite() && s.is_finite() {
                (s / a) as f32
            } else {
                0.0
            };
            *px = [v; 3];
        }
        Some(img)
    }
}

impl SplatSink for StagedSplats {
    #[inline]
    fn add(&mut self, splat: &Splat, weight: f64) -> bool {
        self.image.add_rgb(splat.raster, splat.rgb, weight)
    }

    #[inline]
    fn add_at_stage(&mut self, splat: &Splat, weight: f64, stage: u8) -> bool {
        let added = self.image.add_rgb(splat.raster, splat.rgb, weight);
        if added && stage == 2 {
            if let Some(layer) = &self.stage2 {
                layer.add_rgb(splat.raster, splat.rgb, weight);
            }
        }
        added
    }

    /// Adds `other`'s layers unless they are this sink's own (clones share their layers, so
    /// the render loop's per-job merge is free).
    fn merge(&mut self, other: &Self) {
        self.image.add_grid(&other.image);
        if let (Some(a), Some(b)) = (&self.stage2, &other.stage2) {
            a.add_grid(b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_map_is_the_second_stage_share() {
        let mut s = StagedSplats::new(2, 1, true);
        let splat = |x: f32| Splat {
            raster: [x, 0.5],
            rgb: [1.0, 1.0, 1.0],
        };
        assert!(s.add(&splat(0.5), 3.0));
        assert!(s.add_at_stage(&splat(0.5), 1.0, 2));
        assert!(s.add_at_stage(&splat(1.5), 2.0, 1));
        let map = s.stage_map().unwrap();
        assert!((map.pixels[0][0] - 0.25).abs() < 1e-6);
        assert_eq!(map.pixels[1][0], 0.0);
        // The image layer holds every splat.
        assert!((s.image.get(0, 0)[0] - 4.0).abs() < 1e-12);
        assert!(StagedSplats::new(2, 1, false).stage_map().is_none());
    }
}
