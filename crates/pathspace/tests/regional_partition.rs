//! Partitions for regional adaptation: disjoint and complete (proptest over random points and
//! refinement histories), deterministic refinement, and the quadtree refinement rules of
//! section 6.2 as the shared controller applies them (split at `>= M_split` visits, one split
//! per leaf per pass, children inherit `lambda` and `n / 4`). Negative control: the checker
//! rejects a partition whose cells overlap.

mod common;

use mcmc_core::controller::ScaleAdaptParams;
use mcmc_core::render_loop::SharedController;
use mcmc_core::{Controller, Partition, StepInfo};
use pathspace::analytic::AnalyticScene;
use pathspace::regional::{
    cylindrical, DirectionPartition, PathPartition, PlanePartition, PooledRegionalStats,
    RegionalAdaptParams, RegionalSigmas, RegionalUpdateRule, ScreenPartition,
    SharedRegionalAdaptation, SharedSigmas,
};
use pathspace::{Camera, Path, Vec3, Vertex};
use proptest::prelude::*;

/// Checks that `region` is a partition of `[0, 1)^2` into the boxes `bounds(k)`,
/// `k < n`: every sample point lies in the box of its region (complete, consistent), every
/// box's centre maps back to it (no two ids share a box: disjoint), the boxes' areas sum to 1.
fn check_plane(
    region: &dyn Fn([f64; 2]) -> usize,
    bounds: &dyn Fn(usize) -> [[f64; 2]; 2],
    n: usize,
    points: &[[f64; 2]],
) -> Result<(), String> {
    for &p in points {
        let k = region(p);
        if k >= n {
            return Err(format!("{p:?} -> region {k} of {n}"));
        }
        let [lo, hi] = bounds(k);
        if !(lo[0] <= p[0] && p[0] < hi[0] && lo[1] <= p[1] && p[1] < hi[1]) {
            return Err(format!("{p:?} -> region {k} with bounds {lo:?}..{hi:?}"));
        }
    }
    let mut area = 0.0;
    for k in 0..n {
        let [lo, hi] = bounds(k);
        area += (hi[0] - lo[0]) * (hi[1] - lo[1]);
        let c = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        if region(c) != k {
            return Err(format!("centre of region {k} maps to {}", region(c)));
        }
    }
    if (area - 1.0).abs() > 1e-12 {
        return Err(format!("areas sum to {area}"));
    }
    Ok(())
}

fn unit_points() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec(
        prop_oneof![
            (0.0..1.0f64, 0.0..1.0f64).prop_map(|(x, y)| [x, y]),
            // Dyadic points sit exactly on quadtree borders.
            (0u32..64, 0u32..64).prop_map(|(x, y)| [f64::from(x) / 64.0, f64::from(y) / 64.0]),
        ],
        64,
    )
}

