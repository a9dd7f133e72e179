//! MALA with adaptation (`mcmc_core::langevin`) passes the harness with its adaptation state
//! fixed: pairwise flow balance on random pairs and chi-square stationarity from exact starts,
//! on the ridge, the banana, the disconnected mixture and a torus mixture with mass across the
//! seams; the same after adaptation has stopped (cache full) or has run long (diminishing
//! adaptation at t = 10^6); cheap-then-expensive delayed rejection passes the two-stage flow
//! balance (through the ghost y*) and stationarity. Negative controls: the authors' code's
//! reverse density (the reverse Gaussian formed from statistics that already hold g(x)) fails
//! the pairwise balance; a MALA step without its Hastings term fails it and stationarity.
//!
//! Run with `cargo test -p mcmc-core --release --test langevin -- --nocapture` for the
//! statistics.
//!
//! Statistics: every stationarity test is exact under the null (independent exact starts, a
//! fixed kernel), so its p-value is uniform; each must pass at the Sidak level for
//! [`STATIONARITY_TESTS`] tests, keeping the file's false-failure probability at 0.01. The
//! negative controls must *fail* at the same level. Pairwise checks are identities (1e-9).

use mcmc_core::delayed_rejection::{Euclidean, Torus};
use mcmc_core::langevin::{
    AdamStart, Adaptation, AnyAdaptation, CacheDriven, CheapThenExpensive, FullOnline, Hybrid,
    Langevin, LangevinParams, LangevinSpace, Online, Plain, ProposalGaussian,
};
use mcmc_core::proposal::IndependentUniform;
use mcmc_core::testing::{
    assert_pairwise_balance, assert_path_balance, stationarity_test, PairwiseParams,
    StationarityParams,
};
use mcmc_core::toy::{Banana, GaussianMixture2d, Ridge, TorusMixture, ToyTarget};
use mcmc_core::{
    Chain, DifferentiableTarget, FiniteDifference, GaussianRandomWalk, Kernel, NoAdaptation, Target,
};
use proptest::prelude::*;
use proptest::strategy::BoxedStrategy;
use rand::SeedableRng;

/// Stationarity tests in this file that must pass (Sidak correction). Keep in sync.
const STATIONARITY_TESTS: usize = 40;
// 3 x 8 Euclidean variants + 7 torus + full ridge + long DA + 3 DR + 2 splat = 38.
const STARTS: usize = 10_000;
const STEPS: u64 = 20;

/// The large step of the toys: an independent uniform point of the target's box.
fn uniform_box<T: ToyTarget>(t: &T) -> IndependentUniform {
    let (lo, hi) = t.bounding_box();
    IndependentUniform::new(lo, hi).unwrap()
}

/// A differentiable toy: the toy itself when it has an analytic gradient, else central
/// finite differences (h = 1e-6; forward and reverse use the same deterministic gradient).
fn fd<T: Target<State = Vec<f64>>>(t: T) -> FiniteDifference<T> {
    FiniteDifference { target: t, h: 1e-6 }
}

/// Pairs `(x, x + noise)` with `x` in the target's box (enlarged by 10 %) and noise of
/// standard deviation `scale`: MALA's flows between distant states are astronomically small,
/// so pairs are drawn where the kernel actually moves.
fn near_pairs<T: ToyTarget>(target: &T, scale: f64) -> BoxedStrategy<Vec<Vec<f64>>> {
    let (lo, hi) = target.bounding_box();
    let ranges: Vec<_> = lo
        .iter()
        .zip(&hi)
        .map(|(&l, &h)| {
            let m = 0.1 * (h - l);
            (l - m)..(h + m)
        })
        .collect();
    let d = lo.len();
    (ranges, prop::collection::vec(-3.0..3.0f64, d))
        .prop_map(move |(x, n)| {
            let y: Vec<f64> = x.iter().zip(&n).map(|(a, b)| a + scale * b).collect();
            vec![x, y]
        })
        .boxed()
}

/// Runs `warmup` adapting steps of `kernel` on `target` from `start`, then freezes it.
fn warmed<T, K>(target: &T, kernel: K, start: Vec<f64>, warmup: u64, seed: u64) -> K
where
    T: Target<State = Vec<f64>>,
    K: Kernel<T> + Clone,
{
    let rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut chain = Chain::new(target, kernel, NoAdaptation, rng, start).unwrap();
    chain.run(warmup, &mut ()).unwrap();
    chain.kernel().clone()
}

