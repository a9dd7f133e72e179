//! Every seed's image of a method read back ([`Results::images`]) and the temporal variance
//! over seeds ([`TemporalVariance`]): the flicker of a still "animation" whose frames are the
//! seeds' renders.

use render::image::Image;

use crate::record::Measure;
use crate::results::Results;
use crate::table::Table;
use crate::ExperimentError;

impl Results {
    /// Every seed's final image of `method` on `scene`, in seed order, read back from the
    /// scene's run directory (empty for an unknown scene or method).
    ///
    /// # Errors
    /// [`ExperimentError::Image`] naming an image that cannot be read.
    pub fn images(&self, scene: &str, method: &str) -> Result<Vec<Image>, ExperimentError> {
        let dir = self.scene_dir(scene);
        self.runs(scene, method)
            .map(|r| Ok(render::image_io::read_image(dir.join(&r.image))?))
            .collect()
    }

    /// The [`TemporalVariance`] of `method` on `scene` over its seeds' images, with blocks of
    /// `block x block` pixels; `None` for fewer than two seeds.
    ///
    /// # Errors
    /// As [`Results::images`].
    pub fn temporal_variance(
        &self,
        scene: &str,
        method: &str,
        block: usize,
    ) -> Result<Option<TemporalVariance>, ExperimentError> {
        Ok(TemporalVariance::of(&self.images(scene, method)?, block))
    }

    /// Per method on `scene`: the mean MSE over seeds, the temporal variance
    /// ([`TemporalVariance::pixel_variance`]), their ratio (the noise part of the error, 1 for
    /// an unbiased method's converged mean), the `block x block` ratio and the block means'
    /// variance ([`TemporalVariance::block_variance`], the low-frequency flicker itself); `-`
    /// where a method has fewer than two seeds.
    ///
    /// # Errors
    /// As [`Results::images`].
    pub fn temporal_table(&self, scene: &str, block: usize) -> Result<Table, ExperimentError> {
        let mut table = Table::new([
            "method".to_owned(),
            "mean MSE".to_owned(),
            "temporal variance (mean per-pixel)".to_owned(),
            "variance / mean MSE".to_owned(),
            format!("{block}x{block}-block variance ratio"),
            format!("{block}x{block}-block-mean variance"),
        ]);
        let show = |v: f64, digits: usize| {
            if v.is_nan() {
                "-".to_owned()
            } else if digits == 0 {
                format!("{v:.3e}")
            } else {
                format!("{v:.2}")
            }
        };
        for method in &self.methods {
            let mse = self.values(scene, method, Measure::Mse);
            let mean = mse.iter().sum::<f64>() / mse.len() as f64;
            let (var, ratio, blocks) = self
                .temporal_variance(scene, method, block)?
                .map_or((f64::NAN, f64::NAN, f64::NAN), |t| {
                    (t.pixel_variance, t.block_ratio, t.block_variance())
                });
            table.push_row([
                method.clone(),
                show(mean, 0),
                show(var, 0),
                show(var / mean, 2),
                show(ratio, 2),
                show(blocks, 0),
            ]);
        }
        Ok(table)
    }
}

/// How much a method's image changes from seed to seed, seen as frames of a still animation
/// with a new seed per frame (Tessari et al. 2020 compare the temporal stability of LQMC and
/// MLT this way).
///
/// For an unbiased method [`TemporalVariance::pixel_variance`] is the noise part of the MSE;
/// [`TemporalVariance::block_ratio`] tells uncorrelated pixel noise (1) from blotches larger
/// than a pixel (above 1: Markov chain clumping, or a lattice set splatting into its tile), the
/// low-frequency flicker an animation shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemporalVariance {
    /// The per-pixel variance of the luminance across frames (unbiased, `n - 1`), averaged
    /// over the pixels.
    pub pixel_variance: f64,
    /// The variance across frames of the mean luminance of `block x block` blocks, averaged
    /// over the blocks, times the pixels per block, over [`TemporalVariance::pixel_variance`];
    /// NaN when the image holds no whole block or the pixel variance is zero.
    pub block_ratio: f64,
    /// The block side of [`TemporalVariance::block_ratio`].
    pub block: usize,
    /// Frames (seeds) measured.
    pub frames: usize,
}

impl TemporalVariance {
    /// The variance across frames of a `block x block` block's mean luminance, averaged over
    /// the blocks (`block_ratio * pixel_variance / block^2`): the low-frequency flicker in
    /// absolute terms, comparable between methods whose pixel noise differs.
    #[must_use]
    pub fn block_variance(&self) -> f64 {
        self.block_ratio * self.pixel_variance / (self.block * self.block) as f64
    }

