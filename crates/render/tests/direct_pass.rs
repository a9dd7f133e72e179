//! PSSMLT with a separate direct-lighting pass (`render::mlt::direct`): BDPT at depth <= K
//! plus chains restricted to depths > K converges to the BDPT reference of the full image
//! (Cornell box, depth 5), and two negative controls fail the same comparison: the restricted
//! chains without the pass (the pass's light missing) and the pass added to unrestricted
//! chains (counted twice). Checked for K = 1 with independent numbers and for the default
//! K = 2 with the Owen-scrambled Sobol points (PSSMLT's default sampler for the pass), and for
//! the whole default through `session::render`: the balanced pass, whose share of the budget
//! a pilot picks from its own samples (the pass and the chains stay unbiased for any share
//! that does not depend on their own numbers). The same pass before MMLT-based chains
//! (`mmlt` with the pass on, `mala` by default) and before PSSMLT over the path tracer
//! converges too, and MMLT chains restricted to the deeper depths without it fail.
//!
//! Statistics as in `mlt_convergence.rs` (its module comment): `R` independent replicates per
//! estimate against `K` independent BDPT references, Welch t on the image mean and on
//! `BLOCKS x BLOCKS` block means, critical value Bonferroni over this file's `N_COMPARISONS`
//! at family-wise `ALPHA_FAMILY`, conservative `min(R, K) - 1` degrees of freedom.

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::bdpt_replicates;
use common::stats::{against_reference, assert_finite_non_negative, mean_se, t_critical};
use mcmc_core::Mh;
use pss::{KelemenParams, PssmltProposal, SmallMutation, SmallStep};
use render::bdpt::BdptParams;
use render::image::Image;
use render::methods::direct_pass::DirectSettings;
use render::methods::{DrmltSettings, MethodSettings, MmltSettings};
use render::mlt::direct::{add_into, render_direct, DirectPass, DIRECT_DEPTH_DEFAULT};
use render::mlt::dr::{DrBase, DrVariant};
use render::mlt::{
    LargeStepMode, MltBudget, MltDriver, MltEstimator, MltSettings, MmltTarget, PssmltTarget,
    PATH_STREAMS,
};
use render::sampler::SamplerKind;
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

const ALPHA_FAMILY: f64 = 0.001;
const R: usize = 16;
const K: usize = 16;
const BLOCKS: usize = 4;
/// The positive cases, one per sampler and the session default, the session defaults of
/// the chain methods that share the pass (MMLT with its pass on, `mala`, `pssmlt-pt`), and
/// delayed rejection (orbital over the path tracer without and with the pass, orbital on
/// MMLT and the authors' Tierney-Mira over the path tracer with the pass, orbital on MMLT
/// with the strategy fixed along the chain): image mean and blocks. (The negative controls are expected to exceed the same critical value;
/// they are not null-hypothesis comparisons.)
const N_COMPARISONS: usize = 11 * (1 + BLOCKS * BLOCKS);
const SIZE: u32 = 16;
const DEPTH: u32 = 5;
const PASS: DirectPass = DirectPass::Fixed(16);

fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32)
}

fn cornell() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::cornell_box(SIZE, SIZE))
}

fn params() -> BdptParams {
    BdptParams {
        max_depth: DEPTH,
        ..BdptParams::default()
    }
}

/// `K` independent BDPT renders of the full image, 256 spp.
fn reference() -> &'static [Image] {
    static REFERENCE: OnceLock<Vec<Image>> = OnceLock::new();
    REFERENCE.get_or_init(|| bdpt_replicates(cornell(), &params(), 256, K, 71_000))
}

/// One replicate: PSSMLT (large-step MIS on, as the CLI default) whose chains sample depths
/// `>= chain_min_depth`, plus, if `pass` is `Some((sampler, depth))`, the direct pass of that
/// depth drawn from `sampler`.
fn replicate(seed: u64, chain_min_depth: u32, pass: Option<(SamplerKind, u32)>) -> Image {
    let settings = MltSettings {
        width: SIZE as usize,
        height: SIZE as usize,
        chains: 64,
        bootstrap_samples: 20_000,
        budget: MltBudget::MutationsPerPixel(64.0),
        large_step: LargeStepMode::Fixed(0.3),
        seed,
        streams: PATH_STREAMS,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    };
    let kernel = |p: f64| {
        let small = SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
        Mh::new(PssmltProposal::new(small, p).unwrap())
    };
    let cancel = AtomicBool::new(false);
    let target = PssmltTarget::new(cornell(), params(), SIZE, SIZE).with_min_depth(chain_min_depth);
    let estimator = MltEstimator {
        large_step_mis: true,
        ..MltEstimator::plain()
    };
    let out = MltDriver::new(&[target], &settings)
        .estimator(estimator)
        .run(kernel, &NoProgress, &cancel);
    assert!(out.message.is_none(), "{:?}", out.message);
    let mut image = out.image;
    if let Some((sampler, depth)) = pass {
        let budget = PASS.budget(Some(64.0), None);
        assert_eq!(budget, (Some(16), None));
        let pass = render_direct(
            cornell(),
            &params(),
            depth,
            sampler,
            budget,
            seed,
            render::shard::Shard::WHOLE,
            &NoProgress,
            &cancel,
        );
        assert_eq!(pass.spp, 16);
        add_into(&mut image, &pass.image);
    }
    assert_finite_non_negative(&image, "direct pass replicate");
    image
}

