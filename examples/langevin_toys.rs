//! Langevin MCMC on 2-D toys: the paper's Fig. 2 (an anisotropic ridge) and Fig. 4 (a
//! disconnected Gaussian mixture), with acceptance and ESS per second per kernel
//! (Luan et al. 2020, sections 4-6).
//!
//! ```sh
//! cargo run --release --example langevin_toys            # writes target/langevin_toys/
//! cargo run --release --example langevin_toys -- --out DIR --steps 50000
//! ```
//!
//! * **Fig. 2** (`fig2_<kernel>.png`): 2048 samples of each kernel from the same start at the
//!   far end of the thin ridge (`Ridge::thin`: 30 degrees, standard deviations 1 and 0.05):
//!   a Gaussian random walk ("Kelemen"), plain MALA, MALA with diagonal Adam
//!   preconditioning, + momentum, and full preconditioning; all with `epsilon` 0.01 (the
//!   paper's value) and no diminishing adaptation (as in the figure). Red: chain states.
//! * **Fig. 4** (`fig4_<online|hybrid>_<n>.png`): online (diminishing adaptation, the
//!   paper's Alg. 2) versus hybrid adaptation (Alg. 4, cache size 2000 here so that the
//!   switch to the cache happens within the run) on the disconnected mixture, large-step
//!   probability 0.1 (uniform over the box), snapshots after 0.5K, 1K, 2K, 4K, 8K and 16K
//!   samples. The paper uses *full* preconditioning for this figure; our hybrid is diagonal.
//! * **Table** (stdout and `table.md`): acceptance, ESS of the first coordinate and ESS per
//!   second over `--steps` steps from an exact start, per kernel and target.
//!
//! docs/methods/mala.md shows the images and the table of a run.

use std::path::{Path, PathBuf};
use std::time::Instant;

use mcmc_core::langevin::{FullOnline, Hybrid, Langevin, LangevinParams, Online, Plain};
use mcmc_core::proposal::IndependentUniform;
use mcmc_core::stats::effective_sample_size;
use mcmc_core::toy::{GaussianMixture2d, Ridge, ToyTarget};
use mcmc_core::{
    Chain, DifferentiableTarget, Euclidean, FiniteDifference, GaussianRandomWalk, Kernel, Mh,
    NoAdaptation, Proposal, Proposed,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use render::image::Image;
use render::image_io::write_png;

/// A Gaussian walk or the large step: the components of the baseline's mixture.
#[derive(Clone, Debug)]
enum Step {
    Walk(GaussianRandomWalk),
    Large(IndependentUniform),
}

impl Proposal<Vec<f64>> for Step {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        match self {
            Step::Walk(w) => w.propose(x, y, rng),
            Step::Large(l) => l.propose(x, y, rng),
        }
    }
    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        match self {
            Step::Walk(w) => w.log_q(from, to),
            Step::Large(l) => l.log_q(from, to),
        }
    }
    fn is_symmetric(&self) -> bool {
        true
    }
}

/// One Fig. 2 kernel: writes its scatter plot into the directory, returns the acceptance over
/// the 2048 samples and its table row over `n` steps.
type Fig2Run<'a> = Box<dyn Fn(&Path, u64) -> (f64, Row) + 'a>;

struct Options {
    out: PathBuf,
    steps: u64,
}

fn parse_options() -> Options {
    let mut o = Options {
        out: PathBuf::from("target/langevin_toys"),
        steps: 50_000,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => {
                o.out = PathBuf::from(
                    args.next()
                        .unwrap_or_else(|| usage("--out needs a directory")),
                )
            }
            "--steps" => {
                o.steps = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|&n: &u64| (1000..=100_000_000).contains(&n))
                    .unwrap_or_else(|| usage("--steps needs a number in 1000..=100000000"))
            }
            other => usage(&format!("unknown argument {other}")),
        }
    }
    o
}

fn usage(msg: &str) -> ! {
    eprintln!("{msg}\nusage: langevin_toys [--out DIR] [--steps N]");
    std::process::exit(2)
}

