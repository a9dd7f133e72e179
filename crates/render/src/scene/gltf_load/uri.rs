//! Buffer and image URIs: base64 data URIs, and files resolved in the scene's folder (kept
//! inside it unless the options allow otherwise) and read with size limits.

use std::io::Read;
use std::path::{Component, PathBuf};

use super::Loader;
use crate::error::RenderError;
use crate::files;
use crate::scene::MAX_IMAGE_FILE_BYTES;

/// How much of a URI's target [`Loader::read_uri`] reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum UriLimit {
    /// A buffer: at most this many bytes (its `byteLength`; a shorter file is an error).
    UpTo(u64),
    /// An image: at most [`MAX_IMAGE_FILE_BYTES`]; a larger file is an error.
    Image,
}

/// Decodes standard base64 (RFC 4648, with optional `=` padding).
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let text = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for &c in text {
        acc = (acc << 6) | value(c)?;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// Decodes `%XX` escapes of a relative URI into a UTF-8 path.
fn percent_decode(uri: &str) -> Option<String> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok();
            if let Some(v) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).ok()
}

impl Loader<'_> {
    /// Reads the bytes of the URI of `what` (`buffers[i]` or `images[i]`; errors name its
    /// `.uri` field and say why): a base64 data URI, or a regular file found by
    /// [`Loader::resolve`], read no further than `limit` allows.
    pub(super) fn read_uri(
        &self,
        uri: &str,
        what: &str,
        limit: UriLimit,
    ) -> Result<Vec<u8>, RenderError> {
        let field = format!("{what}.uri");
        let too_big = |len: u64| {
            self.err(format!(
                "{field}: the image has {len} bytes, more than the {} MiB allowed for an image",
                MAX_IMAGE_FILE_BYTES >> 20
            ))
        };
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, data) = rest
                .split_once(";base64,")
                .ok_or_else(|| self.err(format!("{field}: only base64 data URIs are supported")))?;
            let bytes = decode_base64(data)
                .ok_or_else(|| self.err(format!("{field}: invalid base64 in data URI")))?;
            if limit == UriLimit::Image && bytes.len() as u64 > MAX_IMAGE_FILE_BYTES {
                return Err(too_big(bytes.len() as u64));
            }
            return Ok(bytes);
        }
        let path = self.resolve(uri, &field)?;
        let cannot =
            |e: std::io::Error| self.err(format!("{field}: cannot read '{}': {e}", path.display()));
        // Only regular files, checked before opening (opening a FIFO blocks) and on the
        // opened file (the path may have been replaced meanwhile).
        let refuse = |e: std::io::Error| {
            if e.kind() == std::io::ErrorKind::InvalidInput {
                self.err(format!("{field}: '{}' is {e}", path.display()))
            } else {
                cannot(e)
            }
        };
        let meta = files::regular_file_metadata(&path).map_err(refuse)?;
        let max = match limit {
            UriLimit::UpTo(n) => n,
            UriLimit::Image if meta.len() > MAX_IMAGE_FILE_BYTES => {
                return Err(too_big(meta.len()))
            }
            UriLimit::Image => MAX_IMAGE_FILE_BYTES + 1,
        };
        let file = files::open_regular(&path).map_err(refuse)?;
        let meta = file.metadata().map_err(cannot)?;
        let mut out = Vec::with_capacity(usize::try_from(meta.len().min(max)).unwrap_or(0));
        file.take(max).read_to_end(&mut out).map_err(cannot)?;
        if limit == UriLimit::Image && out.len() as u64 > MAX_IMAGE_FILE_BYTES {
            return Err(too_big(out.len() as u64));
        }
        Ok(out)
    }

    /// The file a (non-data) URI names, for `field`. Relative references (percent-decoded)
    /// resolve in the scene's folder. Unless
    /// [`LoadOptions::allow_external_files`](crate::scene::LoadOptions::allow_external_files)
    /// is set, the file must be inside that folder: absolute paths are refused, `..` may not
    /// leave it, and the path with every symbolic link resolved (a relative path or a
    /// `file://` URI) must still lie inside the folder with its links resolved. Other URI
    /// schemes are refused.
    fn resolve(&self, uri: &str, field: &str) -> Result<PathBuf, RenderError> {
        const HINT: &str =
            "(LoadOptions::allow_external_files or `--allow-external-files` allows other files)";
        let allow = self.options.allow_external_files;
        let decode = |s: &str| {
            percent_decode(s).ok_or_else(|| {
                self.err(format!(
                    "{field}: '{uri}' is not valid UTF-8 after percent-decoding"
                ))
            })
        };
        let colon = uri.find(':');
        let drive_letter = colon == Some(1) && uri.as_bytes()[0].is_ascii_alphabetic();
        let scheme = colon.filter(|&i| {
            i > 1
                && uri[..i]
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'+' | b'-' | b'.'))
        });
        let (path, relative) = if let Some(rest) = uri.strip_prefix("file://") {
            let decoded = decode(rest)?;
            let local = decoded.strip_prefix("localhost").unwrap_or(&decoded);
            if !local.starts_with('/') {
                return Err(self.err(format!(
                    "{field}: '{uri}' names a host; only local file URIs are supported"
                )));
            }
            (PathBuf::from(local), false)
        } else if scheme.is_some() {
            return Err(self.err(format!(
                "{field}: unsupported URI scheme in '{uri}' (only relative paths and data URIs are read)"
            )));
        } else {
            let rel = decode(uri)?;
            let rel_path = PathBuf::from(&rel);
            if rel_path.is_absolute() || rel.starts_with(['/', '\\']) || drive_letter {
                if !allow {
                    return Err(self.err(format!(
                        "{field}: '{uri}' is an absolute path; only files inside the scene folder are read {HINT}"
                    )));
                }
                (rel_path, false)
            } else {
                let base = self.base_dir.ok_or_else(|| {
                    self.err(format!(
                        "{field}: external file '{rel}' cannot be resolved without a base directory"
                    ))
                })?;
                if !allow {
                    let mut depth = 0usize;
                    for c in rel_path.components() {
                        match c {
                            Component::Normal(_) => depth += 1,
                            Component::CurDir => {}
                            Component::ParentDir if depth > 0 => depth -= 1,
                            _ => {
                                return Err(self.err(format!(
                                    "{field}: '{uri}' leaves the scene folder through '..'; only files inside it are read {HINT}"
                                )))
                            }
                        }
                    }
                }
                (base.join(rel_path), true)
            }
        };
        if allow {
            return Ok(path);
        }
        let base = self.base_dir.ok_or_else(|| {
            self.err(format!(
                "{field}: '{uri}' is outside the scene folder (the scene has none) {HINT}"
            ))
        })?;
        let canonical_base = base.canonicalize().map_err(|e| {
            self.err(format!(
                "{field}: cannot resolve the scene folder '{}': {e}",
                base.display()
            ))
        })?;
        let real = path
            .canonicalize()
            .map_err(|e| self.err(format!("{field}: cannot read '{}': {e}", path.display())))?;
        if !real.starts_with(&canonical_base) {
            return Err(self.err(format!(
                "{field}: '{uri}' resolves{} to '{}', outside the scene folder '{}'; only files inside it are read {HINT}",
                if relative { " through a symbolic link" } else { "" },
                real.display(),
                canonical_base.display()
            )));
        }
        Ok(real)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("a$b").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("100%").unwrap(), "100%");
        assert_eq!(percent_decode("%zz").unwrap(), "%zz");
        assert!(percent_decode("%FF").is_none());
    }
}
