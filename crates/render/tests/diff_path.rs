//! The differentiable path evaluator (`render::bdpt::diff`) against the f32 renderer and
//! against itself (the checks `docs/methods/mala.md` reports):
//!
//! - **value**: on every bundled scene and depths 0..=4, at PSS states where the f32 MMLT
//!   target carries light, the evaluator's f64 contribution (times the number of strategies)
//!   equals the f32 renderer's luminance within a relative `1e-3`, on at least 99 % of the
//!   states (the rest: a discrete decision that flips between the f32 and the f64 arithmetic,
//!   e.g. a ray grazing a triangle edge, which we count and print);
//! - **gradient**: the dual-number gradient equals finite differences of the f64 evaluator
//!   (central differences at `h = 1e-6` and `h / 2`, Richardson-extrapolated: truncation
//!   `O(h^4)`, rounding `~1e-16 / h`; plain central differences leave `1e-5`-relative
//!   truncation errors on the steepest glossy lobes, where log-gradients reach `4e3`)
//!   within `1e-5 (|g| + 1)` in the Euclidean norm, at random states of
//!   every bundled scene where the path structure does not change within the step (same
//!   strategy, read counts and discrete decisions — triangles hit, lights chosen, lobes — at
//!   `u +- h`, checked); proptest over the state key, 64 compared states per run;
//! - **negative controls**: a gradient with two lanes swapped, or FD of the f32 renderer at
//!   the same step, fail the comparison.

use std::path::Path;

use mcmc_core::Target;
use proptest::prelude::*;
use pss::PssState;
use render::bdpt::diff::{evaluate_strategy, Dual, Evaluation};
use render::bdpt::{BdptParams, MisHeuristic};
use render::glam::Vec2;
use render::mlt::{MmltTarget, PathPayload, PATH_STREAMS};
use render::scene::Scene;

const SIZE: u32 = 32;

fn bundled() -> Vec<(String, Scene)> {
    let mut v = vec![("builtin cornell".to_owned(), Scene::cornell_box(SIZE, SIZE))];
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
        .collect();
    names.sort();
    for path in names {
        let mut s = Scene::load(&path).expect("bundled scene loads");
        s.set_resolution(SIZE, SIZE);
        v.push((path.file_stem().unwrap().to_string_lossy().into_owned(), s));
    }
    v
}

fn lanes(x: &PssState) -> [usize; 3] {
    let c = x.read_counts();
    [0, c[0], c[0] + c[1]]
}

fn eval_f64(scene: &Scene, depth: u32, values: &[f64], lanes: [usize; 3]) -> Evaluation<f64> {
    evaluate_strategy::<f64>(
        scene,
        depth,
        Vec2::splat(SIZE as f32),
        MisHeuristic::Power,
        values,
        PATH_STREAMS,
        lanes,
        |v, _| v,
    )
}

/// A state of `target` with light, searched from `key`.
fn lit_state(target: &MmltTarget<'_>, key: u64) -> Option<(PssState, f64)> {
    let mut payload = PathPayload::default();
    (0..400u64).find_map(|k| {
        let mut x = PssState::new(PATH_STREAMS, key.wrapping_mul(7919).wrapping_add(k));
        let v = target.evaluate(&mut x, &mut payload);
        v.is_finite().then_some((x, v))
    })
}

