//! Unbiasedness of the LQMC estimator (paper Alg. 1, eq. 8-9, with the breakup probability)
//! on an analytic integrand with discontinuities, path classes and a stochastic breakup
//! point, and a negative control: the authors' code, which leaves the breakup probability out
//! of the weights, is detected as biased by the same statistic.
//!
//! The "path" is `x = (x0, x1, x2)` on the unit cube, sampled by inversion from `u`:
//! `x0` with density `q0(x) = 0.5 + x`, `x1` with `q1(x) = 1.5 - x`, `x2` uniform, so
//! `p_t(x) = q0(x0) q1(x1)`. The integrand (Lebesgue measure on the cube)
//! `f(x) = [x0 + x1 > 0.8] (1 + x2) + 3 [x1 < 0.25] x0` has the exact integral
//! `0.68 * 1.5 + 3 * 0.25 * 0.5 = 1.395`.
//!
//! Breakup point `b` in {0, 1}: `b = 0` explores `u0` (prefix `x0`, `J = q0`), `b = 1`
//! explores `(u0, u1)` (`J = q0 q1`); `x2` is the static suffix. `P(b = 0 | x) = 0.2 + 0.6 x1`
//! depends on `x1`, which varies inside a `b = 1` set. Class `A = [x0 < 0.5]` uses `N = 7`,
//! class `B` uses `N = 23`, with different tilings; members of the other class are rejected.
//! The tiling jitter is re-drawn every 1000 seeds (a "progression").

use lqmc::{breakup_probability, sample_breakup, LocalQmc, Rank1Lattice, Rebuilt, Tiling};
use rand_pcg::rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;

const EXACT: f64 = 1.395;
const SEEDS: usize = 200_000;
const PROGRESSION: usize = 1000;

fn uniform(rng: &mut Pcg64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

struct Path {
    x: [f64; 3],
    q: [f64; 3],
}

fn warp(u: &[f64; 3]) -> Path {
    let x0 = (-1.0 + (1.0 + 8.0 * u[0]).sqrt()) / 2.0;
    let x1 = (3.0 - (9.0 - 8.0 * u[1]).sqrt()) / 2.0;
    Path {
        x: [x0, x1, u[2]],
        q: [0.5 + x0, 1.5 - x1, 1.0],
    }
}

fn f(x: &[f64; 3]) -> f64 {
    let a = if x[0] + x[1] > 0.8 { 1.0 + x[2] } else { 0.0 };
    let b = if x[1] < 0.25 { 3.0 * x[0] } else { 0.0 };
    a + b
}

fn class(x: &[f64; 3]) -> usize {
    usize::from(x[0] >= 0.5)
}

/// Unnormalised breakup weights over b = 0, 1 (here already normalised).
fn breakup_weights(x: &[f64; 3]) -> [f64; 2] {
    let p0 = 0.2 + 0.6 * x[1];
    [p0, 1.0 - p0]
}

/// `[class][b]`: the lattice and tiling of each configuration.
fn configurations() -> [[LocalQmc; 2]; 2] {
    let q = |n: u32, tiles: Vec<u32>| {
        let s = tiles.len();
        LocalQmc::new(
            Rank1Lattice::from_table(n, s).unwrap(),
            Tiling::new(tiles).unwrap(),
        )
        .unwrap()
    };
    [
        [q(7, vec![2]), q(7, vec![2, 1])],
        [q(23, vec![3]), q(23, vec![3, 2])],
    ]
}

/// `SEEDS` independent LQMC estimates of the integral; with `ignore_breakup` the breakup
/// probability is replaced by 1 in the weights (the authors' `bprob = 1`).
fn estimates(seed: u64, ignore_breakup: bool) -> Vec<f64> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut configs = configurations();
    let mut out = Vec::with_capacity(SEEDS);
    let mut splats = Vec::new();
    for i in 0..SEEDS {
        if i % PROGRESSION == 0 {
            for c in configs.iter_mut().flatten() {
                let jitter: Vec<f64> = (0..c.dims()).map(|_| uniform(&mut rng)).collect();
                c.set_jitter(&jitter).unwrap();
            }
        }
        let u = [uniform(&mut rng), uniform(&mut rng), uniform(&mut rng)];
        let seed_path = warp(&u);
        let c = class(&seed_path.x);
        let (b, _) = sample_breakup(&breakup_weights(&seed_path.x), uniform(&mut rng)).unwrap();
        let s_bar = b + 1;
        let rebuilt = |p: &Path| Rebuilt {
            payload: (),
            contribution: f(&p.x),
            prefix_jacobian: p.q[..s_bar].iter().product(),
            density: p.q.iter().product(),
            breakup_probability: if ignore_breakup {
                1.0
            } else {
                breakup_probability(&breakup_weights(&p.x), b)
            },
        };
        let mut integrand = |v: &[f64]| {
            let mut w = u;
            w[..s_bar].copy_from_slice(v);
            let p = warp(&w);
            (class(&p.x) == c).then(|| rebuilt(&p))
        };
        splats.clear();
        configs[c][b].explore(
            &u[..s_bar],
            rebuilt(&seed_path),
            &mut integrand,
            &mut splats,
        );
        out.push(splats.iter().map(|s| s.value).sum());
    }
    out
}

