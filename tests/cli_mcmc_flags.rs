//! CLI tests of the MCMC options: delayed rejection, large-step MIS, raster mutation,
//! roulette, small steps, the direct-lighting pass and MMLT's robustness options.

mod common;

use common::{assert_fails_with, chainlight, path_str, stderr, stdout, temp_dir, tiny_render};
use render::image_io::read_exr;

/// `--dr-variant` / `--dr-on`: every variant renders on both samplers; bad values name the
/// flag and the allowed values.
#[test]
fn drmlt_flags() {
    let dir = temp_dir("drmlt");
    let out = dir.join("dr.exr");
    for variant in [
        "tierney-mira",
        "green-mira",
        "orbital",
        "tierney-mira-pairwise",
        "green-mira-pairwise",
    ] {
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
            "tierney-mira, green-mira, orbital, cheap-then-expensive, tierney-mira-pairwise, \
             green-mira-pairwise",
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
        &["--dr-on", "pssmlt, pssmlt-pt or mmlt"],
    );
}

/// `--large-step-mis`: on by default for pssmlt, off for mmlt and drmlt (docs/methods/large-step-mis.md,
/// "Measured"); `on` / `off` override it, and the render says when it is on.
#[test]
fn large_step_mis_defaults_per_integrator_and_can_be_set() {
    let dir = temp_dir("large-step-mis");
    let out = dir.join("mis.exr");
    for (integrator, flag, expect_on) in [
        ("pssmlt", None, true),
        ("pssmlt", Some("off"), false),
        ("mmlt", None, false),
        ("mmlt", Some("on"), true),
        ("drmlt", None, false),
        ("drmlt", Some("on"), true),
    ] {
        let extra: &[&str] = match flag {
            Some(value) => &["--large-step-mis", value],
            None => &[],
        };
        let text = tiny_render(&out, integrator, extra);
        assert_eq!(
            text.contains("large-step MIS"),
            expect_on,
            "{integrator} {flag:?}: {text}"
        );
        assert!(read_exr(&out).unwrap().mean_luminance() > 0.0);
    }
}

/// `--raster-mutation off|on|P` (docs/performance.md, "Raster mutation"): on (0.5) by default
/// for pssmlt, off for mmlt; `on` is `pss::RASTER_DEFAULT_PROBABILITY`; the render says when
/// raster steps are taken; a bad value names the flag.
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
        let extra: &[&str] = match flag {
            Some(value) => &["--raster-mutation", value],
            None => &[],
        };
        let text = tiny_render(&out, integrator, extra);
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

/// `--roulette off|N` and `--small-step kelemen=S1,S2`, and `--direct-samples N`,
/// `--direct-depth K` and `--direct-share auto|S` (the direct-lighting pass: on for pssmlt,
/// balanced against the chains from a pilot, depth 2, off elsewhere): bad values name the flag
/// and the allowed range; good ones render, and the direct pass says so in the log.
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
    // never for bdpt; `--direct-samples` with mmlt is an error:
    // `flags_without_effect_are_errors_naming_where_they_apply`)
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
    ] {
        let text = tiny_render(&out, extra[1], &extra[2..]);
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

/// MMLT's robustness options (docs/performance.md, "MMLT robustness"):
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

/// A method flag typed for an integrator it has no effect on is an error naming the flag, the
/// integrator and where the flag applies (every integrator x flag: the unit tests of
/// `src/cli/method_flags.rs`); nothing is rendered.
#[test]
fn flags_without_effect_are_errors_naming_where_they_apply() {
    let dir = temp_dir("inapplicable");
    let out = dir.join("x.exr");
    for (args, needles) in [
        (
            &["--integrator", "drmlt", "--dr-fixed-strategy"][..],
            &[
                "--dr-fixed-strategy",
                "--integrator drmlt",
                "drmlt with --dr-on mmlt and --dr-variant orbital",
            ][..],
        ),
        (
            &["--integrator", "pt", "--chains", "8"],
            &["--chains", "--integrator pt", "pathmlt"],
        ),
        (
            &["--integrator", "pssmlt", "--strategy-images"],
            &["--strategy-images", "applies to: bdpt"],
        ),
        (
            &["--integrator", "drmlt", "--mala-gradient", "fd"],
            &[
                "--mala-gradient",
                "drmlt with --dr-variant cheap-then-expensive",
            ],
        ),
        (
            &["--integrator", "lqmc", "--roulette", "2"],
            &["--roulette", "--integrator lqmc"],
        ),
    ] {
        let full = [&["render", "--spp", "1", "-o", path_str(&out)][..], args].concat();
        assert_fails_with(&full, needles);
        assert!(!out.exists(), "{args:?}");
    }
    // Negative control: the same flags where they apply render.
    let chains = ["--chains", "8", "--bootstrap-samples", "1000"];
    for args in [
        &["--integrator", "pssmlt", "--direct-samples", "4"][..],
        &[
            "--integrator",
            "bdpt",
            "--strategy-images",
            "--max-depth",
            "1",
        ],
        &[
            "--integrator",
            "drmlt",
            "--dr-variant",
            "cheap-then-expensive",
            "--mala-gradient",
            "fd",
        ],
    ] {
        let mcmc = if args[1] == "bdpt" {
            &[][..]
        } else {
            &chains[..]
        };
        let size = ["--width", "8", "--height", "8"];
        let full = [
            &["render", "--spp", "1", "-o", path_str(&out)][..],
            &size,
            mcmc,
            args,
        ]
        .concat();
        let output = chainlight(&full);
        assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    }
}
