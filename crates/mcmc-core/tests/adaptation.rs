//! Adaptation controllers reach their targets, and the adapted (frozen) kernels still leave the
//! target invariant.
//!
//! - `GlobalScale` (regional-adaptive paper, Alg. 1 with one region, eq. 4-6) drives MH's
//!   acceptance on a 10-D correlated Gaussian to within 0.05 of 0.5.
//!   After freezing, the sign rule's last step `gamma_n = 5 / sqrt(5000) = 0.07` moves `log
//!   sigma^2` by 0.07, i.e. sigma by 3.5%, which shifts the acceptance by about 0.02 at most;
//!   the acceptance measured over the 200 000-step window has a standard error below 0.005.
//! - `RegionalScale` (sections 4 and 7; the shared controller the path-space renderer runs) on
//!   the DR paper's mixture of uniforms, with one region for the spike and one for the plateau,
//!   synchronised every 100 mutations, brings each region's acceptance to within 0.05 of 0.5
//!   (one sign-rule update per region and round, about 5000 per region, so the last step
//!   `gamma_n = 5 / sqrt(5000) = 0.07` moves sigma by 3.5%) and ends with a smaller scale in the
//!   spike than on the plateau (the scales solving acceptance = 0.5 differ by about a factor
//!   10).
//! - `AutoLargeStep` (automatic-large-step paper, section 2) sets `p_l` to
//!   `automatic_large_step_probability` of the statistics it measured, which we re-measure
//!   independently with an observer; `eta_0` and `eta_l` match their exact values within 4.5
//!   standard errors.
//!
//! The stationarity tests of the frozen kernels ([`STATIONARITY_TESTS`] in this file) pass at
//! the Sidak level for alpha = 0.01.

use std::sync::Arc;

use mcmc_core::controller::{
    automatic_large_step_probability, AutoLargeStep, GlobalScale, HasSharedScales,
    LargeStepTunable, PooledRegionalScales, RegionalScale, RegionalScaleParams, ScaleAdaptParams,
    ScaleTunable, SharedController, SharedRegionalScales,
};
use mcmc_core::partition::Partition;
use mcmc_core::partition::UniformGrid;
use mcmc_core::proposal::{FixedSelection, Scaled, ScaledProposal};
use mcmc_core::stats::integrated_autocorrelation_time;
use mcmc_core::testing::{toy_stationarity_test, StationarityParams};
use mcmc_core::toy::{CorrelatedGaussian, PiecewiseConstant, ToyTarget, UniformMixture};
use mcmc_core::{
    Chain, GaussianRandomWalk, Mh, Mixture, NoAdaptation, Observer, Proposal, Proposed, StepInfo,
};
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// Stationarity tests in this file (Sidak correction).
const STATIONARITY_TESTS: usize = 3;

#[test]
fn global_scale_reaches_target_acceptance_then_freezes() {
    let target = CorrelatedGaussian::ar1(10, 0.9).unwrap();
    let params = ScaleAdaptParams {
        freeze_after_updates: Some(5000),
        ..ScaleAdaptParams::otsu2018()
    };
    let controller = GlobalScale::new(params).unwrap();
    let mut kernel = Mh::new(Scaled::new(GaussianRandomWalk::new(1.0).unwrap(), 0.0));
    controller.init(&mut kernel);
    let mut rng = Pcg64::seed_from_u64(201);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(&target, kernel, controller, rng, start).unwrap();

    // Adaptation phase: 5000 updates of L = 10 proposals each.
    chain.run(50_000, &mut ()).unwrap();
    type K = Mh<Scaled<GaussianRandomWalk>>;
    assert!(mcmc_core::Controller::<K, Vec<f64>>::is_frozen(
        chain.controller()
    ));
    assert_eq!(chain.controller().updates(), 5000);
    let lambda = chain.kernel().log_scale();

    // Measurement window with the frozen kernel.
    let before = *chain.stats();
    chain.run(200_000, &mut ()).unwrap();
    assert_eq!(
        chain.kernel().log_scale(),
        lambda,
        "a frozen controller changed the scale"
    );
    let after = chain.stats();
    let steps = (after.steps - before.steps) as f64;
    let acceptance = (after.accepted[0] - before.accepted[0]) as f64 / steps;
    let mean_accept_prob = (after.accept_prob_sum[0] - before.accept_prob_sum[0]) / steps;
    eprintln!(
        "GlobalScale: sigma = {:.4}, acceptance {acceptance:.4}, mean accept prob {mean_accept_prob:.4}",
        (0.5 * lambda).exp()
    );
    assert!((acceptance - 0.5).abs() < 0.05, "acceptance {acceptance}");

    // The frozen kernel is a fixed MH kernel: it passes stationarity from exact starts.
    let report = toy_stationarity_test(
        &target,
        chain.kernel(),
        &StationarityParams::new(10_000, 20, 201),
    );
    eprintln!("GlobalScale frozen kernel: {report}");
    report.assert_passes("frozen GlobalScale kernel", STATIONARITY_TESTS);
}

