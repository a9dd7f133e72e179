//! Every paper preset of `render::methods` pins the values its paper (or its authors' code)
//! states, section cited; and differs from the command line's defaults where those add later
//! improvements (the negative control: a pin that cannot tell the preset from the default
//! would not catch a drifted preset).

use mcmc_core::langevin::LangevinParams;
use pathspace::PerturbationKind;
use pss::{KelemenParams, PairwiseKelemenParams, SmallMutation};
use render::methods::direct_pass::DirectSettings;
use render::methods::{
    ChainSettings, DrmltSettings, LqmcSettings, MalaSettings, MethodSettings, MmltSettings,
    PathMltSettings, PssmltSettings,
};
use render::mlt::direct::DirectPass;
use render::mlt::dr::{DrBase, DrVariant};
use render::mlt::mala::MalaVariant;
use render::mlt::pathmlt::{PathAdapt, ADAPT_GRID_BOTTOM, ADAPT_GRID_N};
use render::mlt::LargeStepMode;
use render::IntegratorKind;

/// Kelemen et al. 2002, section 3 (quoted by Rioux-Lavoie et al. 2020, section 3.1): small
/// steps between 1/1024 and 1/64; large steps with probability 0.3 and 100 000 bootstrap
/// samples (the DR authors' pLarge and luminanceSamples, pbrt-v3's values).
fn assert_kelemen_chain(chain: &ChainSettings) {
    let SmallMutation::Kelemen(k) = chain.small_step else {
        panic!("not Kelemen's small step: {:?}", chain.small_step);
    };
    assert_eq!(k, KelemenParams::kelemen2002());
    assert_eq!((k.s1, k.s2), (1.0 / 1024.0, 1.0 / 64.0));
    assert_eq!(chain.large_step, LargeStepMode::Fixed(0.3));
    assert_eq!((chain.chains, chain.bootstrap_samples), (256, 100_000));
}

#[test]
fn pssmlt_kelemen2002_is_the_expected_value_estimator_with_kelemen_steps() {
    let p = PssmltSettings::kelemen2002();
    assert_kelemen_chain(&p.chain);
    // Eq. 5 with expected values; no raster steps; no separate direct pass.
    assert!(!p.large_step_mis);
    assert!(p.raster.is_off());
    assert_eq!(p.direct, DirectPass::Off);
    // Section 4's MIS of the large steps is its own preset.
    let mis = PssmltSettings::kelemen2002_mis();
    assert!(mis.large_step_mis);
    assert_eq!(
        PssmltSettings {
            large_step_mis: false,
            ..mis
        },
        p
    );
    // Negative control: the command line's PSSMLT adds MIS, raster steps and a direct pass.
    assert_ne!(PssmltSettings::default(), p);
}

#[test]
fn pssmlt_zsolnai2013_estimates_the_large_step_probability() {
    // Zsolnai & Szirmay-Kalos 2013, section 2: statistics of an initial phase give p_l.
    let z = PssmltSettings::zsolnai2013();
    assert_eq!(
        z.chain.large_step,
        LargeStepMode::Auto {
            initial: 0.5,
            estimation_steps: 1_000
        }
    );
    assert_eq!(
        PssmltSettings {
            chain: ChainSettings {
                large_step: LargeStepMode::Fixed(0.3),
                ..z.chain
            },
            ..z
        },
        PssmltSettings::kelemen2002()
    );
    // Section 2's rule on Table 1's Cherry scene (eta_l, eta_s, eta_0) = (0.126, 0.487,
    // 0.911): p_l = eta_s / (2 (eta_s - eta_l)) = 0.67.
    let rule = mcmc_core::controller::automatic_large_step_probability(0.487, 0.126, 0.911);
    assert!((rule - 0.67).abs() < 0.01, "{rule}");
    assert!(PssmltSettings::zsolnai2013_luxrender().large_step_mis);
}

#[test]
fn mmlt_hachisuka2014_runs_kelemen_steps_with_joint_allocation() {
    let m = MmltSettings::hachisuka2014();
    assert_kelemen_chain(&m.chain);
    assert!(!m.large_step_mis && m.raster.is_off() && !m.strategy_strata);
    assert_eq!(m.bdpt_normalization, 0);
    assert_eq!(
        m.chain_allocation,
        mcmc_core::render_loop::ChainAllocation::Joint
    );
    assert_eq!(MmltSettings::default(), m);
}

