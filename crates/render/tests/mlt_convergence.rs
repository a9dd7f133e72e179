//! PSSMLT and MMLT on real scenes: convergence to a closed form (the analytic enclosure) and to
//! a BDPT reference (the Cornell box), a negative control showing the tests can fail, scenes
//! without a light-carrying path, and bit-identical output with 1 and 2 threads.
//!
//! # Statistics
//!
//! MCMC pixels are correlated (a chain splats into neighbouring pixels for many mutations, and
//! all pixels share the bootstrap's `b`), so no standard error is computed from the pixels of
//! one image. Every MCMC quantity is instead rendered as `R` independent replicates (different
//! master seeds, hence independent bootstraps, chain starts and chains). For a statistic `X` of
//! one image (the image mean, a block mean) the replicate values `X_1..X_R` are i.i.d.; each is
//! a sum over tens of thousands of mutations and bootstrap samples, so close to normal. With
//! `m` their mean and `s^2` their sample variance, `T = (m - mu) / (s / sqrt(R))` follows
//! Student's t with `R - 1` degrees of freedom when `E[X] = mu`.
//!
//! `E[X]` is the true value for any run length, not only in the limit: chains start from
//! bootstrap samples resampled in proportion to `f`, so for any `g`,
//! `E[b g(X_0)] = E[(1/n) sum_i f(u_i) g(u_i)] = int f g`, and a Metropolis-Hastings step `P`
//! leaves `f` invariant, so `E[b g(X_t)] = E[b (P^t g)(X_0)] = int f P^t g = int f g`. The
//! image is `b` times such averages.
//!
//! Against the BDPT reference, itself `K` independent renders, the statistic is
//! `T = (m_mlt - m_ref) / sqrt(s_mlt^2 / R + s_ref^2 / K)`; its Welch-Satterthwaite degrees of
//! freedom are at least `min(R, K) - 1`, and t quantiles decrease with the degrees of freedom,
//! so `min(R, K) - 1` is conservative. (The reference's standard error is *not* taken from the
//! spread of its pixels, as `common::mean_and_se` does for the uniform enclosure: over the
//! pixels of a structured image that spread is mostly the image itself, not noise.)
//!
//! Family-wise error: the `N_COMPARISONS` null-hypothesis comparisons of this file share
//! `ALPHA_FAMILY = 0.001` (Bonferroni): each uses the two-sided critical value
//! `t_df(1 - alpha / 2)` with `alpha = ALPHA_FAMILY / N_COMPARISONS`, computed from the exact
//! Student t distribution function for integer degrees of freedom (Abramowitz & Stegun
//! 26.7.3-4, checked against table values below). `R = K = 16` rather than 8: with 7 degrees
//! of freedom the critical value would be 9.8, with 15 it is 6.0, at the same total work.

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use common::stats::{
    assert_finite_non_negative, block_t, mean_se, relmse_observed_and_expected, rounded, t_critical,
};
use common::{
    analytic_enclosure, bdpt_replicates, enclosure_radiance, ENCLOSURE_ALBEDO, ENCLOSURE_LE,
};
use glam::{Mat4, Vec3, Vec3A};
use mcmc_core::render_loop::ChainSlot;
use mcmc_core::{Mh, Target};
use pss::{KelemenParams, PssState, PssmltProposal, SmallMutation, SmallStep};
use render::bdpt::BdptParams;
use render::image::Image;
use render::mlt::dr::{self, DrBase, DrVariant};
use render::mlt::mala::{self, MalaConfig, MalaVariant};
use render::mlt::{
    LargeStepMode, MltBudget, MltDriver, MltEstimator, MltOutput, MltSettings, MmltTarget,
    PerChain, PssmltTarget, PATH_STREAMS,
};
use render::scene::{CameraSpec, Material, Mesh, Scene};
use render::session::NoProgress;

