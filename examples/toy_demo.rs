//! Toy demo: acceptance, effective sample size and autocorrelation time of MH kernels on every
//! toy target of `mcmc-core`.
//!
//! For each target it runs Metropolis-Hastings with an isotropic Gaussian random walk at three
//! scales (a quarter of, equal to, and four times a hand-picked scale for the target), and an
//! adaptive random walk whose scale is tuned by the global sign rule of the regional-adaptive
//! paper (Alg. 1 with one region, eq. 4-6, target acceptance 0.5) for 1000 updates and then
//! frozen. Every chain starts from an exact draw of the target (so there is no burn-in) and is
//! measured over 10 000 steps.
//!
//! ```sh
//! cargo run --release --example toy_demo
//! ```
//!
//! Columns: acceptance rate; ESS of the first coordinate per 10 000 steps (`n / tau`);
//! integrated autocorrelation time `tau` of the first coordinate (Geyer's initial monotone
//! sequence estimator).
//!
//! # Notes
//! Each row is one chain of 10 000 steps, so ESS and IAT are rough (single-chain estimates).
//! On the multimodal targets (disconnected mixture; the torus mixture seen by a walk that does
//! not wrap around) a local walk rarely or never changes mode, and the numbers describe mixing
//! *within* the mode the exact start fell in: a small IAT there does not mean the chain
//! explores the target.

use mcmc_core::controller::{Controller, GlobalScale, ScaleAdaptParams, ScaleTunable};
use mcmc_core::proposal::Scaled;
use mcmc_core::seed::chain_seed;
use mcmc_core::stats::integrated_autocorrelation_time;
use mcmc_core::toy::{
    Banana, CorrelatedGaussian, GaussianMixture2d, PiecewiseConstant, Ridge, TorusMixture,
    ToyTarget, UniformMixture,
};
use mcmc_core::{Chain, GaussianRandomWalk, Kernel, Mh, NoAdaptation};
use rand::SeedableRng;
use rand_pcg::Pcg64;

/// Steps measured per row.
const STEPS: u64 = 10_000;
/// Sign-rule updates of the adaptive rows before freezing (`L = 10` steps each).
const ADAPT_UPDATES: u64 = 1000;
/// The demo's seed; row `i` uses `chain_seed(SEED, i)`.
const SEED: u64 = 2024;

/// One line of the table.
struct Row {
    target: &'static str,
    kernel: String,
    acceptance: f64,
    ess_per_10k: f64,
    iat: f64,
}

/// Runs `warmup` steps (adaptation), then measures `STEPS` steps of the same chain. `label`
/// names the kernel after the run (e.g. with its adapted scale).
fn measure<T, K, C>(
    target: &T,
    kernel: K,
    controller: C,
    warmup: u64,
    seed: u64,
    label: impl Fn(&K) -> String,
) -> Row
where
    T: ToyTarget,
    K: Kernel<T>,
    C: Controller<K, Vec<f64>>,
{
    let mut rng = Pcg64::seed_from_u64(seed);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(target, kernel, controller, rng, start).expect("exact start");
    chain.run(warmup, &mut ()).expect("toy targets are finite");
    let accepted_before: u64 = chain.stats().accepted.iter().sum();
    let mut series = Vec::with_capacity(STEPS as usize);
    for _ in 0..STEPS {
        chain.step(&mut ()).expect("toy targets are finite");
        series.push(chain.state()[0]);
    }
    let accepted: u64 = chain.stats().accepted.iter().sum::<u64>() - accepted_before;
    let iat = integrated_autocorrelation_time(&series);
    Row {
        target: target.name(),
        kernel: label(chain.kernel()),
        acceptance: accepted as f64 / STEPS as f64,
        ess_per_10k: series.len() as f64 / iat * (10_000.0 / STEPS as f64),
        iat,
    }
}

/// The rows of one target: random walks at `scale / 4`, `scale`, `4 scale`, then adaptive.
fn rows_for<T: ToyTarget>(target: &T, scale: f64, next_seed: &mut u64) -> Vec<Row> {
    let mut seed = || {
        *next_seed += 1;
        chain_seed(SEED, *next_seed)
    };
    let mut rows = Vec::new();
    for sigma in [scale / 4.0, scale, 4.0 * scale] {
        let kernel = Mh::new(GaussianRandomWalk::new(sigma).expect("positive sigma"));
        rows.push(measure(target, kernel, NoAdaptation, 0, seed(), |_| {
            format!("MH RW sigma={sigma:.3}")
        }));
    }
    let params = ScaleAdaptParams {
        freeze_after_updates: Some(ADAPT_UPDATES),
        ..ScaleAdaptParams::otsu2018()
    };
    let controller = GlobalScale::new(params).expect("valid parameters");
    let mut kernel = Mh::new(Scaled::new(
        GaussianRandomWalk::new(1.0).expect("1 > 0"),
        0.0,
    ));
    controller.init(&mut kernel);
    let warmup = ADAPT_UPDATES * params.updates_every;
    rows.push(measure(target, kernel, controller, warmup, seed(), |k| {
        format!("adaptive MH -> {:.3}", (0.5 * k.log_scale()).exp())
    }));
    rows
}

fn main() {
    let mut seed = 0;
    let mut rows = Vec::new();
    rows.extend(rows_for(
        &UniformMixture::rioux_lavoie2020(),
        0.3,
        &mut seed,
    ));
    rows.extend(rows_for(&Ridge::thin(), 0.3, &mut seed));
    rows.extend(rows_for(&GaussianMixture2d::disconnected(), 0.5, &mut seed));
    rows.extend(rows_for(&TorusMixture::across_seam(), 0.1, &mut seed));
    rows.extend(rows_for(&Banana::curved(), 1.0, &mut seed));
    let gaussian = CorrelatedGaussian::ar1(10, 0.9).expect("valid covariance");
    rows.extend(rows_for(&gaussian, 0.3, &mut seed));
    rows.extend(rows_for(&PiecewiseConstant::with_holes(), 0.15, &mut seed));

    println!(
        "{:<36} {:<24} {:>10} {:>12} {:>10}",
        "target", "kernel", "acceptance", "ESS/10k", "IAT"
    );
    println!("{}", "-".repeat(96));
    for r in &rows {
        println!(
            "{:<36} {:<24} {:>10.3} {:>12.1} {:>10.1}",
            r.target, r.kernel, r.acceptance, r.ess_per_10k, r.iat
        );
    }
}
