//! `chainlight report`: manifest round trip and validation, metrics against `render::metrics`,
//! the no-network check (with an injected external URL as negative control), the CLI, and the
//! end-to-end browser test in headless Chromium.

use std::path::{Path, PathBuf};
use std::process::Command;

use experiments::report::{
    find_external_urls, write_report, ConvergencePoint, ConvergenceSeries, MethodRun, ReportError,
    RunManifest, SeedImage,
};
use render::image::Image;
use render::image_io::write_exr;

/// A fresh directory under Cargo's per-test scratch space.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("report")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A smooth reference: a colour gradient with a bright spot.
fn reference(w: usize, h: usize) -> Image {
    let mut img = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
            let spot = (-((u - 0.6).powi(2) + (v - 0.3).powi(2)) * 40.0).exp() * 4.0;
            img.set(
                x,
                y,
                [0.2 + u * 0.6 + spot, 0.1 + v * 0.5 + spot, 0.3 + spot],
            );
        }
    }
    img
}

/// `reference` with deterministic multiplicative noise of relative size `amount`.
fn noisy(reference: &Image, amount: f32, seed: u64) -> Image {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let mut img = reference.clone();
    for p in &mut img.pixels {
        for c in p.iter_mut() {
            *c *= 1.0 + 2.0 * amount * next();
        }
    }
    img
}

/// A run directory with two methods over three seeds and convergence samples.
fn synthetic_run(dir: &Path) -> RunManifest {
    let (w, h) = (40, 30);
    let reference = reference(w, h);
    write_exr(dir.join("reference.exr"), &reference).unwrap();
    let mut methods = Vec::new();
    for (name, amount) in [("low noise", 0.1f32), ("high noise", 0.5)] {
        let mut images = Vec::new();
        let mut convergence = Vec::new();
        for seed in 0..3u64 {
            let file = format!("{}-{seed}.exr", name.replace(' ', "_"));
            write_exr(dir.join(&file), &noisy(&reference, amount, seed + 1)).unwrap();
            images.push(SeedImage {
                seed,
                path: file.into(),
            });
            let points = (0..5)
                .map(|k| {
                    let t = 0.1 * 2f64.powi(k);
                    ConvergencePoint {
                        time_s: t,
                        relmse: f64::from(amount).powi(2) / t * (1.0 + 0.1 * seed as f64),
                    }
                })
                .collect();
            convergence.push(ConvergenceSeries { seed, points });
        }
        methods.push(MethodRun {
            name: name.into(),
            parameters: [("noise".to_string(), amount.to_string())].into(),
            images,
            convergence,
        });
    }
    let manifest = RunManifest {
        title: "synthetic <run> & test".into(),
        commit: "0123456789ab".into(),
        parameters: [("size".to_string(), format!("{w}x{h}"))].into(),
        reference: "reference.exr".into(),
        methods,
    };
    manifest.save(dir).unwrap();
    manifest
}

#[test]
fn manifest_round_trips_and_validation_names_the_problem() {
    let dir = scratch("manifest");
    let manifest = synthetic_run(&dir);
    assert_eq!(RunManifest::load(&dir).unwrap(), manifest);

    let mut dup = manifest.clone();
    dup.methods[1].name = dup.methods[0].name.clone();
    let e = write_report(&dup, &dir, dir.join("x.html")).unwrap_err();
    assert!(e.to_string().contains("appears twice"), "{e}");

    let mut empty = manifest.clone();
    empty.methods.clear();
    assert!(matches!(
        write_report(&empty, &dir, dir.join("x.html")),
        Err(ReportError::Invalid(_))
    ));

    let mut bad = manifest.clone();
    bad.methods[0].convergence[0].points[0].relmse = f64::NAN;
    assert!(matches!(bad.validate(), Err(ReportError::Invalid(_))));

    std::fs::write(dir.join("broken").join("run.json"), "{").unwrap_or_else(|_| {
        std::fs::create_dir_all(dir.join("broken")).unwrap();
        std::fs::write(dir.join("broken").join("run.json"), "{").unwrap();
    });
    let e = RunManifest::load(dir.join("broken")).unwrap_err();
    assert!(e.to_string().contains("run.json"), "{e}");
}

#[test]
fn missing_and_mismatched_images_are_errors_naming_the_file() {
    let dir = scratch("errors");
    let mut manifest = synthetic_run(&dir);
    manifest.methods[1].images[2].path = "absent.exr".into();
    let e = write_report(&manifest, &dir, dir.join("x.html")).unwrap_err();
    assert!(e.to_string().contains("absent.exr"), "{e}");

    write_exr(dir.join("small.exr"), &reference(8, 8)).unwrap();
    manifest.methods[1].images[2].path = "small.exr".into();
    let e = write_report(&manifest, &dir, dir.join("x.html")).unwrap_err();
    assert!(matches!(e, ReportError::Metric { .. }), "{e}");
    assert!(e.to_string().contains("small.exr"), "{e}");
}

