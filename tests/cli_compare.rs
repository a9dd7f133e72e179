//! CLI tests of `chainlight compare`: the metrics it prints, the error map it writes, and
//! errors naming the files.

mod common;

use common::{assert_fails_with, chainlight, path_str, stderr, stdout, temp_dir};
use render::image::Image;
use render::image_io::write_exr;

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
