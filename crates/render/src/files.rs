//! Safe file access shared by every reader and writer: only regular files are read, and every
//! file is written atomically.
//!
//! * **Reading** ([`open_regular`], [`regular_file_metadata`]): a FIFO would block the reader
//!   forever, a device (`/dev/zero`, `/dev/urandom`) never ends and a directory is not data,
//!   so anything but a regular file (after following symbolic links) is refused with an error
//!   that says what the path is ([`file_kind`]). The check runs before the file is opened
//!   (opening a FIFO blocks) and again on the opened file (the path may have been replaced
//!   in between).
//! * **Writing** ([`write_atomic`]): the bytes go to a temporary file in the destination's
//!   folder, which is flushed to disk and then renamed over the destination. A failed write
//!   (full disk, encoder error) or an abort while writing leaves the destination as it was (the
//!   old file, or none), never a truncated file; the temporary file is removed on error, and
//!   [`remove_temporaries`] removes the ones still being written (what a second Ctrl-C calls
//!   before it exits). [`check_writable`] reports up front whether a write would succeed.

use std::fs::{File, Metadata, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// What a file's metadata says it is, for error messages (`a FIFO`, `a directory`, ...).
#[must_use]
pub fn file_kind(meta: &Metadata) -> &'static str {
    let ty = meta.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ty.is_fifo() {
            return "a FIFO";
        }
        if ty.is_char_device() {
            return "a character device";
        }
        if ty.is_block_device() {
            return "a block device";
        }
        if ty.is_socket() {
            return "a socket";
        }
    }
    if ty.is_dir() {
        "a directory"
    } else if ty.is_file() {
        "a regular file"
    } else {
        "a special file"
    }
}

/// The error for a path that is not a regular file (kind [`io::ErrorKind::InvalidInput`]).
fn not_regular(meta: &Metadata) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "{}, not a regular file; only regular files are read",
            file_kind(meta)
        ),
    )
}

/// The metadata of `path` (symbolic links followed) if it is a regular file.
///
/// # Errors
/// The operating system's error if `path` cannot be examined; [`io::ErrorKind::InvalidInput`]
/// naming what it is ([`file_kind`]) if it is not a regular file.
pub fn regular_file_metadata(path: impl AsRef<Path>) -> io::Result<Metadata> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        Ok(meta)
    } else {
        Err(not_regular(&meta))
    }
}

/// Opens `path` for reading if it is a regular file (checked before opening, since opening a
/// FIFO blocks, and again on the opened file).
///
/// # Errors
/// As [`regular_file_metadata`], or the operating system's error from opening the file.
pub fn open_regular(path: impl AsRef<Path>) -> io::Result<File> {
    let path = path.as_ref();
    regular_file_metadata(path)?;
    let file = File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_file() {
        Ok(file)
    } else {
        Err(not_regular(&meta))
    }
}

/// Temporary files being written, removed by [`remove_temporaries`].
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Makes the temporary file names of one process unique.
static COUNTER: AtomicU64 = AtomicU64::new(0);

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Removes every temporary file [`write_atomic`] is still writing (their destinations stay as
/// they were). For a process about to exit in the middle of a write, e.g. on a second Ctrl-C.
pub fn remove_temporaries() {
    remove_pending(|_| true);
}

/// Removes the pending temporary files `select` picks.
fn remove_pending(select: impl Fn(&Path) -> bool) {
    pending().retain(|path| {
        if select(path) {
            let _ = std::fs::remove_file(path);
            false
        } else {
            true
        }
    });
}

/// The file a write to `path` replaces: the target of a symbolic link (so writing through a
/// link updates what it points to, as a plain write would), else `path` itself.
fn destination(path: &Path) -> PathBuf {
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_symlink() => {
            std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
        }
        _ => path.to_path_buf(),
    }
}

/// Checks what is at the destination: nothing, or a regular file the user may write. Returns
/// the existing file's metadata.
fn check_destination(dest: &Path) -> io::Result<Option<Metadata>> {
    match std::fs::metadata(dest) {
        Ok(meta) if meta.is_dir() => Err(io::Error::new(
            io::ErrorKind::IsADirectory,
            "it is a directory",
        )),
        Ok(meta) if !meta.is_file() => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it is {}, not a regular file", file_kind(&meta)),
        )),
        Ok(meta) => {
            // Replacing a file the user may not write would bypass its permissions.
            OpenOptions::new().write(true).open(dest)?;
            Ok(Some(meta))
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

/// Creates a new, empty temporary file next to `dest` and registers it for
/// [`remove_temporaries`].
fn create_temporary(dest: &Path) -> io::Result<(PathBuf, File)> {
    let name = dest
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy());
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let temp = dest.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()));
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)?;
    pending().push(temp.clone());
    Ok((temp, file))
}

/// Removes `temp` and forgets it.
fn discard(temp: &Path) {
    let _ = std::fs::remove_file(temp);
    pending().retain(|p| p != temp);
}

/// Fails unless [`write_atomic`] to `path` could succeed, changing nothing: the destination is
/// absent or a regular file the user may write (not a directory, FIFO or device), and a file
/// can be created in its folder (created and removed again).
///
/// # Errors
/// The reason, as an [`io::Error`] without the path (callers name it).
pub fn check_writable(path: impl AsRef<Path>) -> io::Result<()> {
    let dest = destination(path.as_ref());
    check_destination(&dest)?;
    let (temp, _file) = create_temporary(&dest)?;
    discard(&temp);
    Ok(())
}

