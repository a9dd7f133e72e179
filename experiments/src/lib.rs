//! The paper examples' shared harness: command-line options, equal-time / equal-sample
//! comparisons over seeds and scenes, run directories, tables and the self-contained HTML
//! report (`chainlight report`).
//!
//! A paper example states *which methods* it compares; this package does everything else:
//!
//! | step | item |
//! |---|---|
//! | shared flags (`--quick`, `--time` / `--spp`, `--seeds`, `--size`, `--threads`, `--out`, `--no-report`, scenes) | [`CommonOptions`] (flatten it into your own `clap::Parser`), [`parse`], [`Defaults`], [`Quick`] → [`Plan`] |
//! | a compared configuration | [`Method`]: a name and a [`render::session::RenderSettings`] template (or a closure of the [`RunContext`]) |
//! | the comparison | [`Experiment`]: every seed × scene × method interleaved, under a [`Regime`], each render measured against the scene's reference ([`SceneCase`]) with the machine's [`LoadAverage`] |
//! | per-run statistics | [`run_stats`] → [`RunStats`] (b, its standard error, acceptance, the large-step estimate, mutations, the acceptance counts per component and stage) |
//! | outputs | per scene a [`RunDirectory`] (images per seed, extra images such as stage maps via [`Experiment::extra_image`], `run.json`, `report.html` via [`report`]); `results.md` ([`Results::markdown`], [`Table`]) and `results.csv` ([`Results::csv`]) |
//! | other tables | [`TableSpec`] of [`Column`]s (which [`Measure`]s, ranges or medians, which measure the baseline ratio divides, step cost, acceptance per stage) → [`Results::table`], [`Results::write_with`] |
//! | analyses before or beside the comparison | [`load_bundled`] scenes, [`calibrate`] (a parameter matched to a target acceptance by [`Bisection`]), [`ToyStudy`] (kernels on a toy target: acceptance, IAT, trace and histogram panels) |
//! | plots | the report's convergence plot; [`plot::write_log_log_svg`] for an example's own |
//! | several budgets in one run | [`Ladder`] (an [`Experiment`] per rung) → [`LadderResults`]: error-vs-time curves, a table per scene, one CSV |
//! | an example's own per-run values | [`RunValues`] (filled in [`Experiment::inspect`], looked up and summarised like [`Results`]' measures) |
//! | over seeds | [`Results::images`] (every seed's image read back), [`TemporalVariance`] ([`Results::temporal_variance`]), [`Results::compare`] → [`Comparison`] (medians and seed-by-seed wins) |
//! | per-pixel maps | [`maps`]: upscaled false-colour PNGs of any map of a run ([`maps::write_map_png`], named by [`maps::map_path`]) and relative-error maps ([`Results::write_error_maps`]) |
//! | sampling-pattern figures | [`scatter`]: point sets as dots in panels, [`scatter::cells_hit`] |
//! | beyond one machine | `--emit-jobs DIR` / `--run-one ID` / `--collect` ([`JobMode`], [`Experiment::execute`]): the runs as a job list with a Slurm array script and a Kubernetes Indexed Job ([`sweep`]), run by `chainlight sweep run` or a cluster, collected into the same tables |
//!
//! # How a paper example uses it
//!
//! 1. Declare its [`Defaults`] (scenes, regime, seeds, size, what `--quick` runs) and parse the
//!    shared flags — [`parse::<CommonOptions>`](parse), or its own `Parser` with
//!    `#[command(flatten)] common: CommonOptions` when it has flags of its own — into a
//!    [`Plan`] ([`CommonOptions::plan`]).
//! 2. List its comparison as [`Method`]s: paper presets on one footing, each a name and a
//!    settings template. The harness sets only `width`, `height`, `budget`, `seed` and
//!    `threads`; the integrator and its settings are the method's.
//! 3. Run it: `Experiment::new(plan).methods(methods).baseline("...").run()?` renders, measures,
//!    writes `<out>/<scene>/` with `run.json` and `report.html`, and returns [`Results`];
//!    `execute()?` instead also honours `--emit-jobs`, `--run-one` and `--collect` (it returns
//!    `None` when there is nothing to write).
//! 4. `results.write(&extra)` writes `results.md` (a table per scene: medians over seeds,
//!    ratios to the baseline) with the example's own tables appended, and `results.csv`;
//!    `results.write_with(&[TableSpec..], &extra)` writes chosen tables instead.
//!
//! # Example
//!
//! Two methods, two seeds, equal samples, on the built-in Cornell box at 16 x 16 (the paper
//! examples load the bundled scenes by name from the plan instead of [`Experiment::scenes`]).
//!
//! ```
//! use experiments::{Defaults, Experiment, Measure, Method, Plan, Regime, SceneCase};
//! use render::session::{IntegratorKind, RenderSettings};
//!
//! let out = std::env::temp_dir().join(format!("experiments-doc-{}", std::process::id()));
//! let plan = Plan {
//!     seeds: vec![1, 2],
//!     size: 16,
//!     threads: 1,
//!     out: out.clone(),
//!     ..Plan::from_defaults(&Defaults::new("doc", Regime::EqualSamples(4)))
//! };
//! let method = |name: &str, integrator: IntegratorKind| {
//!     let method = integrator.settings();
//!     Method::new(name, RenderSettings { method, max_depth: 5, ..RenderSettings::default() })
//! };
//! let results = Experiment::new(plan)
//!     .methods([method("PT", IntegratorKind::Pt), method("BDPT", IntegratorKind::Bdpt)])
//!     .baseline("PT")
//!     .scenes(vec![SceneCase::cornell_box(16, 64)?])
//!     .run()?;
//! assert_eq!(results.records.len(), 4);
//! assert!(results.median("cornell-box", "BDPT", Measure::RelMse) > 0.0);
//! assert!(results.scene_table("cornell-box").to_markdown().contains("| BDPT |"));
//! assert!(out.join("cornell-box/run.json").is_file() && out.join("cornell-box/report.html").is_file());
//! # std::fs::remove_dir_all(&out).ok();
//! # Ok::<(), experiments::ExperimentError>(())
//! ```

