//! The MCMC normalisation on the command line: the summary's brightness line (the achieved
//! standard error, and a note when it exceeds 1 %; negative control: a well-estimated `b`
//! gets no note), `--normalization B|FILE` giving the image that mean luminance, and clear
//! errors for bad values, missing or unreadable files, a `b` below PSSMLT's direct pass, and
//! the flag on an integrator without chains.

mod common;

use std::path::Path;

use common::{assert_fails_with, chainlight, path_str, stderr, stdout, temp_dir};

/// Renders the Cornell box at 16 x 16, 2 mutations per pixel, with `extra` flags; returns
/// the summary (stdout).
fn render(dir: &Path, integrator: &str, extra: &[&str]) -> String {
    let out = dir.join(format!("{integrator}.exr"));
    let mut args = vec![
        "render",
        "scenes/cornell.gltf",
        "--integrator",
        integrator,
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "2",
        "--threads",
        "2",
        "-o",
        path_str(&out),
    ];
    args.extend_from_slice(extra);
    let o = chainlight(&args);
    assert!(o.status.success(), "{integrator} {extra:?}: {}", stderr(&o));
    stdout(&o)
}

/// The brightness line's standard error in percent.
fn brightness_error(summary: &str) -> f64 {
    let line = summary
        .lines()
        .find(|l| l.starts_with("brightness"))
        .unwrap_or_else(|| panic!("no brightness line in\n{summary}"));
    let after = line.split("standard error ").nth(1).unwrap();
    after.split(' ').next().unwrap().parse().unwrap()
}

/// The brightness line's mean luminance.
fn mean_luminance(summary: &str) -> f64 {
    let line = summary
        .lines()
        .find(|l| l.starts_with("brightness"))
        .unwrap();
    let after = line.split("mean luminance ").nth(1).unwrap();
    after
        .trim_end_matches(|c: char| !c.is_ascii_digit())
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn the_summary_reports_the_brightness_error_and_notes_a_large_one() {
    let dir = temp_dir("cli-normalization-summary");
    // Twenty bootstrap samples and no large step: b is known to tens of percent.
    let poor = render(
        &dir,
        "mmlt",
        &["--bootstrap-samples", "20", "--large-step", "0"],
    );
    assert!(brightness_error(&poor) > 1.0, "{poor}");
    assert!(poor.contains("exceeds 1 %"), "{poor}");
    // Negative control: the default bootstrap pooled with the large steps.
    let good = render(&dir, "pssmlt", &[]);
    let error = brightness_error(&good);
    assert!(error > 0.0 && error < 1.0, "{good}");
    assert!(!good.contains("exceeds 1 %"), "{good}");
    assert!(good.contains("large steps"), "{good}");
}

#[test]
fn a_given_normalization_sets_the_brightness() {
    let dir = temp_dir("cli-normalization-given");
    let given = render(&dir, "mmlt", &["--normalization", "0.5"]);
    assert!(given.contains("b = 0.500000 given"), "{given}");
    let mean = mean_luminance(&given);
    assert!((mean / 0.5 - 1.0).abs() < 0.01, "{given}");
    // From a reference image: its mean luminance.
    let reference = render(
        &dir,
        "mmlt",
        &["--normalization", "scenes/references/cornell.exr"],
    );
    let line = reference
        .lines()
        .find(|l| l.starts_with("brightness"))
        .unwrap();
    assert!(line.contains("given"), "{reference}");
    let (b, mean) = (
        line.split("b = ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse::<f64>()
            .unwrap(),
        mean_luminance(&reference),
    );
    assert!((mean / b - 1.0).abs() < 0.01, "{reference}");
    // PSSMLT: the chains get what the direct pass leaves; the image still has mean b.
    let pss = render(&dir, "pssmlt", &["--normalization", "0.5"]);
    assert!((mean_luminance(&pss) / 0.5 - 1.0).abs() < 0.02, "{pss}");
}

#[test]
fn bad_normalizations_are_clear_errors() {
    let dir = temp_dir("cli-normalization-errors");
    let base = [
        "render",
        "scenes/cornell.gltf",
        "--width",
        "8",
        "--height",
        "8",
    ];
    fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [base, extra].concat()
    }
    for bad in ["-1", "0", "nan", "inf"] {
        assert_fails_with(
            &with(&base, &["--integrator", "mmlt", "--normalization", bad]),
            &["--normalization", "> 0"],
        );
    }
    assert_fails_with(
        &with(
            &base,
            &[
                "--integrator",
                "mmlt",
                "--normalization",
                "no-such-reference.exr",
            ],
        ),
        &["--normalization", "no such file"],
    );
    let junk = dir.join("junk.exr");
    std::fs::write(&junk, b"not an image").unwrap();
    assert_fails_with(
        &with(
            &base,
            &["--integrator", "mmlt", "--normalization", path_str(&junk)],
        ),
        &["--normalization", "cannot read the reference image"],
    );
    assert_fails_with(
        &with(&base, &["--integrator", "pt", "--normalization", "0.5"]),
        &["--normalization"],
    );
    // Below the direct pass's own light: nothing left for the chains.
    let o = chainlight(&with(
        &base,
        &["--integrator", "pssmlt", "--normalization", "1e-9"],
    ));
    assert!(!o.status.success());
    assert!(stderr(&o).contains("normalization"), "{}", stderr(&o));
}
