//! Path-space MLT on render's scenes (`render::pathspace_scene`, `render::mlt::pathmlt`):
//! pairwise flow balance of every mutation at f32 tolerance, the candidates' path invariants,
//! the scene features pathmlt refuses, and negative controls.
//!
//! The flow-balance harness (mcmc-core `testing`) checks
//! `pi(x) T(x -> y) a(x, y) == pi(y) T(y -> x) a(y, x)` for `y` proposed from `x`, with both
//! densities computed from the two paths alone, and the Hastings term `propose` reports
//! against them. On render's scenes the vertices come from f32 ray casts, so the tolerance is
//! f32's (relative `1e-6` on log flows) rather than the analytic scene's `1e-9`.

mod common;

use glam::Vec3A;
use mcmc_core::testing::{assert_hastings_consistent, assert_path_balance, PairwiseParams};
use mcmc_core::{Mh, Proposal, Proposed};
use pathspace::{
    ra_mixture, BidirectionalMutation, BidirectionalParams, FixedScale, IndependenceMutation,
    IndependentSampler, Path, PathTarget, Perturbation, PerturbationKind, ScaleSource,
    UnidirectionalParams, UnidirectionalSampler,
};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use render::light::PunctualLight;
use render::methods::PathMltSettings;
use render::mlt::pathmlt;
use render::mlt::pathmlt::PathAdapt;
use render::pathspace_scene::PathSpaceScene;
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};
use render::RenderError;

/// Relative tolerance of the flow checks on render's f32 scenes.
const F32_TOL: f64 = 1e-6;

fn load(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    scene.set_resolution(16, 16);
    scene
}

/// The scenes: the built-in Cornell box (diffuse), the glass Cornell box (smooth dielectric:
/// specular chains) and the glossy highlight (rough conductor).
fn scenes() -> Vec<(&'static str, Scene)> {
    vec![
        ("cornell", Scene::cornell_box(16, 16)),
        ("cornell-glass", load("cornell-glass.gltf")),
        ("glossy-highlight", load("glossy-highlight.gltf")),
    ]
}

fn sampler<'a>(view: &'a PathSpaceScene<'a>) -> UnidirectionalSampler<'a, PathSpaceScene<'a>> {
    UnidirectionalSampler::new(
        view,
        UnidirectionalParams {
            max_segments: 6,
            connect_probability: 0.5,
        },
    )
    .unwrap()
}

fn rng(seed: u64) -> rand_pcg::Pcg64 {
    rand_pcg::Pcg64::seed_from_u64(seed)
}

fn draw<Smp: IndependentSampler>(sampler: &Smp, rng: &mut rand_pcg::Pcg64) -> Path {
    let mut p = Path::new();
    for _ in 0..100_000 {
        if sampler.sample(rng, &mut p) {
            return p;
        }
    }
    panic!("the sampler failed 100000 times in a row");
}

/// `(x, y)`: `x` from the sampler, `y` proposed from it (a few attempts; else another
/// independent path, whose flows are zero for a perturbation).
fn proposed_pair<Smp: IndependentSampler, P: Proposal<Path>>(
    sampler: &Smp,
    proposal: &P,
    seed: u64,
) -> Vec<Path> {
    let mut rng = rng(seed);
    let x = draw(sampler, &mut rng);
    let mut y = Path::new();
    for _ in 0..8 {
        if let Proposed::Move { .. } = proposal.propose(&x, &mut y, &mut rng) {
            return vec![x, y];
        }
    }
    let other = draw(sampler, &mut rng);
    vec![x, other]
}

fn check<P: Proposal<Path> + Clone>(name: &str, view: &PathSpaceScene<'_>, proposal: P, seed: u64) {
    let sampler = sampler(view);
    let target = PathTarget::new(view);
    let params = PairwiseParams {
        rel_tol: F32_TOL,
        cases: 256,
        ..PairwiseParams::with_seed(seed)
    };
    let paths = any::<u64>().prop_map(|s| proposed_pair(&sampler, &proposal, s));
    let report = assert_path_balance(&target, &Mh::new(proposal.clone()), paths, &params);
    let states = any::<u64>().prop_map(|s| draw(&sampler, &mut rng(s)));
    let hastings = assert_hastings_consistent(&proposal, states, &params);
    eprintln!("{name}: {report:?}, Hastings {hastings:?}");
}

