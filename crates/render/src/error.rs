//! The render crate's error type: every way user input (scene files, settings) can be rejected.

use std::path::PathBuf;

/// An error at the render crate's boundaries: scene files and render settings.
///
/// The hot path never returns it; user input never panics. Every variant names the offending
/// file or setting and says what was expected.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// A scene file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A scene file is not a usable glTF 2.0 document (malformed JSON or GLB container, an
    /// index out of range, a missing buffer, an accessor outside its buffer, ...).
    #[error("invalid glTF scene {file}: {reason}")]
    Gltf {
        /// The file (or `<memory>` for scenes loaded from a byte slice).
        file: String,
        /// What is wrong, naming the glTF field (e.g. `accessors[3].count`).
        reason: String,
    },
    /// A scene file has an extension other than `.gltf` or `.glb`.
    #[error("unsupported scene file {path}: expected a .gltf or .glb file")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// A render setting is outside its allowed range.
    #[error("invalid setting {field} = {value}: allowed {allowed}")]
    InvalidSetting {
        /// The setting (the CLI flag without dashes, e.g. `width`).
        field: &'static str,
        /// The rejected value.
        value: String,
        /// The allowed range, e.g. `1..=65536`.
        allowed: &'static str,
    },
    /// The requested integrator is not implemented by [`crate::session::render`].
    #[error("integrator {0} is not supported by this renderer")]
    UnsupportedIntegrator(String),
    /// The render would need more memory than is available: refused before any work
    /// (`render::methods::memory::check`).
    #[error(
        "not enough memory: the render needs about {} but {} is available ({limit}): {advice}",
        Bytes(*needed),
        Bytes(*available)
    )]
    OutOfMemory {
        /// The estimated peak in bytes.
        needed: u64,
        /// The bytes available.
        available: u64,
        /// What limits them (`/proc/meminfo`, the address-space limit, or the environment
        /// variable `CHAINLIGHT_MEMORY_LIMIT`).
        limit: String,
        /// What the estimate is made of and which flags would make the render fit.
        advice: String,
    },
    /// The integrator cannot render this scene (e.g. its bootstrap found no light-carrying
    /// path): refused with the reason instead of a black image reported as success.
    #[error("integrator {integrator} cannot render this scene: {reason}")]
    Unrenderable {
        /// The integrator (its `--integrator` name).
        integrator: &'static str,
        /// What it could not do, and what to try instead.
        reason: String,
    },
    /// The worker thread pool could not be created.
    #[error("cannot start {threads} worker threads: {reason}")]
    ThreadPool {
        /// Requested thread count.
        threads: usize,
        /// The reason reported by rayon.
        reason: String,
    },
}

/// Bytes as `12.34 GiB`, `456 MiB` or `789 KiB`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bytes(pub u64);

impl std::fmt::Display for Bytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let b = self.0 as f64;
        if b >= (1u64 << 30) as f64 {
            write!(f, "{:.2} GiB", b / (1u64 << 30) as f64)
        } else if b >= (1u64 << 20) as f64 {
            write!(f, "{:.0} MiB", b / (1u64 << 20) as f64)
        } else {
            write!(f, "{:.0} KiB", b / 1024.0)
        }
    }
}

impl RenderError {
    /// A [`RenderError::Gltf`] for `file` with `reason`.
    #[must_use]
    pub fn gltf(file: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Gltf {
            file: file.into(),
            reason: reason.into(),
        }
    }

    /// A [`RenderError::InvalidSetting`].
    #[must_use]
    pub fn setting(field: &'static str, value: impl ToString, allowed: &'static str) -> Self {
        Self::InvalidSetting {
            field,
            value: value.to_string(),
            allowed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_file_and_field() {
        let e = RenderError::gltf("a.gltf", "accessors[3].count: 12 elements exceed the view");
        let s = e.to_string();
        assert!(s.contains("a.gltf") && s.contains("accessors[3]"), "{s}");
        let e = RenderError::setting("width", 0, "1..=65536");
        assert_eq!(
            e.to_string(),
            "invalid setting width = 0: allowed 1..=65536"
        );
    }

    #[test]
    fn is_send_sync() {
        fn check<T: Send + Sync + 'static>() {}
        check::<RenderError>();
    }
}
