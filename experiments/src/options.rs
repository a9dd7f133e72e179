//! The command-line options every paper example shares (clap derive; flatten
//! [`CommonOptions`] into an example's own `Parser` to add flags), resolved against the
//! example's [`Defaults`] into a [`Plan`].

use std::ffi::OsString;
use std::path::PathBuf;

use clap::Parser;

use crate::plan::{all_cores, seed_list, Defaults, Plan};
use crate::regime::Regime;
use crate::scene::bundled_scene_names;
use crate::sweep::{JobMode, RunId};
use crate::ExperimentError;

/// Longest accepted `--time`, in seconds (a day).
const MAX_SECONDS: f64 = 86_400.0;

/// The options every paper example accepts. Absent flags take the example's [`Defaults`];
/// `--quick` takes its [`crate::Quick`] preset, and explicit flags win over both.
///
/// An example with flags of its own flattens this struct:
///
/// ```
/// use clap::Parser;
/// use experiments::{CommonOptions, Defaults, Regime};
///
/// #[derive(Parser)]
/// struct Args {
///     #[command(flatten)]
///     common: CommonOptions,
///     /// Skip the 1-D toy.
///     #[arg(long)]
///     no_toy: bool,
/// }
///
/// let defaults = Defaults::new("drmlt", Regime::seconds(4.0));
/// let args: Args =
///     experiments::try_parse_from(&defaults, ["drmlt", "--no-toy", "--spp", "16", "cornell"])?;
/// let plan = args.common.plan(&defaults)?;
/// assert!(args.no_toy);
/// assert_eq!(plan.regime, Regime::EqualSamples(16));
/// assert_eq!(plan.scenes, ["cornell"]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Parser)]
#[command(
    about = "A chainlight paper example: compares methods over seeds on the bundled scenes.",
    long_about = None
)]
pub struct CommonOptions {
    /// Smoke run: small images, short budgets, few seeds and scenes (explicit flags win).
    #[arg(long)]
    pub quick: bool,
    /// Equal time: seconds per render, bootstrap included.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, conflicts_with = "spp")]
    pub time: Option<f64>,
    /// Equal samples: samples (MCMC: mutations) per pixel per render.
    #[arg(long, visible_alias = "mpp", value_name = "N",
          value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub spp: Option<u32>,
    /// Seeds per method and scene.
    #[arg(long, visible_alias = "runs", value_name = "N",
          value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub seeds: Option<u32>,
    /// The first seed; the others follow it.
    #[arg(long, value_name = "SEED")]
    pub first_seed: Option<u64>,
    /// Image side in pixels (it must divide the references' 256).
    #[arg(long, value_name = "PIXELS", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub size: Option<u32>,
    /// Render threads per render.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Output directory: results.md, results.csv and one run directory per scene.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// No report.html, and none of the extra renders its convergence plot needs.
    #[arg(long)]
    pub no_report: bool,
    /// Render nothing: write the runs as a job list (jobs.jsonl, sweep.json, slurm.sbatch,
    /// k8s-job.json) into DIR, one run per scene and seed (see docs/cluster.md).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["run_one", "collect"])]
    pub emit_jobs: Option<PathBuf>,
    /// Render one run of the job list, SCENE/seedN (every method on that scene with that
    /// seed), and record it in the scene's run directory.
    #[arg(long, value_name = "ID", value_parser = parse_run_id, conflicts_with = "collect")]
    pub run_one: Option<RunId>,
    /// Render nothing: read the job list's recorded runs and write the results and reports.
    #[arg(long)]
    pub collect: bool,
    /// Scenes to run (bundled: scenes/NAME.gltf); `all` is every bundled scene.
    #[arg(value_name = "SCENE")]
    pub scenes: Vec<String>,
}