/// Pairwise balance on near pairs and on random pairs, then stationarity from exact starts.
fn check<T, K>(what: &str, target: &T, toy: &impl ToyTarget, kernel: &K, scale: f64, seed: u64)
where
    T: Target<State = Vec<f64>>,
    K: Kernel<T> + Clone,
{
    let near = assert_path_balance(
        target,
        kernel,
        near_pairs(toy, scale),
        &PairwiseParams::with_seed(seed),
    );
    let report = stationarity_test(
        target,
        kernel,
        |rng| toy.sample_exact(rng),
        &toy.bins(),
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!(
        "{what}: pairwise {}/{} informative (worst {:.1e}); stationarity {report}",
        near.informative, near.cases, near.worst_log_difference
    );
    report.assert_passes(what, STATIONARITY_TESTS);
}

fn params(epsilon: f64) -> LangevinParams {
    LangevinParams {
        epsilon,
        cache_size: 400,
        ..LangevinParams::luan2020()
    }
}

/// Every adaptation variant with the warm-up (adapting steps before freezing) it is checked
/// after: plain; online with and without DA; cache partial (frozen before full) and full;
/// hybrid in its online and its cache stage; full preconditioning (not on a torus: the images
/// of a full Gaussian do not factorise).
fn variants(p: &LangevinParams, with_full: bool) -> Vec<(&'static str, AnyAdaptation, u64)> {
    let mut v = vec![
        ("plain", AnyAdaptation::Plain(Plain), 0),
        ("online (DA)", AnyAdaptation::Online(Online::new(true)), 500),
        (
            "online (no DA)",
            AnyAdaptation::Online(Online::new(false)),
            500,
        ),
        (
            "cache (partial)",
            AnyAdaptation::Cache(CacheDriven::new(p)),
            150,
        ),
        (
            "cache (full)",
            AnyAdaptation::Cache(CacheDriven::new(p)),
            3000,
        ),
        (
            "hybrid (online stage)",
            AnyAdaptation::Hybrid(Hybrid::new(p)),
            150,
        ),
        (
            "hybrid (cache stage)",
            AnyAdaptation::Hybrid(Hybrid::new(p)),
            3000,
        ),
    ];
    if with_full {
        v.push((
            "full online (no DA)",
            AnyAdaptation::Full(FullOnline::new(false)),
            300,
        ));
    }
    v
}

/// Every adaptation on one Euclidean toy: plain; online with and without diminishing
/// adaptation (frozen after a warm-up); online after a long run (t = 10^6, adapting); full
/// online; cache-driven with a partial (frozen) and a full cache; hybrid in both stages.
/// Each is mixed with a large step (p 0.1) and a fallback walk (p 0.1).
fn check_all_euclidean<T>(
    name: &str,
    target: &T,
    toy: &impl ToyTarget,
    epsilon: f64,
    start: Vec<f64>,
    seed: u64,
    full: bool,
) where
    T: DifferentiableTarget<State = Vec<f64>>,
{
    let p = params(epsilon);
    let large = uniform_box(toy);
    let fallback = GaussianRandomWalk::new(0.3).unwrap();
    let build = |a: AnyAdaptation| {
        Langevin::new(p, a, Euclidean)
            .unwrap()
            .with_large_step(large.clone(), 0.1)
            .unwrap()
            .with_fallback(fallback, 0.1)
            .unwrap()
    };
    let variants = variants(&p, true);
    for (i, (label, adaptation, warmup)) in variants.into_iter().enumerate() {
        let mut kernel = warmed(
            target,
            build(adaptation),
            start.clone(),
            warmup,
            seed + i as u64,
        );
        kernel.freeze();
        if label.starts_with("cache (full)") || label.starts_with("hybrid (cache") {
            let view = match &kernel.adaptation {
                AnyAdaptation::Cache(c) => c.cache(),
                AnyAdaptation::Hybrid(h) => h.cache(),
                _ => unreachable!(),
            };
            assert!(
                view.is_full(),
                "{label}: the cache should be full after {warmup} steps ({} entries)",
                view.len()
            );
        }
        // With `full`, every variant also runs the stationarity test; otherwise only the
        // plain kernel does (keeps the file's test count bounded) and the others are checked
        // pairwise, with stationarity on the ridge and the torus.
        if full || label == "plain" {
            check(
                &format!("{name} / {label}"),
                target,
                toy,
                &kernel,
                epsilon.sqrt(),
                seed + 100 + i as u64,
            );
        } else {
            let r = assert_path_balance(
                target,
                &kernel,
                near_pairs(toy, epsilon.sqrt()),
                &PairwiseParams::with_seed(seed + 200 + i as u64),
            );
            eprintln!(
                "{name} / {label}: pairwise {}/{} informative (worst {:.1e})",
                r.informative, r.cases, r.worst_log_difference
            );
        }
    }
}

// ---- the four toys ----

#[test]
fn ridge_every_adaptation() {
    let t = Ridge::thin();
    check_all_euclidean("ridge", &t, &t, 0.004, vec![0.0, 0.0], 10, true);
}

#[test]
fn banana_every_adaptation() {
    let t = Banana::haario(0.03).unwrap();
    check_all_euclidean("banana", &t, &t, 0.5, vec![0.0, 0.0], 20, true);
}

#[test]
fn disconnected_mixture_every_adaptation() {
    let t = GaussianMixture2d::disconnected();
    let start = t.components()[0].mean.to_vec();
    check_all_euclidean("mixture", &fd(t.clone()), &t, 0.05, start, 30, true);
}

#[test]
fn full_preconditioning_on_the_ridge() {
    let t = Ridge::thin();
    let p = params(0.004);
    let mut kernel = warmed(
        &t,
        Langevin::new(p, FullOnline::new(true), Euclidean).unwrap(),
        vec![0.0, 0.0],
        500,
        40,
    );
    kernel.freeze();
    check("ridge / full online", &t, &t, &kernel, 0.06, 41);
}

#[test]
fn torus_seam_every_adaptation() {
    // PSS-like: coordinates wrap, the move density is the wrapped Gaussian; modes straddle
    // the seams.
    let toy = TorusMixture::across_seam();
    let t = fd(toy.clone());
    let p = params(0.002);
    let large = IndependentUniform::new(vec![0.0, 0.0], vec![1.0, 1.0]).unwrap();
    let variants = variants(&p, false);
    for (i, (label, a, warmup)) in variants.into_iter().enumerate() {
        let kernel = Langevin::new(p, a, Torus)
            .unwrap()
            .with_large_step(large.clone(), 0.1)
            .unwrap();
        let mut kernel = warmed(&t, kernel, vec![0.02, 0.98], warmup, 50 + i as u64);
        kernel.freeze();
        check(
            &format!("torus seam / {label}"),
            &t,
            &toy,
            &kernel,
            0.05,
            60 + i as u64,
        );
    }
}

#[test]
fn online_after_a_long_run_stays_stationary() {
    // Diminishing adaptation run long: the counter at t = 10^6 (weights t^-0.5 = 0.001),
    // adaptation *not* frozen during the test chains.
    let t = Ridge::thin();
    let p = params(0.004);
    let mut online = Online::new(true);
    online.set_steps(1_000_000);
    let kernel = warmed(
        &t,
        Langevin::new(p, online, Euclidean).unwrap(),
        vec![0.0, 0.0],
        500,
        70,
    );
    assert!(!kernel.adaptation.is_frozen());
    check(
        "ridge / online (DA, t = 1e6, adapting)",
        &t,
        &t,
        &kernel,
        0.06,
        71,
    );
}

// ---- cheap-then-expensive delayed rejection ----

/// Triples `(x, y, z)` with `y`, `z` near `x` (wrapped onto the unit square with `wrap`:
/// the kernel's candidates on the torus always are).
fn triples<T: ToyTarget>(toy: &T, s1: f64, s2: f64, wrap: bool) -> BoxedStrategy<Vec<Vec<f64>>> {
    let w = move |v: f64| if wrap { mcmc_core::torus::wrap(v) } else { v };
    let (lo, hi) = toy.bounding_box();
    let ranges: Vec<_> = lo.iter().zip(&hi).map(|(&l, &h)| l..h).collect();
    let d = lo.len();
    (
        ranges,
        prop::collection::vec(-3.0..3.0f64, d),
        prop::collection::vec(-3.0..3.0f64, d),
    )
        .prop_map(move |(x, a, b)| {
            let y: Vec<f64> = x.iter().zip(&a).map(|(v, n)| w(v + s1 * n)).collect();
            let z: Vec<f64> = x.iter().zip(&b).map(|(v, n)| w(v + s2 * n)).collect();
            vec![x, y, z]
        })
        .boxed()
}

#[test]
fn cheap_then_expensive_balance_and_stationarity() {
    let t = Ridge::thin();
    let p = params(0.004);
    let large = uniform_box(&t);
    for (i, (label, a)) in [
        ("plain", AnyAdaptation::Plain(Plain)),
        ("online (DA)", AnyAdaptation::Online(Online::new(true))),
    ]
    .into_iter()
    .enumerate()
    {
        let kernel = CheapThenExpensive::new(p, 0.5, a, Euclidean)
            .unwrap()
            .with_large_step(large.clone(), 0.1)
            .unwrap();
        let mut kernel = warmed(&t, kernel, vec![0.0, 0.0], 300, 80 + i as u64);
        kernel.adaptation.freeze();
        let r2 = assert_pairwise_balance(
            &t,
            &kernel,
            near_pairs(&t, 0.5).prop_map(|v| v[0].clone()),
            &PairwiseParams::with_seed(90 + i as u64),
        );
        let r3 = assert_path_balance(
            &t,
            &kernel,
            triples(&t, 0.5, 0.06, false),
            &PairwiseParams::with_seed(91 + i as u64),
        );
        eprintln!("cheap-then-expensive / {label}: pairs+triples {} informative, triples near {} (worst {:.1e})", r2.informative, r3.informative, r3.worst_log_difference);
        check(
            &format!("ridge / cheap-then-expensive ({label})"),
            &t,
            &t,
            &kernel,
            0.5,
            95 + i as u64,
        );
    }
    // On the torus, with the ghost wrapping across the seam.
    let toy = TorusMixture::across_seam();
    let tt = fd(toy.clone());
    let kernel = CheapThenExpensive::new(params(0.002), 0.2, Plain, Torus).unwrap();
    let r = assert_path_balance(
        &tt,
        &kernel,
        triples(&toy, 0.2, 0.05, true),
        &PairwiseParams::with_seed(97),
    );
    eprintln!(
        "torus / cheap-then-expensive: triples {} informative",
        r.informative
    );
    check(
        "torus seam / cheap-then-expensive",
        &tt,
        &toy,
        &kernel,
        0.2,
        98,
    );
}

// ---- negative controls ----

/// The authors' code's reverse density: the reverse Gaussian at `y` blends `g(y)` into chain
/// statistics that *already* hold `g(x)` (`v2' = beta v2_chain + (1 - beta) g(y)^2`), while
/// the forward Gaussian used the statistics before `g(x)`. A step-level fixture: the kernel
/// calls `gaussian` for the forward move, then for the reverse one.
#[derive(Clone, Debug)]
struct CodeReverse {
    inner: Online,
    forward_gradient: Option<Vec<f64>>,
}

impl Adaptation for CodeReverse {
    fn name(&self) -> &'static str {
        "code-reverse"
    }
    fn needs_gradient(&self, _dim: usize) -> bool {
        true
    }
    fn gaussian(
        &mut self,
        p: &LangevinParams,
        u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        match self.forward_gradient.take() {
            None => {
                self.forward_gradient = Some(g.to_vec());
                self.inner.gaussian(p, u, g, out)
            }
            Some(gx) => {
                let mut ahead = self.inner.clone();
                ahead.adapt(p, u, &gx, false);
                ahead.gaussian(p, u, g, out)
            }
        }
    }
    fn adapt(&mut self, _: &LangevinParams, _: &[f64], _: &[f64], _: bool) {
        // Frozen statistics; a new step starts with a forward Gaussian.
        self.forward_gradient = None;
    }
    fn freeze(&mut self) {}
    fn is_frozen(&self) -> bool {
        false
    }
}

