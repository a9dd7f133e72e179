//! Self-contained HTML comparison reports: a reference, each method's images over seeds,
//! metrics, error maps and convergence plots in one `report.html` that needs no network.
//!
//! A report is built from a [`RunManifest`] — the `run.json` of a run directory an example wrote
//! ([`RunManifest::load`]), or one assembled from loose EXR files ([`RunManifest::from_images`]).
//! [`write_report`] computes the metrics with [`render::metrics`], draws the false-colour error
//! maps with [`render::image_io::false_color_rgb8`], plots convergence with [`crate::plot`] (SVG) and
//! fills an HTML template with minijinja. Images are embedded as data URIs (PNG) and as base64
//! float data for the exposure control and the pixel inspector, so the file stands alone.
//!
//! # Example
//! ```no_run
//! use experiments::report::{write_report, RunManifest};
//!
//! let manifest = RunManifest::load("out/zsolnai/cornell-glass")?;
//! let html = write_report(&manifest, "out/zsolnai/cornell-glass", "out/zsolnai/cornell-glass/report.html")?;
//! println!("wrote {}", html.display());
//! # Ok::<(), experiments::report::ReportError>(())
//! ```

mod build;
mod check;
mod manifest;

use std::path::PathBuf;

pub use build::write_report;
pub use check::find_external_urls;
pub use manifest::{
    ConvergencePoint, ConvergenceSeries, MethodRun, RunManifest, SeedImage, BUILD_COMMIT,
    MANIFEST_FILE,
};

/// Errors building a report; each names the file or method at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// A file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// `run.json` is not a valid manifest.
    #[error("{}: not a valid run manifest: {message}", path.display())]
    Manifest {
        /// The manifest file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An image could not be read.
    #[error(transparent)]
    Image(#[from] render::image_io::ImageError),
    /// An image does not match the reference (size, non-finite pixels).
    #[error("{}: cannot compare with the reference: {source}", path.display())]
    Metric {
        /// The image.
        path: PathBuf,
        /// The underlying error.
        source: render::metrics::MetricError,
    },
    /// The manifest is well-formed but unusable (no methods, duplicate names, ...).
    #[error("invalid run: {0}")]
    Invalid(String),
    /// Encoding a PNG, plotting or templating failed.
    #[error("cannot produce the report: {0}")]
    Output(String),
}

impl RunManifest {
    /// Saves `dir/run.json` and writes `dir/report.html` from it: what an example does at the
    /// end of a run. Returns the report's path.
    ///
    /// # Errors
    /// As [`RunManifest::save`] and [`write_report`].
    pub fn save_with_report(
        &self,
        dir: impl AsRef<std::path::Path>,
    ) -> Result<PathBuf, ReportError> {
        let dir = dir.as_ref();
        self.save(dir)?;
        write_report(self, dir, dir.join("report.html"))
    }

    /// A manifest comparing loose images with a reference: one method per image, named after
    /// its file stem, seed 0, no convergence samples.
    #[must_use]
    pub fn from_images(reference: PathBuf, images: &[PathBuf], commit: String) -> Self {
        let methods = images
            .iter()
            .map(|p| MethodRun {
                name: p
                    .file_stem()
                    .map_or_else(|| p.display().to_string(), |s| s.to_string_lossy().into()),
                images: vec![SeedImage {
                    seed: 0,
                    path: p.clone(),
                }],
                ..MethodRun::default()
            })
            .collect();
        Self {
            title: "chainlight comparison".into(),
            commit,
            parameters: Default::default(),
            reference,
            methods,
        }
    }
}
