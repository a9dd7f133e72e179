//! Your own integrand rendered with PSSMLT, delayed-rejection MLT (orbital) and Langevin MLT
//! (MALA) through chainlight's generic render loop, using only `mcmc-core` and `pss` (no
//! renderer: `cargo tree -p pss -e normal` lists neither `render` nor `pathspace`).
//!
//! The "renderer" is an analytic 2-D integrand `g(u0, u1)` on the unit square, mapped onto a
//! `WIDTH x HEIGHT` image: pixel `(x, y)` shows `WIDTH * HEIGHT` times the integral of `g` over
//! its part of the square. To plug in your own renderer, replace `Integrand::point` by your
//! path sampler: read random numbers from the `PssState` (`next_sample`, one stream per
//! subpath if you like), return `ln f` of the path and say where it lands. Everything else —
//! bootstrap, chain starts, chains in deterministic jobs, automatic large-step control,
//! expected-value splatting — comes from `mcmc_core::render_loop`, and each method is one
//! kernel factory:
//! - PSSMLT: `Mh` of `pss::PssmltProposal` (Kelemen et al. 2002);
//! - DRMLT: `pss::dr::orbital_kernel` on the pair layout of what the integrand reads
//!   (Rioux-Lavoie et al. 2020, section 4.4);
//! - MALA: `pss::mala::mala_kernel`, for which the integrand also implements
//!   `mcmc_core::DifferentiableTarget` (Luan et al. 2020), its gradient caches shared by
//!   `mcmc_core::langevin::CacheSharing` (fixed large-step probability).
//!
//! `cargo run --release -p pss --example pss_custom_target` writes `custom_target.ppm` (PSSMLT)
//! and prints each method's error against the exact image.

use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

use mcmc_core::controller::AutoLargeStep;
use mcmc_core::langevin::CacheSharing;
use mcmc_core::render_loop::{LoopBudget, LoopSettings, RenderLoop, Splat, SplatGrid};
use mcmc_core::{DifferentiableTarget, Mh, NoProgress, Target};
use pss::dr::{orbital_kernel, SecondStageStreams};
use pss::mala::{mala_kernel, MalaParams};
use pss::{FreshPss, KelemenParams, PairLayout, PssState, PssmltProposal, SmallMutation};

/// Image width in pixels.
pub(crate) const WIDTH: usize = 16;
/// Image height in pixels.
pub(crate) const HEIGHT: usize = 12;

/// Chains of every render (64), and mutations per chain per round (200).
const CHAINS: usize = 64;
const ROUND: u64 = 200;

/// `g(u0, u1) = (1 + 0.9 cos 6 pi u0) (0.2 + u1^2)`: stripes, brighter towards the bottom.
fn g(u0: f64, u1: f64) -> f64 {
    (1.0 + 0.9 * (6.0 * PI * u0).cos()) * (0.2 + u1 * u1)
}

/// The gradient of `ln g` (what MALA needs).
fn grad_ln_g(u0: f64, u1: f64) -> [f64; 2] {
    let stripe = -0.9 * 6.0 * PI * (6.0 * PI * u0).sin() / (1.0 + 0.9 * (6.0 * PI * u0).cos());
    [stripe, 2.0 * u1 / (0.2 + u1 * u1)]
}

/// The integrand as an MCMC target over primary sample space: `ln g` and one splat.
pub(crate) struct Integrand;

impl Integrand {
    /// The path sampler: reads the point and splats `g` there.
    fn point(u: &mut PssState, splat: &mut Option<Splat>) -> (f64, f64) {
        u.begin();
        let (u0, u1) = (u.next_sample(), u.next_sample());
        *splat = Some(Splat {
            raster: [(u0 * WIDTH as f64) as f32, (u1 * HEIGHT as f64) as f32],
            rgb: [g(u0, u1) as f32; 3],
        });
        (u0, u1)
    }
}

impl Target for Integrand {
    type State = PssState;
    type Payload = Option<Splat>;
    fn evaluate(&self, u: &mut PssState, splat: &mut Option<Splat>) -> f64 {
        let (u0, u1) = Self::point(u, splat);
        g(u0, u1).ln()
    }
}

