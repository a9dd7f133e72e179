//! The independent sampler and the contribution: valid paths, and `E_p[f / p]` equals the
//! furnace box's closed-form measurement.

mod common;

use pathspace::analytic::AnalyticScene;
use pathspace::{IndependentSampler, Path, UnidirectionalParams, UnidirectionalSampler};

#[test]
fn sampled_paths_are_valid_and_have_positive_density() {
    let scene = AnalyticScene::test_box().unwrap();
    let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
    let mut rng = common::rng(1);
    let mut specular = 0;
    for _ in 0..2000 {
        let p = common::draw(&sampler, &mut rng);
        p.check_valid(&scene, 1e-9).unwrap();
        assert!(sampler.log_density(&p).is_finite());
        specular += usize::from(p.vertices.iter().any(|v| v.is_specular()));
    }
    assert!(
        specular > 200,
        "only {specular} paths with specular vertices"
    );
}

/// Importance sampling with the sampler's density: `E_p[f(X) / p(X)] = int f dmu`, which in
/// the furnace box with at most `n` edges is `L_e sum_{j<n} albedo^j` (the camera's raster
/// measurement of the whole image is the mean radiance). Tests the density and `f` together.
#[test]
fn furnace_measurement_matches_closed_form() {
    let (albedo, emission, n) = (0.6, 1.5, 3usize);
    let scene = AnalyticScene::furnace_box(albedo, emission).unwrap();
    let params = UnidirectionalParams {
        max_segments: n,
        connect_probability: 0.5,
    };
    let sampler = UnidirectionalSampler::new(&scene, params).unwrap();
    let mut rng = common::rng(2);
    let batches: Vec<f64> = (0..40)
        .map(|_| {
            let m = 5000;
            let mut sum = 0.0;
            let mut p = Path::new();
            for _ in 0..m {
                if sampler.sample(&mut rng, &mut p) {
                    sum += p.contribution(&scene).luminance() / sampler.log_density(&p).exp();
                }
            }
            sum / f64::from(m)
        })
        .collect();
    let (mean, se) = common::mean_and_se(&batches);
    let truth = emission * (0..n).map(|j| albedo.powi(j as i32)).sum::<f64>();
    assert!(
        (mean - truth).abs() < 4.0 * se,
        "E[f/p] = {mean} +- {se}, closed form {truth}"
    );
    assert!(
        se < 0.01 * truth,
        "standard error {se} too large to be informative"
    );
}
