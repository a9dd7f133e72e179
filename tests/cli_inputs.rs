//! CLI tests of hostile inputs to `render --env`, `compare` and `report`: images declaring huge
//! sizes, devices and FIFOs, extreme convergence samples, a repository whose git
//! configuration runs a command, and environment maps with NaN texels.
#![cfg(unix)]

mod common;

use std::path::Path;
use std::time::Duration;

use common::{
    chainlight, chainlight_within, exr_declaring, grey_exr, mkfifo, path_str, stderr, temp_dir,
};
use experiments::report::{
    ConvergencePoint, ConvergenceSeries, MethodRun, RunManifest, SeedImage, BUILD_COMMIT,
};
use render::image_io::{read_exr, read_image, ImageError};

/// Generous: each command here finishes in well under a second when it works.
const LIMIT: Duration = Duration::from_secs(60);

/// Asserts that `args` fail (within [`LIMIT`], not by a signal) with every `needle` in stderr
/// and no panic.
fn fails_within(args: &[&str], needles: &[&str]) {
    let output = chainlight_within(args, None, LIMIT);
    let err = stderr(&output);
    // 1: the command's error, 2: a flag's value refused by the parser.
    assert!(
        matches!(output.status.code(), Some(1 | 2)),
        "{args:?}: {:?} {err}",
        output.status
    );
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    for needle in needles {
        assert!(
            err.contains(needle),
            "{args:?}: stderr lacks '{needle}': {err}"
        );
    }
}

/// A 377-byte-class EXR declaring 65536 x 65536 (or 32768 x 32768) pixels is refused by the
/// reader before any pixel memory is allocated, and so by `render --env`, `compare` and
/// `report`, with an error naming the file and the limit.
#[test]
fn images_declaring_huge_sizes_are_refused_before_allocating() {
    let dir = temp_dir("huge-declared");
    let reference = dir.join("ref.exr");
    grey_exr(&reference, 4, 4, 0.5);
    let out = dir.join("out.exr");
    for (w, h) in [(65_536, 65_536), (32_768, 32_768), (16_385, 16_384)] {
        let big = dir.join(format!("big{w}.exr"));
        exr_declaring(&big, w, h);
        assert!(std::fs::metadata(&big).unwrap().len() < 1024);
        let err = read_exr(&big).unwrap_err();
        assert!(matches!(err, ImageError::TooLarge { .. }), "{err:?}");
        let needles = [path_str(&big), &format!("{w}x{h}"), "16384x16384"];
        fails_within(&["compare", path_str(&big), path_str(&reference)], &needles);
        fails_within(&["compare", path_str(&reference), path_str(&big)], &needles);
        fails_within(
            &[
                "report",
                "--reference",
                path_str(&big),
                path_str(&reference),
            ],
            &needles,
        );
        fails_within(
            &[
                "render",
                "--env",
                path_str(&big),
                "--width",
                "8",
                "--height",
                "8",
                "--spp",
                "1",
                "-o",
                path_str(&out),
            ],
            &needles,
        );
    }
    // Negative control: the same patch within the limits passes the size check and fails in
    // the decoder (the pixel data of 64 x 64 is missing); declaring 1 x 1 reads.
    let small = dir.join("small.exr");
    exr_declaring(&small, 64, 64);
    assert!(matches!(read_exr(&small), Err(ImageError::Exr { .. })));
    fails_within(
        &["compare", path_str(&small), path_str(&reference)],
        &["small.exr", "not a readable RGB OpenEXR file"],
    );
    exr_declaring(&small, 1, 1);
    assert_eq!(read_exr(&small).unwrap().pixels.len(), 1);
    assert!(!out.exists());
}

