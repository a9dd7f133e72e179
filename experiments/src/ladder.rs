//! A budget ladder: the same experiment at several budgets in one run (one [`Experiment`] per
//! rung), summarised as error against time ([`LadderResults::curves`] for
//! [`crate::plot::write_log_log_svg`], [`LadderResults::table`], [`LadderResults::csv`]), and
//! its command-line flags ([`LadderOptions`], with an example's [`LadderDefaults`]).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::harness::Experiment;
use crate::options::parse_seconds;
use crate::plan::{seed_list, Plan};
use crate::plot::{write_log_log_svg, Axes, Curve};
use crate::record::Measure;
use crate::regime::Regime;
use crate::results::Results;
use crate::table::{median, median_range, Table};
use crate::ExperimentError;

/// Several budgets of one experiment: each rung runs the plan with its regime, its run
/// directories under `<plan.out>/<regime label>/` (e.g. `ladder/4s/<scene>/`).
///
/// The rungs run in order, each interleaved as [`Experiment`] is (for seed, for scene, for
/// method).
///
/// # Example
/// ```no_run
/// use experiments::{Defaults, Experiment, Ladder, Measure, Plan, Regime};
///
/// # fn methods() -> Vec<experiments::Method> { Vec::new() }
/// let plan = Plan::from_defaults(&Defaults::new("ladder", Regime::seconds(1.0)));
/// let ladder = Ladder::new(plan, [1.0, 4.0, 15.0].map(Regime::seconds))
///     .run(|plan| Experiment::new(plan).methods(methods()))?;
/// println!("{}", ladder.table("cornell", Measure::RRmse).to_markdown());
/// # Ok::<(), experiments::ExperimentError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Ladder {
    plan: Plan,
    regimes: Vec<Regime>,
}

impl Ladder {
    /// The ladder of `plan` over `regimes` (the plan's own regime is not a rung).
    #[must_use]
    pub fn new(plan: Plan, regimes: impl IntoIterator<Item = Regime>) -> Self {
        Self {
            plan,
            regimes: regimes.into_iter().collect(),
        }
    }

    /// The plan of each rung: the ladder's plan with the rung's regime and output
    /// `<plan.out>/<regime label>`.
    #[must_use]
    pub fn plans(&self) -> Vec<Plan> {
        self.regimes
            .iter()
            .map(|&regime| Plan {
                regime,
                out: self.plan.out.join(regime.label()),
                ..self.plan.clone()
            })
            .collect()
    }

    /// Runs `experiment(plan)` for every rung's plan, in order.
    ///
    /// # Errors
    /// [`ExperimentError::Invalid`] for no rungs or two rungs with the same label; the first
    /// rung's error.
    pub fn run<'a>(
        &self,
        mut experiment: impl FnMut(Plan) -> Experiment<'a>,
    ) -> Result<LadderResults, ExperimentError> {
        let plans = self.plans();
        if plans.is_empty() {
            return Err(ExperimentError::Invalid("a ladder without rungs".into()));
        }
        for (i, p) in plans.iter().enumerate() {
            if plans[..i].iter().any(|q| q.out == p.out) {
                return Err(ExperimentError::Invalid(format!(
                    "the ladder has the rung {} twice",
                    p.regime.label()
                )));
            }
        }
        let rungs = plans
            .into_iter()
            .map(|plan| {
                eprintln!("ladder rung: {}", plan.regime);
                experiment(plan).run()
            })
            .collect::<Result<_, _>>()?;
        Ok(LadderResults { rungs })
    }
}

/// The ladder flags of an example with an error-vs-time ladder (flatten them into its
/// `clap::Parser` beside [`crate::CommonOptions`]); absent flags take its [`LadderDefaults`].
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
#[command(
    about = "A chainlight paper example: compares methods over seeds on the bundled scenes.",
    long_about = None
)]
pub struct LadderOptions {
    /// Ladder budgets in seconds per render, comma-separated (default: the example's).
    #[arg(long, value_delimiter = ',', value_name = "SECONDS", value_parser = parse_seconds)]
    pub ladder: Option<Vec<f64>>,
    /// Seeds per ladder rung; 0 skips the ladder (default: the example's).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=1000))]
    pub ladder_seeds: Option<u32>,
    /// The ladder's scene (default: the example's).
    #[arg(long, value_name = "SCENE")]
    pub ladder_scene: Option<String>,
}

