//! The measured claims of the delayed-rejection tests: Tierney-Mira's vanishing second-stage
//! acceptance after a Kelemen first stage versus the orbital rule (section 4.3), and the
//! integrated autocorrelation times on the 1-D toy of Fig. 3 (a module of
//! `tests/delayed_rejection.rs`, whose Sidak count includes these comparisons).

use std::cell::Cell;
use std::f64::consts::FRAC_PI_6;
use std::rc::Rc;

use super::fixtures::{ProductKelemen, Ridges};
use super::{grw, level, rho, tm_fig3};
use mcmc_core::delayed_rejection::{IndependentSecondStage, OrbitalWalk, RadialKelemen};
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::stats::{integrated_autocorrelation_time, AcceptanceStats};
use mcmc_core::toy::special::normal_cdf;
use mcmc_core::toy::{Ridge, ToyTarget, UniformMixture};
use mcmc_core::{
    Chain, DelayedRejection, Euclidean, Kernel, Mh, NoAdaptation, Observer, Proposed, StepInfo,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

// ---- 5. vanishing second-stage acceptance (section 4.3) ----

/// Counts second-stage proposals whose candidate `z` cannot reach the rejected `y` with the
/// first stage (`Q1(y | z) = 0`: the Tierney-Mira ratio vanishes, Fig. 4).
#[derive(Clone, Debug)]
struct CountVanished<Q, Q1> {
    inner: Q,
    first: Q1,
    counts: Rc<Cell<(u64, u64)>>,
}

impl<Q: ConditionalProposal<Vec<f64>>, Q1: mcmc_core::Proposal<Vec<f64>>>
    ConditionalProposal<Vec<f64>> for CountVanished<Q, Q1>
{
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &Vec<f64>,
        y: &Vec<f64>,
        z: &mut Vec<f64>,
        rng: &mut R,
    ) -> Proposed {
        let p = self.inner.propose(x, y, z, rng);
        let (vanished, total) = self.counts.get();
        let v = u64::from(self.first.log_q(z, y) == f64::NEG_INFINITY);
        self.counts.set((vanished + v, total + 1));
        p
    }
    fn log_q(&self, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        self.inner.log_q(x, y, z)
    }
}

/// Per-chain mean second-stage acceptance probability.
#[derive(Default)]
struct StageTwo {
    tried: u64,
    sum: f64,
}

impl<S, P> Observer<S, P> for StageTwo {
    fn step(&mut self, info: &StepInfo) {
        if info.stages_tried == 2 {
            self.tried += 1;
            self.sum += info.accept_prob[1];
        }
    }
}

/// Mean and standard error over `chains` independent chains (exact starts, 500 steps) of the
/// per-chain mean `a2`.
fn mean_a2<K: Kernel<Ridges> + Clone>(target: &Ridges, kernel: &K, seed: u64) -> (f64, f64) {
    let chains = 200;
    let means: Vec<f64> = (0..chains)
        .map(|i| {
            let mut rng = Pcg64::seed_from_u64(mcmc_core::seed::chain_seed(seed, i));
            let x0 = target.sample_exact(&mut rng);
            let mut chain = Chain::new(target, kernel.clone(), NoAdaptation, rng, x0).unwrap();
            let mut o = StageTwo::default();
            chain.run(500, &mut o).unwrap();
            o.sum / o.tried.max(1) as f64
        })
        .collect();
    mean_and_se(&means)
}