/// Applies a refinement history (each entry picks an existing region) to a quadtree.
fn refined(history: &[u32], max_depth: u8) -> PlanePartition {
    let mut p = PlanePartition::quadtree(max_depth).unwrap();
    for &h in history {
        let k = h as usize % p.num_regions();
        let _ = p.split(k);
    }
    p
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn quadtree_is_a_partition(history in prop::collection::vec(any::<u32>(), 0..40), points in unit_points()) {
        let p = refined(&history, 5);
        check_plane(&|x| p.region(x), &|k| p.bounds(k), p.num_regions(), &points)
            .map_err(TestCaseError::fail)?;
        // Deterministic: the same history gives the same tree.
        prop_assert_eq!(&p, &refined(&history, 5));
    }

    #[test]
    fn grid_is_a_partition(n in 1usize..40, points in unit_points()) {
        let g = PlanePartition::grid(n).unwrap();
        check_plane(&|x| g.region(x), &|k| g.bounds(k), g.num_regions(), &points)
            .map_err(TestCaseError::fail)?;
    }

    /// The 4-D partition: a region id names one (top cell, leaf) pair, the point lies in both,
    /// and every leaf of every cell has exactly one global id.
    #[test]
    fn direction_partition_is_a_partition(
        history in prop::collection::vec(any::<u32>(), 0..30),
        screens in unit_points(),
        dirs in unit_points(),
    ) {
        let scene = AnalyticScene::test_box().unwrap();
        let mut part = DirectionPartition::new(&scene, 3, PlanePartition::quadtree(4).unwrap()).unwrap();
        let mut twin = part.clone();
        for &h in &history {
            let k = h as usize % part.num_regions();
            let a = part.split(k);
            prop_assert_eq!(a, twin.split(k));
        }
        let n = part.num_regions();
        let mut seen = vec![false; n];
        for c in 0..9 {
            let cell = part.cell_partition(c);
            for l in 0..cell.num_regions() {
                let [lo, hi] = cell.bounds(l);
                let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
                let screen = [(f64::from((c % 3) as u32) + 0.5) / 3.0, (f64::from((c / 3) as u32) + 0.5) / 3.0];
                let g = part.region_of_point(screen, centre);
                prop_assert_eq!(part.cell_of(g), (c, l));
                prop_assert!(!seen[g], "region {} twice", g);
                seen[g] = true;
            }
        }
        prop_assert!(seen.iter().all(|&s| s), "every id is a leaf");
        for (s, d) in screens.iter().zip(&dirs) {
            let g = part.region_of_point(*s, *d);
            let (c, l) = part.cell_of(g);
            prop_assert_eq!(c, ((s[1] * 3.0) as usize).min(2) * 3 + ((s[0] * 3.0) as usize).min(2));
            let [lo, hi] = part.cell_partition(c).bounds(l);
            prop_assert!(lo[0] <= d[0] && d[0] < hi[0] && lo[1] <= d[1] && d[1] < hi[1]);
        }
    }

    /// Cylindrical coordinates of any direction lie in the unit square and invert.
    #[test]
    fn cylindrical_inverts(z in -1.0..1.0f64, phi in 0.0..std::f64::consts::TAU) {
        let r = (1.0 - z * z).sqrt();
        let w = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let c = cylindrical(w);
        prop_assert!((0.0..=1.0).contains(&c[0]) && (0.0..1.0).contains(&c[1]));
        prop_assert!((c[0] - 0.5 * (z + 1.0)).abs() < 1e-12);
        let back = c[1] * std::f64::consts::TAU;
        let d = (back - phi).abs();
        prop_assert!(d < 1e-9 || (d - std::f64::consts::TAU).abs() < 1e-9, "{} vs {}", back, phi);
    }
}

/// Negative control: a "partition" whose cells overlap (a 4 x 4 grid reporting 2 x 4 boxes of
/// double width) is rejected by the checker.
#[test]
fn negative_control_overlapping_cells_are_rejected() {
    let g = PlanePartition::grid(4).unwrap();
    let wide = |k: usize| {
        let [lo, hi] = g.bounds(k);
        [[lo[0], lo[1]], [(hi[0] + 0.25).min(1.0), hi[1]]]
    };
    let points: Vec<[f64; 2]> = (0..100).map(|i| [f64::from(i) / 100.0, 0.37]).collect();
    let err = check_plane(&|x| g.region(x), &wide, 16, &points).unwrap_err();
    eprintln!("rejected: {err}");
    // The real grid passes the same check.
    check_plane(&|x| g.region(x), &|k| g.bounds(k), 16, &points).unwrap();
}

/// Paths on the screen: the camera vertex and one vertex along the ray through `raster`
/// (enough for the screen partition).
fn screen_path(scene: &AnalyticScene, raster: [f64; 2]) -> Path {
    let o = scene.origin();
    let mut first = Vertex::default();
    first.point.position = o;
    let mut second = Vertex::default();
    second.point.position = o + scene.direction(raster);
    Path {
        vertices: vec![first, second],
    }
}

