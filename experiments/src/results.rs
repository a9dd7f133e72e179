//! What an experiment measured: every [`RunRecord`], queries over seeds, and the summary it
//! writes (`results.md` with a table per scene, `results.csv` with a row per run).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use crate::load::{describe, LoadAverage};
use crate::plan::Plan;
use crate::record::{Measure, RunRecord};
use crate::table::{median, median_range, ratio, Table};
use crate::ExperimentError;

/// The error measures of the standard tables, in column order.
const ERRORS: [Measure; 4] = [Measure::RelMse, Measure::Mse, Measure::RRmse, Measure::Mad];

/// The results of [`crate::Experiment::run`].
#[derive(Clone, Debug, PartialEq)]
pub struct Results {
    /// The plan that ran.
    pub plan: Plan,
    /// The method names, in the order they ran.
    pub methods: Vec<String>,
    /// Each method's baseline for the ratio column (absent: no ratio).
    pub baselines: BTreeMap<String, String>,
    /// The scenes that loaded and ran, in order.
    pub scenes: Vec<String>,
    /// Parameters shared by every method.
    pub parameters: Vec<(String, String)>,
    /// Every final render, in the order they ran.
    pub records: Vec<RunRecord>,
    /// The commit the run was made from.
    pub commit: String,
    /// The machine's load before the first render.
    pub load_before: Option<LoadAverage>,
    /// The machine's load after the last render.
    pub load_after: Option<LoadAverage>,
    /// Wall-clock seconds of the whole experiment.
    pub wall_seconds: f64,
}

