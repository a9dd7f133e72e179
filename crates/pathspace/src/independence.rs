//! The independence mutation: regenerate the whole path from an [`IndependentSampler`].

use mcmc_core::{Proposal, Proposed};
use rand::Rng;

use crate::path::Path;
use crate::sampler::IndependentSampler;

/// Regenerates the whole path: `y ~ p(.)` independently of `x`, with transition density
/// `T(y | x) = p(y)` and Hastings term `ln p(x) - ln p(y)`, where `p` is the sampler's exact
/// density (for [`crate::UnidirectionalSampler`], the two-technique sum documented there;
/// for a renderer's bidirectional sampler, the combined density of its strategies).
///
/// This is the global, ergodic move of path-space MLT (the role of Veach and Guibas'
/// bidirectional mutation, regional-adaptive paper, section 3.3): every path the sampler can
/// produce is reachable in one step. A failed sample is [`Proposed::Invalid`].
///
/// # Example
/// ```
/// use mcmc_core::Proposal;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{
///     IndependenceMutation, IndependentSampler, Path, UnidirectionalParams, UnidirectionalSampler,
/// };
/// use rand::SeedableRng;
///
/// let scene = AnalyticScene::furnace_box(0.5, 1.0).unwrap();
/// let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
/// let mutation = IndependenceMutation::new(sampler);
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
/// let (mut x, mut y) = (Path::new(), Path::new());
/// while !sampler.sample(&mut rng, &mut x) {}
/// while !sampler.sample(&mut rng, &mut y) {}
/// assert_eq!(mutation.log_q(&x, &y), sampler.log_density(&y));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct IndependenceMutation<Smp> {
    /// The path sampler.
    pub sampler: Smp,
}

impl<Smp: IndependentSampler> IndependenceMutation<Smp> {
    /// The mutation drawing from `sampler`.
    pub fn new(sampler: Smp) -> Self {
        Self { sampler }
    }
}

impl<Smp: IndependentSampler> Proposal<Path> for IndependenceMutation<Smp> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        if !self.sampler.sample(rng, y) {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.sampler.log_density(x) - self.sampler.log_density(y))
    }

    fn log_q(&self, _from: &Path, to: &Path) -> f64 {
        self.sampler.log_density(to)
    }
}
