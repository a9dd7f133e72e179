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
    /// Commit the run was made from (`git describe --always --dirty`), or `unknown`.
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
    /// [`ReportError::Io`] if the file cannot be read, [`ReportError::Manifest`] if it is not a
    /// valid manifest.
    pub fn load(dir: impl AsRef<Path>) -> Result<Self, ReportError> {
        let path = dir.as_ref().join(MANIFEST_FILE);
        let text = std::fs::read_to_string(&path).map_err(|source| ReportError::Io {
            path: path.clone(),
            source,
        })?;
        serde_json::from_str(&text).map_err(|e| ReportError::Manifest {
            path,
            message: e.to_string(),
        })
    }

    /// Writes `dir/run.json` (pretty-printed), creating `dir` if needed.
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
        std::fs::write(&path, text).map_err(|source| ReportError::Io { path, source })
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

/// `path` relative to `dir` unless it is absolute.
pub(crate) fn resolve(dir: &Path, path: &Path) -> PathBuf {
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        dir.join(path)
    }
}

/// The commit of the working tree at `dir` (`git describe --always --dirty`), or `unknown`
/// when git or the repository is not available.
#[must_use]
pub fn current_commit(dir: impl AsRef<Path>) -> String {
    std::process::Command::new("git")
        .args(["describe", "--always", "--dirty", "--abbrev=12"])
        .current_dir(dir)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown".into())
}