#[test]
fn f64_value_matches_the_f32_renderer_on_every_bundled_scene() {
    let params = BdptParams::default();
    let scenes = bundled();
    assert!(
        scenes.len() >= 9,
        "the eight bundled scenes and the built-in one"
    );
    for (name, scene) in &scenes {
        let (mut checked, mut agree, mut worst) = (0usize, 0usize, 0.0f64);
        for depth in 0..=4u32 {
            let target = MmltTarget::all_depths(scene, params, SIZE, SIZE)[depth as usize];
            for key in 0..40u64 {
                let Some((x, log_f32)) = lit_state(&target, key * 1000 + u64::from(depth)) else {
                    continue;
                };
                let f32_lum = log_f32.exp();
                checked += 1;
                match eval_f64(scene, depth, x.raw_values(), lanes(&x)) {
                    Evaluation::Contribution { reads, .. } if reads != x.read_counts()[..3] => {
                        eprintln!("{name} depth {depth} key {key}: read counts differ");
                    }
                    e => {
                        let lum = e.luminance().expect("bundled scenes are supported");
                        let rel = (lum - f32_lum).abs() / f32_lum;
                        if rel <= 1e-3 {
                            agree += 1;
                            worst = worst.max(rel);
                        } else {
                            eprintln!(
                                "{name} depth {depth} key {key}: f64 {lum:.6e} vs f32 {f32_lum:.6e}"
                            );
                        }
                    }
                }
            }
        }
        eprintln!("{name}: {agree} of {checked} states within 1e-3 (worst agreeing {worst:.1e})");
        assert!(checked >= 60, "{name}: too few lit states ({checked})");
        assert!(
            agree * 100 >= checked * 99,
            "{name}: only {agree} of {checked} states agree"
        );
    }
}

/// The dual gradient (`lanes` = moved coordinates) of the f64 evaluator's luminance.
fn dual_gradient(scene: &Scene, depth: u32, x: &PssState) -> Option<(f64, Vec<f64>)> {
    let l = lanes(x);
    let n = x.read_counts().iter().sum::<usize>();
    assert!(n <= 32, "depth <= 4 reads at most 32 numbers, got {n}");
    let e = evaluate_strategy::<Dual<32>>(
        scene,
        depth,
        Vec2::splat(SIZE as f32),
        MisHeuristic::Power,
        x.raw_values(),
        PATH_STREAMS,
        l,
        Dual::variable,
    );
    let lum = e.luminance()?;
    (lum.v > 0.0).then(|| (lum.v, lum.d[..n].to_vec()))
}

/// Central differences of the f64 evaluator's luminance, or `None` where the structure
/// changes within `h` of the state.
fn fd_gradient(scene: &Scene, depth: u32, x: &PssState, h: f64) -> Option<Vec<f64>> {
    let counts = x.read_counts();
    let l = lanes(x);
    let Evaluation::Contribution {
        s,
        t,
        reads,
        decisions,
        ..
    } = eval_f64(scene, depth, x.raw_values(), l)
    else {
        return None;
    };
    let mut values = x.raw_values().to_vec();
    let mut g = Vec::new();
    for (stream, &n) in counts.iter().enumerate().take(PATH_STREAMS) {
        for k in 0..n {
            let i = stream + PATH_STREAMS * k;
            let u = values[i];
            let mut side = |v: f64| {
                values[i] = v;
                let e = eval_f64(scene, depth, &values, l);
                values[i] = u;
                match e {
                    Evaluation::Contribution {
                        s: s2,
                        t: t2,
                        reads: r2,
                        decisions: d2,
                        ..
                    } if (s2, t2, r2, d2) == (s, t, reads, decisions) => e.luminance(),
                    _ => None,
                }
            };
            if !(h..1.0 - h).contains(&u) {
                return None;
            }
            // Richardson extrapolation of central differences at h and h / 2: error O(h^4),
            // so even the steepest glossy lobes (log-gradients ~4e3) stay far below 1e-5.
            let d1 = (side(u + h)? - side(u - h)?) / (2.0 * h);
            let d2 = (side(u + h / 2.0)? - side(u - h / 2.0)?) / h;
            g.push((4.0 * d2 - d1) / 3.0);
        }
    }
    Some(g)
}

/// `|a - b| / (|b| + 1)` in the Euclidean norm, on log-luminance gradients `g / lum`.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let d = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
    let n = b.iter().map(|y| y * y).sum::<f64>();
    d.sqrt() / (n.sqrt() + 1.0)
}

