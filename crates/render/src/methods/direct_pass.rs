//! A separate direct-lighting pass before the chains ([`crate::mlt::direct`]; Mitsuba 0.6's
//! `directSamples`): BDPT renders path depths `0..=K`, the chains only the deeper ones. A
//! balanced pass first runs a pilot that picks its share of the budget.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use super::{DirectPassStats, RenderSettings, Run};
use crate::bdpt::{BdptOutput, BdptParams};
use crate::budget::Budget;
use crate::mlt::direct::{self, DirectPass};
use crate::sampler::SamplerKind;
use crate::scene::Scene;

/// A direct-lighting pass that ran.
#[derive(Debug)]
pub struct DirectRun {
    /// The pass's image and counters.
    pub pass: BdptOutput,
    /// Its statistics.
    pub stats: DirectPassStats,
    /// Wall-clock time of the pass, its pilot included.
    pub elapsed: Duration,
}

/// The most all-strategy samples a balanced direct pass's pilot may take: under a mutation
/// budget an eighth of the mutations (at least 1024), so a tiny render is not dominated by
/// its pilot; under a time budget [`direct::BALANCE_SAMPLES`].
fn pilot_cap(common: &RenderSettings) -> u64 {
    match common.budget {
        Budget::SamplesPerPixel(n) => {
            let mutations = u64::from(n) * u64::from(common.width) * u64::from(common.height);
            (mutations / 8).max(1024)
        }
        Budget::Time(_) => direct::BALANCE_SAMPLES,
    }
}

/// Runs `pass` over depths `0..=depth` if it applies at `common.max_depth`, drawing from
/// `sampler`; its notes go to `notes`. Under a time budget the pilot's time is the pass's.
#[allow(clippy::too_many_arguments)]
pub fn run(
    scene: &Scene,
    params: &BdptParams,
    common: &RenderSettings,
    pass: DirectPass,
    depth: u32,
    sampler: SamplerKind,
    run: &Run<'_>,
    notes: &mut Vec<String>,
) -> Option<DirectRun> {
    if !pass.applies_to(common.max_depth, depth) {
        return None;
    }
    let t0 = Instant::now();
    let mut light_share = None;
    // A balanced pass takes its share from a pilot's estimate of how the light divides.
    let pass = if let DirectPass::Balanced { .. } = pass {
        let pilot = direct::BALANCE_SAMPLES.min(pilot_cap(common));
        let phi = direct::pilot_light_share(
            scene,
            params,
            common.width,
            common.height,
            depth,
            pilot,
            common.seed,
            run.cancel,
        );
        light_share = phi;
        let resolved = pass.resolve(phi.unwrap_or(f64::NAN));
        if let DirectPass::Proportional { time_share, .. } = resolved {
            notes.push(match phi {
                Some(phi) => format!(
                    "direct-lighting pass balanced against the chains: depths 0-{depth} carry {:.0} % of the light ({pilot} BDPT samples, {:.2} s) -> {:.0} % of the budget",
                    phi * 100.0,
                    t0.elapsed().as_secs_f64(),
                    time_share * 100.0
                ),
                None if run.cancel.load(Ordering::Relaxed) => {
                    "cancelled during the direct-lighting pass's pilot".to_owned()
                }
                None => format!(
                    "direct-lighting pass: the pilot found no light ({pilot} BDPT samples); {:.0} % of the budget",
                    time_share * 100.0
                ),
            });
        }
        resolved
    } else {
        pass
    };
    let budget = match common.budget {
        Budget::SamplesPerPixel(n) => pass.budget(Some(f64::from(n)), None),
        // The pilot's time is the pass's.
        Budget::Time(t) => match pass.budget(None, Some(t)) {
            (spp, Some(share)) => (
                spp,
                Some(
                    share
                        .saturating_sub(t0.elapsed())
                        .max(Duration::from_millis(1)),
                ),
            ),
            other => other,
        },
    };
    let out = direct::render_direct(
        scene,
        params,
        depth,
        sampler,
        budget,
        common.seed,
        run.shard,
        run.progress,
        run.cancel,
    );
    notes.push(format!(
        "direct-lighting pass: depths 0-{} by BDPT at {} spp ({:.2} s); the chains sample depths >= {}",
        depth,
        out.spp,
        t0.elapsed().as_secs_f64(),
        depth + 1
    ));
    let time_share = match pass {
        DirectPass::Proportional { time_share, .. } => Some(time_share),
        _ => None,
    };
    Some(DirectRun {
        stats: DirectPassStats {
            depth,
            spp: out.spp,
            light_share,
            time_share,
        },
        pass: out,
        elapsed: t0.elapsed(),
    })
}
