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

/// Renders the default scene at 16 x 16, 2 samples (mutations) per pixel with `integrator`
/// (MCMC integrators also get a 2000-sample bootstrap and 16 chains), writes `out`, appends
/// `extra`, and asserts success; returns the summary and the log (stdout then stderr).
pub fn tiny_render(out: &Path, integrator: &str, extra: &[&str]) -> String {
    let mut args = vec![
        "render",
        "--integrator",
        integrator,
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "2",
        "-o",
        path_str(out),
    ];
    if !matches!(integrator, "bdpt" | "pt" | "qmc" | "lqmc") {
        args.extend(["--bootstrap-samples", "2000", "--chains", "16"]);
    }
    args.extend_from_slice(extra);
    let output = chainlight(&args);
    assert!(
        output.status.success(),
        "{integrator} {extra:?}: {}",
        stderr(&output)
    );
    format!("{}{}", stdout(&output), stderr(&output))
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

/// Runs `chainlight args` in `dir` (the current directory if `None`), failing the test if it
/// has not exited after `limit` (it is killed): for inputs that used to hang the commands.
pub fn chainlight_within(args: &[&str], dir: Option<&Path>, limit: std::time::Duration) -> Output {
    use std::process::Stdio;
    let mut command = Command::new(env!("CARGO_BIN_EXE_chainlight"));
    command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    if let Some(dir) = dir {
        command.current_dir(dir);
    }
    let mut child = command.spawn().expect("the chainlight binary runs");
    let start = std::time::Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let output = child.wait_with_output().unwrap();
            panic!(
                "{args:?} did not finish within {limit:?}; stderr: {}",
                stderr(&output)
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Writes a valid 1x1 EXR at `path` whose data and display windows are then rewritten to
/// declare `width x height` pixels: a few hundred bytes, like a hostile file.
pub fn exr_declaring(path: &Path, width: i32, height: i32) {
    render::image_io::write_exr(path, &render::Image::new(1, 1)).unwrap();
    let mut bytes = std::fs::read(path).unwrap();
    for attribute in [&b"dataWindow\0box2i\0"[..], b"displayWindow\0box2i\0"] {
        let at = bytes
            .windows(attribute.len())
            .position(|w| w == attribute)
            .expect("the attribute is in the header")
            + attribute.len()
            + 4;
        // box2i: x_min, y_min, x_max, y_max as little-endian i32.
        bytes[at + 8..at + 12].copy_from_slice(&(width - 1).to_le_bytes());
        bytes[at + 12..at + 16].copy_from_slice(&(height - 1).to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// Writes a small valid EXR (`w x h`, grey `v`) at `path`.
pub fn grey_exr(path: &Path, w: usize, h: usize, v: f32) {
    let image = render::Image::from_pixels(w, h, vec![[v; 3]; w * h]).unwrap();
    render::image_io::write_exr(path, &image).unwrap();
}

/// Makes a FIFO at `path` (`mkfifo`).
#[cfg(unix)]
pub fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(status.success(), "mkfifo {}", path.display());
}

/// The names in `dir`, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}