#[test]
fn report_holds_metrics_maps_plot_parameters_and_no_external_url() {
    let dir = scratch("content");
    let manifest = synthetic_run(&dir);
    let out = write_report(&manifest, &dir, dir.join("report.html")).unwrap();
    let html = std::fs::read_to_string(out).unwrap();

    // Metrics: the table's relMSE median is render::metrics' median over the seeds.
    let reference = render::image_io::read_exr(dir.join("reference.exr")).unwrap();
    for m in &manifest.methods {
        let values: Vec<f64> = m
            .images
            .iter()
            .map(|s| {
                let img = render::image_io::read_exr(dir.join(&s.path)).unwrap();
                render::metrics::relmse(&img, &reference).unwrap()
            })
            .collect();
        let (median, min, max) = render::metrics::median_min_max(&values).unwrap();
        assert!(min < max, "seeds must differ");
        assert!(
            html.contains(&format!("{median:.4e}")),
            "median relMSE of {}",
            m.name
        );
        assert!(
            html.contains(&format!("[{min:.3e} – {max:.3e}]")),
            "range of {}",
            m.name
        );
    }
    // Every method has a false-colour error map and a convergence line; the title is escaped.
    assert_eq!(
        html.matches("class=\"error-map\" src=\"data:image/png;base64,")
            .count(),
        2
    );
    assert!(html.contains("<svg") && html.contains("relMSE vs render time"));
    assert!(html.contains("synthetic &lt;run&gt; &amp; test"));
    assert!(html.contains("0123456789ab") && html.contains("40x30"));
    assert!(
        find_external_urls(&html).is_empty(),
        "{:?}",
        find_external_urls(&html)
    );

    // A method name cannot close the embedded data block.
    let mut hostile = manifest.clone();
    hostile.methods[0].name = "x</script><!--<script>y".into();
    let out = write_report(&hostile, &dir, dir.join("hostile.html")).unwrap();
    let page = std::fs::read_to_string(out).unwrap();
    assert_eq!(
        page.matches("</script>").count(),
        2,
        "data block and main script only"
    );
    assert!(page.contains("x\\u003c/script>"));

    // Negative control: the check sees an external image, stylesheet or script.
    for inject in [
        r#"<img src="https://example.org/a.png">"#,
        r#"<link rel="stylesheet" href="//cdn.example.org/x.css">"#,
        r#"<script src="http://example.org/x.js"></script>"#,
    ] {
        let bad = html.replacen("</body>", &format!("{inject}</body>"), 1);
        assert_eq!(find_external_urls(&bad).len(), 1, "missed {inject}");
    }
}

#[test]
fn cli_report_from_a_run_directory_and_from_images() {
    let dir = scratch("cli");
    synthetic_run(&dir);
    let bin = env!("CARGO_BIN_EXE_chainlight");
    let run = Command::new(bin).arg("report").arg(&dir).output().unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(dir.join("report.html").is_file());

    let out = dir.join("loose").join("cmp.html");
    let run = Command::new(bin)
        .args(["report", "--title", "loose files", "--reference"])
        .arg(dir.join("reference.exr"))
        .arg(dir.join("low_noise-0.exr"))
        .arg(dir.join("high_noise-0.exr"))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let html = std::fs::read_to_string(&out).unwrap();
    assert!(html.contains("low_noise-0") && html.contains("loose files"));

    // Bad input: a directory without run.json, a missing reference; exit code 1 and the path.
    let run = Command::new(bin)
        .arg("report")
        .arg(dir.join("loose"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("run.json"));
    let run = Command::new(bin)
        .args(["report", "--reference", "no-such-ref.exr"])
        .arg(dir.join("low_noise-0.exr"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("no-such-ref.exr"));
}

/// Installs Chromium and playwright-core with the project's script; `Err` says why not.
fn install_browser() -> Result<(), String> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/browser/install.sh");
    let out = Command::new("bash")
        .arg(&script)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{} failed: {}",
            script.display(),
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("")
        ))
    }
}

/// Runs the browser check on `report`; returns (passed, its JSON line).
fn browser_check(report: &Path, screenshot: &Path) -> (bool, String) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/browser/report_check.mjs");
    let out = Command::new("node")
        .arg(script)
        .arg(report)
        .arg(screenshot)
        .output()
        .expect("node runs (install.sh checked npm)");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

#[test]
fn report_works_in_headless_chromium() {
    if let Err(why) = install_browser() {
        println!("SKIPPED report_works_in_headless_chromium: Chromium/playwright-core cannot be installed here ({why})");
        return;
    }
    let dir = scratch("browser");
    let manifest = synthetic_run(&dir);
    let report = write_report(&manifest, &dir, dir.join("report.html")).unwrap();
    let shot = dir.join("report.png");
    let (ok, text) = browser_check(&report, &shot);
    assert!(ok, "browser check failed: {text}");
    assert!(text.contains("\"failures\":[]"), "{text}");
    let png = std::fs::read(&shot).expect("screenshot written");
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 10_000,
        "screenshot too small"
    );

    // Negative control: the same report with an external image fails in the browser too.
    let html = std::fs::read_to_string(&report).unwrap();
    let bad = dir.join("external.html");
    std::fs::write(
        &bad,
        html.replacen(
            "</body>",
            r#"<img src="http://example.invalid/x.png"></body>"#,
            1,
        ),
    )
    .unwrap();
    let (ok, text) = browser_check(&bad, &dir.join("external.png"));
    assert!(!ok && text.contains("external request blocked"), "{text}");
}