/// `compare` and `report` (and `render --env`) refuse devices, FIFOs and symbolic links to
/// them with an error saying what the path is, instead of reading `/dev/zero` until memory
/// runs out or blocking on a FIFO forever.
#[test]
fn devices_and_fifos_are_refused_by_every_command() {
    let dir = temp_dir("special-inputs");
    let reference = dir.join("ref.exr");
    grey_exr(&reference, 4, 4, 0.5);
    let zero = dir.join("zero.pfm");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let fifo = dir.join("fifo.exr");
    mkfifo(&fifo);
    let (zero, fifo, reference) = (path_str(&zero), path_str(&fifo), path_str(&reference));
    let device = [zero, "a character device", "not a regular file"];
    let pipe = [fifo, "a FIFO", "not a regular file"];
    fails_within(&["compare", zero, reference], &device);
    fails_within(&["compare", reference, fifo], &pipe);
    fails_within(&["report", "--reference", zero, reference], &device);
    fails_within(&["report", "--reference", reference, fifo], &pipe);
    let out = dir.join("out.exr");
    for env in [zero, fifo] {
        fails_within(
            &["render", "--env", env, "--spp", "1", "-o", path_str(&out)],
            &[env, "not a regular file"],
        );
    }
    // A run directory whose run.json is a FIFO.
    let run = dir.join("run");
    std::fs::create_dir(&run).unwrap();
    mkfifo(&run.join("run.json"));
    fails_within(&["report", path_str(&run)], &["run.json", "a FIFO"]);
    // Negative control: the same commands on regular files succeed.
    let output = chainlight_within(&["compare", reference, reference], None, LIMIT);
    assert!(output.status.success(), "{}", stderr(&output));
}

/// A run directory: an 8 x 8 reference, one method's image and its convergence `samples`.
fn run_with_samples(dir: &Path, samples: Vec<ConvergencePoint>) -> RunManifest {
    grey_exr(&dir.join("reference.exr"), 8, 8, 0.5);
    grey_exr(&dir.join("a.exr"), 8, 8, 0.55);
    let manifest = RunManifest {
        title: "extreme samples".into(),
        commit: "0123456789ab".into(),
        reference: "reference.exr".into(),
        methods: vec![MethodRun {
            name: "a".into(),
            images: vec![SeedImage {
                seed: 0,
                path: "a.exr".into(),
            }],
            convergence: vec![ConvergenceSeries {
                seed: 0,
                points: samples,
            }],
            ..MethodRun::default()
        }],
        ..RunManifest::default()
    };
    manifest.save(dir).unwrap();
    manifest
}

/// `report` finishes on finite convergence samples at the ends of the f64 range (relMSE 1e308,
/// time 1e-308), which pass the manifest's validation: the plot leaves out what it cannot
/// draw and the report is written.
#[test]
fn report_finishes_on_extreme_convergence_samples() {
    let point = |time_s, relmse| ConvergencePoint { time_s, relmse };
    for (name, extreme) in [
        ("relmse", point(1.0, 1e308)),
        ("time", point(1e-308, 0.1)),
        ("both", point(f64::MIN_POSITIVE, f64::MAX)),
    ] {
        let dir = temp_dir(&format!("extreme-{name}"));
        let manifest = run_with_samples(&dir, vec![point(0.5, 0.2), extreme, point(2.0, 0.05)]);
        // The values are valid input: the test reaches the plot.
        manifest.validate().unwrap();
        let output = chainlight_within(&["report", path_str(&dir)], None, LIMIT);
        assert!(output.status.success(), "{name}: {}", stderr(&output));
        let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
        assert!(
            html.contains("extreme samples") && html.contains("<svg"),
            "{name}"
        );
    }
}

/// Runs `git args` in `dir` (test set-up only).
fn git(dir: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .expect("git runs")
}

