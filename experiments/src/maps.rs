//! Per-pixel maps of a run as upscaled false-colour PNG previews: the relative error against
//! the reference, or any map a method returns (a learned scale, a stage share, ...).
//!
//! Maps are named after the run's method: `<slug>_<suffix>.png` in the scene's run directory
//! ([`map_path`]); write them for one seed per method (e.g. the first) from
//! [`crate::Experiment::inspect`], or for every method's first seed after the run with
//! [`Results::write_error_maps`].

use std::path::{Path, PathBuf};

use render::image::Image;
use render::image_io::{write_false_color, ErrorScale};

use crate::record::RunRecord;
use crate::results::Results;
use crate::ExperimentError;

/// Log10 from 1e-3 (bottom colour) to 1 (top): the report's relative-error scale, and a fair
/// one for angles in radians.
pub const LOG_SCALE: ErrorScale = ErrorScale::Log10 {
    min: 1e-3,
    max: 1.0,
};

/// `values` (`width x height`, row-major) with every value repeated `factor` times along
/// both axes (nearest neighbour); `factor` 0 counts as 1.
///
/// # Example
/// ```
/// assert_eq!(experiments::maps::upscale(&[1.0, 2.0], 2, 1, 2), [1.0, 1.0, 2.0, 2.0, 1.0, 1.0, 2.0, 2.0]);
/// ```
///
/// # Panics
/// If `values` holds fewer than `width * height` values.
#[must_use]
pub fn upscale(values: &[f32], width: usize, height: usize, factor: usize) -> Vec<f32> {
    let factor = factor.max(1);
    let mut out = Vec::with_capacity(width * height * factor * factor);
    for y in 0..height * factor {
        let row = &values[(y / factor) * width..][..width];
        out.extend(row.iter().flat_map(|&v| std::iter::repeat_n(v, factor)));
    }
    out
}

/// Writes `values` (`width x height`, row-major) as a viridis PNG on `scale`, upscaled
/// `factor` times ([`upscale`]).
///
/// # Errors
/// [`ExperimentError::Invalid`] if `values` does not hold `width * height` values;
/// [`ExperimentError::Image`] if the file cannot be written.
pub fn write_map_png(
    path: impl AsRef<Path>,
    values: &[f32],
    width: usize,
    height: usize,
    scale: ErrorScale,
    factor: usize,
) -> Result<(), ExperimentError> {
    let path = path.as_ref();
    if values.len() != width * height {
        return Err(ExperimentError::Invalid(format!(
            "{}: {} values for a {width}x{height} map",
            path.display(),
            values.len()
        )));
    }
    let factor = factor.max(1);
    let big = upscale(values, width, height, factor);
    write_false_color(path, &big, width * factor, height * factor, scale)?;
    Ok(())
}

/// Writes the per-pixel relative error of `image` against `reference`
/// ([`render::metrics::relative_error_map`]) on [`LOG_SCALE`], upscaled.
///
/// # Errors
/// [`ExperimentError::Invalid`] if the sizes differ; as [`write_map_png`].
pub fn write_error_map_png(
    path: impl AsRef<Path>,
    image: &Image,
    reference: &Image,
    factor: usize,
) -> Result<(), ExperimentError> {
    let path = path.as_ref();
    let map = render::metrics::relative_error_map(image, reference)
        .map_err(|e| ExperimentError::Invalid(format!("{}: {e}", path.display())))?;
    write_map_png(
        path,
        &map,
        reference.width,
        reference.height,
        LOG_SCALE,
        factor,
    )
}

/// `<dir>/<slug>_<suffix>.png`: the map `suffix` of `record`'s method, named after the
/// method's images (`<slug>_seed<seed>.exr`).
///
/// # Example
/// ```
/// # let record = experiments::RunRecord {
/// #     scene: "s".into(), method: "lens FIXED".into(), seed: 7, seconds: 1.0, samples: 1,
/// #     metrics: render::metrics::Metrics { mse: 0.0, rmse: 0.0, relmse: 0.0, rrmse: 0.0, mad: 0.0 },
/// #     stats: Default::default(), load: None, image: "lens-fixed_seed7.exr".into(),
/// #     convergence: Vec::new(),
/// # };
/// let path = experiments::maps::map_path("out/s".as_ref(), &record, "sigma");
/// assert_eq!(path, std::path::Path::new("out/s/lens-fixed_sigma.png"));
/// ```
#[must_use]
pub fn map_path(dir: &Path, record: &RunRecord, suffix: &str) -> PathBuf {
    let file = record.image.file_name().map_or_else(
        || record.method.clone(),
        |f| f.to_string_lossy().into_owned(),
    );
    let tail = format!("_seed{}.exr", record.seed);
    let slug = file.strip_suffix(&tail).unwrap_or(&file);
    dir.join(format!("{slug}_{suffix}.png"))
}

