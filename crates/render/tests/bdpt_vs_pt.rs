//! BDPT equals PT: on the Cornell box (per-block z-tests and a relMSE bound derived from the
//! measured variance) and on the analytic enclosure (closed form).

mod common;

use std::sync::atomic::AtomicBool;

use render::image::Image;
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

const R: usize = 8;

fn replicates(
    scene: &Scene,
    integrator: IntegratorKind,
    size: u32,
    spp: u32,
    max_depth: u32,
) -> Vec<Image> {
    (0..R)
        .map(|r| {
            let settings = RenderSettings {
                method: integrator.settings(),
                width: size,
                height: size,
                budget: Budget::SamplesPerPixel(spp),
                threads: 2,
                seed: 1000 + r as u64 * 7 + integrator as u64 * 100,
                max_depth,
            };
            render(scene, &settings, &NoProgress, &AtomicBool::new(false))
                .expect("render")
                .image
        })
        .collect()
}

/// Per pixel and channel: mean over replicates and variance of that mean.
fn mean_and_var_of_mean(reps: &[Image]) -> (Vec<f64>, Vec<f64>) {
    let n = reps[0].pixels.len() * 3;
    let mut mean = vec![0.0; n];
    let mut var = vec![0.0; n];
    for k in 0..n {
        let vals: Vec<f64> = reps
            .iter()
            .map(|im| f64::from(im.pixels[k / 3][k % 3]))
            .collect();
        let m = vals.iter().sum::<f64>() / R as f64;
        let v = vals.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (R - 1) as f64;
        mean[k] = m;
        var[k] = v / R as f64;
    }
    (mean, var)
}

/// 4x4 blocks of the image: block means of both integrators agree within a Welch z bound,
/// and the relMSE between the two replicate-averaged images is what their variance predicts.
///
/// Statistics: each block mean (luminance-free: channel sum) is an average over R = 8
/// independent replicates per integrator; its standard error comes from the replicate
/// spread. With 16 blocks and a family-wise alpha of 0.001 (Bonferroni, 6.25e-5 per block)
/// and about 14 degrees of freedom (Welch), the two-sided t critical value is about 5.6.
/// relMSE: for unbiased, independent estimates, E[(a - b)^2] = var_a + var_b per pixel, so the
/// expected relMSE is mean((var_a + var_b) / (r^2 + 0.01)); the observed value is an average
/// over 3 x 24 x 24 such terms, concentrated near its expectation; a bias of a few percent
/// adds (bias r)^2 / (r^2 + 0.01) and pushes it above 1.5x the expectation.
#[test]
fn bdpt_equals_pt_on_the_cornell_box() {
    let size = 24;
    let scene = Scene::cornell_box(size, size);
    let pt = replicates(&scene, IntegratorKind::Pt, size, 32, 5);
    let bd = replicates(&scene, IntegratorKind::Bdpt, size, 16, 5);
    let (m_pt, v_pt) = mean_and_var_of_mean(&pt);
    let (m_bd, v_bd) = mean_and_var_of_mean(&bd);
    let s = size as usize;
    let block = s / 4;
    for by in 0..4 {
        for bx in 0..4 {
            let (mut a, mut b, mut va, mut vb) = (0.0, 0.0, 0.0, 0.0);
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    for c in 0..3 {
                        let k = (y * s + x) * 3 + c;
                        a += m_pt[k];
                        b += m_bd[k];
                        va += v_pt[k];
                        vb += v_bd[k];
                    }
                }
            }
            let z = (a - b) / (va + vb).sqrt().max(1e-12);
            assert!(
                z.abs() < 5.6,
                "block ({bx},{by}): PT {a:.4} BDPT {b:.4} z {z:.2}"
            );
        }
    }
    let mut observed = 0.0;
    let mut expected = 0.0;
    for k in 0..m_pt.len() {
        let r = 0.5 * (m_pt[k] + m_bd[k]);
        observed += (m_pt[k] - m_bd[k]).powi(2) / (r * r + 0.01);
        expected += (v_pt[k] + v_bd[k]) / (r * r + 0.01);
    }
    let n = m_pt.len() as f64;
    let (observed, expected) = (observed / n, expected / n);
    assert!(
        observed < 1.5 * expected,
        "relMSE {observed:.5} vs expected {expected:.5}"
    );
    // Total brightness: the most sensitive check of a global bias.
    let (ta, tb): (f64, f64) = (m_pt.iter().sum(), m_bd.iter().sum());
    let tv: f64 = v_pt.iter().sum::<f64>() + v_bd.iter().sum::<f64>();
    assert!(
        (ta - tb).abs() < 5.0 * tv.sqrt(),
        "total PT {ta:.3} BDPT {tb:.3} se {:.3}",
        tv.sqrt()
    );
}

/// PT and BDPT both give the closed-form radiance of the analytic enclosure.
#[test]
fn pt_and_bdpt_match_the_analytic_enclosure() {
    let size = 16;
    let scene = common::analytic_enclosure(size, size);
    let exact = common::enclosure_radiance(4);
    for integrator in [IntegratorKind::Pt, IntegratorKind::Bdpt] {
        let settings = RenderSettings {
            method: integrator.settings(),
            width: size,
            height: size,
            budget: Budget::SamplesPerPixel(16),
            threads: 2,
            seed: 3,
            max_depth: 4,
        };
        let img = render(&scene, &settings, &NoProgress, &AtomicBool::new(false))
            .unwrap()
            .image;
        let (mean, se) = common::mean_and_se(&img.pixels);
        assert!(
            (mean - exact).abs() < 5.0 * se + 1e-5 * exact,
            "{integrator:?}: mean {mean:.5} exact {exact:.5} se {se:.5}"
        );
    }
}

/// Negative control: BDPT limited to 2 bounces against PT with 5 loses light, and the same
/// statistics detect it, so the comparison above can fail.
#[test]
fn a_missing_bounce_is_detected() {
    let size = 24;
    let scene = Scene::cornell_box(size, size);
    let pt = replicates(&scene, IntegratorKind::Pt, size, 32, 5);
    let bd = replicates(&scene, IntegratorKind::Bdpt, size, 16, 2);
    let (m_pt, v_pt) = mean_and_var_of_mean(&pt);
    let (m_bd, v_bd) = mean_and_var_of_mean(&bd);
    let (ta, tb): (f64, f64) = (m_pt.iter().sum(), m_bd.iter().sum());
    let tv: f64 = v_pt.iter().sum::<f64>() + v_bd.iter().sum::<f64>();
    assert!(
        (ta - tb).abs() > 5.0 * tv.sqrt(),
        "total PT {ta:.3} BDPT {tb:.3} se {:.3}",
        tv.sqrt()
    );
}
