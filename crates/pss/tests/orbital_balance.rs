//! Detailed balance of orbital delayed-rejection MLT (DR paper section 4.4, eq. 11;
//! docs/methods/drmlt.md): a chain of the library's kernel keeps its target across the torus
//! seams, and the two-stage flows balance on every sampled triple; each has a negative control
//! that must fail it.
//!
//! Run with `cargo test -p pss --release --test orbital_balance -- --nocapture` to see the
//! statistics; the levels are in `orbital_support`.
//!
//! # Flows and chains
//! Detailed balance of "propose `y`, reject it, propose `z`, accept it" is, for each triple
//! `(x, y, z)`, `flow(x -> z via y) = flow(z -> x via y)` with the flow
//! `pi(x) q1(y|x) (1 - a1(x, y)) q2(z|x, y) a2(x, z)` and `a2` from eq. 11
//! ([`orbital_log_flow`]). It holds exactly when `q1(y|z) = q1(y|x)` and
//! `q2(x|z, y) = q2(z|x, y)`, which is what the proposals promise; the negative controls (a
//! first stage of independent 1-D Kelemen steps; an orbit built from the raw, not minimal,
//! displacement) break it on most or many triples.
//!
//! Chains run the library's kernel, `mcmc_core::DelayedRejection::orbital`: stage 1 MH with
//! the pairwise step, stage 2 (after a rejection) the orbital proposal with eq. 11; chi-square
//! stationarity from exact starts checks it on the torus target whose modes straddle both
//! seams and on a 3-D target with a lone third coordinate. Stationarity from exact starts is
//! a weak detector of these local errors (20 000 starts, 30-300 steps, measured while writing
//! these tests: p = 0.44-0.93 for the independent first stage, 1.8e-2 to 1e-15 for the raw
//! orbit, 1e-9 to 7e-3 for a plain Metropolis second stage), so the negative controls are
//! the flow identities, which catch them deterministically.

mod orbital_support;

use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::testing::{ChiSquareReport, StationarityParams};
use mcmc_core::toy::special::normal_interval;
use mcmc_core::toy::{wrapped_normal_pdf, Bins, TorusMixture, ToyTarget};
use mcmc_core::{Kernel, Proposal, Proposed, Target};
use orbital_support::{report, TESTS};
use pss::{
    torus_displacement, wrap, Orbital, PairwiseKelemen, PairwiseKelemenParams, WrappedCauchy,
};
use rand::{Rng, RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;

/// A 3-D target: [`TorusMixture::across_seam`] on the first pair times a wrapped normal
/// (mean 0.97, sd 0.06, across the seam) on the lone third coordinate.
///
/// Bins: a coarse `4 x 4 x 4` grid of `[0, 1)^3` (cell edges at multiples of 1/4, so the
/// seams are cell edges), with exact probabilities from the normal CDF differences of the 7
/// nearest periodic images per axis (as the torus mixture's own bins). Coarse cells give the
/// chi-square its power against smooth, large-scale departures.
#[derive(Clone, Debug)]
struct TorusTimesSeam {
    torus: TorusMixture,
}

const THIRD: (f64, f64) = (0.97, 0.06);

/// Cells per axis of [`TorusTimesSeam`]'s bins.
const CELLS: usize = 4;

/// `P(lo <= X < hi)` for the wrapped normal `(mean, sd)` on `[0, 1)`.
fn wrapped_interval(lo: f64, hi: f64, mean: f64, sd: f64) -> f64 {
    (-3..=3)
        .map(|m| {
            let m = f64::from(m);
            normal_interval((lo + m - mean) / sd, (hi + m - mean) / sd)
        })
        .sum()
}

impl Target for TorusTimesSeam {
    type State = Vec<f64>;
    type Payload = ();
    fn evaluate(&self, x: &mut Vec<f64>, _payload: &mut ()) -> f64 {
        self.log_density(x)
    }
}

impl ToyTarget for TorusTimesSeam {
    fn name(&self) -> &'static str {
        "torus mixture x seam normal"
    }
    fn dim(&self) -> usize {
        3
    }
    fn log_density(&self, x: &[f64]) -> f64 {
        if x.len() != 3 || !(0.0..1.0).contains(&x[2]) {
            return f64::NEG_INFINITY;
        }
        self.torus.log_density(&x[..2]) + wrapped_normal_pdf(x[2], THIRD.0, THIRD.1).ln()
    }
    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let mut x = self.torus.sample_exact(rng);
        let n: f64 = StandardNormal.sample(rng);
        x.push(wrap(THIRD.0 + THIRD.1 * n));
        x
    }
    fn bins(&self) -> Bins {
        let w = 1.0 / CELLS as f64;
        let cell = |i: usize| (i as f64 * w, (i + 1) as f64 * w);
        let mut probabilities = Vec::with_capacity(CELLS.pow(3));
        for i in 0..CELLS {
            for j in 0..CELLS {
                let pair: f64 = self
                    .torus
                    .components()
                    .iter()
                    .map(|c| {
                        c.weight
                            * wrapped_interval(cell(i).0, cell(i).1, c.mean[0], c.sd[0])
                            * wrapped_interval(cell(j).0, cell(j).1, c.mean[1], c.sd[1])
                    })
                    .sum();
                for k in 0..CELLS {
                    probabilities
                        .push(pair * wrapped_interval(cell(k).0, cell(k).1, THIRD.0, THIRD.1));
                }
            }
        }
        Bins::new(probabilities, |x| {
            let c = |v: f64| ((v * CELLS as f64) as usize).min(CELLS - 1);
            (c(x[0]) * CELLS + c(x[1])) * CELLS + c(x[2])
        })
    }
    fn bounding_box(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0; 3], vec![1.0; 3])
    }
}

