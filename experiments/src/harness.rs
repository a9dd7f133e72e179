//! The comparison harness: every method on every scene with every seed, interleaved, each run
//! measured against the scene's reference and recorded with the machine's load.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use render::image::Image;
use render::metrics::Metrics;
use render::session::RenderOutput;

use crate::load::{describe, LoadAverage};
use crate::method::{Method, RunContext};
use crate::plan::Plan;
use crate::record::RunRecord;
use crate::report::{ConvergencePoint, BUILD_COMMIT};
use crate::results::Results;
use crate::rundir::{scene_manifest, RunDirectory};
use crate::scene::{load_bundled, SceneCase};
use crate::stats::run_stats;
use crate::sweep::JobMode;
use crate::ExperimentError;

/// Extra parameters of a scene's run, computed from the finished results.
type SceneParameters<'a> = dyn Fn(&Results, &str) -> Vec<(String, String)> + 'a;
/// Sees every final render (its record, its output and the scene's run directory).
type Inspect<'a> = dyn FnMut(&RunRecord, &RenderOutput, &Path) + 'a;
/// Takes an extra image (a stage map, say) from a final render's output.
type ExtraImage<'a> = dyn Fn(&RenderOutput) -> Option<Image> + 'a;

/// A comparison of methods: build it from a [`Plan`], add methods, [`Experiment::run`] it.
///
/// The order of the renders is: for each seed, for each scene, for each method — so a change
/// in machine load during the run hits every method alike (the examples' interleaving).
/// Under an equal-samples regime the order does not change any image.
pub struct Experiment<'a> {
    pub(crate) plan: Plan,
    pub(crate) methods: Vec<Method>,
    cases: Option<Vec<SceneCase>>,
    baseline: Option<String>,
    convergence: Vec<f64>,
    pub(crate) parameters: Vec<(String, String)>,
    scene_parameters: Option<Box<SceneParameters<'a>>>,
    pub(crate) inspect: Option<Box<Inspect<'a>>>,
    extra_images: Vec<(String, Box<ExtraImage<'a>>)>,
    pub(crate) command_line: Option<Vec<String>>,
}

impl<'a> Experiment<'a> {
    /// An experiment running `plan` with no methods yet.
    #[must_use]
    pub fn new(plan: Plan) -> Self {
        Self {
            plan,
            methods: Vec::new(),
            cases: None,
            baseline: None,
            convergence: Vec::new(),
            parameters: Vec::new(),
            scene_parameters: None,
            inspect: None,
            extra_images: Vec::new(),
            command_line: None,
        }
    }

    /// Adds a method (rendered in the order added).
    #[must_use]
    pub fn method(mut self, method: Method) -> Self {
        self.methods.push(method);
        self
    }

    /// Adds methods (rendered in the order given).
    #[must_use]
    pub fn methods(mut self, methods: impl IntoIterator<Item = Method>) -> Self {
        self.methods.extend(methods);
        self
    }

    /// The method the tables' ratio column divides by.
    #[must_use]
    pub fn baseline(mut self, name: impl Into<String>) -> Self {
        self.baseline = Some(name.into());
        self
    }

    /// Error-vs-time samples for the report: besides the final render, one extra render per
    /// fraction of the budget (e.g. `[0.125, 0.25, 0.5]`), skipped without a report. Without
    /// fractions each seed contributes one sample (its final render).
    #[must_use]
    pub fn convergence(mut self, fractions: &[f64]) -> Self {
        self.convergence = fractions.to_vec();
        self
    }

    /// Adds a parameter shared by every method, shown in the report and `results.md`.
    #[must_use]
    pub fn parameter(mut self, key: impl Into<String>, value: impl std::fmt::Display) -> Self {
        self.parameters.push((key.into(), value.to_string()));
        self
    }

    /// Computes extra parameters of each scene's report from the finished results (e.g. a
    /// statistic measured on the scene).
    #[must_use]
    pub fn scene_parameters(
        mut self,
        f: impl Fn(&Results, &str) -> Vec<(String, String)> + 'a,
    ) -> Self {
        self.scene_parameters = Some(Box::new(f));
        self
    }

    /// Calls `f` after every final render with its record, the full render output (notes,
    /// stage maps, ...) and the scene's run directory, e.g. to save an extra image.
    #[must_use]
    pub fn inspect(mut self, f: impl FnMut(&RunRecord, &RenderOutput, &Path) + 'a) -> Self {
        self.inspect = Some(Box::new(f));
        self
    }

