//! Regional-adaptive path-space MLT through mcmc-core's `RenderLoop` on the analytic scenes:
//! shared statistics are deterministic for 1, 2 and 3 rayon threads (the paper's immediate,
//! lock-based sharing is not: negative control); RA-MLT converges to the furnace box's closed
//! form (MLT without the Hastings term does not: negative control); on a scene whose two image
//! halves need different scales the shared regional controller brings both halves' acceptance
//! to the target within 0.05, a global controller cannot; on that scene the regional kernel
//! with frozen scales preserves `pi` from exact starts (the reverse density at the current
//! state's region scale does not: negative control).

mod common;

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

use mcmc_core::controller::AdaptState;
use mcmc_core::render_loop::{
    ChainSlot, IndependentStates, LoopBudget, LoopOutput, LoopSettings, RenderLoop,
    SharedController, Splat, SplatGrid,
};
use mcmc_core::{
    Chain, Controller, Kernel, Mh, NoAdaptation, NoProgress, Partition, Proposal, Proposed,
    StepInfo, Target,
};
use pathspace::analytic::{AnalyticScene, Material, PinholeCamera};
use pathspace::regional::{
    DirectionPartition, HasSharedSigmas, PathPartition, PlanePartition, PooledRegionalStats,
    RegionalAdaptParams, RegionalSigmas, ScreenPartition, SharedRegionalAdaptation, SharedSigmas,
};
use pathspace::{
    ra_mixture, BidirectionalMutation, IndependentSampler, Path, PathContribution, PathTarget,
    Perturbation, PerturbationKind, Rgb, UnidirectionalParams, UnidirectionalSampler, Vec3,
};
use rand::{Rng, SeedableRng};

type Part = PathPartition<&'static AnalyticScene>;

fn leak<T>(t: T) -> &'static T {
    Box::leak(Box::new(t))
}

/// `PathTarget` with a splat on a `width x rows` grid: column from the raster x, row from the
/// path length (`segments - 1`), or from the raster y if `by_length` is false.
struct SplatTarget {
    inner: PathTarget<'static, AnalyticScene>,
    width: usize,
    by_length: bool,
    rows: usize,
}

impl Target for SplatTarget {
    type State = Path;
    type Payload = Option<Splat>;
    fn evaluate(&self, x: &mut Path, out: &mut Option<Splat>) -> f64 {
        let mut c = PathContribution::default();
        let ld = self.inner.evaluate(x, &mut c);
        *out = (ld > f64::NEG_INFINITY).then(|| {
            let row = if self.by_length {
                (x.segments() - 1) as f64 + 0.5
            } else {
                c.raster[1] * self.rows as f64
            };
            Splat {
                raster: [(c.raster[0] * self.width as f64) as f32, row as f32],
                rgb: c.rgb.0.map(|v| v as f32),
            }
        });
        ld
    }
}

/// Independent paths from the unidirectional sampler, weight `f / p`.
struct PathStates(UnidirectionalSampler<'static, AnalyticScene>);

impl IndependentStates<Path> for PathStates {
    fn empty(&self) -> Path {
        Path::new()
    }
    fn independent(&self, key: u64, state: &mut Path) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(key);
        if !self.0.sample(&mut rng, state) {
            state.vertices.clear();
        }
    }
    fn weight(&self, state: &Path, log_density: f64) -> f64 {
        if state.is_empty() || log_density == f64::NEG_INFINITY {
            0.0
        } else {
            (log_density - self.0.log_density(state)).exp()
        }
    }
}

fn sampler(
    scene: &'static AnalyticScene,
    segments: usize,
) -> UnidirectionalSampler<'static, AnalyticScene> {
    UnidirectionalSampler::new(
        scene,
        UnidirectionalParams {
            max_segments: segments,
            connect_probability: 0.5,
        },
    )
    .unwrap()
}

fn bidirectional(
    scene: &'static AnalyticScene,
    segments: usize,
) -> BidirectionalMutation<'static, AnalyticScene> {
    common::bidirectional(scene, segments)
}

/// The RA mixture (section 8.1) of a regional perturbation and the bidirectional mutation.
fn kernel(
    scene: &'static AnalyticScene,
    kind: PerturbationKind,
    sigmas: &SharedSigmas<Part>,
    segments: usize,
) -> impl Kernel<SplatTarget> + HasSharedSigmas<Partition = Part> + Clone + Send {
    Mh::new(
        ra_mixture(
            kind,
            Perturbation::new(scene, kind, sigmas.clone()),
            bidirectional(scene, segments),
        )
        .unwrap(),
    )
}