/// A smooth state-dependent scale: every pair crosses a sigma change.
fn varying_sigma(p: &Path) -> [f64; 2] {
    let d = p.primary_direction();
    [0.01 + 0.03 * (d.x + 1.0), 0.02 + 0.02 * (d.y + 1.0)]
}

fn bidirectional<'a>(
    view: &'a PathSpaceScene<'a>,
) -> BidirectionalMutation<'a, PathSpaceScene<'a>> {
    BidirectionalMutation::new(
        view,
        BidirectionalParams {
            max_segments: 6,
            ..BidirectionalParams::default()
        },
    )
    .unwrap()
}

#[test]
fn every_mutation_balances_flows_on_render_scenes() {
    for (i, (name, scene)) in scenes().iter().enumerate() {
        let view = PathSpaceScene::new(scene).unwrap();
        let seed = 100 * i as u64;
        let v = &view;
        check(
            &format!("{name}: lens"),
            v,
            Perturbation::lens(v, FixedScale::uniform(0.03)),
            seed + 1,
        );
        check(
            &format!("{name}: lens, varying sigma"),
            v,
            Perturbation::lens(v, varying_sigma),
            seed + 2,
        );
        check(
            &format!("{name}: multi-chain, varying sigma"),
            v,
            Perturbation::multi_chain(v, varying_sigma),
            seed + 3,
        );
        check(
            &format!("{name}: bidirectional"),
            v,
            bidirectional(v),
            seed + 4,
        );
        check(
            &format!("{name}: independence"),
            v,
            IndependenceMutation::new(sampler(v)),
            seed + 5,
        );
        for kind in [PerturbationKind::Lens, PerturbationKind::MultiChain] {
            check(
                &format!("{name}: pathmlt's mutation ({kind:?})"),
                v,
                pathmlt::mutation(v, kind, pathmlt::PATHMLT_SIGMA, 5).unwrap(),
                seed + 6 + kind as u64,
            );
            check(
                &format!("{name}: RA mixture ({kind:?}, varying sigma)"),
                v,
                ra_mixture(
                    kind,
                    Perturbation::new(v, kind, varying_sigma),
                    bidirectional(v),
                )
                .unwrap(),
                seed + 8 + kind as u64,
            );
        }
    }
}

/// Every candidate of every mutation satisfies the path invariants (`Path::check_valid`: camera
/// origin, unoccluded edges, specular successors on their specular rays, last vertex on an
/// emitter) at f32 resolution, and the glass box exercises specular vertices.
#[test]
fn candidates_are_valid_paths() {
    for (name, scene) in scenes() {
        let view = PathSpaceScene::new(&scene).unwrap();
        let tol = 1e3 * view.epsilon();
        let sampler = sampler(&view);
        let mut rng = rng(7);
        let (mut moves, mut specular) = (0, 0);
        let mut y = Path::new();
        for kind in [PerturbationKind::Lens, PerturbationKind::MultiChain] {
            let m = pathmlt::mutation(&view, kind, 0.05, 5).unwrap();
            for _ in 0..3000 {
                let x = draw(&sampler, &mut rng);
                x.check_valid(&view, tol)
                    .unwrap_or_else(|e| panic!("{name}: sampled path: {e}"));
                if let Proposed::Move { .. } = m.propose(&x, &mut y, &mut rng) {
                    y.check_valid(&view, tol)
                        .unwrap_or_else(|e| panic!("{name}: {kind:?} candidate: {e}"));
                    moves += 1;
                    specular += usize::from(y.vertices.iter().any(|v| v.is_specular()));
                }
            }
        }
        eprintln!("{name}: {moves} valid candidates, {specular} with specular vertices");
        assert!(moves > 1000, "{name}: {moves}");
        if name == "cornell-glass" {
            assert!(specular > 100, "{name}: {specular} specular candidates");
        }
    }
}

/// The reverse density evaluated at the *current* state's sigma: a Hastings term that ignores
/// the sigma change (pitfall 6 of the reference-implementation notes). `log_q` stays honest,
/// so the harness sees the flows of what the kernel really does.
#[derive(Clone)]
struct CurrentSigmaReverse<'a, Sc>(Perturbation<'a, PathSpaceScene<'a>, Sc>);

