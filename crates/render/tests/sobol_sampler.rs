//! PT and BDPT with the Owen-scrambled Sobol sampler (`--sampler sobol`) converge to the
//! independent-sample BDPT reference on the Cornell box and the glass Cornell box (image mean,
//! 4 x 4 block means, relMSE against its expectation); a negative control (Sobol PT one bounce
//! short) fails the same test; same seed on 1 and 2 threads is bit-identical; the sampler is an
//! error for integrators that own their numbers.
//!
//! # Statistics
//!
//! `R` replicates per estimate with master seeds `seed0 + r` (independent scramblings). The
//! pixels of one Sobol image are independent of each other (each pixel is scrambled with its
//! own keys) but a pixel's samples are not, so standard errors come from the replicates
//! (`common::stats::against_reference`: Welch t per statistic). Bonferroni over
//! `N_COMPARISONS` at family-wise `ALPHA_FAMILY`, Student-t critical values with `R - 1`
//! degrees of freedom (conservative).

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::scene_file;
use common::stats::{against_reference, block_t, mean_se, t_critical};
use render::bdpt::{render_bdpt_sampled, BdptParams};
use render::budget::Budget;
use render::image::Image;
use render::methods::{BdptSettings, MethodSettings, PssmltSettings, PtSettings};
use render::sampler::SamplerKind;
use render::scene::Scene;
use render::session::{render, IntegratorKind, NoProgress, RenderSettings};

/// Family-wise false-alarm probability of the null-hypothesis comparisons.
const ALPHA_FAMILY: f64 = 0.001;
/// Replicates per estimate.
const R: usize = 16;
/// Blocks per side.
const BLOCKS: usize = 4;
/// Two scenes x two integrators x (image mean + blocks).
const N_COMPARISONS: usize = 2 * 2 * (1 + BLOCKS * BLOCKS);
/// Maximum path depth of every render.
const DEPTH: u32 = 4;

fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R - 1) as u32)
}

fn params(max_depth: u32) -> BdptParams {
    BdptParams {
        max_depth,
        ..BdptParams::default()
    }
}

fn cornell() -> &'static (Scene, Vec<Image>) {
    static CELL: OnceLock<(Scene, Vec<Image>)> = OnceLock::new();
    CELL.get_or_init(|| {
        let scene = Scene::cornell_box(24, 24);
        let reference = common::bdpt_replicates(&scene, &params(DEPTH), 16, R, 1000);
        (scene, reference)
    })
}

fn glass() -> &'static (Scene, Vec<Image>) {
    static CELL: OnceLock<(Scene, Vec<Image>)> = OnceLock::new();
    CELL.get_or_init(|| {
        let scene = scene_file("cornell-glass.gltf", 24);
        let reference = common::bdpt_replicates(&scene, &params(DEPTH), 16, R, 1000);
        (scene, reference)
    })
}

/// `R` Sobol PT renders through the session (seeds `seed0..`), `spp` samples per pixel.
fn pt_sobol(scene: &Scene, spp: u32, max_depth: u32, seed0: u64) -> Vec<Image> {
    (0..R as u64)
        .map(|r| {
            let settings = RenderSettings {
                method: PtSettings {
                    sampler: SamplerKind::Sobol,
                    ..PtSettings::default()
                }
                .into(),
                width: scene.camera().width(),
                height: scene.camera().height(),
                budget: Budget::SamplesPerPixel(spp),
                seed: seed0 + r,
                max_depth,
                ..RenderSettings::default()
            };
            let out = render(scene, &settings, &NoProgress, &AtomicBool::new(false)).unwrap();
            assert_eq!(out.dropped_nonfinite, 0);
            out.image
        })
        .collect()
}

/// `R` Sobol BDPT renders (seeds `seed0..`), `spp` samples per pixel.
fn bdpt_sobol(scene: &Scene, spp: u32, seed0: u64) -> Vec<Image> {
    (0..R as u64)
        .map(|r| {
            let out = render_bdpt_sampled(
                scene,
                &params(DEPTH),
                SamplerKind::Sobol,
                Some(spp),
                None,
                seed0 + r,
                false,
                &NoProgress,
                &AtomicBool::new(false),
            );
            assert_eq!(out.dropped, 0);
            out.image
        })
        .collect()
}

