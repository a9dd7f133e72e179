//! The bidirectional independent sampler: valid paths, `E_p[f / p]` against the furnace box's
//! closed form, and light tracing against path tracing on a caustic (its light-side densities
//! across specular vertices), each with a negative control.

mod common;

use pathspace::analytic::{AnalyticScene, Material, PinholeCamera};
use pathspace::{
    BidirectionalSampler, BidirectionalSamplerParams, BsdfSample, Bsdfs, Camera, Emitters,
    IndependentSampler, Path, RayTracer, Rgb, SpecularLobe, SurfacePoint, Vec3,
};

#[test]
fn sampled_paths_are_valid_and_have_positive_density() {
    let scene = AnalyticScene::test_box().unwrap();
    let params = BidirectionalSamplerParams { max_segments: 6 };
    let sampler = BidirectionalSampler::new(&scene, params).unwrap();
    let mut rng = common::rng(1);
    let mut specular = 0;
    for _ in 0..3000 {
        let p = common::draw(&sampler, &mut rng);
        p.check_valid(&scene, 1e-7).unwrap();
        assert!(sampler.log_density(&p).is_finite());
        specular += usize::from(p.vertices.iter().any(|v| v.is_specular()));
    }
    assert!(
        specular > 200,
        "only {specular} paths with specular vertices"
    );
}

/// Batch means of `f / p` with the density `log_p` (the sampler's own, or a wrong one).
fn batch_means<S: pathspace::PathScene>(
    scene: &S,
    draw: &mut dyn FnMut(&mut Path) -> bool,
    log_p: &dyn Fn(&Path) -> f64,
    f: &dyn Fn(&Path) -> f64,
    batches: usize,
    per_batch: usize,
) -> (f64, f64) {
    let _ = scene;
    let mut p = Path::new();
    let means: Vec<f64> = (0..batches)
        .map(|_| {
            let mut sum = 0.0;
            for _ in 0..per_batch {
                if draw(&mut p) {
                    let fx = f(&p);
                    if fx > 0.0 {
                        sum += fx / log_p(&p).exp();
                    }
                }
            }
            sum / per_batch as f64
        })
        .collect();
    common::mean_and_se(&means)
}

/// `E_p[f / p] = int f dmu = L_e sum_{j<n} albedo^j` in the furnace box; the negative control
/// leaves light tracing (`t = 1`) out of the density and must miss the closed form.
#[test]
fn furnace_measurement_matches_closed_form() {
    let (albedo, emission, n) = (0.6, 1.5, 3usize);
    let scene = AnalyticScene::furnace_box(albedo, emission).unwrap();
    let sampler =
        BidirectionalSampler::new(&scene, BidirectionalSamplerParams { max_segments: n }).unwrap();
    let truth = emission * (0..n).map(|j| albedo.powi(j as i32)).sum::<f64>();
    let f = |p: &Path| p.contribution(&scene).luminance();
    let mut rng = common::rng(2);
    let (mean, se) = batch_means(
        &scene,
        &mut |p| sampler.sample(&mut rng, p),
        &|p| sampler.log_density(p),
        &f,
        40,
        5000,
    );
    assert!(
        (mean - truth).abs() < 4.0 * se,
        "E[f/p] = {mean} +- {se}, closed form {truth}"
    );
    assert!(
        se < 0.01 * truth,
        "standard error {se} too large to be informative"
    );

    // Negative control: the density without the light-tracing strategy.
    let wrong = |p: &Path| {
        let k = p.len();
        let terms: Vec<f64> = (2..=k)
            .map(|t| sampler.log_strategy_density(p, t))
            .collect();
        mcmc_core::proposal::log_sum_exp(&terms) - (k as f64).ln() - (n as f64).ln()
    };
    let mut rng = common::rng(2);
    let (bad, bad_se) = batch_means(
        &scene,
        &mut |p| sampler.sample(&mut rng, p),
        &wrong,
        &f,
        40,
        5000,
    );
    assert!(
        (bad - truth).abs() > 4.0 * bad_se,
        "the negative control passed: {bad} +- {bad_se} vs {truth}"
    );
}