/// Per-region scales over a grid behind an `Arc`: the handle the shared regional controller
/// reads regions from and publishes new scales through (copy-on-write).
#[derive(Clone, Debug)]
struct GridScales(Arc<(UniformGrid, Vec<f64>)>);

impl SharedRegionalScales for GridScales {
    type Partition = UniformGrid;
    fn partition(&self) -> &UniformGrid {
        &self.0 .0
    }
    fn num_regions(&self) -> usize {
        self.0 .1.len()
    }
    fn log_scale_of(&self, region: usize) -> f64 {
        self.0 .1[region]
    }
    fn set_log_scale_of(&mut self, region: usize, lambda: f64) {
        Arc::make_mut(&mut self.0).1[region] = lambda;
    }
    fn split_region(&mut self, _region: usize) -> Option<std::ops::Range<usize>> {
        None
    }
    fn same_as(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The Gaussian walk at the scale of the current state's region, with the reverse density at
/// the scale of the proposed state's region (regional-adaptive paper, eq. 2-3), reading its
/// scales from a [`GridScales`] handle.
#[derive(Clone, Debug)]
struct SharedRegionalWalk {
    walk: GaussianRandomWalk,
    scales: GridScales,
}

impl SharedRegionalWalk {
    fn lambda(&self, x: &Vec<f64>) -> f64 {
        self.scales.log_scale_of(self.scales.partition().region(x))
    }
}

impl Proposal<Vec<f64>> for SharedRegionalWalk {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        let lx = self.lambda(x);
        match self.walk.propose_at_scale(lx, x, y, rng) {
            Proposed::Move { .. } => Proposed::Move {
                log_hastings: self.walk.log_q_at_scale(self.lambda(y), y, x)
                    - self.walk.log_q_at_scale(lx, x, y),
                component: 0,
            },
            invalid => invalid,
        }
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        self.walk.log_q_at_scale(self.lambda(from), from, to)
    }
}

impl HasSharedScales for SharedRegionalWalk {
    type Scales = GridScales;
    fn shared_scales(&self) -> Option<&GridScales> {
        Some(&self.scales)
    }
    fn shared_scales_mut(&mut self) -> Option<&mut GridScales> {
        Some(&mut self.scales)
    }
}

/// Mutations per round between synchronisation points.
const ROUND: u64 = 100;

#[test]
fn regional_scale_reaches_target_per_region_and_shrinks_the_spike() {
    let target = UniformMixture::rioux_lavoie2020();
    // Two regions split at 0: region 0 = [-1, 0) holds the spike [-0.1, 0), region 1 =
    // [0, 1) is the plateau.
    let grid = UniformGrid::new(1, 2, -1.0, 1.0).unwrap();
    let params = RegionalScaleParams {
        split_after_visits: None,
        perturbation_component: None,
        ..RegionalScaleParams::otsu2018()
    };
    let scales = GridScales(Arc::new((grid, vec![params.adapt.lambda_initial; 2])));
    let kernel = Mh::new(SharedRegionalWalk {
        walk: GaussianRandomWalk::new(1.0).unwrap(),
        scales,
    });
    let controller = RegionalScale::new(params).unwrap();
    let mut rng = Pcg64::seed_from_u64(202);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(&target, kernel, controller, rng, start).unwrap();
    // One chain synchronised by hand every ROUND mutations (a render loop does this for many).
    type K = Mh<SharedRegionalWalk>;
    let mut pooled = PooledRegionalScales::default();
    for _ in 0..ROUNDS {
        chain.run(ROUND, &mut ()).unwrap();
        let (kernel, controller) = chain.kernel_and_controller_mut();
        controller.contribute(kernel, &mut pooled);
        <RegionalScale as SharedController<K>>::end_round(&mut pooled);
        controller.receive(kernel, &pooled);
    }
    assert_eq!(pooled.rounds(), ROUNDS);
    assert_eq!(pooled.mutations(), ROUNDS * ROUND);
    for k in 0..2 {
        let updates = pooled.region_stats(k).unwrap().adapt.updates;
        assert!(updates > ROUNDS / 2, "region {k}: {updates} updates");
    }

    let kernel = chain.kernel().clone();
    assert!(kernel.proposal.scales.same_as(pooled.sigmas().unwrap()));
    let sigmas: Vec<f64> = kernel
        .proposal
        .scales
        .0
         .1
        .iter()
        .map(|l| (0.5 * l).exp())
        .collect();

    // Acceptance per region with the adapted scales held fixed.
    let mut rng = Pcg64::seed_from_u64(2020);
    let start = target.sample_exact(&mut rng);
    let mut fixed = Chain::new(&target, kernel.clone(), NoAdaptation, rng, start).unwrap();
    let (mut sum, mut count) = ([0.0; 2], [0u64; 2]);
    for _ in 0..200_000 {
        let k = kernel.proposal.scales.partition().region(fixed.state());
        let info = fixed.step(&mut ()).unwrap();
        sum[k] += info.accept_prob[0];
        count[k] += 1;
    }
    let acceptance = [sum[0] / count[0] as f64, sum[1] / count[1] as f64];
    eprintln!(
        "RegionalScale: sigma spike {:.4}, plateau {:.4}; acceptance {acceptance:.4?}",
        sigmas[0], sigmas[1]
    );
    for a in acceptance {
        assert!(
            (a - 0.5).abs() < 0.05,
            "per-region acceptance {acceptance:?}"
        );
    }
    assert!(
        sigmas[0] < sigmas[1],
        "spike sigma {} vs plateau {}",
        sigmas[0],
        sigmas[1]
    );

    // With the adapted scales held fixed, the regional kernel is a valid MH kernel.
    let report = toy_stationarity_test(&target, &kernel, &StationarityParams::new(10_000, 20, 202));
    eprintln!("RegionalScale adapted kernel: {report}");
    report.assert_passes("adapted RegionalScale kernel", STATIONARITY_TESTS);
}

/// Synchronisation points of the regional test.
const ROUNDS: u64 = 5000;

/// Independent uniform "large step" on `[lo, hi)`: `q(x -> y) = 1 / (hi - lo)` on the box.
#[derive(Clone, Debug)]
struct IndependentUniform {
    lo: f64,
    hi: f64,
}

impl Proposal<Vec<f64>> for IndependentUniform {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clear();
        y.push(self.lo + (self.hi - self.lo) * rng.random::<f64>());
        Proposed::hastings(self.log_q(y, x) - self.log_q(x, y))
    }