/// Independent 1-D Kelemen steps per coordinate (the product law of PSSMLT): not circularly
/// symmetric per pair, so eq. 11 is wrong with it (negative control).
#[derive(Clone, Copy, Debug)]
struct IndependentKelemen(PairwiseKelemenParams);

impl Proposal<Vec<f64>> for IndependentKelemen {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clone_from(x);
        for v in y.iter_mut() {
            let r = self.0.radius(rng.random());
            *v = wrap(*v + if rng.random::<f64>() < 0.5 { r } else { -r });
        }
        Proposed::symmetric()
    }
    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        from.iter()
            .zip(to)
            .map(|(a, b)| self.0.single_log_density(torus_displacement(*a, *b)))
            .sum()
    }
    fn is_symmetric(&self) -> bool {
        true
    }
}

/// The orbital rotation applied to the raw displacement `x - y` (no minimal image):
/// negative control for the torus handling.
#[derive(Clone, Copy, Debug)]
struct RawOrbital(WrappedCauchy);

impl ConditionalProposal<Vec<f64>> for RawOrbital {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &Vec<f64>,
        y: &Vec<f64>,
        z: &mut Vec<f64>,
        rng: &mut R,
    ) -> Proposed {
        z.clone_from(x);
        for k in 0..x.len() / 2 {
            let (a, b) = (2 * k, 2 * k + 1);
            let (ux, uy) = (x[a] - y[a], x[b] - y[b]);
            let (s, c) = self.0.sample(rng).sin_cos();
            z[a] = wrap(y[a] + c * ux - s * uy);
            z[b] = wrap(y[b] + s * ux + c * uy);
        }
        Proposed::symmetric()
    }
    fn log_q(&self, _x: &Vec<f64>, _y: &Vec<f64>, _z: &Vec<f64>) -> f64 {
        0.0
    }
}

/// Wide radii, so that few steps cross the modes and the seams often.
fn wide() -> PairwiseKelemenParams {
    PairwiseKelemenParams::new(0.01, 0.2).unwrap()
}

const CHAIN_STARTS: usize = 20_000;
const CHAIN_STEPS: u64 = 30;

fn run<T: ToyTarget, K: Kernel<T> + Clone>(target: &T, kernel: &K, seed: u64) -> ChiSquareReport {
    mcmc_core::testing::toy_stationarity_test(
        target,
        kernel,
        &StationarityParams::new(CHAIN_STARTS, CHAIN_STEPS, seed),
    )
}

#[test]
fn orbital_rule_keeps_targets_across_the_seams() {
    let kernel =
        mcmc_core::DelayedRejection::orbital(PairwiseKelemen::new(wide()), Orbital::default());
    let torus = TorusMixture::across_seam();
    let r = run(&torus, &kernel, 61);
    report("eq. 11 chain on the torus mixture (2-D)", &r);
    r.assert_passes("orbital DR on torus mixture", TESTS);
    let three = TorusTimesSeam { torus };
    let r = run(&three, &kernel, 62);
    report(
        "eq. 11 chain on torus x seam normal (3-D, lone coordinate)",
        &r,
    );
    r.assert_passes("orbital DR on 3-D target", TESTS);
}

