//! Determinism: under a sample budget the same seed gives a bit-identical image with 1, 2 and
//! 3 threads, for every integrator of the table (work units are fixed and merged in a fixed
//! order, random numbers are keyed by seed, pixel, sample and dimension, or by seed and chain);
//! a different seed gives a different image.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use render::image::Image;
use render::methods::{DrmltSettings, MethodSettings, MmltSettings, PssmltSettings};
use render::scene::Scene;
use render::session::{render, Budget, NoProgress, RenderSettings};
use render::{IntegratorKind, INTEGRATORS};

fn settings(width: u32, height: u32, threads: usize, seed: u64) -> RenderSettings {
    with_method(IntegratorKind::Pt.settings(), width, height, threads, seed)
}

/// `method` with 16 chains and a bootstrap of 5000 samples (Markov chain methods).
fn with_method(
    method: MethodSettings,
    width: u32,
    height: u32,
    threads: usize,
    seed: u64,
) -> RenderSettings {
    RenderSettings {
        width,
        height,
        budget: Budget::SamplesPerPixel(3),
        threads,
        seed,
        max_depth: 6,
        method: method.with_chains(16, 5_000),
    }
}

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn run(scene: &Scene, s: &RenderSettings) -> Image {
    let out = render(scene, s, &NoProgress, &AtomicBool::new(false)).unwrap();
    assert!(!out.cancelled);
    if !s.integrator().is_mcmc() {
        assert_eq!(out.samples, u64::from(s.width * s.height) * 3);
    }
    out.image
}

#[test]
fn same_seed_any_thread_count_is_bit_identical() {
    // 40 x 20 is not a multiple of PT's 16-pixel tiles nor of BDPT's 8 bands.
    let scene = Scene::cornell_box(40, 20);
    for info in INTEGRATORS {
        let with = |threads| with_method(info.kind.settings(), 40, 20, threads, 7);
        let reference = run(&scene, &with(1));
        assert!(reference.mean_luminance() > 0.0, "{}: black", info.name);
        for threads in [2, 3] {
            let image = run(&scene, &with(threads));
            assert!(
                bits(&image) == bits(&reference),
                "{}: {threads} threads differ from 1",
                info.name
            );
        }
    }
}

/// The delayed-rejection variant that is not a row of the table: cheap then expensive
/// (Gaussian, then MALA with a finite-difference gradient).
#[test]
fn drmlt_cheap_then_expensive_is_bit_identical() {
    let scene = Scene::cornell_box(24, 16);
    let with = |threads| {
        let method = DrmltSettings::rioux_lavoie2020_with(
            render::mlt::dr::DrVariant::CheapThenExpensive,
            render::mlt::dr::DrBase::Mmlt,
        );
        with_method(method.into(), 24, 16, threads, 11)
    };
    let reference = run(&scene, &with(1));
    assert!(reference.mean_luminance() > 0.0);
    assert!(bits(&run(&scene, &with(2))) == bits(&reference));
    let mut other = with(1);
    other.seed = 12;
    assert!(bits(&run(&scene, &other)) != bits(&reference));
}

/// The delayed-rejection rules over both stage families, on both samplers: the authors'
/// Tierney-Mira and Green-Mira (1-D Kelemen, then Gaussian 0.1/64) and the pairwise ones.
#[test]
fn drmlt_tierney_mira_and_green_mira_are_bit_identical() {
    use render::mlt::dr::{DrBase, DrVariant};
    let scene = Scene::cornell_box(24, 16);
    for variant in [
        DrVariant::TierneyMira,
        DrVariant::GreenMira,
        DrVariant::TierneyMiraPairwise,
        DrVariant::GreenMiraPairwise,
    ] {
        for base in [DrBase::Pssmlt, DrBase::Mmlt] {
            let with = |threads| {
                let method = DrmltSettings::rioux_lavoie2020_with(variant, base);
                with_method(method.into(), 24, 16, threads, 13)
            };
            let reference = run(&scene, &with(1));
            assert!(reference.mean_luminance() > 0.0, "{variant:?} {base:?}");
            assert!(
                bits(&run(&scene, &with(2))) == bits(&reference),
                "{variant:?} {base:?}: 2 threads differ from 1"
            );
            let mut other = with(1);
            other.seed = 14;
            assert!(
                bits(&run(&scene, &other)) != bits(&reference),
                "{variant:?} {base:?}: seed ignored"
            );
        }
    }
}

/// Delayed rejection with the large-step MIS estimator (`--large-step-mis on`): 1 and 2
/// threads give the same image, and the option changes the image.
#[test]
fn drmlt_large_step_mis_is_bit_identical() {
    use render::mlt::dr::{DrBase, DrVariant};
    let scene = Scene::cornell_box(24, 16);
    for (variant, base) in [
        (DrVariant::Orbital, DrBase::Pssmlt),
        (DrVariant::TierneyMira, DrBase::Mmlt),
    ] {
        let with = |threads, mis| {
            let mut method = DrmltSettings::rioux_lavoie2020_with(variant, base);
            method.large_step_mis = mis;
            with_method(method.into(), 24, 16, threads, 15)
        };
        let reference = run(&scene, &with(1, true));
        assert!(reference.mean_luminance() > 0.0, "{variant:?} {base:?}");
        assert!(
            bits(&run(&scene, &with(2, true))) == bits(&reference),
            "{variant:?} {base:?}: 2 threads differ from 1"
        );
        assert!(
            bits(&run(&scene, &with(1, false))) != bits(&reference),
            "{variant:?} {base:?}: the option has no effect"
        );
    }
}