fn replicates(seed0: u64, chain_min_depth: u32, pass: Option<(SamplerKind, u32)>) -> Vec<Image> {
    (0..R as u64)
        .map(|r| replicate(seed0 + r, chain_min_depth, pass))
        .collect()
}

/// The image-mean t statistic against the reference.
fn mean_t(images: &[Image]) -> f64 {
    let (mm, sm) = mean_se(&images.iter().map(Image::mean_luminance).collect::<Vec<_>>());
    let (mr, sr) = mean_se(
        &reference()
            .iter()
            .map(Image::mean_luminance)
            .collect::<Vec<_>>(),
    );
    (mm - mr) / sm.hypot(sr)
}

#[test]
fn pssmlt_with_a_direct_pass_converges_to_bdpt() {
    assert_eq!(DIRECT_DEPTH_DEFAULT, 2);
    for (sampler, depth, seed0) in [
        (SamplerKind::Independent, 1, 40_000),
        (SamplerKind::Sobol, DIRECT_DEPTH_DEFAULT, 43_000),
    ] {
        assert!(PASS.applies_to(DEPTH, depth));
        let min_depth = PASS.chain_min_depth(DEPTH, depth);
        assert_eq!(min_depth, depth + 1);
        let images = replicates(seed0, min_depth, Some((sampler, depth)));
        against_reference(
            &format!("cornell PSSMLT + direct pass of depth {depth} ({sampler})"),
            &images,
            reference(),
            BLOCKS,
            critical(),
        );
    }
}

#[test]
fn negative_controls_missing_or_doubled_direct_light_fail() {
    let crit = critical();
    // The restricted chains alone: the pass's depths are missing.
    let missing = mean_t(&replicates(
        41_000,
        PASS.chain_min_depth(DEPTH, DIRECT_DEPTH_DEFAULT),
        None,
    ));
    // The pass added to chains over every depth: its depths counted twice.
    let doubled = mean_t(&replicates(
        42_000,
        0,
        Some((SamplerKind::Sobol, DIRECT_DEPTH_DEFAULT)),
    ));
    eprintln!(
        "negative controls: t missing {missing:.1}, t doubled {doubled:.1}, critical {crit:.2}"
    );
    assert!(
        missing < -crit,
        "missing direct light not detected: t {missing}"
    );
    assert!(
        doubled > crit,
        "doubled direct light not detected: t {doubled}"
    );
}

/// PSSMLT as the renderer runs it by default (`session::render`: the balanced direct pass of
/// depth 2 with its pilot, large-step MIS, raster mutation) converges to BDPT.
#[test]
fn the_default_balanced_pass_converges_to_bdpt() {
    let images = session_replicates(
        IntegratorKind::Pssmlt.settings(),
        44_000,
        "balanced against the chains",
    );
    against_reference(
        "cornell PSSMLT, session default (balanced direct pass)",
        &images,
        reference(),
        BLOCKS,
        critical(),
    );
}

/// `R` replicates of `method` as the session renders it, at 64 mutations per pixel; every
/// replicate's notes must report the direct pass and include `note`.
fn session_replicates(method: MethodSettings, seed0: u64, note: &str) -> Vec<Image> {
    session_replicates_with(method, seed0, Some(note))
}

/// [`session_replicates`], with the direct pass's notes checked only if `note` is given.
fn session_replicates_with(method: MethodSettings, seed0: u64, note: Option<&str>) -> Vec<Image> {
    let cancel = AtomicBool::new(false);
    (0..R as u64)
        .map(|r| {
            let settings = RenderSettings {
                width: SIZE,
                height: SIZE,
                budget: Budget::SamplesPerPixel(64),
                threads: 2,
                seed: seed0 + r,
                max_depth: DEPTH,
                method: method.with_chains(64, 20_000),
            };
            let out = render(cornell(), &settings, &NoProgress, &cancel).unwrap();
            if let Some(note) = note {
                for needle in ["direct-lighting pass: depths 0-", note] {
                    assert!(
                        out.notes.iter().any(|n| n.contains(needle)),
                        "{needle}: {:?}",
                        out.notes
                    );
                }
                assert!(out.mcmc.as_ref().unwrap().direct_pass.is_some());
            }
            assert_finite_non_negative(&out.image, "session replicate");
            out.image
        })
        .collect()
}

