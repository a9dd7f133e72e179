//! BDPT against closed forms: the analytic enclosure (all strategies together, each strategy
//! alone without MIS), and light-tracing splats landing in the right pixel.

mod common;

use std::sync::atomic::AtomicBool;

use common::{analytic_enclosure, enclosure_radiance, mean_and_se};
use glam::{Vec2, Vec3};
use render::bdpt::{self, BdptParams, BdptScratch, MisHeuristic, Roulette};
use render::sampler::{IndependentSampler, Sampler};
use render::session::NoProgress;

/// All strategies, MIS-weighted (power and balance heuristics), with Russian roulette: the
/// image mean equals the closed form within 5 standard errors (pixels are independent; light
/// tracing splats make neighbouring pixels weakly correlated, which the 5-sigma bound absorbs).
#[test]
fn bdpt_matches_the_analytic_enclosure() {
    let scene = analytic_enclosure(24, 24);
    for heuristic in [MisHeuristic::Power, MisHeuristic::Balance] {
        let params = BdptParams {
            max_depth: 4,
            heuristic,
            roulette: Roulette { start: Some(2) },
            ..BdptParams::default()
        };
        let out = bdpt::render_bdpt(
            &scene,
            &params,
            Some(16),
            None,
            7,
            false,
            &NoProgress,
            &AtomicBool::new(false),
        );
        let (mean, se) = mean_and_se(&out.image.pixels);
        let exact = enclosure_radiance(4);
        assert!(
            (mean - exact).abs() < 5.0 * se,
            "{heuristic:?}: mean {mean:.5} exact {exact:.5} se {se:.5}"
        );
        assert_eq!(out.dropped, 0);
    }
}

/// Each strategy (s, t) alone, without MIS, is an unbiased estimator of the paths it can
/// sample: in the enclosure every path of depth d = s + t - 2 carries Le rho^d, so each
/// strategy's unweighted mean over the image must be Le rho^d (light tracing, t = 1, splats
/// elsewhere: its mean over the whole image is still Le rho^d).
#[test]
fn every_strategy_alone_is_unbiased() {
    let (w, h) = (16u32, 16u32);
    let scene = analytic_enclosure(w, h);
    let params = BdptParams {
        max_depth: 3,
        heuristic: MisHeuristic::Balance,
        roulette: Roulette { start: None },
        ..BdptParams::default()
    };
    let mut scratch = BdptScratch::default();
    let mut sampler = IndependentSampler::new(11);
    let stride = 6;
    let spp = 64u64;
    let mut sums = vec![0.0f64; stride * stride];
    let mut sq = vec![0.0f64; stride * stride];
    let n = u64::from(w * h) * spp;
    for i in 0..n {
        let pixel = i % u64::from(w * h);
        sampler.start_pixel_sample(pixel, i / u64::from(w * h));
        let p = Vec2::new((pixel % u64::from(w)) as f32, (pixel / u64::from(w)) as f32)
            + sampler.next_2d();
        let mut this = vec![0.0f64; stride * stride];
        bdpt::sample(
            &scene,
            &mut sampler,
            p,
            &params,
            false,
            &mut scratch,
            |sp| {
                this[sp.s as usize * stride + sp.t as usize] += f64::from(sp.l.x);
            },
        );
        for k in 0..this.len() {
            sums[k] += this[k];
            sq[k] += this[k] * this[k];
        }
    }
    let le = f64::from(common::ENCLOSURE_LE);
    let rho = f64::from(common::ENCLOSURE_ALBEDO);
    let mut checked = 0;
    for s in 0..stride {
        for t in 1..stride {
            let depth = s as i64 + t as i64 - 2;
            if !(0..=3).contains(&depth) || (s == 1 && t == 1) {
                continue;
            }
            let k = s * stride + t;
            let mean = sums[k] / n as f64;
            let se = ((sq[k] / n as f64 - mean * mean) / n as f64).sqrt();
            let exact = le * rho.powi(depth as i32);
            // 13 strategies: Bonferroni at alpha = 0.001 gives |z| < 4.0; we use 4.5. Some
            // strategies have zero variance here (e.g. s = 0: cosine sampling of a uniform
            // enclosure), so f32 rounding gets a relative allowance of 1e-5.
            assert!(
                (mean - exact).abs() < 4.5 * se + 1e-5 * exact,
                "(s={s}, t={t}): mean {mean:.5} exact {exact:.5} se {se:.5}"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 13);
}

/// A light-tracing (t = 1) splat lands in the pixel the connected point projects to: put the
/// light subpath's end on a known point and check its raster position against the camera's
/// projection of that point.
#[test]
fn light_tracing_splats_land_in_the_right_pixel() {
    let scene = render::scene::Scene::cornell_box(64, 64);
    let camera = scene.camera();
    // Points on the floor of the box, seen by the camera; project each through sample_wi and
    // compare with the pixel through which generate_ray sees it.
    let mut matched = 0;
    for (px, py) in [(10.5f32, 50.5f32), (32.5, 60.5), (50.5, 45.5), (20.5, 20.5)] {
        let ray = camera.generate_ray(Vec2::new(px, py), Vec2::splat(0.5), 0.5);
        let Some(hit) = scene.intersect(&ray) else {
            continue;
        };
        let cs = camera
            .sample_wi(hit.p, Vec2::splat(0.5), ray.time)
            .expect("visible point projects");
        assert!(
            (cs.p_raster - Vec2::new(px, py)).length() < 1e-2,
            "pixel ({px},{py}) -> {:?}",
            cs.p_raster
        );
        matched += 1;
    }
    assert_eq!(matched, 4);
    // And through BDPT: every t = 1 splat of many samples falls inside the image, and the
    // splats of a path whose camera-side end is not used cover the image (light tracing is
    // not confined to the sample's own pixel).
    let params = BdptParams::default();
    let mut scratch = BdptScratch::default();
    let mut sampler = IndependentSampler::new(5);
    let mut far = 0;
    for i in 0..2000u64 {
        sampler.start_pixel_sample(0, i);
        bdpt::sample(
            &scene,
            &mut sampler,
            Vec2::new(0.5, 0.5),
            &params,
            true,
            &mut scratch,
            |sp| {
                if sp.t == 1 {
                    assert!(
                        sp.p_raster.x >= 0.0
                            && sp.p_raster.x < 64.0
                            && sp.p_raster.y >= 0.0
                            && sp.p_raster.y < 64.0
                    );
                    if sp.p_raster.length() > 8.0 {
                        far += 1;
                    }
                    assert!(sp.l.cmpge(Vec3::ZERO).all());
                }
            },
        );
    }
    assert!(
        far > 100,
        "light tracing splats should land all over the image, got {far}"
    );
}