/// A bright light above a glass ball over a diffuse floor (a caustic, `L S S D E`).
fn caustic_scene() -> AnalyticScene {
    let camera = PinholeCamera::look_at(
        Vec3::new(0.0, 0.3, 1.0),
        Vec3::new(0.0, -0.9, -0.5),
        Vec3::new(0.0, 1.0, 0.0),
        50.0,
        1.0,
    )
    .unwrap();
    let mut scene = AnalyticScene::new(camera);
    scene
        .add_rectangle(
            Vec3::new(-2.0, -1.0, -3.0),
            Vec3::new(0.0, 0.0, 4.0),
            Vec3::new(4.0, 0.0, 0.0),
            Material::Diffuse {
                albedo: Rgb::gray(0.8),
            },
            Rgb::BLACK,
        )
        .unwrap();
    scene
        .add_rectangle(
            Vec3::new(-0.3, 0.6, -0.8),
            Vec3::new(0.6, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.6),
            Material::Black,
            Rgb::gray(10.0),
        )
        .unwrap();
    scene
        .add_sphere(
            Vec3::new(0.0, -0.55, -0.5),
            0.4,
            Material::Dielectric {
                ior: 1.5,
                tint: Rgb::gray(1.0),
            },
        )
        .unwrap();
    scene
}

/// The analytic scene with a wrong specular Jacobian (1 everywhere): a negative control for
/// the light walk's measure conversion.
struct NoJacobian<'a>(&'a AnalyticScene);

impl RayTracer for NoJacobian<'_> {
    fn intersect(&self, o: Vec3, d: Vec3) -> Option<SurfacePoint> {
        self.0.intersect(o, d)
    }
    fn visible(&self, a: Vec3, b: Vec3) -> bool {
        self.0.visible(a, b)
    }
}

