//! What one render measured ([`RunRecord`]) and the quantities tables summarise over seeds
//! ([`Measure`]).

use std::fmt;
use std::path::PathBuf;

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
            Self::Acceptance | Self::PLarge => format!("{value:.3}"),
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
    }
}
