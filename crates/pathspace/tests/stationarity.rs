//! Stationarity from exact starts on the white furnace box (mcmc-core's harness): N exact
//! draws from `pi / b`, k kernel steps each, chi-square of the final states over
//! (path length) x (raster quadrant) against the closed-form probabilities.
//!
//! Exact draws: in the furnace box `f / p_hit = L_e rho^{n-1}` for the unidirectional
//! sampler's hit technique (cosine sampling matches the Lambertian BSDF), so
//! `f / p <= N L_e / (1 - c)`, and rejection sampling from the sampler with that bound is exact.
//! Under `pi / b`, the share of paths with `j` edges is `rho^{j-1} / sum_{i<N} rho^i`, and within
//! each length the raster position is uniform (every ray carries the same radiance).

mod common;

use mcmc_core::testing::{stationarity_test, FnBins, MhWithoutHastings, StationarityParams};
use mcmc_core::{Mh, Proposal, Proposed};
use pathspace::analytic::AnalyticScene;
use pathspace::{
    ra_mixture, BidirectionalMutation, BidirectionalParams, FixedScale, IndependenceMutation,
    IndependentSampler, Path, PathTarget, Perturbation, PerturbationKind, ScaleSource,
    UnidirectionalParams, UnidirectionalSampler,
};
use rand::{Rng, RngExt};

const ALBEDO: f64 = 0.6;
const EMISSION: f64 = 1.0;
const SEGMENTS: usize = 3;
const CONNECT: f64 = 0.5;
/// Number of stationarity tests in this file that must pass (Sidak correction).
const TESTS: usize = 4;

fn sampler(scene: &AnalyticScene) -> UnidirectionalSampler<'_, AnalyticScene> {
    UnidirectionalSampler::new(
        scene,
        UnidirectionalParams {
            max_segments: SEGMENTS,
            connect_probability: CONNECT,
        },
    )
    .unwrap()
}

/// An exact draw from `pi / b` by rejection from the sampler.
fn exact_draw<R: Rng>(scene: &AnalyticScene, rng: &mut R) -> Path {
    let sampler = sampler(scene);
    let bound = SEGMENTS as f64 * EMISSION / (1.0 - CONNECT);
    loop {
        let p = common::draw(&sampler, rng);
        let ratio = p.contribution(scene).luminance() / sampler.log_density(&p).exp();
        assert!(
            ratio <= bound * (1.0 + 1e-9),
            "f/p = {ratio} exceeds the bound {bound}"
        );
        if rng.random::<f64>() * bound < ratio {
            return p;
        }
    }
}

fn bins(scene: &AnalyticScene) -> FnBins<impl Fn(&Path) -> usize + '_> {
    let norm: f64 = (0..SEGMENTS).map(|j| ALBEDO.powi(j as i32)).sum();
    let probabilities = (0..SEGMENTS * 4)
        .map(|b| ALBEDO.powi((b / 4) as i32) / norm / 4.0)
        .collect();
    FnBins {
        probabilities,
        bin_of: move |p: &Path| {
            let r = p.raster(scene).unwrap();
            (p.segments() - 1) * 4 + usize::from(r[0] >= 0.5) * 2 + usize::from(r[1] >= 0.5)
        },
    }
}

/// A scale that jumps across the image.
fn jumping_sigma(p: &Path) -> [f64; 2] {
    if p.primary_direction().x < 0.2 {
        [0.03, 0.03]
    } else {
        [0.5, 0.5]
    }
}

fn furnace() -> AnalyticScene {
    AnalyticScene::furnace_box(ALBEDO, EMISSION).unwrap()
}

fn bidirectional(scene: &AnalyticScene) -> BidirectionalMutation<'_, AnalyticScene> {
    BidirectionalMutation::new(
        scene,
        BidirectionalParams {
            max_segments: SEGMENTS,
            ..BidirectionalParams::default()
        },
    )
    .unwrap()
}

#[test]
fn lens_and_independence_preserve_pi() {
    let scene = furnace();
    let kernel = Mh::new(
        ra_mixture(
            PerturbationKind::Lens,
            Perturbation::lens(&scene, jumping_sigma),
            IndependenceMutation::new(sampler(&scene)),
        )
        .unwrap(),
    );
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &kernel,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 10, 1),
    );
    eprintln!("{report:?}");
    report.assert_passes("lens + independence", TESTS);
}

#[test]
fn multi_chain_and_bidirectional_preserve_pi() {
    let scene = furnace();
    let kernel = Mh::new(
        ra_mixture(
            PerturbationKind::MultiChain,
            Perturbation::multi_chain(&scene, jumping_sigma),
            bidirectional(&scene),
        )
        .unwrap(),
    );
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &kernel,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 10, 2),
    );
    eprintln!("{report:?}");
    report.assert_passes("multi-chain + bidirectional", TESTS);
}

#[test]
fn bidirectional_preserves_pi() {
    let scene = furnace();
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &Mh::new(bidirectional(&scene)),
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 10, 3),
    );
    eprintln!("{report:?}");
    report.assert_passes("bidirectional", TESTS);
}

#[test]
fn negative_control_without_hastings_fails() {
    let scene = furnace();
    let kernel = MhWithoutHastings {
        proposal: bidirectional(&scene),
    };
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &kernel,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 10, 4),
    );
    eprintln!("broken: {report:?}");
    assert!(
        report.p_value < 1e-6,
        "the broken kernel passed: {report:?}"
    );
}

/// The reverse density at the current state's sigma (see `flow_balance.rs`).
#[derive(Clone)]
struct CurrentSigmaReverse<'a, Sc>(Perturbation<'a, AnalyticScene, Sc>);

impl<Sc: ScaleSource + Clone> Proposal<Path> for CurrentSigmaReverse<'_, Sc> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        let s = self.0.scale().sigmas(x);
        if !self.0.propose_with(x, y, rng, s) {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.0.log_q_with(y, x, s) - self.0.log_q_with(x, y, s))
    }
    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.0.log_q(from, to)
    }
}

#[test]
fn negative_control_current_sigma_reverse_fails() {
    let scene = furnace();
    let kernel = Mh::new(CurrentSigmaReverse(Perturbation::lens(
        &scene,
        jumping_sigma,
    )));
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &kernel,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 30, 5),
    );
    eprintln!("broken: {report:?}");
    assert!(
        report.p_value < 1e-6,
        "the broken kernel passed: {report:?}"
    );
    // The same proposal at a fixed sigma is correct and passes.
    let ok = Mh::new(CurrentSigmaReverse(Perturbation::lens(
        &scene,
        FixedScale::uniform(0.2),
    )));
    let report = stationarity_test(
        &PathTarget::new(&scene),
        &ok,
        |rng| exact_draw(&scene, rng),
        &bins(&scene),
        &StationarityParams::new(6000, 30, 6),
    );
    eprintln!("{report:?}");
    report.assert_passes("lens at fixed sigma (control of the control)", TESTS);
}
