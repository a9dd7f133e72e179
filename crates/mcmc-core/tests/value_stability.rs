//! Value stability: the first states of each kernel's chain for a fixed seed, pinned as
//! literals (rand_distr's `tests/value_stability.rs` style).
//!
//! A change here means chains are no longer reproducible across versions: an RNG stream
//! reordered, a proposal drawing its numbers differently, an acceptance decision changed.
//! If the change is intended, update the literals and say so in the commit message.
//! Comparisons allow `1e-12` relative error, so that last-ulp differences of `exp`/`ln` between
//! platforms' math libraries do not count as instability.

use mcmc_core::controller::RegionalTunable;
use mcmc_core::partition::UniformGrid;
use mcmc_core::proposal::Regional;
use mcmc_core::testing::ThresholdSelection;
use mcmc_core::toy::{CorrelatedGaussian, ToyTarget, UniformMixture};
use mcmc_core::{Chain, GaussianRandomWalk, Kernel, Mh, Mixture, NoAdaptation, Target};
use rand::SeedableRng;
use rand_pcg::Pcg64;

fn gaussian_2d() -> CorrelatedGaussian {
    CorrelatedGaussian::new(vec![0.5, -1.0], &[1.0, 0.8, 0.8, 2.0]).unwrap()
}

fn first_states<T, K>(target: &T, kernel: K, seed: u64, start: Vec<f64>) -> Vec<Vec<f64>>
where
    T: Target<State = Vec<f64>>,
    K: Kernel<T>,
{
    let mut chain = Chain::new(
        target,
        kernel,
        NoAdaptation,
        Pcg64::seed_from_u64(seed),
        start,
    )
    .unwrap();
    (0..5)
        .map(|_| {
            chain.step(&mut ()).unwrap();
            chain.state().clone()
        })
        .collect()
}

fn assert_pinned(what: &str, got: &[Vec<f64>], expected: &[&[f64]]) {
    assert_eq!(got.len(), expected.len(), "{what}");
    for (step, (g, e)) in got.iter().zip(expected).enumerate() {
        assert_eq!(g.len(), e.len(), "{what} step {step}");
        for (a, b) in g.iter().zip(e.iter()) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                "{what}: state {step} is {g:?}, pinned {e:?}"
            );
        }
    }
}

#[test]
fn mh_random_walk() {
    let kernel = Mh::new(GaussianRandomWalk::new(0.5).unwrap());
    let got = first_states(&gaussian_2d(), kernel, 42, vec![0.0, 0.0]);
    assert_pinned(
        "MH / Gaussian random walk",
        &got,
        &[
            &[0.0, 0.0],
            &[0.0, 0.0],
            &[0.0, 0.0],
            &[-0.13060140996217415, -0.8753782790712529],
            &[0.6921910988401271, -0.9278870745014982],
        ],
    );
}

#[test]
fn mh_mixture_with_state_dependent_selection() {
    let proposal = Mixture::new(
        vec![
            GaussianRandomWalk::new(0.1).unwrap(),
            GaussianRandomWalk::new(1.0).unwrap(),
        ],
        ThresholdSelection::new(0.0, &[0.8, 0.2], &[0.3, 0.7]).unwrap(),
    )
    .unwrap();
    let got = first_states(&gaussian_2d(), Mh::new(proposal), 43, vec![0.0, 0.0]);
    assert_pinned(
        "MH / mixture",
        &got,
        &[
            &[1.08665318523171, 1.1548713193153701],
            &[1.08665318523171, 1.1548713193153701],
            &[1.6067297291502107, 1.3836866091848137],
            &[1.4958293100780522, 1.1728412886788095],
            &[1.9561681264981123, 0.4555903981679319],
        ],
    );
}

#[test]
fn mh_regional() {
    let grid = UniformGrid::new(1, 11, -0.1, 1.0).unwrap();
    let mut proposal = Regional::new::<Vec<f64>>(
        GaussianRandomWalk::new(1.0).unwrap(),
        grid,
        (0.3f64 * 0.3).ln(),
    );
    RegionalTunable::<Vec<f64>>::set_log_scale_of(&mut proposal, 0, (0.05f64 * 0.05).ln());
    let got = first_states(
        &UniformMixture::rioux_lavoie2020(),
        Mh::new(proposal),
        44,
        vec![0.3],
    );
    assert_pinned(
        "MH / regional",
        &got,
        &[
            &[0.5130707680760798],
            &[0.5130707680760798],
            &[0.5130707680760798],
            &[0.6220402186521595],
            &[0.8624754091094704],
        ],
    );
}

#[test]
fn exact_sampler() {
    let mut rng = Pcg64::seed_from_u64(45);
    let got: Vec<Vec<f64>> = (0..3)
        .map(|_| gaussian_2d().sample_exact(&mut rng))
        .collect();
    assert_pinned(
        "CorrelatedGaussian::sample_exact",
        &got,
        &[
            &[-1.9941508000320902, -1.3901694002286755],
            &[0.16204323379602054, -0.6018861512128393],
            &[0.39472677924689215, -0.8527627655216823],
        ],
    );
}
