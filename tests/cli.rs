//! End-to-end tests of the `chainlight` binary: flag validation, `compare`, and a tiny render.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use render::image::Image;
use render::image_io::{read_exr, write_exr};
use render::{IntegratorInfo, INTEGRATORS};

fn chainlight(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_chainlight"))
        .args(args)
        .output()
        .expect("the chainlight binary runs")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A fresh directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chainlight-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Asserts a non-zero exit whose stderr contains every `needle`.
fn assert_fails_with(args: &[&str], needles: &[&str]) {
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

#[test]
fn bad_flags_are_rejected_with_the_flag_named() {
    assert_fails_with(&["render", "--width", "0"], &["--width", "1..=16384"]);
    assert_fails_with(
        &["render", "--height", "100000"],
        &["--height", "1..=16384"],
    );
    assert_fails_with(
        &["render", "--spp", "4", "--time", "1"],
        &["--spp", "--time"],
    );
    assert_fails_with(&["render", "--spp", "0"], &["--spp"]);
    assert_fails_with(&["render", "--time", "-3"], &["--time"]);
    assert_fails_with(&["render", "--time", "nan"], &["--time"]);
    assert_fails_with(&["render", "--threads", "0"], &["--threads"]);
    assert_fails_with(&["render", "--exposure", "inf"], &["--exposure"]);
    assert_fails_with(&["render", "--seed", "-1"], &["--seed"]);
    assert_fails_with(&["render", "--integrator", "nope"], &["--integrator", "pt"]);
    assert_fails_with(
        &["render", "--integrator", "pathmlt", "--adapt", "sideways"],
        &[
            "--adapt",
            "expected fixed, global, grid or quadtree",
            "sideways",
        ],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "mala",
            "--mala-gradient",
            "reverse",
        ],
        &["--mala-gradient", "expected dual or fd", "reverse"],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "pssmlt",
            "--large-step-mis",
            "maybe",
        ],
        &["--large-step-mis", "expected on or off", "maybe"],
    );
    assert_fails_with(&["render", "-o", "out.png"], &["--output", ".exr"]);
    assert_fails_with(
        &["render", "-o", "/no/such/dir/out.exr"],
        &["--output", "/no/such/dir"],
    );
    assert_fails_with(&["compare", "only-one.exr"], &["REFERENCE"]);
}

#[test]
fn missing_and_malformed_scene_files_name_the_file() {
    let dir = temp_dir("scenes");
    let missing = dir.join("missing.gltf");
    assert_fails_with(&["render", path_str(&missing)], &["missing.gltf"]);

    let malformed = dir.join("broken.gltf");
    std::fs::write(&malformed, b"{ \"asset\": { \"version\": ").unwrap();
    let out = dir.join("out.exr");
    assert_fails_with(
        &["render", path_str(&malformed), "-o", path_str(&out)],
        &["broken.gltf"],
    );

    let wrong_kind = dir.join("scene.obj");
    std::fs::write(&wrong_kind, b"v 0 0 0").unwrap();
    assert_fails_with(&["render", path_str(&wrong_kind)], &["scene.obj", ".gltf"]);
}

