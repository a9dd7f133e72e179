//! Transport coverage: every integrator of the table either converges to the BDPT reference on
//! every coverage scene (`common::coverage`: a caustic, a floor lit only via two mirrors, a
//! light seen only in a mirror, a tiny bright light, an environment-lit room) or refuses the
//! scene with an error; a negative control (BDPT with its light-side strategies switched off)
//! fails the same check.
//!
//! # Statistics
//!
//! As in `mlt_convergence.rs`: each integrator renders `R` independent replicates (different
//! seeds), BDPT `K`. For a statistic `X` of one image (its mean luminance, the mean of each of
//! its `BLOCKS x BLOCKS` blocks) the replicate values are i.i.d. and, each a sum over
//! thousands of samples, close to normal; every method here is unbiased or, for the Markov
//! chain methods, exact in expectation for any run length (their start is resampled in
//! proportion to the target), so `T = (m - m_ref) / sqrt(s^2 / R + s_ref^2 / K)` is Student's t
//! with at least `min(R, K) - 1` degrees of freedom under the null hypothesis. All the
//! comparisons of this file share a family-wise false-alarm probability `ALPHA_FAMILY`
//! (Bonferroni). A method that misses a class of paths (or reaches it with a heavy-tailed
//! estimator, so that most replicates lack it) is low in the blocks those paths light, by many
//! of its own standard errors.

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::coverage::{CoverageScene, SCENES};
use common::stats::{assert_finite_non_negative, block_means, mean_se, t_critical};
use rayon::prelude::*;
use render::bdpt::{render_bdpt, BdptParams};
use render::image::Image;
use render::scene::Scene;
use render::session::{render, Budget, NoProgress, RenderSettings};
use render::{IntegratorKind, INTEGRATORS};

/// Family-wise false-alarm probability of all the comparisons in this file.
const ALPHA_FAMILY: f64 = 0.001;
/// Image size (pixels per side).
const SIZE: u32 = 16;
/// Maximum path depth (the deepest path of the scenes, `L S S D E` and the glass ball's
/// `L S S D S S E`, fits).
const DEPTH: u32 = 6;
/// Replicates per integrator and of the reference.
const R: usize = 16;
/// BDPT reference replicates.
const K: usize = 16;
/// Samples per pixel of one reference replicate.
const REF_SPP: u32 = 256;
/// Samples (or mutations) per pixel of one replicate of the tested integrators.
const SPP: u32 = 64;
/// Chains and bootstrap samples of the Markov chain integrators.
const CHAINS: usize = 32;
const BOOTSTRAP: usize = 20_000;
/// Each image is split into `BLOCKS x BLOCKS` blocks.
const BLOCKS: usize = 2;
/// Null-hypothesis comparisons: per scene and tested integrator (every row but BDPT), the
/// image mean and every block mean.
const N_COMPARISONS: usize = SCENES.len() * (INTEGRATORS.len() - 1) * (1 + BLOCKS * BLOCKS);

fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32)
}

fn statistics(image: &Image) -> Vec<f64> {
    let mut s = vec![image.mean_luminance()];
    s.extend(block_means(image, BLOCKS));
    s
}

/// The reference of one scene: `K` BDPT replicates, and for the negative control the same
/// renders' camera-side strategies with `s <= 1` (eye subpaths that hit a light or connect to
/// one light vertex: light-side sampling switched off, the other strategies' MIS weights
/// unchanged).
struct Reference {
    full: Vec<Image>,
    eye_side_only: Vec<Image>,
}

fn reference(scene: &CoverageScene) -> &'static Reference {
    static CACHE: OnceLock<Vec<OnceLock<Reference>>> = OnceLock::new();
    let cache = CACHE.get_or_init(|| SCENES.iter().map(|_| OnceLock::new()).collect());
    let i = SCENES.iter().position(|s| s.name == scene.name).unwrap();
    cache[i].get_or_init(|| {
        let built = (scene.build)(SIZE);
        let params = BdptParams {
            max_depth: DEPTH,
            ..BdptParams::default()
        };
        // Independent renders (one seed each): on the rayon pool, collected in seed order.
        let renders: Vec<(Image, Image)> = (0..K as u64)
            .into_par_iter()
            .map(|k| {
                let cancel = AtomicBool::new(false);
                let out = render_bdpt(
                    &built,
                    &params,
                    Some(REF_SPP),
                    None,
                    50_000 + k,
                    true,
                    &NoProgress,
                    &cancel,
                );
                assert_eq!(out.dropped, 0, "{}: BDPT reference", scene.name);
                assert_finite_non_negative(&out.image, "BDPT reference");
                let mut eye = Image::new(out.image.width, out.image.height);
                for (_, img) in out.strategy_images.iter().filter(|((s, _), _)| *s <= 1) {
                    for (p, q) in eye.pixels.iter_mut().zip(&img.pixels) {
                        for c in 0..3 {
                            p[c] += q[c];
                        }
                    }
                }
                (out.image, eye)
            })
            .collect();
        let (full, eye_side_only) = renders.into_iter().unzip();
        if let Some(dir) = std::env::var_os("CHAINLIGHT_COVERAGE_DUMP") {
            // For inspection: the reference's mean image, at 64 x 64 pixels.
            let big = (scene.build)(64);
            let cancel = AtomicBool::new(false);
            let out = render_bdpt(
                &big,
                &params,
                Some(1024),
                None,
                1,
                false,
                &NoProgress,
                &cancel,
            );
            let path = std::path::Path::new(&dir).join(format!("{}.png", scene.name));
            render::image_io::write_png(&path, &out.image, 0.0).unwrap();
        }
        Reference {
            full,
            eye_side_only,
        }
    })
}

