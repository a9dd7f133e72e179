//! Configurable results tables ([`TableSpec`]): which methods a table lists, which measures
//! its columns show and how each is summarised over seeds, and which measure the ratio to the
//! baseline divides.

use std::path::PathBuf;

use crate::record::Measure;
use crate::results::Results;
use crate::table::{median_range, ratio, Table};
use crate::ExperimentError;

/// How a [`Column`] summarises its measure over a method's seeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Summary {
    /// `median [min, max]`.
    Range,
    /// The median.
    Median,
    /// The method's median divided by its baseline's.
    Ratio,
    /// The baseline's median divided by the method's.
    InverseRatio,
}

/// One column of a [`TableSpec`]: a [`Measure`] and how it is summarised over seeds.
///
/// Ratios divide medians over seeds and name the baseline in the cell (`0.67 (PSSMLT/K)`);
/// a method without a baseline shows `-`, and a table of an experiment without baselines
/// leaves its ratio columns out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Column {
    measure: Measure,
    summary: Summary,
    heading: Option<String>,
    if_reported: bool,
}

impl Column {
    fn of(measure: Measure, summary: Summary) -> Self {
        Self {
            measure,
            summary,
            heading: None,
            if_reported: false,
        }
    }

    /// `median [min, max]` over seeds (headed `relMSE median [min, max]`).
    #[must_use]
    pub fn range(measure: Measure) -> Self {
        Self::of(measure, Summary::Range)
    }

    /// The median over seeds (headed by the measure's label).
    #[must_use]
    pub fn median(measure: Measure) -> Self {
        Self::of(measure, Summary::Median)
    }

    /// The method's median over the baseline's (headed `MSE / baseline`): the ratio the
    /// comparison is about (an error measure: below 1 is better).
    #[must_use]
    pub fn ratio(measure: Measure) -> Self {
        Self::of(measure, Summary::Ratio)
    }

    /// The baseline's median over the method's (headed `baseline samples/s / samples/s`),
    /// for a rate whose inverse is the quantity of interest.
    #[must_use]
    pub fn inverse_ratio(measure: Measure) -> Self {
        Self::of(measure, Summary::InverseRatio)
    }

    /// The cost of one sample (MCMC: one step) relative to the baseline's: the baseline's
    /// samples per second over the method's ([`Column::inverse_ratio`] of
    /// [`Measure::SamplesPerSecond`], headed `step cost vs baseline`). Under equal time, a
    /// method with step cost 2 takes half the baseline's samples.
    #[must_use]
    pub fn step_cost() -> Self {
        Self::inverse_ratio(Measure::SamplesPerSecond).titled("step cost vs baseline")
    }

    /// Sets the heading.
    #[must_use]
    pub fn titled(mut self, heading: impl Into<String>) -> Self {
        self.heading = Some(heading.into());
        self
    }

    /// Leaves the column out of a scene's table when none of the table's methods has the
    /// measure there (e.g. acceptance in a table of PT and BDPT).
    #[must_use]
    pub fn if_reported(mut self) -> Self {
        self.if_reported = true;
        self
    }

    /// The measure the column shows.
    #[must_use]
    pub fn measure(&self) -> Measure {
        self.measure
    }

    /// The column's heading.
    #[must_use]
    pub fn heading(&self) -> String {
        let m = self.measure;
        self.heading.clone().unwrap_or_else(|| match self.summary {
            Summary::Range => format!("{m} median [min, max]"),
            Summary::Median => m.to_string(),
            Summary::Ratio => format!("{m} / baseline"),
            Summary::InverseRatio => format!("baseline {m} / {m}"),
        })
    }

    fn is_ratio(&self) -> bool {
        matches!(self.summary, Summary::Ratio | Summary::InverseRatio)
    }

    /// The cell of `method` on `scene`.
    fn cell(&self, results: &Results, scene: &str, method: &str) -> String {
        let m = self.measure;
        let of = |name: &str| results.median(scene, name, m);
        match self.summary {
            Summary::Range => median_range(m, &results.values(scene, method, m)),
            Summary::Median => m.format(of(method)),
            Summary::Ratio | Summary::InverseRatio => {
                results.baselines.get(method).map_or("-".into(), |b| {
                    let (value, base) = if self.summary == Summary::Ratio {
                        (of(method), of(b))
                    } else {
                        (of(b), of(method))
                    };
                    format!("{} ({b})", ratio(value, base))
                })
            }
        }
    }
}