    fn log_q(&self, _from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        if (self.lo..self.hi).contains(&to[0]) {
            -(self.hi - self.lo).ln()
        } else {
            f64::NEG_INFINITY
        }
    }
}

/// A small Gaussian step or a large independent step.
#[derive(Clone, Debug)]
enum Step {
    Small(GaussianRandomWalk),
    Large(IndependentUniform),
}

impl Proposal<Vec<f64>> for Step {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        match self {
            Step::Small(p) => p.propose(x, y, rng),
            Step::Large(p) => p.propose(x, y, rng),
        }
    }
    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        match self {
            Step::Small(p) => p.log_q(from, to),
            Step::Large(p) => p.log_q(from, to),
        }
    }
    fn log_hastings(&self, j: usize, x: &Vec<f64>, y: &Vec<f64>) -> f64 {
        match self {
            Step::Small(p) => p.log_hastings(j, x, y),
            Step::Large(p) => p.log_hastings(j, x, y),
        }
    }
}

/// PSSMLT-style mixture: component 0 small step, component 1 large step with probability p_l.
#[derive(Clone, Debug)]
struct LargeStepMixture(Mixture<Step, FixedSelection>);

impl Proposal<Vec<f64>> for LargeStepMixture {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        self.0.propose(x, y, rng)
    }
    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        self.0.log_q(from, to)
    }
    fn num_components(&self) -> usize {
        2
    }
    fn log_q_component(&self, j: usize, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        self.0.log_q_component(j, from, to)
    }
    fn log_hastings(&self, j: usize, x: &Vec<f64>, y: &Vec<f64>) -> f64 {
        self.0.log_hastings(j, x, y)
    }
}

impl LargeStepTunable for LargeStepMixture {
    fn large_step_probability(&self) -> f64 {
        self.0.selection().probabilities()[1]
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.0.selection_mut().set(&[1.0 - p, p]).unwrap();
    }
    fn is_large_step(&self, component: usize) -> bool {
        component == 1
    }
}

/// Re-measures the large-step statistics from the step reports.
#[derive(Default)]
struct Tally {
    small: u64,
    small_accept: f64,
    large: u64,
    large_accept: f64,
    large_nonzero: u64,
    /// Acceptance probability of each large step, in order.
    large_series: Vec<f64>,
}

impl<S, P> Observer<S, P> for Tally {
    fn step(&mut self, info: &StepInfo) {
        if info.component == 1 {
            self.large += 1;
            self.large_accept += info.accept_prob[0];
            self.large_series.push(info.accept_prob[0]);
            self.large_nonzero += u64::from(info.candidate_log_density[0] > f64::NEG_INFINITY);
        } else {
            self.small += 1;
            self.small_accept += info.accept_prob[0];
        }
    }
}

