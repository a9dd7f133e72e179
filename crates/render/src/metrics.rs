//! Image error metrics against a reference: MSE, RMSE, relMSE, rRMSE and MAD (see `docs/metrics.md`).
//!
//! For an image `I` and a reference `R` of `W × H` pixels with channels `c ∈ {r, g, b}`
//! (`N = 3·W·H` samples), all sums accumulated in `f64`:
//!
//! | metric | definition | used by |
//! |---|---|---|
//! | [`mse`] | `Σ_{px,c} (I − R)² / N` | Langevin MCMC rendering (Luan et al. 2020) |
//! | [`rmse`] | `sqrt(Σ_{px,c} (I − R)² / (W·H))` = `sqrt(3 · MSE)` | corona-13's `pfmdiff` (LQMC authors' code) |
//! | [`relmse`] | `Σ_{px,c} (I − R)² / (R² + ε) / N`, `ε = 10⁻²` | DRMLT (Rioux-Lavoie et al. 2020), "rmSE" |
//! | [`rrmse`] | `sqrt(relMSE)` | Regional adaptive MLT (Otsu et al.), which does not define it |
//! | [`mad`] | `Σ_{px,c} \|I − R\| / N` | Local QMC exploration (Tessari et al.), ajar door |
//!
//! Non-finite policy: a NaN or infinite channel in either image is an error
//! ([`MetricError::NonFinite`], reporting how many pixels and the first one), never silently
//! skipped, because a skipped firefly would flatter the method being measured.

use crate::image::Image;

/// The `ε` added to `R²` in the relative metrics ([`relmse`], [`rrmse`],
/// [`relative_error_map`]): the common Rousselle / Bitterli convention.
pub const RELMSE_EPSILON: f64 = 1e-2;

/// Which of the two compared images a [`MetricError`] refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// The image being measured.
    Image,
    /// The reference image.
    Reference,
}

impl std::fmt::Display for Which {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Image => "image",
            Self::Reference => "reference",
        })
    }
}

/// Why two images cannot be compared.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum MetricError {
    /// The images differ in size.
    #[error(
        "size mismatch: image is {image_width}x{image_height}, \
         reference is {reference_width}x{reference_height}"
    )]
    SizeMismatch {
        /// Width of the image being measured.
        image_width: usize,
        /// Height of the image being measured.
        image_height: usize,
        /// Width of the reference.
        reference_width: usize,
        /// Height of the reference.
        reference_height: usize,
    },
    /// The images have no pixels (or a pixel count that does not match their size).
    #[error("cannot compare empty or malformed images ({width}x{height}, {pixels} pixels)")]
    Empty {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// Number of pixels present in the image being measured.
        pixels: usize,
    },
    /// One image holds NaN or infinite values.
    #[error(
        "the {which} has {count} pixel(s) with NaN or infinite values, the first at ({x}, {y})"
    )]
    NonFinite {
        /// The image with bad pixels.
        which: Which,
        /// How many pixels have at least one non-finite channel.
        count: usize,
        /// Column of the first bad pixel.
        x: usize,
        /// Row of the first bad pixel.
        y: usize,
    },
}

/// All metrics of one comparison.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// Mean squared error, see [`mse`].
    pub mse: f64,
    /// Root of the per-pixel summed squared error (corona-13), see [`rmse`].
    pub rmse: f64,
    /// Relative mean squared error, see [`relmse`].
    pub relmse: f64,
    /// Relative root mean squared error, see [`rrmse`].
    pub rrmse: f64,
    /// Mean absolute difference, see [`mad`].
    pub mad: f64,
}

fn check(image: &Image, reference: &Image) -> Result<(), MetricError> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(MetricError::SizeMismatch {
            image_width: image.width,
            image_height: image.height,
            reference_width: reference.width,
            reference_height: reference.height,
        });
    }
    let n = image.width.checked_mul(image.height);
    if n == Some(0) || n != Some(image.pixels.len()) || n != Some(reference.pixels.len()) {
        return Err(MetricError::Empty {
            width: image.width,
            height: image.height,
            pixels: image.pixels.len(),
        });
    }
    for (which, img) in [(Which::Image, image), (Which::Reference, reference)] {
        let bad = |p: &[f32; 3]| !p.iter().all(|c| c.is_finite());
        if let Some(first) = img.pixels.iter().position(bad) {
            return Err(MetricError::NonFinite {
                which,
                count: img.pixels.iter().filter(|p| bad(p)).count(),
                x: first % img.width,
                y: first / img.width,
            });
        }
    }
    Ok(())
}