/// Family-wise false-alarm probability of all the comparisons in this file.
const ALPHA_FAMILY: f64 = 0.001;
/// MCMC replicates per estimate.
const R: usize = 16;
/// BDPT reference replicates.
const K: usize = 16;
/// The Cornell box is split into `BLOCKS x BLOCKS` blocks for the regional test.
const BLOCKS: usize = 4;
/// Max depth of the enclosure renders.
const ENCLOSURE_DEPTH: u32 = 3;
/// Null-hypothesis comparisons in this file: the enclosure's image mean (PSSMLT, MMLT, the
/// seven DR configurations — orbital, the authors' and the pairwise Tierney-Mira and
/// Green-Mira on PSSMLT, orbital on MMLT, orbital with large-step MIS — the four MALA
/// variants and cheap-then-expensive)
/// and MMLT's per-depth bootstrap means (depths `0..=ENCLOSURE_DEPTH`); the Cornell box's
/// image mean and blocks (PSSMLT, MMLT, six DR configurations, four MALA variants,
/// cheap-then-expensive).
const N_COMPARISONS: usize =
    (2 + 7 + 5) + (ENCLOSURE_DEPTH as usize + 1) + 13 * (1 + BLOCKS * BLOCKS);

// ---------------------------------------------------------------------------------------------
// Student's t (`common::stats`).

/// The critical value of the replicate comparisons (Bonferroni over `N_COMPARISONS`).
fn critical() -> f64 {
    t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, (R.min(K) - 1) as u32)
}