/// MALA without its Hastings term: the reverse Gaussian is the forward one mirrored (so the
/// two densities cancel), i.e. the drift is ignored in the acceptance.
#[derive(Clone, Debug)]
struct NoHastings {
    forward: Option<ProposalGaussian>,
}

impl Adaptation for NoHastings {
    fn name(&self) -> &'static str {
        "no-hastings"
    }
    fn needs_gradient(&self, _dim: usize) -> bool {
        true
    }
    fn gaussian(
        &mut self,
        p: &LangevinParams,
        u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        match self.forward.take() {
            None => {
                Plain.gaussian(p, u, g, out);
                self.forward = Some(out.clone());
            }
            Some(_) => {
                // The isotropic Gaussian without drift: density of -offset equals that of the
                // forward offset only for a zero drift; with it the ratio is 1 in expectation
                // of nothing. Using zero drift on both sides is MALA proposing with drift but
                // accepting as a symmetric walk.
                let zeros = vec![0.0; g.len()];
                Plain.gaussian(p, u, &zeros, out);
            }
        }
        true
    }
    fn adapt(&mut self, _: &LangevinParams, _: &[f64], _: &[f64], _: bool) {
        self.forward = None;
    }
    fn freeze(&mut self) {}
    fn is_frozen(&self) -> bool {
        false
    }
}