/// Runs one chain's controller over `visits` (raster point, acceptance), then synchronises.
/// The last step at each point reports an accepted move (the chain leaves for the next
/// point), so that the handle does not keep the point's region as the current one.
fn round<'a>(
    controller: &mut SharedRegionalAdaptation,
    kernel: &mut SharedSigmas<PathPartition<&'a AnalyticScene>>,
    pooled: &mut PooledRegionalStats<PathPartition<&'a AnalyticScene>>,
    scene: &'a AnalyticScene,
    visits: &[([f64; 2], f64, usize)],
) {
    for &(raster, accept, count) in visits {
        let x = screen_path(scene, raster);
        for i in 0..count {
            controller.before_step(kernel, &x);
            let mut info = StepInfo::new(0);
            info.accept_prob[0] = accept;
            info.accepted_stage = u8::from(i + 1 == count);
            Controller::<_, Path>::after_step(controller, kernel, &info);
        }
    }
    controller.contribute(kernel, pooled);
    pooled.end_round();
    controller.receive(kernel, pooled);
}

#[test]
fn quadtree_refinement_rules() {
    let scene = AnalyticScene::test_box().unwrap();
    let part = PathPartition::Screen(ScreenPartition::new(
        &scene,
        PlanePartition::quadtree(6).unwrap(),
    ));
    let params = RegionalAdaptParams {
        adapt: ScaleAdaptParams {
            updates_every: 10,
            ..ScaleAdaptParams::otsu2018()
        },
        split_after_visits: Some(10),
        refine_every: 100,
        perturbation_component: Some(0),
        freeze_after_mutations: None,
        // The counts below follow one step per region per round (the refinement rules do not
        // depend on the rule; `pathspace::regional`'s paper-speed rule is tested in mcmc-core).
        update_rule: RegionalUpdateRule::OncePerRound,
        ..RegionalAdaptParams::otsu2018()
    };
    let mut kernel = SharedSigmas::new(RegionalSigmas::new(part, 1.0, 1.0).unwrap());
    let mut c = SharedRegionalAdaptation::new(params).unwrap();
    let mut pooled = PooledRegionalStats::default();
    let (q0, q1, q2, q3) = ([0.2, 0.2], [0.7, 0.2], [0.2, 0.7], [0.7, 0.7]);
    // Rounds of 50 mutations: the first sync point (50) only adapts; the second (100) also
    // refines the root (100 visits >= M_split), once.
    round(&mut c, &mut kernel, &mut pooled, &scene, &[(q0, 1.0, 50)]);
    assert_eq!(pooled.refinements(), 0);
    assert_eq!(pooled.num_regions(), 1);
    let lambda_1 = kernel.get().lambdas()[0];
    assert_eq!(
        lambda_1, 2.0,
        "acceptance 1 > 0.5 grows lambda by gamma_1 = 1 (eq. 5, 6)"
    );
    round(&mut c, &mut kernel, &mut pooled, &scene, &[(q0, 0.0, 50)]);
    assert_eq!(pooled.refinements(), 1);
    assert_eq!(
        pooled.splits(),
        1,
        "one split per leaf per pass: the children wait"
    );
    assert_eq!(kernel.get().num_regions(), 4);
    // Parent after its second update: lambda = 2 - 1 = 1, n = 3; children inherit both.
    for k in 0..4 {
        assert_eq!(kernel.get().lambdas()[k], 1.0, "region {k} inherits lambda");
        let s = pooled.region_stats(k).unwrap();
        assert_eq!(s.adapt.updates, 1, "n = max(1, 3 / 4)");
        assert_eq!((s.adapt.visits, s.visits_since_refine), (0, 0));
    }
    // Next pass: exactly M_split visits split (>=), M_split - 1 do not.
    let k0 = kernel.get().partition().region(&screen_path(&scene, q0));
    let k1 = kernel.get().partition().region(&screen_path(&scene, q1));
    let k3 = kernel.get().partition().region(&screen_path(&scene, q3));
    round(
        &mut c,
        &mut kernel,
        &mut pooled,
        &scene,
        &[(q0, 1.0, 10), (q1, 1.0, 9), (q3, 0.0, 10), (q2, 0.0, 0)],
    );
    round(&mut c, &mut kernel, &mut pooled, &scene, &[(q3, 0.0, 71)]);
    assert_eq!(pooled.refinements(), 2);
    assert_eq!(pooled.splits(), 3);
    assert_eq!(kernel.get().num_regions(), 10);
    let after = |raster| {
        kernel
            .get()
            .partition()
            .region(&screen_path(&scene, raster))
    };
    assert_eq!(after([0.05, 0.05]), k0, "the split id is the first child");
    assert_eq!(after(q1), k1, "9 < M_split visits: not split");
    let children_of_q3: Vec<usize> = [[0.55, 0.55], [0.8, 0.55], [0.55, 0.8], [0.8, 0.8]]
        .iter()
        .map(|&r| after(r))
        .collect();
    // q3 had 81 visits in two rounds: one update per synchronisation point (not one per L
    // visits), n = 1 + 2 = 3 -> children n = max(1, 3 / 4) = 1; lambda 1 - 1 - 1 = -1.
    for &k in &children_of_q3 {
        assert_eq!(kernel.get().lambdas()[k], -1.0);
        assert_eq!(pooled.region_stats(k).unwrap().adapt.updates, 1);
    }
    assert_eq!(children_of_q3[0], k3);
    // The parent of q1 kept its own statistics: 9 visits pending, no update.
    assert_eq!(pooled.region_stats(k1).unwrap().adapt.visits, 9);
    // Determinism: the same history on a fresh controller gives the same partition and scales.
    let part = PathPartition::Screen(ScreenPartition::new(
        &scene,
        PlanePartition::quadtree(6).unwrap(),
    ));
    let mut kernel2 = SharedSigmas::new(RegionalSigmas::new(part, 1.0, 1.0).unwrap());
    let mut c2 = SharedRegionalAdaptation::new(params).unwrap();
    let mut pooled2 = PooledRegionalStats::default();
    round(
        &mut c2,
        &mut kernel2,
        &mut pooled2,
        &scene,
        &[(q0, 1.0, 50)],
    );
    round(
        &mut c2,
        &mut kernel2,
        &mut pooled2,
        &scene,
        &[(q0, 0.0, 50)],
    );
    round(
        &mut c2,
        &mut kernel2,
        &mut pooled2,
        &scene,
        &[(q0, 1.0, 10), (q1, 1.0, 9), (q3, 0.0, 10)],
    );
    round(
        &mut c2,
        &mut kernel2,
        &mut pooled2,
        &scene,
        &[(q3, 0.0, 71)],
    );
    assert_eq!(kernel.get().lambdas(), kernel2.get().lambdas());
    for raster in [q0, q1, q2, q3, [0.9, 0.9], [0.55, 0.8]] {
        assert_eq!(
            after(raster),
            kernel2
                .get()
                .partition()
                .region(&screen_path(&scene, raster))
        );
    }
}

