//! Regional adaptation's typed results through the session (`--integrator pathmlt --adapt`):
//! the learned sigma map and the `AdaptSummary` (whose note is the render's note), RA-QUADTREE's
//! refinement schedule from `PathMltSettings::refine_for_mutations` / `split_after_visits`;
//! negative controls: FIXED reports neither, a schedule beyond the budget never refines, and
//! `M_split = 0` is refused.

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
fn quadtree_refines_on_the_schedule_it_is_given() {
    let quadtree = PathMltSettings::otsu2018(PerturbationKind::Lens, PathAdapt::Quadtree);
    let refinements = |method| {
        let out = run(method).unwrap();
        out.mcmc.unwrap().regional_adapt.unwrap().refinements
    };
    // Scaled to the budget (12 288 mutations): M_refine = 1000, about a dozen passes.
    let scaled = refinements(quadtree);
    assert!(scaled >= 5, "{scaled}");
    // The same schedule given explicitly gives the same render.
    let explicit = PathMltSettings {
        refine_for_mutations: Some(64 * 16 * 12),
        ..quadtree
    };
    assert_eq!(refinements(explicit), scaled);
    // Negative control: scaled to 10^9 mutations, M_refine is beyond the budget.
    let late = PathMltSettings {
        refine_for_mutations: Some(1_000_000_000),
        ..quadtree
    };
    assert_eq!(refinements(late), 0);
    let never = PathMltSettings {
        split_after_visits: Some(0),
        ..quadtree
    };
    assert!(run(never).is_err());
}
