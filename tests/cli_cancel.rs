//! CLI tests of Ctrl-C: an interrupted render still writes its partial image, promptly and
//! for every integrator.
#![cfg(unix)]

mod common;

use std::process::Output;

use common::{chainlight, path_str, stderr, stdout, temp_dir};
use render::image_io::read_exr;
use render::INTEGRATORS;

/// Runs `chainlight args` and sends it SIGINT (Ctrl-C) `wait` after the render started
/// ([`common::signal_after_start`]).
#[cfg(unix)]
fn interrupt(
    args: &[&str],
    wait: std::time::Duration,
) -> (Output, Vec<String>, std::time::Duration) {
    signal(args, wait, "INT")
}

/// [`interrupt`] with the signal `name` (`INT`, `TERM`, ...): [`common::signal_after_start`].
#[cfg(unix)]
fn signal(
    args: &[&str],
    wait: std::time::Duration,
    name: &str,
) -> (Output, Vec<String>, std::time::Duration) {
    common::signal_after_start(args, name, wait)
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

/// SIGTERM (what `kill`, `timeout` and service managers send) is treated like Ctrl-C: the
/// render stops within a few seconds and writes its partial image. Negative control: SIGKILL,
/// which cannot be handled, writes nothing.
#[cfg(unix)]
#[test]
fn sigterm_writes_the_partial_image() {
    use std::time::Duration;

    let dir = temp_dir("sigterm");
    let out = dir.join("partial.exr");
    let args = ["render", "--width", "32", "--height", "32", "--time", "30"];
    let args = [&args[..], &["--threads", "1", "-o", path_str(&out)]].concat();
    let (output, rest, took) = signal(&args, Duration::from_millis(500), "TERM");
    assert!(output.status.success(), "{rest:?}");
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(rest.iter().any(|l| l.contains("partial image")), "{rest:?}");
    assert!(stdout(&output).contains("cancelled"), "{}", stdout(&output));
    let image = read_exr(&out).unwrap();
    assert_eq!((image.width, image.height), (32, 32));
    assert!(image.mean_luminance() > 0.0);

    let killed = dir.join("killed.exr");
    let args = [&args[..args.len() - 1], &[path_str(&killed)]].concat();
    let (output, _, _) = signal(&args, Duration::from_millis(500), "KILL");
    assert!(!output.status.success());
    assert!(!killed.exists());
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
