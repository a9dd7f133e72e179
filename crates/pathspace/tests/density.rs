//! The perturbations' transition densities are the densities of what `propose` draws.
//!
//! For a fixed `x`, `E_{y ~ T(.|x)}[p(y) / T(x -> y)] = int_{reach(x)} p dmu` for any density
//! `p` (invalid candidates count 0). With `p` the independent sampler's density and `x` a path
//! whose reachable set is "every path with its structure" (the eye subpath ends at the light),
//! the right side is the probability that the sampler draws a path of that structure: known
//! in closed form in the furnace box, estimated by sampling in the test box. A density missing
//! its `sin θ` Jacobian fails the identity; so does the angular kernel's chi-square.

mod common;

use std::f64::consts::{PI, TAU};

use mcmc_core::testing::chi_square_test;
use mcmc_core::{Proposal, Proposed};
use pathspace::analytic::{AnalyticScene, Material, PinholeCamera};
use pathspace::perturb::DirectionKernel;
use pathspace::{
    eye_subpath_end, BidirectionalMutation, BidirectionalParams, BidirectionalSampler,
    BidirectionalSamplerParams, FixedScale, IndependentSampler, Path, Perturbation,
    PerturbationKind, Rgb, TruncatedNormalDirection, UnidirectionalParams, UnidirectionalSampler,
    Vec3,
};
use rand::Rng;

/// The bug: the solid-angle density without the `sin θ` Jacobian (a density "in θ and φ"
/// used as if it were per steradian); sampling is unchanged.
#[derive(Clone, Copy, Debug)]
struct WithoutSinJacobian;
impl DirectionKernel for WithoutSinJacobian {
    fn sample_angles<R: Rng + ?Sized>(&self, sigma: f64, rng: &mut R) -> (f64, f64) {
        TruncatedNormalDirection.sample_angles(sigma, rng)
    }
    fn log_density(&self, theta: f64, sigma: f64) -> f64 {
        TruncatedNormalDirection::log_polar_density(theta, sigma) - TAU.ln()
    }
}

/// Mean and standard error of `p(y) / T(x -> y)` over `n` proposals from `x`.
fn reach_mass<P: Proposal<Path>, Smp: IndependentSampler>(
    pert: &P,
    sampler: &Smp,
    x: &Path,
    n: usize,
    seed: u64,
) -> (f64, f64) {
    reach_mass_where(pert, sampler, x, n, seed, |_| true)
}

/// As [`reach_mass`], counting only candidates with `keep(y)`.
fn reach_mass_where<P: Proposal<Path>, Smp: IndependentSampler>(
    pert: &P,
    sampler: &Smp,
    x: &Path,
    n: usize,
    seed: u64,
    keep: impl Fn(&Path) -> bool,
) -> (f64, f64) {
    let mut rng = common::rng(seed);
    let mut y = Path::new();
    let values: Vec<f64> = (0..n)
        .map(|_| match pert.propose(x, &mut y, &mut rng) {
            Proposed::Move { .. } if keep(&y) => {
                (sampler.log_density(&y) - pert.log_q(x, &y)).exp()
            }
            _ => 0.0,
        })
        .collect();
    common::mean_and_se(&values)
}

#[test]
fn lens_density_in_the_furnace_box() {
    let scene = AnalyticScene::furnace_box(0.5, 1.0).unwrap();
    let n_max = 3;
    let sampler = UnidirectionalSampler::new(
        &scene,
        UnidirectionalParams {
            max_segments: n_max,
            connect_probability: 0.5,
        },
    )
    .unwrap();
    let mut rng = common::rng(1);
    let x = loop {
        let p = common::draw(&sampler, &mut rng);
        if p.segments() == 1 {
            break p;
        }
    };
    // Every camera ray hits an emitting wall: the sampler draws a one-edge path w.p. 1/3.
    let truth = 1.0 / n_max as f64;
    let lens = Perturbation::lens(&scene, FixedScale::uniform(0.5));
    let (m, se) = reach_mass(&lens, &sampler, &x, 200_000, 2);
    assert!((m - truth).abs() < 4.0 * se, "{m} +- {se} vs {truth}");
    assert!(se < 0.02 * truth, "{m} +- {se}");
    let broken =
        Perturbation::lens(&scene, FixedScale::uniform(0.5)).with_kernel(WithoutSinJacobian);
    let (mb, seb) = reach_mass(&broken, &sampler, &x, 200_000, 2);
    assert!(
        (mb - truth).abs() > 10.0 * seb.max(se),
        "the density without sin θ passed: {mb} +- {seb} vs {truth}"
    );
}

