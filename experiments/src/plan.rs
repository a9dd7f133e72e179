//! What an experiment runs: the example's defaults ([`Defaults`], with a `--quick` smoke
//! preset) and the resolved [`Plan`] (scenes, regime, seeds, size, threads, output).

use std::path::PathBuf;

use crate::regime::Regime;
use crate::sweep::JobMode;

/// An example's defaults for the shared command-line options.
///
/// Every field is what the example runs when the flag is absent; [`Quick`] is what `--quick`
/// runs instead. Build one with struct update syntax from [`Defaults::new`]:
///
/// ```
/// use experiments::{Defaults, Quick, Regime};
///
/// let defaults = Defaults {
///     scenes: vec!["glossy-highlight".into(), "caustic-pool".into()],
///     seeds: 5,
///     quick: Quick { scenes: Some(vec!["cornell".into()]), ..Quick::default() },
///     ..Defaults::new("drmlt", Regime::seconds(4.0))
/// };
/// assert_eq!(defaults.out, std::path::PathBuf::from("out/drmlt"));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Defaults {
    /// The experiment's name: the title prefix of its reports and `out/<name>`.
    pub name: String,
    /// The scenes to run; empty means every bundled scene (`scenes/*.gltf`).
    pub scenes: Vec<String>,
    /// The budget per render.
    pub regime: Regime,
    /// Seeds per method and scene.
    pub seeds: u32,
    /// The first seed (seeds are consecutive).
    pub first_seed: u64,
    /// Image side in pixels (square images; it must divide the references' 256).
    pub size: u32,
    /// Render threads; `None` is every core.
    pub threads: Option<usize>,
    /// Output directory.
    pub out: PathBuf,
    /// What `--quick` runs.
    pub quick: Quick,
}

impl Defaults {
    /// Every bundled scene, `regime`, 3 seeds from 0, 64 x 64, every core, `out/<name>`, and
    /// the default [`Quick`] preset.
    #[must_use]
    pub fn new(name: impl Into<String>, regime: Regime) -> Self {
        let name = name.into();
        Self {
            out: PathBuf::from("out").join(&name),
            name,
            scenes: Vec::new(),
            regime,
            seeds: 3,
            first_seed: 0,
            size: 64,
            threads: None,
            quick: Quick::default(),
        }
    }
}

/// The `--quick` smoke run: small images, short budgets, few seeds and scenes. Flags given
/// explicitly still win over it.
#[derive(Clone, Debug, PartialEq)]
pub struct Quick {
    /// Scenes instead of the default list (`None`: the default list).
    pub scenes: Option<Vec<String>>,
    /// The budget per render.
    pub regime: Regime,
    /// Seeds per method and scene.
    pub seeds: u32,
    /// Image side in pixels.
    pub size: u32,
}

impl Default for Quick {
    /// Two scenes (cornell, cornell-glass), 8 samples per pixel, 2 seeds, 16 x 16.
    fn default() -> Self {
        Self {
            scenes: Some(vec!["cornell".into(), "cornell-glass".into()]),
            regime: Regime::EqualSamples(8),
            seeds: 2,
            size: 16,
        }
    }
}

/// A resolved experiment: what [`crate::Experiment`] runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The experiment's name (title prefix of its reports).
    pub name: String,
    /// The scenes, in order.
    pub scenes: Vec<String>,
    /// The budget per render.
    pub regime: Regime,
    /// The seeds, in order.
    pub seeds: Vec<u64>,
    /// Image side in pixels.
    pub size: u32,
    /// Render threads.
    pub threads: usize,
    /// Output directory: `results.md`, `results.csv` and one run directory per scene.
    pub out: PathBuf,
    /// Write `report.html` per scene and run the extra renders of its convergence plot.
    pub report: bool,
    /// Whether this is a `--quick` smoke run.
    pub quick: bool,
    /// Run here, or as a job list ([`crate::Experiment::execute`]).
    pub jobs: JobMode,
}

impl Plan {
    /// The plan of `defaults` without any flag.
    #[must_use]
    pub fn from_defaults(defaults: &Defaults) -> Self {
        Self {
            name: defaults.name.clone(),
            scenes: defaults.scenes.clone(),
            regime: defaults.regime,
            seeds: seed_list(defaults.first_seed, defaults.seeds),
            size: defaults.size,
            threads: defaults.threads.unwrap_or_else(all_cores),
            out: defaults.out.clone(),
            report: true,
            quick: false,
            jobs: JobMode::Local,
        }
    }
}

/// `count` consecutive seeds from `first`.
pub(crate) fn seed_list(first: u64, count: u32) -> Vec<u64> {
    (0..u64::from(count)).map(|i| first + i).collect()
}

/// The number of cores (1 if unknown).
pub(crate) fn all_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_from_defaults() {
        let d = Defaults {
            first_seed: 100,
            threads: Some(2),
            ..Defaults::new("zsolnai", Regime::EqualSamples(64))
        };
        let p = Plan::from_defaults(&d);
        assert_eq!(p.seeds, vec![100, 101, 102]);
        assert_eq!((p.size, p.threads, p.report), (64, 2, true));
        assert_eq!(p.out, PathBuf::from("out/zsolnai"));
    }
}
