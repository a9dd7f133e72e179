//! PSSMLT and MMLT with Kelemen et al. 2002's large-step MIS estimator
//! (`MltEstimator::large_step_mis`): convergence to the closed form of the analytic enclosure
//! and to a BDPT reference on the Cornell box (fixed and automatic large-step probability),
//! and bit-identical images for 1 and 2 threads.
//!
//! # Statistics
//! As `mlt_convergence.rs` (whose module docs derive them): `R` independent replicates per
//! estimate, Welch t of the image mean and of `BLOCKS x BLOCKS` block means against `K`
//! independent BDPT renders (`common::stats::against_reference`), and the relMSE of the
//! replicate average below 3x its expectation under no bias. The `N_COMPARISONS` comparisons
//! share a family-wise `ALPHA_FAMILY = 0.001` (Bonferroni). With the MIS estimator the
//! enclosure's image mean is no longer `b` itself (the weights differ between splats), so the
//! enclosure test checks the weights' normalisation, not only `b`.
//!
//! Unbiasedness of the weights themselves is checked in mcmc-core
//! (`crates/mcmc-core/tests/large_step_mis.rs`: the splat-weight check and its negative
//! controls).

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::stats::{against_reference, assert_finite_non_negative, mean_se, t_critical};
use common::{analytic_enclosure, bdpt_replicates, enclosure_radiance};
use mcmc_core::Mh;
use pss::{KelemenParams, PssmltProposal, SmallMutation, SmallStep};
use render::bdpt::BdptParams;
use render::image::Image;
use render::mlt::{
    LargeStepMode, MltBudget, MltDriver, MltEstimator, MltOutput, MltSettings, MmltTarget,
    PssmltTarget, PATH_STREAMS,
};
use render::scene::Scene;
use render::session::NoProgress;

/// Family-wise false-alarm probability of all the comparisons in this file.
const ALPHA_FAMILY: f64 = 0.001;
/// MCMC replicates per estimate.
const R: usize = 16;
/// BDPT reference replicates.
const K: usize = 16;
/// The Cornell box is split into `BLOCKS x BLOCKS` blocks.
const BLOCKS: usize = 4;
/// Null-hypothesis comparisons: the enclosure's image mean (PSSMLT, MMLT) and the Cornell
/// box's image mean and blocks (PSSMLT fixed p, MMLT fixed p, PSSMLT automatic p).
const N_COMPARISONS: usize = 2 + 3 * (1 + BLOCKS * BLOCKS);

fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Method {
    Pssmlt,
    Mmlt,
}

fn kernel(p: f64) -> Mh<PssmltProposal> {
    let small = SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
    Mh::new(PssmltProposal::new(small, p).unwrap())
}

fn settings(scene: &Scene, seed: u64, mpp: f64, large_step: LargeStepMode) -> MltSettings {
    MltSettings {
        width: scene.camera().width() as usize,
        height: scene.camera().height() as usize,
        chains: 256,
        bootstrap_samples: 20_000,
        budget: MltBudget::MutationsPerPixel(mpp),
        large_step,
        seed,
        streams: PATH_STREAMS,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    }
}

const MIS: MltEstimator = MltEstimator {
    large_step_mis: true,
    ..MltEstimator::plain()
};

fn render(method: Method, scene: &Scene, params: BdptParams, s: &MltSettings) -> MltOutput {
    let (w, h) = (s.width as u32, s.height as u32);
    let cancel = AtomicBool::new(false);
    match method {
        Method::Pssmlt => MltDriver::new(&[PssmltTarget::new(scene, params, w, h)], s)
            .estimator(MIS)
            .run(kernel, &NoProgress, &cancel),
        Method::Mmlt => MltDriver::new(&MmltTarget::all_depths(scene, params, w, h), s)
            .estimator(MIS)
            .run(kernel, &NoProgress, &cancel),
    }
}

fn replicates(
    method: Method,
    scene: &Scene,
    params: BdptParams,
    seed0: u64,
    mpp: f64,
    large_step: LargeStepMode,
) -> Vec<Image> {
    (0..R as u64)
        .map(|r| {
            let s = settings(scene, seed0 + r, mpp, large_step);
            let out = render(method, scene, params, &s);
            assert!(out.message.is_none(), "{method:?}: {:?}", out.message);
            assert!(!out.cancelled && out.dropped == 0);
            assert_finite_non_negative(&out.image, &format!("{method:?} replicate {r}"));
            out.image
        })
        .collect()
}