/// Mean over validated channel pairs of `f(i, r)`, in f64.
fn mean_of(
    image: &Image,
    reference: &Image,
    f: impl Fn(f64, f64) -> f64,
) -> Result<f64, MetricError> {
    check(image, reference)?;
    let mut sum = 0.0;
    for (p, q) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            sum += f(f64::from(p[c]), f64::from(q[c]));
        }
    }
    Ok(sum / (3 * image.pixels.len()) as f64)
}

/// Mean squared error over pixels and channels: `MSE = Σ_{px,c} (I − R)² / (3·W·H)`.
///
/// # Errors
///
/// See [`MetricError`]: size mismatch, empty images, non-finite values.
pub fn mse(image: &Image, reference: &Image) -> Result<f64, MetricError> {
    mean_of(image, reference, |i, r| (i - r) * (i - r))
}

/// RMSE as corona-13's `pfmdiff` computes it: `sqrt(Σ_px Σ_rgb (I − R)² / (W·H))`, i.e. the
/// channel errors are summed, not averaged (`RMSE = sqrt(3 · MSE)`).
///
/// # Errors
///
/// See [`MetricError`].
pub fn rmse(image: &Image, reference: &Image) -> Result<f64, MetricError> {
    Ok((3.0 * mse(image, reference)?).sqrt())
}

/// Relative MSE: `relMSE = Σ_{px,c} (I − R)² / (R² + ε) / (3·W·H)` with `ε =`
/// [`RELMSE_EPSILON`] (Rousselle / Bitterli convention; the DRMLT paper's "rmSE").
///
/// # Errors
///
/// See [`MetricError`].
pub fn relmse(image: &Image, reference: &Image) -> Result<f64, MetricError> {
    mean_of(image, reference, |i, r| {
        (i - r) * (i - r) / (r * r + RELMSE_EPSILON)
    })
}

/// Relative root mean squared error: `rRMSE = sqrt(relMSE)`. The regional adaptive MLT paper
/// reports rRMSE without defining it; this is our reading.
///
/// # Errors
///
/// See [`MetricError`].
pub fn rrmse(image: &Image, reference: &Image) -> Result<f64, MetricError> {
    Ok(relmse(image, reference)?.sqrt())
}

/// Mean absolute difference over pixels and channels: `MAD = Σ_{px,c} |I − R| / (3·W·H)` (the
/// LQMC paper's metric for high-dynamic-range scenes).
///
/// # Errors
///
/// See [`MetricError`].
pub fn mad(image: &Image, reference: &Image) -> Result<f64, MetricError> {
    mean_of(image, reference, |i, r| (i - r).abs())
}

/// Every metric at once (one validation, two passes).
///
/// # Errors
///
/// See [`MetricError`].
pub fn compare(image: &Image, reference: &Image) -> Result<Metrics, MetricError> {
    let mse = mse(image, reference)?;
    let relmse = relmse(image, reference)?;
    Ok(Metrics {
        mse,
        rmse: (3.0 * mse).sqrt(),
        relmse,
        rrmse: relmse.sqrt(),
        mad: mad(image, reference)?,
    })
}

/// Per-pixel relative error for error maps: `e_px = sqrt(Σ_c (I − R)² / (R² + ε) / 3)`, the
/// rRMSE of that pixel alone, so that the mean of `e²` over pixels equals [`relmse`]. One value
/// per pixel, row-major, top row first.
///
/// # Errors
///
/// See [`MetricError`].
pub fn relative_error_map(image: &Image, reference: &Image) -> Result<Vec<f32>, MetricError> {
    check(image, reference)?;
    Ok(image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, q)| {
            let mut sum = 0.0;
            for c in 0..3 {
                let (i, r) = (f64::from(p[c]), f64::from(q[c]));
                sum += (i - r) * (i - r) / (r * r + RELMSE_EPSILON);
            }
            (sum / 3.0).sqrt() as f32
        })
        .collect())
}