/// Writes a per-pixel map of `record`'s run (`values`, row-major, `width` pixels wide; e.g. a
/// learned scale per pixel) to [`map_path`]`(dir, record, suffix)` with [`write_map_png`];
/// returns the path.
///
/// # Errors
/// [`ExperimentError::Invalid`] for an empty map or one that is not a whole number of rows;
/// as [`write_map_png`].
pub fn write_run_map(
    dir: &Path,
    record: &RunRecord,
    suffix: &str,
    values: &[f64],
    width: usize,
    scale: ErrorScale,
    factor: usize,
) -> Result<PathBuf, ExperimentError> {
    let path = map_path(dir, record, suffix);
    if width == 0 || values.is_empty() || !values.len().is_multiple_of(width) {
        return Err(ExperimentError::Invalid(format!(
            "{}: {} values are no rows of {width}",
            path.display(),
            values.len()
        )));
    }
    let map: Vec<f32> = values.iter().map(|&v| v as f32).collect();
    write_map_png(&path, &map, width, values.len() / width, scale, factor)?;
    Ok(path)
}

impl Results {
    /// Writes every method's relative-error map of its first seed on every scene,
    /// `<slug>_error.png` ([`map_path`], [`write_error_map_png`]), upscaled `factor` times;
    /// returns the paths.
    ///
    /// # Errors
    /// [`ExperimentError::Image`] for an image or reference that cannot be read or a map that
    /// cannot be written.
    pub fn write_error_maps(&self, factor: usize) -> Result<Vec<PathBuf>, ExperimentError> {
        let mut written = Vec::new();
        let Some(&seed) = self.plan.seeds.first() else {
            return Ok(written);
        };
        for scene in &self.scenes {
            let dir = self.scene_dir(scene);
            let reference = render::image_io::read_image(dir.join("reference.exr"))?;
            for method in &self.methods {
                let Some(run) = self.run(scene, method, seed) else {
                    continue;
                };
                let image = render::image_io::read_image(dir.join(&run.image))?;
                let path = map_path(&dir, run, "error");
                write_error_map_png(&path, &image, &reference, factor)?;
                written.push(path);
            }
        }
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{scratch, tiny_experiment};

    #[test]
    fn upscale_repeats_rows_and_columns() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let big = upscale(&v, 3, 2, 2);
        assert_eq!(big.len(), 24);
        assert_eq!(&big[..6], &[1.0, 1.0, 2.0, 2.0, 3.0, 3.0]);
        assert_eq!(&big[6..12], &big[..6]);
        assert_eq!(&big[12..18], &[4.0, 4.0, 5.0, 5.0, 6.0, 6.0]);
        assert_eq!(upscale(&v, 3, 2, 0), v, "factor 0 is 1");
    }

    #[test]
    fn maps_are_written_upscaled_and_wrong_sizes_refused() {
        let dir = scratch("maps");
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.png");
        write_map_png(&path, &[0.01, 0.1, 1.0, 0.5], 2, 2, LOG_SCALE, 3).unwrap();
        let png = image::open(&path).unwrap();
        assert_eq!((png.width(), png.height()), (6, 6));
        // Negative control: a map of the wrong length is refused, nothing written.
        let bad = dir.join("bad.png");
        assert!(write_map_png(&bad, &[1.0; 3], 2, 2, LOG_SCALE, 3).is_err());
        assert!(!bad.exists());
        assert!(write_error_map_png(&bad, &Image::new(2, 2), &Image::new(3, 2), 1).is_err());
    }

    #[test]
    fn run_maps_are_named_after_the_method() {
        let (results, out) = tiny_experiment("maps-run");
        let dir = out.join("cornell-box");
        let run = results.run("cornell-box", "BDPT", 1).unwrap();
        let path = write_run_map(&dir, run, "sigma", &[0.01; 6], 3, LOG_SCALE, 2).unwrap();
        assert_eq!(path, dir.join("BDPT_sigma.png"));
        let png = image::open(&path).unwrap();
        assert_eq!((png.width(), png.height()), (6, 4));
        // Negative controls: ragged or empty maps are refused.
        assert!(write_run_map(&dir, run, "x", &[0.01; 5], 3, LOG_SCALE, 2).is_err());
        assert!(write_run_map(&dir, run, "x", &[], 3, LOG_SCALE, 2).is_err());
        assert!(write_run_map(&dir, run, "x", &[0.1], 0, LOG_SCALE, 2).is_err());
        assert!(!dir.join("BDPT_x.png").exists());
    }

    #[test]
    fn error_maps_of_every_methods_first_seed() {
        let (results, out) = tiny_experiment("maps-error");
        let written = results.write_error_maps(2).unwrap();
        assert_eq!(
            written,
            [
                out.join("cornell-box/PT_error.png"),
                out.join("cornell-box/BDPT_error.png")
            ]
        );
        let png = image::open(&written[0]).unwrap();
        assert_eq!((png.width(), png.height()), (16, 16));
        // Negative control: no map of a later seed.
        assert!(!out.join("cornell-box/PT_seed2_error.png").exists());
    }
}