/// A results table, one per scene: the methods it lists (default every method, in run
/// order), its columns, an optional title and note.
///
/// # Example
/// The Langevin comparison's table: MSE and relMSE with their ranges, speed, acceptance, and
/// MSE relative to each method's baseline.
/// ```
/// use experiments::{Column, Measure, TableSpec};
///
/// let spec = TableSpec::new([
///     Column::range(Measure::Mse),
///     Column::range(Measure::RelMse),
///     Column::median(Measure::SamplesPerSecond),
///     Column::median(Measure::Acceptance).if_reported(),
///     Column::ratio(Measure::Mse),
/// ]);
/// assert_eq!(spec.headings()[5], "MSE / baseline");
/// assert_eq!(TableSpec::standard().headings()[1], "relMSE median [min, max]");
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TableSpec {
    /// A line above each scene's table (bold), e.g. what a second table shows.
    pub title: Option<String>,
    /// The methods listed, in this order (`None`: every method of the experiment).
    pub methods: Option<Vec<String>>,
    /// The columns after the method's name.
    pub columns: Vec<Column>,
    /// A sentence explaining the table, printed once at the top of `results.md`.
    pub note: Option<String>,
}

impl TableSpec {
    /// A table of every method with these columns.
    #[must_use]
    pub fn new(columns: impl IntoIterator<Item = Column>) -> Self {
        Self {
            columns: columns.into_iter().collect(),
            ..Self::default()
        }
    }

    /// The harness's standard table ([`Results::scene_table`]): relMSE, MSE, rRMSE and MAD
    /// with their ranges, samples per second, acceptance (when reported) and relMSE over the
    /// baseline.
    #[must_use]
    pub fn standard() -> Self {
        Self::new([
            Column::range(Measure::RelMse),
            Column::range(Measure::Mse),
            Column::range(Measure::RRmse),
            Column::range(Measure::Mad),
            Column::median(Measure::SamplesPerSecond),
            Column::median(Measure::Acceptance).if_reported(),
            Column::ratio(Measure::RelMse),
        ])
    }

    /// Errors and cost: `median [min, max]` of each error measure, then samples per second and
    /// acceptance (when reported) as medians; add a ratio with [`TableSpec::with`].
    /// [`TableSpec::standard`] is this for relMSE, MSE, rRMSE and MAD with the relMSE ratio.
    #[must_use]
    pub fn errors(measures: impl IntoIterator<Item = Measure>) -> Self {
        let mut spec = Self::new(measures.into_iter().map(Column::range));
        spec.columns.push(Column::median(Measure::SamplesPerSecond));
        spec.columns
            .push(Column::median(Measure::Acceptance).if_reported());
        spec
    }

    /// Appends a column.
    #[must_use]
    pub fn with(mut self, column: Column) -> Self {
        self.columns.push(column);
        self
    }

    /// Acceptance per kernel stage (for delayed rejection and other multi-stage kernels):
    /// overall acceptance, stage 1 acceptance, the share of steps that tried stage 2, stage 2
    /// acceptance, the stage-2 share of accepted moves and candidates per step, all medians
    /// over seeds; titled `acceptance per stage`, with a note on what stage 2 and the
    /// candidate count mean.
    #[must_use]
    pub fn acceptance_by_stage() -> Self {
        Self::new([
            Column::median(Measure::Acceptance),
            Column::median(Measure::StageAcceptance(0)),
            Column::median(Measure::StageTried(1)),
            Column::median(Measure::StageAcceptance(1)),
            Column::median(Measure::SecondStageShare),
            Column::median(Measure::CandidatesPerStep),
        ])
        .titled("acceptance per stage")
        .with_note("stage 2 runs only after a rejected first stage; candidates per step count each stage's candidate once, not a kernel's extra evaluations (Green-Mira's ghost path at each second stage).")
    }

    /// Sets the title.
    #[must_use]
    pub fn titled(mut self, title: impl Into<String>) -> Self {
        self.title = Some(title.into());
        self
    }