fn screen_quadtree(scene: &'static AnalyticScene) -> Part {
    PathPartition::Screen(ScreenPartition::new(
        scene,
        PlanePartition::quadtree(8).unwrap(),
    ))
}

fn direction_quadtree(scene: &'static AnalyticScene) -> Part {
    PathPartition::Direction(
        DirectionPartition::new(scene, 2, PlanePartition::quadtree(8).unwrap()).unwrap(),
    )
}

fn run_in_pool<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

fn settings(seed: u64, chains: usize, mutations: u64, round: u64) -> LoopSettings {
    LoopSettings {
        chains,
        bootstrap_samples: 4000,
        budget: LoopBudget::Mutations(mutations),
        seed,
        round_mutations: round,
        jobs: 5,
        ..LoopSettings::default()
    }
}

fn furnace() -> &'static AnalyticScene {
    leak(AnalyticScene::furnace_box(0.5, 1.0).unwrap())
}

/// One regional-adaptive render of the furnace box on a 4 x 3 grid.
fn ra_render(
    threads: usize,
    kind: PerturbationKind,
    partition: Part,
    params: RegionalAdaptParams,
) -> LoopOutput<SplatGrid, PooledRegionalStats<Part>> {
    let scene = furnace();
    let sigmas = SharedSigmas::new(RegionalSigmas::new(partition, 1.0, 0.5).unwrap());
    let target = SplatTarget {
        inner: PathTarget::new(scene),
        width: 4,
        by_length: false,
        rows: 3,
    };
    let states = PathStates(sampler(scene, 3));
    run_in_pool(threads, || {
        RenderLoop {
            targets: std::slice::from_ref(&target),
            states: &states,
            kernel: |_| kernel(scene, kind, &sigmas, 3),
            controller: |_| SharedRegionalAdaptation::new(params).unwrap(),
            sink: || SplatGrid::new(4, 3),
        }
        .run(
            &settings(7, 12, 36_000, 250),
            &NoProgress,
            &AtomicBool::new(false),
        )
        .unwrap()
    })
}

fn refining_params() -> RegionalAdaptParams {
    RegionalAdaptParams {
        split_after_visits: Some(300),
        refine_every: 6_000,
        ..RegionalAdaptParams::otsu2018()
    }
}

fn bits(grid: &SplatGrid) -> Vec<[u64; 3]> {
    grid.pixels().iter().map(|p| p.map(f64::to_bits)).collect()
}

fn lambda_bits(out: &LoopOutput<SplatGrid, PooledRegionalStats<Part>>) -> Vec<u64> {
    let sigmas = out
        .shared
        .sigmas()
        .expect("the controller pooled statistics");
    sigmas.get().lambdas().iter().map(|l| l.to_bits()).collect()
}

#[test]
fn shared_statistics_are_identical_for_1_2_3_threads() {
    for (kind, partition) in [
        (PerturbationKind::Lens, screen_quadtree(furnace())),
        (PerturbationKind::MultiChain, direction_quadtree(furnace())),
    ] {
        let outs: Vec<_> = [1, 2, 3]
            .map(|t| ra_render(t, kind, partition.clone(), refining_params()))
            .into();
        let o = &outs[0];
        eprintln!(
            "{kind:?}: {} mutations, {} rounds, {} refinements, {} splits, {} regions, acceptance {:.3}",
            o.mutations,
            o.shared.rounds(),
            o.shared.refinements(),
            o.shared.splits(),
            o.shared.num_regions(),
            o.stats.acceptance_rate()
        );
        assert_eq!(o.mutations, 36_000);
        assert!(
            o.shared.refinements() >= 5 && o.shared.splits() >= 3,
            "refinement exercised"
        );
        for other in &outs[1..] {
            assert_eq!(bits(&o.sink), bits(&other.sink), "{kind:?}: images differ");
            assert_eq!(
                lambda_bits(o),
                lambda_bits(other),
                "{kind:?}: scales differ"
            );
            assert_eq!(o.shared.num_regions(), other.shared.num_regions());
        }
    }
}

/// The paper's scheme (section 7): every chain updates one shared set of statistics under a
/// lock as soon as `L` visits are counted and proposes with the newest scales. Correct as
/// adaptive MCMC, but the image depends on the thread interleaving.
#[derive(Clone)]
struct Immediate {
    shared: Arc<Mutex<(RegionalSigmas<Part>, Vec<AdaptState>)>>,
    region: usize,
}