/// `(mean - EXACT) / standard error`.
fn z_score(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (mean - EXACT) / (var / n).sqrt())
}

/// The paper's estimator (breakup probability in the weights) is unbiased: the mean over
/// 200 000 independent seeds lies within 4 standard errors (from the sample variance) of the
/// exact value, for three RNG seeds; the negative control (authors' code) does not.
#[test]
fn lqmc_is_unbiased_and_the_authors_weights_are_not() {
    for seed in [1u64, 2, 3] {
        let (mean, z) = z_score(&estimates(seed, false));
        println!("paper weights, seed {seed}: mean {mean:.5} (exact {EXACT}), z = {z:.2}");
        assert!(z.abs() < 4.0, "biased? mean {mean}, z {z}");
    }
    let (mean, z) = z_score(&estimates(1, true));
    println!("bprob = 1 (authors' code): mean {mean:.5} (exact {EXACT}), z = {z:.2}");
    assert!(
        z.abs() > 4.0,
        "negative control not detected: mean {mean}, z {z}"
    );
}

/// Plain Monte Carlo on the same integrand agrees (checks the test's own integrand, warps and
/// exact value).
#[test]
fn the_exact_value_is_right() {
    let mut rng = Pcg64::seed_from_u64(9);
    let xs: Vec<f64> = (0..SEEDS)
        .map(|_| {
            let u = [uniform(&mut rng), uniform(&mut rng), uniform(&mut rng)];
            let p = warp(&u);
            f(&p.x) / p.q.iter().product::<f64>()
        })
        .collect();
    let (mean, z) = z_score(&xs);
    assert!(z.abs() < 4.0, "mean {mean}, z {z}");
}

/// A second integrand: six dimensions, the first five explored with the N = 97 lattice in
/// tiles (2, 24, 1, 50, 3) with jitter, every coordinate warped with density `0.5 + x`,
/// `f = prod_{d<5} [x_d < a_d] + [x0 > x1] x5` (exact `prod a_d + 0.25`), a fixed breakup
/// point and one class.
#[test]
fn lqmc_is_unbiased_in_five_explored_dimensions() {
    const A: [f64; 5] = [0.3, 0.7, 0.55, 0.9, 0.45];
    let exact = A.iter().product::<f64>() + 0.25;
    let warp = |u: f64| (-1.0 + (1.0 + 8.0 * u).sqrt()) / 2.0;
    let path = |u: &[f64; 6]| {
        let x = u.map(warp);
        let q = x.map(|x| 0.5 + x);
        let box_ = A.iter().zip(&x).all(|(a, x)| x < a);
        let f = f64::from(u8::from(box_)) + if x[0] > x[1] { x[5] } else { 0.0 };
        Rebuilt {
            payload: (),
            contribution: f,
            prefix_jacobian: q[..5].iter().product(),
            density: q.iter().product(),
            breakup_probability: 1.0,
        }
    };
    let mut qmc = LocalQmc::new(
        Rank1Lattice::from_table(97, 5).unwrap(),
        Tiling::new(vec![2, 24, 1, 50, 3]).unwrap(),
    )
    .unwrap();
    let mut rng = Pcg64::seed_from_u64(11);
    let mut splats = Vec::new();
    let mut xs = Vec::new();
    for i in 0..50_000 {
        if i % PROGRESSION == 0 {
            let jitter: Vec<f64> = (0..5).map(|_| uniform(&mut rng)).collect();
            qmc.set_jitter(&jitter).unwrap();
        }
        let u: [f64; 6] = std::array::from_fn(|_| uniform(&mut rng));
        let mut integrand = |v: &[f64]| {
            let mut w = u;
            w[..5].copy_from_slice(v);
            Some(path(&w))
        };
        splats.clear();
        qmc.explore(&u[..5], path(&u), &mut integrand, &mut splats);
        xs.push(splats.iter().map(|s| s.value).sum::<f64>());
    }
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let z = (mean - exact) / (var / n).sqrt();
    println!("5 explored dims: mean {mean:.5} (exact {exact:.5}), z = {z:.2}");
    assert!(z.abs() < 4.0, "mean {mean}, exact {exact}, z {z}");
}
