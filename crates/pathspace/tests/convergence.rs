//! Path-space MLT converges to closed-form values on the white furnace box.
//!
//! In the closed furnace box (every wall Lambertian with albedo `rho` and emitting `L_e`), the
//! radiance carried along any camera ray by paths of exactly `j` edges is `L_e rho^{j-1}`, so
//! under the normalised target `pi / b` (paths of at most `n` edges) the share of paths with
//! `j` edges is `rho^{j-1} / sum_{i<n} rho^i` and the share with a raster position in the left
//! half of the image is exactly 1/2. MH over the RA mixture (section 8.1) of a perturbation and
//! the independence mutation must reproduce them: `R` independent chains (starts resampled
//! from independent samples in proportion to `f/p`), the replicate mean within 4 standard
//! errors of the truth. Negative controls (MH without the Hastings term; the perturbation's
//! reverse density at the current state's sigma) must miss by more than that.

mod common;

use mcmc_core::testing::MhWithoutHastings;
use mcmc_core::{Chain, Kernel, Mh, NoAdaptation, Proposal, Proposed};
use pathspace::analytic::AnalyticScene;
use pathspace::{
    ra_mixture, FixedScale, IndependenceMutation, IndependentSampler, Path, PathTarget,
    Perturbation, PerturbationKind, ScaleSource, UnidirectionalParams, UnidirectionalSampler,
};
use rand::{Rng, RngExt};

const ALBEDO: f64 = 0.5;
const SEGMENTS: usize = 3;
const CHAINS: u64 = 32;
const STEPS: usize = 20_000;
const BOX_CHAINS: u64 = 96;
const BOX_STEPS: usize = 8_000;

fn furnace() -> AnalyticScene {
    AnalyticScene::furnace_box(ALBEDO, 1.0).unwrap()
}

fn sampler(scene: &AnalyticScene) -> UnidirectionalSampler<'_, AnalyticScene> {
    UnidirectionalSampler::new(
        scene,
        UnidirectionalParams {
            max_segments: SEGMENTS,
            connect_probability: 0.5,
        },
    )
    .unwrap()
}

/// A start resampled from 64 independent paths in proportion to `f / p`.
fn start<R: Rng>(scene: &AnalyticScene, rng: &mut R) -> Path {
    let sampler = sampler(scene);
    let candidates: Vec<(Path, f64)> = (0..64)
        .map(|_| {
            let p = common::draw(&sampler, rng);
            let w = p.contribution(scene).luminance() / sampler.log_density(&p).exp();
            (p, w)
        })
        .collect();
    let total: f64 = candidates.iter().map(|c| c.1).sum();
    let mut u = rng.random::<f64>() * total;
    for (p, w) in &candidates {
        if u < *w {
            return p.clone();
        }
        u -= w;
    }
    candidates.last().unwrap().0.clone()
}

/// Per-chain means of `[1{1 edge}, 1{2 edges}, 1{3 edges}, 1{left half}]`.
fn run<K: Kernel<PathTarget<'static, AnalyticScene>> + Clone>(
    scene: &'static AnalyticScene,
    kernel: K,
    seed: u64,
) -> Vec<[f64; 4]> {
    let target = PathTarget::new(scene);
    (0..CHAINS)
        .map(|c| {
            let mut rng = common::rng(seed * 1000 + c);
            let x0 = start(scene, &mut rng);
            let mut chain = Chain::new(&target, kernel.clone(), NoAdaptation, rng, x0).unwrap();
            let mut sums = [0.0; 4];
            for _ in 0..STEPS {
                chain.step(&mut ()).unwrap();
                let x = &chain.current().state;
                sums[x.segments() - 1] += 1.0;
                sums[3] += f64::from(u8::from(chain.current().payload.raster[0] < 0.5));
            }
            sums.map(|s| s / STEPS as f64)
        })
        .collect()
}

fn truth() -> [f64; 4] {
    let norm: f64 = (0..SEGMENTS).map(|j| ALBEDO.powi(j as i32)).sum();
    [1.0 / norm, ALBEDO / norm, ALBEDO * ALBEDO / norm, 0.5]
}

/// `(deviation / standard error)` per statistic.
fn z_scores(per_chain: &[[f64; 4]]) -> [f64; 4] {
    let t = truth();
    std::array::from_fn(|i| {
        let v: Vec<f64> = per_chain.iter().map(|c| c[i]).collect();
        let (m, se) = common::mean_and_se(&v);
        eprintln!("  statistic {i}: {m:.5} +- {se:.5} (truth {:.5})", t[i]);
        (m - t[i]) / se
    })
}