/// `report --reference` runs nothing from the current directory: a repository whose
/// `core.fsmonitor` runs a command (what `git describe --dirty` would trigger) is left
/// alone, and the report records the commit the binary was built from.
#[test]
fn report_runs_no_program_from_the_current_directory() {
    let dir = temp_dir("hostile-repo");
    assert!(git(&dir, &["init", "-q"]).status.success());
    let marker = dir.join("fsmonitor-ran");
    let hook = dir.join("hook.sh");
    std::fs::write(
        &hook,
        format!("#!/bin/sh\ntouch '{}'\nexit 1\n", marker.display()),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&hook, std::fs::Permissions::from_mode(0o755)).unwrap();
    grey_exr(&dir.join("ref.exr"), 4, 4, 0.5);
    grey_exr(&dir.join("a.exr"), 4, 4, 0.6);
    for args in [
        &[
            "-c",
            "user.name=t",
            "-c",
            "user.email=t@t",
            "add",
            "ref.exr",
        ][..],
        &[
            "-c",
            "user.name=t",
            "-c",
            "user.email=t@t",
            "commit",
            "-qm",
            "x",
        ],
        &["config", "core.fsmonitor", path_str(&hook)],
    ] {
        let out = git(&dir, args);
        assert!(out.status.success(), "git {args:?}: {}", stderr(&out));
    }
    // Negative control: what the report used to run does run the repository's command.
    git(&dir, &["describe", "--always", "--dirty"]);
    assert!(
        marker.exists(),
        "the set-up does not trigger core.fsmonitor"
    );
    std::fs::remove_file(&marker).unwrap();

    let output = chainlight_within(
        &[
            "report",
            "--reference",
            "ref.exr",
            "a.exr",
            "-o",
            "out.html",
        ],
        Some(&dir),
        LIMIT,
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        !marker.exists(),
        "report ran the repository's fsmonitor command"
    );

    // The recorded commit is the build's (this checkout's HEAD), not the folder's.
    let head = git(
        Path::new(env!("CARGO_MANIFEST_DIR")),
        &["-c", "core.fsmonitor=false", "rev-parse", "HEAD"],
    );
    let expected = if head.status.success() {
        String::from_utf8_lossy(&head.stdout).trim()[..12].to_string()
    } else {
        "unknown".to_string()
    };
    assert_eq!(BUILD_COMMIT, expected);
    let folder = git(&dir, &["-c", "core.fsmonitor=false", "rev-parse", "HEAD"]);
    let folder = String::from_utf8_lossy(&folder.stdout).trim()[..12].to_string();
    assert_ne!(folder, expected);
    let html = std::fs::read_to_string(dir.join("out.html")).unwrap();
    assert!(
        html.contains(&format!(">{expected}<")),
        "commit {expected} not in the report"
    );
    assert!(!html.contains(&folder));
}

/// A PFM environment map with the given texels (one row).
fn pfm_row(path: &Path, texels: &[[f32; 3]]) {
    let mut bytes = format!("PF\n{} 1\n-1.0\n", texels.len()).into_bytes();
    for c in texels.iter().flatten() {
        bytes.extend_from_slice(&c.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// NaN, infinite and negative texels of an environment map count as 0, and the render says
/// how many there were.
#[test]
fn bad_environment_texels_are_counted_in_a_warning() {
    let dir = temp_dir("env-texels");
    let out = dir.join("out.exr");
    let bad = dir.join("bad.pfm");
    pfm_row(
        &bad,
        &[
            [1.0; 3],
            [f32::NAN, 1.0, 1.0],
            [f32::INFINITY; 3],
            [1.0, -2.0, 1.0],
        ],
    );
    let clean = dir.join("clean.pfm");
    pfm_row(&clean, &[[1.0; 3]; 4]);
    let render = |map: &Path| {
        chainlight(&[
            "render",
            "--env",
            path_str(map),
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "1",
            "-o",
            path_str(&out),
        ])
    };
    let output = render(&bad);
    assert!(output.status.success(), "{}", stderr(&output));
    let err = stderr(&output);
    assert!(
        err.contains("bad.pfm': 2 texels with a NaN or infinite channel and 1 with a negative"),
        "{err}"
    );
    assert!(read_image(&out).is_ok());
    // Negative control: a clean map gives no such warning.
    let output = render(&clean);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(!stderr(&output).contains("texels"), "{}", stderr(&output));
}