    /// Saves an extra image of every final render that has one: `f` takes it from the
    /// render's output (e.g. `|out| out.stage_map.clone()`, delayed rejection's stage map),
    /// and the harness writes it next to the method's image as `<slug>_<name>_seed<seed>.exr`
    /// (the first seed also as `<slug>_<name>.exr` and `.png`). `name` is a file stem of ASCII
    /// letters, digits, `-` and `_`.
    #[must_use]
    pub fn extra_image(
        mut self,
        name: impl Into<String>,
        f: impl Fn(&RenderOutput) -> Option<Image> + 'a,
    ) -> Self {
        self.extra_images.push((name.into(), Box::new(f)));
        self
    }

    /// Runs on these scenes instead of loading the plan's bundled scenes (each reference must
    /// be `plan.size` square).
    #[must_use]
    pub fn scenes(mut self, cases: Vec<SceneCase>) -> Self {
        self.cases = Some(cases);
        self
    }

    /// The command line a job list repeats for each run (`--emit-jobs`): the example's program
    /// and arguments [default: this process's]. `--emit-jobs DIR` is removed from it and
    /// `--run-one <id>` (or `--collect`) appended.
    #[must_use]
    pub fn command_line(mut self, argv: impl IntoIterator<Item = impl Into<String>>) -> Self {
        self.command_line = Some(argv.into_iter().map(Into::into).collect());
        self
    }

    /// Runs every render, writes every scene's run directory (images, `run.json`, and
    /// `report.html` unless the plan says no) and returns the results. Scenes that cannot be
    /// loaded are skipped with a message on stderr; progress goes to stderr.
    ///
    /// This runs everything in this process; [`Experiment::execute`] also honours the plan's
    /// [`crate::JobMode`] (a job list instead).
    ///
    /// # Errors
    /// [`ExperimentError::Invalid`] for an inconsistent experiment (no methods or seeds,
    /// duplicate names or file stems, an unknown baseline, no loadable scene, a reference of
    /// the wrong size) or a plan whose job mode is not [`crate::JobMode::Local`];
    /// [`ExperimentError::Render`] naming the scene, method and seed of a failed render; I/O,
    /// image and report errors naming the file.
    pub fn run(self) -> Result<Results, ExperimentError> {
        if self.plan.jobs != JobMode::Local {
            return Err(ExperimentError::Invalid(format!(
                "{} renders in one process: it does not take --emit-jobs, --run-one or --collect",
                self.plan.name
            )));
        }
        self.run_here()
    }

    /// [`Experiment::run`] in this process.
    pub(crate) fn run_here(mut self) -> Result<Results, ExperimentError> {
        self.validate()?;
        let started = Instant::now();
        let load_before = LoadAverage::read();
        let commit = BUILD_COMMIT.to_string();
        let cases = self.load_cases()?;
        let dirs = self.scene_directories(&cases)?;
        let mut records = Vec::new();
        for seed in self.plan.seeds.clone() {
            for (case, dir) in cases.iter().zip(&dirs) {
                records.extend(self.run_slot(case, dir, seed)?);
            }
        }
        let mut results = self.results(&cases, records, commit);
        results.load_before = load_before;
        self.write_scenes(&results, &cases, &dirs)?;
        results.load_after = LoadAverage::read();
        results.wall_seconds = started.elapsed().as_secs_f64();
        Ok(results)
    }

    /// Every scene's run directory, created, with its reference written.
    pub(crate) fn scene_directories(
        &self,
        cases: &[SceneCase],
    ) -> Result<Vec<RunDirectory>, ExperimentError> {
        cases
            .iter()
            .map(|c| {
                let dir = RunDirectory::create(self.plan.out.join(&c.name))?;
                dir.write_reference(&c.reference)?;
                Ok(dir)
            })
            .collect()
    }

    /// Every method, in order, on `case` with `seed` (one slot of the interleaving): their
    /// records, images and extra images, each seen by the inspect callback.
    pub(crate) fn run_slot(
        &mut self,
        case: &SceneCase,
        dir: &RunDirectory,
        seed: u64,
    ) -> Result<Vec<RunRecord>, ExperimentError> {
        let mut slot: Vec<RunRecord> = Vec::new();
        for method in &self.methods {
            let (record, output) = self.run_one(case, dir, method, seed, &slot)?;
            self.write_extra_images(dir, method, seed, &output)?;
            if let Some(f) = self.inspect.as_mut() {
                f(&record, &output, dir.path());
            }
            slot.push(record);
        }
        Ok(slot)
    }