/// Median, minimum and maximum of `values` (NaNs ordered last by `f64::total_cmp`): the
/// summary the paper examples report over seeds. `None` for an empty slice.
///
/// # Example
/// ```
/// assert_eq!(render::metrics::median_min_max(&[3.0, 1.0, 2.0, 10.0]), Some((2.5, 1.0, 10.0)));
/// ```
#[must_use]
pub fn median_min_max(values: &[f64]) -> Option<(f64, f64, f64)> {
    if values.is_empty() {
        return None;
    }
    let mut s = values.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    let median = if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    };
    Some((median, s[0], s[n - 1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2x1 image vs reference, hand-computed:
    /// pixel 0: I = (1, 2, 3), R = (1, 1, 1) -> diffs (0, 1, 2)
    /// pixel 1: I = (0, 0, 0), R = (0, 0.5, 1) -> diffs (0, -0.5, -1)
    fn pair() -> (Image, Image) {
        let image = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]).unwrap();
        let reference = Image::from_pixels(2, 1, vec![[1.0, 1.0, 1.0], [0.0, 0.5, 1.0]]).unwrap();
        (image, reference)
    }

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
    }

    #[test]
    fn mse_and_rmse() {
        let (i, r) = pair();
        // squared diffs: 0 + 1 + 4 + 0 + 0.25 + 1 = 6.25 over 6 samples.
        close(mse(&i, &r).unwrap(), 6.25 / 6.0);
        // corona: sqrt(6.25 / 2 pixels) = sqrt(3.125).
        close(rmse(&i, &r).unwrap(), 3.125f64.sqrt());
    }

    #[test]
    fn relmse_and_rrmse() {
        let (i, r) = pair();
        // 0/(1.01) + 1/1.01 + 4/1.01 + 0/0.01 + 0.25/(0.25+0.01) + 1/1.01
        let expected = (6.0 / 1.01 + 0.25 / 0.26) / 6.0;
        close(relmse(&i, &r).unwrap(), expected);
        close(rrmse(&i, &r).unwrap(), expected.sqrt());
    }

    #[test]
    fn mad_value() {
        let (i, r) = pair();
        close(mad(&i, &r).unwrap(), (1.0 + 2.0 + 0.5 + 1.0) / 6.0);
    }

    #[test]
    fn compare_agrees_with_each_metric_and_zero_on_identical() {
        let (i, r) = pair();
        let m = compare(&i, &r).unwrap();
        close(m.mse, mse(&i, &r).unwrap());
        close(m.rmse, rmse(&i, &r).unwrap());
        close(m.relmse, relmse(&i, &r).unwrap());
        close(m.rrmse, rrmse(&i, &r).unwrap());
        close(m.mad, mad(&i, &r).unwrap());
        let z = compare(&r, &r).unwrap();
        assert_eq!(
            (z.mse, z.rmse, z.relmse, z.rrmse, z.mad),
            (0.0, 0.0, 0.0, 0.0, 0.0)
        );
    }

    #[test]
    fn error_map_squares_average_to_relmse() {
        let (i, r) = pair();
        let map = relative_error_map(&i, &r).unwrap();
        assert_eq!(map.len(), 2);
        let expected0 = (5.0 / 1.01 / 3.0f64).sqrt();
        assert!((f64::from(map[0]) - expected0).abs() < 1e-6, "{map:?}");
        let mean_sq = map
            .iter()
            .map(|&e| f64::from(e) * f64::from(e))
            .sum::<f64>()
            / 2.0;
        assert!((mean_sq - relmse(&i, &r).unwrap()).abs() < 1e-6);
    }

    #[test]
    fn errors() {
        let (i, _) = pair();
        let other = Image::new(1, 2);
        let err = mse(&i, &other).unwrap_err();
        assert!(matches!(
            err,
            MetricError::SizeMismatch {
                image_width: 2,
                reference_width: 1,
                ..
            }
        ));
        assert!(
            err.to_string().contains("2x1") && err.to_string().contains("1x2"),
            "{err}"
        );

        let empty = Image::new(0, 0);
        assert!(matches!(
            mad(&empty, &empty),
            Err(MetricError::Empty { .. })
        ));

        let mut bad = i.clone();
        bad.set(1, 0, [0.0, f32::NAN, 0.0]);
        let err = relmse(&i, &bad).unwrap_err();
        assert_eq!(
            err,
            MetricError::NonFinite {
                which: Which::Reference,
                count: 1,
                x: 1,
                y: 0
            }
        );
        assert!(err.to_string().contains("reference"), "{err}");
        bad.set(0, 0, [f32::INFINITY; 3]);
        let err = compare(&bad, &i).unwrap_err();
        assert_eq!(
            err,
            MetricError::NonFinite {
                which: Which::Image,
                count: 2,
                x: 0,
                y: 0
            }
        );
    }
}