/// A scatter plot of `points` over the target's density (grey) on its box.
fn scatter<T: ToyTarget>(target: &T, points: &[Vec<f64>], path: &Path) {
    const SIZE: usize = 256;
    let (lo, hi) = target.bounding_box();
    let mut img = Image::new(SIZE, SIZE);
    let mut max = f64::MIN;
    let mut dens = vec![0.0; SIZE * SIZE];
    for j in 0..SIZE {
        for i in 0..SIZE {
            let x = [
                lo[0] + (hi[0] - lo[0]) * (i as f64 + 0.5) / SIZE as f64,
                lo[1] + (hi[1] - lo[1]) * (1.0 - (j as f64 + 0.5) / SIZE as f64),
            ];
            let d = target.log_density(&x).exp();
            dens[j * SIZE + i] = d;
            max = max.max(d);
        }
    }
    for j in 0..SIZE {
        for i in 0..SIZE {
            let g = (0.15 + 0.5 * (dens[j * SIZE + i] / max).sqrt()) as f32;
            img.set(i, j, [g, g, g]);
        }
    }
    for p in points {
        let i = ((p[0] - lo[0]) / (hi[0] - lo[0]) * SIZE as f64).floor();
        let j = ((1.0 - (p[1] - lo[1]) / (hi[1] - lo[1])) * SIZE as f64).floor();
        if (0.0..SIZE as f64).contains(&i) && (0.0..SIZE as f64).contains(&j) {
            img.set(i as usize, j as usize, [1.0, 0.1, 0.05]);
        }
    }
    if let Err(e) = write_png(path, &img, 0.0) {
        eprintln!("cannot write {}: {e}", path.display());
    }
}

/// Runs `n` steps of `kernel` from `start`, recording the states.
fn trace<T, K>(target: &T, kernel: K, start: Vec<f64>, n: u64, seed: u64) -> (Vec<Vec<f64>>, f64)
where
    T: DifferentiableTarget<State = Vec<f64>>,
    K: Kernel<T>,
{
    let rng = Pcg64::seed_from_u64(seed);
    let mut chain = Chain::new(target, kernel, NoAdaptation, rng, start).expect("valid start");
    let mut states = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let _ = chain.step(&mut ());
        states.push(chain.state().clone());
    }
    (states, chain.stats().acceptance_rate())
}

/// One table row: acceptance, ESS of x0 and ESS per second over `n` steps from an exact start.
struct Row {
    target: &'static str,
    kernel: String,
    acceptance: f64,
    ess: f64,
    ess_per_s: f64,
}

fn measure<T, K>(
    name: &'static str,
    label: &str,
    target: &T,
    toy: &impl ToyTarget,
    kernel: K,
    n: u64,
    seed: u64,
) -> Row
where
    T: DifferentiableTarget<State = Vec<f64>>,
    K: Kernel<T>,
{
    let mut rng = Pcg64::seed_from_u64(seed);
    let start = toy.sample_exact(&mut rng);
    let t0 = Instant::now();
    let (states, acceptance) = trace(target, kernel, start, n, seed ^ 0x5eed);
    let secs = t0.elapsed().as_secs_f64();
    let series: Vec<f64> = states.iter().map(|s| s[0]).collect();
    let ess = effective_sample_size(&series);
    Row {
        target: name,
        kernel: label.to_string(),
        acceptance,
        ess,
        ess_per_s: ess / secs,
    }
}

