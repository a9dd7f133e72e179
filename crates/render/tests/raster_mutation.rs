//! The raster mutation (`pss::RasterStep`, `--raster-mutation`) on a real scene: PSSMLT and
//! MMLT with raster steps converge to the Cornell box's BDPT reference, and a render with
//! raster steps is bit-identical for 1, 2 and 3 threads.
//!
//! # Statistics
//! As `mlt_convergence.rs` ("Cornell box against a BDPT reference"): `R` independent MCMC
//! replicates against `K` independent BDPT renders; Welch t of the image mean and of
//! `BLOCKS x BLOCKS` block means with the conservative `min(R, K) - 1` degrees of freedom,
//! Bonferroni over the [`N_COMPARISONS`] comparisons for a family-wise 0.001; the relMSE of the
//! replicate average below 3x its expectation under no bias (`common::stats::against_reference`).
//! The raster probability is 0.5 (twice the `on` default) so that raster steps are a large
//! share of the mutations.

mod common;

use std::sync::atomic::AtomicBool;

use common::stats::{against_reference, assert_finite_non_negative, t_critical};
use mcmc_core::Mh;
use pss::{KelemenParams, PssmltProposal, RasterParams, RasterStep, SmallMutation, SmallStep};
use render::bdpt::{render_bdpt, BdptParams};
use render::image::Image;
use render::methods::{MethodSettings, MmltSettings, PssmltSettings};
use render::mlt::{
    LargeStepMode, MltBudget, MltDriver, MltSettings, MmltTarget, PssmltTarget, PATH_STREAMS,
};
use render::scene::Scene;
use render::session::{render, IntegratorKind, NoProgress, RenderSettings};

/// Family-wise false-alarm probability of the comparisons in this file.
const ALPHA_FAMILY: f64 = 0.001;
/// MCMC replicates per estimate.
const R: usize = 16;
/// BDPT reference replicates.
const K: usize = 16;
/// Blocks per side of the regional test.
const BLOCKS: usize = 4;
/// Image mean and blocks, for PSSMLT and MMLT.
const N_COMPARISONS: usize = 2 * (1 + BLOCKS * BLOCKS);
const SIDE: u32 = 16;
const DEPTH: u32 = 5;
/// Fraction of the small steps that are raster steps.
const RASTER_PROBABILITY: f64 = 0.5;

fn kernel(p: f64) -> Mh<PssmltProposal> {
    let small = SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap();
    let raster = RasterStep::for_image(&RasterParams::with_probability(1.0), SIDE, SIDE, small);
    Mh::new(
        PssmltProposal::new(SmallStep::new(small), p)
            .unwrap()
            .with_raster(raster, RASTER_PROBABILITY)
            .unwrap(),
    )
}

fn mlt_settings(seed: u64, mutations_per_pixel: f64) -> MltSettings {
    MltSettings {
        width: SIDE as usize,
        height: SIDE as usize,
        chains: 256,
        bootstrap_samples: 20_000,
        budget: MltBudget::MutationsPerPixel(mutations_per_pixel),
        large_step: LargeStepMode::Fixed(0.3),
        seed,
        streams: PATH_STREAMS,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    }
}

fn params() -> BdptParams {
    BdptParams {
        max_depth: DEPTH,
        ..BdptParams::default()
    }
}

fn bdpt_reference(scene: &Scene) -> Vec<Image> {
    (0..K as u64)
        .map(|k| {
            let out = render_bdpt(
                scene,
                &params(),
                Some(256),
                None,
                90_000 + k,
                false,
                &NoProgress,
                &AtomicBool::new(false),
            );
            assert_finite_non_negative(&out.image, "BDPT reference");
            out.image
        })
        .collect()
}

/// PSSMLT (256 mutations per pixel) and MMLT (512: one strategy per mutation) with raster
/// steps: image mean, blocks and relMSE against BDPT.
#[test]
fn pssmlt_and_mmlt_with_raster_steps_match_bdpt_on_the_cornell_box() {
    let scene = Scene::cornell_box(SIDE, SIDE);
    let reference = bdpt_reference(&scene);
    let crit = t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32);
    let cancel = AtomicBool::new(false);
    for (what, mpp) in [("PSSMLT + raster", 256.0), ("MMLT + raster", 512.0)] {
        let images: Vec<Image> = (0..R as u64)
            .map(|r| {
                let s = mlt_settings(31_000 + r, mpp);
                let out =
                    if what.starts_with("PSSMLT") {
                        MltDriver::new(&[PssmltTarget::new(&scene, params(), SIDE, SIDE)], &s).run(
                            kernel,
                            &NoProgress,
                            &cancel,
                        )
                    } else {
                        MltDriver::new(&MmltTarget::all_depths(&scene, params(), SIDE, SIDE), &s)
                            .run(kernel, &NoProgress, &cancel)
                    };
                assert!(out.message.is_none(), "{what}: {:?}", out.message);
                assert!(out.b.is_finite() && out.b > 0.0);
                assert_finite_non_negative(&out.image, what);
                // Raster steps are component 2; they must be taken and sometimes accepted.
                let raster_rate = out.stats.component_acceptance_rate(2);
                assert!(
                    raster_rate > 0.0 && raster_rate < 1.0,
                    "{what}: raster acceptance {raster_rate}"
                );
                out.image
            })
            .collect();
        against_reference(
            &format!("cornell {what}"),
            &images,
            &reference,
            BLOCKS,
            crit,
        );
    }
}

fn session_settings(integrator: IntegratorKind, threads: usize, raster: f64) -> RenderSettings {
    RenderSettings {
        width: 24,
        height: 16,
        budget: render::session::Budget::SamplesPerPixel(3),
        threads,
        seed: 17,
        max_depth: 6,
        method: match integrator {
            IntegratorKind::Pssmlt => MethodSettings::from(PssmltSettings {
                raster: RasterParams::with_probability(raster),
                ..PssmltSettings::default()
            }),
            _ => MmltSettings {
                raster: RasterParams::with_probability(raster),
                ..MmltSettings::default()
            }
            .into(),
        }
        .with_chains(16, 5_000),
    }
}

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

/// `--raster-mutation 0.5` through the session: 1, 2 and 3 threads give the same image, and
/// the option changes the image (it is used).
#[test]
fn raster_mutation_is_bit_identical_across_threads() {
    let scene = Scene::cornell_box(24, 16);
    let run = |s: &RenderSettings| {
        let out = render(&scene, s, &NoProgress, &AtomicBool::new(false)).unwrap();
        assert!(!out.cancelled);
        out.image
    };
    for integrator in [IntegratorKind::Pssmlt, IntegratorKind::Mmlt] {
        let reference = run(&session_settings(integrator, 1, 0.5));
        assert!(reference.mean_luminance() > 0.0);
        for threads in [2, 3] {
            assert!(
                bits(&run(&session_settings(integrator, threads, 0.5))) == bits(&reference),
                "{integrator:?} with raster steps: {threads} threads differ from 1"
            );
        }
        let off = run(&session_settings(integrator, 1, 0.0));
        assert!(
            bits(&off) != bits(&reference),
            "{integrator:?}: the raster option changed nothing"
        );
    }
}