impl<Sc: ScaleSource + Clone> Proposal<Path> for CurrentSigmaReverse<'_, Sc> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        let s = self.0.scale().sigmas(x);
        if !self.0.propose_with(x, y, rng, s) {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.log_hastings(0, x, y))
    }
    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.0.log_q(from, to)
    }
    fn log_hastings(&self, _j: usize, x: &Path, y: &Path) -> f64 {
        let s = self.0.scale().sigmas(x);
        self.0.log_q_with(y, x, s) - self.0.log_q_with(x, y, s)
    }
}

/// Negative control: on the glass Cornell box, the reverse move at the current sigma violates
/// detailed balance by far more than the f32 tolerance.
#[test]
#[should_panic(expected = "detailed balance violated")]
fn negative_control_reverse_at_current_sigma_fails() {
    let scene = load("cornell-glass.gltf");
    let view = PathSpaceScene::new(&scene).unwrap();
    let broken = CurrentSigmaReverse(Perturbation::lens(&view, varying_sigma));
    let sampler = sampler(&view);
    let paths = any::<u64>().prop_map(|s| proposed_pair(&sampler, &broken, s));
    assert_path_balance(
        &PathTarget::new(&view),
        &Mh::new(broken.clone()),
        paths,
        &PairwiseParams {
            rel_tol: F32_TOL,
            cases: 256,
            ..PairwiseParams::with_seed(31)
        },
    );
}

/// The same code at a fixed sigma is not a bug: it passes, so the failure above comes from
/// the sigma change, not from the tolerance.
#[test]
fn control_at_fixed_sigma_passes() {
    let scene = load("cornell-glass.gltf");
    let view = PathSpaceScene::new(&scene).unwrap();
    let ok = CurrentSigmaReverse(Perturbation::lens(&view, FixedScale::uniform(0.04)));
    let sampler = sampler(&view);
    let paths = any::<u64>().prop_map(|s| proposed_pair(&sampler, &ok, s));
    assert_path_balance(
        &PathTarget::new(&view),
        &Mh::new(ok.clone()),
        paths,
        &PairwiseParams {
            rel_tol: F32_TOL,
            cases: 256,
            ..PairwiseParams::with_seed(32)
        },
    );
}

fn pathmlt_settings() -> RenderSettings {
    RenderSettings {
        width: 8,
        height: 8,
        budget: Budget::SamplesPerPixel(4),
        threads: 1,
        max_depth: 3,
        method: IntegratorKind::PathMlt.settings().with_chains(4, 1000),
        ..RenderSettings::default()
    }
}

fn pathmlt_error(scene: &Scene, settings: &RenderSettings) -> String {
    match render(
        scene,
        settings,
        &NoProgress,
        &std::sync::atomic::AtomicBool::new(false),
    ) {
        Err(e @ RenderError::InvalidSetting { .. }) => e.to_string(),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("rendered a scene pathmlt does not support"),
    }
}

/// What pathmlt cannot represent is an error naming the feature, never a silently wrong
/// image: thin lens, punctual lights, environment (also the default one), depth > 63. The
/// control: the same settings render the Cornell box.
#[test]
fn unsupported_features_are_errors() {
    let s = pathmlt_settings();
    let dof = load("dof.gltf");
    let e = pathmlt_error(&dof, &s);
    // It says what to change in the scene (there is no --aperture flag).
    assert!(
        e.contains("pinhole") && e.contains("aperture_radius") && !e.contains("--aperture"),
        "{e}"
    );
    let mut punctual = Scene::cornell_box(8, 8);
    punctual.add_punctual_lights([PunctualLight::point(
        Vec3A::new(0.0, 0.5, 0.0),
        glam::Vec3::ONE,
    )]);
    let e = pathmlt_error(&punctual, &s);
    assert!(e.contains("punctual"), "{e}");
    let mut env = Scene::cornell_box(8, 8);
    env.set_environment(Some(render::light::EnvironmentLight::constant(
        glam::Vec3::ONE,
    )));
    let e = pathmlt_error(&env, &s);
    assert!(e.contains("environment"), "{e}");
    let deep = RenderSettings {
        max_depth: 64,
        ..pathmlt_settings()
    };
    let e = pathmlt_error(&Scene::cornell_box(8, 8), &deep);
    assert!(e.contains("max-depth") && e.contains("0..=63"), "{e}");
    // Control: the supported case renders.
    let out = render(
        &Scene::cornell_box(8, 8),
        &s,
        &NoProgress,
        &std::sync::atomic::AtomicBool::new(false),
    )
    .unwrap();
    assert!(out.image.mean_luminance() > 0.0);
    assert_eq!(out.samples, 4 * 64);
}

