//! Self-test of the harness's two-stage paths (pairwise triples, the finite-state two-stage
//! sum, stationarity with two scratch samples), with a minimal test-local Tierney-Mira delayed
//! rejection kernel (DR paper, section 4.1, eq. 5-6), and a broken variant that the harness
//! must reject.
//!
//! The broken variant drops the ratio `Q1(y|z) / Q1(y|x)` from eq. 6, the pitfall the DR paper
//! warns about ("symmetry in Q1 is not sufficient to eliminate it", after eq. 7).
//!
//! Statistics as in `harness_mh.rs`: one stationarity test of a correct kernel in this file
//! (level alpha = 0.01); the broken kernel must reach p < 1e-6, and a finite-state asymmetry
//! above 1e-6: six orders of magnitude above the check's tolerance (1e-12) and twelve above the
//! correct kernel's rounding-level asymmetry. (Two-stage flows enter `K` with the factor
//! `c^2 h^2`, so a second-stage bug shows up smaller, relative to the largest entry, than a
//! first-stage one.)

use std::panic::{catch_unwind, AssertUnwindSafe};

use mcmc_core::testing::{
    assert_finite_state_balance, assert_pairwise_balance, assert_path_balance, finite_state_check,
    grid_centres, toy_stationarity_test, PairwiseParams, StationarityParams,
};
use mcmc_core::toy::{ToyTarget, UniformMixture};
use mcmc_core::{
    mh_accept_prob, GaussianRandomWalk, Kernel, Observer, Proposal, Proposed, SampleOf, StepInfo,
    Target,
};
use proptest::prelude::*;
use rand::{Rng, RngExt};

/// Two-stage Tierney-Mira delayed rejection with first stage `q1` and a second stage `q2`
/// that proposes `z` from `x` (independent of the rejected `y`).
#[derive(Clone, Debug)]
struct TierneyMira {
    q1: GaussianRandomWalk,
    q2: GaussianRandomWalk,
    /// Negative control: drop `Q1(y|z) / Q1(y|x)` from the second-stage ratio.
    drop_q1_ratio: bool,
}

impl TierneyMira {
    fn a1(&self, lx: f64, ly: f64, x: &Vec<f64>, y: &Vec<f64>) -> f64 {
        mh_accept_prob(lx, ly, self.q1.log_q(y, x) - self.q1.log_q(x, y))
    }

    /// Log of the stage-2 flow numerator `pi(x) Q1(y|x) [1 - a1(x, y)] Q2(z|x)`.
    fn log_stage2_mass(&self, lx: f64, ly: f64, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        let q1 = if self.drop_q1_ratio {
            0.0
        } else {
            self.q1.log_q(x, y)
        };
        lx + q1 + (-self.a1(lx, ly, x, y)).ln_1p() + self.q2.log_q(x, z)
    }

    /// `ln a2(x, y, z)` of eq. 6 (0 <-> 1, -inf <-> 0).
    fn log_a2(&self, lx: f64, ly: f64, lz: f64, x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>) -> f64 {
        if lz == f64::NEG_INFINITY {
            return f64::NEG_INFINITY;
        }
        let num = self.log_stage2_mass(lz, ly, z, y, x);
        let den = self.log_stage2_mass(lx, ly, x, y, z);
        if num == f64::NEG_INFINITY || den == f64::NEG_INFINITY {
            return f64::NEG_INFINITY;
        }
        (num - den).min(0.0)
    }
}

impl<T: Target<State = Vec<f64>>> Kernel<T> for TierneyMira {
    fn stages(&self) -> usize {
        2
    }

