//! Cancellation of the independent renderers (PT, BDPT) under a huge sample budget: the render
//! returns within a second of the flag being set, with a partial image whose brightness
//! matches ordinary short renders (every pixel averaged over its own samples, not divided by
//! the planned sample count).
//!
//! Run with `cargo test -p render --release --test cancel`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderOutput, RenderSettings};

/// Image side: 4 PT tiles, 8 BDPT bands of 4 rows.
const SIZE: u32 = 32;
/// Independent reference renders.
const REFERENCES: u64 = 16;
/// Samples per pixel of each reference render.
const REFERENCE_SPP: u32 = 16;
/// How long the cancelled render runs before the flag is set.
const RUN_FOR: Duration = Duration::from_millis(200);
/// How soon after the flag the render must return.
const RESPONSE: Duration = Duration::from_secs(1);
/// Tolerance in standard errors. The reference spread is estimated from 16 renders, so the
/// standardised difference is roughly Student-t with 15 degrees of freedom:
/// P(|t_15| > 5) = 1.6e-4 per test.
const Z: f64 = 5.0;

fn settings(integrator: IntegratorKind, spp: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        budget: Budget::SamplesPerPixel(spp),
        threads: 2,
        seed,
        max_depth: 5,
        method: integrator.settings().with_chains(64, 10_000),
    }
}

/// Counts progress units, so the test can wait until the render has really started.
#[derive(Default)]
struct Count(std::sync::atomic::AtomicU64);

impl render::session::Progress for Count {
    fn set_total(&self, _total: u64) {}
    fn advance(&self, done: u64) {
        self.0.fetch_add(done, Ordering::Relaxed);
    }
}

/// Starts a render of 10^6 samples (mutations) per pixel, waits until it has rendered (for
/// MCMC: until the bootstrap is over and chains run, however loaded the machine is), sets the
/// cancel flag [`RUN_FOR`] later and returns its output and how long it took to return after
/// the flag was set.
fn cancelled_render(scene: &Scene, integrator: IntegratorKind) -> (RenderOutput, Duration) {
    let settings = settings(integrator, 1_000_000, 7);
    // Progress units before the first pixel sample or mutation: the bootstrap samples.
    let targets = if integrator == IntegratorKind::Mmlt {
        u64::from(settings.max_depth) + 1
    } else {
        1
    };
    // PSSMLT's direct-lighting pass (on by default) renders before the bootstrap and reports
    // its pixel samples as progress too.
    let direct_units = if integrator == IntegratorKind::Pssmlt {
        let pass = render::methods::PssmltSettings::default().direct;
        let (spp, _) = pass.budget(Some(1_000_000.0), None);
        u64::from(spp.unwrap_or(0)) * u64::from(SIZE * SIZE)
    } else {
        0
    };
    let warm_up = if integrator.is_mcmc() {
        10_000 * targets + direct_units
    } else {
        0
    };
    let cancel = AtomicBool::new(false);
    let count = Count::default();
    std::thread::scope(|scope| {
        let job = scope.spawn(|| render(scene, &settings, &count, &cancel).unwrap());
        let waiting = Instant::now();
        while count.0.load(Ordering::Relaxed) <= warm_up
            && waiting.elapsed() < Duration::from_secs(60)
        {
            std::thread::sleep(Duration::from_millis(5));
        }
        std::thread::sleep(RUN_FOR);
        cancel.store(true, Ordering::Relaxed);
        let flagged = Instant::now();
        let out = job.join().unwrap();
        (out, flagged.elapsed())
    })
}

/// Cancels a huge render and compares its mean luminance with [`REFERENCES`] short renders.
///
/// The reference means `m_k` give the mean `M` (standard error `s / sqrt(K)`) and the spread
/// `s` of one render of `n_ref = REFERENCE_SPP * pixels` samples. The cancelled render's
/// `n` samples are spread over the pixels within a factor of two (PT passes never more than
/// double a pixel's samples; BDPT passes add one sample per pixel), so its mean has a standard
/// error of at most `s * sqrt(2 n_ref / n)`.
fn check(integrator: IntegratorKind) {
    let scene = Scene::cornell_box(SIZE, SIZE);
    let (out, response) = cancelled_render(&scene, integrator);
    let name = integrator.name();
    assert!(out.cancelled, "{name}: not cancelled");
    assert!(
        response < RESPONSE,
        "{name}: returned {response:?} after the cancel flag"
    );
    let pixels = u64::from(SIZE * SIZE);
    assert!(
        out.samples >= pixels && out.samples < 1_000_000 * pixels,
        "{name}: {} samples",
        out.samples
    );
    assert_eq!(out.image.count_nonfinite(), 0);

    let means: Vec<f64> = (0..REFERENCES)
        .map(|k| {
            let s = settings(integrator, REFERENCE_SPP, 1_000 + k);
            let r = render(&scene, &s, &NoProgress, &AtomicBool::new(false)).unwrap();
            r.image.mean_luminance()
        })
        .collect();
    let k = means.len() as f64;
    let reference = means.iter().sum::<f64>() / k;
    let spread = (means.iter().map(|m| (m - reference).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
    let n_ref = f64::from(REFERENCE_SPP) * pixels as f64;
    let se_cancelled = spread * (2.0 * n_ref / out.samples as f64).sqrt();
    let se = (spread * spread / k + se_cancelled * se_cancelled).sqrt();
    let partial = out.image.mean_luminance();
    println!(
        "{name}: returned {response:?} after the flag, {:.1} samples per pixel, mean {partial:.5} \
         vs {reference:.5} (se {se:.2e})",
        out.samples as f64 / pixels as f64
    );
    assert!(partial > 0.0, "{name}: black partial image");
    assert!(
        (partial - reference).abs() < Z * se,
        "{name}: partial image mean {partial} vs reference {reference} (se {se:.3e}, z {:.1})",
        (partial - reference) / se
    );
}

#[test]
fn pt_cancels_promptly_with_a_correct_partial_image() {
    check(IntegratorKind::Pt);
}

#[test]
fn bdpt_cancels_promptly_with_a_correct_partial_image() {
    check(IntegratorKind::Bdpt);
}

/// PSSMLT and MMLT: the render loop polls the cancel flag every 64 mutations and normalises by
/// the mutations made. The bound on the cancelled render's standard error assumes it scales
/// like `1 / sqrt(mutations)` as for the references (the same chains, started the same way,
/// only longer), with the same factor-of-two allowance.
#[test]
fn pssmlt_cancels_promptly_with_a_correct_partial_image() {
    check(IntegratorKind::Pssmlt);
}

#[test]
fn mmlt_cancels_promptly_with_a_correct_partial_image() {
    check(IntegratorKind::Mmlt);
}
