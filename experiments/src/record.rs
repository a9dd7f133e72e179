//! What one render measured ([`RunRecord`]) and the quantities tables summarise over seeds
//! ([`Measure`]).

use std::fmt;
use std::path::PathBuf;

use mcmc_core::stats::AcceptanceStats;
use render::metrics::Metrics;

use crate::load::LoadAverage;
use crate::report::ConvergencePoint;
use crate::stats::RunStats;

/// One render of one method on one scene with one seed.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRecord {
    /// The scene's name.
    pub scene: String,
    /// The method's name.
    pub method: String,
    /// The seed.
    pub seed: u64,
    /// Wall-clock seconds of the render call, measured by the harness for every method alike.
    pub seconds: f64,
    /// Samples (MCMC: mutations) the render evaluated.
    pub samples: u64,
    /// Errors against the scene's reference ([`render::metrics::compare`]); NaN when the
    /// image could not be compared (non-finite pixels).
    pub metrics: Metrics,
    /// The method's own statistics ([`crate::run_stats`]).
    pub stats: RunStats,
    /// The machine's load just before the render.
    pub load: Option<LoadAverage>,
    /// The final image, relative to the scene's run directory.
    pub image: PathBuf,
    /// Error-vs-time samples: extra renders at fractions of the budget, then this one.
    pub convergence: Vec<ConvergencePoint>,
}

impl RunRecord {
    /// Samples (MCMC: mutations) per second of wall-clock time.
    #[must_use]
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.seconds
    }
}

/// A per-run quantity a table summarises over seeds (median, range, ratio to a baseline).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Measure {
    /// Mean squared error ([`render::metrics::mse`]; Luan et al. 2020).
    Mse,
    /// Relative MSE ([`render::metrics::relmse`]; Rioux-Lavoie et al. 2020).
    RelMse,
    /// Root relative MSE ([`render::metrics::rrmse`]; Otsu et al. 2018).
    RRmse,
    /// Mean absolute difference ([`render::metrics::mad`]; Tessari et al.).
    Mad,
    /// Wall-clock seconds of the render.
    Seconds,
    /// Samples (MCMC: mutations) per second.
    SamplesPerSecond,
    /// Overall acceptance rate (MCMC).
    Acceptance,
    /// The bootstrap's normalisation `b` (MCMC).
    B,
    /// The large-step probability automatic control chose (MCMC).
    PLarge,
    /// The 1-minute load average before the render.
    Load,
    /// Acceptance rate of the candidates tried at kernel stage `s` (0-based, as
    /// `AcceptanceStats::stage_acceptance_rate`; labelled from 1 as the delayed-rejection
    /// paper numbers its stages). NaN where the stage never ran (MCMC).
    StageAcceptance(usize),
    /// The share of steps that tried kernel stage `s` (0-based): for two-stage delayed
    /// rejection, stage 1 is tried after every first-stage rejection (MCMC).
    StageTried(usize),
    /// The share of accepted moves made at the second stage
    /// (`AcceptanceStats::second_stage_share`; the quantity of the DR paper's stage maps).
    /// NaN without a second stage (MCMC).
    SecondStageShare,
    /// Candidates evaluated per step: every stage tried counts once (one per step for MH; a
    /// kernel's extra evaluations, like Green-Mira's ghost, are not counted) (MCMC).
    CandidatesPerStep,
    /// Acceptance rate of the steps whose first-stage proposal came from mixture component
    /// `j` (0-based, as `AcceptanceStats::component_acceptance_rate`: for PSSMLT and MMLT 0 is
    /// the small step, 1 the large step). NaN where the component never ran (MCMC).
    ComponentAcceptance(usize),
}

/// Headings of [`Measure::StageAcceptance`] by stage.
const STAGE_ACCEPTANCE: [&str; 4] = [
    "stage 1 acceptance",
    "stage 2 acceptance",
    "stage 3 acceptance",
    "stage 4 acceptance",
];
/// Headings of [`Measure::StageTried`] by stage.
const STAGE_TRIED: [&str; 4] = [
    "stage 1 tried (share of steps)",
    "stage 2 tried (share of steps)",
    "stage 3 tried (share of steps)",
    "stage 4 tried (share of steps)",
];
/// Headings of [`Measure::ComponentAcceptance`] by component.
const COMPONENT_ACCEPTANCE: [&str; 8] = [
    "component 0 acceptance",
    "component 1 acceptance",
    "component 2 acceptance",
    "component 3 acceptance",
    "component 4 acceptance",
    "component 5 acceptance",
    "component 6 acceptance",
    "component 7 acceptance",
];

