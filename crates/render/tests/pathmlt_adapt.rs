//! Regional adaptive path-space MLT (`--integrator pathmlt --adapt global|grid|quadtree`,
//! `render::mlt::pathmlt::render_adaptive`): the image is bit-identical for 1, 2 and 3
//! threads under a mutation budget for every `--adapt` mode (statistics shared in job order
//! through the render loop's round hook), and every adaptive mode (global, grid, quadtree) of
//! both perturbations converges to the BDPT reference on the Cornell box (`fixed` is
//! `pathmlt::render`, tested by `pathmlt_convergence.rs`) with `pathmlt_convergence.rs`'s
//! replicate statistics (Welch's t on the image mean and 4 x 4 blocks, Bonferroni over this
//! file's comparisons); negative control: the quadtree variant at max depth 1 fails the block
//! test.

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::stats::{against_reference, assert_finite_non_negative, block_t, rounded, t_critical};
use pathspace::PerturbationKind;
use render::bdpt::{render_bdpt, BdptParams};
use render::image::Image;
use render::methods::PathMltSettings;
use render::mlt::pathmlt::{self, PathAdapt};
use render::mlt::{LargeStepMode, MltBudget, MltSettings};
use render::scene::Scene;
use render::session::{render, Budget, NoProgress, RenderSettings};

/// Family-wise false-alarm probability of all the comparisons in this file.
const ALPHA_FAMILY: f64 = 0.001;
/// MCMC replicates per estimate.
const R: usize = 16;
/// BDPT reference replicates.
const K: usize = 16;
/// Blocks per side of the regional test.
const BLOCKS: usize = 4;
/// Image side and max depth of the Cornell box.
const SIZE: u32 = 16;
const DEPTH: u32 = 5;
/// BDPT reference samples per pixel.
const REF_SPP: u32 = 256;
/// pathmlt mutations per pixel.
const MPP: f64 = 1024.0;
/// Comparisons: image mean and blocks for lens quadtree, grid, global and multi-chain
/// quadtree, grid, global.
const N_COMPARISONS: usize = 6 * (1 + BLOCKS * BLOCKS);

fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32)
}

fn cornell() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::cornell_box(SIZE, SIZE))
}

fn cornell_reference() -> &'static [Image] {
    static REFERENCE: OnceLock<Vec<Image>> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        let params = BdptParams {
            max_depth: DEPTH,
            ..BdptParams::default()
        };
        (0..K as u64)
            .map(|k| {
                let out = render_bdpt(
                    cornell(),
                    &params,
                    Some(REF_SPP),
                    None,
                    92_000 + k,
                    false,
                    &NoProgress,
                    &AtomicBool::new(false),
                );
                assert_eq!(out.dropped, 0);
                assert_finite_non_negative(&out.image, "BDPT reference");
                out.image
            })
            .collect()
    })
}

/// `R` replicates of pathmlt with `adapt` (seeds `seed0 + r`).
fn replicates(
    kind: PerturbationKind,
    adapt: PathAdapt,
    depth: u32,
    seed0: u64,
    mutations_per_pixel: f64,
) -> Vec<Image> {
    let scene = cornell();
    (0..R as u64)
        .map(|r| {
            let s = MltSettings {
                width: SIZE as usize,
                height: SIZE as usize,
                chains: 256,
                bootstrap_samples: 20_000,
                budget: MltBudget::MutationsPerPixel(mutations_per_pixel),
                large_step: LargeStepMode::Fixed(0.0),
                seed: seed0 + r,
                streams: 1,
                stage_map: false,
                shard: render::shard::Shard::WHOLE,
                normalization: Default::default(),
            };
            let out = pathmlt::render_adaptive(
                scene,
                kind,
                adapt,
                depth,
                &s,
                &NoProgress,
                &AtomicBool::new(false),
            )
            .unwrap();
            let what = format!("{kind:?} {adapt:?} replicate {r}");
            assert!(out.message.is_none(), "{what}: {:?}", out.message);
            assert_eq!(
                out.mutations,
                (mutations_per_pixel * f64::from(SIZE * SIZE)) as u64
            );
            assert_eq!(out.non_finite, 0, "{what}");
            assert_finite_non_negative(&out.image, &what);
            if r == 0 {
                eprintln!("{what}: {:?}", out.notes);
            }
            out.image
        })
        .collect()
}