impl Results {
    /// The runs of `method` on `scene`, in seed order.
    pub fn runs<'r>(
        &'r self,
        scene: &'r str,
        method: &'r str,
    ) -> impl Iterator<Item = &'r RunRecord> + 'r {
        self.records
            .iter()
            .filter(move |r| r.scene == scene && r.method == method)
    }

    /// The run of `method` on `scene` with `seed`.
    #[must_use]
    pub fn run(&self, scene: &str, method: &str, seed: u64) -> Option<&RunRecord> {
        self.records
            .iter()
            .find(|r| r.scene == scene && r.method == method && r.seed == seed)
    }

    /// `measure` of every run of `method` on `scene`, in seed order.
    #[must_use]
    pub fn values(&self, scene: &str, method: &str, measure: Measure) -> Vec<f64> {
        self.runs(scene, method).map(|r| measure.of(r)).collect()
    }

    /// The median of `measure` over the seeds of `method` on `scene` (NaN for no runs).
    #[must_use]
    pub fn median(&self, scene: &str, method: &str, measure: Measure) -> f64 {
        median(&self.values(scene, method, measure))
    }

    /// The run directory of `scene`.
    #[must_use]
    pub fn scene_dir(&self, scene: &str) -> PathBuf {
        self.plan.out.join(scene)
    }

    /// The standard table of `scene`: per method the median [min, max] over seeds of relMSE,
    /// MSE, rRMSE and MAD, median samples per second, acceptance (when any method reports
    /// it), and relMSE relative to the method's baseline (when there is one).
    #[must_use]
    pub fn scene_table(&self, scene: &str) -> Table {
        let acceptance = self
            .records
            .iter()
            .any(|r| r.scene == scene && r.stats.acceptance.is_some());
        let mut headers: Vec<String> = ERRORS
            .iter()
            .map(|m| format!("{m} median [min, max]"))
            .collect();
        headers.insert(0, "method".into());
        headers.push("samples/s".into());
        if acceptance {
            headers.push("acceptance".into());
        }
        if !self.baselines.is_empty() {
            headers.push("relMSE / baseline".into());
        }
        let mut table = Table::new(headers);
        for method in &self.methods {
            let mut row = vec![method.clone()];
            for m in ERRORS {
                row.push(median_range(m, &self.values(scene, method, m)));
            }
            let rate = self.median(scene, method, Measure::SamplesPerSecond);
            row.push(Measure::SamplesPerSecond.format(rate));
            if acceptance {
                let a = self.median(scene, method, Measure::Acceptance);
                row.push(Measure::Acceptance.format(a));
            }
            if !self.baselines.is_empty() {
                row.push(self.baselines.get(method).map_or("-".into(), |b| {
                    let of = |m: &str| self.median(scene, m, Measure::RelMse);
                    format!("{} ({b})", ratio(of(method), of(b)))
                }));
            }
            table.push_row(row);
        }
        table
    }

    /// `results.md`: a header (regime, seeds, size, threads, commit, machine load, wall time)
    /// and [`Results::scene_table`] per scene.
    #[must_use]
    pub fn markdown(&self) -> String {
        let mut md = self.markdown_header();
        let _ = writeln!(
            md,
            "\nErrors against each scene's reference, median [min, max] over the seeds; samples/s and acceptance are medians; the ratio divides the relMSE medians."
        );
        for scene in &self.scenes {
            let _ = write!(
                md,
                "\n### {scene}\n\n{}",
                self.scene_table(scene).to_markdown()
            );
        }
        md.push_str(&self.markdown_footer());
        md
    }

    /// The title line, the run's description and the shared parameters of `results.md`.
    pub(crate) fn markdown_header(&self) -> String {
        let p = &self.plan;
        let mut md = format!(
            "# {}\n\n{}, seeds {:?}, {}x{} pixels, {} render thread(s){}; runs interleaved (for seed, for scene, for method). Commit {}.\n",
            p.name,
            p.regime,
            p.seeds,
            p.size,
            p.size,
            p.threads,
            if p.quick { ", --quick smoke run" } else { "" },
            self.commit
        );
        if !self.parameters.is_empty() {
            let list: Vec<String> = self
                .parameters
                .iter()
                .map(|(k, v)| format!("{k}: {v}"))
                .collect();
            let _ = writeln!(md, "\n{}.", list.join("; "));
        }
        md
    }

    /// The machine-load and wall-time line that ends `results.md`'s tables.
    pub(crate) fn markdown_footer(&self) -> String {
        let loads: Vec<f64> = self.records.iter().map(|r| Measure::Load.of(r)).collect();
        let (l, l0, l1) = render::metrics::median_min_max(&loads)
            .filter(|s| !s.0.is_nan())
            .unwrap_or((f64::NAN, f64::NAN, f64::NAN));
        format!(
            "\nMachine load (1, 5, 15 min) before: {}; after: {}; 1-minute load before each render: median {l:.2} [min {l0:.2}, max {l1:.2}]. Wall time {:.0} s.\n",
            describe(self.load_before),
            describe(self.load_after),
            self.wall_seconds
        )
    }

    /// `results.csv`: one row per run with its errors, cost, statistics and load.
    #[must_use]
    pub fn csv(&self) -> String {
        let mut csv = String::from(
            "scene,method,seed,budget,seconds,samples,samples_per_second,mse,relmse,rrmse,mad,acceptance,b,b_standard_error,mutations,eta_s,eta_l,eta_0,p_large,load1\n",
        );
        let opt = |v: Option<f64>| v.map_or_else(String::new, |v| v.to_string());
        for r in &self.records {
            let l = r.stats.large_step;
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                quote(&r.scene),
                quote(&r.method),
                r.seed,
                self.plan.regime.label(),
                r.seconds,
                r.samples,
                r.samples_per_second(),
                r.metrics.mse,
                r.metrics.relmse,
                r.metrics.rrmse,
                r.metrics.mad,
                opt(r.stats.acceptance),
                opt(r.stats.b),
                opt(r.stats.b_standard_error),
                r.stats
                    .mutations
                    .map_or_else(String::new, |m| m.to_string()),
                opt(l.map(|l| l.eta_s)),
                opt(l.map(|l| l.eta_l)),
                opt(l.map(|l| l.eta_0)),
                opt(l.map(|l| l.p_large)),
                opt(r.load.map(|l| l.one)),
            );
        }
        csv
    }

    /// Writes `<out>/results.md` ([`Results::markdown`] followed by `extra_markdown`, e.g. an
    /// example's own table) and `<out>/results.csv`, prints the markdown to stdout and
    /// returns the markdown file's path.
    ///
    /// # Errors
    /// [`ExperimentError::Io`] naming the file that cannot be written.
    pub fn write(&self, extra_markdown: &str) -> Result<PathBuf, ExperimentError> {
        self.write_markdown(self.markdown(), extra_markdown)
    }

    /// Writes `md` followed by `extra_markdown` as `results.md`, and `results.csv`; prints
    /// the markdown and returns its path.
    pub(crate) fn write_markdown(
        &self,
        mut md: String,
        extra_markdown: &str,
    ) -> Result<PathBuf, ExperimentError> {
        let out = &self.plan.out;
        std::fs::create_dir_all(out).map_err(ExperimentError::io(out))?;
        if !extra_markdown.is_empty() {
            md.push('\n');
            md.push_str(extra_markdown);
        }
        let md_path = out.join("results.md");
        render::files::write_bytes_atomic(&md_path, &md).map_err(ExperimentError::io(&md_path))?;
        let csv_path = out.join("results.csv");
        render::files::write_bytes_atomic(&csv_path, self.csv())
            .map_err(ExperimentError::io(&csv_path))?;
        println!("{md}");
        eprintln!("wrote {} and {}", md_path.display(), csv_path.display());
        Ok(md_path)
    }
}

