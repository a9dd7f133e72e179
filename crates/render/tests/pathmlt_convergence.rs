//! Path-space MLT (`render::mlt::pathmlt`) converges: to the closed form on the analytic
//! enclosure, and to the BDPT reference on the Cornell box (lens and multi-chain) and on the
//! glass Cornell box (multi-chain: specular chains), with replicate-based bounds; negative
//! controls (a wrong path depth, a bootstrap without the `1 / p` of its independent sampler)
//! fail the same statistics.
//!
//! The statistics are `mlt_convergence.rs`'s (see its module docs): `R` independent replicate
//! renders per estimate, the BDPT reference as `K` independent renders, Welch's t with
//! `min(R, K) - 1` degrees of freedom, Bonferroni over the `N_COMPARISONS` comparisons of this
//! file at family-wise `ALPHA_FAMILY`; helpers in `common::stats`.

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::stats::{
    against_reference, assert_finite_non_negative, block_t, mean_se, rounded, t_critical,
};
use common::{analytic_enclosure, enclosure_radiance};
use mcmc_core::render_loop::IndependentStates;
use mcmc_core::{Mh, NoAdaptation};
use pathspace::{Path, PerturbationKind};
use render::bdpt::{render_bdpt, BdptParams};
use render::image::Image;
use render::mlt::pathmlt::{self, IndependentPaths, PathMltTarget};
use render::mlt::{LargeStepMode, MltBudget, MltDriver, MltOutput, MltSettings};
use render::pathspace_scene::PathSpaceScene;
use render::scene::Scene;
use render::session::NoProgress;

/// Family-wise false-alarm probability of all the comparisons in this file.
const ALPHA_FAMILY: f64 = 0.001;
/// MCMC replicates per estimate.
const R: usize = 16;
/// BDPT reference replicates.
const K: usize = 16;
/// Blocks per side of the regional test.
const BLOCKS: usize = 4;
/// Max depth of the enclosure renders.
const ENCLOSURE_DEPTH: u32 = 3;
/// Image side and max depth of the Cornell boxes.
const SIZE: u32 = 16;
const DEPTH: u32 = 5;
/// BDPT reference samples per pixel.
const REF_SPP: u32 = 256;
/// pathmlt mutations per pixel on the Cornell boxes.
const MPP: f64 = 1024.0;
/// Comparisons: the enclosure's image mean (lens, multi-chain); image mean and blocks on the
/// Cornell box (lens, multi-chain) and the glass Cornell box (multi-chain).
const N_COMPARISONS: usize = 2 + 3 * (1 + BLOCKS * BLOCKS);

fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32)
}

fn settings(scene: &Scene, seed: u64, mutations_per_pixel: f64) -> MltSettings {
    MltSettings {
        width: scene.camera().width() as usize,
        height: scene.camera().height() as usize,
        chains: 256,
        bootstrap_samples: 20_000,
        budget: MltBudget::MutationsPerPixel(mutations_per_pixel),
        large_step: LargeStepMode::Fixed(0.0),
        seed,
        streams: 1,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    }
}

fn check_output(out: &MltOutput, s: &MltSettings, what: &str) {
    assert!(out.message.is_none(), "{what}: {:?}", out.message);
    assert!(!out.cancelled);
    assert_eq!(
        out.mutations,
        (s.budget_mutations() * (s.width * s.height) as f64) as u64
    );
    assert!(out.b.is_finite() && out.b > 0.0, "{what}: b = {}", out.b);
    assert_eq!(out.non_finite, 0, "{what}");
    assert_finite_non_negative(&out.image, what);
}

trait BudgetMutations {
    fn budget_mutations(&self) -> f64;
}

impl BudgetMutations for MltSettings {
    fn budget_mutations(&self) -> f64 {
        match self.budget {
            MltBudget::MutationsPerPixel(m) => m,
            MltBudget::Time(_) => unreachable!(),
        }
    }
}