    /// The results of `records` on `cases` (no load or wall time yet).
    pub(crate) fn results(
        &self,
        cases: &[SceneCase],
        records: Vec<RunRecord>,
        commit: String,
    ) -> Results {
        Results {
            plan: self.plan.clone(),
            methods: self.method_names(),
            baselines: self.baselines(),
            scenes: cases.iter().map(|c| c.name.clone()).collect(),
            parameters: self.parameters.clone(),
            records,
            commit,
            load_before: None,
            load_after: None,
            wall_seconds: 0.0,
        }
    }

    /// The methods' names, in order.
    pub(crate) fn method_names(&self) -> Vec<String> {
        self.methods.iter().map(|m| m.name().to_owned()).collect()
    }

    /// Writes every scene's `run.json` (and `report.html`).
    pub(crate) fn write_scenes(
        &self,
        results: &Results,
        cases: &[SceneCase],
        dirs: &[RunDirectory],
    ) -> Result<(), ExperimentError> {
        for (case, dir) in cases.iter().zip(dirs) {
            self.write_scene(results, case, dir)?;
        }
        Ok(())
    }

    /// Checks what [`Experiment::run`] relies on.
    pub(crate) fn validate(&self) -> Result<(), ExperimentError> {
        let invalid = |m: String| Err(ExperimentError::Invalid(m));
        if self.methods.is_empty() {
            return invalid("no methods".into());
        }
        if self.plan.seeds.is_empty() {
            return invalid("no seeds".into());
        }
        for (i, m) in self.methods.iter().enumerate() {
            let earlier = &self.methods[..i];
            if m.name().trim().is_empty() {
                return invalid(format!("method {i} has an empty name"));
            }
            if earlier.iter().any(|o| o.name() == m.name()) {
                return invalid(format!("method name {:?} appears twice", m.name()));
            }
            if let Some(o) = earlier.iter().find(|o| o.slug() == m.slug()) {
                return invalid(format!(
                    "methods {:?} and {:?} share the file stem {:?} (Method::with_slug)",
                    o.name(),
                    m.name(),
                    m.slug()
                ));
            }
        }
        for (i, (name, _)) in self.extra_images.iter().enumerate() {
            let safe = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_';
            if name.is_empty() || !name.chars().all(safe) {
                return invalid(format!("extra image name {name:?} is not a file stem"));
            }
            if self.extra_images[..i].iter().any(|(n, _)| n == name) {
                return invalid(format!("extra image {name:?} appears twice"));
            }
            let clash = self.methods.iter().find_map(|m| {
                let stem = format!("{}_{name}", m.slug());
                self.methods
                    .iter()
                    .find(|o| o.slug() == stem)
                    .map(|o| (m, o))
            });
            if let Some((m, o)) = clash {
                return invalid(format!(
                    "extra image {name:?} of {:?} would overwrite the images of {:?}",
                    m.name(),
                    o.name()
                ));
            }
        }
        let known = |b: &str| self.methods.iter().any(|m| m.name() == b);
        for b in self.baselines().values().chain(self.baseline.as_ref()) {
            if !known(b) {
                return invalid(format!("baseline {b:?} is not a method of the experiment"));
            }
        }
        Ok(())
    }

    /// Writes the extra images of one final render ([`Experiment::extra_image`]).
    fn write_extra_images(
        &self,
        dir: &RunDirectory,
        method: &Method,
        seed: u64,
        output: &RenderOutput,
    ) -> Result<(), ExperimentError> {
        let first = self.plan.seeds.first() == Some(&seed);
        for (name, f) in &self.extra_images {
            if let Some(image) = f(output) {
                let stem = format!("{}_{name}", method.slug());
                dir.write_seed_image(&stem, seed, &image, first)?;
            }
        }
        Ok(())
    }

    /// Each method's baseline: its own, else the experiment's.
    fn baselines(&self) -> BTreeMap<String, String> {
        self.methods
            .iter()
            .filter_map(|m| {
                let b = m.baseline().or(self.baseline.as_deref())?;
                Some((m.name().to_owned(), b.to_owned()))
            })
            .collect()
    }

    /// The scenes given with [`Experiment::scenes`], or the plan's bundled scenes.
    pub(crate) fn load_cases(&mut self) -> Result<Vec<SceneCase>, ExperimentError> {
        let size = self.plan.size as usize;
        let cases = match self.cases.take() {
            Some(cases) => cases,
            None => load_bundled(&self.plan.scenes, self.plan.size),
        };
        if cases.is_empty() {
            return Err(ExperimentError::Invalid("no scene could be loaded".into()));
        }
        for c in &cases {
            if (c.reference.width, c.reference.height) != (size, size) {
                return Err(ExperimentError::Invalid(format!(
                    "{}: the reference is {}x{}, the plan renders {size}x{size}",
                    c.name, c.reference.width, c.reference.height
                )));
            }
        }
        Ok(cases)
    }