/// Runs `f` and reports whether it panicked (the pairwise check panics on a violation).
fn fails(f: impl FnOnce()) -> bool {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).is_err()
}

#[test]
fn negative_controls_fail() {
    let t = Ridge::thin();
    let p = params(0.004);
    let warm = warmed(
        &t,
        Langevin::new(p, Online::new(false), Euclidean).unwrap(),
        vec![0.0, 0.0],
        200,
        110,
    );
    // Not frozen: `CodeReverse` never calls `adapt` on it (its statistics stay as they are),
    // but it advances a copy for the reverse Gaussian.
    let online = warm.adaptation.clone();
    // The exact reverse with these statistics passes (see `ridge / online (no DA)` above);
    // the authors' reverse with the same statistics does not.
    let code = Langevin::new(
        p,
        CodeReverse {
            inner: online,
            forward_gradient: None,
        },
        Euclidean,
    )
    .unwrap();
    assert!(
        fails(|| {
            assert_path_balance(
                &t,
                &code,
                near_pairs(&t, 0.06),
                &PairwiseParams::with_seed(111),
            );
        }),
        "the authors' reverse density should fail the pairwise balance"
    );
    let broken = Langevin::new(p, NoHastings { forward: None }, Euclidean).unwrap();
    assert!(
        fails(|| {
            assert_path_balance(
                &t,
                &broken,
                near_pairs(&t, 0.06),
                &PairwiseParams::with_seed(112),
            );
        }),
        "MALA without its Hastings term should fail the pairwise balance"
    );
    // ...and the missing Hastings term biases the chain visibly.
    let report = stationarity_test(
        &t,
        &broken,
        |rng| t.sample_exact(rng),
        &t.bins(),
        &StationarityParams::new(STARTS, 200, 113),
    );
    eprintln!("negative control, MALA without Hastings term: {report}");
    assert!(
        report.rejects(mcmc_core::testing::sidak_alpha(0.01, STATIONARITY_TESTS)),
        "MALA without its Hastings term should fail stationarity: {report}"
    );
}