/// The analytic enclosure (radiance `enclosure_radiance(3)` everywhere): the image mean of
/// `R` replicates against the closed form.
fn enclosure_case(method: Method, seed0: u64) {
    let scene = analytic_enclosure(16, 16);
    let params = BdptParams {
        max_depth: 3,
        ..BdptParams::default()
    };
    let exact = enclosure_radiance(3);
    let images = replicates(
        method,
        &scene,
        params,
        seed0,
        32.0,
        LargeStepMode::Fixed(0.3),
    );
    let (m, se) = mean_se(&images.iter().map(|im| im.mean()[0]).collect::<Vec<_>>());
    let (t, crit) = ((m - exact) / se, critical());
    eprintln!("enclosure {method:?} + MIS: mean {m:.6} exact {exact:.6} se {se:.2e} t {t:.2}");
    assert!(
        (m - exact).abs() < crit * se + 1e-6 * exact,
        "{method:?}: image mean {m} vs exact {exact}, se {se}, t {t}, critical {crit}"
    );
}

#[test]
fn pssmlt_and_mmlt_with_mis_match_the_analytic_enclosure() {
    enclosure_case(Method::Pssmlt, 11_000);
    enclosure_case(Method::Mmlt, 12_000);
}

const CORNELL: u32 = 16;
const CORNELL_DEPTH: u32 = 5;

fn cornell() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::cornell_box(CORNELL, CORNELL))
}

fn params() -> BdptParams {
    BdptParams {
        max_depth: CORNELL_DEPTH,
        ..BdptParams::default()
    }
}

/// `K` independent BDPT renders of the Cornell box at depth 5, 256 spp.
fn reference() -> &'static [Image] {
    static REFERENCE: OnceLock<Vec<Image>> = OnceLock::new();
    REFERENCE.get_or_init(|| bdpt_replicates(cornell(), &params(), 256, K, 93_000))
}

fn cornell_case(method: Method, seed0: u64, mpp: f64, large_step: LargeStepMode) {
    let images = replicates(method, cornell(), params(), seed0, mpp, large_step);
    against_reference(
        &format!("cornell {method:?} + MIS, {large_step:?}"),
        &images,
        reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn pssmlt_with_mis_converges_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Pssmlt, 13_000, 256.0, LargeStepMode::Fixed(0.3));
}

#[test]
fn mmlt_with_mis_converges_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Mmlt, 14_000, 512.0, LargeStepMode::Fixed(0.3));
}

/// Automatic large-step control: `p` is 0.5 during the estimation phase and the pooled
/// estimate afterwards; every step is weighted with its own `p`.
#[test]
fn pssmlt_with_mis_and_automatic_large_steps_converges_on_the_cornell_box() {
    cornell_case(
        Method::Pssmlt,
        15_000,
        256.0,
        LargeStepMode::Auto {
            initial: 0.5,
            estimation_steps: 100,
        },
    );
}

/// The same seed gives a bit-identical image with 1 and 2 threads, with the option on, under
/// fixed and automatic large-step probability; the option changes the image.
#[test]
fn with_mis_one_and_two_threads_are_bit_identical() {
    let scene = Scene::cornell_box(24, 16);
    let bits =
        |im: &Image| -> Vec<[u32; 3]> { im.pixels.iter().map(|p| p.map(f32::to_bits)).collect() };
    for method in [Method::Pssmlt, Method::Mmlt] {
        for large_step in [
            LargeStepMode::Fixed(0.3),
            LargeStepMode::Auto {
                initial: 0.5,
                estimation_steps: 20,
            },
        ] {
            let s = MltSettings {
                chains: 16,
                bootstrap_samples: 5_000,
                ..settings(&scene, 5, 8.0, large_step)
            };
            let with = |threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| render(method, &scene, params(), &s))
            };
            let (a, b) = (with(1), with(2));
            assert!(a.image.mean_luminance() > 0.0);
            assert!(
                bits(&a.image) == bits(&b.image),
                "{method:?} {large_step:?}: 1 and 2 threads differ"
            );
            let plain = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap()
                .install(|| {
                    let (w, h) = (s.width as u32, s.height as u32);
                    let none = MltEstimator::default();
                    let cancel = AtomicBool::new(false);
                    match method {
                        Method::Pssmlt => {
                            MltDriver::new(&[PssmltTarget::new(&scene, params(), w, h)], &s)
                                .estimator(none)
                                .run(kernel, &NoProgress, &cancel)
                        }
                        Method::Mmlt => {
                            MltDriver::new(&MmltTarget::all_depths(&scene, params(), w, h), &s)
                                .estimator(none)
                                .run(kernel, &NoProgress, &cancel)
                        }
                    }
                });
            assert!(bits(&a.image) != bits(&plain.image));
        }
    }
}