/// The largest |t| of `images` against `reference` over the image mean and the blocks, with
/// the statistic's index.
fn worst_t(images: &[Image], reference: &[Image]) -> (f64, usize, f64, f64) {
    let a: Vec<Vec<f64>> = images.iter().map(statistics).collect();
    let b: Vec<Vec<f64>> = reference.iter().map(statistics).collect();
    let mut worst = (0.0, 0, 0.0, 0.0);
    for k in 0..a[0].len() {
        let (ma, sa) = mean_se(&a.iter().map(|s| s[k]).collect::<Vec<_>>());
        let (mb, sb) = mean_se(&b.iter().map(|s| s[k]).collect::<Vec<_>>());
        let t = (ma - mb) / (sa * sa + sb * sb).sqrt().max(1e-300);
        if t.abs() > worst.0 {
            worst = (t.abs(), k, ma, mb);
        }
    }
    worst
}

fn settings(kind: IntegratorKind, seed: u64) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        budget: Budget::SamplesPerPixel(SPP),
        threads: 1,
        seed,
        max_depth: DEPTH,
        method: kind.settings().with_chains(CHAINS, BOOTSTRAP),
    }
}

/// What an integrator did with a scene.
enum Outcome {
    /// Refused it, with this error message.
    Refused(String),
    /// Rendered these replicates.
    Rendered(Vec<Image>),
}

/// The `R` replicates of `kind` (seeds `seed0 + r`), independent one-thread renders run on the
/// rayon pool and collected in seed order; an integrator that refuses the scene refuses it on
/// every replicate.
fn run(kind: IntegratorKind, scene: &Scene, seed0: u64) -> Outcome {
    let results: Vec<Result<Image, String>> = (0..R as u64)
        .into_par_iter()
        .map(|r| -> Result<Image, String> {
            let s = settings(kind, seed0 + r);
            let out = render(scene, &s, &NoProgress, &AtomicBool::new(false))
                .map_err(|e| e.to_string())?;
            assert!(!out.cancelled);
            assert_finite_non_negative(&out.image, "coverage replicate");
            Ok(out.image)
        })
        .collect();
    if let Err(message) = &results[0] {
        for (r, result) in results.iter().enumerate() {
            assert!(
                result.is_err(),
                "refused on replicate 0 only, not on {r}: {message}"
            );
        }
        return Outcome::Refused(message.clone());
    }
    let mut images = Vec::with_capacity(R);
    for (r, result) in results.into_iter().enumerate() {
        images.push(result.unwrap_or_else(|e| panic!("refused on replicate {r} only: {e}")));
    }
    Outcome::Rendered(images)
}

fn coverage(index: usize) {
    let case = &SCENES[index];
    let scene = (case.build)(SIZE);
    let reference = reference(case);
    assert!(
        reference
            .full
            .iter()
            .map(Image::mean_luminance)
            .sum::<f64>()
            > 0.0,
        "{}: the reference is black",
        case.name
    );
    let crit = critical();
    let mut failures = Vec::new();
    for (i, info) in INTEGRATORS.iter().enumerate() {
        if info.kind == IntegratorKind::Bdpt {
            continue;
        }
        match run(info.kind, &scene, 1000 * (i as u64 + 1)) {
            Outcome::Refused(message) => {
                assert!(
                    message.len() > 20,
                    "{} refused {} without saying why: {message:?}",
                    info.name,
                    case.name
                );
                eprintln!("{} / {}: refused: {message}", case.name, info.name);
            }
            Outcome::Rendered(images) => {
                let (t, k, m, m_ref) = worst_t(&images, &reference.full);
                eprintln!(
                    "{} / {}: worst |t| {t:.2} (statistic {k}: {m:.5} vs {m_ref:.5}), critical {crit:.2}",
                    case.name, info.name
                );
                if t > crit {
                    failures.push(format!(
                        "{} on {} ({}): statistic {k} is {m:.5}, BDPT {m_ref:.5}, |t| = {t:.1} > {crit:.1}",
                        info.name, case.name, case.paths
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn caustic_through_glass() {
    coverage(0);
}

#[test]
fn floor_lit_via_two_mirrors() {
    coverage(1);
}

#[test]
fn light_seen_only_in_a_mirror() {
    coverage(2);
}

#[test]
fn tiny_bright_light() {
    coverage(3);
}

#[test]
fn environment_through_a_window() {
    coverage(4);
}

/// The negative control: BDPT without its light-side strategies (`s >= 2`), the other
/// strategies' MIS weights unchanged, fails the check on the scenes whose light reaches the
/// camera only via specular surfaces and a diffuse one (there the light-side strategies carry
/// most of the image).
#[test]
fn negative_control_without_light_side_sampling_fails() {
    // The control's images are the eye-side part of the second half of the reference renders,
    // compared with the first half's full images (independent renders).
    let half = K / 2;
    let crit = t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (half - 1) as u32);
    for index in [0, 1] {
        let case = &SCENES[index];
        let reference = reference(case);
        let (t, k, m, m_ref) = worst_t(&reference.eye_side_only[half..], &reference.full[..half]);
        eprintln!(
            "negative control on {}: worst |t| {t:.1} (statistic {k}: {m:.5} vs {m_ref:.5})",
            case.name
        );
        assert!(
            t > crit,
            "{}: BDPT without light-side strategies passed (|t| = {t:.2} <= {crit:.2})",
            case.name
        );
    }
}