#[test]
fn quadtree_lens_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(
        PerturbationKind::Lens,
        PathAdapt::Quadtree,
        DEPTH,
        14_000,
        MPP,
    );
    against_reference(
        "cornell lens quadtree",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn grid_lens_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(PerturbationKind::Lens, PathAdapt::Grid, DEPTH, 15_000, MPP);
    against_reference(
        "cornell lens grid",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn quadtree_multichain_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(
        PerturbationKind::MultiChain,
        PathAdapt::Quadtree,
        DEPTH,
        16_000,
        MPP,
    );
    against_reference(
        "cornell multi-chain quadtree",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn global_lens_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(
        PerturbationKind::Lens,
        PathAdapt::Global,
        DEPTH,
        18_000,
        MPP,
    );
    against_reference(
        "cornell lens global",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn grid_multichain_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(
        PerturbationKind::MultiChain,
        PathAdapt::Grid,
        DEPTH,
        19_000,
        MPP,
    );
    against_reference(
        "cornell multi-chain grid",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn global_multichain_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(
        PerturbationKind::MultiChain,
        PathAdapt::Global,
        DEPTH,
        20_000,
        MPP,
    );
    against_reference(
        "cornell multi-chain global",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

/// Negative control: the quadtree variant at max depth 1 (direct lighting only) against the
/// depth-5 reference must be rejected by the block statistic with its critical value.
#[test]
fn negative_control_wrong_depth_fails_the_block_test() {
    let images = replicates(
        PerturbationKind::Lens,
        PathAdapt::Quadtree,
        1,
        17_000,
        256.0,
    );
    let crit = critical();
    let t_blocks: Vec<f64> = block_t(&images, cornell_reference(), BLOCKS)
        .iter()
        .map(|b| b[0])
        .collect();
    let worst = t_blocks.iter().map(|t| t.abs()).fold(0.0, f64::max);
    eprintln!(
        "negative control (quadtree, depth 1 vs 5): block t {:?}, max |t| {worst:.1}, critical {crit:.2}",
        rounded(&t_blocks)
    );
    assert!(
        worst > crit,
        "not detected: max |t| {worst}, critical {crit}"
    );
}

/// Every `--adapt` mode, both perturbations: 1, 2 and 3 threads give identical bytes; another
/// seed differs; an adaptive image differs from the fixed one (the scales did change).
#[test]
fn every_adapt_mode_is_bit_identical_across_threads() {
    let scene = Scene::cornell_box(16, 12);
    let with = |kind, adapt, threads, seed| RenderSettings {
        width: 16,
        height: 12,
        threads,
        seed,
        budget: Budget::SamplesPerPixel(64),
        max_depth: 4,
        method: PathMltSettings {
            chains: 16,
            bootstrap_samples: 4000,
            ..PathMltSettings::otsu2018(kind, adapt)
        }
        .into(),
    };
    let bits = |s: &RenderSettings| -> Vec<[u32; 3]> {
        render(&scene, s, &NoProgress, &AtomicBool::new(false))
            .unwrap()
            .image
            .pixels
            .iter()
            .map(|p| p.map(f32::to_bits))
            .collect()
    };
    for kind in [PerturbationKind::Lens, PerturbationKind::MultiChain] {
        let fixed = bits(&with(kind, PathAdapt::Fixed, 1, 5));
        for adapt in [
            PathAdapt::Fixed,
            PathAdapt::Global,
            PathAdapt::Grid,
            PathAdapt::Quadtree,
        ] {
            let one = bits(&with(kind, adapt, 1, 5));
            assert!(one.iter().any(|p| p[0] != 0), "{kind:?} {adapt:?}: black");
            for threads in [2, 3] {
                assert!(
                    bits(&with(kind, adapt, threads, 5)) == one,
                    "{kind:?} {adapt:?}: {threads} threads differ from 1"
                );
            }
            assert!(
                bits(&with(kind, adapt, 1, 6)) != one,
                "{kind:?} {adapt:?}: another seed gives the same image"
            );
            if adapt != PathAdapt::Fixed {
                assert!(one != fixed, "{kind:?} {adapt:?}: same image as fixed");
            }
        }
    }
}