/// The bidirectional mutation can regenerate the whole path (deletion `(0, k)`), so
/// `E_{y ~ T(.|x)}[p(y) 1{y shares no vertex with x} / T(x -> y)]` is the probability that the sampler
/// succeeds, for any `x`. (Candidates that keep vertices of `x` live on a null set of the path
/// measure: they are excluded from the identity; the convergence tests cover them.)
#[test]
fn bidirectional_density_integrates_the_sampler_density() {
    let scene = mirror_room();
    let n_max = 4;
    let sampler = UnidirectionalSampler::new(
        &scene,
        UnidirectionalParams {
            max_segments: n_max,
            connect_probability: 0.5,
        },
    )
    .unwrap();
    let mutation = BidirectionalMutation::new(
        &scene,
        BidirectionalParams {
            max_segments: n_max,
            ..BidirectionalParams::default()
        },
    )
    .unwrap();
    let mut rng = common::rng(20);
    let draws = 400_000;
    let mut p = Path::new();
    let success = (0..draws)
        .filter(|_| sampler.sample(&mut rng, &mut p))
        .count() as f64
        / draws as f64;
    let success_se = (success * (1.0 - success) / draws as f64).sqrt();
    // The camera does not see the ceiling emitter: paths have 2 to 4 edges.
    // Longer paths are fully regenerated less often (p_d(0, k) = 2^{-k} / D_k): more draws.
    for (seed, edges, n) in [
        (0u64, 2usize, 1_500_000),
        (1, 3, 3_000_000),
        (2, 4, 5_000_000),
    ] {
        let x = loop {
            let p = common::draw(&sampler, &mut rng);
            if p.segments() == edges {
                break p;
            }
        };
        // Regenerated from the camera to the light: new x_2 and new light vertex.
        let fresh = |y: &Path| {
            y.vertices[1].position() != x.vertices[1].position()
                && y.vertices.last().unwrap().position() != x.vertices.last().unwrap().position()
        };
        let (m, se) = reach_mass_where(&mutation, &sampler, &x, n, 21 + seed, fresh);
        let tol = 4.5 * (se * se + success_se * success_se).sqrt();
        assert!(
            (m - success).abs() < tol && tol < 0.15 * success,
            "x with {} edges: E[p/T] = {m} +- {se}, sampler success {success} +- {success_se}",
            x.segments()
        );
    }
}

/// A box whose floor is a mirror, whose whole ceiling emits, with diffuse side walls and a
/// glass sphere: specular chains to the light are common.
fn mirror_room() -> AnalyticScene {
    let camera = PinholeCamera::look_at(
        Vec3::new(0.0, 0.3, 0.9),
        Vec3::new(0.0, -0.8, -0.6),
        Vec3::new(0.0, 1.0, 0.0),
        70.0,
        1.0,
    )
    .unwrap();
    let mut s = AnalyticScene::new(camera);
    let white = Material::Diffuse {
        albedo: Rgb::gray(0.6),
    };
    let (x, y, z) = (
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, 0.0, 2.0),
    );
    let lo = Vec3::new(-1.0, -1.0, -1.0);
    let mirror = Material::Mirror {
        reflectance: Rgb::gray(0.9),
    };
    s.add_rectangle(lo, z, x, mirror, Rgb::BLACK).unwrap(); // floor, normal +y
    s.add_rectangle(lo + y, x, z, Material::Black, Rgb::gray(2.0))
        .unwrap(); // ceiling, -y
    s.add_rectangle(lo, y, z, white, Rgb::BLACK).unwrap(); // left, +x
    s.add_rectangle(lo + x, z, y, white, Rgb::BLACK).unwrap(); // right, -x
    s.add_rectangle(lo, x, y, white, Rgb::BLACK).unwrap(); // back, +z
    s.add_rectangle(lo + z, y, x, white, Rgb::BLACK).unwrap(); // front, -z
    s.add_sphere(
        Vec3::new(0.3, -0.5, -0.3),
        0.3,
        Material::Dielectric {
            ior: 1.5,
            tint: Rgb::gray(1.0),
        },
    )
    .unwrap();
    s
}