#[test]
fn drmlt_rioux_lavoie2020_is_the_orbital_rule_on_pssmlt() {
    // Section 4.3 (eq. 11): the pairwise orbital rule, recommended; section 5.1.1: PSSMLT.
    let d = DrmltSettings::rioux_lavoie2020();
    assert_eq!((d.variant, d.on), (DrVariant::Orbital, DrBase::Pssmlt));
    assert_kelemen_chain(&d.chain);
    // The authors' orbital first stage scales Kelemen's radii by 1.9 ("compensate pairwise
    // vs i.i.d."), and the wrapped Cauchy has rho = exp(-0.25).
    let first = PairwiseKelemenParams::drmlt2020();
    assert!((first.r_min - 1.9 / 1024.0).abs() < 1e-15);
    assert!((first.r_max - 1.9 / 64.0).abs() < 1e-15);
    let rho = mcmc_core::delayed_rejection::WrappedCauchy::rioux_lavoie2020().rho();
    assert!((rho - (-0.25f64).exp()).abs() < 1e-12, "{rho}");
    // Fig. 7 compares the rules: the other presets differ only in the rule and sampler.
    let tm = DrmltSettings::rioux_lavoie2020_with(DrVariant::TierneyMira, DrBase::Mmlt);
    assert_eq!(
        DrmltSettings {
            variant: DrVariant::Orbital,
            on: DrBase::Pssmlt,
            ..tm
        },
        d
    );
    assert_ne!(tm, d);
    // Cheap-then-expensive's MALA stage is the Langevin paper's preset.
    assert_eq!(d.mala, render::mlt::mala::MalaConfig::default());
    assert_eq!(d.mala, MalaSettings::luan2020().config);
}

#[test]
fn mala_luan2020_pins_section_7_and_the_code() {
    // Section 7: epsilon 0.01, K = 30, H = 10 000; Adam beta 0.999, delta 1e-3 (eq. 10-11).
    let m = MalaSettings::luan2020();
    assert_eq!(m.config.variant, MalaVariant::Hybrid);
    let p = m.config.params;
    assert_eq!((p.epsilon, p.neighbours, p.cache_size), (0.01, 30, 10_000));
    assert_eq!(
        (p.alpha, p.beta, p.delta, p.max_gradient),
        (0.9, 0.999, 0.001, 100.0)
    );
    assert_eq!(p, LangevinParams::luan2020());
    // The authors' code (dptoptions.h): step 0.005, K = 5, H = 3000, shrink prior 0.005.
    let c = MalaSettings::luan2020_code().config.params;
    assert_eq!(
        (c.epsilon, c.neighbours, c.cache_size, c.max_std),
        (0.005, 5, 3000, 0.005)
    );
    assert_ne!(c, p);
    // The paper's values with the code's semantics, and the code, read epsilon as a
    // standard deviation with a floor; both add the code's fallback step (0.1).
    let v = MalaSettings::luan2020_values().config;
    assert_eq!(
        (v.params.epsilon, v.params.neighbours, v.params.cache_size),
        (0.01, 30, 10_000)
    );
    for s in [v, MalaSettings::luan2020_code().config] {
        assert_eq!(
            s.params.covariance,
            mcmc_core::langevin::Covariance::EpsilonSquaredMPlusOne
        );
        assert_eq!(s.params.preconditioner_range, [0.01, 100.0]);
        assert_eq!(s.params.drift_clamp, 5.0);
        assert!(s.params.radius_per_dimension);
        assert_eq!(
            s.params.adam_start,
            mcmc_core::langevin::AdamStart::FirstVisit
        );
        assert_eq!(s.fallback, 0.1);
    }
    assert_eq!(m.config.fallback, 0.0);
    assert!(!m.cheap_then_expensive);
    // The variants (Alg. 2-4) are presets too, each its own table row.
    for (variant, kind) in [
        (MalaVariant::Plain, IntegratorKind::Mala),
        (MalaVariant::Online, IntegratorKind::MalaOnline),
        (MalaVariant::Cache, IntegratorKind::MalaCache),
        (MalaVariant::Hybrid, IntegratorKind::MalaHybrid),
    ] {
        let preset = MalaSettings::luan2020_variant(variant);
        assert_eq!(preset.direct, MalaSettings::AUTHORS_DIRECT);
        let s: MethodSettings = preset.into();
        assert_eq!(s.kind(), kind);
        // The row's default is the preset with its direct pass budgeted as pssmlt's.
        let row = MethodSettings::from(MalaSettings {
            direct: DirectSettings::balanced(1),
            ..preset
        });
        assert_eq!(
            kind.settings(),
            row,
            "{kind:?}: the row's default is the preset (balanced direct pass)"
        );
    }
}