#[test]
fn compare_prints_the_metrics() {
    let dir = temp_dir("compare");
    // Same hand-computed pair as the metrics unit tests:
    // diffs (0, 1, 2) and (0, -0.5, -1); reference (1, 1, 1) and (0, 0.5, 1).
    let image = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]).unwrap();
    let reference = Image::from_pixels(2, 1, vec![[1.0, 1.0, 1.0], [0.0, 0.5, 1.0]]).unwrap();
    let (a, r) = (dir.join("a.exr"), dir.join("ref.exr"));
    write_exr(&a, &image).unwrap();
    write_exr(&r, &reference).unwrap();

    let output = chainlight(&["compare", path_str(&a), path_str(&r)]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    let value = |name: &str| -> f64 {
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("no {name} line in:\n{text}"));
        line.split_whitespace().nth(1).unwrap().parse().unwrap()
    };
    let relmse = (6.0 / 1.01 + 0.25 / 0.26) / 6.0;
    let expected = [
        ("MSE", 6.25 / 6.0),
        ("RMSE", 3.125f64.sqrt()),
        ("relMSE", relmse),
        ("rRMSE", relmse.sqrt()),
        ("MAD", 4.5 / 6.0),
    ];
    for (name, want) in expected {
        let got = value(name);
        assert!((got - want).abs() <= 1e-6 * want, "{name}: {got} vs {want}");
    }
    let map = dir.join("a_error.png");
    assert!(map.is_file(), "default error map not written:\n{text}");

    let custom = dir.join("custom.png");
    let output = chainlight(&[
        "compare",
        path_str(&a),
        path_str(&r),
        "--error-map",
        path_str(&custom),
        "--linear",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(custom.is_file());
}

#[test]
fn compare_errors_name_the_files() {
    let dir = temp_dir("compare-errors");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    write_exr(&a, &Image::new(2, 2)).unwrap();
    write_exr(&b, &Image::new(3, 2)).unwrap();
    assert_fails_with(
        &["compare", path_str(&a), path_str(&b)],
        &["2x2", "3x2", "a.exr"],
    );

    let missing = dir.join("missing.exr");
    assert_fails_with(
        &["compare", path_str(&a), path_str(&missing)],
        &["missing.exr"],
    );

    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();
    assert_fails_with(
        &["compare", path_str(&garbage), path_str(&a)],
        &["garbage.exr"],
    );

    assert_fails_with(
        &[
            "compare",
            path_str(&a),
            path_str(&a),
            "--error-min",
            "2",
            "--error-max",
            "1",
        ],
        &["--error-max"],
    );
}

#[test]
fn tiny_render_writes_exr_and_png() {
    let dir = temp_dir("render");
    let out = dir.join("tiny.exr");
    let output = chainlight(&[
        "render",
        "--width",
        "16",
        "--height",
        "12",
        "--spp",
        "1",
        "--threads",
        "2",
        "-o",
        path_str(&out),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let image = read_exr(&out).unwrap();
    assert_eq!((image.width, image.height), (16, 12));
    assert!(image
        .pixels
        .iter()
        .flatten()
        .all(|c| c.is_finite() && *c >= 0.0));
    assert!(
        image.mean_luminance() > 0.0,
        "the Cornell box should not be black"
    );
    let png = dir.join("tiny.png");
    assert!(png.is_file());
    let summary = stdout(&output);
    assert!(
        summary.contains("samples/s") && summary.contains("tiny.png"),
        "{summary}"
    );
}

/// Runs `chainlight args`, sends it SIGINT (Ctrl-C) `wait` after it reports that the render
/// started (the "rendering ..." line comes after the Ctrl-C handler is installed), and returns
/// its output, its stderr lines after the first, and how long it took to exit after the signal.
#[cfg(unix)]
fn interrupt(
    args: &[&str],
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
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let interrupted = std::time::Instant::now();
    let rest: Vec<String> = stderr_lines.map_while(Result::ok).collect();
    let output = child.wait_with_output().unwrap();
    (output, rest, interrupted.elapsed())
}

/// Ctrl-C (SIGINT) during a long render still writes the partial image and exits with 0.
#[cfg(unix)]
#[test]
fn ctrl_c_writes_the_partial_image() {
    let dir = temp_dir("ctrl-c");
    let out = dir.join("partial.exr");
    let args = ["render", "--width", "32", "--height", "32", "--time", "60"];
    let (output, rest, _) = interrupt(
        &[&args[..], &["--threads", "1", "-o", path_str(&out)]].concat(),
        std::time::Duration::ZERO,
    );
    assert!(output.status.success(), "{rest:?}");
    assert!(rest.iter().any(|l| l.contains("partial image")), "{rest:?}");
    assert!(stdout(&output).contains("cancelled"), "{}", stdout(&output));
    let image = read_exr(&out).unwrap();
    assert_eq!((image.width, image.height), (32, 32));
    assert!(dir.join("partial.png").is_file());
}

/// Ctrl-C under a huge `--spp` stops every integrator of the table within a second or two
/// (writing the files included), with a partial image as bright as a finished render: every
/// pixel is averaged over the samples taken, not divided by the million planned.
#[cfg(unix)]
#[test]
fn ctrl_c_under_spp_is_prompt_for_every_integrator() {
    use std::time::Duration;

    let dir = temp_dir("ctrl-c-spp");
    let size = ["--width", "32", "--height", "32"];
    let mcmc = ["--bootstrap-samples", "4000", "--chains", "64"];
    // pathmlt's bootstrap draws one unidirectional path per sample (weight f / p, one path
    // length per sample): its b has about 6 times the variance per sample of a BDPT sample's,
    // 27% relative standard error at 4000 samples on this box. 64 000 (about the cost of 4000 BDPT
    // samples) bring it to 7%, so the 25% check tests the cancellation, not the bootstrap.
    let pathmlt = ["--bootstrap-samples", "64000", "--chains", "64"];
    let reference = dir.join("reference.exr");
    let output = chainlight(
        &[
            &["render", "--integrator", "bdpt", "--spp", "64"][..],
            &size,
            &["-o", path_str(&reference)],
        ]
        .concat(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let reference = read_exr(&reference).unwrap().mean_luminance();
    for info in INTEGRATORS {
        let out = dir.join(format!("{}.exr", info.name));
        let args = [
            &["render", "--integrator", info.name, "--spp", "1000000"][..],
            &size,
            &["--threads", "2", "-o", path_str(&out)],
            if info.kind == render::IntegratorKind::PathMlt {
                &pathmlt[..]
            } else if info.is_mcmc {
                &mcmc[..]
            } else {
                &[]
            },
        ]
        .concat();
        let (output, rest, took) = interrupt(&args, Duration::from_secs(2));
        assert!(output.status.success(), "{}: {rest:?}", info.name);
        assert!(took < Duration::from_secs(2), "{}: {took:?}", info.name);
        assert!(stdout(&output).contains("cancelled"), "{}", stdout(&output));
        let mean = read_exr(&out).unwrap().mean_luminance();
        assert!(
            (mean - reference).abs() < 0.25 * reference,
            "{}: partial image mean {mean} vs {reference}",
            info.name
        );
    }
}

/// The same seed gives a bit-identical EXR with 1 and 2 threads; another seed differs.
#[test]
fn same_seed_same_exr_for_any_thread_count() {
    let dir = temp_dir("determinism");
    let render = |name: &str, threads: &str, seed: &str| -> Vec<u8> {
        let out = dir.join(name);
        let output = chainlight(&[
            "render",
            "--width",
            "12",
            "--height",
            "10",
            "--spp",
            "2",
            "--threads",
            threads,
            "--seed",
            seed,
            "-o",
            path_str(&out),
        ]);
        assert!(output.status.success(), "{}", stderr(&output));
        std::fs::read(&out).unwrap()
    };
    let one = render("t1.exr", "1", "7");
    assert_eq!(one, render("t2.exr", "2", "7"));
    assert_ne!(one, render("s8.exr", "2", "8"));
}

/// A bundled glTF scene renders through the CLI.
#[test]
fn renders_a_bundled_gltf_scene() {
    let dir = temp_dir("gltf");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.gltf");
    let out = dir.join("cornell.exr");
    let output = chainlight(&[
        "render",
        path_str(&scene),
        "--width",
        "8",
        "--height",
        "6",
        "--spp",
        "1",
        "-o",
        path_str(&out),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(read_exr(&out).unwrap().width, 8);
    assert!(stdout(&output).contains("cornell.gltf"));
}

#[test]
fn mcmc_flags_are_validated() {
    assert_fails_with(
        &["render", "--integrator", "pssmlt", "--large-step", "1.5"],
        &["--large-step", "0..=1"],
    );
    assert_fails_with(
        &["render", "--integrator", "mmlt", "--large-step", "often"],
        &["--large-step", "auto"],
    );
    assert_fails_with(
        &["render", "--small-step", "gaussian=-1"],
        &["--small-step", "(0, 10]"],
    );
    assert_fails_with(
        &["render", "--small-step", "uniform"],
        &["--small-step", "kelemen"],
    );
    assert_fails_with(&["render", "--chains", "0"], &["--chains"]);
    assert_fails_with(
        &["render", "--bootstrap-samples", "0"],
        &["--bootstrap-samples"],
    );
}

/// `render --help` lists every integrator of the table with its help line.
#[test]
fn help_lists_every_integrator_of_the_table() {
    let output = chainlight(&["render", "--help"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let help = stdout(&output);
    for info in INTEGRATORS {
        let line = help
            .lines()
            .find(|l| {
                let l = l.trim_start().trim_start_matches("- ");
                l.starts_with(&format!("{}:", info.name))
            })
            .unwrap_or_else(|| panic!("no '{}:' line in:\n{help}", info.name));
        assert!(line.contains(info.description), "{line}");
    }
}

/// Every integrator of the table renders a tiny image; the MCMC ones log their bootstrap and,
/// with `--large-step auto`, the measured statistics and the chosen probability.
#[test]
fn every_integrator_renders_and_mcmc_logs_its_statistics() {
    let dir = temp_dir("integrators");
    for &IntegratorInfo {
        name: integrator,
        is_mcmc,
        ..
    } in INTEGRATORS
    {
        let out = dir.join(format!("{integrator}.exr"));
        let output = chainlight(&[
            "render",
            "--integrator",
            integrator,
            "--mutations-per-pixel",
            "4",
            "--width",
            "16",
            "--height",
            "16",
            "--threads",
            "2",
            "--large-step",
            "auto",
            "--bootstrap-samples",
            "2000",
            "--chains",
            "16",
            "-o",
            path_str(&out),
        ]);
        assert!(output.status.success(), "{integrator}: {}", stderr(&output));
        let img = read_exr(&out).unwrap();
        assert!(img
            .pixels
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
        assert!(
            img.pixels.iter().any(|p| p[0] > 0.0),
            "{integrator}: black image"
        );
        if is_mcmc {
            let err = stderr(&output);
            assert!(err.contains("bootstrap: b ="), "{err}");
            if integrator == "pathmlt" {
                // Path-space MLT has no large steps: it says that it ignores the flag.
                assert!(err.contains("--large-step is ignored"), "{err}");
            } else {
                assert!(
                    err.contains("automatic large-step control: eta_s =")
                        && err.contains("p_large ="),
                    "{integrator}: {err}"
                );
            }
        }
    }
}

#[test]
fn bdpt_strategy_images_are_written() {
    let dir = temp_dir("strategies");
    let out = dir.join("b.exr");
    let output = chainlight(&[
        "render",
        "--integrator",
        "bdpt",
        "--spp",
        "2",
        "--width",
        "16",
        "--height",
        "16",
        "--max-depth",
        "2",
        "--strategy-images",
        "-o",
        path_str(&out),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    for (s, t) in [(0, 2), (1, 2), (2, 1)] {
        assert!(
            dir.join(format!("b_s{s}_t{t}.exr")).is_file(),
            "missing strategy ({s},{t}): {}",
            stdout(&output)
        );
    }
}

/// `--time` covers the whole MCMC render, bootstrap included: with a bootstrap of 2 * 10^7
/// samples (minutes of work) and `--time 2`, the bootstrap stops at its share of the budget
/// and the render returns in about 2 s (bound: 8 s, for a loaded machine), saying so.
#[test]
fn mcmc_time_budget_includes_a_huge_bootstrap() {
    let dir = temp_dir("mcmc-time");
    let out = dir.join("timed.exr");
    for integrator in ["pssmlt", "mmlt"] {
        let start = std::time::Instant::now();
        let output = chainlight(&[
            "render",
            "--integrator",
            integrator,
            "--width",
            "32",
            "--height",
            "32",
            "--time",
            "2",
            "--bootstrap-samples",
            "20000000",
            "--threads",
            "2",
            "-o",
            path_str(&out),
        ]);
        let elapsed = start.elapsed();
        assert!(output.status.success(), "{}", stderr(&output));
        let text = format!("{}{}", stdout(&output), stderr(&output));
        assert!(text.contains("bootstrap stopped"), "{text}");
        assert!(
            elapsed < std::time::Duration::from_secs(8),
            "{integrator}: {elapsed:?}"
        );
        let image = read_exr(&out).unwrap();
        assert!(image.mean_luminance() > 0.0, "{integrator}: black image");
    }
}

/// Runs a tiny Cornell-box render writing `out`, expecting it to fail before rendering with
/// every needle in stderr.
fn assert_fails_before_rendering(out: &Path, needles: &[&str]) {
    let args = [
        "render",
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "1",
        "-o",
        path_str(out),
    ];
    assert_fails_with(&args, needles);
    let err = stderr(&chainlight(&args));
    assert!(
        !err.contains("rendering "),
        "the render started before the output check failed:\n{err}"
    );
}

#[test]
fn unwritable_outputs_fail_before_rendering() {
    let dir = temp_dir("unwritable");
    // The output path is a directory.
    let out = dir.join("out.exr");
    std::fs::create_dir_all(&out).unwrap();
    assert_fails_before_rendering(&out, &["--output", "out.exr", "is a directory"]);

    // The PNG preview path is a directory; the EXR probe leaves nothing behind, and an
    // existing EXR is not touched.
    let exr = dir.join("pic.exr");
    std::fs::create_dir_all(dir.join("pic.png")).unwrap();
    assert_fails_before_rendering(&exr, &["PNG preview", "pic.png", "is a directory"]);
    assert!(!exr.exists(), "the probe file was not removed");
    std::fs::write(&exr, b"keep").unwrap();
    assert_fails_before_rendering(&exr, &["PNG preview", "pic.png"]);
    assert_eq!(std::fs::read(&exr).unwrap(), b"keep");

    // A directory that exists but where nothing can be created (procfs, even for root).
    #[cfg(target_os = "linux")]
    assert_fails_before_rendering(
        Path::new("/proc/chainlight-cli-test.exr"),
        &[
            "--output",
            "/proc/chainlight-cli-test.exr",
            "cannot be written",
        ],
    );

    // A read-only directory (not read-only for root: then only the above applies).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = dir.join("read-only");
        std::fs::create_dir_all(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        let can_write = std::fs::write(ro.join("probe"), b"").is_ok();
        if can_write {
            println!("read-only directory check skipped: running with permission override (root)");
        } else {
            assert_fails_before_rendering(
                &ro.join("out.exr"),
                &["--output", "cannot be written", "ermission denied"],
            );
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }

    // Control: a writable output renders, and the file is there afterwards.
    let ok = dir.join("ok.exr");
    let output = chainlight(&[
        "render",
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "1",
        "-o",
        path_str(&ok),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(ok.is_file() && dir.join("ok.png").is_file());
}

#[test]
fn external_scene_files_need_the_flag() {
    let dir = temp_dir("external");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/render/tests/data");
    // The fixture with its buffer and image named by absolute paths outside `dir`.
    let text = std::fs::read_to_string(data.join("tiny.gltf")).unwrap();
    let mut edited = text.clone();
    for name in ["tiny.bin", "checker.png"] {
        let abs = path_str(&data.join(name)).to_owned();
        edited = edited.replace(
            &format!("\"uri\": \"{name}\""),
            &format!("\"uri\": \"{abs}\""),
        );
    }
    assert_eq!(edited.matches(path_str(&data)).count(), 2, "{edited}");
    let scene = dir.join("scene.gltf");
    std::fs::write(&scene, edited).unwrap();
    let out = dir.join("out.exr");
    let args = [
        "render",
        path_str(&scene),
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "1",
        "-o",
        path_str(&out),
    ];
    assert_fails_with(
        &args,
        &[
            "scene.gltf",
            "buffers[0].uri",
            "absolute path",
            "--allow-external-files",
        ],
    );
    let mut allowed = args.to_vec();
    allowed.push("--allow-external-files");
    let output = chainlight(&allowed);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(read_exr(&out).unwrap().width, 4);
}

/// Writes `dir/wall.gltf` (+ `wall.bin`): a 0.4 x 0.4 m emissive wall at z = 0 facing +z with
/// `emissiveStrength` `strength`, filling the view of a camera at z = 0.5 looking down -z
/// (small, so that its power, radiance x area x pi, stays finite in f32).
fn emissive_wall(dir: &Path, strength: &str) -> PathBuf {
    let mut bin = Vec::new();
    for p in [
        [-0.2f32, -0.2, 0.0],
        [0.2, -0.2, 0.0],
        [0.2, 0.2, 0.0],
        [-0.2, 0.2, 0.0],
    ] {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    std::fs::write(dir.join("wall.bin"), &bin).unwrap();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scenes": [{{"nodes": [0, 1]}}], "scene": 0,
        "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 0, 0.5]}}],
        "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.5, "znear": 0.01}}}}],
        "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0, 0, 0, 1]}},
            "emissiveFactor": [1, 1, 1],
            "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": {strength}}}}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
        "accessors": [
            {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [-0.2, -0.2, 0], "max": [0.2, 0.2, 0]}},
            {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 48}},
            {{"buffer": 0, "byteOffset": 48, "byteLength": 12}}],
        "buffers": [{{"byteLength": 60, "uri": "wall.bin"}}]}}"#
    );
    let path = dir.join("wall.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// Renders `scene` with PSSMLT at 8 x 8, 64 mutations per pixel (every pixel is visited); returns the image and the
/// summary's non-finite count. The direct-lighting pass is off: the emitter seen directly
/// (depth 0) must go through the chains' splats, the path under test.
fn pssmlt_render(scene: &Path, out: &Path) -> (Image, u64) {
    let output = chainlight(&[
        "render",
        path_str(scene),
        "--integrator",
        "pssmlt",
        "--direct-samples",
        "0",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "64",
        "--chains",
        "64",
        "--bootstrap-samples",
        "1000",
        "-o",
        path_str(out),
    ]);
    let err = stderr(&output);
    assert!(output.status.success(), "{err}");
    let summary = stdout(&output);
    let dropped: u64 = summary
        .lines()
        .find_map(|l| l.strip_prefix("non-finite"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no non-finite line in {summary}"));
    (read_exr(out).unwrap(), dropped)
}

/// An emitter of radiance 3e38 (finite in f32) through PSSMLT: the f64 pixel estimates
/// scatter around 3e38, and those above f32::MAX (3.4e38) would be inf in the f32 image.
/// They are dropped (black) and counted in the summary (before: inf pixels and "non-finite 0
/// samples dropped").
#[test]
fn huge_emission_through_pssmlt_gives_no_inf() {
    let dir = temp_dir("huge-emission");
    let (image, dropped) = pssmlt_render(&emissive_wall(&dir, "3e38"), &dir.join("hot.exr"));
    assert!(
        image.pixels.iter().flatten().all(|c| c.is_finite()),
        "the EXR has non-finite pixels"
    );
    // Every pixel sees the wall: a black pixel is a dropped one, and each is counted.
    let black = image.pixels.iter().filter(|p| **p == [0.0; 3]).count() as u64;
    assert!(
        black > 0,
        "no pixel overflowed: the test does not test anything"
    );
    assert_eq!(dropped, black, "dropped pixels and the summary disagree");
    assert!(image
        .pixels
        .iter()
        .flatten()
        .all(|c| *c == 0.0 || *c > 1e37));
    // Control: the same wall at 1e30 has no drop and no black pixel.
    let (image, dropped) = pssmlt_render(&emissive_wall(&dir, "1e30"), &dir.join("warm.exr"));
    assert_eq!(dropped, 0);
    assert!(image
        .pixels
        .iter()
        .flatten()
        .all(|c| *c > 1e29 && c.is_finite()));
}

/// `--env`: a lightless model renders under the default environment with a note; `--env none`
/// renders it black; a constant and a map environment light it; bad values name the flag.
#[test]
fn environment_flags() {
    let dir = temp_dir("env");
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/third-party/BoxVertexColors/BoxVertexColors.glb"
    );
    let render = |extra: &[&str], name: &str| -> (Output, Image) {
        let out = dir.join(name);
        let mut args = vec![
            "render",
            model,
            "--integrator",
            "pt",
            "--spp",
            "4",
            "--width",
            "16",
            "--height",
            "16",
            "-o",
            path_str(&out),
        ];
        args.extend_from_slice(extra);
        let output = chainlight(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        let image = read_exr(&out).unwrap();
        (output, image)
    };
    let mean = |im: &Image| im.pixels.iter().map(|p| p[1]).sum::<f32>() / im.pixels.len() as f32;
    let (output, default) = render(&[], "default.exr");
    let text = format!("{}{}", stdout(&output), stderr(&output));
    assert!(text.contains("default uniform white environment"), "{text}");
    assert!(mean(&default) > 0.1);
    let (_, none) = render(&["--env", "none"], "none.exr");
    assert_eq!(mean(&none), 0.0);
    let (_, dim) = render(&["--env", "0.5", "--env-strength", "0.5"], "dim.exr");
    // The background is exactly the environment's radiance.
    assert!(
        (dim.pixels[0][1] - 0.25).abs() < 1e-6,
        "{:?}",
        dim.pixels[0]
    );
    let mut map = Image::new(8, 4);
    for (i, p) in map.pixels.iter_mut().enumerate() {
        *p = [0.1 * (i % 8) as f32, 0.2, 0.3];
    }
    let map_path = dir.join("sky.exr");
    write_exr(&map_path, &map).unwrap();
    let (_, lit) = render(
        &["--env", path_str(&map_path), "--env-rotate", "45"],
        "map.exr",
    );
    assert!(mean(&lit) > 0.0 && lit.pixels.iter().flatten().all(|c| c.is_finite()));
    let out = dir.join("x.exr");
    for (args, needle) in [
        (vec!["--env", "1,2"], "--env"),
        (vec!["--env", "-1"], "0..=1000000"),
        (vec!["--env", "missing.hdr"], "no such file"),
        (vec!["--env", "1", "--env-rotate", "400"], "-360..=360"),
        (
            vec!["--env", "1", "--env-strength", "nan"],
            "--env-strength",
        ),
        (vec!["--env-strength", "2"], "--env"),
    ] {
        let mut full = vec!["render", "--spp", "1", "-o", path_str(&out)];
        full.extend(args);
        assert_fails_with(&full, &[needle]);
    }
}

/// `--dr-variant` / `--dr-on`: every variant renders on both samplers; bad values name the
/// flag and the allowed values.
#[test]
fn drmlt_flags() {
    let dir = temp_dir("drmlt");
    let out = dir.join("dr.exr");
    for variant in ["tierney-mira", "green-mira", "orbital"] {
        for base in ["pssmlt", "mmlt"] {
            let output = chainlight(&[
                "render",
                "--integrator",
                "drmlt",
                "--dr-variant",
                variant,
                "--dr-on",
                base,
                "--spp",
                "2",
                "--width",
                "8",
                "--height",
                "8",
                "--bootstrap-samples",
                "2000",
                "--chains",
                "8",
                "-o",
                path_str(&out),
            ]);
            assert!(
                output.status.success(),
                "{variant} {base}: {}",
                stderr(&output)
            );
            let text = format!("{}{}", stdout(&output), stderr(&output));
            assert!(
                text.contains(&format!("delayed rejection: {variant}")),
                "{text}"
            );
        }
    }
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "drmlt",
            "--dr-variant",
            "greenmira",
            "-o",
            path_str(&out),
        ],
        &[
            "--dr-variant",
            "tierney-mira, green-mira, orbital or cheap-then-expensive",
        ],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "drmlt",
            "--dr-on",
            "bdpt",
            "-o",
            path_str(&out),
        ],
        &["--dr-on", "pssmlt or mmlt"],
    );
}

/// `--large-step-mis`: on by default for pssmlt, off for mmlt (docs/performance.md, "Equal-time
/// efficiency (issue 17)"); `on` / `off` override it, and the render says when it is on.
#[test]
fn large_step_mis_defaults_per_integrator_and_can_be_set() {
    let dir = temp_dir("large-step-mis");
    let out = dir.join("mis.exr");
    for (integrator, flag, expect_on) in [
        ("pssmlt", None, true),
        ("pssmlt", Some("off"), false),
        ("mmlt", None, false),
        ("mmlt", Some("on"), true),
    ] {
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
            "--bootstrap-samples",
            "2000",
            "--chains",
            "16",
            "-o",
            path_str(&out),
        ];
        if let Some(value) = flag {
            args.extend(["--large-step-mis", value]);
        }
        let output = chainlight(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        let text = format!("{}{}", stdout(&output), stderr(&output));
        assert_eq!(
            text.contains("large-step MIS"),
            expect_on,
            "{integrator} {flag:?}: {text}"
        );
        assert!(read_exr(&out).unwrap().mean_luminance() > 0.0);
    }
}

/// `--raster-mutation off|on|P` (issue 17, item 2): on (0.5) by default for pssmlt, off for
/// mmlt; `on` is `pss::RASTER_DEFAULT_PROBABILITY`; the render says when raster steps are
/// taken; a bad value names the flag.
#[test]
fn raster_mutation_flag_sets_the_probability() {
    let dir = temp_dir("raster-mutation");
    let out = dir.join("raster.exr");
    for (integrator, flag, expect) in [
        ("pssmlt", None, Some("raster mutation: 0.5 ")),
        ("pssmlt", Some("0.25"), Some("raster mutation: 0.25 ")),
        ("pssmlt", Some("off"), None),
        ("mmlt", None, None),
        ("mmlt", Some("on"), Some("raster mutation: 0.5 ")),
    ] {
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
            "--bootstrap-samples",
            "2000",
            "--chains",
            "16",
            "-o",
            path_str(&out),
        ];
        if let Some(value) = flag {
            args.extend(["--raster-mutation", value]);
        }
        let output = chainlight(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        let text = format!("{}{}", stdout(&output), stderr(&output));
        match expect {
            Some(note) => assert!(text.contains(note), "{integrator} {flag:?}: {text}"),
            None => assert!(!text.contains("raster mutation"), "{flag:?}: {text}"),
        }
        assert!(read_exr(&out).unwrap().mean_luminance() > 0.0);
    }
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "pssmlt",
            "--raster-mutation",
            "1.5",
        ],
        &[
            "--raster-mutation",
            "expected `off`, `on` or a probability",
            "1.5",
        ],
    );
}

/// `--roulette off|N` and `--small-step kelemen=S1,S2` (issue 17, item 1) and
/// `--direct-samples N`, `--direct-depth K` and `--direct-share auto|S` (item 2; on for
/// pssmlt, balanced against the chains from a pilot, depth 2, off elsewhere): bad values name the
/// flag and the allowed range; good ones render, and the direct pass says so in the log.
#[test]
fn roulette_small_step_and_direct_pass_flags() {
    assert_fails_with(
        &["render", "--integrator", "bdpt", "--roulette", "sometimes"],
        &["--roulette", "off", "0..=1024", "sometimes"],
    );
    assert_fails_with(
        &["render", "--integrator", "bdpt", "--roulette", "2000"],
        &["--roulette", "0..=1024"],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "pssmlt",
            "--small-step",
            "kelemen=0.1",
        ],
        &["--small-step", "kelemen=S1,S2"],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "pssmlt",
            "--small-step",
            "kelemen=0.2,0.1",
        ],
        &["--small-step", "0 < s1 < s2 <= 0.5"],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "pssmlt",
            "--direct-samples",
            "70000",
        ],
        &["--direct-samples", "0..=65536"],
    );
    for bad in ["0", "65"] {
        assert_fails_with(
            &["render", "--integrator", "pssmlt", "--direct-depth", bad],
            &["--direct-depth", "1..=64"],
        );
    }
    for bad in ["0", "0.95", "half", "nan"] {
        assert_fails_with(
            &["render", "--integrator", "pssmlt", "--direct-share", bad],
            &["--direct-share", "auto", "0.01..=0.9", bad],
        );
    }
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "pssmlt",
            "--direct-share",
            "0.2",
            "--direct-samples",
            "4",
        ],
        &["--direct-share", "--direct-samples", "cannot be used with"],
    );
    let dir = temp_dir("roulette-direct");
    let out = dir.join("img.exr");
    // (arguments, whether the direct pass runs: on by default for pssmlt, 0 turns it off,
    // never for bdpt or mmlt)
    for (extra, direct) in [
        (&["--integrator", "bdpt", "--roulette", "off"][..], false),
        (
            &[
                "--integrator",
                "pssmlt",
                "--roulette",
                "5",
                "--small-step",
                "kelemen=0.001,0.05",
            ][..],
            true,
        ),
        (
            &["--integrator", "pssmlt", "--direct-samples", "4"][..],
            true,
        ),
        (
            &["--integrator", "pssmlt", "--direct-samples", "0"][..],
            false,
        ),
        (&["--integrator", "pssmlt", "--direct-depth", "1"][..], true),
        (
            &["--integrator", "pssmlt", "--direct-share", "0.3"][..],
            true,
        ),
        (
            &["--integrator", "pssmlt", "--direct-share", "auto"][..],
            true,
        ),
        (
            &["--integrator", "mmlt", "--direct-samples", "4"][..],
            false,
        ),
    ] {
        let mut args = vec![
            "render",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "2",
            "--bootstrap-samples",
            "2000",
            "--chains",
            "16",
            "-o",
            path_str(&out),
        ];
        args.extend_from_slice(extra);
        let output = chainlight(&args);
        assert!(output.status.success(), "{extra:?}: {}", stderr(&output));
        let text = format!("{}{}", stdout(&output), stderr(&output));
        assert_eq!(
            text.contains("direct-lighting pass"),
            direct,
            "{extra:?}: {text}"
        );
        if direct {
            // The pass's depth: 2 by default, `--direct-depth` sets it.
            let depths = if extra.contains(&"--direct-depth") {
                "depths 0-1 by BDPT"
            } else {
                "depths 0-2 by BDPT"
            };
            assert!(text.contains(depths), "{extra:?}: {text}");
            // The default (`auto`) balances the pass against the chains from a pilot and
            // says what it found; a fixed share or sample count does not.
            let expect = !extra.contains(&"--direct-samples") && !extra.contains(&"0.3");
            assert_eq!(
                text.contains("balanced against the chains"),
                expect,
                "{extra:?}: {text}"
            );
            if expect {
                assert!(
                    text.contains("of the light") && text.contains("of the budget"),
                    "{extra:?}: {text}"
                );
            }
        }
        assert!(read_exr(&out).unwrap().mean_luminance() > 0.0);
    }
}

/// MMLT's robustness options (issue 17, item 3; docs/performance.md, "MMLT robustness"):
/// `--chain-allocation per-depth`, `--strategy-strata on` and `--bdpt-normalization N` render
/// (the normalisation is named in the notes); bad values are refused with the flag named.
#[test]
fn mmlt_robustness_flags_render_and_bad_values_are_named() {
    let dir = temp_dir("mmlt-robust");
    let out = dir.join("mmlt.exr");
    let output = chainlight(&[
        "render",
        "--integrator",
        "mmlt",
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "2",
        "--bootstrap-samples",
        "2000",
        "--chains",
        "16",
        "--chain-allocation",
        "per-depth",
        "--strategy-strata",
        "on",
        "--bdpt-normalization",
        "2000",
        "-o",
        path_str(&out),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = format!("{}{}", stdout(&output), stderr(&output));
    assert!(text.contains("MMLT depth normalisation"), "{text}");
    assert!(read_exr(&out).unwrap().mean_luminance() > 0.0);
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "mmlt",
            "--chain-allocation",
            "random",
        ],
        &[
            "--chain-allocation",
            "expected joint or per-depth",
            "random",
        ],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "mmlt",
            "--strategy-strata",
            "maybe",
        ],
        &["--strategy-strata", "expected on or off", "maybe"],
    );
}