    fn step<R, O>(
        &mut self,
        target: &T,
        current: &mut SampleOf<T>,
        scratch: &mut [SampleOf<T>],
        rng: &mut R,
        observer: &mut O,
    ) -> StepInfo
    where
        R: Rng + ?Sized,
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let mut info = StepInfo::new(0);
        let (first, rest) = scratch.split_at_mut(1);
        let (y, z) = (&mut first[0], &mut rest[0]);
        let _: Proposed = self.q1.propose(&current.state, &mut y.state, rng);
        y.log_density = target.evaluate(&mut y.state, &mut y.payload);
        let a1 = self.a1(current.log_density, y.log_density, &current.state, &y.state);
        info.stages_tried = 1;
        info.accept_prob[0] = a1;
        info.candidate_log_density[0] = y.log_density;
        if a1 >= 1.0 || (a1 > 0.0 && rng.random::<f64>() < a1) {
            observer.splat(current, 1.0 - a1);
            observer.splat(y, a1);
            std::mem::swap(current, y);
            info.accepted_stage = 1;
            observer.step(&info);
            return info;
        }
        let _: Proposed = self.q2.propose(&current.state, &mut z.state, rng);
        z.log_density = target.evaluate(&mut z.state, &mut z.payload);
        let a2 = self
            .log_a2(
                current.log_density,
                y.log_density,
                z.log_density,
                &current.state,
                &y.state,
                &z.state,
            )
            .exp();
        info.stages_tried = 2;
        info.accept_prob[1] = a2;
        info.candidate_log_density[1] = z.log_density;
        observer.splat(current, 1.0 - a2);
        observer.splat(z, a2);
        if a2 >= 1.0 || (a2 > 0.0 && rng.random::<f64>() < a2) {
            std::mem::swap(current, z);
            info.accepted_stage = 2;
        }
        observer.step(&info);
        info
    }

    fn log_flow(&self, _target: &T, path: &[SampleOf<T>]) -> f64 {
        match path {
            [x, y] => {
                let a1 = self.a1(x.log_density, y.log_density, &x.state, &y.state);
                x.log_density + self.q1.log_q(&x.state, &y.state) + a1.ln()
            }
            [x, y, z] => {
                // The *true* flow of what the kernel does: pi(x) Q1(y|x) (1 - a1) Q2(z|x) a2,
                // with a2 as the kernel computes it (possibly without the Q1 ratio).
                let lx = x.log_density;
                let stage2 = lx
                    + self.q1.log_q(&x.state, &y.state)
                    + (-self.a1(lx, y.log_density, &x.state, &y.state)).ln_1p()
                    + self.q2.log_q(&x.state, &z.state);
                stage2
                    + self.log_a2(
                        lx,
                        y.log_density,
                        z.log_density,
                        &x.state,
                        &y.state,
                        &z.state,
                    )
            }
            _ => f64::NEG_INFINITY,
        }
    }
}

fn kernel(drop_q1_ratio: bool) -> TierneyMira {
    // A timid first stage and a bolder second stage: z lands far from x relative to Q1's
    // scale, so Q1(y|z) / Q1(y|x) is far from 1 and dropping it matters.
    TierneyMira {
        q1: GaussianRandomWalk::new(0.2).unwrap(),
        q2: GaussianRandomWalk::new(0.5).unwrap(),
        drop_q1_ratio,
    }
}

/// Triples with `x`, `z` in the support and `y` anywhere in a wider range: a triple's flow is
/// nonzero only if `y` is rejected from both ends, which on this piecewise-constant target
/// needs `pi(y) < pi(x)` and `pi(y) < pi(z)` (e.g. `y` outside the support).
fn triples() -> impl Strategy<Value = Vec<Vec<f64>>> {
    (-0.1..1.0f64, -1.0..2.0f64, -0.1..1.0f64).prop_map(|(x, y, z)| vec![vec![x], vec![y], vec![z]])
}

fn states() -> impl Strategy<Value = Vec<f64>> + Clone {
    prop::collection::vec(-0.15..1.05f64, 1)
}

#[test]
fn tierney_mira_passes_all_three_checks() {
    let target = UniformMixture::rioux_lavoie2020();
    let good = kernel(false);
    // Independent random triples are rarely informative here (about 8%: see `triples`), so
    // the generic check gets a lower bar and the targeted triples the default one.
    let params = PairwiseParams {
        min_informative: 0.05,
        ..PairwiseParams::with_seed(301)
    };
    let pairwise = assert_pairwise_balance(&target, &good, states(), &params);
    let targeted = assert_path_balance(&target, &good, triples(), &PairwiseParams::with_seed(301));
    eprintln!(
        "targeted triples: {}/{} informative",
        targeted.informative, targeted.cases
    );
    let (lo, hi) = target.bounding_box();
    let (cells, volume) = grid_centres(&lo, &hi, &[22]);
    let fs = assert_finite_state_balance(&target, &good, &cells, volume);
    let report = toy_stationarity_test(&target, &good, &StationarityParams::new(10_000, 50, 301));
    eprintln!(
        "Tierney-Mira DR: pairwise {}/{} informative; finite-state asymmetry {:.1e}; {report}",
        pairwise.informative, pairwise.cases, fs.max_asymmetry
    );
    report.assert_passes("Tierney-Mira DR", 1);
}

#[test]
fn dropping_the_first_stage_ratio_fails() {
    let target = UniformMixture::rioux_lavoie2020();
    let bad = kernel(true);
    let caught = catch_unwind(AssertUnwindSafe(|| {
        assert_path_balance(&target, &bad, triples(), &PairwiseParams::with_seed(302));
    }));
    assert!(
        caught.is_err(),
        "pairwise check missed the dropped Q1 ratio"
    );
    let (lo, hi) = target.bounding_box();
    let (cells, volume) = grid_centres(&lo, &hi, &[22]);
    let asym = finite_state_check(&target, &bad, &cells, volume).max_asymmetry;
    let report = toy_stationarity_test(&target, &bad, &StationarityParams::new(10_000, 50, 302));
    eprintln!("DR without the Q1 ratio: finite-state asymmetry {asym:.3e}; {report}");
    assert!(asym > 1e-6, "finite-state asymmetry {asym}");
    assert!(report.p_value < 1e-6, "{report}");
}
