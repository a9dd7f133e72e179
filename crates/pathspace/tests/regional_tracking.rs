//! The region (and scale) a `SharedSigmas` handle tracks for its chain's current state (reused
//! from the accepted candidate's lookup instead of looked up again every step) is the current
//! state's after every step of a regional-adaptive chain, for the lens and the multi-chain
//! perturbation, with and without refinement; a controller that does not report the steps'
//! moves to the handle leaves it holding stale regions (negative control).

mod common;

use mcmc_core::controller::{RegionalScale, SharedRegionalScales};
use mcmc_core::{Chain, Controller, Mh, Mixture, Partition, StepInfo};
use pathspace::analytic::AnalyticScene;
use pathspace::regional::{
    DirectionPartition, HasSharedSigmas, PathPartition, PlanePartition, RegionalAdaptParams,
    RegionalSigmas, ScreenPartition, SharedRegionalAdaptation, SharedSigmas,
};
use pathspace::{
    ra_mixture, BidirectionalMutation, Path, PathMutation, PathTarget, PerturbOrGlobal,
    Perturbation, PerturbationKind, ScaleSource,
};

type Part<'a> = PathPartition<&'a AnalyticScene>;

/// Steps per chain.
const STEPS: usize = 3000;

/// A controller that asks the handle to track the current region but never reports how the
/// steps moved the state: the deliberately wrong variant.
struct Unreported(RegionalScale);

impl<K: HasSharedSigmas<Partition = Part<'static>>> Controller<K, Path> for Unreported {
    fn before_step(&mut self, kernel: &K, x: &Path) {
        self.0.observe(kernel.shared_sigmas(), x);
    }
    fn after_step(&mut self, _kernel: &mut K, _info: &StepInfo) {}
    fn is_frozen(&self) -> bool {
        false
    }
}

/// The partitions checked: screen and 4-D grids (many small regions, so accepted moves
/// change the region often).
fn partition(scene: &'static AnalyticScene, kind: PerturbationKind) -> Part<'static> {
    match kind {
        PerturbationKind::Lens => PathPartition::Screen(ScreenPartition::new(
            scene,
            PlanePartition::grid(16).unwrap(),
        )),
        PerturbationKind::MultiChain => PathPartition::Direction(
            DirectionPartition::new(scene, 4, PlanePartition::grid(8).unwrap()).unwrap(),
        ),
    }
}

/// The RA mixture (section 8.1) of a regional perturbation and the bidirectional mutation.
type Kernel = Mh<
    Mixture<
        PathMutation<
            Perturbation<'static, AnalyticScene, SharedSigmas<Part<'static>>>,
            BidirectionalMutation<'static, AnalyticScene>,
        >,
        PerturbOrGlobal,
    >,
>;

fn scene() -> &'static AnalyticScene {
    Box::leak(Box::new(AnalyticScene::test_box().unwrap()))
}

/// Runs 8 regional-adaptive chains of [`STEPS`] steps on the test box with the controller
/// `make` builds from `params`; after every step compares the handle's tracked region with the current
/// state's. Returns (steps whose region was known, of them wrong, steps that changed the
/// region).
fn run<C: Controller<Kernel, Path>>(
    kind: PerturbationKind,
    make: impl Fn(RegionalAdaptParams) -> C,
    params: RegionalAdaptParams,
) -> (usize, usize, usize) {
    let scene = scene();
    let target = PathTarget::new(scene);
    let part = partition(scene, kind);
    let sigmas =
        SharedSigmas::new(RegionalSigmas::new(part.clone(), (0.05f64).ln() * 2.0, 1.0).unwrap());
    let sampler = common::unidirectional(scene, 4);
    let bidir = common::bidirectional(scene, 4);
    let (mut known, mut wrong, mut moved) = (0, 0, 0);
    for c in 0..8 {
        let kernel: Kernel = Mh::new(
            ra_mixture(kind, Perturbation::new(scene, kind, sigmas.clone()), bidir).unwrap(),
        );
        let mut rng = common::rng(40 + c);
        let x0 = common::lit_path(scene, &sampler, &mut rng);
        let controller = make(params);
        let mut chain = Chain::new(&target, kernel, controller, rng, x0).unwrap();
        let mut before = part.region(chain.state());
        for _ in 0..STEPS {
            chain.step(&mut ()).unwrap();
            let now = part.region(chain.state());
            moved += usize::from(now != before);
            before = now;
            let handle = chain.kernel().shared_sigmas().unwrap();
            if let Some(r) = handle.current_region() {
                known += 1;
                // The kept scale too (no synchronisation point here: the scales are fixed).
                let kept = handle.current_sigmas(chain.state());
                wrong += usize::from(r != now || kept != handle.sigmas(chain.state()));
            }
        }
    }
    (known, wrong, moved)
}

fn params(refine: bool) -> RegionalAdaptParams {
    RegionalAdaptParams {
        split_after_visits: refine.then_some(200),
        ..RegionalAdaptParams::otsu2018()
    }
}

#[test]
fn tracked_region_is_the_current_states_region() {
    for kind in [PerturbationKind::Lens, PerturbationKind::MultiChain] {
        for refine in [false, true] {
            let (known, wrong, moved) = run(
                kind,
                |p| SharedRegionalAdaptation::new(p).unwrap(),
                params(refine),
            );
            eprintln!("{kind:?} refine {refine}: {known} of {} steps known, {wrong} wrong, {moved} region changes", 8 * STEPS);
            assert_eq!(wrong, 0, "{kind:?} refine {refine}");
            // The check has teeth: the state changed region often, and the handle knew the
            // region on most steps (all but those after an accepted bidirectional move).
            assert!(moved > 400, "{kind:?}: {moved} region changes");
            assert!(known > 8 * STEPS / 2, "{kind:?}: {known} known");
        }
    }
}

#[test]
fn negative_control_unreported_moves_leave_stale_regions() {
    for kind in [PerturbationKind::Lens, PerturbationKind::MultiChain] {
        let (known, wrong, moved) = run(
            kind,
            |p| Unreported(RegionalScale::new(p).unwrap()),
            params(false),
        );
        eprintln!("{kind:?} unreported: {known} known, {wrong} wrong, {moved} region changes");
        assert!(
            wrong > moved / 2,
            "{kind:?}: {wrong} wrong of {moved} changes"
        );
    }
}