/// `field` quoted for CSV when it holds a comma, a quote or a line break.
fn quote(field: &str) -> String {
    if field.contains([',', '"', '\n']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_owned()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use render::metrics::Metrics;

    use super::*;
    use crate::plan::Defaults;
    use crate::regime::Regime;
    use crate::stats::RunStats;

    fn record(method: &str, seed: u64, relmse: f64, acceptance: Option<f64>) -> RunRecord {
        RunRecord {
            scene: "s".into(),
            method: method.into(),
            seed,
            seconds: 2.0,
            samples: 1000 * (seed + 1),
            metrics: Metrics {
                mse: relmse / 10.0,
                rmse: 0.0,
                relmse,
                rrmse: relmse.sqrt(),
                mad: relmse / 2.0,
            },
            stats: RunStats {
                acceptance,
                ..RunStats::default()
            },
            load: None,
            image: PathBuf::new(),
            convergence: Vec::new(),
        }
    }

    /// Two methods, two seeds, one scene; `base` is every method's baseline.
    pub(crate) fn results() -> Results {
        Results {
            plan: Plan::from_defaults(&Defaults::new("t", Regime::EqualSamples(4))),
            methods: vec!["base".into(), "new, better".into()],
            baselines: [
                ("base".to_string(), "base".to_string()),
                ("new, better".to_string(), "base".to_string()),
            ]
            .into(),
            scenes: vec!["s".into()],
            parameters: vec![("max depth".into(), "5".into())],
            records: vec![
                record("base", 0, 0.04, None),
                record("new, better", 0, 0.01, Some(0.5)),
                record("base", 1, 0.02, None),
                record("new, better", 1, 0.03, Some(0.25)),
            ],
            commit: "abc".into(),
            load_before: None,
            load_after: None,
            wall_seconds: 1.0,
        }
    }

    #[test]
    fn scene_table_holds_medians_ranges_and_ratios() {
        let r = results();
        assert_eq!(r.values("s", "base", Measure::RelMse), [0.04, 0.02]);
        assert_eq!(r.run("s", "base", 1).map(|x| x.seed), Some(1));
        let t = r.scene_table("s");
        assert_eq!(t.headers()[0], "method");
        assert_eq!(t.headers().last().unwrap(), "relMSE / baseline");
        assert_eq!(t.rows()[0][1], "0.0300 [0.0200, 0.0400]");
        assert_eq!(t.rows()[0][5], "750");
        assert_eq!(t.rows()[0][6], "-", "no acceptance for the baseline");
        assert_eq!(t.rows()[1][6], "0.375");
        assert_eq!(t.rows()[0][7], "1.00 (base)");
        assert_eq!(t.rows()[1][7], "0.67 (base)");
        let md = r.markdown();
        assert!(md.contains("### s\n\n| method |"), "{md}");
        assert!(md.contains("max depth: 5") && md.contains("Commit abc"));
    }

    #[test]
    fn csv_has_one_row_per_run_and_empty_cells_for_missing_statistics() {
        let csv = results().csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 5);
        assert!(lines[2].starts_with("s,\"new, better\",0,4spp,2,1000,500,"));
        assert_eq!(lines[0].split(',').count(), lines[2].split(',').count() - 1);
        assert!(lines[1].ends_with(",,,,,,,,,"), "{}", lines[1]);
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(quote("PSSMLT/K"), "PSSMLT/K");
        assert_eq!(quote("a, b"), "\"a, b\"");
        assert_eq!(quote("say \"x\""), "\"say \"\"x\"\"\"");
    }
}