/// Writes a file atomically: `write` fills a buffered temporary file in the folder of `path`,
/// which is then flushed, synced and renamed over `path` (keeping an existing file's
/// permissions). On any error the temporary file is removed and `path` is left as it was.
///
/// `io_error` turns the I/O errors of this function into the caller's error type; `write`
/// returns the caller's errors (an encoder's, say) unchanged.
///
/// # Errors
/// `io_error` of the failure if the destination is a directory, FIFO, device or a file the
/// user may not write, or if the temporary file cannot be created, synced or renamed; what
/// `write` returns if it fails.
pub fn write_atomic<E>(
    path: impl AsRef<Path>,
    io_error: impl Fn(io::Error) -> E,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
) -> Result<(), E> {
    let dest = destination(path.as_ref());
    let existing = check_destination(&dest).map_err(&io_error)?;
    let (temp, file) = create_temporary(&dest).map_err(&io_error)?;
    let mut writer = BufWriter::new(file);
    let result = write(&mut writer).and_then(|()| {
        let mut finish = || -> io::Result<()> {
            writer.flush()?;
            let file = writer.get_ref();
            if let Some(meta) = &existing {
                file.set_permissions(meta.permissions())?;
            }
            file.sync_all()?;
            std::fs::rename(&temp, &dest)
        };
        finish().map_err(&io_error)
    });
    match result {
        Ok(()) => {
            pending().retain(|p| p != &temp);
            Ok(())
        }
        Err(e) => {
            discard(&temp);
            Err(e)
        }
    }
}

/// [`write_atomic`] of a byte string, with plain I/O errors.
///
/// # Errors
/// As [`write_atomic`].
pub fn write_bytes_atomic(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> io::Result<()> {
    write_atomic(path, |e| e, |w| w.write_all(bytes.as_ref()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("chainlight-files-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// The directory's entries, sorted.
    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn atomic_write_replaces_the_file_and_leaves_no_temporary() {
        let dir = temp_dir("replace");
        let path = dir.join("out.txt");
        write_bytes_atomic(&path, b"first").unwrap();
        write_bytes_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        assert_eq!(entries(&dir), ["out.txt"]);
    }

    #[test]
    fn failed_write_keeps_the_old_file_and_removes_the_temporary() {
        let dir = temp_dir("fail");
        let path = dir.join("out.txt");
        std::fs::write(&path, b"old contents").unwrap();
        let result: io::Result<()> = write_atomic(
            &path,
            |e| e,
            |w| {
                // Half the data, then the encoder fails.
                w.write_all(b"new con")?;
                w.flush()?;
                Err(io::Error::other("encoder failed"))
            },
        );
        assert_eq!(result.unwrap_err().to_string(), "encoder failed");
        assert_eq!(std::fs::read(&path).unwrap(), b"old contents");
        assert_eq!(entries(&dir), ["out.txt"]);
        // A missing destination stays missing.
        let fresh = dir.join("fresh.txt");
        let result: io::Result<()> = write_atomic(&fresh, |e| e, |_| Err(io::Error::other("x")));
        assert!(result.is_err() && !fresh.exists());
        assert_eq!(entries(&dir), ["out.txt"]);
    }

    /// The negative control of the test above: a plain `std::fs::write`-style truncating write
    /// that fails half way does destroy the old file.
    #[test]
    fn a_truncating_write_that_fails_loses_the_old_file() {
        let dir = temp_dir("truncating");
        let path = dir.join("out.txt");
        std::fs::write(&path, b"old contents").unwrap();
        let mut file = File::create(&path).unwrap();
        file.write_all(b"new con").unwrap();
        drop(file);
        assert_ne!(std::fs::read(&path).unwrap(), b"old contents");
    }

    #[test]
    fn pending_temporaries_are_removed_on_request() {
        let dir = temp_dir("pending");
        let path = dir.join("out.txt");
        std::fs::write(&path, b"old").unwrap();
        let result: io::Result<()> = write_atomic(
            &path,
            |e| e,
            |w| {
                w.write_all(b"partial")?;
                w.flush()?;
                assert_eq!(entries(&dir).len(), 2, "the temporary file exists");
                // What the second Ctrl-C does before exiting (`remove_temporaries`), limited
                // to this test's folder: other tests write files at the same time.
                remove_pending(|p| p.starts_with(&dir));
                assert_eq!(entries(&dir), ["out.txt"]);
                Err(io::Error::other("interrupted"))
            },
        );
        assert!(result.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
    }

    #[test]
    fn destinations_that_cannot_be_replaced_are_refused() {
        let dir = temp_dir("refuse");
        let sub = dir.join("sub.txt");
        std::fs::create_dir(&sub).unwrap();
        let err = write_bytes_atomic(&sub, b"x").unwrap_err();
        assert!(err.to_string().contains("directory"), "{err}");
        assert!(check_writable(&sub).is_err());
        assert!(check_writable(dir.join("missing/x.txt")).is_err());
        assert!(check_writable(dir.join("ok.txt")).is_ok());
        assert!(!dir.join("ok.txt").exists());
        #[cfg(unix)]
        {
            let err = check_writable("/dev/null").unwrap_err();
            assert!(err.to_string().contains("character device"), "{err}");
        }
        assert_eq!(entries(&dir), ["sub.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn writing_through_a_symbolic_link_updates_its_target() {
        let dir = temp_dir("symlink");
        let target = dir.join("target.txt");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_bytes_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
    }

    #[cfg(unix)]
    #[test]
    fn only_regular_files_are_opened() {
        let dir = temp_dir("regular");
        let file = dir.join("a.txt");
        std::fs::write(&file, b"a").unwrap();
        assert!(open_regular(&file).is_ok());
        let err = open_regular(&dir).unwrap_err();
        assert!(err.to_string().contains("a directory"), "{err}");
        let err = open_regular("/dev/zero").unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("character device"), "{err}");
        let link = dir.join("zero.pfm");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        assert!(open_regular(&link).is_err());
    }
}