    /// Lists only these methods, in this order (unknown names are skipped).
    #[must_use]
    pub fn only<S: Into<String>>(mut self, methods: impl IntoIterator<Item = S>) -> Self {
        self.methods = Some(methods.into_iter().map(Into::into).collect());
        self
    }

    /// Sets the note.
    #[must_use]
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.note = Some(note.into());
        self
    }

    /// Every column's heading, `method` first (all columns, whether reported or not).
    #[must_use]
    pub fn headings(&self) -> Vec<String> {
        std::iter::once("method".to_owned())
            .chain(self.columns.iter().map(Column::heading))
            .collect()
    }
}

impl Results {
    /// The table `spec` describes on `scene`: one row per listed method that ran.
    #[must_use]
    pub fn table(&self, scene: &str, spec: &TableSpec) -> Table {
        let methods: Vec<&String> = match &spec.methods {
            Some(names) => names.iter().filter(|n| self.methods.contains(n)).collect(),
            None => self.methods.iter().collect(),
        };
        let columns: Vec<&Column> = spec
            .columns
            .iter()
            .filter(|c| !c.is_ratio() || !self.baselines.is_empty())
            .filter(|c| {
                !c.if_reported
                    || methods
                        .iter()
                        .any(|m| (self.runs(scene, m)).any(|r| !c.measure.of(r).is_nan()))
            })
            .collect();
        let mut headings = vec!["method".to_owned()];
        headings.extend(columns.iter().map(|c| c.heading()));
        let mut table = Table::new(headings);
        for method in methods {
            let mut row = vec![method.clone()];
            row.extend(columns.iter().map(|c| c.cell(self, scene, method)));
            table.push_row(row);
        }
        table
    }

    /// `results.md` with these tables per scene instead of the standard one: the header of
    /// [`Results::markdown`], the tables' notes, per scene every table (titled), and the
    /// machine-load footer.
    #[must_use]
    pub fn markdown_with(&self, specs: &[TableSpec]) -> String {
        let mut md = self.markdown_header();
        md.push_str("\nmedian [min, max] over the seeds; other columns are medians over the seeds; a ratio divides medians, the baseline named in the cell.\n");
        for spec in specs {
            if let Some(note) = &spec.note {
                let title = spec
                    .title
                    .as_deref()
                    .map_or(String::new(), |t| format!("{t}: "));
                md.push_str(&format!("\n{title}{note}\n"));
            }
        }
        for scene in &self.scenes {
            md.push_str(&format!("\n### {scene}\n"));
            for spec in specs {
                if let Some(title) = &spec.title {
                    md.push_str(&format!("\n**{title}**\n"));
                }
                md.push('\n');
                md.push_str(&self.table(scene, spec).to_markdown());
            }
        }
        md.push_str(&self.markdown_footer());
        md
    }