impl CommonOptions {
    /// The plan these options select: explicit flags, else `--quick`'s preset, else
    /// `defaults`.
    ///
    /// # Errors
    /// [`ExperimentError::Invalid`] when no scene is selected (the default list is "every
    /// bundled scene" and `scenes/` is not in the working directory).
    pub fn plan(&self, defaults: &Defaults) -> Result<Plan, ExperimentError> {
        let quick = self.quick.then_some(&defaults.quick);
        let regime = match (self.time, self.spp) {
            (Some(t), _) => Regime::seconds(t),
            (None, Some(n)) => Regime::EqualSamples(n),
            (None, None) => quick.map_or(defaults.regime, |q| q.regime),
        };
        let mut scenes = if self.scenes.is_empty() {
            quick
                .and_then(|q| q.scenes.clone())
                .unwrap_or_else(|| defaults.scenes.clone())
        } else {
            self.scenes.clone()
        };
        if scenes.is_empty() || scenes.iter().any(|s| s == "all") {
            scenes = bundled_scene_names();
        }
        if scenes.is_empty() {
            return Err(ExperimentError::Invalid(
                "no scenes: scenes/*.gltf not found (run from the repository root) and none named"
                    .into(),
            ));
        }
        let seeds = self
            .seeds
            .unwrap_or_else(|| quick.map_or(defaults.seeds, |q| q.seeds));
        let seeds = seed_list(self.first_seed.unwrap_or(defaults.first_seed), seeds);
        let jobs = match (&self.emit_jobs, &self.run_one, self.collect) {
            (Some(dir), ..) => JobMode::Emit(dir.clone()),
            (None, Some(id), _) => {
                if !scenes.contains(&id.scene) || !seeds.contains(&id.seed) {
                    return Err(ExperimentError::Invalid(format!(
                        "--run-one {id}: not a run of this sweep (scenes {scenes:?}, seeds {seeds:?})"
                    )));
                }
                // The run's scene alone: an example's per-scene work before the comparison
                // (a calibration, say) then runs for it only.
                scenes = vec![id.scene.clone()];
                JobMode::RunOne(id.clone())
            }
            (None, None, true) => JobMode::Collect,
            (None, None, false) => JobMode::Local,
        };
        Ok(Plan {
            name: defaults.name.clone(),
            scenes,
            regime,
            seeds,
            size: self
                .size
                .unwrap_or_else(|| quick.map_or(defaults.size, |q| q.size)),
            threads: self
                .threads
                .map(|t| t as usize)
                .or(defaults.threads)
                .unwrap_or_else(all_cores),
            out: self.out.clone().unwrap_or_else(|| defaults.out.clone()),
            report: !self.no_report,
            quick: self.quick,
            jobs,
        })
    }
}

/// Parses the process's arguments into `T` (an example's `Parser`, or [`CommonOptions`]
/// itself), with the example's defaults in the help text. Exits with clap's usage message and
/// code 2 on bad flags, as clap does.
#[must_use]
pub fn parse<T: Parser>(defaults: &Defaults) -> T {
    try_parse_from(defaults, std::env::args_os()).unwrap_or_else(|e| e.exit())
}

/// [`parse`] from the given arguments (the first is the program name).
///
/// # Errors
/// clap's error for a bad flag, a value out of range or `--help`.
pub fn try_parse_from<T, I, S>(defaults: &Defaults, args: I) -> Result<T, clap::Error>
where
    T: Parser,
    I: IntoIterator<Item = S>,
    S: Into<OsString> + Clone,
{
    let mut matches = with_defaults(T::command(), defaults).try_get_matches_from(args)?;
    T::from_arg_matches_mut(&mut matches)
}

/// `command` named after the experiment, its shared options' help ending with the example's
/// default and `--quick` value.
fn with_defaults(command: clap::Command, d: &Defaults) -> clap::Command {
    let q = &d.quick;
    // Each regime flag names its own default, or points at the other one.
    let regime_note = |regime: Regime, quick: Regime, time: bool| {
        let value = |r: Regime| match (r, time) {
            (Regime::EqualTime(t), true) => Some(t.as_secs_f64().to_string()),
            (Regime::EqualSamples(n), false) => Some(n.to_string()),
            _ => None,
        };
        let other = if time {
            "equal samples, see --spp"
        } else {
            "equal time, see --time"
        };
        let default = value(regime).unwrap_or_else(|| other.to_owned());
        match value(quick) {
            Some(v) => format!("[default: {default}; --quick: {v}]"),
            None => format!("[default: {default}]"),
        }
    };
    let scenes = if d.scenes.is_empty() {
        "every bundled scene".to_owned()
    } else {
        d.scenes.join(" ")
    };
    let notes = [
        ("time", regime_note(d.regime, q.regime, true)),
        ("spp", regime_note(d.regime, q.regime, false)),
        (
            "seeds",
            format!("[default: {}; --quick: {}]", d.seeds, q.seeds),
        ),
        ("first_seed", format!("[default: {}]", d.first_seed)),
        (
            "size",
            format!("[default: {}; --quick: {}]", d.size, q.size),
        ),
        (
            "threads",
            format!(
                "[default: {}]",
                d.threads.map_or("every core".into(), |t| t.to_string())
            ),
        ),
        ("out", format!("[default: {}]", d.out.display())),
        (
            "scenes",
            format!(
                "[default: {scenes}; --quick: {}]",
                q.scenes.as_ref().map_or(scenes.clone(), |s| s.join(" "))
            ),
        ),
    ];
    let mut command = command.bin_name(d.name.clone());
    let present: Vec<String> = command
        .get_arguments()
        .map(|a| a.get_id().to_string())
        .collect();
    for (id, note) in notes {
        if present.iter().any(|p| p == id) {
            command = command.mut_arg(id, |a| {
                let help = a.get_help().map_or_else(String::new, ToString::to_string);
                a.help(format!("{help} {note}"))
            });
        }
    }
    command
}

/// A run id, `SCENE/seedN`.
fn parse_run_id(text: &str) -> Result<RunId, String> {
    text.parse()
}