/// `table[i]`, or `beyond` past its end.
fn indexed(table: &[&'static str], i: usize, beyond: &'static str) -> &'static str {
    table.get(i).copied().unwrap_or(beyond)
}

/// `count / total`, NaN for a zero total.
fn share(count: f64, total: u64) -> f64 {
    if total == 0 {
        f64::NAN
    } else {
        count / total as f64
    }
}

impl Measure {
    /// The column heading.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Self::Mse => "MSE",
            Self::RelMse => "relMSE",
            Self::RRmse => "rRMSE",
            Self::Mad => "MAD",
            Self::Seconds => "seconds",
            Self::SamplesPerSecond => "samples/s",
            Self::Acceptance => "acceptance",
            Self::B => "b",
            Self::PLarge => "p_large",
            Self::Load => "load (1 min)",
            Self::StageAcceptance(s) => indexed(&STAGE_ACCEPTANCE, s, "stage acceptance"),
            Self::StageTried(s) => indexed(&STAGE_TRIED, s, "stage tried (share of steps)"),
            Self::SecondStageShare => "stage-2 share of accepted moves",
            Self::CandidatesPerStep => "candidates per step",
            Self::ComponentAcceptance(j) => {
                indexed(&COMPONENT_ACCEPTANCE, j, "component acceptance")
            }
        }
    }

    /// The quantity for `run`; NaN where the run has none.
    #[must_use]
    pub fn of(self, run: &RunRecord) -> f64 {
        let m = &run.metrics;
        match self {
            Self::Mse => m.mse,
            Self::RelMse => m.relmse,
            Self::RRmse => m.rrmse,
            Self::Mad => m.mad,
            Self::Seconds => run.seconds,
            Self::SamplesPerSecond => run.samples_per_second(),
            Self::Acceptance => run.stats.acceptance.unwrap_or(f64::NAN),
            Self::B => run.stats.b.unwrap_or(f64::NAN),
            Self::PLarge => run.stats.large_step.map_or(f64::NAN, |l| l.p_large),
            Self::Load => run.load.map_or(f64::NAN, |l| l.one),
            Self::StageAcceptance(_)
            | Self::StageTried(_)
            | Self::SecondStageShare
            | Self::CandidatesPerStep
            | Self::ComponentAcceptance(_) => run
                .stats
                .acceptance_counts
                .map_or(f64::NAN, |a| self.of_counts(&a)),
        }
    }

    /// A per-stage or per-component measure from the acceptance counts (NaN for an index
    /// beyond the counts, a stage or component that never ran, and the other measures).
    fn of_counts(self, a: &AcceptanceStats) -> f64 {
        match self {
            Self::StageAcceptance(s) => a
                .stage_tried
                .get(s)
                .map_or(f64::NAN, |&tried| share(a.stage_accepted[s] as f64, tried)),
            Self::StageTried(s) => a
                .stage_tried
                .get(s)
                .map_or(f64::NAN, |&tried| share(tried as f64, a.steps)),
            Self::SecondStageShare => {
                let accepted: u64 = a.stage_accepted.iter().sum();
                if a.stage_tried.get(1).is_some_and(|&t| t > 0) {
                    share(a.stage_accepted[1] as f64, accepted)
                } else {
                    f64::NAN
                }
            }
            Self::CandidatesPerStep => share(a.stage_tried.iter().sum::<u64>() as f64, a.steps),
            Self::ComponentAcceptance(j) => a
                .proposed
                .get(j)
                .map_or(f64::NAN, |&proposed| share(a.accepted[j] as f64, proposed)),
            _ => f64::NAN,
        }
    }

    /// `value` as the tables print it: 4 significant digits in the style of the quantity
    /// (`0.0123`, `1.234e-5`, `81234`).
    #[must_use]
    pub fn format(self, value: f64) -> String {
        if value.is_nan() {
            return "-".to_owned();
        }
        match self {
            Self::Mse | Self::B => format!("{value:.3e}"),
            Self::RelMse | Self::RRmse | Self::Mad => {
                if value != 0.0 && value.abs() < 1e-3 {
                    format!("{value:.3e}")
                } else {
                    format!("{value:.4}")
                }
            }
            Self::Seconds | Self::Load => format!("{value:.2}"),
            Self::SamplesPerSecond => format!("{value:.0}"),
            Self::Acceptance
            | Self::PLarge
            | Self::StageAcceptance(_)
            | Self::StageTried(_)
            | Self::SecondStageShare
            | Self::ComponentAcceptance(_) => format!("{value:.3}"),
            Self::CandidatesPerStep => format!("{value:.2}"),
        }
    }
}

