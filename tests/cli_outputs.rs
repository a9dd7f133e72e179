//! CLI tests of what the commands write: side files checked up front and never costing the
//! image, outputs that would overwrite an input refused, and atomic writes (no truncated file,
//! no temporary file left behind).
#![cfg(unix)]

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use common::{assert_fails_with, chainlight, entries, grey_exr, path_str, stderr, temp_dir};
use render::image_io::{read_exr, read_image};

/// The render arguments of a tiny BDPT render with strategy images into `out`.
fn bdpt_strategy_images(out: &Path, budget: [&'static str; 2]) -> Vec<String> {
    [
        "render",
        "--integrator",
        "bdpt",
        "--strategy-images",
        "--max-depth",
        "2",
        "--width",
        "8",
        "--height",
        "8",
        budget[0],
        budget[1],
        "--threads",
        "1",
        "-o",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([path_str(out).to_string()])
    .collect()
}

/// A side file that cannot be written (a directory in its place) is refused before rendering,
/// like the EXR and the PNG: BDPT's strategy images and DRMLT's stage map and its preview.
#[test]
fn unwritable_side_files_are_refused_before_rendering() {
    let dir = temp_dir("side-up-front");
    let out = dir.join("b.exr");
    std::fs::create_dir(dir.join("b_s0_t2.exr")).unwrap();
    let args = bdpt_strategy_images(&out, ["--spp", "1"]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    assert_fails_with(&args, &["strategy image", "b_s0_t2.exr", "directory"]);
    assert!(!out.exists());
    for blocked in ["d_stage2.exr", "d_stage2.png"] {
        let dir = temp_dir(&format!("side-drmlt-{blocked}"));
        std::fs::create_dir(dir.join(blocked)).unwrap();
        let out = dir.join("d.exr");
        assert_fails_with(
            &[
                "render",
                "--integrator",
                "drmlt",
                "--spp",
                "1",
                "-o",
                path_str(&out),
            ],
            &["DR stage map", blocked, "directory"],
        );
        assert!(!out.exists());
    }
    // Negative control: without the directory both render and write their side files.
    let dir = temp_dir("side-ok");
    let out = dir.join("b.exr");
    let args = bdpt_strategy_images(&out, ["--spp", "1"]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let output = chainlight(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(read_exr(dir.join("b_s0_t2.exr")).is_ok());
}

/// A side file that becomes unwritable during the render (a directory created in its place
/// after the check) fails the command, but only after the image, its preview and the other
/// side files are written.
#[test]
fn a_side_file_failing_after_the_render_loses_nothing_else() {
    let dir = temp_dir("side-late");
    let out = dir.join("b.exr");
    let args = bdpt_strategy_images(&out, ["--time", "3"]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_chainlight"))
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    // "rendering ..." is printed after the up-front checks passed.
    let first = lines.next().unwrap().unwrap();
    assert!(first.starts_with("rendering"), "{first}");
    std::fs::create_dir(dir.join("b_s0_t2.exr")).unwrap();
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(1), "{rest:?}");
    let last = rest.last().cloned().unwrap_or_default();
    assert!(
        last.contains("could not be written") && last.contains("b_s0_t2.exr"),
        "{rest:?}"
    );
    let image = read_exr(&out).unwrap();
    assert!(image.mean_luminance() > 0.0);
    assert!(read_image(dir.join("b_s1_t2.exr")).is_ok());
    assert!(dir.join("b.png").is_file());
}

/// Runs `args`, expecting a refusal naming both files, and checks `input` kept its bytes.
fn refused_keeps(args: &[&str], input: &Path, needles: &[&str]) {
    let before = std::fs::read(input).unwrap();
    assert_fails_with(
        args,
        &[needles, &["refusing to overwrite an input"]].concat(),
    );
    assert_eq!(std::fs::read(input).unwrap(), before, "{args:?}");
}

/// No command writes over its own inputs: the same path, another spelling, a hard or a
/// symbolic link; the error names both files.
#[test]
fn outputs_never_overwrite_inputs() {
    let dir = temp_dir("inputs");
    let map = dir.join("m.exr");
    grey_exr(&map, 4, 2, 0.5);
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    grey_exr(&a, 4, 4, 0.5);
    grey_exr(&b, 4, 4, 0.6);
    let small = ["--width", "8", "--height", "8", "--spp", "1"];
    fn render<'a>(small: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [&["render"][..], small, extra].concat()
    }
    let m = path_str(&map);
    refused_keeps(
        &render(&small, &["--env", m, "-o", m]),
        &map,
        &["--output", "--env"],
    );
    let spelled = format!("{}/./m.exr", dir.display());
    refused_keeps(
        &render(&small, &["--env", m, "-o", &spelled]),
        &map,
        &["--env"],
    );
    // The PNG preview as a hard link to the map.
    std::fs::hard_link(&map, dir.join("p.png")).unwrap();
    let p = dir.join("p.exr");
    refused_keeps(
        &render(&small, &["--env", m, "-o", path_str(&p)]),
        &map,
        &["the PNG preview", "p.png", "--env"],
    );
    // A side file: the DR stage map.
    let stage = dir.join("s_stage2.exr");
    grey_exr(&stage, 4, 2, 0.5);
    let s = dir.join("s.exr");
    refused_keeps(
        &render(
            &small,
            &[
                "--integrator",
                "drmlt",
                "--env",
                path_str(&stage),
                "-o",
                path_str(&s),
            ],
        ),
        &stage,
        &["DR stage map", "--env"],
    );
    // The scene, through a symbolic link named like an output.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.gltf");
    let copy = dir.join("scene.gltf");
    std::fs::copy(&scene, &copy).unwrap();
    let link = dir.join("link.exr");
    std::os::unix::fs::symlink(&copy, &link).unwrap();
    refused_keeps(
        &render(&small, &[path_str(&copy), "-o", path_str(&link)]),
        &copy,
        &["--output", "SCENE"],
    );
    // compare: the error map onto the reference or the image.
    let (a_s, b_s) = (path_str(&a), path_str(&b));
    refused_keeps(
        &["compare", a_s, b_s, "--error-map", b_s],
        &b,
        &["the error map", "REFERENCE"],
    );
    refused_keeps(
        &["compare", a_s, b_s, "--error-map", a_s],
        &a,
        &["the error map", "IMAGE"],
    );
    // report: the output onto the reference or a result image.
    refused_keeps(
        &["report", "--reference", b_s, a_s, "-o", b_s],
        &b,
        &["the report", "the reference"],
    );
    refused_keeps(
        &["report", "--reference", b_s, a_s, "-o", a_s],
        &a,
        &["the report", "the image of a"],
    );
    // Negative control: distinct outputs are written.
    let output = chainlight(&[
        "compare",
        a_s,
        b_s,
        "--error-map",
        path_str(&dir.join("e.png")),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let output = chainlight(&render(
        &small,
        &["--env", m, "-o", path_str(&dir.join("ok.exr"))],
    ));
    assert!(output.status.success(), "{}", stderr(&output));
}

/// Every command's outputs are complete files and no temporary file is left in the folder,
/// also when an existing output is replaced.
#[test]
fn outputs_are_replaced_whole_without_leftovers() {
    let dir = temp_dir("atomic");
    let out = dir.join("o.exr");
    for spp in ["1", "2"] {
        let output = chainlight(&[
            "render",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            spp,
            "-o",
            path_str(&out),
        ]);
        assert!(output.status.success(), "{}", stderr(&output));
    }
    let output = chainlight(&["compare", path_str(&out), path_str(&out)]);
    assert!(output.status.success(), "{}", stderr(&output));
    let output = chainlight(&[
        "report",
        "--reference",
        path_str(&out),
        path_str(&out),
        "-o",
        path_str(&dir.join("r.html")),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(entries(&dir), ["o.exr", "o.png", "o_error.png", "r.html"]);
    assert!(read_exr(&out).is_ok());
}

/// A second Ctrl-C aborts at whatever point the render is (possibly while writing): the
/// output is then the old file or a complete new one, never a truncated one, and no
/// temporary file is left behind.
#[test]
fn a_second_interrupt_never_leaves_a_truncated_output() {
    let dir = temp_dir("second-interrupt");
    let out = dir.join("o.exr");
    grey_exr(&out, 4, 4, 0.25);
    for delay_ms in [0u64, 50, 200] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_chainlight"))
            .args([
                "render",
                "--width",
                "1024",
                "--height",
                "1024",
                "--time",
                "30",
                "--threads",
                "1",
                "-o",
            ])
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
        let first = lines.next().unwrap().unwrap();
        assert!(first.starts_with("rendering"), "{first}");
        let pid = child.id().to_string();
        let interrupt = || Command::new("kill").args(["-INT", &pid]).status().unwrap();
        assert!(interrupt().success());
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        // The process may already have finished writing and exited: then this one fails.
        interrupt();
        let _rest: Vec<String> = lines.map_while(Result::ok).collect();
        let status = child.wait().unwrap();
        assert!(matches!(status.code(), Some(0 | 130)), "{status:?}");
        let image = read_exr(&out).expect("the output is a complete EXR");
        assert!(matches!((image.width, image.height), (4, 4) | (1024, 1024)));
        let names = entries(&dir);
        assert!(
            names.iter().all(|n| n == "o.exr" || n == "o.png"),
            "{names:?}"
        );
    }
}
