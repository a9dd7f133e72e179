//! Langevin MLT's default gradient (`render::mlt::mala::DifferentiableMmlt`, dual numbers
//! with `f32` derivative lanes) against the reference replay with `f64` lanes
//! (`DiffScene::evaluate_continuous::<Dual<32, f64>>`, one lane per continuous coordinate in
//! `pss::langevin::PssCoordinates` order) on bundled scenes, depths 1-3.
//!
//! Statistics: both sides replay the same path with the same `f64` values; only the
//! derivative lanes differ in rounding (`2^-24` relative per operation in `f32`, a few
//! thousand operations per path). So the difference `|g32 - g64| / (|g64| + 1)` in the
//! Euclidean norm is a rounding error, not a sampling one: every state must agree within
//! `1e-4` (measured: at most a few `1e-6`). Negative control: the reference with a wrong lane
//! mapping (every coordinate one lane off, as a caller whose prefix sums started at 1
//! would get) must differ by more than `1e-2` on at least 90 % of the states.

mod common;

use glam::Vec2;
use mcmc_core::DifferentiableTarget;
use pss::PssState;
use render::bdpt::diff::{DiffScene, Dual, Evaluation};
use render::bdpt::BdptParams;
use render::mlt::mala::{continuous_counts, DifferentiableMmlt};
use render::mlt::{MmltTarget, PATH_STREAMS};
use render::scene::Scene;

const SIZE: u32 = 32;

fn scenes() -> Vec<(String, Scene)> {
    common::gradient::gradient_scenes(SIZE)
}

/// The gradient of `ln L` by the `f64`-lane replay, with the streams' first lanes at `lanes`
/// (the prefix sums of the continuous counts, or a wrong mapping), in lane order.
fn reference(
    diff: &DiffScene<'_>,
    depth: u32,
    x: &PssState,
    lanes: [usize; 3],
    n: usize,
) -> Option<Vec<f64>> {
    let mask = x.discrete_mask();
    let e = diff.evaluate_continuous::<Dual<32, f64>>(
        depth,
        Vec2::splat(SIZE as f32),
        BdptParams::default().heuristic,
        x.raw_values(),
        PATH_STREAMS,
        lanes,
        [mask[0], mask[1], mask[2]],
        Dual::variable,
    );
    let (Evaluation::Contribution { .. }, Some(lum)) = (&e, e.luminance()) else {
        return None;
    };
    (lum.v > 0.0).then(|| lum.d[..n].iter().map(|d| d / lum.v).collect())
}

#[test]
fn f32_lane_gradient_matches_the_f64_lane_replay() {
    let params = BdptParams::default();
    let (mut checked, mut worst, mut control_detected) = (0, 0.0f64, 0);
    for (name, scene) in scenes() {
        let diff = DiffScene::new(&scene).expect("bundled scenes are supported");
        for depth in 1..=3u32 {
            let base = MmltTarget::all_depths(&scene, params, SIZE, SIZE)[depth as usize];
            let target = DifferentiableMmlt::new(base, 1e-4);
            let mut payload = Default::default();
            let lit = common::gradient::finite_states(&base).filter_map(|(key, x)| {
                let c = continuous_counts(&x);
                let n = c.iter().sum::<usize>();
                let g64 = reference(&diff, depth, &x, [0, c[0], c[0] + c[1]], n)?;
                Some((key, x, c, n, g64))
            });
            for (key, mut x, c, n, g64) in lit.take(4) {
                let mut g = Vec::new();
                target.evaluate_with_grad(&mut x, &mut payload, &mut g);
                assert_eq!(
                    g.len(),
                    n,
                    "{name} depth {depth}: one entry per moved coordinate"
                );
                let m = common::gradient::norm_relative_difference(&g, &g64);
                assert!(
                    m < 1e-4,
                    "{name} depth {depth} key {key}: f32 lanes differ by {m:e}\n{g:?}\n{g64:?}"
                );
                worst = worst.max(m);
                // Negative control: every lane one off (prefix sums starting at 1).
                let shifted = [1, c[0] + 1, c[0] + c[1] + 1];
                let wrong = reference(&diff, depth, &x, shifted, n).expect("same path");
                if common::gradient::norm_relative_difference(&wrong, &g64) > 1e-2 {
                    control_detected += 1;
                }
                checked += 1;
            }
        }
    }
    eprintln!(
        "{checked} states: worst difference {worst:e}; the shifted-lane control was detected \
         on {control_detected}"
    );
    assert!(checked >= 30, "too few states with light: {checked}");
    assert!(
        control_detected * 10 >= checked * 9,
        "the shifted-lane control should disagree on most states: {control_detected} of {checked}"
    );
}