impl Bsdfs for NoJacobian<'_> {
    fn is_specular(&self, p: &SurfacePoint) -> bool {
        self.0.is_specular(p)
    }
    fn eval(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> Rgb {
        self.0.eval(p, wo, wi)
    }
    fn pdf(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> f64 {
        self.0.pdf(p, wo, wi)
    }
    fn sample(&self, p: &SurfacePoint, wo: Vec3, u: [f64; 3]) -> Option<BsdfSample> {
        self.0.sample(p, wo, u)
    }
    fn specular_direction(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Option<Vec3> {
        self.0.specular_direction(p, wo, lobe)
    }
    fn specular_weight(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Rgb {
        self.0.specular_weight(p, wo, lobe)
    }
    fn specular_pdf(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> f64 {
        self.0.specular_pdf(p, wo, lobe)
    }
    fn specular_jacobian(&self, _p: &SurfacePoint, _wo: Vec3, _lobe: SpecularLobe) -> f64 {
        1.0
    }
}

impl Emitters for NoJacobian<'_> {
    fn emitted(&self, p: &SurfacePoint, w: Vec3) -> Rgb {
        self.0.emitted(p, w)
    }
    fn is_emitter(&self, p: &SurfacePoint) -> bool {
        self.0.is_emitter(p)
    }
    fn sample_emitter(&self, u: [f64; 3]) -> Option<(SurfacePoint, f64)> {
        self.0.sample_emitter(u)
    }
    fn emitter_pdf(&self, p: &SurfacePoint) -> f64 {
        self.0.emitter_pdf(p)
    }
}

impl Camera for NoJacobian<'_> {
    fn origin(&self) -> Vec3 {
        self.0.origin()
    }
    fn direction(&self, raster: [f64; 2]) -> Vec3 {
        self.0.direction(raster)
    }
    fn raster(&self, dir: Vec3) -> Option<[f64; 2]> {
        self.0.raster(dir)
    }
    fn importance(&self, dir: Vec3) -> f64 {
        self.0.importance(dir)
    }
    fn direction_pdf(&self, dir: Vec3) -> f64 {
        self.0.direction_pdf(dir)
    }
}

/// A camera and a diffuse floor under a flat glass interface (ior 1.5, the camera's side
/// inside), lit from above it: `E D S L` crosses one refraction, whose solid-angle Jacobian
/// `cos θ_o / (η^2 cos θ_t)` does not cancel (through a sphere the entry and exit factors do).
fn interface_scene() -> AnalyticScene {
    let camera = PinholeCamera::look_at(
        Vec3::new(0.0, -0.3, 1.0),
        Vec3::new(0.0, -1.0, -0.5),
        Vec3::new(0.0, 1.0, 0.0),
        50.0,
        1.0,
    )
    .unwrap();
    let mut scene = AnalyticScene::new(camera);
    scene
        .add_rectangle(
            Vec3::new(-2.0, -1.0, -3.0),
            Vec3::new(0.0, 0.0, 4.5),
            Vec3::new(4.0, 0.0, 0.0),
            Material::Diffuse {
                albedo: Rgb::gray(0.8),
            },
            Rgb::BLACK,
        )
        .unwrap();
    // The interface at y = 0, normal up (its interior, the glass, below).
    scene
        .add_rectangle(
            Vec3::new(-3.0, 0.0, -4.0),
            Vec3::new(0.0, 0.0, 6.0),
            Vec3::new(6.0, 0.0, 0.0),
            Material::Dielectric {
                ior: 1.5,
                tint: Rgb::gray(1.0),
            },
            Rgb::BLACK,
        )
        .unwrap();
    scene
        .add_rectangle(
            Vec3::new(-0.3, 0.6, -0.8),
            Vec3::new(0.6, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.6),
            Material::Black,
            Rgb::gray(10.0),
        )
        .unwrap();
    scene
}

/// Estimates `int f` over paths of `n` edges with specular vertices and a non-specular first
/// hit, by strategy `t` alone of `sampler`.
fn strategy_estimate<S: pathspace::PathScene + ?Sized>(
    sampler: &BidirectionalSampler<'_, S>,
    scene: &AnalyticScene,
    n: usize,
    t: usize,
    seed: u64,
) -> (f64, f64) {
    let f = |p: &Path| {
        if p.vertices[1].is_specular() || !p.vertices.iter().any(|v| v.is_specular()) {
            0.0
        } else {
            p.contribution(scene).luminance()
        }
    };
    let mut rng = common::rng(seed);
    batch_means(
        scene,
        &mut |p| sampler.sample_strategy(&mut rng, p, n, t),
        &|p| sampler.log_strategy_density(p, t),
        &f,
        40,
        25_000,
    )
}

/// Light tracing (`t = 1`) and path tracing (`t = k`) estimate the same integral over paths
/// of `n` edges whose first hit is non-specular: the caustic `E D S S L` through a glass
/// ball (4 edges) and `E D S L` through a flat interface (3 edges), whose light-side densities
/// cross refractions (the Jacobian `J(x_j -> x_{j-1}) / J(x_j -> x_{j+1}) dω_{j+1} / dω_{j-1}`).
/// With the solid-angle Jacobian left out (negative control) light tracing through the flat
/// interface disagrees.
#[test]
fn light_tracing_matches_path_tracing_through_refraction() {
    for (name, scene, n, control) in [
        ("glass ball", caustic_scene(), 4, false),
        ("flat interface", interface_scene(), 3, true),
    ] {
        let params = BidirectionalSamplerParams { max_segments: n };
        let good = BidirectionalSampler::new(&scene, params).unwrap();
        let (pt, pt_se) = strategy_estimate(&good, &scene, n, n + 1, 3);
        let (lt, lt_se) = strategy_estimate(&good, &scene, n, 1, 4);
        let se = (pt_se * pt_se + lt_se * lt_se).sqrt();
        eprintln!("{name}: path tracing {pt} +- {pt_se}, light tracing {lt} +- {lt_se}");
        assert!(
            pt > 0.0 && (pt - lt).abs() < 4.0 * se,
            "{name}: {pt} vs {lt} (se {se})"
        );
        assert!(
            se < 0.05 * pt,
            "{name}: standard error {se} too large to be informative"
        );
        if control {
            let wrong_scene = NoJacobian(&scene);
            let wrong = BidirectionalSampler::new(&wrong_scene, params).unwrap();
            let (bad, bad_se) = strategy_estimate(&wrong, &scene, n, 1, 4);
            let se = (pt_se * pt_se + bad_se * bad_se).sqrt();
            eprintln!("{name}, negative control without the Jacobian: {bad} +- {bad_se}");
            assert!(
                (pt - bad).abs() > 4.0 * se,
                "the negative control passed: {bad} vs {pt}"
            );
        }
    }
}
