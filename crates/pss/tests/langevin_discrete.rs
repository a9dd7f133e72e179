//! MALA moving only the continuous primary samples (`pss::langevin::PssCoordinates`: reads
//! tagged discrete by `PssState::next_discrete` stay fixed in Langevin steps): every variant
//! as the renderer builds it (`pss::mala::mala_kernel`: plain, online, cache-driven, hybrid,
//! each with large steps; cheap-then-expensive) passes pairwise balance and stationarity from
//! exact starts on `LobeChoice`, a target with a discrete lobe choice, a read set that
//! depends on the state and a set of discrete numbers that depends on the state.
//!
//! Negative control: a space that moves the continuous numbers of the current state but does
//! not compare the candidate's discrete tags with the current state's (only the read
//! counts, which agree). On `LobeChoice`'s branch B the forward move then changes `(u1, u3)`
//! and the reverse density is formed over `(u1, u2)`, differentiating as continuous a number
//! that was a discrete choice where the move started: it fails both checks.
//!
//! Statistics: each stationarity test must pass at the Sidak level for
//! [`STATIONARITY_TESTS`] tests (false-failure probability 0.01 for the file); the negative
//! control must fail at the same level. Pairwise checks are identities (1e-9 relative).

use mcmc_core::langevin::{AnyAdaptation, LangevinParams};
use mcmc_core::testing::{
    assert_path_balance, sidak_alpha, stationarity_test, PairwiseParams, StationarityParams,
};
use mcmc_core::toy::wrap;
use mcmc_core::{Chain, Kernel, NoAdaptation};
use proptest::prelude::*;
use pss::mala::{
    cheap_then_expensive_kernel, mala_kernel, MalaChainKernel, MalaParams, MalaVariant,
};
use pss::testing::{
    pss_stationarity_test, BlindPssCoordinates, Blindness, ExactPssTarget, LobeChoice,
};
use pss::{KelemenParams, LargeStep, PssState, SmallMutation};
use rand::SeedableRng;

const STATIONARITY_TESTS: usize = 11;
const STARTS: usize = 20_000;
const STEPS: u64 = 100;