/// Freezing: after `freeze_after_mutations` the scales and the partition stop changing.
#[test]
fn freeze_stops_adaptation_and_refinement() {
    let scene = AnalyticScene::test_box().unwrap();
    let part = PathPartition::Screen(ScreenPartition::new(
        &scene,
        PlanePartition::quadtree(6).unwrap(),
    ));
    let params = RegionalAdaptParams {
        split_after_visits: Some(10),
        refine_every: 100,
        freeze_after_mutations: Some(100),
        update_rule: RegionalUpdateRule::OncePerRound,
        ..RegionalAdaptParams::otsu2018()
    };
    let mut kernel = SharedSigmas::new(RegionalSigmas::new(part, 1.0, 1.0).unwrap());
    let mut c = SharedRegionalAdaptation::new(params).unwrap();
    let mut pooled = PooledRegionalStats::default();
    round(
        &mut c,
        &mut kernel,
        &mut pooled,
        &scene,
        &[([0.3, 0.3], 1.0, 100)],
    );
    assert!(
        pooled.is_frozen()
            && Controller::<SharedSigmas<PathPartition<&AnalyticScene>>, Path>::is_frozen(&c)
    );
    let frozen = kernel.get().lambdas();
    assert_eq!(
        frozen,
        vec![2.0],
        "the round before the freeze still adapts, no refinement"
    );
    round(
        &mut c,
        &mut kernel,
        &mut pooled,
        &scene,
        &[([0.3, 0.3], 0.0, 500)],
    );
    assert_eq!(kernel.get().lambdas(), frozen);
    assert_eq!(pooled.refinements(), 0);
    // Negative control: without the freeze, the same history refines and adapts further.
    let part = PathPartition::Screen(ScreenPartition::new(
        &scene,
        PlanePartition::quadtree(6).unwrap(),
    ));
    let mut kernel = SharedSigmas::new(RegionalSigmas::new(part, 1.0, 1.0).unwrap());
    let params = RegionalAdaptParams {
        freeze_after_mutations: None,
        ..params
    };
    let mut c = SharedRegionalAdaptation::new(params).unwrap();
    let mut pooled = PooledRegionalStats::default();
    round(
        &mut c,
        &mut kernel,
        &mut pooled,
        &scene,
        &[([0.3, 0.3], 1.0, 100)],
    );
    round(
        &mut c,
        &mut kernel,
        &mut pooled,
        &scene,
        &[([0.3, 0.3], 0.0, 500)],
    );
    assert!(pooled.refinements() >= 1 && kernel.get().lambdas() != frozen);
}