#[test]
fn sobol_pt_and_bdpt_match_bdpt_on_the_cornell_box() {
    let (scene, reference) = cornell();
    against_reference(
        "cornell, pt sobol",
        &pt_sobol(scene, 16, DEPTH, 21),
        reference,
        BLOCKS,
        critical(),
    );
    against_reference(
        "cornell, bdpt sobol",
        &bdpt_sobol(scene, 8, 31),
        reference,
        BLOCKS,
        critical(),
    );
}

#[test]
fn sobol_pt_and_bdpt_match_bdpt_on_the_glass_cornell_box() {
    let (scene, reference) = glass();
    against_reference(
        "glass, pt sobol",
        &pt_sobol(scene, 32, DEPTH, 41),
        reference,
        BLOCKS,
        critical(),
    );
    against_reference(
        "glass, bdpt sobol",
        &bdpt_sobol(scene, 8, 51),
        reference,
        BLOCKS,
        critical(),
    );
}

/// Negative control: Sobol PT one bounce short of the reference's depth misses the light of
/// the longest paths, and the same statistics detect it.
#[test]
fn negative_control_a_render_one_bounce_short_fails() {
    let (scene, reference) = cornell();
    let short = pt_sobol(scene, 16, DEPTH - 1, 21);
    let (m, s) = mean_se(&short.iter().map(Image::mean_luminance).collect::<Vec<_>>());
    let (mr, sr) = mean_se(
        &reference
            .iter()
            .map(Image::mean_luminance)
            .collect::<Vec<_>>(),
    );
    let t_mean = ((m - mr) / s.hypot(sr)).abs();
    let t_blocks = block_t(&short, reference, BLOCKS)
        .iter()
        .map(|b| b[0].abs())
        .fold(0.0, f64::max);
    eprintln!(
        "pt sobol, depth {}: |t| mean {t_mean:.2}, blocks {t_blocks:.2}",
        DEPTH - 1
    );
    assert!(
        t_mean.max(t_blocks) > critical(),
        "a render one bounce short passed"
    );
}

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn same_seed_one_and_two_threads_are_bit_identical() {
    let scene = scene_file("cornell-glass.gltf", 40);
    for integrator in [IntegratorKind::Pt, IntegratorKind::Bdpt] {
        let run = |threads, seed| {
            let settings = RenderSettings {
                method: integrator.settings(),
                width: 40,
                height: 24,
                budget: Budget::SamplesPerPixel(3),
                threads,
                seed,
                max_depth: 5,
            };
            assert!(
                matches!(
                    settings.method,
                    MethodSettings::Pt(PtSettings {
                        sampler: SamplerKind::Sobol,
                        ..
                    }) | MethodSettings::Bdpt(BdptSettings {
                        sampler: SamplerKind::Sobol,
                        ..
                    })
                ),
                "Sobol is the default"
            );
            bits(
                &render(&scene, &settings, &NoProgress, &AtomicBool::new(false))
                    .unwrap()
                    .image,
            )
        };
        let one = run(1, 5);
        assert!(one == run(2, 5), "{integrator:?}: 1 and 2 threads differ");
        // Negative control: another seed changes the bits.
        assert!(one != run(2, 6), "{integrator:?}: the seed changed nothing");
    }
}

/// PSSMLT takes the sampler for its direct-lighting pass: the setting reaches the pass (the
/// two samplers give different images, the default is Sobol's).
#[test]
fn pssmlt_draws_its_direct_pass_from_the_sampler() {
    let scene = Scene::cornell_box(8, 8);
    let image = |sampler| {
        let settings = RenderSettings {
            method: match sampler {
                Some(sampler) => PssmltSettings {
                    sampler,
                    ..PssmltSettings::default()
                }
                .into(),
                None => IntegratorKind::Pssmlt.settings(),
            },
            width: 8,
            height: 8,
            budget: Budget::SamplesPerPixel(8),
            threads: 2,
            seed: 5,
            ..RenderSettings::default()
        };
        render(&scene, &settings, &NoProgress, &AtomicBool::new(false))
            .expect("pssmlt takes --sampler")
            .image
    };
    let (default, sobol, independent) = (
        image(None),
        image(Some(SamplerKind::Sobol)),
        image(Some(SamplerKind::Independent)),
    );
    assert!(
        default.pixels == sobol.pixels,
        "the default is not the Sobol pass"
    );
    assert!(
        sobol.pixels != independent.pixels,
        "the sampler does not reach the direct pass"
    );
}