impl<K: HasSharedSigmas<Partition = Part>> Controller<K, Path> for Immediate {
    fn before_step(&mut self, kernel: &K, x: &Path) {
        self.region = kernel.shared_sigmas().unwrap().get().partition().region(x);
    }
    fn after_step(&mut self, kernel: &mut K, info: &StepInfo) {
        if info.component != 0 {
            return;
        }
        let mut guard = self.shared.lock().unwrap();
        let (sigmas, states) = &mut *guard;
        let k = self.region;
        let lambda = sigmas.lambdas()[k];
        if let Some(new) = states[k].record(
            info.accept_prob[0],
            lambda,
            &RegionalAdaptParams::otsu2018().adapt,
        ) {
            sigmas.set_lambda(k, new);
        }
        *kernel.shared_sigmas_mut().unwrap() = SharedSigmas::new(sigmas.clone());
    }
    fn is_frozen(&self) -> bool {
        false
    }
}

impl<K> SharedController<K> for Immediate {
    type Shared = ();
    fn contribute(&mut self, _kernel: &mut K, _pooled: &mut ()) {}
    fn receive(&mut self, _kernel: &mut K, _pooled: &()) {}
}

#[test]
fn negative_control_immediate_lock_sharing_depends_on_threads() {
    let scene = furnace();
    let partition = PathPartition::Screen(ScreenPartition::new(
        scene,
        PlanePartition::grid(4).unwrap(),
    ));
    let target = SplatTarget {
        inner: PathTarget::new(scene),
        width: 4,
        by_length: false,
        rows: 3,
    };
    let states = PathStates(sampler(scene, 3));
    let render = |threads: usize| {
        let sigmas = RegionalSigmas::new(partition.clone(), 1.0, 1.0).unwrap();
        let shared = Arc::new(Mutex::new((sigmas.clone(), vec![AdaptState::new(); 16])));
        let start = SharedSigmas::new(sigmas);
        run_in_pool(threads, || {
            RenderLoop {
                targets: std::slice::from_ref(&target),
                states: &states,
                kernel: |_| kernel(scene, PerturbationKind::Lens, &start, 3),
                controller: |_| Immediate {
                    shared: Arc::clone(&shared),
                    region: 0,
                },
                sink: || SplatGrid::new(4, 3),
            }
            .run(
                &settings(7, 12, 36_000, 250),
                &NoProgress,
                &AtomicBool::new(false),
            )
            .unwrap()
        })
    };
    let one = bits(&render(1).sink);
    // Up to three tries: a 3-thread pool whose workers never get a core (a loaded machine)
    // would run the jobs in order, like one thread.
    let differ = (0..3).any(|_| bits(&render(3).sink) != one);
    eprintln!("immediate lock-based sharing: 1 vs 3 threads differ: {differ}");
    assert!(differ, "immediate sharing happened to be reproducible");
}

/// Path-length and left-half shares of the furnace box (closed form, as in `convergence.rs`).
fn furnace_truth(albedo: f64, segments: usize) -> Vec<f64> {
    let norm: f64 = (0..segments).map(|j| albedo.powi(j as i32)).sum();
    let mut t: Vec<f64> = (0..segments)
        .map(|j| albedo.powi(j as i32) / norm)
        .collect();
    t.push(0.5);
    t
}

/// Shares of one render: rows = path lengths, columns 0-1 = left half of the image.
fn shares(grid: &SplatGrid, segments: usize) -> Vec<f64> {
    let lum = |p: [f64; 3]| Rgb(p).luminance();
    let total: f64 = grid.pixels().iter().map(|&p| lum(p)).sum();
    let mut s: Vec<f64> = (0..segments)
        .map(|r| (0..4).map(|c| lum(grid.get(c, r))).sum::<f64>() / total)
        .collect();
    s.push(
        (0..segments)
            .flat_map(|r| (0..2).map(move |c| (c, r)))
            .map(|(c, r)| lum(grid.get(c, r)))
            .sum::<f64>()
            / total,
    );
    s
}

/// MH over the RA mixture without the Hastings term (the broken kernel of the control).
#[derive(Clone)]
struct NoHastings<P>(P);

impl<P: Proposal<Path>> Proposal<Path> for NoHastings<P> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        match self.0.propose(x, y, rng) {
            Proposed::Move { component, .. } => Proposed::Move {
                log_hastings: 0.0,
                component,
            },
            invalid => invalid,
        }
    }
    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.0.log_q(from, to)
    }
}