/// Seconds in `(0, 86400]`.
pub(crate) fn parse_seconds(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|t| *t > 0.0 && *t <= MAX_SECONDS)
        .ok_or_else(|| format!("expected seconds in (0, {MAX_SECONDS}], got {text:?}"))
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::plan::Quick;

    fn defaults() -> Defaults {
        Defaults {
            scenes: vec!["a".into(), "b".into()],
            first_seed: 100,
            quick: Quick {
                scenes: Some(vec!["q".into()]),
                regime: Regime::EqualSamples(4),
                seeds: 1,
                size: 8,
            },
            ..Defaults::new("test", Regime::seconds(2.0))
        }
    }

    fn plan(args: &[&str]) -> Result<Plan, String> {
        let d = defaults();
        let argv = std::iter::once("test").chain(args.iter().copied());
        try_parse_from::<CommonOptions, _, _>(&d, argv)
            .map_err(|e| e.to_string())?
            .plan(&d)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn defaults_apply_without_flags() {
        let p = plan(&[]).unwrap();
        assert_eq!(p.scenes, ["a", "b"]);
        assert_eq!(p.regime, Regime::EqualTime(Duration::from_secs(2)));
        assert_eq!((p.seeds, p.size), (vec![100, 101, 102], 64));
        assert_eq!(p.out, PathBuf::from("out/test"));
        assert!(p.report && !p.quick);
    }

    #[test]
    fn quick_preset_and_explicit_flags_win_over_it() {
        let p = plan(&["--quick"]).unwrap();
        assert_eq!(p.scenes, ["q"]);
        assert_eq!(
            (p.regime, p.seeds.len(), p.size),
            (Regime::EqualSamples(4), 1, 8)
        );
        let p = plan(&["--size", "32", "--quick", "--time", "0.5", "c"]).unwrap();
        assert_eq!((p.size, p.scenes.clone()), (32, vec!["c".to_owned()]));
        assert_eq!(p.regime, Regime::seconds(0.5));
    }

    #[test]
    fn aliases_of_the_older_examples_still_parse() {
        let p = plan(&[
            "--mpp",
            "64",
            "--runs",
            "3",
            "--first-seed",
            "7",
            "--no-report",
        ])
        .unwrap();
        assert_eq!(p.regime, Regime::EqualSamples(64));
        assert_eq!(p.seeds, vec![7, 8, 9]);
        assert!(!p.report);
        let p = plan(&["--threads", "2", "--out", "x/y"]).unwrap();
        assert_eq!((p.threads, p.out), (2, PathBuf::from("x/y")));
    }

    #[test]
    fn bad_values_are_usage_errors_naming_the_flag() {
        for (args, flag) in [
            (&["--time", "0"][..], "--time"),
            (&["--time", "inf"][..], "--time"),
            (&["--spp", "0"][..], "--spp"),
            (&["--seeds", "x"][..], "--seeds"),
            (&["--size", "5000"][..], "--size"),
            (&["--time", "1", "--spp", "4"][..], "--spp"),
            (&["--bogus"][..], "--bogus"),
        ] {
            let e = plan(args).unwrap_err();
            assert!(e.contains(flag), "{args:?}: {e}");
        }
    }

    #[test]
    fn job_flags_select_the_job_mode() {
        assert_eq!(plan(&[]).unwrap().jobs, JobMode::Local);
        let emit = plan(&["--emit-jobs", "d", "--spp", "4"]).unwrap();
        assert_eq!(emit.jobs, JobMode::Emit("d".into()));
        let p = plan(&["--run-one", "b/seed101"]).unwrap();
        assert_eq!(p.jobs, JobMode::RunOne(RunId::new("b", 101)));
        assert_eq!(
            (p.scenes, p.seeds),
            (vec!["b".to_owned()], vec![100, 101, 102])
        );
        assert_eq!(plan(&["--collect"]).unwrap().jobs, JobMode::Collect);
        // Negative controls: runs outside the sweep, malformed ids and two modes at once.
        for (args, needle) in [
            (&["--run-one", "c/seed100"][..], "not a run of this sweep"),
            (&["--run-one", "a/seed99"][..], "not a run of this sweep"),
            (&["--run-one", "a"][..], "SCENE/seedN"),
            (
                &["--collect", "--emit-jobs", "d"][..],
                "cannot be used with",
            ),
            (
                &["--run-one", "a/seed100", "--collect"][..],
                "cannot be used with",
            ),
        ] {
            let e = plan(args).unwrap_err();
            assert!(e.contains(needle), "{args:?}: {e}");
        }
    }

    #[test]
    fn help_shows_the_examples_defaults() {
        let d = defaults();
        let e = try_parse_from::<CommonOptions, _, _>(&d, ["test", "--help"]).unwrap_err();
        let help = e.to_string();
        assert!(help.contains("[default: 2]"), "{help}");
        assert!(
            help.contains("[default: equal time, see --time; --quick: 4]"),
            "{help}"
        );
        assert!(help.contains("[default: a b; --quick: q]"), "{help}");
        assert!(help.contains("out/test"), "{help}");
    }
}