// ---- cache behaviour and truncation ----

#[test]
fn cache_stops_growing_at_h_and_truncation_applies() {
    let t = Ridge::thin();
    let p = LangevinParams {
        cache_size: 123,
        ..params(0.004)
    };
    let kernel = Langevin::new(p, CacheDriven::new(&p), Euclidean).unwrap();
    let mut chain = Chain::new(
        &t,
        kernel,
        NoAdaptation,
        rand_pcg::Pcg64::seed_from_u64(5),
        vec![0.0, 0.0],
    )
    .unwrap();
    chain.run(5000, &mut ()).unwrap();
    let cache = chain.kernel().adaptation.cache();
    assert_eq!(cache.len(), 123);
    assert!(cache.is_full() && chain.kernel().adaptation.is_frozen());
    // Truncation: a gradient component of 1e6 is clamped to 100.
    let mut g = vec![1e6, -1e6, 5.0, f64::NAN];
    p.truncate(&mut g);
    assert_eq!(g, vec![100.0, -100.0, 5.0, 0.0]);
    // ...and the kernel uses it: on a steep target the drift is at most eps * 100 / 2.
    struct Steep;
    impl Target for Steep {
        type State = Vec<f64>;
        type Payload = ();
        fn evaluate(&self, x: &mut Vec<f64>, _: &mut ()) -> f64 {
            -1e4 * x[0]
        }
    }
    impl DifferentiableTarget for Steep {
        fn evaluate_with_grad(&self, x: &mut Vec<f64>, _: &mut (), g: &mut Vec<f64>) -> f64 {
            g.clear();
            g.push(-1e4);
            -1e4 * x[0]
        }
    }
    let pp = params(0.01);
    let k = Langevin::new(pp, Plain, Euclidean).unwrap();
    let mut g = vec![-1e4];
    pp.truncate(&mut g);
    let mut q = ProposalGaussian::default();
    let mut plain = Plain;
    plain.gaussian(&pp, &[0.0], &g, &mut q);
    assert!((q.mean()[0] + 0.5).abs() < 1e-12, "drift {}", q.mean()[0]);
    let fwd = k.log_mala_density(&vec![0.0], &g, &vec![-0.5]);
    assert!(fwd.is_finite());
    let _ = Euclidean.wraps();
    let _ = Steep;
}

