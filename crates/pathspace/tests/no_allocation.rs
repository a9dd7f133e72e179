//! Steady-state path-space MLT allocates nothing per mutation: after a warm-up (in which every
//! chain's current and candidate paths reach their longest length), the lens and multi-chain
//! perturbations mixed with the bidirectional mutation make no heap allocation in thousands
//! of steps. Negative control: a proposal that copies the current path the way a derived
//! `Clone::clone_from` does (`*y = x.clone()`) allocates on every step, and the counter sees it.

mod common;

use mcmc_core::testing::CountingAllocator;
use mcmc_core::{Chain, Mh, NoAdaptation, Proposal, Proposed};
use pathspace::analytic::AnalyticScene;
use pathspace::{ra_mixture, FixedScale, Path, PathTarget, Perturbation, PerturbationKind};
use rand::Rng;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Steps before counting (every buffer reaches its size) and steps counted.
const WARM_UP: usize = 2_000;
const COUNTED: usize = 5_000;

/// A proposal that first copies `x` into a fresh path, as a derived `clone_from` does.
struct FreshCopy<P>(P);

impl<P: Proposal<Path>> Proposal<Path> for FreshCopy<P> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        *y = x.clone();
        self.0.propose(x, y, rng)
    }
    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.0.log_q(from, to)
    }
}

/// Allocations in [`COUNTED`] steps of a chain of `kernel` after [`WARM_UP`] steps.
fn counted<K: mcmc_core::Kernel<PathTarget<'static, AnalyticScene>>>(
    scene: &'static AnalyticScene,
    kernel: K,
    seed: u64,
) -> usize {
    let target = PathTarget::new(scene);
    let sampler = common::unidirectional(scene, 4);
    let mut rng = common::rng(seed);
    let x0 = common::lit_path(scene, &sampler, &mut rng);
    let mut chain = Chain::new(&target, kernel, NoAdaptation, rng, x0).unwrap();
    for _ in 0..WARM_UP {
        chain.step(&mut ()).unwrap();
    }
    let before = CountingAllocator::allocations();
    for _ in 0..COUNTED {
        chain.step(&mut ()).unwrap();
    }
    CountingAllocator::allocations() - before
}

fn scene() -> &'static AnalyticScene {
    Box::leak(Box::new(AnalyticScene::test_box().unwrap()))
}

#[test]
fn perturbations_and_the_bidirectional_mutation_allocate_nothing_per_step() {
    let scene = scene();
    for (seed, kind) in [
        (1, PerturbationKind::Lens),
        (2, PerturbationKind::MultiChain),
    ] {
        let perturbation = Perturbation::new(scene, kind, FixedScale::uniform(0.05));
        let kernel =
            Mh::new(ra_mixture(kind, perturbation, common::bidirectional(scene, 4)).unwrap());
        let n = counted(scene, kernel, seed);
        assert_eq!(n, 0, "{kind:?}: {n} allocations in {COUNTED} steps");
    }
}

#[test]
fn negative_control_a_fresh_copy_per_step_is_counted() {
    let scene = scene();
    let kind = PerturbationKind::Lens;
    let perturbation = FreshCopy(Perturbation::new(scene, kind, FixedScale::uniform(0.05)));
    let n = counted(scene, Mh::new(perturbation), 3);
    // Every step copies the current path (a valid path has at least two vertices).
    assert!(n >= COUNTED, "{n} allocations in {COUNTED} steps");
}
