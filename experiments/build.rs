//! Records the commit this package is built from, as `CHAINLIGHT_BUILD_COMMIT` (the first 12
//! hex digits, or `unknown` outside a git checkout), for run manifests and reports.
//!
//! It reads the repository's files (`HEAD`, the branch's ref file or `packed-refs`) and runs
//! no program: no `git`, so no hook or `core.fsmonitor` command of any repository runs, and
//! only the workspace's own `.git` (next to this package) is looked at.

use std::fs;
use std::path::{Path, PathBuf};

fn main() {
    let mut watched = Vec::new();
    let commit = std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .and_then(|dir| dir.parent().map(Path::to_path_buf))
        .and_then(|root| head_commit(&root, &mut watched))
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=CHAINLIGHT_BUILD_COMMIT={commit}");
    println!("cargo:rerun-if-changed=build.rs");
    for path in watched {
        println!("cargo:rerun-if-changed={}", path.display());
    }
}

/// The commit `HEAD` of the repository at `root` names; pushes the files (and ref folders)
/// whose change may change it onto `watched`.
fn head_commit(root: &Path, watched: &mut Vec<PathBuf>) -> Option<String> {
    let (git_dir, common_dir) = git_dirs(&root.join(".git"))?;
    let head_file = git_dir.join("HEAD");
    let head = fs::read_to_string(&head_file).ok()?;
    watched.push(head_file);
    let head = head.trim();
    let Some(name) = head.strip_prefix("ref:").map(str::trim) else {
        return abbreviate(head);
    };
    if name.split('/').any(|part| part.is_empty() || part == "..") {
        return None;
    }
    let packed = common_dir.join("packed-refs");
    if packed.is_file() {
        watched.push(packed.clone());
    }
    for dir in [&git_dir, &common_dir] {
        let loose = dir.join(name);
        if let Some(folder) = loose.parent().filter(|f| f.is_dir()) {
            // A new loose ref (the first commit after `git pack-refs`) changes the folder.
            watched.push(folder.to_path_buf());
        }
        if let Ok(text) = fs::read_to_string(&loose) {
            watched.push(loose);
            return abbreviate(text.trim());
        }
    }
    let packed = fs::read_to_string(packed).ok()?;
    packed
        .lines()
        .filter(|line| !line.starts_with('#') && !line.starts_with('^'))
        .find_map(|line| {
            let (hash, refname) = line.split_once(' ')?;
            (refname.trim() == name).then(|| abbreviate(hash))?
        })
}

/// The repository's own folder and its common folder (they differ in a linked worktree,
/// whose `.git` is a file `gitdir: PATH`).
fn git_dirs(dot_git: &Path) -> Option<(PathBuf, PathBuf)> {
    let meta = fs::metadata(dot_git).ok()?;
    let git_dir = if meta.is_dir() {
        dot_git.to_path_buf()
    } else {
        let text = fs::read_to_string(dot_git).ok()?;
        let target = PathBuf::from(text.trim().strip_prefix("gitdir:")?.trim());
        dot_git.parent()?.join(target)
    };
    let common_dir = match fs::read_to_string(git_dir.join("commondir")) {
        Ok(text) => git_dir.join(text.trim()),
        Err(_) => git_dir.clone(),
    };
    Some((git_dir, common_dir))
}

/// The first 12 digits of a full hexadecimal object name (SHA-1 or SHA-256).
fn abbreviate(hash: &str) -> Option<String> {
    let full =
        (hash.len() == 40 || hash.len() == 64) && hash.bytes().all(|b| b.is_ascii_hexdigit());
    full.then(|| hash[..12].to_ascii_lowercase())
}
