//! CLI tests of rendering: a tiny render writes the EXR and the PNG, the same seed gives the
//! same file for any thread count, every integrator renders, and `--time` bounds MCMC renders.

mod common;

use common::{assert_fails_with, chainlight, path_str, stderr, stdout, temp_dir};
use render::image_io::read_exr;
use render::{IntegratorInfo, INTEGRATORS};

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

/// Every integrator of the table renders a tiny image; the MCMC ones log their bootstrap and,
/// with `--large-step auto` (path-space MLT has no large steps: the flag is an error there),
/// the measured statistics and the chosen probability.
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
        let mut args = vec![
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
            "-o",
            path_str(&out),
        ];
        if is_mcmc {
            args.extend(["--bootstrap-samples", "2000", "--chains", "16"]);
        }
        let large_step = ["--large-step", "auto"];
        if integrator == "pathmlt" {
            assert_fails_with(
                &[&args[..], &large_step].concat(),
                &["--large-step", "--integrator pathmlt", "it applies to"],
            );
        } else if is_mcmc {
            args.extend(large_step);
        }
        let output = chainlight(&args);
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
            assert!(err.contains("normalisation: b ="), "{err}");
            if integrator == "pathmlt" {
                assert!(err.contains("no large steps"), "{err}");
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

/// `--write-parts`: a render with a direct-lighting pass writes the pass's image and the
/// chains' part, which add up to the image (to f32 rounding); both carry light. A render
/// without a pass writes no parts and says why (the negative control).
#[test]
fn direct_pass_parts_add_up_to_the_image() {
    let dir = temp_dir("parts");
    let render = |method: &[&str], name: &str| {
        let out = dir.join(name);
        let mut args = vec!["render", "--spp", "4", "--width", "16", "--height", "16"];
        args.extend_from_slice(method);
        args.extend_from_slice(&["--write-parts", "-o", path_str(&out)]);
        let output = chainlight(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        output
    };
    let pssmlt = ["--integrator", "pssmlt", "--bootstrap-samples", "2000"];
    render(&pssmlt, "p.exr");
    let image = read_exr(dir.join("p.exr")).unwrap();
    let direct = read_exr(dir.join("p_direct.exr")).unwrap();
    let chains = read_exr(dir.join("p_chains.exr")).unwrap();
    assert!(direct.mean_luminance() > 0.0 && chains.mean_luminance() > 0.0);
    for ((sum, d), c) in image.pixels.iter().zip(&direct.pixels).zip(&chains.pixels) {
        for k in 0..3 {
            let tolerance = 1e-5 * sum[k].abs().max(1e-3);
            assert!(
                (sum[k] - (d[k] + c[k])).abs() <= tolerance,
                "{sum:?} != {d:?} + {c:?}"
            );
        }
    }
    let without = render(&["--integrator", "pt"], "q.exr");
    assert!(!dir.join("q_direct.exr").exists() && !dir.join("q_chains.exr").exists());
    assert!(
        stderr(&without).contains("no separate direct-lighting pass"),
        "{}",
        stderr(&without)
    );
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
