//! LQMC on a discontinuous integrand on the unit square, against Halton points and plain
//! Monte Carlo at an equal number of integrand evaluations.
//!
//! `f(x, y) = [x + y < 1] + 2 [x < 0.3]` (exact integral 1.1). LQMC: Owen-scrambled Halton
//! seeds, each explored by the embedded N = 23 lattice in 4 x 4 jittered tiles (paper Alg. 1;
//! the uniform seed sampler makes all Jacobians 1). The root-mean-square error over 20
//! scrambling seeds is printed for each method.
//!
//! Run: `cargo run -p lqmc --release --example explore_square`

use lqmc::{Halton, LocalQmc, Rank1Lattice, Rebuilt, Scrambling, Tiling};

const EXACT: f64 = 1.1;

fn f(u: &[f64]) -> f64 {
    f64::from(u8::from(u[0] + u[1] < 1.0)) + 2.0 * f64::from(u8::from(u[0] < 0.3))
}

fn rebuilt(u: &[f64]) -> Rebuilt<()> {
    Rebuilt {
        payload: (),
        contribution: f(u),
        prefix_jacobian: 1.0,
        density: 1.0,
        breakup_probability: 1.0,
    }
}

fn lqmc_estimate(seeds: u64, scramble: u64) -> f64 {
    let lattice = Rank1Lattice::from_table(23, 2).expect("embedded lattice");
    let tiling = Tiling::new(vec![4, 4]).expect("valid tiling");
    let mut lqmc = LocalQmc::new(lattice, tiling).expect("matching dimensions");
    // One progression: the jitter comes from the PRNG dimensions of the sequence.
    let halton = Halton::new(Scrambling::Owen, scramble);
    let jitter = [halton.sample(0, 300), halton.sample(0, 301)];
    lqmc.set_jitter(&jitter).expect("jitter in [0, 1)");
    let mut splats = Vec::new();
    let mut sum = 0.0;
    for i in 0..seeds {
        let mut u = [0.0; 2];
        halton.fill(i, &mut u);
        splats.clear();
        let mut integrand = |v: &[f64]| Some(rebuilt(v));
        lqmc.explore(&u, rebuilt(&u), &mut integrand, &mut splats);
        sum += splats.iter().map(|s| s.value).sum::<f64>();
    }
    sum / seeds as f64
}

fn halton_estimate(points: u64, scramble: u64) -> f64 {
    let halton = Halton::new(Scrambling::Owen, scramble);
    let mut u = [0.0; 2];
    (0..points)
        .map(|i| {
            halton.fill(i, &mut u);
            f(&u)
        })
        .sum::<f64>()
        / points as f64
}

fn random_estimate(points: u64, scramble: u64) -> f64 {
    // Dimensions >= 256 of the sequence are a counter-based PRNG.
    let prng = Halton::new(Scrambling::None, scramble);
    (0..points)
        .map(|i| f(&[prng.sample(i, 256), prng.sample(i, 257)]))
        .sum::<f64>()
        / points as f64
}

fn rmse(estimates: impl Iterator<Item = f64>) -> f64 {
    let errors: Vec<f64> = estimates.map(|e| (e - EXACT).powi(2)).collect();
    (errors.iter().sum::<f64>() / errors.len() as f64).sqrt()
}

fn main() {
    println!("evaluations  RMSE: random     Halton(Owen)  LQMC N=23 (Halton seeds)");
    for seeds in [64u64, 256, 1024, 4096] {
        let evaluations = 23 * seeds;
        let r = rmse((0..20).map(|s| random_estimate(evaluations, s)));
        let h = rmse((0..20).map(|s| halton_estimate(evaluations, s)));
        let l = rmse((0..20).map(|s| lqmc_estimate(seeds, s)));
        println!("{evaluations:>11}        {r:.2e}   {h:.2e}      {l:.2e}");
    }
}