/// The same identity through specular vertices: lens on camera -> specular -> light paths,
/// multi-chain on camera -> diffuse -> specular -> light, and on
/// camera -> specular -> diffuse -> specular -> light (two chains, each through a specular
/// vertex).
#[test]
fn perturbation_densities_through_specular_chains() {
    let scene = mirror_room();
    let sampler = UnidirectionalSampler::new(
        &scene,
        UnidirectionalParams {
            max_segments: 4,
            connect_probability: 0.5,
        },
    )
    .unwrap();
    let cases = [
        (PerturbationKind::Lens, vec![false, true, false], 0.3, 4u64),
        (
            PerturbationKind::MultiChain,
            vec![false, false, true, false],
            0.6,
            5,
        ),
        (
            PerturbationKind::MultiChain,
            vec![false, true, false, true, false],
            0.6,
            6,
        ),
    ];
    let matches = |p: &Path, pattern: &[bool]| {
        p.len() == pattern.len()
            && p.vertices
                .iter()
                .zip(pattern)
                .all(|(v, &s)| v.is_specular() == s)
    };
    let mut rng = common::rng(3);
    let draws = 1_500_000;
    let mut counts = [0usize; 3];
    let mut first: [Option<Path>; 3] = [None, None, None];
    let mut p = Path::new();
    for _ in 0..draws {
        if sampler.sample(&mut rng, &mut p) {
            for (i, case) in cases.iter().enumerate() {
                if matches(&p, &case.1) {
                    counts[i] += 1;
                    first[i].get_or_insert_with(|| p.clone());
                }
            }
        }
    }
    for (i, (kind, _, sigma, seed)) in cases.iter().enumerate() {
        let x = first[i].clone().expect("no such path");
        assert_eq!(eye_subpath_end(*kind, &x), Some(x.len() - 1));
        let prob = counts[i] as f64 / draws as f64;
        let prob_se = (prob * (1.0 - prob) / draws as f64).sqrt();
        let pert = Perturbation::new(&scene, *kind, FixedScale::uniform(*sigma));
        let (m, se) = reach_mass(&pert, &sampler, &x, 800_000, *seed);
        let tol = 4.5 * (se * se + prob_se * prob_se).sqrt();
        assert!(
            (m - prob).abs() < tol,
            "{kind:?} case {i}: E[p/T] = {m} +- {se}, sampler probability {prob} +- {prob_se}"
        );
        assert!(
            tol < 0.25 * prob,
            "{kind:?} case {i}: not informative: E[p/T] = {m} +- {se}, sampler probability \
             {prob} +- {prob_se} ({} paths)",
            counts[i]
        );
    }
}