/// For MALA: the gradient in the order of the coordinates read (stream 0: `u0`, then `u1`).
impl DifferentiableTarget for Integrand {
    fn evaluate_with_grad(
        &self,
        u: &mut PssState,
        splat: &mut Option<Splat>,
        grad: &mut Vec<f64>,
    ) -> f64 {
        let (u0, u1) = Self::point(u, splat);
        grad.clear();
        grad.extend(grad_ln_g(u0, u1));
        g(u0, u1).ln()
    }
}

/// The rendering methods of this example.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Method {
    Pssmlt,
    DrOrbital,
    Mala,
}

/// Renders the image with `method` and `mutations` mutations in total; row-major RGB.
pub(crate) fn render(method: Method, mutations: u64, seed: u64) -> Vec<[f32; 3]> {
    let settings = LoopSettings {
        chains: CHAINS,
        bootstrap_samples: 10_000,
        budget: LoopBudget::Mutations(mutations),
        seed,
        round_mutations: ROUND,
        ..LoopSettings::default()
    };
    let states = FreshPss::new(1).expect("one stream");
    // Pooled over all chains: p_large is set once 64 x 200 steps have been measured.
    let auto = || AutoLargeStep::pooled(CHAINS as u64 * ROUND).expect("positive");
    let (no_progress, no_cancel) = (NoProgress, AtomicBool::new(false));
    // The loop's estimate is per unit of primary sample space (sink x splat scale).
    let (sink, splat_scale) = match method {
        Method::Pssmlt => RenderLoop {
            targets: &[Integrand],
            states: &states,
            kernel: |_| Mh::new(PssmltProposal::kelemen2002()),
            controller: |_| auto(),
            sink: || SplatGrid::new(WIDTH, HEIGHT),
        }
        .run(&settings, &no_progress, &no_cancel)
        .map(|out| (out.sink, out.splat_scale)),
        // The pairwise stages move what the integrand reads: stream 0's two numbers, one pair.
        Method::DrOrbital => RenderLoop {
            targets: &[Integrand],
            states: &states,
            kernel: |_| {
                orbital_kernel(PairLayout::single_stream(2), 0.3, SecondStageStreams::all())
            },
            controller: |_| auto(),
            sink: || SplatGrid::new(WIDTH, HEIGHT),
        }
        .run(&settings, &no_progress, &no_cancel)
        .map(|out| (out.sink, out.splat_scale)),
        // Path depth 0: every chain runs MALA (hybrid adaptation, the paper's parameters), with
        // large steps of fixed probability 0.3 as in the renderer; the chains share their
        // gradient caches at the end of every round.
        Method::Mala => RenderLoop {
            targets: &[Integrand],
            states: &states,
            kernel: |_| {
                let beyond = SmallMutation::Kelemen(KelemenParams::kelemen2002());
                mala_kernel(&MalaParams::luan2020(), 0, beyond, 0.3)
            },
            controller: |_| CacheSharing,
            sink: || SplatGrid::new(WIDTH, HEIGHT),
        }
        .run(&settings, &no_progress, &no_cancel)
        .map(|out| (out.sink, out.splat_scale)),
    }
    .expect("valid settings");
    // A pixel is 1/(W H) of the unit square.
    sink.to_rgb32(splat_scale * (WIDTH * HEIGHT) as f64)
}

/// The exact image: `W H` times the integral of `g` over each pixel (closed form).
pub(crate) fn exact_image() -> Vec<[f32; 3]> {
    let a = |u: f64| u + 0.9 * (6.0 * PI * u).sin() / (6.0 * PI);
    let b = |u: f64| 0.2 * u + u * u * u / 3.0;
    let (w, h) = (WIDTH as f64, HEIGHT as f64);
    (0..HEIGHT)
        .flat_map(|y| (0..WIDTH).map(move |x| (x as f64, y as f64)))
        .map(|(x, y)| {
            let v = w * h * (a((x + 1.0) / w) - a(x / w)) * (b((y + 1.0) / h) - b(y / h));
            [v as f32; 3]
        })
        .collect()
}