impl<P: HasSharedSigmas> HasSharedSigmas for NoHastings<P> {
    type Partition = P::Partition;
    fn shared_sigmas(&self) -> Option<&SharedSigmas<P::Partition>> {
        self.0.shared_sigmas()
    }
    fn shared_sigmas_mut(&mut self) -> Option<&mut SharedSigmas<P::Partition>> {
        self.0.shared_sigmas_mut()
    }
}

/// `z` scores of the replicate means of the shares against the closed form.
fn convergence_z(kind: PerturbationKind, hastings: bool, seed: u64) -> Vec<f64> {
    const SEGMENTS: usize = 3;
    const REPLICATES: u64 = 8;
    let scene = leak(AnalyticScene::furnace_box(0.5, 1.0).unwrap());
    let target = SplatTarget {
        inner: PathTarget::new(scene),
        width: 4,
        by_length: true,
        rows: SEGMENTS,
    };
    let states = PathStates(sampler(scene, SEGMENTS));
    let partition = match kind {
        PerturbationKind::Lens => screen_quadtree(scene),
        PerturbationKind::MultiChain => direction_quadtree(scene),
    };
    let params = RegionalAdaptParams {
        split_after_visits: Some(2_000),
        refine_every: 40_000,
        ..RegionalAdaptParams::otsu2018()
    };
    let per_replicate: Vec<Vec<f64>> = (0..REPLICATES)
        .map(|r| {
            let sigmas =
                SharedSigmas::new(RegionalSigmas::new(partition.clone(), 1.0, 1.0).unwrap());
            let mixture = ra_mixture(
                kind,
                Perturbation::new(scene, kind, sigmas),
                bidirectional(scene, SEGMENTS),
            )
            .unwrap();
            let s = settings(seed * 100 + r, 64, 320_000, 500);
            let controller = |_: ChainSlot| SharedRegionalAdaptation::new(params).unwrap();
            let sink = || SplatGrid::new(4, SEGMENTS);
            let out = if hastings {
                RenderLoop {
                    targets: std::slice::from_ref(&target),
                    states: &states,
                    kernel: |_| Mh::new(mixture.clone()),
                    controller,
                    sink,
                }
                .run(&s, &NoProgress, &AtomicBool::new(false))
                .unwrap()
            } else {
                RenderLoop {
                    targets: std::slice::from_ref(&target),
                    states: &states,
                    kernel: |_| Mh::new(NoHastings(mixture.clone())),
                    controller,
                    sink,
                }
                .run(&s, &NoProgress, &AtomicBool::new(false))
                .unwrap()
            };
            assert!(out.shared.num_regions() > 1);
            shares(&out.sink, SEGMENTS)
        })
        .collect();
    let truth = furnace_truth(0.5, SEGMENTS);
    (0..truth.len())
        .map(|i| {
            let v: Vec<f64> = per_replicate.iter().map(|s| s[i]).collect();
            let (m, se) = common::mean_and_se(&v);
            eprintln!(
                "  {kind:?} hastings={hastings}: share {i}: {m:.5} +- {se:.5} (truth {:.5})",
                truth[i]
            );
            (m - truth[i]) / se
        })
        .collect()
}

#[test]
fn ra_lens_converges_to_the_closed_form() {
    let z = convergence_z(PerturbationKind::Lens, true, 1);
    assert!(z.iter().all(|z| z.abs() < 4.0), "z {z:?}");
}

#[test]
fn ra_multi_chain_converges_to_the_closed_form() {
    let z = convergence_z(PerturbationKind::MultiChain, true, 2);
    assert!(z.iter().all(|z| z.abs() < 4.0), "z {z:?}");
}

#[test]
fn negative_control_without_hastings_misses() {
    let z = convergence_z(PerturbationKind::Lens, false, 3);
    assert!(
        z.iter().any(|z| z.abs() > 8.0),
        "the broken kernel passed: z {z:?}"
    );
}