#[test]
fn pathmlt_otsu2018_mixes_the_perturbation_with_the_bidirectional_mutation() {
    // Section 8.1: N_top = 20 screen cells per axis, N_bottom = 50 direction cells.
    assert_eq!((ADAPT_GRID_N, ADAPT_GRID_BOTTOM), (20, 50));
    for kind in [PerturbationKind::Lens, PerturbationKind::MultiChain] {
        for adapt in [
            PathAdapt::Fixed,
            PathAdapt::Global,
            PathAdapt::Grid,
            PathAdapt::Quadtree,
        ] {
            let s = PathMltSettings::otsu2018(kind, adapt);
            assert_eq!((s.perturbation, s.adapt), (kind, adapt));
            assert_eq!((s.chains, s.bootstrap_samples), (256, 100_000));
        }
    }
    assert_ne!(
        PathMltSettings::otsu2018(PerturbationKind::Lens, PathAdapt::Grid),
        PathMltSettings::default()
    );
}

#[test]
fn lqmc_tessari2020_pins_section_4_parameters() {
    // Section 4 "Parameters": lattices of 23 (normal, depth of field) and 97 (caustic)
    // points; 24 image tiles across (48 for caustics); 2 x 2 aperture tiles.
    let p = LqmcSettings::tessari2020().params;
    assert_eq!((p.n_normal, p.n_depth_of_field, p.n_caustic), (23, 23, 97));
    assert_eq!((p.image_tiles, p.image_tiles_caustic), (24, 48));
    assert_eq!(p.aperture_tiles, 2);
    assert_eq!(LqmcSettings::default(), LqmcSettings::tessari2020());
    // Negative control: another lattice size is told apart.
    let mut other = p;
    other.n_caustic = 23;
    assert_ne!(other, p);
}

#[test]
fn lqmc_tessari2020_code_explores_nee_with_seven_points() {
    // The authors' code (corona-13 `lqmc.c`): NEE-classified paths explored with N = 7; the
    // paper's rule splats them unexplored. Nothing else differs.
    let code = LqmcSettings::tessari2020_code().params;
    let paper = LqmcSettings::tessari2020().params;
    assert!(code.explore_nee && code.n_nee == 7);
    assert!(!paper.explore_nee);
    assert_eq!(
        render::integrator::lqmc::LqmcParams {
            explore_nee: false,
            ..code
        },
        paper
    );
}

#[test]
fn pssmlt_corona13_kmlt_is_kmlt_over_the_path_tracer() {
    // corona-13 `kmlt.c`: large steps 0.2, uniform box small steps (0.01 for directions),
    // expected-value splats, b over 2^20 samples; over the path tracer (pssmlt-pt), without
    // roulette like LQMC's tracer, no raster steps, no direct pass.
    let p = PssmltSettings::corona13_kmlt();
    assert_eq!(p.base, render::methods::PathBase::Pt);
    assert_eq!(MethodSettings::from(p).kind(), IntegratorKind::PssmltPt);
    assert_eq!(p.chain.large_step, LargeStepMode::Fixed(0.2));
    assert_eq!(p.chain.small_step, SmallMutation::Uniform { amount: 0.01 });
    assert_eq!(p.chain.bootstrap_samples, 1 << 20);
    assert!(!p.large_step_mis && p.raster.is_off());
    assert_eq!(p.direct, DirectPass::Off);
    assert_eq!(p.roulette.start, None);
    // Negative control: PSSMLT/K over BDPT (the earlier pairing) is told apart.
    assert_ne!(PssmltSettings::kelemen2002(), p);
    assert_ne!(
        PssmltSettings::kelemen2002().on(render::methods::PathBase::Pt),
        p
    );
}
