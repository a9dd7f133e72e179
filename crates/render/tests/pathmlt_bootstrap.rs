//! pathmlt's bootstrap on smooth-shaded scenes: the mean of `f / p` over independent paths
//! (`render::mlt::pathmlt::IndependentPaths`) equals BDPT's image mean, which checks the
//! measurement contribution `f(x)` of `render::pathspace_scene` where shading and geometric
//! normals differ (the `|n_s . w_i| / |n_g . w_i|` factor) and the sampler's density. The
//! Cornell-box tests cannot see this: their shading is flat. Negative control: the bootstrap at
//! a shallower max depth misses the same reference.

mod common;

use std::sync::atomic::AtomicBool;

use common::stats::{mean_se, t_critical};
use mcmc_core::render_loop::{bootstrap_key, IndependentStates};
use mcmc_core::Target;
use pathspace::Path;
use render::bdpt::{render_bdpt, BdptParams};
use render::mlt::pathmlt::{self, IndependentPaths, PathMltTarget};
use render::pathspace_scene::PathSpaceScene;
use render::scene::Scene;
use render::session::NoProgress;

/// Image side, max depth, BDPT reference renders and their samples per pixel.
const SIZE: u32 = 16;
const DEPTH: u32 = 5;
const K: u64 = 8;
const REF_SPP: u32 = 256;
/// Independent paths per bootstrap estimate.
const PATHS: u64 = 1_000_000;
/// Comparisons (two scenes; the negative control uses the same critical value).
const N_COMPARISONS: usize = 2;

fn load(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    let mut scene = Scene::load(&path).unwrap();
    scene.set_resolution(SIZE, SIZE);
    scene
}

/// Mean luminance of `K` BDPT renders: (mean, standard error).
fn bdpt_mean(scene: &Scene) -> (f64, f64) {
    let params = BdptParams {
        max_depth: DEPTH,
        ..BdptParams::default()
    };
    let means: Vec<f64> = (0..K)
        .map(|k| {
            render_bdpt(
                scene,
                &params,
                Some(REF_SPP),
                None,
                70_000 + k,
                false,
                &NoProgress,
                &AtomicBool::new(false),
            )
            .image
            .mean_luminance()
        })
        .collect();
    mean_se(&means)
}

/// The bootstrap estimate of `b` (mean luminance) from `PATHS` independent paths at `depth`:
/// (mean, standard error).
fn bootstrap_mean(scene: &Scene, depth: u32, seed: u64) -> (f64, f64) {
    let view = PathSpaceScene::new(scene).unwrap();
    let states = IndependentPaths {
        sampler: pathmlt::independent_sampler(&view, depth).unwrap(),
    };
    let target = PathMltTarget::new(&view, SIZE as usize, SIZE as usize);
    let (mut path, mut payload) = (Path::new(), None);
    let (mut s1, mut s2) = (0.0, 0.0);
    for i in 0..PATHS {
        states.independent(bootstrap_key(seed, 0, i), &mut path);
        let log_density = target.evaluate(&mut path, &mut payload);
        let w = states.weight(&path, log_density);
        assert!(w.is_finite() && w >= 0.0);
        s1 += w;
        s2 += w * w;
    }
    let n = PATHS as f64;
    let m = s1 / n;
    (m, ((s2 / n - m * m) / (n - 1.0)).sqrt())
}

#[test]
fn bootstrap_matches_bdpt_on_smooth_shaded_scenes() {
    // Degrees of freedom: K - 1 for the reference (the bootstrap's are ~10^6): conservative.
    let crit = t_critical(0.001 / N_COMPARISONS as f64, (K - 1) as u32);
    for (name, seed) in [("glossy-diffuse.gltf", 1), ("caustic-pool.gltf", 2)] {
        let scene = load(name);
        let (mr, sr) = bdpt_mean(&scene);
        let (mb, sb) = bootstrap_mean(&scene, DEPTH, seed);
        let t = (mb - mr) / sr.hypot(sb);
        eprintln!("{name}: bootstrap {mb:.5} (se {sb:.1e}) BDPT {mr:.5} (se {sr:.1e}) t {t:.2} critical {crit:.2}");
        assert!(t.abs() < crit, "{name}: t {t}, critical {crit}");
        if seed == 1 {
            // Negative control: depth 1 (direct lighting only) against the depth-5 reference.
            let (mw, sw) = bootstrap_mean(&scene, 1, seed);
            let tw = (mw - mr) / sr.hypot(sw);
            eprintln!("{name}, negative control (depth 1): {mw:.5} t {tw:.1}");
            assert!(tw.abs() > crit, "{name}: depth 1 not detected: t {tw}");
        }
    }
}