pub(crate) fn main() -> std::io::Result<()> {
    let exact = exact_image();
    let mut pssmlt = Vec::new();
    for method in [Method::Pssmlt, Method::DrOrbital, Method::Mala] {
        let image = render(method, 2_000_000, 1);
        let relmse = image
            .iter()
            .zip(&exact)
            .map(|(p, e)| (f64::from(p[0]) - f64::from(e[0])).powi(2) / f64::from(e[0]).powi(2))
            .sum::<f64>()
            / image.len() as f64;
        println!(
            "{method:?}: {WIDTH}x{HEIGHT} image, 2 000 000 mutations: relMSE against the exact image {relmse:.2e}"
        );
        if let Method::Pssmlt = method {
            pssmlt = image;
        }
    }
    // A binary PPM, brightest pixel at 255.
    let max = pssmlt
        .iter()
        .map(|p| p[0])
        .fold(0.0f32, f32::max)
        .max(1e-12);
    let mut ppm = format!("P6\n{WIDTH} {HEIGHT}\n255\n").into_bytes();
    ppm.extend(
        pssmlt
            .iter()
            .flat_map(|p| p.map(|c| (c / max * 255.0).round() as u8)),
    );
    std::fs::write("custom_target.ppm", ppm)?;
    println!("wrote custom_target.ppm");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Replicate renders' mean against an image, per pixel: the largest |t| over pixels.
    fn worst_t(reps: &[Vec<[f32; 3]>], against: &[[f32; 3]]) -> f64 {
        let r = reps.len() as f64;
        (0..against.len())
            .map(|i| {
                let v: Vec<f64> = reps.iter().map(|img| f64::from(img[i][0])).collect();
                let mean = v.iter().sum::<f64>() / r;
                let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (r - 1.0);
                ((mean - f64::from(against[i][0])) / (var / r).sqrt()).abs()
            })
            .fold(0.0, f64::max)
    }

    /// 16 independent replicates of `method` (MCMC pixels are correlated within a run, so the
    /// spread comes from replicates). Critical value: Student t with 15 degrees of freedom at
    /// two-sided alpha = 0.01 / 192 pixels (Bonferroni), about 6.0. The negative control
    /// compares the same renders with the exact image of a different integrand (stripe
    /// amplitude 0.8 instead of 0.9, pixels differ by up to ~5%), which the test must reject.
    fn assert_converges(method: Method, seed: u64) {
        let reps: Vec<Vec<[f32; 3]>> = (0..16).map(|s| render(method, 200_000, seed + s)).collect();
        let exact = exact_image();
        let t = worst_t(&reps, &exact);
        assert!(t < 6.0, "{method:?}: worst pixel t = {t}");
        let wrong: Vec<[f32; 3]> = exact
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let x = (i % WIDTH) as f64 + 0.5;
                let stripe = (6.0 * PI * x / WIDTH as f64).cos();
                [(f64::from(e[0]) * (1.0 + 0.8 * stripe) / (1.0 + 0.9 * stripe)) as f32; 3]
            })
            .collect();
        let t_wrong = worst_t(&reps, &wrong);
        println!(
            "{method:?}: worst pixel |t| {t:.2} vs the exact image, {t_wrong:.2} vs the wrong one"
        );
        println!(
            "{method:?}: worst pixel |t| {t:.2} vs the exact image, {t_wrong:.2} vs the wrong one"
        );
        assert!(
            t_wrong > 6.0,
            "{method:?}: negative control not detected (t = {t_wrong})"
        );
    }

    #[test]
    fn pssmlt_converges_to_the_exact_integral() {
        assert_converges(Method::Pssmlt, 100);
    }

    #[test]
    fn dr_orbital_converges_to_the_exact_integral() {
        assert_converges(Method::DrOrbital, 200);
    }

    #[test]
    fn mala_converges_to_the_exact_integral() {
        assert_converges(Method::Mala, 300);
    }

    #[test]
    fn the_gradient_matches_central_differences() {
        let h = 1e-6;
        for (u0, u1) in [(0.1, 0.2), (0.37, 0.9), (0.6, 0.05), (0.95, 0.5)] {
            let [d0, d1] = grad_ln_g(u0, u1);
            let f0 = (g(u0 + h, u1).ln() - g(u0 - h, u1).ln()) / (2.0 * h);
            let f1 = (g(u0, u1 + h).ln() - g(u0, u1 - h).ln()) / (2.0 * h);
            assert!((d0 - f0).abs() < 1e-5 * (1.0 + f0.abs()), "{d0} vs {f0}");
            assert!((d1 - f1).abs() < 1e-5 * (1.0 + f1.abs()), "{d1} vs {f1}");
        }
    }
}