/// The pass shared by the MMLT-based integrators: MMLT with the balanced pass of depth 1,
/// Langevin MLT's default (the same pass) and PSSMLT over the path tracer (its default pass of
/// depth 2) converge to BDPT.
#[test]
fn the_pass_before_mmlt_mala_and_pssmlt_pt_converges_to_bdpt() {
    let mmlt = MethodSettings::from(MmltSettings {
        direct: DirectSettings::balanced(1),
        ..MmltSettings::default()
    });
    let cases = [
        ("mmlt", mmlt, 46_000),
        ("mala", IntegratorKind::Mala.settings(), 47_000),
        ("pssmlt-pt", IntegratorKind::PssmltPt.settings(), 48_000),
    ];
    for (name, method, seed0) in cases {
        let images = session_replicates(method, seed0, "direct-lighting pass");
        against_reference(
            &format!("cornell {name} with the direct pass"),
            &images,
            reference(),
            BLOCKS,
            critical(),
        );
    }
}

/// Delayed rejection over the path tracer (`--dr-on pssmlt-pt`) without and with the direct
/// pass, on MMLT with the pass (its chains then start at depth 2: the kernels' strategy
/// choice reads the chain's true depth), and the authors' Tierney-Mira over the path tracer
/// with the pass, converge to BDPT.
#[test]
fn drmlt_over_the_path_tracer_and_with_the_pass_converges_to_bdpt() {
    let dr = |variant, on, direct| {
        MethodSettings::from(DrmltSettings {
            direct,
            ..DrmltSettings::rioux_lavoie2020_with(variant, on)
        })
    };
    let pass = DirectSettings::balanced(1);
    let cases = [
        (
            "drmlt orbital on pssmlt-pt",
            dr(DrVariant::Orbital, DrBase::PssmltPt, DirectSettings::OFF),
            50_000,
            None,
        ),
        (
            "drmlt orbital on pssmlt-pt, direct pass",
            dr(DrVariant::Orbital, DrBase::PssmltPt, pass),
            51_000,
            Some("delayed rejection"),
        ),
        (
            "drmlt orbital on mmlt, direct pass",
            dr(DrVariant::Orbital, DrBase::Mmlt, pass),
            52_000,
            Some("delayed rejection"),
        ),
        (
            "drmlt tierney-mira on pssmlt-pt, direct pass",
            dr(DrVariant::TierneyMira, DrBase::PssmltPt, pass),
            53_000,
            Some("delayed rejection"),
        ),
    ];
    for (name, method, seed0, note) in cases {
        let images = session_replicates_with(method, seed0, note);
        against_reference(name, &images, reference(), BLOCKS, critical());
    }
}

/// Delayed rejection on MMLT with the strategy fixed along the chain in both stages (the
/// paper's chain, `DrmltSettings::fixed_strategy`) converges to BDPT.
#[test]
fn drmlt_with_the_strategy_fixed_along_the_chain_converges_to_bdpt() {
    let method = MethodSettings::from(DrmltSettings {
        fixed_strategy: true,
        ..DrmltSettings::rioux_lavoie2020_with(DrVariant::Orbital, DrBase::Mmlt)
    });
    let images = session_replicates_with(method, 54_000, None);
    against_reference(
        "drmlt orbital on mmlt, strategy fixed along the chain",
        &images,
        reference(),
        BLOCKS,
        critical(),
    );
}

/// Negative control for the MMLT split: chains over depths 2..=5 only
/// ([`MmltTarget::depths_from`]) without the pass miss the direct light.
#[test]
fn mmlt_chains_without_the_pass_miss_the_direct_light() {
    let cancel = AtomicBool::new(false);
    let targets = MmltTarget::depths_from(cornell(), params(), SIZE, SIZE, 2);
    assert_eq!(targets.first().map(MmltTarget::depth), Some(2));
    let images: Vec<Image> = (0..R as u64)
        .map(|r| {
            let settings = MltSettings {
                width: SIZE as usize,
                height: SIZE as usize,
                chains: 64,
                bootstrap_samples: 20_000,
                budget: MltBudget::MutationsPerPixel(64.0),
                large_step: LargeStepMode::Fixed(0.3),
                seed: 49_000 + r,
                streams: PATH_STREAMS,
                stage_map: false,
                shard: render::shard::Shard::WHOLE,
                normalization: Default::default(),
            };
            let kernel = |p: f64| {
                let small =
                    SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
                Mh::new(PssmltProposal::new(small, p).unwrap())
            };
            MltDriver::new(&targets, &settings)
                .first_depth(2)
                .run(kernel, &NoProgress, &cancel)
                .image
        })
        .collect();
    let t = mean_t(&images);
    assert!(t < -critical(), "missing direct light not detected: t {t}");
}