/// The angular kernel draws what its density says: chi-square of the polar angle against
/// `2 pi sin θ p_ω(θ)` integrated over bins; the density without `sin θ` fails.
#[test]
fn angular_kernel_chi_square() {
    let sigma = 0.7;
    let bins = 40;
    let n = 100_000;
    let mut rng = common::rng(6);
    let mut observed = vec![0u64; bins];
    for _ in 0..n {
        let (theta, _) = TruncatedNormalDirection.sample_angles(sigma, &mut rng);
        observed[((theta / PI * bins as f64) as usize).min(bins - 1)] += 1;
    }
    let probabilities = |k: &dyn Fn(f64) -> f64| -> Vec<f64> {
        (0..bins)
            .map(|b| {
                let sub = 200;
                let h = PI / (bins * sub) as f64;
                (0..sub)
                    .map(|i| {
                        let t = (b * sub + i) as f64 * h + 0.5 * h;
                        TAU * t.sin() * k(t).exp() * h
                    })
                    .sum()
            })
            .collect()
    };
    let good = probabilities(&|t| TruncatedNormalDirection.log_density(t, sigma));
    chi_square_test(&observed, &good, 5.0).assert_passes("truncated normal direction", 1);
    let bad = probabilities(&|t| WithoutSinJacobian.log_density(t, sigma));
    let report = chi_square_test(&observed, &bad, 5.0);
    assert!(report.p_value < 1e-9, "missing sin θ passed: {report:?}");
}

/// The same identity for the bidirectional mutation with light-side regeneration against the
/// bidirectional sampler, whose paths include light-traced ones (`t = 1`) and caustics through
/// the mirror floor and the glass sphere that no eye walk joined to the light reaches: for any
/// `x`, `E_{y ~ T(.|x)}[p(y) 1{y shares no vertex with x} / T(x -> y)]` is the probability that
/// the sampler succeeds. Negative control: the density summed over the eye-only split alone
/// (the earlier eye-side mutation's `T`) for the same candidates misses it.
#[test]
fn light_side_bidirectional_density_integrates_the_bidirectional_sampler_density() {
    let scene = mirror_room();
    let n_max = 3;
    let sampler = BidirectionalSampler::new(
        &scene,
        BidirectionalSamplerParams {
            max_segments: n_max,
        },
    )
    .unwrap();
    let params = BidirectionalParams {
        max_segments: n_max,
        light_side: true,
    };
    let mutation = BidirectionalMutation::new(&scene, params).unwrap();
    let eye_only = BidirectionalMutation::new(
        &scene,
        BidirectionalParams {
            light_side: false,
            ..params
        },
    )
    .unwrap();
    let mut rng = common::rng(30);
    let draws = 400_000;
    let mut p = Path::new();
    let success = (0..draws)
        .filter(|_| sampler.sample(&mut rng, &mut p))
        .count() as f64
        / draws as f64;
    let success_se = (success * (1.0 - success) / draws as f64).sqrt();
    for (seed, edges, n) in [(0u64, 2usize, 1_000_000), (1, 3, 2_000_000)] {
        let x = loop {
            let p = common::draw(&sampler, &mut rng);
            if p.segments() == edges {
                break p;
            }
        };
        let fresh = |y: &Path| {
            y.vertices[1].position() != x.vertices[1].position()
                && y.vertices.last().unwrap().position() != x.vertices.last().unwrap().position()
        };
        let (m, se) = reach_mass_where(&mutation, &sampler, &x, n, 31 + seed, fresh);
        let tol = 4.5 * (se * se + success_se * success_se).sqrt();
        eprintln!("x with {edges} edges: E[p/T] = {m} +- {se}, success {success} +- {success_se}");
        assert!(
            (m - success).abs() < tol && tol < 0.15 * success,
            "x with {edges} edges: E[p/T] = {m} +- {se}, sampler success {success} +- {success_se}"
        );
        // Negative control: the same candidates weighted by the eye-only density.
        let mut rng = common::rng(31 + seed);
        let mut y = Path::new();
        let (mut sum, mut count) = (0.0, 0usize);
        for _ in 0..n / 10 {
            if let Proposed::Move { .. } = mutation.propose(&x, &mut y, &mut rng) {
                if fresh(&y) {
                    let w = (sampler.log_density(&y) - eye_only.log_q(&x, &y)).exp();
                    sum += if w.is_finite() { w } else { 1e6 };
                    count += 1;
                }
            }
        }
        let wrong = sum / (n / 10) as f64;
        eprintln!("negative control (eye-only density): {wrong} over {count} fresh candidates");
        assert!(
            (wrong - success).abs() > 10.0 * tol,
            "the eye-only density passed: {wrong} vs {success}"
        );
    }
}