/// A wall whose left half is a sharp glossy reflector (Phong exponent 3000) and right half is
/// Lambertian, facing a large emitter behind the pinhole: lens perturbations need a much
/// smaller scale on the left than on the right.
fn two_material_scene() -> &'static AnalyticScene {
    let camera = PinholeCamera::look_at(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(0.0, 1.0, 0.0),
        50.0,
        1.0,
    )
    .unwrap();
    let mut scene = AnalyticScene::new(camera);
    let glossy = Material::Phong {
        diffuse: Rgb::BLACK,
        specular: Rgb::gray(0.9),
        exponent: 3000.0,
    };
    let diffuse = Material::Diffuse {
        albedo: Rgb::gray(0.8),
    };
    let (u, v) = (Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, 6.0, 0.0));
    scene
        .add_rectangle(Vec3::new(-3.0, -3.0, -2.0), u, v, glossy, Rgb::BLACK)
        .unwrap();
    scene
        .add_rectangle(Vec3::new(0.0, -3.0, -2.0), u, v, diffuse, Rgb::BLACK)
        .unwrap();
    scene
        .add_rectangle(
            Vec3::new(3.0, -3.0, 1.0),
            Vec3::new(-6.0, 0.0, 0.0),
            Vec3::new(0.0, 6.0, 0.0),
            diffuse,
            Rgb::gray(1.0),
        )
        .unwrap();
    leak(scene)
}

/// Mean acceptance probability of lens proposals from the left and right image halves, with
/// the scales learned by a render loop, frozen.
fn learned_halves(partition: Part) -> [f64; 2] {
    let scene = two_material_scene();
    let target = SplatTarget {
        inner: PathTarget::new(scene),
        width: 2,
        by_length: false,
        rows: 2,
    };
    let states = PathStates(sampler(scene, 2));
    let sigmas = SharedSigmas::new(RegionalSigmas::new(partition, 1.0, 1.0).unwrap());
    let params = RegionalAdaptParams {
        split_after_visits: None,
        ..RegionalAdaptParams::otsu2018()
    };
    let out = RenderLoop {
        targets: std::slice::from_ref(&target),
        states: &states,
        kernel: |_| kernel(scene, PerturbationKind::Lens, &sigmas, 2),
        controller: |_| SharedRegionalAdaptation::new(params).unwrap(),
        sink: || SplatGrid::new(2, 2),
    }
    .run(
        &settings(11, 32, 800_000, 25),
        &NoProgress,
        &AtomicBool::new(false),
    )
    .unwrap();
    let learned = out.shared.sigmas().unwrap().clone();
    let sig: Vec<f64> = (0..learned.get().num_regions())
        .map(|k| learned.get().sigmas_of_region(k)[0])
        .collect();
    eprintln!("learned sigma per region: {sig:.4?}");
    eprintln!(
        "{} rounds, updates per region {:?}",
        out.shared.rounds(),
        (0..out.shared.num_regions())
            .map(|k| out.shared.region_stats(k).unwrap().adapt.updates - 1)
            .collect::<Vec<_>>()
    );
    // Measure with the learned scales frozen: 16 chains from the bootstrap's sampler.
    let k = kernel(scene, PerturbationKind::Lens, &learned, 2);
    let smp = sampler(scene, 2);
    let (mut sum, mut count) = ([0.0; 2], [0u64; 2]);
    for c in 0..16 {
        let mut rng = common::rng(500 + c);
        let x0 = common::lit_path(scene, &smp, &mut rng);
        let mut chain = Chain::new(&target, k.clone(), NoAdaptation, rng, x0).unwrap();
        for _ in 0..6000 {
            let half = usize::from(chain.state().raster(scene).unwrap()[0] >= 0.5);
            let info = chain.step(&mut ()).unwrap();
            if info.component == 0 {
                sum[half] += info.accept_prob[0];
                count[half] += 1;
            }
        }
    }
    let acc = [sum[0] / count[0] as f64, sum[1] / count[1] as f64];
    eprintln!(
        "acceptance left {:.3} ({} proposals), right {:.3} ({})",
        acc[0], count[0], acc[1], count[1]
    );
    acc
}

#[test]
fn shared_regional_controller_reaches_the_target_in_both_halves_global_cannot() {
    let scene = two_material_scene();
    let regional = learned_halves(PathPartition::Screen(ScreenPartition::new(
        scene,
        PlanePartition::grid(2).unwrap(),
    )));
    for a in regional {
        assert!((a - 0.5).abs() < 0.05, "regional: acceptance {regional:?}");
    }
    let global = learned_halves(PathPartition::Single);
    assert!(
        global.iter().any(|a| (a - 0.5).abs() > 0.05),
        "a global scale reached the target in both halves: {global:?}"
    );
}

