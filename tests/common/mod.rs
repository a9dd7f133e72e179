//! Shared helpers of the `chainlight` CLI tests: running the binary, reading its output,
//! scratch directories and failure assertions.
#![allow(dead_code, unreachable_pub)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `chainlight` binary with `args` and waits for it.
pub fn chainlight(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_chainlight"))
        .args(args)
        .output()
        .expect("the chainlight binary runs")
}

/// The stderr of `output` as text.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The stdout of `output` as text.
pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A fresh directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chainlight-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `p` as UTF-8 (test paths always are).
pub fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Asserts a non-zero exit whose stderr contains every `needle`.
pub fn assert_fails_with(args: &[&str], needles: &[&str]) {
    let output = chainlight(args);
    let err = stderr(&output);
    assert!(
        !output.status.success(),
        "{args:?} succeeded; stderr: {err}"
    );
    for needle in needles {
        assert!(
            err.contains(needle),
            "{args:?}: stderr lacks '{needle}':\n{err}"
        );
    }
    assert!(!err.contains("panicked"), "{args:?} panicked:\n{err}");
}

/// Runs `chainlight args`, sends it `signal` (`"INT"`: Ctrl-C, `"TERM"`) `wait` after it
/// reports that the render started (the "rendering ..." line comes after the signal handler
/// is installed), and returns its output, its stderr lines after the first, and how long it
/// took to exit after the signal.
#[cfg(unix)]
pub fn signal_after_start(
    args: &[&str],
    signal: &str,
    wait: std::time::Duration,
) -> (Output, Vec<String>, std::time::Duration) {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;

    let mut child = Command::new(env!("CARGO_BIN_EXE_chainlight"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr_lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let first = stderr_lines.next().unwrap().unwrap();
    assert!(first.starts_with("rendering"), "{first}");
    std::thread::sleep(wait);
    let status = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let signalled = std::time::Instant::now();
    let rest: Vec<String> = stderr_lines.map_while(Result::ok).collect();
    let output = child.wait_with_output().unwrap();
    (output, rest, signalled.elapsed())
}