    /// One final render of `method` (plus its convergence renders) on `case` with `seed`.
    fn run_one(
        &self,
        case: &SceneCase,
        dir: &RunDirectory,
        method: &Method,
        seed: u64,
        slot: &[RunRecord],
    ) -> Result<(RunRecord, RenderOutput), ExperimentError> {
        let render_at = |regime| {
            let context = RunContext {
                scene: &case.name,
                regime,
                seed,
                size: self.plan.size,
                threads: self.plan.threads,
                previous: slot,
            };
            let settings = method.settings(&context);
            let start = Instant::now();
            let output = method.render(&case.scene, &settings).map_err(|source| {
                ExperimentError::Render {
                    scene: case.name.clone(),
                    method: method.name().to_owned(),
                    seed,
                    source,
                }
            })?;
            Ok::<_, ExperimentError>((output, start.elapsed().as_secs_f64()))
        };
        let mut convergence = Vec::new();
        if self.plan.report {
            for &f in &self.convergence {
                if let Some(regime) = self.plan.regime.scaled(f).filter(|_| f < 1.0) {
                    let (output, seconds) = render_at(regime)?;
                    if let Ok(relmse) = render::metrics::relmse(&output.image, &case.reference) {
                        convergence.push(ConvergencePoint {
                            time_s: seconds,
                            relmse,
                        });
                    }
                }
            }
        }
        let load = LoadAverage::read();
        let (output, seconds) = render_at(self.plan.regime)?;
        let metrics =
            render::metrics::compare(&output.image, &case.reference).unwrap_or_else(|e| {
                eprintln!("{}, {}, seed {seed}: {e}", case.name, method.name());
                Metrics {
                    mse: f64::NAN,
                    rmse: f64::NAN,
                    relmse: f64::NAN,
                    rrmse: f64::NAN,
                    mad: f64::NAN,
                }
            });
        if metrics.relmse.is_finite() {
            convergence.push(ConvergencePoint {
                time_s: seconds,
                relmse: metrics.relmse,
            });
        }
        let first = self.plan.seeds.first() == Some(&seed);
        let image = dir.write_seed_image(method.slug(), seed, &output.image, first)?;
        let record = RunRecord {
            scene: case.name.clone(),
            method: method.name().to_owned(),
            seed,
            seconds,
            samples: output.samples,
            metrics,
            stats: run_stats(&output),
            load,
            image,
            convergence,
        };
        eprintln!(
            "{} seed {seed} {}: relMSE {:.4}, MSE {:.3e}, {:.0} samples/s{}, load {}",
            case.name,
            method.name(),
            metrics.relmse,
            metrics.mse,
            record.samples_per_second(),
            record
                .stats
                .acceptance
                .map_or_else(String::new, |a| format!(", acceptance {a:.3}")),
            describe(load)
        );
        Ok((record, output))
    }

    /// Writes `run.json` (and `report.html`) of one scene.
    fn write_scene(
        &self,
        results: &Results,
        case: &SceneCase,
        dir: &RunDirectory,
    ) -> Result<(), ExperimentError> {
        let plan = &self.plan;
        let mut parameters: BTreeMap<String, String> = [
            ("scene", case.name.clone()),
            ("size", format!("{0}x{0}", plan.size)),
            ("budget", plan.regime.to_string()),
            ("seeds", format!("{:?}", plan.seeds)),
            ("render threads", plan.threads.to_string()),
            ("reference", case.reference_source.clone()),
            (
                "order",
                "interleaved: for seed, for scene, for method".into(),
            ),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_owned(), v))
        .collect();
        if plan.report && self.convergence.iter().any(|&f| f > 0.0 && f < 1.0) {
            parameters.insert(
                "convergence".into(),
                format!(
                    "independent renders at {:?} of the budget, and the final one",
                    self.convergence
                ),
            );
        }
        parameters.extend(self.parameters.iter().cloned());
        if let Some(f) = &self.scene_parameters {
            parameters.extend(f(results, &case.name));
        }
        let manifest = scene_manifest(
            format!("{}: {}", plan.name, case.name),
            results.commit.clone(),
            parameters,
            &case.name,
            &self.methods,
            &results.records,
        );
        if let Some(html) = dir.save(&manifest, plan.report)? {
            eprintln!("{}: report {}", case.name, html.display());
        }
        Ok(())
    }
}