#[test]
fn t_quantiles_match_tables() {
    // Standard table values (two-sided alpha, degrees of freedom, quantile).
    for (alpha, df, table) in [
        (0.05, 1, 12.706),
        (0.01, 2, 9.925),
        (0.05, 7, 2.365),
        (0.01, 7, 3.499),
        (0.001, 7, 5.408),
        (0.001, 10, 4.587),
        (0.001, 15, 4.073),
        (0.05, 30, 2.042),
    ] {
        let t = t_critical(alpha, df);
        assert!(
            (t - table).abs() < 2e-3,
            "t({alpha}, {df}) = {t}, table {table}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Rendering helpers.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Method {
    Pssmlt,
    Mmlt,
    /// Delayed-rejection MLT over PSSMLT (`render::mlt::dr`).
    Dr(DrVariant),
    /// Delayed-rejection MLT over MMLT, orbital second stage on the camera subpath.
    DrMmlt,
    /// Orbital delayed rejection over PSSMLT with the large-step MIS estimator.
    DrMis,
    /// Langevin MLT (`render::mlt::mala`) with the given adaptation.
    Mala(MalaVariant),
    /// Delayed rejection, cheap (Gaussian) then expensive (MALA), on MMLT.
    CheapThenExpensive,
    /// Langevin MLT under the paper-values preset (`MalaParams::luan2020_values`: the code's
    /// semantics, fallback steps) with the given adaptation.
    MalaValues(MalaVariant),
}

fn kernel(p: f64) -> Mh<PssmltProposal> {
    let small = SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
    Mh::new(PssmltProposal::new(small, p).unwrap())
}

fn settings(scene: &Scene, seed: u64, mutations_per_pixel: f64) -> MltSettings {
    MltSettings {
        width: scene.camera().width() as usize,
        height: scene.camera().height() as usize,
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

fn render(method: Method, scene: &Scene, params: BdptParams, settings: &MltSettings) -> MltOutput {
    let (w, h) = (settings.width as u32, settings.height as u32);
    let cancel = AtomicBool::new(false);
    match method {
        Method::Pssmlt => MltDriver::new(&[PssmltTarget::new(scene, params, w, h)], settings).run(
            kernel,
            &NoProgress,
            &cancel,
        ),
        Method::Mmlt => MltDriver::new(&MmltTarget::all_depths(scene, params, w, h), settings).run(
            kernel,
            &NoProgress,
            &cancel,
        ),
        Method::Dr(variant) => {
            let targets = [PssmltTarget::new(scene, params, w, h)];
            let layout = dr::dr_layout(params.max_depth);
            let base = DrBase::Pssmlt;
            match variant {
                DrVariant::Orbital => MltDriver::new(&targets, settings).run(
                    |p| dr::lazy_orbital_kernel(base, p, 0, false),
                    &NoProgress,
                    &cancel,
                ),
                DrVariant::TierneyMira => MltDriver::new(&targets, settings).run(
                    |p| dr::tierney_mira_kernel(layout, base, p, 0),
                    &NoProgress,
                    &cancel,
                ),
                DrVariant::GreenMira => MltDriver::new(&targets, settings).run(
                    |p| dr::green_mira_kernel(layout, base, p, 0),
                    &NoProgress,
                    &cancel,
                ),
                DrVariant::TierneyMiraPairwise => MltDriver::new(&targets, settings).run(
                    |p| dr::pairwise_tierney_mira_kernel(layout, base, p, 0),
                    &NoProgress,
                    &cancel,
                ),
                DrVariant::GreenMiraPairwise => MltDriver::new(&targets, settings).run(
                    |p| dr::pairwise_green_mira_kernel(layout, base, p, 0),
                    &NoProgress,
                    &cancel,
                ),
                DrVariant::CheapThenExpensive => unreachable!("Method::CheapThenExpensive"),
            }
        }
        Method::Mala(variant) => mala::render(
            scene,
            params,
            &MalaConfig {
                variant,
                ..MalaConfig::default()
            },
            false,
            settings,
            SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap(),
            &NoProgress,
            &cancel,
        ),
        Method::MalaValues(variant) => {
            let p = render::mlt::mala::MalaParams::luan2020_values();
            mala::render(
                scene,
                params,
                &MalaConfig {
                    variant,
                    params: p.langevin,
                    fallback: p.fallback,
                    ..MalaConfig::default()
                },
                false,
                settings,
                SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap(),
                &NoProgress,
                &cancel,
            )
        }
        Method::CheapThenExpensive => mala::render(
            scene,
            params,
            &MalaConfig::default(),
            true,
            settings,
            SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap(),
            &NoProgress,
            &cancel,
        ),
        Method::DrMis => {
            let targets = [PssmltTarget::new(scene, params, w, h)];
            MltDriver::new(&targets, settings)
                .estimator(MltEstimator {
                    large_step_mis: true,
                    ..MltEstimator::plain()
                })
                .run(
                    |p| dr::lazy_orbital_kernel(DrBase::Pssmlt, p, 0, false),
                    &NoProgress,
                    &cancel,
                )
        }
        Method::DrMmlt => MltDriver::new(&MmltTarget::all_depths(scene, params, w, h), settings)
            .run(
                PerChain(|slot: ChainSlot, p| {
                    dr::lazy_orbital_kernel(DrBase::Mmlt, p, slot.target as u32, false)
                }),
                &NoProgress,
                &cancel,
            ),
    }
}

/// Every channel of every pixel finite and non-negative.
/// `R` replicate renders with seeds `seed0 + r`; checks that each ran to completion and that
/// its image is finite and non-negative.
fn replicates(
    method: Method,
    scene: &Scene,
    params: BdptParams,
    seed0: u64,
    mutations_per_pixel: f64,
) -> Vec<Image> {
    (0..R as u64)
        .map(|r| {
            let s = settings(scene, seed0 + r, mutations_per_pixel);
            let out = render(method, scene, params, &s);
            assert!(out.message.is_none(), "{method:?}: {:?}", out.message);
            assert!(!out.cancelled);
            assert_eq!(
                out.mutations,
                (mutations_per_pixel * (s.width * s.height) as f64) as u64
            );
            assert!(
                out.b.is_finite() && out.b > 0.0,
                "{method:?}: b = {}",
                out.b
            );
            assert_finite_non_negative(&out.image, &format!("{method:?} replicate {r}"));
            out.image
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// 1. The analytic enclosure: radiance is `enclosure_radiance(max_depth)` everywhere.

/// The image mean of `R` replicates against the closed form. PSSMLT's image is `b W H / N`
/// times the expected-value splat sum, and in this grey scene every splat's luminance equals
/// its red channel, so the image mean is the bootstrap's `b` itself: this tests `b` (the mean
/// of the MIS-weighted BDPT sample luminance) and the splat normalisation. MMLT's `b` sums the
/// per-depth bootstraps (one strategy per sample, times the number of strategies).
fn enclosure_case(method: Method, seed0: u64) {
    let scene = analytic_enclosure(16, 16);
    let params = BdptParams {
        max_depth: ENCLOSURE_DEPTH,
        ..BdptParams::default()
    };
    let exact = enclosure_radiance(ENCLOSURE_DEPTH);
    let images = replicates(method, &scene, params, seed0, 32.0);
    let means: Vec<f64> = images.iter().map(|im| im.mean()[0]).collect();
    let (m, se) = mean_se(&means);
    let t = (m - exact) / se;
    let crit = critical();
    eprintln!(
        "enclosure {method:?}: mean {m:.6} exact {exact:.6} se {se:.2e} ({:.3}%) t {t:.2} \
         critical {crit:.2}",
        100.0 * se / exact
    );
    // f32 pixels: a relative allowance of 1e-6 for rounding (in case se is tiny).
    assert!(
        (m - exact).abs() < crit * se + 1e-6 * exact,
        "{method:?}: image mean {m} vs exact {exact}, se {se}, t {t}, critical {crit}"
    );
}

#[test]
fn pssmlt_matches_the_analytic_enclosure() {
    enclosure_case(Method::Pssmlt, 1000);
}

#[test]
fn mmlt_matches_the_analytic_enclosure() {
    enclosure_case(Method::Mmlt, 2000);
}

#[test]
fn drmlt_variants_match_the_analytic_enclosure() {
    enclosure_case(Method::Dr(DrVariant::Orbital), 5000);
    enclosure_case(Method::Dr(DrVariant::TierneyMira), 6000);
    enclosure_case(Method::Dr(DrVariant::GreenMira), 7000);
    enclosure_case(Method::DrMmlt, 8000);
    enclosure_case(Method::Dr(DrVariant::TierneyMiraPairwise), 6500);
    enclosure_case(Method::Dr(DrVariant::GreenMiraPairwise), 7500);
    enclosure_case(Method::DrMis, 8500);
}

/// MMLT's per-depth targets: in the enclosure every path of depth `d` carries `Le rho^d`, and
/// the depth-`d` target (one strategy chosen uniformly, its MIS-weighted contribution times
/// the number of strategies) has expectation `Le rho^d` over primary sample space. The
/// bootstrap samples are independent, so their standard error is the usual one; the degrees of
/// freedom are capped at 1000 (conservative).
#[test]
fn mmlt_per_depth_bootstrap_matches_the_enclosure() {
    let scene = analytic_enclosure(16, 16);
    let params = BdptParams {
        max_depth: ENCLOSURE_DEPTH,
        ..BdptParams::default()
    };
    let n = 40_000;
    let crit = t_critical(ALPHA_FAMILY / N_COMPARISONS as f64, 1000);
    for (d, target) in MmltTarget::all_depths(&scene, params, 16, 16)
        .iter()
        .enumerate()
    {
        let weights = bootstrap_weights(target, n, 7_000 + d as u64);
        let (m, se) = mean_se(&weights);
        let exact = f64::from(ENCLOSURE_LE) * f64::from(ENCLOSURE_ALBEDO).powi(d as i32);
        let t = (m - exact) / se.max(f64::MIN_POSITIVE);
        eprintln!("enclosure MMLT depth {d}: b_d {m:.6} exact {exact:.6} se {se:.2e} t {t:.2}");
        assert!(weights.iter().all(|w| w.is_finite() && *w >= 0.0));
        assert!(
            (m - exact).abs() < crit * se + 1e-6 * exact,
            "depth {d}: b_d {m} vs exact {exact}, se {se}, t {t}, critical {crit}"
        );
    }
}

/// `f(u)` of `n` independent primary-sample-space points (the render loop's bootstrap weights).
fn bootstrap_weights<T: Target<State = PssState>>(target: &T, n: u64, seed: u64) -> Vec<f64> {
    let mut payload = T::Payload::default();
    (0..n)
        .map(|i| {
            let key = mcmc_core::render_loop::bootstrap_key(seed, 0, i);
            let mut state = PssState::new(PATH_STREAMS, key);
            target.evaluate(&mut state, &mut payload).exp()
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// 2. The Cornell box against a BDPT reference.

const CORNELL: u32 = 16;
const CORNELL_DEPTH: u32 = 5;
const REF_SPP: u32 = 256;
/// PSSMLT evaluates all strategies per mutation; MMLT one, so it gets more mutations.
const PSSMLT_MPP: f64 = 256.0;
const MMLT_MPP: f64 = 512.0;

fn cornell() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::cornell_box(CORNELL, CORNELL))
}

/// `K` independent BDPT renders of the Cornell box at depth 5 (shared by the tests).
fn reference() -> &'static [Image] {
    static REFERENCE: OnceLock<Vec<Image>> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        let params = BdptParams {
            max_depth: CORNELL_DEPTH,
            ..BdptParams::default()
        };
        bdpt_replicates(cornell(), &params, REF_SPP, K, 90_000)
    })
}

fn cornell_case(method: Method, seed0: u64, mutations_per_pixel: f64) {
    let params = BdptParams {
        max_depth: CORNELL_DEPTH,
        ..BdptParams::default()
    };
    let reference = reference();
    let images = replicates(method, cornell(), params, seed0, mutations_per_pixel);
    let crit = critical();

    // (a) Image means (luminance).
    let (mm, sm) = mean_se(&images.iter().map(Image::mean_luminance).collect::<Vec<_>>());
    let (mr, sr) = mean_se(
        &reference
            .iter()
            .map(Image::mean_luminance)
            .collect::<Vec<_>>(),
    );
    let se = sm.hypot(sr);
    let t_mean = (mm - mr) / se;
    eprintln!(
        "cornell {method:?}: mean {mm:.5} (se {sm:.2e} = {:.2}%) reference {mr:.5} (se {sr:.2e}) \
         t {t_mean:.2} critical {crit:.2}; a 5% scale error would give t {:.2}",
        100.0 * sm / mm,
        (1.05 * mm - mr) / (1.05 * sm).hypot(sr)
    );

    // (b) Blocks.
    let blocks = block_t(&images, reference, BLOCKS);
    let t_blocks: Vec<f64> = blocks.iter().map(|b| b[0]).collect();
    let rel_se: Vec<f64> = blocks
        .iter()
        .map(|b| 100.0 * b[2].hypot(b[4]) / b[3])
        .collect();
    eprintln!(
        "cornell {method:?}: block t {:?}, max |t| {:.2}; relative se of the differences (%) {:?}",
        rounded(&t_blocks),
        t_blocks.iter().map(|t| t.abs()).fold(0.0, f64::max),
        rounded(&rel_se)
    );

    // (c) relMSE of the replicate average against the reference average. If both are
    // unbiased, E[(I - R)^2] = Var(I) + Var(R) per pixel and channel, so the expected relMSE
    // is the mean of (var_mlt / R + var_ref / K) / (R^2 + eps), estimated from the replicates
    // (15 degrees of freedom per pixel, averaged over 768 values: a stable estimate). The
    // observed relMSE is a mean of 768 squared errors which are strongly correlated (MCMC
    // pixels, and the three channels of a pixel) and heavy-tailed (dark pixels weigh most), so
    // it fluctuates around its expectation by tens of percent, not by a factor of 3: the bound
    // 3 x expected holds with a wide margin when unbiased, while a per-pixel bias adds
    // bias^2 / (R^2 + eps) and fails it once the mean squared relative bias exceeds twice the
    // noise. The constant 1e-6 only matters if the expected value were ~0.
    let (observed, expected) = relmse_observed_and_expected(&images, reference);
    eprintln!(
        "cornell {method:?}: relMSE observed {observed:.3e} expected {expected:.3e} ratio {:.2}",
        observed / expected
    );

    assert!(
        t_mean.abs() < crit,
        "{method:?}: image mean {mm} (se {sm}) vs reference {mr} (se {sr}): t {t_mean}, \
         critical {crit}"
    );
    for (k, b) in blocks.iter().enumerate() {
        assert!(
            b[0].abs() < crit,
            "{method:?}: block {k}: {} (se {}) vs reference {} (se {}): t {}, critical {crit}",
            b[1],
            b[2],
            b[3],
            b[4],
            b[0]
        );
    }
    assert!(
        observed < 3.0 * expected + 1e-6,
        "{method:?}: relMSE {observed} vs expected {expected}"
    );
}

#[test]
fn pssmlt_converges_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Pssmlt, 3000, PSSMLT_MPP);
}

#[test]
fn mmlt_converges_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Mmlt, 4000, MMLT_MPP);
}

#[test]
fn drmlt_orbital_converges_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Dr(DrVariant::Orbital), 5000, PSSMLT_MPP);
}