/// An exact draw from `pi / b` on the two-material scene by rejection from the sampler:
/// `f / p <= N / (1 - c) * max(albedo, k_s (e + 2) / (e + 1)) * L_e` (the hit technique's
/// BSDF sampling cancels the BSDF up to that factor; the camera importance cancels its
/// direction density), here `2 / 0.5 * 0.9003 < 3.7`.
fn exact_two_material(scene: &'static AnalyticScene, rng: &mut rand_pcg::Pcg64) -> Path {
    let smp = sampler(scene, 2);
    let bound = 3.7;
    loop {
        let p = common::draw(&smp, rng);
        let ratio = p.contribution(scene).luminance() / smp.log_density(&p).exp();
        assert!(ratio <= bound, "f/p = {ratio} exceeds the bound");
        if rand::RngExt::random::<f64>(rng) * bound < ratio {
            return p;
        }
    }
}

/// With the two-material scene's learned scales frozen (left ~0.02, right ~0.3: two regions
/// that need different scales), 300 steps of the regional lens + bidirectional kernel from
/// 6000 exact starts leave the distribution of the raster position (4 x 2 bins) unchanged: a
/// two-sample chi-square against 6000 independent exact draws. Negative control: the lens
/// with the reverse density at the current state's region scale moves mass to the left.
#[test]
fn two_region_kernel_with_frozen_learned_scales_preserves_pi() {
    use mcmc_core::testing::chi_square_two_sample;
    let scene = two_material_scene();
    let sigmas = {
        let part = PathPartition::Screen(ScreenPartition::new(
            scene,
            PlanePartition::grid(2).unwrap(),
        ));
        let mut s = RegionalSigmas::new(part, 0.0, 1.0).unwrap();
        for (k, sigma) in [0.022f64, 0.30, 0.019, 0.30].into_iter().enumerate() {
            s.set_lambda(k, (sigma * sigma).ln());
        }
        SharedSigmas::new(s)
    };
    let target = PathTarget::new(scene);
    let bin = |p: &Path| {
        let r = p.raster(scene).unwrap();
        ((r[0] * 4.0) as usize).min(3) * 2 + usize::from(r[1] >= 0.5)
    };
    const STARTS: u64 = 6000;
    const STEPS: u64 = 300;
    let mut reference = vec![0u64; 8];
    let mut rng = common::rng(900);
    for _ in 0..STARTS {
        reference[bin(&exact_two_material(scene, &mut rng))] += 1;
    }
    let stepped = |kernel: &dyn Fn() -> Box<dyn FnMut(Path, rand_pcg::Pcg64) -> Path>| {
        let mut counts = vec![0u64; 8];
        for i in 0..STARTS {
            let mut rng = common::rng(10_000 + i);
            let x0 = exact_two_material(scene, &mut rng);
            counts[bin(&kernel()(x0, rng))] += 1;
        }
        counts
    };
    let correct = stepped(&|| {
        let k = Mh::new(
            ra_mixture(
                PerturbationKind::Lens,
                Perturbation::lens(scene, sigmas.clone()),
                bidirectional(scene, 2),
            )
            .unwrap(),
        );
        Box::new(move |x0, rng| {
            let mut chain = Chain::new(&target, k.clone(), NoAdaptation, rng, x0).unwrap();
            chain.run(STEPS, &mut ()).unwrap();
            chain.state().clone()
        })
    });
    let report = chi_square_two_sample(&correct, &reference, 5.0);
    eprintln!("regional lens + bidirectional: {correct:?} vs {reference:?}: {report:?}");
    report.assert_passes("two-region regional kernel, frozen scales", 1);
    let broken = stepped(&|| {
        let k = Mh::new(CurrentScaleReverse(Perturbation::lens(
            scene,
            sigmas.clone(),
        )));
        Box::new(move |x0, rng| {
            let mut chain = Chain::new(&target, k.clone(), NoAdaptation, rng, x0).unwrap();
            chain.run(STEPS, &mut ()).unwrap();
            chain.state().clone()
        })
    });
    let report = chi_square_two_sample(&broken, &reference, 5.0);
    eprintln!("reverse at the current region's scale: {broken:?}: {report:?}");
    assert!(
        report.p_value < 1e-6,
        "the broken kernel passed: {report:?}"
    );
}

/// The bug of the control: the reverse density at the current state's region scale.
#[derive(Clone)]
struct CurrentScaleReverse<Sc>(Perturbation<'static, AnalyticScene, Sc>);

impl<Sc: pathspace::ScaleSource + Clone> Proposal<Path> for CurrentScaleReverse<Sc> {
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