#[test]
fn auto_large_step_uses_the_measured_statistics() {
    let target = PiecewiseConstant::with_holes();
    let estimation_steps = 20_000;
    let proposal = LargeStepMixture(
        Mixture::new(
            vec![
                Step::Small(GaussianRandomWalk::new(0.005).unwrap()),
                Step::Large(IndependentUniform { lo: 0.0, hi: 1.0 }),
            ],
            FixedSelection::new(&[0.5, 0.5]).unwrap(),
        )
        .unwrap(),
    );
    let controller = AutoLargeStep::new(estimation_steps).unwrap();
    let mut rng = Pcg64::seed_from_u64(203);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(&target, Mh::new(proposal), controller, rng, start).unwrap();
    let mut tally = Tally::default();
    for _ in 0..estimation_steps {
        chain.step(&mut tally).unwrap();
    }
    let estimate = chain
        .controller()
        .estimate()
        .expect("estimation phase is over");
    let eta_s = tally.small_accept / tally.small as f64;
    let eta_l = tally.large_accept / tally.large as f64;
    let eta_0 = tally.large_nonzero as f64 / tally.large as f64;
    let expected = automatic_large_step_probability(eta_s, eta_l, eta_0);
    eprintln!(
        "AutoLargeStep: eta_s {eta_s:.4}, eta_l {eta_l:.4}, eta_0 {eta_0:.4} -> p_l {expected:.4} \
         (controller: {estimate:?})"
    );
    assert_eq!(
        (estimate.small_steps, estimate.large_steps),
        (tally.small, tally.large)
    );
    assert!((estimate.eta_s - eta_s).abs() < 1e-12);
    assert!((estimate.eta_l - eta_l).abs() < 1e-12);
    assert!((estimate.eta_0 - eta_0).abs() < 1e-12);
    assert!((chain.kernel().large_step_probability() - expected).abs() < 1e-12);
    assert!((estimate.large_step_probability - expected).abs() < 1e-12);
    // Neither the flatness fallback (0.25) nor the clamp at 1 applies here: the formula
    // eta_s / (2 (eta_s - eta_l)) itself was exercised.
    assert!(
        eta_l / eta_0 >= 0.1 && expected > 0.25 && expected < 1.0,
        "{estimate:?}"
    );

    // Large-step candidates are i.i.d. uniform on [0, 1), so eta_0 is a binomial proportion
    // with mean 9/16 (the support fraction): |eta_0 - 9/16| < 4.5 sd (two-sided p = 7e-6).
    let support = 9.0 / 16.0;
    let sd = (support * (1.0 - support) / tally.large as f64).sqrt();
    assert!(
        (eta_0 - support).abs() < 4.5 * sd,
        "eta_0 {eta_0} vs {support} (sd {sd})"
    );

    // eta_l is a time average along the chain (x moves); its exact value for x ~ pi and
    // y ~ U[0, 1) is sum_i p_i sum_j min(1, d_j / d_i) / 16 = 0.392045... Standard error from
    // the series' integrated autocorrelation time; |error| < 4.5 se (two-sided p = 7e-6).
    let exact_eta_l = {
        let d = target.cell_densities();
        let n = d.len() as f64;
        d.iter()
            .filter(|&&di| di > 0.0)
            .map(|&di| di / n * d.iter().map(|&dj| (dj / di).min(1.0)).sum::<f64>() / n)
            .sum::<f64>()
    };
    let series = &tally.large_series;
    let var = series
        .iter()
        .map(|a| (a - eta_l) * (a - eta_l))
        .sum::<f64>()
        / series.len() as f64;
    let tau = integrated_autocorrelation_time(series);
    let se = (var * tau / series.len() as f64).sqrt();
    eprintln!("eta_l {eta_l:.4} vs exact {exact_eta_l:.4} (se {se:.4}, tau {tau:.2})");
    assert!(
        (eta_l - exact_eta_l).abs() < 4.5 * se,
        "eta_l {eta_l} vs exact {exact_eta_l}"
    );

    // After estimation the controller is frozen: the kernel is a fixed MH mixture.
    let p_l = chain.kernel().large_step_probability();
    chain.run(1000, &mut ()).unwrap();
    assert_eq!(chain.kernel().large_step_probability(), p_l);
    let report = toy_stationarity_test(
        &target,
        chain.kernel(),
        &StationarityParams::new(10_000, 20, 203),
    );
    eprintln!("AutoLargeStep frozen kernel: {report}");
    report.assert_passes("frozen AutoLargeStep kernel", STATIONARITY_TESTS);
}