/// The authors' Tierney-Mira and Green-Mira (1-D Kelemen first stage, Gaussian 0.1/64
/// second stage).
#[test]
fn drmlt_tierney_mira_and_green_mira_converge_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Dr(DrVariant::TierneyMira), 6000, PSSMLT_MPP);
    cornell_case(Method::Dr(DrVariant::GreenMira), 7000, PSSMLT_MPP);
}

/// Tierney-Mira and Green-Mira over the pairwise stages.
#[test]
fn drmlt_pairwise_tierney_mira_and_green_mira_converge_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Dr(DrVariant::TierneyMiraPairwise), 6500, PSSMLT_MPP);
    cornell_case(Method::Dr(DrVariant::GreenMiraPairwise), 7500, PSSMLT_MPP);
}

#[test]
fn drmlt_on_mmlt_converges_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::DrMmlt, 8000, MMLT_MPP);
}

/// Langevin MLT: MALA on depths <= 3 of the depth-5 box, Kelemen beyond. It gets MMLT's
/// mutation budget: its gradients cost more per mutation, but each mutation is one strategy.
const MALA_MPP: f64 = MMLT_MPP;

#[test]
fn mala_variants_match_the_analytic_enclosure() {
    enclosure_case(Method::Mala(MalaVariant::Plain), 9000);
    enclosure_case(Method::Mala(MalaVariant::Online), 9100);
    enclosure_case(Method::Mala(MalaVariant::Cache), 9200);
    enclosure_case(Method::Mala(MalaVariant::Hybrid), 9300);
    enclosure_case(Method::CheapThenExpensive, 9400);
}