impl fmt::Display for Measure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_follow_the_quantity() {
        assert_eq!(Measure::RelMse.format(0.012_345), "0.0123");
        assert_eq!(Measure::RelMse.format(1.5e-5), "1.500e-5");
        assert_eq!(Measure::Mse.format(0.000_123_4), "1.234e-4");
        assert_eq!(Measure::SamplesPerSecond.format(81_234.4), "81234");
        assert_eq!(Measure::Acceptance.format(f64::NAN), "-");
        assert_eq!(Measure::Load.to_string(), "load (1 min)");
        assert_eq!(Measure::StageAcceptance(1).label(), "stage 2 acceptance");
        assert_eq!(
            Measure::ComponentAcceptance(1).label(),
            "component 1 acceptance"
        );
        assert_eq!(Measure::StageAcceptance(9).label(), "stage acceptance");
        assert_eq!(Measure::CandidatesPerStep.format(1.234_56), "1.23");
    }

    fn run(counts: Option<AcceptanceStats>) -> RunRecord {
        RunRecord {
            scene: "s".into(),
            method: "m".into(),
            seed: 0,
            seconds: 1.0,
            samples: 10,
            metrics: Metrics {
                mse: 0.0,
                rmse: 0.0,
                relmse: 0.0,
                rrmse: 0.0,
                mad: 0.0,
            },
            stats: RunStats {
                acceptance_counts: counts,
                ..RunStats::default()
            },
            load: None,
            image: PathBuf::new(),
            convergence: Vec::new(),
        }
    }

    /// 10 steps, 8 small (component 0) and 2 large; 6 first-stage acceptances, 4 second
    /// stages tried of which 1 accepted.
    fn two_stage_counts() -> AcceptanceStats {
        let mut a = AcceptanceStats {
            steps: 10,
            ..AcceptanceStats::default()
        };
        (a.proposed[0], a.proposed[1]) = (8, 2);
        (a.accepted[0], a.accepted[1]) = (6, 1);
        a.stage_tried = [10, 4];
        a.stage_accepted = [6, 1];
        a
    }

    #[test]
    fn stage_and_component_measures_read_the_counts() {
        let r = run(Some(two_stage_counts()));
        assert_eq!(Measure::StageAcceptance(0).of(&r), 0.6);
        assert_eq!(Measure::StageAcceptance(1).of(&r), 0.25);
        assert_eq!(Measure::StageTried(1).of(&r), 0.4);
        assert_eq!(Measure::SecondStageShare.of(&r), 1.0 / 7.0);
        assert_eq!(Measure::CandidatesPerStep.of(&r), 1.4);
        assert_eq!(Measure::ComponentAcceptance(0).of(&r), 0.75);
        assert_eq!(Measure::ComponentAcceptance(1).of(&r), 0.5);
    }

    #[test]
    fn stages_and_components_that_never_ran_are_nan_not_zero() {
        // Negative control: `AcceptanceStats`'s own rates give 0 for a stage never tried,
        // which a table would show as a measured 0.
        let mut one_stage = two_stage_counts();
        one_stage.stage_tried[1] = 0;
        one_stage.stage_accepted[1] = 0;
        assert_eq!(one_stage.stage_acceptance_rate(1), 0.0);
        let r = run(Some(one_stage));
        assert!(Measure::StageAcceptance(1).of(&r).is_nan());
        assert!(Measure::SecondStageShare.of(&r).is_nan());
        assert!(Measure::ComponentAcceptance(5).of(&r).is_nan());
        assert!(
            Measure::StageAcceptance(7).of(&r).is_nan(),
            "beyond the stages"
        );
        assert_eq!(Measure::CandidatesPerStep.of(&r), 1.0);
        let none = run(None);
        assert!(Measure::StageTried(0).of(&none).is_nan());
        assert!(Measure::CandidatesPerStep.of(&none).is_nan());
    }
}