/// The presets the variants are checked under: the paper's values (sigma 0.1, steps that
/// cross the tag boundaries often) and the authors' code's (shrink prior 0.005), each with a
/// cache small enough to fill in a test's warm-up.
fn presets() -> [(&'static str, MalaParams); 2] {
    let with = |langevin: LangevinParams| MalaParams {
        langevin: LangevinParams {
            cache_size: 200,
            ..langevin
        },
        ..MalaParams::luan2020()
    };
    [
        ("paper", with(LangevinParams::luan2020())),
        ("code", with(LangevinParams::luan2020_code())),
    ]
}

fn small() -> SmallMutation {
    SmallMutation::Kelemen(KelemenParams::kelemen2002())
}

/// The kernel of `variant` after `warmup` steps of one chain, frozen (a fixed MH kernel: what
/// the harness checks).
fn warmed(
    target: &LobeChoice,
    params: &MalaParams,
    variant: MalaVariant,
    warmup: u64,
    seed: u64,
) -> MalaChainKernel {
    let p = MalaParams { variant, ..*params };
    let kernel = mala_kernel(&p, 0, small(), 0.1);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let start = target.sample_exact(&mut rng);
    let mut chain = Chain::new(target, kernel, NoAdaptation, rng, start).unwrap();
    chain.run(warmup, &mut ()).unwrap();
    let mut kernel = chain.kernel().clone();
    if let MalaChainKernel::Mala(k) = &mut kernel {
        k.freeze();
    }
    kernel
}

/// Pairs `(x, y)` of fully materialised 4-D states, `y` = `x` with `u1` moved by up to
/// `3 scale`, and `u2`, `u3`, both or neither moved as well (a Langevin move keeps the
/// discrete one of `u2`, `u3` and moves the other).
fn near_pairs(scale: f64) -> BoxedStrategy<Vec<PssState>> {
    (
        prop::array::uniform4(0.0..1.0f64),
        prop::array::uniform3(-3.0..3.0f64),
        0..4u8,
    )
        .prop_map(move |(u, n, pattern)| {
            let k2 = if pattern & 1 != 0 { scale } else { 0.0 };
            let k3 = if pattern & 2 != 0 { scale } else { 0.0 };
            let v = [
                u[0],
                wrap(u[1] + scale * n[0]),
                wrap(u[2] + k2 * n[1]),
                wrap(u[3] + k3 * n[2]),
            ];
            vec![PssState::from_values(&u), PssState::from_values(&v)]
        })
        .boxed()
}

fn check<K: Kernel<LobeChoice> + Clone>(
    what: &str,
    kernel: &K,
    seed: u64,
    pairwise_scale: Option<f64>,
) {
    let target = LobeChoice::default();
    if let Some(scale) = pairwise_scale {
        let r = assert_path_balance(
            &target,
            kernel,
            near_pairs(scale),
            &PairwiseParams::with_seed(seed),
        );
        eprintln!(
            "{what}: pairwise {}/{} informative (worst {:.1e})",
            r.informative, r.cases, r.worst_log_difference
        );
    }
    let report = pss_stationarity_test(
        &target,
        kernel,
        &StationarityParams::new(STARTS, STEPS, seed),
    );
    eprintln!("{what}: stationarity {report}");
    report.assert_passes(what, STATIONARITY_TESTS);
}

#[test]
fn every_variant_keeps_the_discrete_numbers_and_is_exact() {
    let target = LobeChoice::default();
    for (p, (preset, params)) in presets().iter().enumerate() {
        // Pairs at the scale of the steps (the code's shrink prior keeps them below 0.005).
        let scale = if p == 0 { 0.05 } else { 0.003 };
        for (i, (name, variant)) in MalaVariant::ALL.into_iter().enumerate() {
            let seed = 10 * p as u64 + i as u64;
            let kernel = warmed(&target, params, variant, 3000, 100 + seed);
            let MalaChainKernel::Mala(k) = &kernel else {
                panic!("{name}: expected a MALA kernel");
            };
            if variant == MalaVariant::Hybrid {
                // Frozen after the warm-up either way; the hybrid should have switched itself.
                let switched = matches!(
                    k.adaptation.get(2),
                    Some(AnyAdaptation::Hybrid(h)) if !h.is_online()
                );
                assert!(switched, "{preset}: the hybrid's 2-D cache should be full");
            }
            check(
                &format!("{preset} / {name}"),
                &kernel,
                200 + seed,
                Some(scale),
            );
        }
    }
}

#[test]
fn cheap_then_expensive_keeps_the_discrete_numbers_and_is_exact() {
    for (p, (preset, params)) in presets().iter().enumerate() {
        let kernel = cheap_then_expensive_kernel(params, 0, small(), 0.1);
        assert!(matches!(kernel, MalaChainKernel::CheapThenExpensive(_)));
        let what = format!("{preset} / cheap-then-expensive");
        check(&what, &kernel, 300 + p as u64, None);
    }
}

#[test]
fn negative_control_ignoring_the_tags_of_the_candidate_fails() {
    // The paper's step (sigma 0.1): moves cross the tag boundaries often.
    let p = LangevinParams::luan2020();
    let kernel = mcmc_core::langevin::Langevin::new(
        p,
        mcmc_core::langevin::Plain,
        BlindPssCoordinates(Blindness::Tags),
    )
    .unwrap()
    .with_large_step(LargeStep, 0.1)
    .unwrap();
    let target = LobeChoice::default();
    let report = stationarity_test(
        &target,
        &kernel,
        |rng| target.sample_exact(rng),
        &target.bins(),
        &StationarityParams::new(STARTS, STEPS, 41),
    );
    eprintln!("negative control: stationarity {report}");
    assert!(
        report.rejects(sidak_alpha(0.01, STATIONARITY_TESTS)),
        "{report}"
    );
}

#[test]
fn langevin_steps_never_move_a_discrete_number() {
    // MALA steps only (no large step): the lobe choice u0 and, in branch B, the current
    // choice among u2, u3 stay as they are while the chain moves.
    let target = LobeChoice::default();
    for (_, params) in presets() {
        let kernel = mala_kernel(&params, 0, small(), 0.0);
        let rng = rand_pcg::Pcg64::seed_from_u64(5);
        let start = PssState::from_values(&[0.7, 0.3, 0.2, 0.6]);
        let mut chain = Chain::new(&target, kernel, NoAdaptation, rng, start).unwrap();
        let mut moved = 0;
        for _ in 0..2000 {
            let before = chain.current().state.raw_values().to_vec();
            chain.run(1, &mut ()).unwrap();
            let after = chain.current().state.raw_values().to_vec();
            assert_eq!(before[0], after[0], "the lobe choice moved");
            let choice = if after[1] < 0.5 { 2 } else { 3 };
            if (before[1] < 0.5) == (after[1] < 0.5) {
                assert_eq!(before[choice], after[choice], "a discrete choice moved");
            }
            moved += usize::from(before != after);
        }
        assert!(moved > 200, "the chain should move ({moved} moves)");
    }
}