fn leak(scene: AnalyticScene) -> &'static AnalyticScene {
    Box::leak(Box::new(scene))
}

/// A scale that jumps across the image: small on the left, large on the right.
fn jumping_sigma(p: &Path) -> [f64; 2] {
    if p.primary_direction().x < 0.2 {
        [0.02, 0.02]
    } else {
        [0.4, 0.4]
    }
}

#[test]
fn lens_mixture_converges() {
    let scene = leak(furnace());
    let m = ra_mixture(
        PerturbationKind::Lens,
        Perturbation::lens(scene, FixedScale::uniform(0.1)),
        IndependenceMutation::new(sampler(scene)),
    )
    .unwrap();
    let z = z_scores(&run(scene, Mh::new(m), 1));
    assert!(z.iter().all(|z| z.abs() < 4.0), "z scores {z:?}");
}

#[test]
fn multi_chain_mixture_with_jumping_sigma_converges() {
    let scene = leak(furnace());
    let m = ra_mixture(
        PerturbationKind::MultiChain,
        Perturbation::multi_chain(scene, jumping_sigma),
        IndependenceMutation::new(sampler(scene)),
    )
    .unwrap();
    let z = z_scores(&run(scene, Mh::new(m), 2));
    assert!(z.iter().all(|z| z.abs() < 4.0), "z scores {z:?}");
}

/// The bidirectional mutation (subpath delete / eye-side regenerate) as the global move,
/// alone and mixed with the lens perturbation.
#[test]
fn bidirectional_converges() {
    let scene = leak(furnace());
    let bidir = common::bidirectional(scene, SEGMENTS);
    let z = z_scores(&run(scene, Mh::new(bidir), 5));
    assert!(z.iter().all(|z| z.abs() < 4.0), "alone: z scores {z:?}");
    let m = ra_mixture(
        PerturbationKind::Lens,
        Perturbation::lens(scene, jumping_sigma),
        bidir,
    )
    .unwrap();
    let z = z_scores(&run(scene, Mh::new(m), 6));
    assert!(z.iter().all(|z| z.abs() < 4.0), "with lens: z scores {z:?}");
}

#[test]
fn negative_control_without_hastings_fails() {
    let scene = leak(furnace());
    let m = ra_mixture(
        PerturbationKind::Lens,
        Perturbation::lens(scene, FixedScale::uniform(0.1)),
        IndependenceMutation::new(sampler(scene)),
    )
    .unwrap();
    let z = z_scores(&run(scene, MhWithoutHastings { proposal: m }, 3));
    assert!(
        z.iter().any(|z| z.abs() > 8.0),
        "the broken kernel passed: z {z:?}"
    );
}