/// The multi-chain perturbation on the glass box (specular chains) is as deterministic as the
/// table's default row (`determinism.rs`): same seed, 1 and 2 threads, identical bytes; another
/// seed differs (the control that the comparison can fail).
#[test]
fn multichain_on_glass_is_bit_identical_across_threads() {
    let scene = load("cornell-glass.gltf");
    let with = |threads, seed| RenderSettings {
        width: 16,
        height: 12,
        threads,
        seed,
        budget: Budget::SamplesPerPixel(8),
        max_depth: 5,
        method: PathMltSettings {
            chains: 16,
            bootstrap_samples: 4000,
            ..PathMltSettings::otsu2018(PerturbationKind::MultiChain, PathAdapt::Fixed)
        }
        .into(),
    };
    let bits = |s: &RenderSettings| -> Vec<[u32; 3]> {
        render(
            &scene,
            s,
            &NoProgress,
            &std::sync::atomic::AtomicBool::new(false),
        )
        .unwrap()
        .image
        .pixels
        .iter()
        .map(|p| p.map(f32::to_bits))
        .collect()
    };
    let one = bits(&with(1, 5));
    assert!(one.iter().any(|p| p[0] != 0));
    assert!(bits(&with(2, 5)) == one, "2 threads differ from 1");
    assert!(
        bits(&with(1, 6)) != one,
        "another seed gives the same image"
    );
}

/// A floor under a one-sided lamp facing `lamp_normal_y` (up: away from everything).
fn lamp_over_floor(lamp_normal_y: f32) -> Scene {
    use render::scene::{CameraSpec, Material, Mesh};
    let mut mesh = Mesh::new();
    let materials = vec![
        Material::diffuse("floor", glam::Vec3::splat(0.7), glam::Vec3::ZERO),
        Material::diffuse("lamp", glam::Vec3::ZERO, glam::Vec3::splat(10.0)),
    ];
    let quad = |mesh: &mut Mesh, c: Vec3A, u: Vec3A, v: Vec3A, m: u32| {
        mesh.add_quad([c - u - v, c + u - v, c + u + v, c - u + v], m);
    };
    quad(&mut mesh, Vec3A::ZERO, Vec3A::Z * 2.0, Vec3A::X * 2.0, 0);
    // u x v = (0, lamp_normal_y, 0) with u = z, v = x * sign.
    quad(
        &mut mesh,
        Vec3A::new(0.0, 1.0, 0.0),
        Vec3A::Z * 0.2,
        Vec3A::X * (0.2 * lamp_normal_y),
        1,
    );
    let camera = CameraSpec::look_at(
        Vec3A::new(0.0, 0.5, 2.0),
        Vec3A::new(0.0, 0.0, 0.0),
        Vec3A::Y,
        60.0,
    );
    Scene::new(mesh, materials, vec![], camera, 8, 8)
}

/// A scene whose light reaches nothing the camera sees is refused with an error naming what
/// pathmlt could not do (never a black image reported as success); the same scene with the
/// lamp facing the floor renders (control).
#[test]
fn no_light_carrying_path_is_an_error() {
    let settings = pathmlt_settings();
    let cancel = std::sync::atomic::AtomicBool::new(false);
    match render(&lamp_over_floor(1.0), &settings, &NoProgress, &cancel) {
        Err(e @ RenderError::Unrenderable { .. }) => {
            let msg = e.to_string();
            eprintln!("{msg}");
            assert!(
                msg.contains("pathmlt") && msg.contains("no light-carrying path"),
                "{msg}"
            );
            assert!(msg.contains("--integrator bdpt"), "{msg}");
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("rendered a scene without light-carrying paths"),
    }
    let out = render(&lamp_over_floor(-1.0), &settings, &NoProgress, &cancel).unwrap();
    assert!(out.image.mean_luminance() > 0.0);
}
