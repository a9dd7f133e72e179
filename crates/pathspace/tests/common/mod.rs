//! Helpers shared by the integration tests: seeded RNGs, path draws, statistics, the
//! bidirectional mutation.
#![allow(dead_code)]

use pathspace::{
    BidirectionalMutation, BidirectionalParams, IndependentSampler, Path, PathScene,
    UnidirectionalParams, UnidirectionalSampler,
};
use rand::SeedableRng;

/// A seeded test RNG.
pub(crate) fn rng(seed: u64) -> rand_pcg::Pcg64 {
    rand_pcg::Pcg64::seed_from_u64(seed)
}

/// Draws a valid path (retrying failed samples).
pub(crate) fn draw<Smp: IndependentSampler, R: rand::Rng>(sampler: &Smp, rng: &mut R) -> Path {
    let mut p = Path::new();
    for _ in 0..100_000 {
        if sampler.sample(rng, &mut p) {
            return p;
        }
    }
    panic!("the sampler failed 100000 times in a row");
}

/// Mean and standard error of independent replicates.
pub(crate) fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// The bidirectional mutation over `scene` with at most `max_segments` segments, the other
/// parameters at their defaults.
pub(crate) fn bidirectional<S: PathScene + ?Sized>(
    scene: &S,
    max_segments: usize,
) -> BidirectionalMutation<'_, S> {
    BidirectionalMutation::new(
        scene,
        BidirectionalParams {
            max_segments,
            ..BidirectionalParams::default()
        },
    )
    .unwrap()
}

/// A chain's start: the first path `sampler` draws with a nonzero luminance on `scene`.
pub(crate) fn lit_path<S, Smp, R>(scene: &S, sampler: &Smp, rng: &mut R) -> Path
where
    S: PathScene + ?Sized,
    Smp: IndependentSampler,
    R: rand::Rng,
{
    loop {
        let p = draw(sampler, rng);
        if p.contribution(scene).luminance() > 0.0 {
            return p;
        }
    }
}

/// The unidirectional sampler the chain tests start from: at most `max_segments` segments,
/// light connections with probability 0.5.
pub(crate) fn unidirectional<S: PathScene + ?Sized>(
    scene: &S,
    max_segments: usize,
) -> UnidirectionalSampler<'_, S> {
    UnidirectionalSampler::new(
        scene,
        UnidirectionalParams {
            max_segments,
            connect_probability: 0.5,
        },
    )
    .unwrap()
}
