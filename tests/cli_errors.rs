//! CLI tests of flag validation: bad values name the flag and the allowed range, `--help`
//! lists the integrators, and unwritable outputs fail before the render starts.

mod common;

use std::path::Path;

use common::{assert_fails_with, chainlight, path_str, stderr, stdout, temp_dir};
use render::INTEGRATORS;

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
        &["render", "--integrator", "pathmlt", "--sigma", "4"],
        &[
            "--sigma",
            "expected paper, tuned or radians in (0, pi]",
            "4",
        ],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "pathmlt",
            "--target-acceptance",
            "1.5",
        ],
        &["target-acceptance", "(0, 1)"],
    );
    assert_fails_with(
        &[
            "render",
            "--integrator",
            "mala",
            "--mala-gradient",
            "reverse",
        ],
        &[
            "--mala-gradient",
            "expected dual, dual-constant-mis or fd",
            "reverse",
        ],
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
