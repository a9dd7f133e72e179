//! MMLT's strategy-stratified bootstrap: the independent primary-sample-space states of the
//! render loop, with every primary point of a depth evaluated under every strategy.

use mcmc_core::render_loop::IndependentStates;
use pss::{FreshPss, PssState};

use super::path_sampler::MmltTarget;
use crate::bdpt::MAX_PATH_DEPTH;
use crate::sampler::Stream;

/// Independent states for MMLT's bootstrap, stratified over the strategy choice.
///
/// An MMLT sample of depth `d >= 1` picks its strategy `s` from the first number of the
/// connection stream, `s = floor(u n)` with `n = d + 2` strategies, and its target is the
/// strategy's MIS-weighted contribution times `n` (Hachisuka, Kaplanyan, Dachsbacher 2014,
/// *Multiplexed Metropolis Light Transport*, section 4). Here the bootstrap of depth `d`
/// draws its samples in groups of `n` sharing one fresh primary point; member `k` of a group
/// has that number moved into the `k`-th stratum, `u' = (k + u) / n`. So each primary point
/// is evaluated under every strategy, and the mean over a group is the BDPT all-strategy
/// estimate of the depth (`(1/n) sum_s n C_s = sum_s C_s`).
///
/// Unbiased: stratum `k` has density `n` on `[k/n, (k+1)/n)` in that coordinate (uniform
/// elsewhere); the average of the strata's densities is the uniform density the weight
/// `f(u)` assumes ([`IndependentStates::stratified`]'s contract), and the loop counts whole
/// groups only. Depth 0 (one strategy) is not stratified.
///
/// # Example
/// ```
/// use mcmc_core::render_loop::IndependentStates;
/// use render::mlt::MmltStrata;
///
/// let strata = MmltStrata::new(3, 5);
/// assert_eq!(strata.strata(0), 1); // depth 0: one strategy
/// assert_eq!(strata.strata(3), 5); // depth 3: s = 0..=4
/// let (mut a, mut b) = (strata.empty(), strata.empty());
/// strata.stratified(7, 0, 5, &mut a);
/// strata.stratified(7, 4, 5, &mut b);
/// assert!(a.stream_values(2, 1)[0] < 0.2 && b.stream_values(2, 1)[0] >= 0.8);
/// assert_eq!(a.stream_values(0, 4), b.stream_values(0, 4)); // the same camera numbers
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MmltStrata {
    fresh: FreshPss,
    /// Interleaved index of the connection stream's first number.
    strategy_coordinate: usize,
    /// Strategies per target (depth).
    strategies: Vec<u64>,
}

impl MmltStrata {
    /// The states of [`MmltTarget::all_depths`]'s targets (depths `0..=max_depth`) over
    /// `streams` (1..=4, clamped; [`super::PATH_STREAMS`] for the path samplers) PSS streams.
    #[must_use]
    pub fn new(streams: usize, max_depth: u32) -> Self {
        Self::for_depths(streams, 0, max_depth)
    }

    /// The states of [`MmltTarget::depths_from`]'s targets (depths `min_depth..=max_depth`,
    /// target `i` of depth `min_depth + i`).
    #[must_use]
    pub fn for_depths(streams: usize, min_depth: u32, max_depth: u32) -> Self {
        let streams = streams.clamp(1, pss::MAX_STREAMS);
        Self {
            fresh: FreshPss::new(streams).unwrap_or_else(|_| unreachable!("clamped to 1..=4")),
            strategy_coordinate: Stream::Connection.index().min(streams - 1),
            strategies: (min_depth..=max_depth.min(MAX_PATH_DEPTH))
                .map(|d| if d == 0 { 1 } else { u64::from(d) + 2 })
                .collect(),
        }
    }

    /// The states for these MMLT targets (their largest depth).
    #[must_use]
    pub fn for_targets(streams: usize, targets: &[MmltTarget<'_>]) -> Self {
        Self::for_depths(
            streams,
            targets.iter().map(MmltTarget::depth).min().unwrap_or(0),
            targets.iter().map(MmltTarget::depth).max().unwrap_or(0),
        )
    }
}

impl IndependentStates<PssState> for MmltStrata {
    fn empty(&self) -> PssState {
        self.fresh.empty()
    }

    fn independent(&self, key: u64, state: &mut PssState) {
        self.fresh.independent(key, state);
    }

    fn strata(&self, target: usize) -> u64 {
        self.strategies.get(target).copied().unwrap_or(1)
    }

    fn stratified(&self, key: u64, stratum: u64, strata: u64, state: &mut PssState) {
        self.fresh.independent(key, state);
        if strata > 1 {
            let u = state.get(self.strategy_coordinate);
            state.set(
                self.strategy_coordinate,
                (stratum.min(strata - 1) as f64 + u) / strata as f64,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strata_cover_the_unit_interval_with_the_shared_point() {
        let s = MmltStrata::new(3, 4);
        assert_eq!(
            (0..6).map(|t| s.strata(t)).collect::<Vec<_>>(),
            [1, 3, 4, 5, 6, 1]
        );
        let mut x = s.empty();
        let mut base = s.empty();
        s.independent(99, &mut base);
        let u = base.stream_values(2, 1)[0];
        for k in 0..6 {
            s.stratified(99, k, 6, &mut x);
            let v = x.stream_values(2, 1)[0];
            assert!((v - (k as f64 + u) / 6.0).abs() < 1e-15, "{k}: {v}");
            assert_eq!(x.stream_values(0, 8), base.stream_values(0, 8));
            assert_eq!(x.stream_values(1, 8), base.stream_values(1, 8));
        }
    }
}
