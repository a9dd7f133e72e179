//! The chain's handling of NaN and zero densities: NaN is an error surfaced to the caller with
//! the state unchanged; a zero-density candidate is never accepted, whatever the Hastings term.

use mcmc_core::{
    mh_accept_prob, mh_log_accept_prob, Chain, GaussianRandomWalk, McmcError, Mh, NoAdaptation,
    Proposal, Proposed, Target,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Density 1 on `[0, 1)`; NaN at and beyond 1 (a buggy target); zero below 0.
struct NanAboveOne;

impl Target for NanAboveOne {
    type State = Vec<f64>;
    type Payload = ();
    fn evaluate(&self, x: &mut Vec<f64>, _: &mut ()) -> f64 {
        if x[0] >= 1.0 {
            f64::NAN
        } else if x[0] < 0.0 {
            f64::NEG_INFINITY
        } else {
            0.0
        }
    }
}

/// Always proposes `x + shift`, reporting the given Hastings term.
#[derive(Clone, Debug)]
struct Shift {
    shift: f64,
    log_hastings: f64,
}

impl Proposal<Vec<f64>> for Shift {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, _rng: &mut R) -> Proposed {
        y.clone_from(x);
        y[0] += self.shift;
        Proposed::hastings(self.log_hastings)
    }
    fn log_q(&self, _from: &Vec<f64>, _to: &Vec<f64>) -> f64 {
        0.0
    }
}

#[test]
fn nan_density_is_an_error_and_the_state_is_unchanged() {
    let kernel = Mh::new(Shift {
        shift: 0.75,
        log_hastings: 0.0,
    });
    let mut chain = Chain::new(
        &NanAboveOne,
        kernel,
        NoAdaptation,
        Pcg64::seed_from_u64(1),
        vec![0.5],
    )
    .unwrap();
    let err = chain.step(&mut ()).unwrap_err();
    assert!(
        matches!(err, McmcError::NonFiniteDensity { value, stage: 1 } if value.is_nan()),
        "{err:?}"
    );
    assert_eq!(chain.state(), &vec![0.5]);
    assert_eq!(chain.current().log_density, 0.0);
    assert_eq!(chain.stats().non_finite, 1);
    assert_eq!(chain.stats().acceptance_rate(), 0.0);
    // The chain is still usable after the error.
    assert!(chain.step(&mut ()).is_err());
    assert_eq!(chain.state(), &vec![0.5]);
}

#[test]
fn nan_or_zero_start_is_rejected() {
    let k = Mh::new(GaussianRandomWalk::new(0.1).unwrap());
    let nan = Chain::new(
        &NanAboveOne,
        k.clone(),
        NoAdaptation,
        Pcg64::seed_from_u64(2),
        vec![2.0],
    );
    assert!(matches!(
        nan.err(),
        Some(McmcError::NonFiniteDensity { stage: 0, .. })
    ));
    let zero = Chain::new(
        &NanAboveOne,
        k,
        NoAdaptation,
        Pcg64::seed_from_u64(2),
        vec![-1.0],
    );
    assert!(matches!(zero.err(), Some(McmcError::ZeroDensityStart)));
}

#[test]
fn zero_density_candidate_is_never_accepted() {
    // Every candidate lands at x - 0.75 < 0 (zero density), with a Hastings term of +inf
    // that would force acceptance if zero densities were not checked first.
    let kernel = Mh::new(Shift {
        shift: -0.75,
        log_hastings: f64::INFINITY,
    });
    let mut chain = Chain::new(
        &NanAboveOne,
        kernel,
        NoAdaptation,
        Pcg64::seed_from_u64(3),
        vec![0.5],
    )
    .unwrap();
    for _ in 0..1000 {
        let info = chain.step(&mut ()).unwrap();
        assert!(!info.accepted());
        assert_eq!(info.accept_prob[0], 0.0);
    }
    assert_eq!(chain.state(), &vec![0.5]);
    // And with a random walk, the chain never leaves the support.
    let kernel = Mh::new(GaussianRandomWalk::new(2.0).unwrap());
    let mut chain = Chain::new(
        &NanAboveOne,
        kernel,
        NoAdaptation,
        Pcg64::seed_from_u64(4),
        vec![0.5],
    )
    .unwrap();
    let mut moved = 0;
    for _ in 0..10_000 {
        if let Ok(info) = chain.step(&mut ()) {
            moved += usize::from(info.accepted());
        }
        assert!((0.0..1.0).contains(&chain.state()[0]));
    }
    assert!(
        moved > 100,
        "the walk should still move inside the support ({moved})"
    );
}

#[test]
fn log_acceptance_matches_acceptance_and_does_not_underflow() {
    let cases = [
        (0.0, -1.0, 0.3),
        (-2.0, -1.0, -0.5),
        (0.0, 0.0, 0.0),
        (f64::NEG_INFINITY, -1.0, 0.0),
        (0.0, f64::NEG_INFINITY, 5.0),
        (0.0, -1.0, f64::NEG_INFINITY),
        (0.0, -1.0, f64::NAN),
    ];
    for (x, y, h) in cases {
        let a = mh_accept_prob(x, y, h);
        let log_a = mh_log_accept_prob(x, y, h);
        assert!(
            log_a == a.ln() || (log_a - a.ln()).abs() < 1e-15,
            "{x} {y} {h}: {a} vs {log_a}"
        );
    }
    // Far in the tails exp underflows, the log version does not.
    assert_eq!(mh_accept_prob(0.0, -2000.0, 0.0), 0.0);
    assert_eq!(mh_log_accept_prob(0.0, -2000.0, 0.0), -2000.0);
}
