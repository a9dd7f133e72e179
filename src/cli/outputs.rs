//! The files a command writes, checked before any work: each must be writable, and none may be
//! one of the command's own inputs (the same path, a symbolic or hard link to it).

use std::path::{Path, PathBuf};

use super::CliResult;

/// A file a command reads or writes, with what it is for messages (`--output`, `the
/// reference`, ...).
#[derive(Clone, Debug)]
pub(crate) struct Named {
    /// What the file is, e.g. `--env` or `the PNG preview`.
    pub(crate) what: String,
    /// The path as given.
    pub(crate) path: PathBuf,
}

impl Named {
    /// `path` described as `what`.
    pub(crate) fn new(what: impl Into<String>, path: impl Into<PathBuf>) -> Self {
        Self {
            what: what.into(),
            path: path.into(),
        }
    }
}

/// Fails unless `output` can be written ([`render::files::check_writable`]), naming it.
pub(crate) fn check_writable(output: &Named) -> CliResult<()> {
    render::files::check_writable(&output.path).map_err(|e| {
        format!(
            "{} '{}' cannot be written: {e}",
            output.what,
            output.path.display()
        )
        .into()
    })
}

/// Checks every output before the work starts: not one of `inputs`, and writable.
///
/// # Errors
/// The first output that is an input (naming both), or that cannot be written.
pub(crate) fn check(outputs: &[Named], inputs: &[Named]) -> CliResult<()> {
    refuse_inputs(outputs, inputs)?;
    outputs.iter().try_for_each(check_writable)
}

/// Fails if an output is one of `inputs` ([`same_file`]), naming both.
pub(crate) fn refuse_inputs(outputs: &[Named], inputs: &[Named]) -> CliResult<()> {
    for output in outputs {
        for input in inputs {
            if same_file(&output.path, &input.path) {
                return Err(format!(
                    "{} '{}' is the same file as {} '{}': refusing to overwrite an input",
                    output.what,
                    output.path.display(),
                    input.what,
                    input.path.display()
                )
                .into());
            }
        }
    }
    Ok(())
}

/// True if `a` and `b` name the same file: the same device and inode when both exist (a
/// symbolic or hard link to the other), else the same absolute path with the folder's links
/// resolved.
pub(crate) fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        use std::os::unix::fs::MetadataExt;
        return (ma.dev(), ma.ino()) == (mb.dev(), mb.ino());
    }
    match (resolved(a), resolved(b)) {
        (Some(ra), Some(rb)) => ra == rb,
        _ => false,
    }
}

/// `path` made absolute with its folder's symbolic links resolved (the file itself may not
/// exist yet).
fn resolved(path: &Path) -> Option<PathBuf> {
    if let Ok(full) = std::fs::canonicalize(path) {
        return Some(full);
    }
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Some(std::fs::canonicalize(dir).ok()?.join(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("chainlight-outputs-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn links_and_spellings_of_one_file_are_the_same_file() {
        let dir = temp_dir("same");
        let a = dir.join("a.exr");
        std::fs::write(&a, b"a").unwrap();
        let b = dir.join("b.exr");
        std::fs::write(&b, b"b").unwrap();
        assert!(same_file(&a, &a));
        assert!(same_file(&a, &dir.join(".").join("a.exr")));
        // Negative control: two different files.
        assert!(!same_file(&a, &b));
        assert!(!same_file(&a, &dir.join("missing.exr")));
        // Two spellings of a file that does not exist yet.
        std::fs::create_dir(dir.join("sub")).unwrap();
        assert!(same_file(
            &dir.join("new.exr"),
            &dir.join("sub").join("..").join("new.exr")
        ));
        #[cfg(unix)]
        {
            let hard = dir.join("hard.exr");
            std::fs::hard_link(&a, &hard).unwrap();
            assert!(same_file(&a, &hard));
            let soft = dir.join("soft.exr");
            std::os::unix::fs::symlink(&a, &soft).unwrap();
            assert!(same_file(&soft, &a));
        }
    }

    #[test]
    fn an_output_that_is_an_input_is_refused_naming_both() {
        let dir = temp_dir("check");
        let input = dir.join("m.exr");
        std::fs::write(&input, b"map").unwrap();
        let err = check(
            &[Named::new("--output", &input)],
            &[Named::new("--env", &input)],
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("--output") && err.contains("--env") && err.contains("m.exr"),
            "{err}"
        );
        assert!(check(
            &[Named::new("--output", dir.join("out.exr"))],
            &[Named::new("--env", &input)]
        )
        .is_ok());
        assert_eq!(std::fs::read(&input).unwrap(), b"map");
    }
}