fn main() {
    let o = parse_options();
    if let Err(e) = std::fs::create_dir_all(&o.out) {
        eprintln!("cannot create {}: {e}", o.out.display());
        std::process::exit(1);
    }
    let ridge = Ridge::thin();
    let eps = 0.01;
    let p = LangevinParams {
        epsilon: eps,
        ..LangevinParams::luan2020()
    };
    let start = vec![
        2.5 * 30f64.to_radians().cos(),
        2.5 * 30f64.to_radians().sin(),
    ];
    let mut rows = Vec::new();

    // Fig. 2: the five kernels of the ridge comparison.
    println!("Fig. 2: 2048 samples on the thin ridge from {start:?}");
    let n2 = 2048;
    let fig2: Vec<(&str, Fig2Run)> = vec![
        (
            "kelemen",
            Box::new(|dir: &Path, n: u64| {
                let k = Mh::new(GaussianRandomWalk::new(eps.sqrt()).unwrap());
                let (s, a) = trace(&ridge, k.clone(), start.clone(), n2, 1);
                scatter(&ridge, &s, &dir.join("fig2_kelemen.png"));
                (
                    a,
                    measure("ridge", "Gaussian walk (Kelemen)", &ridge, &ridge, k, n, 11),
                )
            }),
        ),
        (
            "mala",
            Box::new(|dir: &Path, n: u64| {
                let k = Langevin::new(p, Plain, Euclidean).unwrap();
                let (s, a) = trace(&ridge, k.clone(), start.clone(), n2, 2);
                scatter(&ridge, &s, &dir.join("fig2_mala.png"));
                (a, measure("ridge", "MALA", &ridge, &ridge, k, n, 12))
            }),
        ),
        (
            "diag",
            Box::new(|dir: &Path, n: u64| {
                let k = Langevin::new(p, Online::new(false).without_momentum(), Euclidean).unwrap();
                let (s, a) = trace(&ridge, k.clone(), start.clone(), n2, 3);
                scatter(&ridge, &s, &dir.join("fig2_diag.png"));
                (
                    a,
                    measure("ridge", "MALA + diag. precond.", &ridge, &ridge, k, n, 13),
                )
            }),
        ),
        (
            "diag_momentum",
            Box::new(|dir: &Path, n: u64| {
                let k = Langevin::new(p, Online::new(false), Euclidean).unwrap();
                let (s, a) = trace(&ridge, k.clone(), start.clone(), n2, 4);
                scatter(&ridge, &s, &dir.join("fig2_diag_momentum.png"));
                (
                    a,
                    measure("ridge", "MALA + diag. + momentum", &ridge, &ridge, k, n, 14),
                )
            }),
        ),
        (
            "full",
            Box::new(|dir: &Path, n: u64| {
                let k = Langevin::new(p, FullOnline::new(false), Euclidean).unwrap();
                let (s, a) = trace(&ridge, k.clone(), start.clone(), n2, 5);
                scatter(&ridge, &s, &dir.join("fig2_full.png"));
                (
                    a,
                    measure(
                        "ridge",
                        "MALA + full precond. + momentum",
                        &ridge,
                        &ridge,
                        k,
                        n,
                        15,
                    ),
                )
            }),
        ),
    ];
    for (name, run) in &fig2 {
        let (acceptance, row) = run(&o.out, o.steps);
        println!("  {name:<14} acceptance over the 2048 samples: {acceptance:.3}");
        rows.push(row);
    }

    // Fig. 4: online vs hybrid on the disconnected mixture with large steps.
    let mix = GaussianMixture2d::disconnected();
    let fd = FiniteDifference {
        target: mix.clone(),
        h: 1e-6,
    };
    let (lo, hi) = mix.bounding_box();
    let large = IndependentUniform::new(lo, hi).expect("the mixture's box");
    let p4 = LangevinParams {
        epsilon: 0.05,
        cache_size: 2000,
        ..LangevinParams::luan2020()
    };
    let start4 = mix.components()[0].mean.to_vec();
    println!("Fig. 4: disconnected mixture, large-step probability 0.1");
    let snapshots = [500u64, 1000, 2000, 4000, 8000, 16000];
    for (label, seed) in [("online", 21u64), ("hybrid", 22)] {
        let (states, acceptance) = if label == "online" {
            let k = Langevin::new(p4, Online::new(true), Euclidean)
                .unwrap()
                .with_large_step(large.clone(), 0.1)
                .unwrap();
            trace(&fd, k, start4.clone(), 16_000, seed)
        } else {
            let k = Langevin::new(p4, Hybrid::new(&p4), Euclidean)
                .unwrap()
                .with_large_step(large.clone(), 0.1)
                .unwrap();
            trace(&fd, k, start4.clone(), 16_000, seed)
        };
        for &n in &snapshots {
            scatter(
                &mix,
                &states[..n as usize],
                &o.out.join(format!("fig4_{label}_{n}.png")),
            );
        }
        println!("  {label:<7} acceptance over 16K samples: {acceptance:.3}");
    }
    let online = Langevin::new(p4, Online::new(true), Euclidean)
        .unwrap()
        .with_large_step(large.clone(), 0.1)
        .unwrap();
    rows.push(measure(
        "mixture",
        "MALA online (DA) + large step",
        &fd,
        &mix,
        online,
        o.steps,
        31,
    ));
    let hybrid = Langevin::new(p4, Hybrid::new(&p4), Euclidean)
        .unwrap()
        .with_large_step(large.clone(), 0.1)
        .unwrap();
    rows.push(measure(
        "mixture",
        "MALA hybrid (H 2000) + large step",
        &fd,
        &mix,
        hybrid,
        o.steps,
        32,
    ));
    let walk = mcmc_core::Mixture::new(
        vec![
            Step::Walk(GaussianRandomWalk::new(0.05f64.sqrt()).unwrap()),
            Step::Large(large),
        ],
        mcmc_core::proposal::FixedSelection::new(&[0.9, 0.1]).unwrap(),
    )
    .unwrap();
    rows.push(measure(
        "mixture",
        "Gaussian walk + large step",
        &fd,
        &mix,
        Mh::new(walk),
        o.steps,
        33,
    ));

    let mut table =
        String::from("| target | kernel | acceptance | ESS(x0) | ESS/s |\n|---|---|---|---|---|\n");
    for r in &rows {
        table.push_str(&format!(
            "| {} | {} | {:.3} | {:.0} | {:.0} |\n",
            r.target, r.kernel, r.acceptance, r.ess, r.ess_per_s
        ));
    }
    println!(
        "\n{} steps per row from an exact start (one chain each):\n{table}",
        o.steps
    );
    let text = format!(
        "{} steps per row from an exact start (one chain each).\n\n{table}\n",
        o.steps
    );
    if let Err(e) = render::files::write_bytes_atomic(o.out.join("table.md"), text) {
        eprintln!("cannot write table.md: {e}");
    }
    println!("images in {}", o.out.display());
}