/// The sigma heat map of a 4-D partition averages `lambda` over a top cell's direction leaves
/// weighted by their area (control: the unweighted mean of the leaves differs).
#[test]
fn direction_heat_map_weights_leaves_by_area() {
    let scene = AnalyticScene::test_box().unwrap();
    let part = PathPartition::Direction(
        DirectionPartition::new(&scene, 2, PlanePartition::quadtree(4).unwrap()).unwrap(),
    );
    let mut s = RegionalSigmas::new(part, 0.0, 1.0).unwrap();
    // Cell 0: four leaves of area 1/4, then leaf 0 again into four of area 1/16.
    let fresh = s.split(0).unwrap();
    s.split(0).unwrap();
    s.set_lambda(fresh.start, -4.0); // area 1/4
    let ids_in_cell0: Vec<usize> = (0..s.num_regions())
        .filter(|&k| match s.partition() {
            PathPartition::Direction(p) => p.cell_of(k).0 == 0,
            _ => unreachable!(),
        })
        .collect();
    assert_eq!(ids_in_cell0.len(), 7);
    let map = s.screen_sigma_map(2, 2);
    let weighted = (0.5f64 * (-4.0 / 4.0)).exp();
    assert!((map[0] - weighted).abs() < 1e-12, "{map:?}");
    assert_eq!(&map[1..], &[1.0, 1.0, 1.0]);
    let unweighted = (0.5f64 * (-4.0 / 7.0)).exp();
    assert!((map[0] - unweighted).abs() > 0.1);
}

/// The public types can be shared with and sent to the render loop's threads.
#[test]
fn public_types_are_send_and_sync() {
    fn send_sync<T: Send + Sync>() {}
    type P<'a> = PathPartition<&'a AnalyticScene>;
    send_sync::<PlanePartition>();
    send_sync::<ScreenPartition<&AnalyticScene>>();
    send_sync::<DirectionPartition<&AnalyticScene>>();
    send_sync::<P<'_>>();
    send_sync::<RegionalSigmas<P<'_>>>();
    send_sync::<SharedSigmas<P<'_>>>();
    send_sync::<SharedRegionalAdaptation>();
    send_sync::<PooledRegionalStats<P<'_>>>();
    send_sync::<RegionalAdaptParams>();
}