#[test]
fn mala_variants_under_the_paper_values_preset_match_the_analytic_enclosure() {
    enclosure_case(Method::MalaValues(MalaVariant::Plain), 9050);
    enclosure_case(Method::MalaValues(MalaVariant::Online), 9150);
    enclosure_case(Method::MalaValues(MalaVariant::Cache), 9250);
    enclosure_case(Method::MalaValues(MalaVariant::Hybrid), 9350);
}

#[test]
fn mala_and_mala_online_converge_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Mala(MalaVariant::Plain), 9500, MALA_MPP);
    cornell_case(Method::Mala(MalaVariant::Online), 9600, MALA_MPP);
}

#[test]
fn mala_cache_and_hybrid_converge_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::Mala(MalaVariant::Cache), 9700, MALA_MPP);
    cornell_case(Method::Mala(MalaVariant::Hybrid), 9800, MALA_MPP);
}

#[test]
fn drmlt_cheap_then_expensive_converges_to_bdpt_on_the_cornell_box() {
    cornell_case(Method::CheapThenExpensive, 9900, MALA_MPP);
}

// ---------------------------------------------------------------------------------------------
// 3. Negative control: the same block test detects a wrong max depth.

/// MCMC renders with max depth 1 (direct lighting only) against the depth-5 reference: the
/// ceiling is lit only indirectly, so some blocks lose most of their radiance and the block
/// test must reject (this is the statistic of the real test, with its critical value). A
/// subtler error, max depth 2 (about 10% darker), is below what this budget resolves per block
/// for MMLT (relative se of a block difference about 2.5%, so the smallest bias detected with
/// 95% power is about (6.0 + 1.6) x 2.5% = 19%).
#[test]
fn negative_control_wrong_depth_fails_the_block_test() {
    let reference = reference();
    let crit = critical();
    for (method, seed0) in [(Method::Pssmlt, 5000), (Method::Mmlt, 6000)] {
        let params = BdptParams {
            max_depth: 1,
            ..BdptParams::default()
        };
        let images = replicates(method, cornell(), params, seed0, 64.0);
        let t_blocks: Vec<f64> = block_t(&images, reference, BLOCKS)
            .iter()
            .map(|b| b[0])
            .collect();
        let worst = t_blocks.iter().map(|t| t.abs()).fold(0.0, f64::max);
        let rejected = t_blocks.iter().filter(|t| t.abs() > crit).count();
        eprintln!(
            "negative control {method:?} (depth 1 vs 5): block t {:?}, {rejected} of {} blocks \
             rejected (critical {crit:.2})",
            rounded(&t_blocks),
            t_blocks.len()
        );
        assert!(
            worst > crit,
            "{method:?}: depth 1 vs 5 not detected: max |t| {worst}, critical {crit}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 4. No light-carrying path.

/// The inside of a closed grey sphere, without emitter.
fn dark_sphere() -> (Mesh, Vec<Material>) {
    let mut mesh = Mesh::new();
    mesh.add_sphere(Vec3A::ZERO, 1.0, 8, 16, 0, true);
    let materials = vec![Material::diffuse("grey", Vec3::splat(0.7), Vec3::ZERO)];
    (mesh, materials)
}

fn dark_camera() -> CameraSpec {
    CameraSpec::look_at(
        Vec3A::new(0.0, 0.0, 0.6),
        Vec3A::new(0.0, 0.0, -1.0),
        Vec3A::Y,
        60.0,
    )
}

/// Both methods on `scene`: a message naming the problem, a black finite image, no mutation.
fn assert_no_light_path(scene: &Scene, what: &str) {
    for method in [Method::Pssmlt, Method::Mmlt] {
        let out = render(
            method,
            scene,
            BdptParams::default(),
            &settings(scene, 7, 16.0),
        );
        let message = out.message.clone().unwrap_or_default();
        eprintln!("{what}, {method:?}: {message:?}");
        assert!(
            message.contains("no light-carrying path"),
            "{what}, {method:?}: message {:?}, b {} (a light-carrying path was found), \
             mean luminance {}",
            out.message,
            out.b,
            out.image.mean_luminance()
        );
        assert_eq!((out.image.width, out.image.height), (8, 8));
        assert_eq!(out.image.count_nonfinite(), 0);
        assert!(out.image.pixels.iter().all(|p| *p == [0.0; 3]));
        assert_eq!(out.mutations, 0);
        assert_eq!(out.b, 0.0);
    }
}

#[test]
fn a_scene_without_emitters_gives_a_message_and_a_black_image() {
    let (mesh, materials) = dark_sphere();
    let mut scene = Scene::new(mesh, materials, vec![], dark_camera(), 8, 8);
    // Without lights the scene gets the default environment (which cannot reach the camera
    // inside the closed sphere either); without that, it has no light at all.
    assert!(scene.uses_default_environment());
    assert_no_light_path(&scene, "default environment outside a closed sphere");
    scene.set_environment(None);
    assert!(scene.lights().is_empty());
    assert_no_light_path(&scene, "no emitter");
}

/// An emitter sealed inside a closed opaque box (inside the dark sphere, in front of the
/// camera): it exists, but no path joins it to the camera. A failure with a tiny positive `b`
/// means light leaks out of the box: e.g. a ray leaving one wall within 1e-4 of an adjacent
/// wall must hit that wall (obvhs 0.4's CWBVH traversal clamps node entry distances to 1e-4,
/// so triangles nearer than that along the ray are skipped unless the BVH wrapper compensates).
#[test]
fn an_emitter_sealed_in_a_box_gives_a_message_and_a_black_image() {
    let (mut mesh, mut materials) = dark_sphere();
    // The box [-0.15, 0.15]^2 x [-0.55, -0.25], faces outwards, grey.
    mesh.add_box(
        Mat4::from_translation(glam::Vec3::new(0.0, 0.0, -0.4))
            * Mat4::from_scale(glam::Vec3::splat(0.3)),
        0,
    );
    // A one-sided emitter at its centre, facing the camera (through the box's wall).
    materials.push(Material::diffuse(
        "lamp",
        Vec3::splat(0.5),
        Vec3::splat(10.0),
    ));
    let (e, z) = (0.05, -0.4);
    mesh.add_quad(
        [
            Vec3A::new(-e, -e, z),
            Vec3A::new(e, -e, z),
            Vec3A::new(e, e, z),
            Vec3A::new(-e, e, z),
        ],
        1,
    );
    let scene = Scene::new(mesh, materials, vec![], dark_camera(), 8, 8);
    assert!(!scene.lights().is_empty());
    assert_no_light_path(&scene, "sealed emitter");
}

// ---------------------------------------------------------------------------------------------
// 5. Determinism.

#[test]
fn same_seed_gives_identical_bytes_with_one_and_two_threads() {
    let scene = cornell();
    let params = BdptParams::default();
    let dir =
        std::env::temp_dir().join(format!("chainlight-mlt-determinism-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bits =
        |im: &Image| -> Vec<u32> { im.pixels.iter().flat_map(|p| p.map(f32::to_bits)).collect() };
    for method in [
        Method::Pssmlt,
        Method::Mmlt,
        Method::Dr(DrVariant::GreenMira),
        Method::DrMmlt,
    ] {
        let mut s = settings(scene, 42, 16.0);
        if matches!(method, Method::Mmlt | Method::DrMmlt) {
            // Also cover automatic large-step control (statistics pooled over chains; for DR
            // chains eta_s is a small step's probability of moving at either stage).
            s.large_step = LargeStepMode::Auto {
                initial: 0.5,
                estimation_steps: 8,
            };
        }
        let with_threads = |n: usize, s: &MltSettings| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap();
            pool.install(|| render(method, scene, params, s))
        };
        let one = with_threads(1, &s);
        let two = with_threads(2, &s);
        assert!(one.message.is_none(), "{method:?}: {:?}", one.message);
        assert!(one.image.pixels.iter().any(|p| p[0] > 0.0));
        assert_eq!(
            bits(&one.image),
            bits(&two.image),
            "{method:?}: pixels differ"
        );
        assert_eq!(one.b.to_bits(), two.b.to_bits());
        assert_eq!(one.mutations, two.mutations);
        assert_eq!(one.stats, two.stats);
        assert_eq!(
            one.final_large_step_probability.to_bits(),
            two.final_large_step_probability.to_bits()
        );
        let pa = dir.join(format!("{method:?}-1-thread.exr"));
        let pb = dir.join(format!("{method:?}-2-threads.exr"));
        render::image_io::write_exr(&pa, &one.image).unwrap();
        render::image_io::write_exr(&pb, &two.image).unwrap();
        let (ba, bb) = (std::fs::read(&pa).unwrap(), std::fs::read(&pb).unwrap());
        assert!(!ba.is_empty());
        assert!(ba == bb, "{method:?}: EXR bytes differ");
        // A different seed gives a different image.
        let mut other = s;
        other.seed = 43;
        let three = with_threads(2, &other);
        assert_ne!(
            bits(&one.image),
            bits(&three.image),
            "{method:?}: seed ignored"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The delayed-rejection stage map (share of each pixel's estimate from second-stage
/// candidates): present only when asked for, in [0, 1] (every DR splat weight is
/// non-negative), and it tells the rules apart as the per-stage statistics do — the orbital
/// second stage is accepted most of the time, Tierney-Mira's nearly never after a bold
/// pairwise first stage (section 4.3), so orbital's map is far brighter. Control: the
/// one-stage PSSMLT kernel gives an all-zero map.
#[test]
fn drmlt_stage_map() {
    let scene = cornell();
    let params = BdptParams::default();
    let mut s = settings(scene, 11, 32.0);
    assert!(render(Method::Dr(DrVariant::Orbital), scene, params, &s)
        .stage_map
        .is_none());
    s.stage_map = true;
    let mean =
        |m: &Image| m.pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / m.pixels.len() as f64;
    let orbital = render(Method::Dr(DrVariant::Orbital), scene, params, &s)
        .stage_map
        .expect("stage map");
    assert!(orbital
        .pixels
        .iter()
        .all(|p| p[0].is_finite() && (0.0..=1.0 + 1e-6).contains(&p[0])));
    let tm = render(Method::Dr(DrVariant::TierneyMira), scene, params, &s)
        .stage_map
        .expect("stage map");
    let (mo, mt) = (mean(&orbital), mean(&tm));
    assert!(
        mo > 0.02 && mo > 4.0 * mt,
        "orbital {mo} vs tierney-mira {mt}"
    );
    let one_stage = render(Method::Pssmlt, scene, params, &s)
        .stage_map
        .expect("stage map");
    assert!(one_stage.pixels.iter().all(|p| p[0] == 0.0));
}
