//! Delayed-rejection MLT on MMLT, light-tracing strategies (DR paper section 5.1.2, "Handling
//! Light Tracing"): the strategy test reads the same choice BDPT makes, and for `t = 1` states
//! the second stage moves the light subpath (with the camera stream only, it would propose the
//! same path again: the negative control shows that waste).

use glam::Vec2;
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::{Proposal, Target};
use pss::{OnLayout, Orbital, PssState, WrappedCauchy};
use rand::SeedableRng;
use render::bdpt::{self, BdptParams, BdptScratch};
use render::mlt::dr::{self, is_light_tracing, DrBase};
use render::mlt::{MmltTarget, PATH_STREAMS};
use render::scene::Scene;

#[test]
fn light_tracing_test_matches_the_sampled_strategy() {
    let scene = Scene::cornell_box(16, 16);
    let params = BdptParams::default();
    let mut scratch = BdptScratch::default();
    let (mut checked, mut light_tracing) = (0, 0);
    for depth in 1..=4u32 {
        for key in 0..4000u64 {
            let mut x = PssState::new(PATH_STREAMS, key);
            x.begin();
            if let Some(sp) = bdpt::sample_strategy(
                &scene,
                &mut x,
                depth,
                Vec2::splat(16.0),
                &params,
                &mut scratch,
            ) {
                assert_eq!(
                    is_light_tracing(&x, depth),
                    sp.t == 1,
                    "depth {depth} key {key}: t = {}",
                    sp.t
                );
                checked += 1;
                light_tracing += usize::from(sp.t == 1);
            }
        }
    }
    eprintln!("{checked} strategies checked, {light_tracing} light tracing");
    assert!(checked > 1000 && light_tracing > 50);
}

#[test]
fn light_tracing_states_get_a_second_stage_that_moves_the_path() {
    let scene = Scene::cornell_box(16, 16);
    let params = BdptParams::default();
    let depth = 2u32;
    let target = MmltTarget::all_depths(&scene, params, 16, 16)[depth as usize];
    let layout = dr::dr_layout(params.max_depth);
    let kernel = dr::orbital_kernel(layout, DrBase::Mmlt, 0.0, depth);
    // The control: the camera-only second stage for every strategy.
    let camera_only = OnLayout::new(
        Orbital {
            angle: WrappedCauchy::default(),
        },
        layout,
    )
    .with_stream_mask(dr::second_stage_streams(DrBase::Mmlt));
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let mut payload = Default::default();
    let (mut tried, mut moved, mut control_same) = (0, 0, 0);
    for key in 0..20_000u64 {
        if tried == 200 {
            break;
        }
        let mut x = PssState::new(PATH_STREAMS, key);
        let lx = target.evaluate(&mut x, &mut payload);
        if !lx.is_finite() || !is_light_tracing(&x, depth) {
            continue;
        }
        // A first-stage candidate from the pairwise Kelemen step (no large steps: p = 0).
        let mut y = x.clone();
        let _ = kernel.first.propose(&x, &mut y, &mut rng);
        target.evaluate(&mut y, &mut payload);
        // As the kernel does after rejecting y: x keeps what y's catch-up drew of it.
        mcmc_core::Point::absorb_rejected(&mut x, &y);
        let mut z = x.clone();
        if !matches!(
            kernel.second.propose(&x, &y, &mut z, &mut rng),
            mcmc_core::Proposed::Move { .. }
        ) {
            continue;
        }
        tried += 1;
        let lz = target.evaluate(&mut z, &mut payload);
        if lz != lx {
            moved += 1;
        }
        let mut zc = x.clone();
        let _ = camera_only.propose(&x, &y, &mut zc, &mut rng);
        if target.evaluate(&mut zc, &mut payload) == lx {
            control_same += 1;
        }
    }
    eprintln!("{tried} light-tracing states: the strategy-aware stage changed the path on {moved}, the camera-only stage left it unchanged on {control_same}");
    assert!(tried >= 100);
    assert!(moved * 10 >= tried * 9, "{moved} of {tried}");
    assert!(control_same * 10 >= tried * 9, "{control_same} of {tried}");
}

/// The per-depth MMLT layout covers what every strategy of its depth reads (the stages then
/// move every number the chain's paths use, and nothing of the max-depth layout beyond), and
/// it is smaller than the max-depth PSSMLT layout. Control: the layout of depth `d - 2` does
/// not cover depth `d`'s reads.
#[test]
fn per_depth_layout_covers_what_each_depth_reads() {
    let scene = Scene::cornell_box(16, 16);
    let params = BdptParams::default();
    let targets = MmltTarget::all_depths(&scene, params, 16, 16);
    let mut payload = Default::default();
    for (depth, target) in targets.iter().enumerate() {
        let layout = dr::mmlt_layout(depth as u32);
        let mut most = [0usize; PATH_STREAMS];
        for key in 0..3000u64 {
            let mut x = PssState::new(PATH_STREAMS, key);
            target.evaluate(&mut x, &mut payload);
            for (s, m) in most.iter_mut().enumerate() {
                *m = (*m).max(x.read_counts()[s]);
            }
        }
        for (s, &m) in most.iter().enumerate() {
            assert!(m <= layout.dim(s), "depth {depth} stream {s}: reads {m}");
        }
        if depth >= 2 {
            let smaller = dr::mmlt_layout(depth as u32 - 2);
            assert!(
                (0..PATH_STREAMS).any(|s| most[s] > smaller.dim(s)),
                "depth {depth}: {most:?}"
            );
        }
        assert!(layout.len() < dr::dr_layout(params.max_depth).len());
    }
}
