//! The two comparison regimes: every render gets the same wall-clock time, or the same number
//! of samples (for MCMC methods, mutations) per pixel.

use std::fmt;
use std::time::Duration;

use render::Budget;

/// What every method gets per render.
///
/// Equal time answers "which method should I run for a minute?" (it charges a method for its
/// cost per sample); equal samples separates the cost of a sample from its efficiency and is
/// bit-reproducible for a seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Regime {
    /// The same wall-clock time per render, bootstrap and any pre-pass included.
    EqualTime(Duration),
    /// The same number of samples (MCMC: mutations) per pixel per render.
    EqualSamples(u32),
}

impl Regime {
    /// Equal time of `seconds` per render.
    ///
    /// # Panics
    /// If `seconds` is negative, not finite or overflows a [`Duration`]; the command-line
    /// options check their value before calling this.
    #[must_use]
    pub fn seconds(seconds: f64) -> Self {
        Self::EqualTime(Duration::from_secs_f64(seconds))
    }

    /// The renderer's budget for one render.
    #[must_use]
    pub fn budget(self) -> Budget {
        match self {
            Self::EqualTime(t) => Budget::Time(t),
            Self::EqualSamples(n) => Budget::SamplesPerPixel(n),
        }
    }

    /// The regime with `fraction` of the budget (for error-vs-time samples): `None` when a
    /// sample count rounds down to zero or `fraction` is not in `(0, 1]`.
    #[must_use]
    pub fn scaled(self, fraction: f64) -> Option<Self> {
        if !(fraction > 0.0 && fraction <= 1.0) {
            return None;
        }
        match self {
            Self::EqualTime(t) => Some(Self::EqualTime(t.mul_f64(fraction))),
            Self::EqualSamples(n) => {
                let scaled = (f64::from(n) * fraction).floor() as u32;
                (scaled > 0).then_some(Self::EqualSamples(scaled))
            }
        }
    }

    /// A short label for tables and CSV files: `4s` or `64spp`.
    #[must_use]
    pub fn label(self) -> String {
        match self {
            Self::EqualTime(t) => format!("{}s", t.as_secs_f64()),
            Self::EqualSamples(n) => format!("{n}spp"),
        }
    }
}

impl fmt::Display for Regime {
    /// `equal time: 4 s per render (bootstrap included)` or `equal samples: 64 samples
    /// (MCMC: mutations) per pixel`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::EqualTime(t) => write!(
                f,
                "equal time: {} s per render (bootstrap included)",
                t.as_secs_f64()
            ),
            Self::EqualSamples(n) => {
                write!(f, "equal samples: {n} samples (MCMC: mutations) per pixel")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_and_labels() {
        assert_eq!(
            Regime::seconds(2.5).budget(),
            Budget::Time(Duration::from_millis(2500))
        );
        assert_eq!(
            Regime::EqualSamples(64).budget(),
            Budget::SamplesPerPixel(64)
        );
        assert_eq!(Regime::seconds(0.5).label(), "0.5s");
        assert_eq!(Regime::EqualSamples(64).label(), "64spp");
        assert!(Regime::seconds(4.0)
            .to_string()
            .starts_with("equal time: 4 s"));
    }

    #[test]
    fn scaling_rounds_samples_down_and_rejects_empty_budgets() {
        assert_eq!(
            Regime::EqualSamples(64).scaled(0.125),
            Some(Regime::EqualSamples(8))
        );
        assert_eq!(Regime::EqualSamples(4).scaled(0.125), None);
        assert_eq!(
            Regime::seconds(4.0).scaled(0.25),
            Some(Regime::seconds(1.0))
        );
        for bad in [0.0, -1.0, 1.5, f64::NAN] {
            assert_eq!(Regime::EqualSamples(64).scaled(bad), None);
        }
    }
}
