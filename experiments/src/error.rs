//! The one error type of the experiments package: every variant names the file, flag, scene or
//! method at fault.

use std::path::PathBuf;

use crate::report::ReportError;

/// Why an experiment could not be set up, run or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExperimentError {
    /// A file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A render failed (invalid settings for the integrator, a scene it refuses, ...).
    #[error("{scene}, {method}, seed {seed}: {source}")]
    Render {
        /// The scene.
        scene: String,
        /// The method's name.
        method: String,
        /// The seed.
        seed: u64,
        /// The renderer's error.
        source: render::RenderError,
    },
    /// An image could not be read or written.
    #[error(transparent)]
    Image(#[from] render::image_io::ImageError),
    /// The run manifest or the report could not be written.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// A scene or its reference could not be loaded.
    #[error("{0}")]
    Scene(String),
    /// A file of a sweep (job list, status, run record) is malformed.
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// The experiment is inconsistent: no methods, a duplicate name, an unknown baseline, a
    /// flag out of range, a reference of the wrong size, ...
    #[error("invalid experiment: {0}")]
    Invalid(String),
}

impl ExperimentError {
    /// [`ExperimentError::Io`] for `path`.
    pub(crate) fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Self::Io { path, source }
    }

    /// [`ExperimentError::Format`] for `path`.
    pub(crate) fn format(path: impl Into<PathBuf>, message: impl ToString) -> Self {
        Self::Format {
            path: path.into(),
            message: message.to_string(),
        }
    }
}
