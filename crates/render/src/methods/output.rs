//! What a render returns: the image, counters, human-readable notes and typed run statistics
//! ([`McmcStats`] for the Markov chain methods, [`LqmcStats`] for LQMC).

use std::time::Duration;

use mcmc_core::controller::LargeStepEstimate;
use mcmc_core::stats::AcceptanceStats;

use crate::image::Image;
use crate::mlt::pathmlt::AdaptSummary;
use crate::mlt::MltOutput;
use crate::shard::Partial;

/// The result of a render.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The rendered (possibly partial, if cancelled) image.
    pub image: Image,
    /// Number of samples (or mutations) evaluated.
    pub samples: u64,
    /// Samples whose radiance was NaN or infinite; they were dropped, not splatted.
    pub dropped_nonfinite: u64,
    /// True if the render stopped early because `cancel` was set.
    pub cancelled: bool,
    /// Pixels the render never reached (a cancel or the time budget stopped its first pass
    /// before them): black, or for BDPT lit only by light tracing. 0 for a complete image
    /// and for the Markov chain methods, whose image is a global estimate.
    pub unsampled_pixels: u64,
    /// Wall-clock time spent.
    pub elapsed: Duration,
    /// Notes for people (e.g. why an image is black). Programs read [`RenderOutput::mcmc`]
    /// instead: the notes' wording may change.
    pub notes: Vec<String>,
    /// BDPT with `strategy_images`: the MIS-weighted image of each strategy `(s, t)`.
    pub strategy_images: Vec<((u8, u8), Image)>,
    /// Delayed-rejection MLT: the stage map, per pixel the share of the estimate contributed
    /// by second-stage candidates (`render::mlt::StagedSplats`; paper Fig. 1 and 9).
    pub stage_map: Option<Image>,
    /// The Markov chain methods' run statistics (`None` for PT, QMC, BDPT and LQMC).
    pub mcmc: Option<McmcStats>,
    /// Path-space MLT with regional adaptation: the learned `sigma_1` (radians) per pixel,
    /// row-major (`render::mlt::pathmlt::render_adaptive_with_params`; `None` for FIXED, the
    /// other methods, or if no synchronisation point was reached).
    pub sigma_map: Option<Vec<f64>>,
    /// LQMC's run statistics (`None` for the other methods).
    pub lqmc: Option<LqmcStats>,
    /// A sharded render's accumulators, which add up with the other shards' to the whole
    /// render ([`crate::shard`]); `None` for an unsharded render.
    pub partial: Option<Partial>,
    /// The two parts of an MCMC render with a separate direct-lighting pass, whose sum is
    /// [`RenderOutput::image`]; `None` without a pass.
    pub direct_parts: Option<DirectParts>,
}

/// An MCMC render with a separate direct-lighting pass, split: the pass's image (path depths
/// up to the pass's depth) and the chains' (the deeper paths). Comparing the chains' parts of
/// two methods that share the pass measures what the chains differ by without the pass's
/// noise.
#[derive(Clone, Debug)]
pub struct DirectParts {
    /// The direct-lighting pass's image.
    pub direct: Image,
    /// The chains' image.
    pub chains: Image,
}

impl RenderOutput {
    /// An output with `image` and no counters, notes or statistics (the methods fill in the
    /// rest).
    #[must_use]
    pub fn new(image: Image, elapsed: Duration) -> Self {
        Self {
            image,
            samples: 0,
            dropped_nonfinite: 0,
            cancelled: false,
            unsampled_pixels: 0,
            elapsed,
            notes: Vec::new(),
            strategy_images: Vec::new(),
            stage_map: None,
            mcmc: None,
            sigma_map: None,
            lqmc: None,
            partial: None,
            direct_parts: None,
        }
    }
}

/// What pixels a render did not reach lack ([`unsampled_note`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unsampled {
    /// No sample at all: the pixels are black.
    Black,
    /// No camera sample: only BDPT's light-tracing splats reach them.
    CameraSamples,
    /// No seed path: only lattice members of neighbouring seeds reach them (LQMC).
    SeedPaths,
}

/// The note for an image with `unsampled` of its `pixels` not reached: how much of the image
/// is missing and why (a cancel or the time budget stopping the first pass), so that an
/// incomplete image is never presented as complete. `None` if every pixel was reached.
#[must_use]
pub fn unsampled_note(
    unsampled: u64,
    pixels: u64,
    cancelled: bool,
    lacking: Unsampled,
) -> Option<String> {
    if unsampled == 0 || pixels == 0 {
        return None;
    }
    let percent = 100.0 * unsampled as f64 / pixels as f64;
    Some(format!(
        "the image is incomplete: {percent:.1} % of the pixels ({unsampled} of {pixels}) have {}, because {} stopped the first pass before them",
        match lacking {
            Unsampled::Black => "no sample (black)",
            Unsampled::CameraSamples => "no camera sample (only light-tracing contributions)",
            Unsampled::SeedPaths => "no seed path (only neighbouring lattice members)",
        },
        if cancelled { "the cancel" } else { "the time budget" }
    ))
}