pub mod calibrate;
pub mod calibration_cache;
mod columns;
mod compare;
mod error;
mod harness;
mod ladder;
mod load;
pub mod maps;
mod method;
mod options;
mod plan;
pub mod plot;
mod record;
mod regime;
pub mod report;
mod results;
mod rundir;
pub mod scatter;
mod scene;
mod stats;
pub mod sweep;
mod table;
mod toy_study;

pub use calibrate::{Bisection, Calibrated, Calibrations};
pub use calibration_cache::{match_acceptance_cached, CacheUse, CalibrationInputs};
pub use columns::{Column, TableSpec};
mod temporal;
#[cfg(test)]
mod test_support;
mod values;

pub use compare::Comparison;
pub use error::ExperimentError;
pub use harness::Experiment;
pub use ladder::{Ladder, LadderDefaults, LadderOptions, LadderResults};
pub use load::LoadAverage;
pub use method::{Method, RunContext};
pub use options::{parse, try_parse_from, CommonOptions};
pub use plan::{Defaults, Plan, Quick};
pub use record::{Measure, RunRecord};
pub use regime::Regime;
pub use results::Results;
pub use rundir::{scene_manifest, RunDirectory};
pub use scene::{bundled_scene_names, load_bundled, SceneCase, SCENES_DIR};
pub use stats::{run_stats, LargeStepStats, RunStats};
pub use sweep::{JobMode, RunId};
pub use table::{median, median_range, ratio, Table};
pub use temporal::TemporalVariance;
pub use toy_study::{ToyRun, ToyStudy};
pub use values::RunValues;
