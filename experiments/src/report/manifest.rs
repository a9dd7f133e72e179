//! The run directory an example writes: `run.json` naming the reference, each method's images
//! (one per seed), parameters and error-vs-time samples.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::ReportError;

/// File name of the manifest inside a run directory.
pub const MANIFEST_FILE: &str = "run.json";

/// What one comparison run produced: the contents of `run.json`.
///
/// Image paths are relative to the run directory (absolute paths are kept as they are).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunManifest {
    /// Heading of the report, e.g. `zsolnai_large_step: cornell-glass`.
    pub title: String,
    /// The commit of the chainlight build that made the run ([`BUILD_COMMIT`]), or `unknown`.
    pub commit: String,
    /// Parameters shared by every method (size, budget, depth, ...), shown as a table.
    #[serde(default)]
    pub parameters: BTreeMap<String, String>,
    /// The reference image (EXR/PFM/HDR).
    pub reference: PathBuf,
    /// The compared methods, in the order the report lists them.
    pub methods: Vec<MethodRun>,
}

/// One method of a run: its images over seeds and its convergence samples.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodRun {
    /// Name shown in the report (unique within a run).
    pub name: String,
    /// Parameters particular to this method.
    #[serde(default)]
    pub parameters: BTreeMap<String, String>,
    /// Final images, one per seed.
    pub images: Vec<SeedImage>,
    /// Error-vs-time samples, one series per seed (may be empty).
    #[serde(default)]
    pub convergence: Vec<ConvergenceSeries>,
}

/// The final image of one seed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SeedImage {
    /// The seed the image was rendered with.
    pub seed: u64,
    /// Path of the image (EXR/PFM/HDR).
    pub path: PathBuf,
}

/// Error against the reference at increasing render times, for one seed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ConvergenceSeries {
    /// The seed of the series.
    pub seed: u64,
    /// Samples in increasing time.
    pub points: Vec<ConvergencePoint>,
}

/// One error-vs-time sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ConvergencePoint {
    /// Wall-clock render time in seconds.
    pub time_s: f64,
    /// relMSE against the reference at that time.
    pub relmse: f64,
}

impl RunManifest {
    /// Reads `dir/run.json`.
    ///
    /// # Errors
    /// [`ReportError::Io`] if the file cannot be read or is not a regular file,
    /// [`ReportError::Manifest`] if it is not a valid manifest.
    pub fn load(dir: impl AsRef<Path>) -> Result<Self, ReportError> {
        let path = dir.as_ref().join(MANIFEST_FILE);
        let io = |source| ReportError::Io {
            path: path.clone(),
            source,
        };
        // Only a regular file: a FIFO named run.json would block, a device never end.
        let mut text = String::new();
        std::io::Read::read_to_string(
            &mut render::files::open_regular(&path).map_err(io)?,
            &mut text,
        )
        .map_err(io)?;
        serde_json::from_str(&text).map_err(|e| ReportError::Manifest {
            path,
            message: e.to_string(),
        })
    }

    /// Writes `dir/run.json` (pretty-printed, atomically), creating `dir` if needed.
    ///
    /// # Errors
    /// [`ReportError::Io`] if the directory or file cannot be written.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<(), ReportError> {
        let dir = dir.as_ref();
        std::fs::create_dir_all(dir).map_err(|source| ReportError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = dir.join(MANIFEST_FILE);
        let text = serde_json::to_string_pretty(self).map_err(|e| ReportError::Manifest {
            path: path.clone(),
            message: e.to_string(),
        })?;
        render::files::write_bytes_atomic(&path, text)
            .map_err(|source| ReportError::Io { path, source })
    }

    /// Checks what the report relies on: at least one method, unique non-empty names, at least
    /// one image per method, finite non-negative convergence samples.
    ///
    /// # Errors
    /// [`ReportError::Invalid`] naming the method at fault.
    pub fn validate(&self) -> Result<(), ReportError> {
        let invalid = |m: String| Err(ReportError::Invalid(m));
        if self.methods.is_empty() {
            return invalid("the run has no methods".into());
        }
        for (i, m) in self.methods.iter().enumerate() {
            if m.name.trim().is_empty() {
                return invalid(format!("method {i} has an empty name"));
            }
            if self.methods[..i].iter().any(|o| o.name == m.name) {
                return invalid(format!("method name {:?} appears twice", m.name));
            }
            if m.images.is_empty() {
                return invalid(format!("method {:?} has no images", m.name));
            }
            for s in &m.convergence {
                if s.points.iter().any(|p| {
                    !(p.time_s.is_finite() && p.time_s >= 0.0 && p.relmse.is_finite())
                        || p.relmse < 0.0
                }) {
                    return invalid(format!(
                        "method {:?}, seed {}: convergence samples must be finite and non-negative",
                        m.name, s.seed
                    ));
                }
            }
        }
        Ok(())
    }
}

impl RunManifest {
    /// Every image a report of this run reads, with what it is (`the reference`, `the image of
    /// METHOD, seed S`): paths relative to `run_dir` resolved in it.
    #[must_use]
    pub fn image_files(&self, run_dir: impl AsRef<Path>) -> Vec<(String, PathBuf)> {
        let dir = run_dir.as_ref();
        let mut files = vec![("the reference".to_string(), resolve(dir, &self.reference))];
        for method in &self.methods {
            for image in &method.images {
                files.push((
                    format!("the image of {}, seed {}", method.name, image.seed),
                    resolve(dir, &image.path),
                ));
            }
        }
        files
    }
}

/// `path` relative to `dir` unless it is absolute.
pub(crate) fn resolve(dir: &Path, path: &Path) -> PathBuf {
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        dir.join(path)
    }
}

/// The commit chainlight was built from (the first 12 hex digits, or `unknown` when it was not
/// built from a git checkout), recorded at build time by reading the repository's files: the
/// commit of the code that makes a run, not of the folder it runs in. Finding it runs no
/// program (running `git` in a folder runs that repository's configured commands).
pub const BUILD_COMMIT: &str = env!("CHAINLIGHT_BUILD_COMMIT");