/// Wall-clock time of each phase of a Markov chain render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// A separate direct-lighting pass, its pilot included (PSSMLT).
    pub direct_pass: Duration,
    /// A separate estimate of the normalisation (MMLT's `--bdpt-normalization`).
    pub normalization: Duration,
    /// The bootstrap: independent samples for `b` and the chain starts.
    pub bootstrap: Duration,
    /// The first round of the chains; with automatic large-step control, its estimation
    /// phase (the rest of the chains' time is [`PhaseTimes::chains`] minus this).
    pub estimation: Duration,
    /// All rounds of the chains, the estimation phase included.
    pub chains: Duration,
}

/// A separate direct-lighting pass's run (PSSMLT: `render::mlt::direct`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectPassStats {
    /// The pass rendered path depths `0..=depth`; the chains the deeper ones.
    pub depth: u32,
    /// BDPT samples per pixel the pass took.
    pub spp: u32,
    /// With a balanced pass: the pilot's estimate of the pass depths' share of the light.
    pub light_share: Option<f64>,
    /// With a balanced or proportional pass: the share of a time budget it was given.
    pub time_share: Option<f64>,
}

/// Typed statistics of a Markov chain render: the normalisation, acceptance per mixture
/// component and per delayed-rejection stage, the automatic large-step estimate and the time
/// of each phase.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct McmcStats {
    /// The normalisation `b` the chains' image is scaled with: the bootstrap pooled with
    /// every large-step candidate (`mcmc_core::render_loop::Normalization`), the bootstrap's
    /// alone, or the one given.
    pub b: f64,
    /// Standard error of `b` (0 if given).
    pub b_standard_error: f64,
    /// The bootstrap's own estimate of `b` (or the sum of a per-depth normalisation given).
    pub bootstrap_b: f64,
    /// The bootstrap's standard error.
    pub bootstrap_standard_error: f64,
    /// Large-step candidates pooled into `b`.
    pub large_step_samples: u64,
    /// True if `b` was given rather than estimated.
    pub normalization_given: bool,
    /// The standard error of the image's mean brightness that `b`'s error causes, relative to
    /// that mean (`b_standard_error / b`; PSSMLT with a direct pass: over `b` plus the pass's
    /// mean luminance). 0 if `b` was given.
    pub brightness_standard_error: f64,
    /// Bootstrap samples evaluated.
    pub bootstrap_samples: u64,
    /// The estimate `b_d` of each target (MMLT: path depth); they sum to `b`.
    pub target_b: Vec<f64>,
    /// Chains started per target.
    pub target_chains: Vec<usize>,
    /// Mutations performed (all chains).
    pub mutations: u64,
    /// Acceptance pooled over chains: per mixture component
    /// ([`AcceptanceStats::component_acceptance_rate`]) and per delayed-rejection stage
    /// ([`AcceptanceStats::stage_acceptance_rate`]).
    pub acceptance: AcceptanceStats,
    /// The automatic large-step estimate (`eta_s`, `eta_l`, `eta_0`, `p_l`; Zsolnai &
    /// Szirmay-Kalos 2013, section 2), if automatic control ran; its
    /// [`LargeStepEstimate::steps`] are the estimation phase's mutations
    /// ([`McmcStats::estimation_share`]).
    pub large_step: Option<LargeStepEstimate>,
    /// The large-step probability after any estimation phase.
    pub large_step_probability: f64,
    /// A separate direct-lighting pass, if one ran.
    pub direct_pass: Option<DirectPassStats>,
    /// True if the bootstrap found no light-carrying path (the image is black).
    pub found_nothing: bool,
    /// Wall-clock time per phase.
    pub times: PhaseTimes,
    /// Path-space MLT with regional adaptation: what the adaptation did (`None` otherwise).
    pub regional_adapt: Option<AdaptSummary>,
}

/// Typed statistics of an LQMC render (Tessari et al. 2020): the seed paths and what their
/// lattice sets explored (`render::integrator::lqmc::LqmcOutput`'s counters).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LqmcStats {
    /// Seed paths traced.
    pub seeds: u64,
    /// Progressions (samples per pixel) in the image.
    pub progressions: u32,
    /// Contributions explored with a lattice set.
    pub explored: u64,
    /// Contributions splatted unexplored.
    pub direct: u64,
    /// NEE-class contributions explored (the authors' code's rule,
    /// `LqmcSettings::tessari2020_code`; part of `explored`).
    pub explored_nee: u64,
    /// NEE-class contributions splatted unexplored (the paper's rule; part of `direct`).
    pub direct_nee: u64,
    /// Lattice members in their seed's class (seeds included).
    pub members: u64,
    /// Lattice members rejected (left the class).
    pub rejected: u64,
}