/// `log pi(x) + log q1(y | x) + log(1 - a1(x, y)) + log q2(z | x, y) + log a2(x, z)` with
/// `a1 = min(1, pi(y) / pi(x))` and `a2` from eq. 11: the log probability flow density of
/// "propose y, reject it, propose z, accept it" that an orbital DR kernel realises.
fn orbital_log_flow<T: ToyTarget>(
    target: &T,
    q1: &impl Proposal<Vec<f64>>,
    q2: &impl ConditionalProposal<Vec<f64>>,
    [x, y, z]: [&Vec<f64>; 3],
) -> f64 {
    let (lx, ly, lz) = (
        target.log_density(x),
        target.log_density(y),
        target.log_density(z),
    );
    if lx == f64::NEG_INFINITY || ly >= lx {
        return f64::NEG_INFINITY;
    }
    let py = (ly - lx).exp();
    let a2 = (((lz - lx).exp() - py).max(0.0) / (1.0 - py)).min(1.0);
    lx + q1.log_q(x, y) + (-py).ln_1p() + q2.log_q(x, y, z) + a2.ln()
}

/// Over `n` triples `x ~ pi` (half of them moved next to a seam), `y ~ q1(. | x)`,
/// `z ~ q2(. | x, y)`: the number of triples with a positive flow either way, and the
/// number whose forward flow `x -> z` (through `y`) and reverse flow `z -> x` (through the
/// same `y`) differ by more than `1e-9` relative. Detailed balance of the two-stage kernel
/// is exactly "no such triple".
fn flow_mismatches<T: ToyTarget>(
    target: &T,
    q1: &impl Proposal<Vec<f64>>,
    q2: &impl ConditionalProposal<Vec<f64>>,
    n: usize,
    seed: u64,
) -> (usize, usize) {
    let mut rng = Pcg64::seed_from_u64(seed);
    let (mut y, mut z) = (Vec::new(), Vec::new());
    let (mut informative, mut mismatched) = (0, 0);
    for i in 0..n {
        let mut x = target.sample_exact(&mut rng);
        if i % 2 == 0 {
            x[0] = wrap(0.05 * (rng.random::<f64>() - 0.5));
        }
        q1.propose(&x, &mut y, &mut rng);
        if matches!(
            q2.propose(&x, &y, &mut z, &mut rng),
            Proposed::Invalid { .. }
        ) {
            continue;
        }
        let forward = orbital_log_flow(target, q1, q2, [&x, &y, &z]);
        let reverse = orbital_log_flow(target, q1, q2, [&z, &y, &x]);
        if forward == f64::NEG_INFINITY && reverse == f64::NEG_INFINITY {
            continue;
        }
        informative += 1;
        let balanced = (forward - reverse).abs() <= 1e-9 * forward.abs().max(1.0);
        if !balanced {
            mismatched += 1;
        }
    }
    (informative, mismatched)
}

const TRIPLES: usize = 20_000;

#[test]
fn orbital_flows_balance_on_orbit_triples() {
    let target = TorusTimesSeam {
        torus: TorusMixture::across_seam(),
    };
    for (what, params) in [
        ("default radii", PairwiseKelemenParams::drmlt2020()),
        ("wide radii", wide()),
    ] {
        let (informative, mismatched) = flow_mismatches(
            &target,
            &PairwiseKelemen::new(params),
            &Orbital::default(),
            TRIPLES,
            71,
        );
        println!("flow balance, {what}: {mismatched} of {informative} informative triples differ");
        assert!(informative > TRIPLES / 4, "too few informative triples");
        assert_eq!(mismatched, 0);
    }
}

#[test]
fn orbital_flow_negative_controls_fail() {
    let target = TorusTimesSeam {
        torus: TorusMixture::across_seam(),
    };
    let independent = flow_mismatches(
        &target,
        &IndependentKelemen(wide()),
        &Orbital::default(),
        TRIPLES,
        72,
    );
    let raw = flow_mismatches(
        &target,
        &PairwiseKelemen::new(wide()),
        &RawOrbital(WrappedCauchy::rioux_lavoie2020()),
        TRIPLES,
        73,
    );
    for (what, (informative, mismatched)) in [
        ("first stage of independent 1-D Kelemen steps", independent),
        ("orbit from the raw displacement", raw),
    ] {
        println!(
            "negative control, {what}: {mismatched} of {informative} informative triples differ"
        );
        assert!(
            mismatched * 20 > informative,
            "{what}: only {mismatched} of {informative} triples out of balance"
        );
    }
}