/// PSSMLT and MMLT with the large-step MIS estimator (`--large-step-mis on`), under fixed and
/// automatic large-step probability: 1, 2 and 3 threads give the same image.
#[test]
fn large_step_mis_is_bit_identical() {
    let scene = Scene::cornell_box(24, 16);
    for integrator in [IntegratorKind::Pssmlt, IntegratorKind::Mmlt] {
        let method = |large_step| -> MethodSettings {
            if integrator == IntegratorKind::Pssmlt {
                let mut s = PssmltSettings::default();
                (s.chain.large_step, s.large_step_mis) = (large_step, true);
                s.into()
            } else {
                let mut s = MmltSettings::default();
                (s.chain.large_step, s.large_step_mis) = (large_step, true);
                s.into()
            }
        };
        for large_step in [
            render::mlt::LargeStepMode::Fixed(0.3),
            render::mlt::LargeStepMode::Auto {
                initial: 0.5,
                estimation_steps: 10,
            },
        ] {
            let with = |threads| with_method(method(large_step), 24, 16, threads, 13);
            let reference = run(&scene, &with(1));
            assert!(reference.mean_luminance() > 0.0);
            for threads in [2, 3] {
                assert!(
                    bits(&run(&scene, &with(threads))) == bits(&reference),
                    "{integrator:?} {large_step:?} with large-step MIS: {threads} threads differ from 1"
                );
            }
        }
    }
}

#[test]
fn different_seed_gives_a_different_image() {
    let scene = Scene::cornell_box(16, 16);
    let a = run(&scene, &settings(16, 16, 2, 1));
    let b = run(&scene, &settings(16, 16, 2, 2));
    assert!(bits(&a) != bits(&b));
    // ... but the same expected brightness (a loose sanity check).
    let (la, lb) = (a.mean_luminance(), b.mean_luminance());
    assert!((la - lb).abs() < 0.5 * la.max(lb), "{la} vs {lb}");
}

#[test]
fn gltf_scene_with_glass_is_deterministic() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-glass.gltf");
    let scene = Scene::load(&path).unwrap();
    let a = run(&scene, &settings(16, 16, 1, 3));
    let b = run(&scene, &settings(16, 16, 3, 3));
    assert!(bits(&a) == bits(&b));
}

/// Delayed rejection over the path tracer (`--dr-on pssmlt-pt`, orbital and the authors'
/// Tierney-Mira), with the direct pass (orbital on PSSMLT-PT and on MMLT) and with MMLT's
/// strategy fixed along the chain: 1 and 2 threads give the same image, another seed
/// another.
#[test]
fn drmlt_over_the_path_tracer_and_with_the_direct_pass_is_bit_identical() {
    use render::methods::direct_pass::DirectSettings;
    use render::mlt::dr::{DrBase, DrVariant};
    let scene = Scene::cornell_box(24, 16);
    for (variant, base, direct) in [
        (DrVariant::Orbital, DrBase::PssmltPt, DirectSettings::OFF),
        (
            DrVariant::TierneyMira,
            DrBase::PssmltPt,
            DirectSettings::OFF,
        ),
        (
            DrVariant::Orbital,
            DrBase::PssmltPt,
            DirectSettings::balanced(1),
        ),
        (
            DrVariant::Orbital,
            DrBase::Mmlt,
            DirectSettings::balanced(1),
        ),
        (DrVariant::Orbital, DrBase::Mmlt, DirectSettings::OFF),
    ] {
        let with = |threads, seed| {
            let method = DrmltSettings {
                direct,
                // The last row: MMLT's strategy fixed along the chain.
                fixed_strategy: base == DrBase::Mmlt && direct == DirectSettings::OFF,
                ..DrmltSettings::rioux_lavoie2020_with(variant, base)
            };
            with_method(method.into(), 24, 16, threads, seed)
        };
        let reference = run(&scene, &with(1, 17));
        assert!(reference.mean_luminance() > 0.0, "{variant:?} {base:?}");
        assert!(
            bits(&run(&scene, &with(2, 17))) == bits(&reference),
            "{variant:?} {base:?} {direct:?}: 2 threads differ from 1"
        );
        assert!(
            bits(&run(&scene, &with(1, 18))) != bits(&reference),
            "{variant:?} {base:?}: seed ignored"
        );
    }
}

/// The cache-sharing Langevin variants with caches small enough to fill within the test
/// (so rounds pool, the caches freeze and the hybrid switches), pooled every 8 mutations per
/// chain, under the paper-values and the code presets (fallback steps included).
#[test]
fn mala_cache_and_hybrid_with_short_rounds_and_full_caches_are_bit_identical() {
    use render::methods::MalaSettings;
    use render::mlt::mala::MalaVariant;
    let scene = Scene::cornell_box(24, 16);
    for base in [
        MalaSettings::luan2020_values(),
        MalaSettings::luan2020_code(),
    ] {
        for variant in [MalaVariant::Cache, MalaVariant::Hybrid] {
            let with = |threads| {
                let mut m = base;
                m.config.variant = variant;
                m.config.params.cache_size = 40;
                m.config.cache_round = 8;
                with_method(m.into(), 24, 16, threads, 17)
            };
            let reference = run(&scene, &with(1));
            assert!(reference.mean_luminance() > 0.0, "{variant:?}");
            for threads in [2, 3] {
                assert!(
                    bits(&run(&scene, &with(threads))) == bits(&reference),
                    "{variant:?}: {threads} threads differ from 1"
                );
            }
        }
    }
}