impl std::fmt::Display for LqmcStats {
    /// `N seeds, N progressions, N contributions explored (N of them NEE; N members in class,
    /// N rejected), N splatted unexplored (N of them NEE)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} seeds, {} progressions, {} contributions explored ({} of them NEE; {} members in class, {} rejected), {} splatted unexplored ({} of them NEE)",
            self.seeds,
            self.progressions,
            self.explored,
            self.explored_nee,
            self.members,
            self.rejected,
            self.direct,
            self.direct_nee
        )
    }
}

impl McmcStats {
    /// The acceptance rate over all steps.
    #[must_use]
    pub fn acceptance_rate(&self) -> f64 {
        self.acceptance.acceptance_rate()
    }

    /// The share of the mutations that automatic large-step control's estimation phase used
    /// (its steps over [`McmcStats::mutations`]; `None` without automatic control or without
    /// mutations).
    #[must_use]
    pub fn estimation_share(&self) -> Option<f64> {
        let e = self.large_step?;
        (self.mutations > 0).then(|| e.steps() as f64 / self.mutations as f64)
    }

    /// The statistics of an MCMC driver run.
    #[must_use]
    pub fn from_mlt(out: &MltOutput) -> Self {
        Self {
            b: out.b,
            b_standard_error: out.b_standard_error,
            bootstrap_b: out.bootstrap_b,
            bootstrap_standard_error: out.bootstrap_standard_error,
            large_step_samples: out.large_step_samples,
            normalization_given: out.normalization_given,
            brightness_standard_error: relative_error(out.b_standard_error, out.b),
            bootstrap_samples: out.bootstrap_samples,
            target_b: out.target_b.clone(),
            target_chains: out.target_chains.clone(),
            mutations: out.mutations,
            acceptance: out.stats,
            large_step: out.large_step,
            large_step_probability: out.final_large_step_probability,
            direct_pass: None,
            found_nothing: out.message.is_some(),
            times: PhaseTimes {
                bootstrap: out.bootstrap_time,
                estimation: out.estimation_time,
                chains: out.chains_time,
                ..PhaseTimes::default()
            },
            regional_adapt: None,
        }
    }
}

/// `error / mean`, 0 for a non-positive mean.
#[must_use]
pub fn relative_error(error: f64, mean: f64) -> f64 {
    if mean > 0.0 {
        error / mean
    } else {
        0.0
    }
}

/// The brightness error a render should reach: the standard error of the image's mean
/// brightness due to the normalisation, relative to it (1 %: 2 % at 95 % confidence).
pub const BRIGHTNESS_TARGET: f64 = 0.01;

/// The notes every Markov chain render reports: the driver's own, then why the image is black
/// or the bootstrap's `b` and the acceptance rate, then the automatic large-step estimate.
#[must_use]
pub fn mcmc_notes(out: &MltOutput) -> Vec<String> {
    let mut notes = out.notes.clone();
    if let Some(msg) = &out.message {
        notes.push(msg.clone());
    } else {
        if !out.normalization_given {
            notes.push(format!(
                "normalisation: b = {:.6} (standard error {:.2e}, {:.2} %) from {} bootstrap samples{}",
                out.b,
                out.b_standard_error,
                100.0 * relative_error(out.b_standard_error, out.b),
                out.bootstrap_samples,
                if out.large_step_samples > 0 {
                    format!(
                        " and {} large steps (the bootstrap alone: {:.6}, standard error {:.2e})",
                        out.large_step_samples, out.bootstrap_b, out.bootstrap_standard_error
                    )
                } else {
                    String::new()
                }
            ));
        }
        notes.push(format!(
            "acceptance rate {:.3} over {} mutations",
            out.stats.acceptance_rate(),
            out.mutations
        ));
    }
    if let Some(e) = out.large_step {
        notes.push(format!(
            "automatic large-step control: eta_s = {:.4}, eta_l = {:.4}, eta_0 = {:.4} ({} small, {} large steps: the estimation phase, {:.1} % of the mutations) -> p_large = {:.4}",
            e.eta_s,
            e.eta_l,
            e.eta_0,
            e.small_steps,
            e.large_steps,
            100.0 * e.steps() as f64 / out.mutations.max(1) as f64,
            e.large_step_probability
        ));
    }
    notes
}

/// A render output from an MCMC driver run: image, counters, `notes` then the run's own
/// ([`mcmc_notes`]), statistics.
#[must_use]
pub fn mcmc_output(out: MltOutput, mut notes: Vec<String>, elapsed: Duration) -> RenderOutput {
    notes.extend(mcmc_notes(&out));
    let mcmc = McmcStats::from_mlt(&out);
    RenderOutput {
        samples: out.mutations,
        dropped_nonfinite: out.dropped + out.non_finite,
        cancelled: out.cancelled,
        notes,
        stage_map: out.stage_map,
        mcmc: Some(mcmc),
        partial: out.component.map(|c| Partial {
            width: out.image.width,
            height: out.image.height,
            components: vec![c],
        }),
        ..RenderOutput::new(out.image, elapsed)
    }
}