    /// [`Results::write`] with [`Results::markdown_with`]`(specs)` as `results.md`.
    ///
    /// # Errors
    /// [`ExperimentError::Io`] naming the file that cannot be written.
    pub fn write_with(
        &self,
        specs: &[TableSpec],
        extra_markdown: &str,
    ) -> Result<PathBuf, ExperimentError> {
        self.write_markdown(self.markdown_with(specs), extra_markdown)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::tests::results;

    #[test]
    fn the_standard_spec_is_the_standard_table() {
        let r = results();
        assert_eq!(r.table("s", &TableSpec::standard()), r.scene_table("s"));
        // Negative control: without acceptance anywhere the column goes, as in scene_table.
        let mut none = results();
        for rec in &mut none.records {
            rec.stats.acceptance = None;
        }
        let t = none.table("s", &TableSpec::standard());
        assert_eq!(t, none.scene_table("s"));
        assert!(!t.headers().iter().any(|h| h == "acceptance"));
    }

    #[test]
    fn chosen_measures_ratios_and_step_cost() {
        let r = results();
        let spec = TableSpec::new([
            Column::range(Measure::Mse),
            Column::ratio(Measure::Mse),
            Column::step_cost(),
        ])
        .only(["new, better", "missing"]);
        let t = r.table("s", &spec);
        assert_eq!(
            t.headers(),
            [
                "method",
                "MSE median [min, max]",
                "MSE / baseline",
                "step cost vs baseline"
            ]
        );
        assert_eq!(t.rows().len(), 1, "only the listed methods that ran");
        assert_eq!(t.rows()[0][0], "new, better");
        // MSE medians 0.002 vs 0.003; samples/s medians 750 (both): cost 1.
        assert_eq!(t.rows()[0][2], "0.67 (base)");
        assert_eq!(t.rows()[0][3], "1.00 (base)");
        // Negative control: the ratio of another measure differs.
        let speed = r.table(
            "s",
            &TableSpec::new([Column::ratio(Measure::SamplesPerSecond)]),
        );
        assert_eq!(speed.rows()[1][1], "1.00 (base)");
    }

    #[test]
    fn inverse_ratio_divides_the_other_way() {
        let mut r = results();
        for rec in &mut r.records {
            if rec.method == "new, better" {
                rec.seconds *= 2.0;
            }
        }
        let cost = r.table("s", &TableSpec::new([Column::step_cost()]));
        let speed = r.table(
            "s",
            &TableSpec::new([Column::ratio(Measure::SamplesPerSecond)]),
        );
        assert_eq!(cost.rows()[1][1], "2.00 (base)");
        assert_eq!(speed.rows()[1][1], "0.50 (base)");
    }

    #[test]
    fn errors_then_chosen_ratios() {
        let spec =
            TableSpec::errors([Measure::Mse, Measure::Mad]).with(Column::ratio(Measure::Mse));
        assert_eq!(
            spec.headings(),
            [
                "method",
                "MSE median [min, max]",
                "MAD median [min, max]",
                "samples/s",
                "acceptance",
                "MSE / baseline"
            ]
        );
        let std = TableSpec::errors([Measure::RelMse, Measure::Mse, Measure::RRmse, Measure::Mad])
            .with(Column::ratio(Measure::RelMse));
        assert_eq!(std, TableSpec::standard());
    }

    #[test]
    fn ratio_columns_need_baselines_and_if_reported_needs_a_value() {
        let mut r = results();
        r.baselines.clear();
        let spec = TableSpec::new([
            Column::median(Measure::B).if_reported(),
            Column::median(Measure::B),
            Column::ratio(Measure::Mse),
        ]);
        assert_eq!(r.table("s", &spec).headers(), ["method", "b"]);
        assert_eq!(r.table("s", &spec).rows()[0][1], "-");
    }

    #[test]
    fn acceptance_by_stage_reads_the_counts() {
        let mut r = results();
        let mut counts = mcmc_core::stats::AcceptanceStats {
            steps: 10,
            ..Default::default()
        };
        counts.stage_tried = [10, 4];
        counts.stage_accepted = [6, 1];
        counts.proposed[0] = 10;
        counts.accepted[0] = 7;
        for rec in r.records.iter_mut().filter(|x| x.method == "new, better") {
            rec.stats.acceptance_counts = Some(counts);
        }
        let t = r.table("s", &TableSpec::acceptance_by_stage());
        assert_eq!(t.headers()[3], "stage 2 tried (share of steps)");
        assert_eq!(
            t.rows()[1][2..],
            ["0.600", "0.400", "0.250", "0.143", "1.40"]
        );
        // Negative control: the one-stage baseline reports no stage statistics at all.
        assert!(
            t.rows()[0][2..].iter().all(|c| c == "-"),
            "{:?}",
            t.rows()[0]
        );
    }

    #[test]
    fn markdown_with_titles_notes_and_every_scene() {
        let r = results();
        let specs = [
            TableSpec::new([Column::range(Measure::Mse)]),
            TableSpec::new([Column::median(Measure::Acceptance)])
                .titled("Acceptance")
                .only(["new, better"])
                .with_note("medians over seeds"),
        ];
        let md = r.markdown_with(&specs);
        assert!(md.starts_with("# t\n"), "{md}");
        assert!(md.contains("\nAcceptance: medians over seeds\n"), "{md}");
        assert!(
            md.contains("### s\n\n| method | MSE median [min, max] |"),
            "{md}"
        );
        assert!(
            md.contains(
                "**Acceptance**\n\n| method | acceptance |\n|---|---|\n| new, better | 0.375 |"
            ),
            "{md}"
        );
        assert!(md.contains("Machine load"), "{md}");
        assert!(!md.contains("relMSE median"), "no standard table: {md}");
    }
}
