//! Regional adaptation's typed results through the session (`--integrator pathmlt --adapt`):
//! the learned sigma map and the `AdaptSummary` (whose note is the render's note), RA-QUADTREE's
//! refinement schedule from the pixel count (`split_after_visits` overriding it); negative
//! controls: FIXED reports neither, an `M_split` beyond the visits never splits, and
//! `M_split = 0`, a scale outside `(0, pi]` or a target outside `(0, 1)` are refused.

use std::sync::atomic::AtomicBool;

use pathspace::PerturbationKind;
use render::methods::PathMltSettings;
use render::mlt::pathmlt::PathAdapt;
use render::scene::Scene;
use render::session::{render, Budget, NoProgress, RenderOutput, RenderSettings};

/// A 16 x 12 Cornell box, 64 mutations per pixel, 16 chains.
fn run(method: PathMltSettings) -> Result<RenderOutput, render::RenderError> {
    let settings = RenderSettings {
        width: 16,
        height: 12,
        threads: 2,
        seed: 3,
        budget: Budget::SamplesPerPixel(64),
        max_depth: 4,
        method: PathMltSettings {
            chains: 16,
            bootstrap_samples: 4000,
            ..method
        }
        .into(),
    };
    render(
        &Scene::cornell_box(16, 12),
        &settings,
        &NoProgress,
        &AtomicBool::new(false),
    )
}

#[test]
fn adaptive_runs_report_the_sigma_map_and_a_typed_summary() {
    let out = run(PathMltSettings::otsu2018(
        PerturbationKind::Lens,
        PathAdapt::Grid,
    ))
    .unwrap();
    let map = out.sigma_map.as_ref().expect("a sigma map");
    assert_eq!(map.len(), 16 * 12);
    assert!(map.iter().all(|s| s.is_finite() && *s > 0.0));
    let summary = out
        .mcmc
        .as_ref()
        .unwrap()
        .regional_adapt
        .expect("a summary");
    assert!(summary.synchronised && summary.rounds > 0);
    assert_eq!((summary.adapt, summary.regions), (PathAdapt::Grid, 400));
    assert!(summary.updated > 0 && summary.updated <= summary.regions);
    assert!(summary.sigma_min <= summary.sigma_median && summary.sigma_median <= summary.sigma_max);
    assert_eq!(summary.refinements, 0, "grids do not refine");
    assert!(out.notes.contains(&summary.note()), "{:?}", out.notes);
    // Negative control: FIXED learns nothing.
    let fixed = run(PathMltSettings::otsu2018(
        PerturbationKind::Lens,
        PathAdapt::Fixed,
    ))
    .unwrap();
    assert!(fixed.sigma_map.is_none());
    assert!(fixed.mcmc.unwrap().regional_adapt.is_none());
}

#[test]
fn quadtree_refines_on_the_pixel_schedule() {
    let quadtree = PathMltSettings::otsu2018(PerturbationKind::Lens, PathAdapt::Quadtree);
    let summary = |method| run(method).unwrap().mcmc.unwrap().regional_adapt.unwrap();
    // 16 x 12 = 192 pixels: M_split = 500, M_refine = 500 * 12 = 6000, at most 12 leaves;
    // 12 288 mutations reach two passes.
    let s = summary(quadtree);
    assert_eq!(s.refinements, 2);
    assert!(s.splits >= 1 && s.regions <= 12, "{s:?}");
    // Negative control: an M_split beyond any leaf's visits never splits.
    let never_splits = PathMltSettings {
        split_after_visits: Some(1_000_000),
        ..quadtree
    };
    let s = summary(never_splits);
    assert_eq!((s.splits, s.regions), (0, 1));
    let never = PathMltSettings {
        split_after_visits: Some(0),
        ..quadtree
    };
    assert!(run(never).is_err());
}

#[test]
fn scale_and_target_out_of_range_are_refused() {
    let grid = PathMltSettings::otsu2018(PerturbationKind::Lens, PathAdapt::Grid);
    for bad in [
        PathMltSettings { sigma: 0.0, ..grid },
        PathMltSettings { sigma: 4.0, ..grid },
        PathMltSettings {
            target_acceptance: 1.0,
            ..grid
        },
        PathMltSettings {
            round_mutations: 0,
            ..grid
        },
    ] {
        let err = run(bad).unwrap_err().to_string();
        assert!(
            err.contains("sigma") || err.contains("target-acceptance") || err.contains("round"),
            "{err}"
        );
    }
}
