//! Delayed rejection with the pairwise orbital stages on lazy primary-sample-space states
//! (DR paper section 4.4, Alg. 2; docs/methods/drmlt.md): `mcmc_core::DelayedRejection` with
//! the orbital rule (eq. 11), first stage [`PairwiseMltProposal`] (pairwise polar Kelemen on a
//! fixed layout, optionally mixed with large steps), second stage [`OnLayout`]`<Orbital>`,
//! keeps the PSS toy targets from exact starts: the torus mixture whose modes straddle both
//! seams, the stripes whose read set depends on the state, and the roulette path that reads
//! beyond the layout (layouts of odd dimension 5 and of 64).
//!
//! Negative control ([`Unlogged`]): a first stage that moves `x`'s *stored* values instead of
//! reading them through the candidate (so stale coordinates are neither caught up nor logged
//! for `absorb_rejected`) is caught on the stripes target with large steps.
//!
//! Each chi-square test must pass at the Sidak level for [`TESTS`] tests (overall 0.01); the
//! control must give p < 1e-6.
//! Run with `cargo test -p pss --release --test orbital_pss -- --nocapture` for the numbers.

use mcmc_core::controller::LargeStepTunable;
use mcmc_core::testing::StationarityParams;
use mcmc_core::toy::TorusMixture;
use mcmc_core::{DelayedRejection, Proposal, Proposed};
use pss::testing::{pss_stationarity_test, ExactPssTarget, OnPss, RoulettePath, Stripes};
use pss::{
    Group, KelemenParams, LargeStep, OnLayout, Orbital, PairLayout, PairwiseKelemen,
    PairwiseKelemenParams, PairwiseMltProposal, Pending, PssState, SmallMutation,
};
use rand::{Rng, RngExt};

/// Chi-square tests in this file (Sidak correction). Keep in sync.
const TESTS: usize = 7;

/// 20 000 exact starts, 30 steps each.
const PARAMS: StationarityParams = StationarityParams::new(20_000, 30, 5);

/// The DRMLT kernel on PSSMLT: pairwise first stage on `layout` (large steps with
/// `p_large`, never followed by the second stage), orbital second stage, eq. 11.
fn drmlt(
    layout: PairLayout,
    radii: PairwiseKelemenParams,
    p_large: f64,
) -> DelayedRejection<PairwiseMltProposal, OnLayout<Orbital>> {
    let first =
        PairwiseMltProposal::new(OnLayout::new(PairwiseKelemen::new(radii), layout), p_large)
            .unwrap();
    DelayedRejection::orbital(first, OnLayout::new(Orbital::default(), layout))
        .second_stage_after_small_steps()
}

fn check<T: ExactPssTarget>(
    what: &str,
    target: &T,
    kernel: &DelayedRejection<PairwiseMltProposal, OnLayout<Orbital>>,
) {
    let r = pss_stationarity_test(target, kernel, &PARAMS);
    println!("{what}: {r}");
    r.assert_passes(what, TESTS);
}

#[test]
fn orbital_dr_keeps_pss_targets() {
    let wide = PairwiseKelemenParams::new(0.01, 0.2).unwrap();
    let default = PairwiseKelemenParams::drmlt2020();
    let torus = OnPss::new(TorusMixture::across_seam()).unwrap();
    let two = PairLayout::single_stream(2);
    check(
        "torus mixture, default radii",
        &torus,
        &drmlt(two, default, 0.0),
    );
    check("torus mixture, wide radii", &torus, &drmlt(two, wide, 0.0));
    check("stripes", &Stripes::default(), &drmlt(two, default, 0.0));
    let roulette = RoulettePath::default();
    let five = PairLayout::single_stream(5);
    check("roulette, layout 5", &roulette, &drmlt(five, default, 0.0));
    check(
        "roulette, layout 5, p_large 0.3",
        &roulette,
        &drmlt(five, default, 0.3),
    );
    let all = PairLayout::single_stream(64);
    check(
        "roulette, layout 64, p_large 0.1",
        &roulette,
        &drmlt(all, default, 0.1),
    );
}

/// Negative control: [`PairwiseMltProposal`] whose pairwise step moves the values `x`
/// *stores* (stale ones as they are, missing ones drawn afresh) instead of reading them
/// through the candidate: what a stage that skips the catch-up does. After an accepted large
/// step, `x`'s unread coordinates hold their pre-large-step values, which this stage revives.
#[derive(Clone, Copy, Debug)]
struct Unlogged {
    layout: PairLayout,
    p_large: f64,
}

impl Proposal<PssState> for Unlogged {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        if rng.random::<f64>() < self.p_large {
            return LargeStep.propose(x, y, rng).with_component(1);
        }
        y.clone_from(x);
        let identity = Pending::Small {
            mutation: SmallMutation::Kelemen(KelemenParams::kelemen2002()),
            stream_mask: 0,
        };
        y.set_pending(identity, rng.random());
        let step = PairwiseKelemen::default();
        let stored =
            |i: usize, rng: &mut R| x.raw_values().get(i).map_or_else(|| rng.random(), |v| *v);
        for group in self.layout.groups(0xff) {
            match group {
                Group::Pair(a, b) => {
                    let xs = [stored(a, rng), stored(b, rng)];
                    let [va, vb] = step.perturb_pair(xs, rng);
                    y.set(a, va);
                    y.set(b, vb);
                }
                Group::Single(a) => {
                    let v = step.perturb_single(stored(a, rng), rng);
                    y.set(a, v);
                }
            }
        }
        Proposed::symmetric()
    }
    fn log_q(&self, _from: &PssState, _to: &PssState) -> f64 {
        0.0
    }
    fn is_symmetric(&self) -> bool {
        true
    }
    fn num_components(&self) -> usize {
        2
    }
    fn log_q_component(&self, _j: usize, _from: &PssState, _to: &PssState) -> f64 {
        0.0
    }
}

impl LargeStepTunable for Unlogged {
    fn large_step_probability(&self) -> f64 {
        self.p_large
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.p_large = p;
    }
    fn is_large_step(&self, component: usize) -> bool {
        component == 1
    }
}

#[test]
fn skipping_the_catch_up_is_caught() {
    let two = PairLayout::single_stream(2);
    let stripes = Stripes::default();
    check(
        "stripes, p_large 0.3",
        &stripes,
        &drmlt(two, PairwiseKelemenParams::drmlt2020(), 0.3),
    );
    let control = DelayedRejection::orbital(
        Unlogged {
            layout: two,
            p_large: 0.3,
        },
        OnLayout::new(Orbital::default(), two),
    )
    .second_stage_after_small_steps();
    let r = pss_stationarity_test(&stripes, &control, &PARAMS);
    println!("negative control, stage 1 without catch-up: {r}");
    assert!(r.p_value < 1e-6, "{r}");
}
