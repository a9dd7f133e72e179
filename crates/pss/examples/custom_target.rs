//! Your own integrand rendered with PSSMLT and automatic large-step control through
//! chainlight's generic render loop, using only `mcmc-core` and `pss`.
//!
//! The "renderer" is an analytic 2-D integrand `g(u0, u1)` on the unit square, mapped onto a
//! `WIDTH x HEIGHT` image: pixel `(x, y)` shows `WIDTH * HEIGHT` times the integral of `g` over
//! its part of the square. To plug in your own renderer, replace `Integrand::evaluate` by your
//! path sampler: read random numbers from the `PssState` (`next_sample`, one stream per
//! subpath if you like), return `ln f` of the path and say where it lands. Everything else —
//! bootstrap, chain starts, chains in deterministic jobs, automatic large-step control,
//! expected-value splatting — comes from `mcmc_core::render_loop`.
//!
//! `cargo run --release --example custom_target` writes `custom_target.ppm` and prints the
//! error against the exact image.

use std::sync::atomic::AtomicBool;

use mcmc_core::controller::AutoLargeStep;
use mcmc_core::render_loop::{LoopBudget, LoopSettings, RenderLoop, Splat, SplatGrid};
use mcmc_core::{Mh, NoProgress, Target};
use pss::{FreshPss, PssState, PssmltProposal};

/// Image width in pixels.
pub(crate) const WIDTH: usize = 16;
/// Image height in pixels.
pub(crate) const HEIGHT: usize = 12;

/// `g(u0, u1) = (1 + 0.9 cos 6 pi u0) (0.2 + u1^2)`: stripes, brighter towards the bottom.
fn g(u0: f64, u1: f64) -> f64 {
    (1.0 + 0.9 * (6.0 * std::f64::consts::PI * u0).cos()) * (0.2 + u1 * u1)
}

/// The integrand as an MCMC target over primary sample space: `ln g` and one splat.
struct Integrand;

impl Target for Integrand {
    type State = PssState;
    type Payload = Option<Splat>;
    fn evaluate(&self, u: &mut PssState, splat: &mut Option<Splat>) -> f64 {
        u.begin();
        let (u0, u1) = (u.next_sample(), u.next_sample());
        let value = g(u0, u1);
        *splat = Some(Splat {
            raster: [(u0 * WIDTH as f64) as f32, (u1 * HEIGHT as f64) as f32],
            rgb: [value as f32; 3],
        });
        value.ln()
    }
}

/// Renders the image with `mutations` mutations in total (64 chains); row-major RGB.
pub(crate) fn render(mutations: u64, seed: u64) -> Vec<[f32; 3]> {
    let settings = LoopSettings {
        chains: 64,
        bootstrap_samples: 10_000,
        budget: LoopBudget::Mutations(mutations),
        seed,
        round_mutations: 200,
        ..LoopSettings::default()
    };
    let out = RenderLoop {
        targets: &[Integrand],
        states: &FreshPss::new(1).expect("one stream"),
        kernel: |_| Mh::new(PssmltProposal::kelemen2002()),
        // Pooled over all chains: p_large is set once 64 x 200 steps have been measured.
        controller: |_| AutoLargeStep::pooled(64 * 200).expect("positive"),
        sink: || SplatGrid::new(WIDTH, HEIGHT),
    }
    .run(&settings, &NoProgress, &AtomicBool::new(false))
    .expect("valid settings");
    // The loop's estimate is per unit of primary sample space; a pixel is 1/(W H) of it.
    out.sink.to_rgb32(out.splat_scale * (WIDTH * HEIGHT) as f64)
}

/// The exact image: `W H` times the integral of `g` over each pixel (closed form).
pub(crate) fn exact_image() -> Vec<[f32; 3]> {
    let a =
        |u: f64| u + 0.9 * (6.0 * std::f64::consts::PI * u).sin() / (6.0 * std::f64::consts::PI);
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
    let image = render(2_000_000, 1);
    let exact = exact_image();
    let relmse = image
        .iter()
        .zip(&exact)
        .map(|(p, e)| (f64::from(p[0]) - f64::from(e[0])).powi(2) / f64::from(e[0]).powi(2))
        .sum::<f64>()
        / image.len() as f64;
    println!(
        "{WIDTH}x{HEIGHT} image, 2 000 000 mutations: relMSE against the exact image {relmse:.2e}"
    );
    // A binary PPM, brightest pixel at 255.
    let max = image.iter().map(|p| p[0]).fold(0.0f32, f32::max).max(1e-12);
    let mut ppm = format!("P6\n{WIDTH} {HEIGHT}\n255\n").into_bytes();
    ppm.extend(
        image
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

    /// 16 independent replicates (MCMC pixels are correlated within a run, so the spread comes
    /// from replicates). Critical value: Student t with 15 degrees of freedom at two-sided
    /// alpha = 0.01 / 192 pixels (Bonferroni), about 6.0. The negative control compares the
    /// same renders with the exact image of a different integrand (stripe amplitude 0.8
    /// instead of 0.9, pixels differ by up to ~5%), which the test must reject.
    #[test]
    fn the_image_converges_to_the_exact_integral() {
        let reps: Vec<Vec<[f32; 3]>> = (0..16).map(|s| render(200_000, 100 + s)).collect();
        let exact = exact_image();
        let t = worst_t(&reps, &exact);
        assert!(t < 6.0, "worst pixel t = {t}");
        let wrong: Vec<[f32; 3]> = exact
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let x = (i % WIDTH) as f64 + 0.5;
                let stripe = (6.0 * std::f64::consts::PI * x / WIDTH as f64).cos();
                [(f64::from(e[0]) * (1.0 + 0.8 * stripe) / (1.0 + 0.9 * stripe)) as f32; 3]
            })
            .collect();
        assert!(
            worst_t(&reps, &wrong) > 6.0,
            "negative control not detected"
        );
    }
}