/// An example's ladder when its flags are absent: the rungs, seeds and scene, and what
/// `--quick` runs instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LadderDefaults {
    /// The scene.
    pub scene: &'static str,
    /// Seconds per render of each rung.
    pub seconds: &'static [f64],
    /// Seeds per rung.
    pub seeds: u32,
    /// The first seed (seeds are consecutive).
    pub first_seed: u64,
    /// Seconds per render of each rung under `--quick`.
    pub quick_seconds: &'static [f64],
    /// Seeds per rung under `--quick`.
    pub quick_seeds: u32,
}

impl LadderOptions {
    /// The ladder these flags select beside `plan`: equal-time rungs (the flag's, else the
    /// defaults', `--quick`'s under a quick plan) on one scene, output `<plan.out>/ladder`,
    /// the plan's size and threads. `None` with 0 seeds or under an equal-samples plan (a
    /// ladder of time budgets compares nothing there).
    #[must_use]
    pub fn ladder(&self, plan: &Plan, defaults: &LadderDefaults) -> Option<Ladder> {
        let quick = plan.quick;
        let seeds = self.ladder_seeds.unwrap_or(if quick {
            defaults.quick_seeds
        } else {
            defaults.seeds
        });
        if seeds == 0 || !matches!(plan.regime, Regime::EqualTime(_)) {
            return None;
        }
        let seconds = self.ladder.clone().unwrap_or_else(|| {
            if quick {
                defaults.quick_seconds.to_vec()
            } else {
                defaults.seconds.to_vec()
            }
        });
        let scene = self.ladder_scene.as_deref().unwrap_or(defaults.scene);
        let plan = Plan {
            scenes: vec![scene.to_owned()],
            seeds: seed_list(defaults.first_seed, seeds),
            out: plan.out.join("ladder"),
            ..plan.clone()
        };
        Some(Ladder::new(plan, seconds.into_iter().map(Regime::seconds)))
    }
}

/// The results of every rung of a [`Ladder`], in rung order.
#[derive(Clone, Debug, PartialEq)]
pub struct LadderResults {
    /// One [`Results`] per rung.
    pub rungs: Vec<Results>,
}

impl LadderResults {
    /// The methods of the first rung, in order.
    fn methods(&self) -> &[String] {
        self.rungs.first().map_or(&[], |r| &r.methods)
    }

    /// Per method, one series per seed of `(seconds, measure)` over the rungs: the curves of
    /// an error-vs-time plot ([`crate::plot::write_log_log_svg`] draws each seed thin and the
    /// median thick).
    #[must_use]
    pub fn curves(&self, scene: &str, measure: Measure) -> Vec<Curve> {
        let seeds = self.rungs.first().map_or(&[][..], |r| &r.plan.seeds);
        self.methods()
            .iter()
            .map(|method| Curve {
                name: method.clone(),
                series: seeds
                    .iter()
                    .map(|&seed| {
                        self.rungs
                            .iter()
                            .filter_map(|r| r.run(scene, method, seed))
                            .map(|run| (run.seconds, measure.of(run)))
                            .collect()
                    })
                    .collect(),
            })
            .collect()
    }

    /// `measure` per method (rows) and rung (columns): median [min, max] over the seeds,
    /// with the median seconds of the rung's renders in the heading.
    #[must_use]
    pub fn table(&self, scene: &str, measure: Measure) -> Table {
        let mut headers = vec![format!("{measure} median [min, max]")];
        for r in &self.rungs {
            let seconds: Vec<f64> = r
                .records
                .iter()
                .filter(|x| x.scene == scene)
                .map(|x| x.seconds)
                .collect();
            headers.push(format!(
                "{} ({:.2} s)",
                r.plan.regime.label(),
                median(&seconds)
            ));
        }
        let mut table = Table::new(headers);
        for method in self.methods() {
            let mut row = vec![method.clone()];
            row.extend(
                self.rungs
                    .iter()
                    .map(|r| median_range(measure, &r.values(scene, method, measure))),
            );
            table.push_row(row);
        }
        table
    }

