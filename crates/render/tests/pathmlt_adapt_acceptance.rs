//! Regional adaptation at the paper's speed (Otsu et al. 2018, Alg. 1): after the mutations of
//! about one second of a 64 x 64 render (one thread), the recent acceptance of at least 90 % of
//! the visited RA-GRID cells is within 0.5 +- 0.1, starting from the paper's `lambda = 1`.
//! "Visited": at least 200 perturbation proposals from the cell (`render::mlt::pathmlt::VISITED_PROPOSALS`), so that
//! its recent acceptance (a mean over about 200 proposals) is measured to about 0.03.
//! Negative control: the earlier rule of one sign step per cell per round, with its 50
//! mutations per chain per round, leaves most cells far from the target in the same
//! mutations.
//!
//! The budget is a mutation count (244 per pixel, about 10^6 mutations: what one thread makes
//! in about one second on the Cornell box), so the test is deterministic.

use std::sync::atomic::AtomicBool;

use pathspace::regional::RegionalUpdateRule;
use pathspace::PerturbationKind;
use render::methods::PathMltSettings;
use render::mlt::pathmlt::{AdaptSummary, PathAdapt};
use render::scene::Scene;
use render::session::{render, Budget, NoProgress, RenderSettings};

/// RA-GRID (lens, 20 x 20 screen cells) on a 64 x 64 Cornell box, 244 mutations per pixel.
fn grid_summary(method: PathMltSettings) -> AdaptSummary {
    let settings = RenderSettings {
        width: 64,
        height: 64,
        threads: 2,
        seed: 5,
        budget: Budget::SamplesPerPixel(244),
        max_depth: 5,
        method: method.into(),
    };
    let out = render(
        &Scene::cornell_box(64, 64),
        &settings,
        &NoProgress,
        &AtomicBool::new(false),
    )
    .unwrap();
    out.mcmc.unwrap().regional_adapt.unwrap()
}

#[test]
fn paper_speed_puts_nine_in_ten_visited_cells_near_the_target() {
    let paper = PathMltSettings::otsu2018(PerturbationKind::Lens, PathAdapt::Grid);
    let s = grid_summary(paper);
    println!("paper rule: {}", s.note());
    assert!(s.visited >= 200, "{s:?}");
    assert!(s.near_target_share() >= 0.9, "{s:?}");

    // Negative control: one step per cell per round, rounds of 50 mutations per chain.
    let old = PathMltSettings {
        update_rule: RegionalUpdateRule::OncePerRound,
        round_mutations: 50,
        ..paper
    };
    let s = grid_summary(old);
    println!("one step per round: {}", s.note());
    assert!(s.near_target_share() < 0.9, "{s:?}");
}