proptest! {
    // 64 compared states (rejected draws, where the structure changes within h, do not count).
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn dual_gradient_matches_finite_differences_of_the_f64_evaluator(
        scene_index in 0usize..9,
        depth in 1u32..=3,
        key in any::<u64>(),
    ) {
        thread_local!(static SCENES: Vec<(String, Scene)> = bundled());
        SCENES.with(|scenes| {
            let (name, scene) = &scenes[scene_index % scenes.len()];
            let target = MmltTarget::all_depths(scene, BdptParams::default(), SIZE, SIZE)[depth as usize];
            let lit = lit_state(&target, key);
            prop_assume!(lit.is_some(), "no light near this key");
            let (x, _) = lit.unwrap();
            let ad = dual_gradient(scene, depth, &x);
            prop_assume!(ad.is_some(), "the evaluator sees no light (a flipped decision)");
            let (lum, ad) = ad.unwrap();
            let fd = fd_gradient(scene, depth, &x, 1e-6);
            prop_assume!(fd.is_some(), "the path structure changes within h");
            let fd = fd.unwrap();
            let (ad, fd): (Vec<f64>, Vec<f64>) =
                (ad.iter().map(|g| g / lum).collect(), fd.iter().map(|g| g / lum).collect());
            let diff = relative_difference(&ad, &fd);
            prop_assert!(diff < 1e-5, "{} depth {}: AD {:?} vs FD {:?} ({:.2e})", name, depth, ad, fd, diff);
            Ok(())
        })?;
    }
}

/// Negative controls: the comparison above detects a gradient with two lanes swapped, and
/// finite differences of the f32 renderer (rounding noise `~1e-7 / h` at the same step).
#[test]
fn the_gradient_comparison_detects_wrong_gradients() {
    let scenes = bundled();
    let (mut compared, mut swapped_detected, mut f32_detected) = (0, 0, 0);
    for (_, scene) in &scenes {
        let target = MmltTarget::all_depths(scene, BdptParams::default(), SIZE, SIZE)[2];
        for key in 0..6u64 {
            let Some((x, log_f32)) = lit_state(&target, key) else {
                continue;
            };
            let (Some((lum, ad)), Some(fd)) =
                (dual_gradient(scene, 2, &x), fd_gradient(scene, 2, &x, 1e-6))
            else {
                continue;
            };
            let ad: Vec<f64> = ad.iter().map(|g| g / lum).collect();
            let fd: Vec<f64> = fd.iter().map(|g| g / lum).collect();
            compared += 1;
            // Swap the two lanes whose entries differ most.
            let (i, j) = (0..ad.len())
                .flat_map(|i| (0..ad.len()).map(move |j| (i, j)))
                .max_by(|a, b| {
                    (ad[a.0] - ad[a.1])
                        .abs()
                        .total_cmp(&(ad[b.0] - ad[b.1]).abs())
                })
                .unwrap();
            let mut swapped = ad.clone();
            swapped.swap(i, j);
            if relative_difference(&swapped, &fd) >= 1e-5 {
                swapped_detected += 1;
            }
            // Central differences of the f32 target's log luminance at the same step.
            let mut payload = PathPayload::default();
            let mut g32 = Vec::new();
            let counts = x.read_counts();
            for (stream, &n) in counts.iter().enumerate().take(PATH_STREAMS) {
                for k in 0..n {
                    let idx = stream + PATH_STREAMS * k;
                    let u = x.raw_values()[idx];
                    let mut at = |v: f64| {
                        let mut y = x.clone();
                        y.set(idx, v);
                        target.evaluate(&mut y, &mut payload)
                    };
                    g32.push((at(u + 1e-6) - at(u - 1e-6)) / 2e-6);
                }
            }
            assert!(log_f32.is_finite());
            if relative_difference(&g32, &fd) >= 1e-5 {
                f32_detected += 1;
            }
        }
    }
    eprintln!(
        "{compared} states: swapped lanes detected on {swapped_detected}, f32 finite \
         differences on {f32_detected}"
    );
    assert!(compared >= 20, "too few comparable states: {compared}");
    assert!(swapped_detected * 10 >= compared * 9);
    assert!(f32_detected * 10 >= compared * 9);
}
