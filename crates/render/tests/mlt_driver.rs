//! The MCMC render driver on a toy "scene" whose image is known in closed form: convergence,
//! the no-light case, automatic large-step control, and thread-count independence.

use std::sync::atomic::AtomicBool;

use mcmc_core::render_loop::{Splat, SplatPayload};
use mcmc_core::Mh;
use pss::{KelemenParams, PssState, PssmltProposal, SmallMutation, SmallStep};
use render::mlt::{LargeStepMode, MltBudget, MltDriver, MltSettings};
use render::session::NoProgress;

const W: usize = 8;
const H: usize = 8;

/// A toy path sampler: the first two primary samples pick the raster position, the
/// contribution is `g(u0, u1)` (grey), zero in a hole `0.4 <= u0 < 0.5`.
struct Toy {
    dark: bool,
}

fn g(u0: f64, u1: f64) -> f64 {
    if (0.4..0.5).contains(&u0) {
        0.0
    } else {
        0.2 + 4.0 * (3.0 * u0).sin().powi(2) * u1 * u1
    }
}

#[derive(Clone, Debug, Default)]
struct Payload(Vec<Splat>);

impl SplatPayload for Payload {
    fn splats(&self) -> &[Splat] {
        &self.0
    }
}

impl mcmc_core::Target for Toy {
    type State = PssState;
    type Payload = Payload;
    fn evaluate(&self, x: &mut PssState, payload: &mut Payload) -> f64 {
        x.begin();
        let (u0, u1) = (x.next_sample(), x.next_sample());
        payload.0.clear();
        let v = if self.dark { 0.0 } else { g(u0, u1) };
        if v > 0.0 {
            payload.0.push(Splat {
                raster: [(u0 * W as f64) as f32, (u1 * H as f64) as f32],
                rgb: [v as f32; 3],
            });
        }
        v.ln()
    }
}

fn exact_pixel(px: usize, py: usize) -> f64 {
    let n = 64;
    let mut s = 0.0;
    for i in 0..n {
        for j in 0..n {
            let u0 = (px as f64 + (i as f64 + 0.5) / n as f64) / W as f64;
            let u1 = (py as f64 + (j as f64 + 0.5) / n as f64) / H as f64;
            s += g(u0, u1);
        }
    }
    s / (n * n) as f64
}

fn settings(seed: u64, large_step: LargeStepMode) -> MltSettings {
    MltSettings {
        width: W,
        height: H,
        chains: 64,
        bootstrap_samples: 10_000,
        budget: MltBudget::MutationsPerPixel(2_000.0),
        large_step,
        seed,
        streams: 1,
        stage_map: false,
        shard: render::shard::Shard::WHOLE,
        normalization: Default::default(),
    }
}

fn kernel(p: f64) -> Mh<PssmltProposal> {
    let small = SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
    Mh::new(PssmltProposal::new(small, p).unwrap())
}

fn run(seed: u64, large_step: LargeStepMode) -> render::mlt::MltOutput {
    let cancel = AtomicBool::new(false);
    MltDriver::new(&[Toy { dark: false }], &settings(seed, large_step)).run(
        kernel,
        &NoProgress,
        &cancel,
    )
}

/// Eight independent replicate renders; every pixel's replicate mean must match the closed
/// form within 6.5 standard errors (t distribution with 7 degrees of freedom, two-sided
/// alpha = 0.01 / 64 pixels (Bonferroni) gives a critical value of about 6.4). MCMC pixels are
/// correlated within a run, so the spread is estimated from the replicates.
#[test]
fn pssmlt_driver_converges_to_the_closed_form() {
    let reps: Vec<_> = (0..8)
        .map(|r| run(100 + r, LargeStepMode::Fixed(0.3)))
        .collect();
    for py in 0..H {
        for px in 0..W {
            let vals: Vec<f64> = reps
                .iter()
                .map(|o| f64::from(o.image.get(px, py)[0]))
                .collect();
            let mean = vals.iter().sum::<f64>() / 8.0;
            let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 7.0;
            let se = (var / 8.0).sqrt().max(1e-9);
            let exact = exact_pixel(px, py);
            assert!(
                ((mean - exact) / se).abs() < 6.5 || (mean - exact).abs() < 1e-6,
                "pixel ({px},{py}): mean {mean} exact {exact} se {se}"
            );
        }
    }
    // b is the integral of g over the unit square.
    let exact_b: f64 = (0..W)
        .flat_map(|x| (0..H).map(move |y| exact_pixel(x, y)))
        .sum::<f64>()
        / (W * H) as f64;
    let b_mean = reps.iter().map(|o| o.b).sum::<f64>() / 8.0;
    assert!(
        (b_mean - exact_b).abs() < 0.02 * exact_b,
        "b {b_mean} vs {exact_b}"
    );
}

#[test]
fn a_scene_without_light_gives_a_black_image_and_a_message() {
    let cancel = AtomicBool::new(false);
    let out = MltDriver::new(
        &[Toy { dark: true }],
        &settings(1, LargeStepMode::Fixed(0.3)),
    )
    .run(kernel, &NoProgress, &cancel);
    assert!(out
        .message
        .as_deref()
        .unwrap_or("")
        .contains("no light-carrying path"));
    assert!(out.image.pixels.iter().all(|p| *p == [0.0; 3]));
    assert_eq!(out.mutations, 0);
}

#[test]
fn automatic_large_step_control_logs_its_statistics() {
    let out = run(
        5,
        LargeStepMode::Auto {
            initial: 0.5,
            estimation_steps: 200,
        },
    );
    let e = out.large_step.expect("estimate");
    assert!(e.small_steps > 0 && e.large_steps > 0);
    assert!((0.0..=1.0).contains(&e.eta_s) && (0.0..=1.0).contains(&e.eta_l));
    // About 1/10 of the unit square is the hole: eta_0 ~ 0.9 (binomial, n >= 5000 large steps).
    assert!((e.eta_0 - 0.9).abs() < 0.03, "eta_0 = {}", e.eta_0);
    assert_eq!(
        out.final_large_step_probability,
        mcmc_core::controller::automatic_large_step_probability(e.eta_s, e.eta_l, e.eta_0)
    );
}

#[test]
fn same_seed_same_image_with_any_thread_count() {
    let render_with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| run(9, LargeStepMode::Fixed(0.3)))
    };
    let a = render_with(1);
    let b = render_with(2);
    let c = render_with(3);
    assert_eq!(a.image, b.image);
    assert_eq!(a.image, c.image);
    let d = run(10, LargeStepMode::Fixed(0.3));
    assert_ne!(a.image, d.image);
}