// ---- diminishing adaptation (the paper's Fig. 3g point) ----

/// Runs `CHAINS` independent chains of online MALA (paper parameters: epsilon 0.01,
/// alpha 0.9, beta 0.999; no large step) on the thin ridge from exact starts, each for
/// `STEPS_LONG` steps with adaptation running from t = 0, and estimates E[x0^2] per chain from
/// the second half of its states. Returns (mean over chains, standard error over chains,
/// z = (mean - exact) / standard error). The chains are independent, so z is approximately
/// standard normal when the chain is unbiased.
fn ridge_second_moment(diminishing: bool) -> (f64, f64, f64) {
    ridge_second_moment_with(diminishing, AdamStart::Zero, 0.0)
}

/// [`ridge_second_moment`] with the accumulators' start `start` and large steps (uniform on
/// the ridge's box) of probability `p_large`, which restart them under
/// [`AdamStart::FirstVisit`].
fn ridge_second_moment_with(diminishing: bool, start: AdamStart, p_large: f64) -> (f64, f64, f64) {
    const CHAINS: u64 = 800;
    const STEPS_LONG: u64 = 20_000;
    let t = Ridge::thin();
    // x0 = cos(30) u - sin(30) v with sd(u) = 1, sd(v) = 0.05.
    let exact = 0.75 * 1.0 + 0.25 * 0.05 * 0.05;
    let p = LangevinParams {
        adam_start: start,
        ..LangevinParams::luan2020()
    };
    let estimates: Vec<f64> = (0..CHAINS)
        .map(|c| {
            let kernel = Langevin::new(p, Online::new(diminishing), Euclidean)
                .unwrap()
                .with_large_step(uniform_box(&t), p_large)
                .unwrap();
            let mut rng = rand_pcg::Pcg64::seed_from_u64(0xB1A5 + c);
            let start = t.sample_exact(&mut rng);
            let mut chain = Chain::new(&t, kernel, NoAdaptation, rng, start).unwrap();
            let mut sum = 0.0;
            for i in 0..STEPS_LONG {
                chain.step(&mut ()).unwrap();
                if i >= STEPS_LONG / 2 {
                    sum += chain.state()[0] * chain.state()[0];
                }
            }
            sum / (STEPS_LONG / 2) as f64
        })
        .collect();
    let n = estimates.len() as f64;
    let mean = estimates.iter().sum::<f64>() / n;
    let var = estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt();
    (mean, se, (mean - exact) / se)
}

/// Bound on |z|: 4 standard errors (two-sided 6e-5 per test).
const Z_BOUND: f64 = 4.0;

#[test]
fn online_without_diminishing_adaptation_is_biased() {
    let (mean, se, z) = ridge_second_moment(false);
    eprintln!("online MALA without DA: E[x0^2] = {mean:.4} +- {se:.4} (exact 0.7506), z = {z:.1}");
    assert!(
        z.abs() > Z_BOUND,
        "expected a bias beyond {Z_BOUND} standard errors, z = {z:.2}"
    );
}

#[test]
fn online_with_diminishing_adaptation_is_not_biased() {
    let (mean, se, z) = ridge_second_moment(true);
    eprintln!("online MALA with DA: E[x0^2] = {mean:.4} +- {se:.4} (exact 0.7506), z = {z:.1}");
    assert!(
        z.abs() < Z_BOUND,
        "z = {z:.2} beyond {Z_BOUND} standard errors"
    );
}