    /// The temporal variance of `frames` with blocks of `block x block` pixels; `None` for
    /// fewer than two frames, empty images or frames of different sizes.
    ///
    /// # Example
    /// ```
    /// use experiments::TemporalVariance;
    /// use render::image::Image;
    ///
    /// // Two frames of 8 x 8 that differ by a constant: every block flickers as a whole.
    /// let frame = |v: f32| {
    ///     let mut img = Image::new(8, 8);
    ///     img.pixels.iter_mut().for_each(|p| *p = [v; 3]);
    ///     img
    /// };
    /// let t = TemporalVariance::of(&[frame(1.0), frame(3.0)], 4).unwrap();
    /// assert!((t.pixel_variance - 2.0).abs() < 1e-9);
    /// assert!((t.block_ratio - 16.0).abs() < 1e-9);
    /// assert!(TemporalVariance::of(&[frame(1.0)], 4).is_none());
    /// ```
    #[must_use]
    pub fn of(frames: &[Image], block: usize) -> Option<Self> {
        let first = frames.first()?;
        let (w, h) = (first.width, first.height);
        let same = frames.iter().all(|f| (f.width, f.height) == (w, h));
        if frames.len() < 2 || w == 0 || h == 0 || !same {
            return None;
        }
        let mut total = 0.0;
        for y in 0..h {
            for x in 0..w {
                total += variance(frames.iter().map(|f| f64::from(f.luminance(x, y))));
            }
        }
        let pixel_variance = total / (w * h) as f64;
        let (bw, bh) = (w.checked_div(block), h.checked_div(block));
        let (bw, bh) = (bw.unwrap_or(0), bh.unwrap_or(0));
        let block_ratio = if bw == 0 || bh == 0 || pixel_variance <= 0.0 {
            f64::NAN
        } else {
            let mut total = 0.0;
            for by in 0..bh {
                for bx in 0..bw {
                    total += variance(frames.iter().map(|f| {
                        let mut sum = 0.0;
                        for y in by * block..(by + 1) * block {
                            for x in bx * block..(bx + 1) * block {
                                sum += f64::from(f.luminance(x, y));
                            }
                        }
                        sum / (block * block) as f64
                    }));
                }
            }
            total / (bw * bh) as f64 * (block * block) as f64 / pixel_variance
        };
        Some(Self {
            pixel_variance,
            block_ratio,
            block,
            frames: frames.len(),
        })
    }
}

/// The unbiased variance (`n - 1`) of at least two values.
fn variance(values: impl Iterator<Item = f64> + Clone) -> f64 {
    let n = values.clone().count() as f64;
    let mean = values.clone().sum::<f64>() / n;
    values.map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::tiny_experiment;

    /// An 8 x 8 frame with `f(x, y)` in every channel.
    fn frame(f: impl Fn(usize, usize) -> f32) -> Image {
        let mut img = Image::new(8, 8);
        for y in 0..8 {
            for x in 0..8 {
                img.set(x, y, [f(x, y); 3]);
            }
        }
        img
    }

    #[test]
    fn blotches_raise_the_block_ratio_and_pixel_noise_does_not() {
        // Whole-frame offsets: every block flickers as one, the ratio is the block's pixels.
        let offsets = [frame(|_, _| 1.0), frame(|_, _| 2.0), frame(|_, _| 4.0)];
        let t = TemporalVariance::of(&offsets, 4).unwrap();
        assert!((t.block_ratio - 16.0).abs() < 1e-9, "{t:?}");
        assert_eq!(t.frames, 3);
        // The block means are the frame values 1, 2, 4: their variance is 7/3.
        assert!((t.block_variance() - 7.0 / 3.0).abs() < 1e-9, "{t:?}");
        // Negative control: a checkerboard sign flip per frame leaves every block mean fixed.
        let checker = |s: f32| frame(move |x, y| 2.0 + if (x + y) % 2 == 0 { s } else { -s });
        let t = TemporalVariance::of(&[checker(1.0), checker(-1.0)], 4).unwrap();
        assert!((t.pixel_variance - 2.0).abs() < 1e-9, "{t:?}");
        assert!(t.block_ratio.abs() < 1e-12, "{t:?}");
        assert!(t.block_variance().abs() < 1e-12, "{t:?}");
    }

    #[test]
    fn degenerate_inputs_give_none_or_nan() {
        let a = frame(|x, _| x as f32);
        assert!(TemporalVariance::of(&[], 4).is_none());
        assert!(TemporalVariance::of(std::slice::from_ref(&a), 4).is_none());
        assert!(TemporalVariance::of(&[a.clone(), Image::new(4, 4)], 4).is_none());
        let still = TemporalVariance::of(&[a.clone(), a.clone()], 4).unwrap();
        assert_eq!(still.pixel_variance, 0.0);
        assert!(still.block_ratio.is_nan(), "no flicker, no ratio");
        let b = frame(|x, y| (x * y) as f32);
        assert!(TemporalVariance::of(&[a.clone(), b.clone()], 16)
            .unwrap()
            .block_ratio
            .is_nan());
        assert!(TemporalVariance::of(&[a, b], 0)
            .unwrap()
            .block_ratio
            .is_nan());
    }

    #[test]
    fn images_reads_back_every_seed_in_order() {
        let (results, _out) = tiny_experiment("temporal-images");
        let images = results.images("cornell-box", "PT").unwrap();
        assert_eq!(images.len(), results.plan.seeds.len());
        for (image, seed) in images.iter().zip(&results.plan.seeds) {
            let run = results.run("cornell-box", "PT", *seed).unwrap();
            let m = render::metrics::compare(image, &images[0]).unwrap();
            assert_eq!(m.mse == 0.0, *seed == results.plan.seeds[0], "seed {seed}");
            assert!(run.image.to_string_lossy().contains(&format!("seed{seed}")));
        }
        let table = results.temporal_table("cornell-box", 4).unwrap();
        assert_eq!(table.headers()[4], "4x4-block variance ratio");
        assert_eq!(table.headers()[5], "4x4-block-mean variance");
        assert_eq!(table.rows()[1][0], "BDPT");
        assert_ne!(table.rows()[1][2], "-");
        // Negative control: an unknown method has no images, a missing file is an error.
        assert!(results.images("cornell-box", "nope").unwrap().is_empty());
        let first = results
            .run("cornell-box", "PT", results.plan.seeds[0])
            .unwrap();
        std::fs::remove_file(results.scene_dir("cornell-box").join(&first.image)).unwrap();
        assert!(results.images("cornell-box", "PT").is_err());
        let t = results.temporal_variance("cornell-box", "BDPT", 4).unwrap();
        assert!(t.is_some_and(|t| t.pixel_variance > 0.0 && t.frames == 3));
    }
}
