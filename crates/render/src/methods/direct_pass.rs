//! A separate direct-lighting pass before the chains ([`crate::mlt::direct`]; Mitsuba 0.6's
//! `directSamples`): BDPT renders path depths `0..=K`, the chains only the deeper ones. A
//! balanced pass first runs a pilot that picks its share of the budget.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use super::{
    relative_error, unsampled_note, DirectParts, DirectPassStats, RenderOutput, RenderSettings,
    Run, Unsampled,
};
use crate::bdpt::{BdptOutput, BdptParams};
use crate::budget::Budget;
use crate::error::RenderError;
use crate::mlt::direct::{self, DirectPass};
use crate::mlt::MltSettings;
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use mcmc_core::render_loop::NormalizationMode;

/// A direct-lighting pass's settings, shared by the Markov chain integrators over BDPT paths
/// (`mmlt` and the `mala*` rows; `pssmlt` keeps the same three settings as its own fields).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectSettings {
    /// How the pass is budgeted ([`DirectPass::Off`]: no pass, the chains take every depth).
    pub pass: DirectPass,
    /// The pass renders depths `0..=depth` (at least 1; no pass if `depth` >= the maximum
    /// depth).
    pub depth: u32,
    /// The pass's per-pixel sampler.
    pub sampler: SamplerKind,
}

impl DirectSettings {
    /// No pass (depth 1 and Sobol points if one is asked for later, e.g. by
    /// `--direct-samples`: direct light only, the split of the Langevin authors' code).
    pub const OFF: Self = Self {
        pass: DirectPass::Off,
        depth: 1,
        sampler: SamplerKind::Sobol,
    };

    /// PSSMLT's default pass ([`DirectPass::PSSMLT_DEFAULT`], balanced against the chains by
    /// a pilot) over depths `0..=depth`, Sobol points.
    #[must_use]
    pub const fn balanced(depth: u32) -> Self {
        Self {
            pass: DirectPass::PSSMLT_DEFAULT,
            depth,
            sampler: SamplerKind::Sobol,
        }
    }

    /// The pass's depth as used (at least 1).
    #[must_use]
    pub const fn pass_depth(&self) -> u32 {
        if self.depth == 0 {
            1
        } else {
            self.depth
        }
    }

    /// Runs the pass (if on) before the chains: the pass usable by the chains, the time it
    /// took, and the shallowest depth the chains must sample ([`run`], [`usable`],
    /// [`chain_min_depth`]).
    pub fn run(
        &self,
        scene: &Scene,
        params: &BdptParams,
        common: &RenderSettings,
        run_: &Run<'_>,
        notes: &mut Vec<String>,
    ) -> (Option<DirectRun>, Option<Duration>, u32) {
        let depth = self.pass_depth();
        let ran = run(
            scene,
            params,
            common,
            self.pass,
            depth,
            self.sampler,
            run_,
            notes,
        );
        let spent = ran.as_ref().map(|d| d.elapsed);
        let ran = usable(ran, common, notes);
        let min_depth = chain_min_depth(ran.as_ref(), self.pass, common, depth);
        (ran, spent, min_depth)
    }
}

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

/// The pass if the chains can rely on it: a pass whose share of a time budget did not reach
/// every pixel (a huge image) would leave those pixels without their direct light, so it is
/// dropped (with a note) and the chains take every depth.
pub fn usable(
    direct: Option<DirectRun>,
    common: &RenderSettings,
    notes: &mut Vec<String>,
) -> Option<DirectRun> {
    let d = direct?;
    if d.pass.unsampled_pixels > 0 && !d.pass.cancelled {
        let pixels = u64::from(common.width) * u64::from(common.height);
        notes.push(format!(
            "the direct-lighting pass reached only {:.1} % of the pixels in its share of the time budget: it is dropped and the chains render every depth",
            100.0 * (pixels - d.pass.unsampled_pixels.min(pixels)) as f64 / pixels as f64
        ));
        return None;
    }
    Some(d)
}

/// The shallowest path depth the chains sample: beyond the pass's depths if a pass ran,
/// else 0 (every depth).
#[must_use]
pub fn chain_min_depth(
    direct: Option<&DirectRun>,
    pass: DirectPass,
    common: &RenderSettings,
    pass_depth: u32,
) -> u32 {
    if direct.is_some() {
        pass.chain_min_depth(common.max_depth, pass_depth)
    } else {
        0
    }
}

/// Adds the pass to the chains' output: its image, counters, shard component, statistics
/// and notes (what the image holds if the chains found nothing or never ran).
pub fn merge_into(
    d: DirectRun,
    output: &mut RenderOutput,
    common: &RenderSettings,
    run: &Run<'_>,
    chains_ran: bool,
) {
    let depths = format!("path depths 0-{}", d.stats.depth);
    if output.mcmc.as_ref().is_some_and(|m| m.found_nothing) {
        output.notes.push(format!(
            "the bootstrap found no light on deeper paths: the direct-lighting pass ({depths}) is the whole image"
        ));
    } else if !chains_ran {
        output.notes.push(format!(
            "{} before the chains ran: the image holds only the direct-lighting pass ({depths}); the light of deeper paths is missing",
            if output.cancelled || run.cancel.load(Ordering::Relaxed) {
                "cancelled"
            } else {
                "stopped"
            }
        ));
    }
    output.notes.extend(unsampled_note(
        d.pass.unsampled_pixels,
        u64::from(common.width) * u64::from(common.height),
        d.pass.cancelled,
        Unsampled::CameraSamples,
    ));
    output.unsampled_pixels = d.pass.unsampled_pixels;
    let chains = output.image.clone();
    direct::add_into(&mut output.image, &d.pass.image);
    if let (Some(partial), Some(c)) = (output.partial.as_mut(), d.pass.component) {
        partial.components.push(c);
    }
    output.dropped_nonfinite += d.pass.dropped;
    output.cancelled |= d.pass.cancelled;
    if let Some(stats) = output.mcmc.as_mut() {
        stats.direct_pass = Some(d.stats);
        // The pass's light is not scaled by `b`: the brightness error is relative to the
        // whole image.
        stats.brightness_standard_error = relative_error(
            stats.b_standard_error,
            stats.b + d.pass.image.mean_luminance(),
        );
        stats.times.direct_pass = d.elapsed;
    }
    output.direct_parts = Some(DirectParts {
        direct: d.pass.image,
        chains,
    });
}

/// A given normalisation (`--normalization B|FILE`) is the whole image's mean luminance: with
/// a direct pass the chains render what the pass does not, so their `b` is the given one less
/// the pass's mean (with a note).
///
/// # Errors
/// [`RenderError::InvalidSetting`] naming `normalization` if nothing is left for the chains.
pub fn given_normalization(
    settings: &mut MltSettings,
    direct: Option<&DirectRun>,
    notes: &mut Vec<String>,
) -> Result<(), RenderError> {
    if let (NormalizationMode::Given(b), Some(d)) = (settings.normalization, direct) {
        let pass = d.pass.image.mean_luminance();
        if b - pass <= 0.0 || pass.is_nan() {
            return Err(RenderError::setting(
                "normalization",
                b,
                "above the direct-lighting pass's mean luminance (the chains render the rest of the light)",
            ));
        }
        notes.push(format!(
            "normalisation given: b = {b:.6} for the image, {:.6} for the chains after the direct pass's {pass:.6}",
            b - pass
        ));
        settings.normalization = NormalizationMode::Given(b - pass);
    }
    Ok(())
}
