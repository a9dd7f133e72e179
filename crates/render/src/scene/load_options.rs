//! What the glTF loader may read besides the scene file itself.

/// Options of [`Scene::load_with`](super::Scene::load_with).
///
/// The defaults are the safe ones: a scene file may only make the loader read files inside
/// its own folder (see "Loading safety" in `docs/scenes.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Let buffer and image URIs name files outside the scene file's folder: absolute paths,
    /// `file://` URIs, `..` components leaving the folder and symbolic links pointing out of
    /// it (default `false`: such URIs are an error). Even when set, only regular files are
    /// read, buffers no further than their `byteLength` and images up to
    /// [`MAX_IMAGE_FILE_BYTES`].
    pub allow_external_files: bool,
}

/// The largest image file (or data URI) a glTF image may come from: 256 MiB. Larger files
/// are an error naming the image. (Decoding is further limited by the `image` crate's default
/// allocation limit of 512 MiB.)
pub const MAX_IMAGE_FILE_BYTES: u64 = 256 * 1024 * 1024;