    /// Every rung's `results.csv` rows under one header (the `budget` column tells the rungs
    /// apart).
    #[must_use]
    pub fn csv(&self) -> String {
        let mut csv = String::new();
        for (i, r) in self.rungs.iter().enumerate() {
            let text = r.csv();
            let mut lines = text.lines();
            if let Some(header) = lines.next() {
                if i == 0 {
                    let _ = writeln!(csv, "{header}");
                }
            }
            for line in lines {
                let _ = writeln!(csv, "{line}");
            }
        }
        csv
    }
    /// Writes `<dir>/ladder.csv` ([`LadderResults::csv`]) and per scene the log-log plot of
    /// `measure` against time ([`LadderResults::curves`]): `<dir>/convergence.svg` for a
    /// ladder of one scene, `<dir>/convergence_<scene>.svg` otherwise. Returns markdown: per
    /// scene a heading and [`LadderResults::table`].
    ///
    /// # Errors
    /// [`ExperimentError::Io`] naming a file that cannot be written.
    pub fn write(&self, dir: &Path, measure: Measure) -> Result<String, ExperimentError> {
        std::fs::create_dir_all(dir).map_err(ExperimentError::io(dir))?;
        let csv = dir.join("ladder.csv");
        render::files::write_bytes_atomic(&csv, self.csv()).map_err(ExperimentError::io(&csv))?;
        let Some(first) = self.rungs.first() else {
            return Ok(String::new());
        };
        let mut md = String::new();
        for scene in &first.scenes {
            let path: PathBuf = if first.scenes.len() == 1 {
                dir.join("convergence.svg")
            } else {
                dir.join(format!("convergence_{scene}.svg"))
            };
            let caption = format!("{measure} vs render time, {scene} (log-log)");
            let y_label = measure.label();
            let axes = Axes {
                caption: &caption,
                x_label: "time [s]",
                y_label,
            };
            if write_log_log_svg(&path, axes, &self.curves(scene, measure))? {
                eprintln!("wrote {}", path.display());
            }
            let _ = write!(
                md,
                "\n## {measure} vs time: {scene} ({} seeds from {}, `{}`)\n\n{}",
                first.plan.seeds.len(),
                first.plan.seeds.first().copied().unwrap_or_default(),
                path.file_name()
                    .map_or_else(String::new, |f| f.to_string_lossy().into_owned()),
                self.table(scene, measure).to_markdown()
            );
        }
        Ok(md)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{tiny_methods, tiny_plan, tiny_scene};

    #[test]
    fn every_rung_runs_into_its_own_directory() {
        let plan = tiny_plan("ladder");
        let out = plan.out.clone();
        let ladder = Ladder::new(plan, [Regime::EqualSamples(1), Regime::EqualSamples(4)]);
        let results = ladder
            .run(|plan| {
                Experiment::new(plan)
                    .methods(tiny_methods())
                    .scenes(vec![tiny_scene()])
            })
            .unwrap();
        assert_eq!(results.rungs.len(), 2);
        assert!(out.join("1spp/cornell-box/PT_seed1.exr").is_file());
        assert!(out.join("4spp/cornell-box/BDPT_seed3.exr").is_file());
        let curves = results.curves("cornell-box", Measure::RelMse);
        assert_eq!(curves.len(), 2);
        assert_eq!(curves[1].name, "BDPT");
        assert_eq!(curves[0].series.len(), 3, "one series per seed");
        assert!(
            curves[0].series.iter().all(|s| s.len() == 2),
            "one point per rung"
        );
        let t = results.table("cornell-box", Measure::RelMse);
        assert_eq!(t.headers().len(), 3);
        assert!(t.headers()[2].starts_with("4spp ("), "{:?}", t.headers());
        assert_eq!(t.rows().len(), 2);
        let csv = results.csv();
        assert_eq!(csv.lines().count(), 1 + 2 * 2 * 3, "{csv}");
        assert_eq!(csv.matches("scene,method").count(), 1);
        assert!(csv.contains(",1spp,") && csv.contains(",4spp,"));
        // Negative control: another scene has no points.
        let other = results.curves("other", Measure::RelMse);
        assert!(other[0].series.iter().all(Vec::is_empty));
        let md = results.write(&out, Measure::RelMse).unwrap();
        assert!(
            md.contains("## relMSE vs time: cornell-box (3 seeds from 1"),
            "{md}"
        );
        assert!(out.join("ladder.csv").is_file() && out.join("convergence.svg").is_file());
    }

    #[derive(clap::Parser)]
    struct Args {
        #[command(flatten)]
        ladder: LadderOptions,
    }

    const DEFAULTS: LadderDefaults = LadderDefaults {
        scene: "glossy-diffuse",
        seconds: &[1.0, 4.0],
        seeds: 3,
        first_seed: 1000,
        quick_seconds: &[0.25],
        quick_seeds: 1,
    };

    fn options(args: &[&str]) -> LadderOptions {
        use clap::Parser as _;
        Args::try_parse_from(std::iter::once("t").chain(args.iter().copied()))
            .unwrap()
            .ladder
    }

    #[test]
    fn flags_win_over_defaults_and_quick() {
        let mut plan = tiny_plan("ladder-flags");
        plan.regime = Regime::seconds(2.0);
        let l = LadderOptions::default().ladder(&plan, &DEFAULTS).unwrap();
        let plans = l.plans();
        assert_eq!(plans.len(), 2);
        assert_eq!(plans[1].regime, Regime::seconds(4.0));
        assert_eq!(plans[0].seeds, [1000, 1001, 1002]);
        assert_eq!(plans[0].scenes, ["glossy-diffuse"]);
        assert_eq!(plans[0].out, plan.out.join("ladder").join("1s"));
        plan.quick = true;
        let quick = LadderOptions::default().ladder(&plan, &DEFAULTS).unwrap();
        assert_eq!(quick.plans()[0].seeds, [1000]);
        let o = options(&[
            "--ladder",
            "0.5,2",
            "--ladder-seeds",
            "2",
            "--ladder-scene",
            "dof",
        ]);
        let plans = o.ladder(&plan, &DEFAULTS).unwrap().plans();
        assert_eq!(plans[1].regime, Regime::seconds(2.0));
        assert_eq!(
            (plans[0].seeds.len(), plans[0].scenes[0].as_str()),
            (2, "dof")
        );
        // Negative controls: 0 seeds, an equal-samples plan and bad seconds give no ladder.
        assert!(options(&["--ladder-seeds", "0"])
            .ladder(&plan, &DEFAULTS)
            .is_none());
        plan.regime = Regime::EqualSamples(4);
        assert!(LadderOptions::default().ladder(&plan, &DEFAULTS).is_none());
        use clap::Parser as _;
        assert!(Args::try_parse_from(["t", "--ladder", "1,0"]).is_err());
        assert!(Args::try_parse_from(["t", "--ladder", "x"]).is_err());
        // The help's about text is the examples', not this struct's documentation.
        let help = Args::try_parse_from(["t", "--help"])
            .err()
            .unwrap()
            .to_string();
        assert!(help.starts_with("A chainlight paper example"), "{help}");
    }

    #[test]
    fn empty_and_repeated_rungs_are_refused() {
        let never = |_: Plan| -> Experiment<'static> { panic!("no rung may run") };
        let plan = tiny_plan("ladder-bad");
        assert!(Ladder::new(plan.clone(), []).run(never).is_err());
        let twice = Ladder::new(plan, [Regime::EqualSamples(2), Regime::EqualSamples(2)]);
        assert_eq!(twice.plans().len(), 2);
        let e = twice.run(never).unwrap_err();
        assert!(e.to_string().contains("2spp"), "{e}");
    }
}