fn mean_and_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// The one-sided standard normal quantile `z` with `P(Z > z) = p` (bisection on the CDF).
fn upper_quantile(p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 40.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if 1.0 - normal_cdf(mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Asserts `big > small` by a one-sided Welch z-test at the file's Sidak level.
fn assert_greater(what: &str, big: (f64, f64), small: (f64, f64)) {
    let z = (big.0 - small.0) / (big.1 * big.1 + small.1 * small.1).sqrt();
    let z_crit = upper_quantile(level());
    eprintln!(
        "{what}: {:.4} +- {:.4} vs {:.4} +- {:.4}, z = {z:.1} (critical {z_crit:.2})",
        big.0, big.1, small.0, small.1
    );
    assert!(z > z_crit, "{what}: z = {z} <= {z_crit}");
}

/// Tierney-Mira after Kelemen's product mutation (eq. 9, bounds [1/1024, 1/64]) with the
/// reference implementation's timid Gaussian second stage (sigma = 1/640) against the orbital
/// rule after the pairwise polar Kelemen step (bounds x 1.9, rho = exp(-1/4)), on a thin ridge
/// at the Kelemen scale (across-sd 0.005), in 2-D and as 8 independent pairs (16-D).
#[test]
fn tierney_mira_vanishes_where_the_orbital_rule_does_not() {
    let ridge = Ridge::new(FRAC_PI_6, 0.2, 0.005).unwrap();
    let kelemen = ProductKelemen::kelemen2002();
    let mut results = Vec::new();
    for (pairs, seed) in [(1usize, 71u64), (8, 72)] {
        let target = Ridges { ridge, pairs };
        let counts = Rc::new(Cell::new((0, 0)));
        let tm = DelayedRejection::tierney_mira(
            kelemen,
            CountVanished {
                inner: IndependentSecondStage(grw(1.0 / 640.0)),
                first: kelemen,
                counts: counts.clone(),
            },
        )
        .with_symmetric_second_stage();
        let radial = RadialKelemen::new(1.9 / 1024.0, 1.9 / 64.0).unwrap();
        let orbit_counts = Rc::new(Cell::new((0, 0)));
        let orbital = DelayedRejection::orbital(
            radial,
            CountVanished {
                inner: OrbitalWalk::new(rho()).unwrap(),
                first: radial,
                counts: orbit_counts.clone(),
            },
        );
        let gm = DelayedRejection::green_mira(
            kelemen,
            IndependentSecondStage(grw(1.0 / 640.0)),
            Euclidean,
        )
        .with_symmetric_second_stage();
        let a_tm = mean_a2(&target, &tm, seed);
        let a_orbital = mean_a2(&target, &orbital, seed);
        let a_gm = mean_a2(&target, &gm, seed);
        let (v, n) = counts.get();
        let (vo, no) = orbit_counts.get();
        eprintln!(
            "{}-D ridge: mean a2 TM {:.4} (Q1(y|z) = 0 in {:.1}% of {n}), GM {:.4}, orbital {:.4} \
             (Q1(y|z) = 0 in {vo} of {no})",
            2 * pairs,
            a_tm.0,
            100.0 * v as f64 / n as f64,
            a_gm.0,
            a_orbital.0
        );
        assert_eq!(vo, 0, "the orbital stage left the first stage's support");
        assert!(v > 0);
        assert_greater(
            &format!("{}-D: orbital a2 > TM a2", 2 * pairs),
            a_orbital,
            a_tm,
        );
        results.push(a_tm);
    }
    assert_greater("TM a2: 2-D > 16-D", results[0], results[1]);
}

// ---- 6. the 1-D toy of Fig. 3: integrated autocorrelation times ----

/// Integrated autocorrelation times of `x` and of `1[x < 0]` (the spike) over `chains`
/// independent chains from exact starts, and the acceptance rate.
fn iats<K: Kernel<UniformMixture> + Clone>(
    kernel: &K,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, AcceptanceStats) {
    let target = UniformMixture::rioux_lavoie2020();
    let (chains, steps) = (16u64, 50_000usize);
    let (mut tau_x, mut tau_spike) = (Vec::new(), Vec::new());
    let mut stats = AcceptanceStats::default();
    for i in 0..chains {
        let mut rng = Pcg64::seed_from_u64(mcmc_core::seed::chain_seed(seed, i));
        let x0 = target.sample_exact(&mut rng);
        let mut chain = Chain::new(&target, kernel.clone(), NoAdaptation, rng, x0).unwrap();
        let (mut xs, mut spike) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
        for _ in 0..steps {
            chain.step(&mut ()).unwrap();
            xs.push(chain.state()[0]);
            spike.push(f64::from(u8::from(chain.state()[0] < 0.0)));
        }
        tau_x.push(integrated_autocorrelation_time(&xs));
        tau_spike.push(integrated_autocorrelation_time(&spike));
        stats.merge(chain.stats());
    }
    (tau_x, tau_spike, stats)
}

/// Fig. 3: MH with a large sigma (beta = 1, the plateau), MH with a small sigma (alpha = 1/10,
/// the spike), and Tierney-Mira DR with the large step first and the small one second.
#[test]
fn delayed_rejection_mixes_faster_on_the_fig3_toy() {
    let large = iats(&Mh::new(grw(1.0)), 81);
    let small = iats(&Mh::new(grw(0.1)), 82);
    let dr = iats(&tm_fig3(), 83);
    let gm = iats(
        &DelayedRejection::green_mira(grw(1.0), IndependentSecondStage(grw(0.1)), Euclidean)
            .with_symmetric_second_stage(),
        84,
    );
    for (name, r) in [
        ("MH sigma 1", &large),
        ("MH sigma 0.1", &small),
        ("DR TM 1 then 0.1", &dr),
        ("DR GM 1 then 0.1", &gm),
    ] {
        let (x, s) = (mean_and_se(&r.0), mean_and_se(&r.1));
        eprintln!(
            "Fig. 3 toy, {name}: acceptance {:.3} (stage 1 {:.3}, stage 2 {:.3} of {:.1}% of \
             steps; mean a1 {:.3}, mean a2 {:.3}), IAT(x) {:.1} +- {:.1}, IAT(1[x<0]) {:.1} +- \
             {:.1}",
            r.2.acceptance_rate(),
            r.2.stage_acceptance_rate(0),
            r.2.stage_acceptance_rate(1),
            100.0 * r.2.stage_tried[1] as f64 / r.2.steps as f64,
            r.2.stage_mean_accept_prob(0),
            r.2.stage_mean_accept_prob(1),
            x.0,
            x.1,
            s.0,
            s.1
        );
    }
    assert_greater(
        "IAT(x): MH sigma 1 > DR",
        mean_and_se(&large.0),
        mean_and_se(&dr.0),
    );
    assert_greater(
        "IAT(x): MH sigma 0.1 > DR",
        mean_and_se(&small.0),
        mean_and_se(&dr.0),
    );
}