/// The authors' start (accumulators at the first gradient, restarted at every accepted large
/// step) keeps diminishing adaptation exact: restarts happen after decisions and leave the
/// diminishing weights alone. Its negative control is the same start without diminishing
/// adaptation, which stays biased.
#[test]
fn online_with_first_visit_starts_and_restarts_is_not_biased() {
    let (mean, se, z) = ridge_second_moment_with(true, AdamStart::FirstVisit, 0.1);
    eprintln!(
        "online MALA, first-visit starts, large steps 0.1: E[x0^2] = {mean:.4} +- {se:.4} (exact 0.7506), z = {z:.1}"
    );
    assert!(
        z.abs() < Z_BOUND,
        "z = {z:.2} beyond {Z_BOUND} standard errors"
    );
    let (mean, se, z) = ridge_second_moment_with(false, AdamStart::FirstVisit, 0.1);
    eprintln!("negative control, the same without DA: E[x0^2] = {mean:.4} +- {se:.4}, z = {z:.1}");
    assert!(
        z.abs() > Z_BOUND,
        "expected a bias beyond {Z_BOUND} standard errors, z = {z:.2}"
    );
}

/// Under [`AdamStart::FirstVisit`] the first Gaussian uses the point's own gradient
/// (`G' = g^2`, not `0.001 g^2`), and an accepted large step makes the next one fresh again.
#[test]
fn first_visit_start_is_not_inflated_and_restarts() {
    let g = [2.0, -0.5];
    let u = [0.1, 0.2];
    let first = |start: AdamStart| {
        let p = LangevinParams {
            adam_start: start,
            ..LangevinParams::luan2020()
        };
        let mut a = Online::new(true);
        let mut q = ProposalGaussian::default();
        assert!(a.gaussian(&p, &u, &g, &mut q));
        (p, a, q)
    };
    let (_, _, zero) = first(AdamStart::Zero);
    let (p, mut a, fv) = first(AdamStart::FirstVisit);
    // At t = 0 the diminishing weight is 1: M = 1 / (delta + sqrt(G')).
    let m = |g2: f64| 1.0 / (p.delta + g2.sqrt());
    for (i, gi) in g.iter().enumerate() {
        let expect_fv = p.epsilon * m(gi * gi);
        let expect_zero = p.epsilon * m((1.0 - p.beta) * gi * gi);
        assert!((fv.std()[i].powi(2) - expect_fv).abs() < 1e-10 * expect_fv);
        assert!((zero.std()[i].powi(2) - expect_zero).abs() < 1e-10 * expect_zero);
    }
    // After an adapt step the Gaussian blends; after a restart it is fresh again.
    a.adapt(&p, &u, &g, true);
    let mut blended = ProposalGaussian::default();
    a.gaussian(&p, &u, &[0.5, 0.5], &mut blended);
    a.restart(&p);
    let mut fresh = ProposalGaussian::default();
    a.gaussian(&p, &u, &[0.5, 0.5], &mut fresh);
    assert!(fresh.std()[0].powi(2) != blended.std()[0].powi(2));
    let w1 = 2f64.powf(-p.c1);
    let expect = p.epsilon / ((1.0 - w1) + w1 * (p.delta + 0.5));
    assert!((fresh.std()[0].powi(2) - expect).abs() < 1e-10 * expect);
}

// ---- expected-value splatting ----

#[test]
fn splat_weights_are_unbiased() {
    use mcmc_core::testing::{toy_splat_weight_test, SplatParams};
    let t = Ridge::thin();
    let p = params(0.004);
    let large = uniform_box(&t);
    let mala = Langevin::new(p, Plain, Euclidean)
        .unwrap()
        .with_large_step(large.clone(), 0.2)
        .unwrap();
    let report = toy_splat_weight_test(&t, &mala, &SplatParams::new(20_000, 120));
    eprintln!("splat weights, MALA + large step: {report}");
    report.assert_passes("MALA splat weights", STATIONARITY_TESTS);
    let cte = CheapThenExpensive::new(p, 0.5, Plain, Euclidean)
        .unwrap()
        .with_large_step(large, 0.2)
        .unwrap();
    let report = toy_splat_weight_test(&t, &cte, &SplatParams::new(20_000, 121));
    eprintln!("splat weights, cheap-then-expensive: {report}");
    report.assert_passes("cheap-then-expensive splat weights", STATIONARITY_TESTS);
}