/// `R` pathmlt replicates with seeds `seed0 + r`.
fn replicates(
    scene: &Scene,
    kind: PerturbationKind,
    depth: u32,
    seed0: u64,
    mutations_per_pixel: f64,
) -> Vec<Image> {
    (0..R as u64)
        .map(|r| {
            let s = settings(scene, seed0 + r, mutations_per_pixel);
            let out = pathmlt::render(scene, kind, depth, &s, &NoProgress, &AtomicBool::new(false))
                .unwrap();
            check_output(&out, &s, &format!("{kind:?} replicate {r}"));
            out.image
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// 1. The analytic enclosure.

/// The image mean of `R` replicates against the closed form `Le (1 - rho^(D+1)) / (1 - rho)`:
/// in this grey scene the image mean is the bootstrap's `b` (the mean of `f / p` over
/// independent paths) carried through the splat normalisation.
fn enclosure_means(images: &[Image]) -> (f64, f64, f64) {
    let exact = enclosure_radiance(ENCLOSURE_DEPTH);
    let means: Vec<f64> = images.iter().map(|im| im.mean()[0]).collect();
    let (m, se) = mean_se(&means);
    (m, se, exact)
}

#[test]
fn pathmlt_matches_the_analytic_enclosure() {
    let scene = analytic_enclosure(16, 16);
    let crit = critical();
    for (kind, seed0) in [
        (PerturbationKind::Lens, 1000),
        (PerturbationKind::MultiChain, 2000),
    ] {
        let images = replicates(&scene, kind, ENCLOSURE_DEPTH, seed0, 32.0);
        let (m, se, exact) = enclosure_means(&images);
        let t = (m - exact) / se;
        eprintln!(
            "enclosure {kind:?}: mean {m:.6} exact {exact:.6} se {se:.2e} ({:.3}%) t {t:.2} \
             critical {crit:.2}",
            100.0 * se / exact
        );
        assert!(
            (m - exact).abs() < crit * se + 1e-6 * exact,
            "{kind:?}: image mean {m} vs exact {exact}, se {se}, t {t}, critical {crit}"
        );
    }
}

/// The render loop's independent paths with the bootstrap weight `f` instead of `f / p` (the
/// loop's default for uniform primary-sample points): the bug of treating path space like
/// primary sample space.
struct WithoutInversePdf<'a>(
    IndependentPaths<pathspace::BidirectionalSampler<'a, PathSpaceScene<'a>>>,
);

impl IndependentStates<Path> for WithoutInversePdf<'_> {
    fn empty(&self) -> Path {
        self.0.empty()
    }
    fn independent(&self, key: u64, state: &mut Path) {
        self.0.independent(key, state);
    }
}

/// Negative control: the bootstrap without `1 / p` misses the closed form by far.
#[test]
fn negative_control_bootstrap_without_inverse_pdf_fails() {
    let scene = analytic_enclosure(16, 16);
    let view = PathSpaceScene::new(&scene).unwrap();
    let sampler = pathmlt::independent_sampler(&view, ENCLOSURE_DEPTH).unwrap();
    let mutation = pathmlt::mutation(
        &view,
        PerturbationKind::Lens,
        pathmlt::PATHMLT_SIGMA,
        ENCLOSURE_DEPTH,
    )
    .unwrap();
    let targets = [PathMltTarget::new(&view, 16, 16)];
    let states = WithoutInversePdf(IndependentPaths { sampler });
    let images: Vec<Image> = (0..R as u64)
        .map(|r| {
            let s = settings(&scene, 3000 + r, 32.0);
            let out = MltDriver::new(&targets, &s)
                .states(&states)
                .run(
                    |_| Mh::new(mutation.clone()),
                    |_| NoAdaptation,
                    &NoProgress,
                    &AtomicBool::new(false),
                )
                .0;
            check_output(&out, &s, "without 1/p");
            out.image
        })
        .collect();
    let (m, se, exact) = enclosure_means(&images);
    let t = (m - exact) / se;
    let crit = critical();
    eprintln!("negative control (bootstrap weight f, not f/p): mean {m:.6} exact {exact:.6} t {t:.1} critical {crit:.2}");
    assert!(t.abs() > crit, "not detected: t {t}, critical {crit}");
}

// ---------------------------------------------------------------------------------------------
// 2. The Cornell boxes against BDPT.

fn cornell() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::cornell_box(SIZE, SIZE))
}

fn glass() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenes/cornell-glass.gltf");
        let mut scene = Scene::load(&path).unwrap();
        scene.set_resolution(SIZE, SIZE);
        scene
    })
}

/// `K` independent BDPT renders at depth `DEPTH`.
fn bdpt_reference(scene: &Scene, seed0: u64) -> Vec<Image> {
    let params = BdptParams {
        max_depth: DEPTH,
        ..BdptParams::default()
    };
    (0..K as u64)
        .map(|k| {
            let out = render_bdpt(
                scene,
                &params,
                Some(REF_SPP),
                None,
                seed0 + k,
                false,
                &NoProgress,
                &AtomicBool::new(false),
            );
            assert_eq!(out.dropped, 0);
            assert_finite_non_negative(&out.image, "BDPT reference");
            out.image
        })
        .collect()
}

fn cornell_reference() -> &'static [Image] {
    static REFERENCE: OnceLock<Vec<Image>> = OnceLock::new();
    REFERENCE.get_or_init(|| bdpt_reference(cornell(), 90_000))
}

fn glass_reference() -> &'static [Image] {
    static REFERENCE: OnceLock<Vec<Image>> = OnceLock::new();
    REFERENCE.get_or_init(|| bdpt_reference(glass(), 91_000))
}

#[test]
fn pathmlt_lens_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(cornell(), PerturbationKind::Lens, DEPTH, 4000, MPP);
    against_reference(
        "cornell lens",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn pathmlt_multichain_converges_to_bdpt_on_the_cornell_box() {
    let images = replicates(cornell(), PerturbationKind::MultiChain, DEPTH, 5000, MPP);
    against_reference(
        "cornell multi-chain",
        &images,
        cornell_reference(),
        BLOCKS,
        critical(),
    );
}

#[test]
fn pathmlt_multichain_converges_to_bdpt_on_the_glass_cornell_box() {
    let images = replicates(glass(), PerturbationKind::MultiChain, DEPTH, 6000, MPP);
    against_reference(
        "glass cornell multi-chain",
        &images,
        glass_reference(),
        BLOCKS,
        critical(),
    );
}

/// Negative control: pathmlt at max depth 1 (direct lighting only) against the depth-5
/// reference must be rejected by the block statistic with its critical value.
#[test]
fn negative_control_wrong_depth_fails_the_block_test() {
    let images = replicates(cornell(), PerturbationKind::Lens, 1, 7000, 256.0);
    let crit = critical();
    let t_blocks: Vec<f64> = block_t(&images, cornell_reference(), BLOCKS)
        .iter()
        .map(|b| b[0])
        .collect();
    let worst = t_blocks.iter().map(|t| t.abs()).fold(0.0, f64::max);
    eprintln!(
        "negative control (depth 1 vs 5): block t {:?}, max |t| {worst:.1}, critical {crit:.2}",
        rounded(&t_blocks)
    );
    assert!(
        worst > crit,
        "not detected: max |t| {worst}, critical {crit}"
    );
}
