//! [`Experiment::execute`]: an experiment run here, written as a job list (`--emit-jobs`),
//! one run of that list (`--run-one`), or its results collected from the runs' records
//! (`--collect`) — the last giving the same tables a run here gives.

use std::collections::BTreeSet;
use std::path::Path;
use std::time::Instant;

use crate::harness::Experiment;
use crate::report::BUILD_COMMIT;
use crate::results::Results;
use crate::sweep::emit::{experiment_sweep, shown, write_sweep_files};
use crate::sweep::joblist::JOBS_FILE;
use crate::sweep::mode::{JobMode, RunId};
use crate::sweep::records::SlotRecord;
use crate::ExperimentError;

impl Experiment<'_> {
    /// Runs the experiment as its plan's [`JobMode`] says: here ([`Experiment::run`]), as a
    /// job list written to a directory, one run of that list, or the results collected from
    /// the list's runs. Returns the results when there are any (here and collect), `None`
    /// after writing a job list or running one job — then the example has nothing to write.
    ///
    /// A run of the list renders every method on one scene with one seed and records them in
    /// `<out>/<scene>/runs/seed<seed>.json` next to the images; collecting reads those
    /// records (refusing a missing one, or one made with another budget, size or method
    /// list), writes `run.json` and `report.html` and returns [`Results`] whose tables are
    /// those of a run here (errors bit-identical under equal samples; times are the jobs').
    ///
    /// # Errors
    /// As [`Experiment::run`]; an experiment with [`Experiment::inspect`] is refused in the
    /// job modes (the callback sees render outputs a job list cannot carry back); a run id
    /// whose scene or seed is not the plan's; a missing or mismatched record when collecting.
    ///
    /// # Example
    /// ```
    /// use experiments::{Defaults, Experiment, JobMode, Method, Plan, Regime, RunId, SceneCase};
    /// use render::session::{IntegratorKind, RenderSettings};
    ///
    /// let out = std::env::temp_dir().join(format!("experiments-execute-doc-{}", std::process::id()));
    /// let plan = Plan {
    ///     seeds: vec![1],
    ///     size: 8,
    ///     threads: 1,
    ///     report: false,
    ///     out: out.clone(),
    ///     ..Plan::from_defaults(&Defaults::new("doc", Regime::EqualSamples(2)))
    /// };
    /// let pt = || Method::new("PT", RenderSettings { method: IntegratorKind::Pt.settings(), ..RenderSettings::default() });
    /// let experiment = |jobs| {
    ///     Experiment::new(Plan { jobs, ..plan.clone() })
    ///         .method(pt())
    ///         .scenes(vec![SceneCase::cornell_box(8, 4).unwrap()])
    ///         .command_line(["target/release/examples/doc", "--emit-jobs", "jobs"])
    /// };
    /// assert!(experiment(JobMode::Emit(out.join("jobs"))).execute()?.is_none());
    /// assert!(experiment(JobMode::RunOne(RunId::new("cornell-box", 1))).execute()?.is_none());
    /// let results = experiment(JobMode::Collect).execute()?.expect("collected results");
    /// assert_eq!(results.records.len(), 1);
    /// # std::fs::remove_dir_all(&out).ok();
    /// # Ok::<(), experiments::ExperimentError>(())
    /// ```
    pub fn execute(self) -> Result<Option<Results>, ExperimentError> {
        let mode = self.plan.jobs.clone();
        if mode != JobMode::Local && self.inspect.is_some() {
            return Err(ExperimentError::Invalid(format!(
                "{} inspects every render's output in its own process, which a job list cannot carry back: run it without --emit-jobs, --run-one or --collect",
                self.plan.name
            )));
        }
        match mode {
            JobMode::Local => self.run_here().map(Some),
            JobMode::Emit(dir) => self.emit_jobs(&dir).map(|()| None),
            JobMode::RunOne(id) => self.run_job(&id).map(|()| None),
            JobMode::Collect => self.collect().map(Some),
        }
    }

    /// Writes the job list of every scene that loads and every seed into `dir`.
    fn emit_jobs(mut self, dir: &Path) -> Result<(), ExperimentError> {
        self.validate()?;
        let scenes: Vec<String> = self.load_cases()?.into_iter().map(|c| c.name).collect();
        let command_line = match self.command_line.take() {
            Some(argv) => argv,
            None => std::env::args_os()
                .map(|a| {
                    a.into_string().map_err(|a| {
                        ExperimentError::Invalid(format!(
                            "argument {a:?} is not UTF-8; a job list stores text"
                        ))
                    })
                })
                .collect::<Result<_, _>>()?,
        };
        let sweep = experiment_sweep(&self.plan, &scenes, dir, &command_line)?;
        write_sweep_files(&sweep)?;
        let d = shown(&sweep.dir).display().to_string();
        eprintln!(
            "{}: wrote {} runs ({} scenes x {} seeds) to {d}/{JOBS_FILE}. Run them here: chainlight sweep run {d} [--parallel N]; on Slurm: sbatch {d}/slurm.sbatch; on Kubernetes: chainlight sweep k8s {d} --image IMAGE, then kubectl apply -f {d}/k8s-job.json. Then: {}",
            self.plan.name,
            sweep.jobs.len(),
            scenes.len(),
            self.plan.seeds.len(),
            sweep.info.collect.as_deref().unwrap_or_default().join(" ")
        );
        Ok(())
    }

    /// Renders run `id` and records it in its scene's run directory.
    fn run_job(mut self, id: &RunId) -> Result<(), ExperimentError> {
        self.validate()?;
        if !self.plan.seeds.contains(&id.seed) {
            return Err(ExperimentError::Invalid(format!(
                "--run-one {id}: seed {} is not one of the seeds {:?}",
                id.seed, self.plan.seeds
            )));
        }
        let started = Instant::now();
        let cases = self.load_cases()?;
        let Some(case) = cases.iter().find(|c| c.name == id.scene) else {
            return Err(ExperimentError::Invalid(format!(
                "--run-one {id}: scene {:?} is not among the loaded scenes {:?}",
                id.scene,
                cases.iter().map(|c| &c.name).collect::<Vec<_>>()
            )));
        };
        let dir = crate::RunDirectory::create(self.plan.out.join(&case.name))?;
        let path = SlotRecord::path(dir.path(), id.seed);
        // A record left by an earlier run of this job must not outlive a failed re-run.
        if path.exists() {
            std::fs::remove_file(&path).map_err(ExperimentError::io(&path))?;
        }
        let records = self.run_slot(case, &dir, id.seed)?;
        let slot = SlotRecord::new(
            id,
            &self.plan,
            self.method_names(),
            BUILD_COMMIT.to_string(),
            started.elapsed().as_secs_f64(),
            &records,
        );
        slot.write(&path)?;
        eprintln!("{id}: recorded {}", path.display());
        Ok(())
    }

    /// Reads every run's record and writes the results as a run here would.
    fn collect(mut self) -> Result<Results, ExperimentError> {
        self.validate()?;
        let cases = self.load_cases()?;
        let dirs = self.scene_directories(&cases)?;
        let methods = self.method_names();
        let (mut records, mut missing, mut commits, mut wall) =
            (Vec::new(), Vec::new(), BTreeSet::new(), 0.0);
        for &seed in &self.plan.seeds {
            for (case, dir) in cases.iter().zip(&dirs) {
                let id = RunId::new(case.name.clone(), seed);
                let path = SlotRecord::path(dir.path(), seed);
                let Some(slot) = SlotRecord::read(&path)? else {
                    missing.push(id.to_string());
                    continue;
                };
                commits.insert(slot.commit.clone());
                wall += slot.wall_seconds.0;
                records.extend(slot.records_for(&path, &id, &self.plan, &methods)?);
            }
        }
        if !missing.is_empty() {
            let total = cases.len() * self.plan.seeds.len();
            return Err(ExperimentError::Invalid(format!(
                "{} of the {total} runs have no record in {} (first: {}): run them (chainlight sweep run DIR, or --run-one ID) before --collect",
                missing.len(),
                self.plan.out.display(),
                missing[..missing.len().min(3)].join(", ")
            )));
        }
        let commit = commits.into_iter().collect::<Vec<_>>().join(" + ");
        self.parameters.push((
            "job list".into(),
            format!(
                "collected from {} runs; the wall time is their sum",
                cases.len() * self.plan.seeds.len()
            ),
        ));
        let mut results = self.results(&cases, records, commit);
        results.wall_seconds = wall;
        self.write_scenes(&results, &cases, &dirs)?;
        Ok(results)
    }
}