/// The reverse density at the current state's sigma (see `flow_balance.rs`).
#[derive(Clone)]
struct CurrentSigmaReverse<Sc>(Perturbation<'static, AnalyticScene, Sc>);

impl<Sc: ScaleSource + Clone> Proposal<Path> for CurrentSigmaReverse<Sc> {
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
    let scene = leak(furnace());
    let m = ra_mixture(
        PerturbationKind::Lens,
        CurrentSigmaReverse(Perturbation::lens(scene, jumping_sigma)),
        IndependenceMutation::new(sampler(scene)),
    )
    .unwrap();
    let z = z_scores(&run(scene, Mh::new(m), 4));
    assert!(
        z.iter().any(|z| z.abs() > 8.0),
        "the broken kernel passed: z {z:?}"
    );
}

/// The test box (glossy, mirror and glass, a small emitter): MLT over the RA mixture with the
/// multi-chain perturbation at a state-dependent scale agrees with an importance-sampling
/// reference from the independent sampler (self-normalised, `2 * 10^6` paths) on the share of
/// `pi`-mass through a specular vertex, with 2 edges, and in the left half of the image
/// (96 chains of 8000 steps: fewer, longer chains under-estimate the replicate spread, as
/// chains occasionally linger on bright caustic paths).
#[test]
fn test_box_multi_chain_matches_importance_sampling() {
    let scene = leak(AnalyticScene::test_box().unwrap());
    let sampler = box_sampler(scene);
    let kernel = Mh::new(
        ra_mixture(
            PerturbationKind::MultiChain,
            Perturbation::multi_chain(scene, jumping_sigma),
            IndependenceMutation::new(sampler),
        )
        .unwrap(),
    );
    test_box_against_reference(scene, kernel, 5000);
}

/// As above with the bidirectional mutation as the global move (it regenerates subpaths
/// through specular vertices, where regenerated vertices may coincide with old ones).
#[test]
fn test_box_bidirectional_matches_importance_sampling() {
    let scene = leak(AnalyticScene::test_box().unwrap());
    let bidir = common::bidirectional(scene, 4);
    let kernel = Mh::new(
        ra_mixture(
            PerturbationKind::MultiChain,
            Perturbation::multi_chain(scene, jumping_sigma),
            bidir,
        )
        .unwrap(),
    );
    test_box_against_reference(scene, kernel, 6000);
}

fn box_sampler(scene: &'static AnalyticScene) -> UnidirectionalSampler<'static, AnalyticScene> {
    let params = UnidirectionalParams {
        max_segments: 4,
        connect_probability: 0.5,
    };
    UnidirectionalSampler::new(scene, params).unwrap()
}

fn test_box_against_reference<K: Kernel<PathTarget<'static, AnalyticScene>> + Clone>(
    scene: &'static AnalyticScene,
    kernel: K,
    seed: u64,
) {
    let sampler = box_sampler(scene);
    let stats = |p: &Path, raster: [f64; 2]| -> [f64; 3] {
        [
            f64::from(u8::from(p.vertices.iter().any(|v| v.is_specular()))),
            f64::from(u8::from(p.segments() == 2)),
            f64::from(u8::from(raster[0] < 0.5)),
        ]
    };
    // Reference: self-normalised importance sampling in 40 batches.
    let mut rng = common::rng(77);
    let batches: Vec<(f64, [f64; 3])> = (0..40)
        .map(|_| {
            let (mut w_sum, mut h_sum) = (0.0, [0.0; 3]);
            let mut p = Path::new();
            for _ in 0..50_000 {
                if sampler.sample(&mut rng, &mut p) {
                    let f = p.contribution(scene).luminance();
                    if f > 0.0 {
                        let w = f / sampler.log_density(&p).exp();
                        let h = stats(&p, p.raster(scene).unwrap());
                        w_sum += w;
                        for i in 0..3 {
                            h_sum[i] += w * h[i];
                        }
                    }
                }
            }
            (w_sum, h_sum)
        })
        .collect();
    let w_total: f64 = batches.iter().map(|b| b.0).sum();
    let target = PathTarget::new(scene);
    let per_chain: Vec<[f64; 3]> = (0..BOX_CHAINS)
        .map(|c| {
            let mut rng = common::rng(seed * 1000 + c);
            // Start: resample 256 independent paths in proportion to f/p.
            let cands: Vec<(Path, f64)> = (0..256)
                .map(|_| {
                    let p = common::draw(&sampler, &mut rng);
                    let w = p.contribution(scene).luminance() / sampler.log_density(&p).exp();
                    (p, w)
                })
                .collect();
            let total: f64 = cands.iter().map(|c| c.1).sum();
            let mut u = rng.random::<f64>() * total;
            let x0 = cands
                .iter()
                .find(|(_, w)| {
                    let hit = u < *w;
                    u -= w;
                    hit
                })
                .unwrap_or(cands.last().unwrap())
                .0
                .clone();
            let mut chain = Chain::new(&target, kernel.clone(), NoAdaptation, rng, x0).unwrap();
            let mut sums = [0.0; 3];
            for _ in 0..BOX_STEPS {
                chain.step(&mut ()).unwrap();
                let cur = chain.current();
                let h = stats(&cur.state, cur.payload.raster);
                for i in 0..3 {
                    sums[i] += h[i];
                }
            }
            sums.map(|s| s / BOX_STEPS as f64)
        })
        .collect();
    for i in 0..3 {
        // Reference ratio estimate and its delta-method standard error over batches.
        let r = batches.iter().map(|b| b.1[i]).sum::<f64>() / w_total;
        let resid: Vec<f64> = batches.iter().map(|b| b.1[i] - r * b.0).collect();
        let nb = batches.len() as f64;
        let mean_w = w_total / nb;
        let var = resid.iter().map(|e| e * e).sum::<f64>() / (nb - 1.0);
        let ref_se = (var / nb).sqrt() / mean_w;
        let v: Vec<f64> = per_chain.iter().map(|c| c[i]).collect();
        let (m, se) = common::mean_and_se(&v);
        let z = (m - r) / (se * se + ref_se * ref_se).sqrt();
        eprintln!(
            "statistic {i}: MLT {m:.5} +- {se:.5}, reference {r:.5} +- {ref_se:.5}, z {z:.2}"
        );
        assert!(z.abs() < 4.0, "statistic {i}: z = {z}");
    }
}
