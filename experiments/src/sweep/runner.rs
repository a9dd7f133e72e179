//! Executes a sweep's jobs: [`run_local`] runs the list on this machine with a bounded number
//! of concurrent jobs, resumably; [`run_task`] runs the one job a Slurm array task or a
//! Kubernetes Indexed Job pod is given. Both record every job's status in the sweep directory.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{mpsc, Mutex};
use std::time::Instant;

use crate::sweep::joblist::Sweep;
use crate::sweep::status::{
    log_paths, read_status, tail, write_status, Progress, RunState, RunStatus,
};
use crate::ExperimentError;

/// The environment variables a job's index is read from when none is given: the Kubernetes
/// Indexed Job's, then the Slurm array task's.
pub const INDEX_VARIABLES: [&str; 2] = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"];

/// What [`run_local`] runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LocalRun {
    /// Jobs running at once (at least 1).
    pub parallel: usize,
    /// Run only this job, whatever its state (re-running one failed run alone).
    pub only: Option<String>,
    /// Run the jobs here instead of the sweep's working directory.
    pub workdir: Option<PathBuf>,
    /// After the last job, when every job is done, run the sweep's collect command.
    pub collect: bool,
}

impl Default for LocalRun {
    /// One job at a time, every job not done, in the sweep's working directory, then collect.
    fn default() -> Self {
        Self {
            parallel: 1,
            only: None,
            workdir: None,
            collect: true,
        }
    }
}

/// Runs the jobs of `sweep` that are not done (or only `options.only`), `options.parallel` at
/// a time, recording each one's status; prints a line per finished job with the sweep's
/// progress to stderr. Returns the progress at the end; failed jobs are in it, not errors.
///
/// # Errors
/// [`ExperimentError::Invalid`] for an unknown `only` id, a parallelism of 0 or a missing
/// working directory; [`ExperimentError::Io`] if a status file cannot be written; the collect
/// command's failure.
pub fn run_local(sweep: &Sweep, options: &LocalRun) -> Result<Progress, ExperimentError> {
    if options.parallel == 0 {
        return Err(ExperimentError::Invalid(
            "--parallel must be at least 1".into(),
        ));
    }
    let workdir = existing_workdir(sweep, options.workdir.as_deref())?;
    let (mut progress, statuses) = Progress::of(sweep);
    let queue: VecDeque<usize> = match &options.only {
        Some(id) => VecDeque::from([sweep.index_of(id).ok_or_else(|| unknown_id(sweep, id))?]),
        None => (0..sweep.jobs.len())
            .filter(|&i| {
                statuses[i]
                    .as_ref()
                    .is_none_or(|s| s.state != RunState::Done)
            })
            .collect(),
    };
    let planned = queue.len();
    eprintln!(
        "sweep {} ({} jobs in {}): {progress}; running {planned}, {} at a time",
        sweep.info.name,
        sweep.jobs.len(),
        sweep.dir.display(),
        options.parallel.min(planned.max(1))
    );
    // Each job leaves its former state for `running` when it starts (counted here, before
    // the workers start, so the running count is what the progress lines show).
    for &i in &queue {
        match statuses[i].as_ref().map(|s| s.state) {
            Some(RunState::Done) => progress.done -= 1,
            Some(RunState::Failed) => progress.failed -= 1,
            Some(RunState::Running) => progress.running -= 1,
            None => progress.pending -= 1,
        }
        progress.pending += 1;
    }
    let queue = Mutex::new(queue);
    let (sender, receiver) = mpsc::channel();
    std::thread::scope(|scope| -> Result<(), ExperimentError> {
        for _ in 0..options.parallel.min(planned) {
            let sender = sender.clone();
            let (queue, workdir) = (&queue, &workdir);
            scope.spawn(move || loop {
                let next = queue.lock().expect("the job queue").pop_front();
                let Some(i) = next else { break };
                if sender.send((i, run_job(sweep, i, workdir))).is_err() {
                    break;
                }
            });
        }
        drop(sender);
        for (finished, (i, result)) in receiver.into_iter().enumerate() {
            let status = result?;
            progress.pending -= 1;
            match status.state {
                RunState::Done => progress.done += 1,
                _ => progress.failed += 1,
            }
            eprintln!(
                "[{}/{planned}] {}: {} | {progress}",
                finished + 1,
                sweep.jobs[i].id,
                status.summary()
            );
        }
        Ok(())
    })?;
    if progress.failed > 0 {
        let (_, statuses) = Progress::of(sweep);
        for (job, status) in sweep.jobs.iter().zip(&statuses) {
            if let Some(s) = status.as_ref().filter(|s| s.state == RunState::Failed) {
                eprintln!(
                    "failed: {} ({}); its log: {}; re-run it alone: chainlight sweep run {} --only {}",
                    job.id,
                    s.summary(),
                    log_paths(&sweep.dir, &job.id).1.display(),
                    sweep.dir.display(),
                    job.id
                );
            }
        }
    }
    let complete = progress.done == sweep.jobs.len();
    if let (true, true, None, Some(collect)) = (
        options.collect,
        complete,
        &options.only,
        &sweep.info.collect,
    ) {
        eprintln!("every job is done; collecting: {}", collect.join(" "));
        let status = command(collect, &workdir)
            .status()
            .map_err(ExperimentError::io(&collect[0]))?;
        if !status.success() {
            return Err(ExperimentError::Invalid(format!(
                "the collect command {} exited with {status}",
                collect.join(" ")
            )));
        }
    }
    Ok(progress)
}

/// Runs job `index` of `sweep` (its index from [`INDEX_VARIABLES`] when `None`), unless it is
/// done and `force` is off; records and returns its status.
///
/// # Errors
/// [`ExperimentError::Invalid`] for no index, an index that is not a number or beyond the
/// list, or a missing working directory; [`ExperimentError::Io`] if the status cannot be
/// written.
pub fn run_task(
    sweep: &Sweep,
    index: Option<usize>,
    workdir: Option<&Path>,
    force: bool,
) -> Result<RunStatus, ExperimentError> {
    let index = match index {
        Some(i) => i,
        None => index_from_environment()?,
    };
    let Some(job) = sweep.jobs.get(index) else {
        return Err(ExperimentError::Invalid(format!(
            "job index {index} is beyond the {} jobs of {}",
            sweep.jobs.len(),
            sweep.dir.join(crate::sweep::joblist::JOBS_FILE).display()
        )));
    };
    let workdir = existing_workdir(sweep, workdir)?;
    if !force {
        if let Some(done) = read_status(&sweep.dir, &job.id)?.filter(|s| s.state == RunState::Done)
        {
            eprintln!(
                "{}: already done ({}); --force runs it again",
                job.id,
                done.summary()
            );
            return Ok(done);
        }
    }
    let status = run_job(sweep, index, &workdir)?;
    eprintln!("{}: {}", job.id, status.summary());
    Ok(status)
}

/// The job index from the first of [`INDEX_VARIABLES`] that is set.
fn index_from_environment() -> Result<usize, ExperimentError> {
    for name in INDEX_VARIABLES {
        if let Ok(value) = std::env::var(name) {
            return value.trim().parse().map_err(|_| {
                ExperimentError::Invalid(format!(
                    "{name}={value:?} is not a job index (0, 1, 2, ...)"
                ))
            });
        }
    }
    Err(ExperimentError::Invalid(format!(
        "no job index: give one, or set {} (Kubernetes Indexed Job) or {} (Slurm array)",
        INDEX_VARIABLES[0], INDEX_VARIABLES[1]
    )))
}

/// The working directory the jobs run in, checked to exist.
fn existing_workdir(sweep: &Sweep, workdir: Option<&Path>) -> Result<PathBuf, ExperimentError> {
    let dir = sweep.workdir(workdir);
    if dir.is_dir() {
        Ok(dir)
    } else {
        Err(ExperimentError::Invalid(format!(
            "the working directory {} of sweep {} does not exist here (pass --workdir)",
            dir.display(),
            sweep.dir.display()
        )))
    }
}

/// The error for an id that is not in the list, naming a few that are.
fn unknown_id(sweep: &Sweep, id: &str) -> ExperimentError {
    let some: Vec<&str> = sweep.jobs.iter().take(3).map(|j| j.id.as_str()).collect();
    ExperimentError::Invalid(format!(
        "no job {id:?} in {} (ids look like {})",
        sweep.dir.display(),
        some.join(", ")
    ))
}

/// `argv` as a command in `workdir`: a relative program path with a `/` is taken relative to
/// `workdir`, a bare name is looked up on `PATH`.
fn command(argv: &[String], workdir: &Path) -> Command {
    let program = Path::new(&argv[0]);
    let program = if program.is_relative() && argv[0].contains('/') {
        workdir.join(program)
    } else {
        program.to_path_buf()
    };
    let mut command = Command::new(program);
    command.args(&argv[1..]).current_dir(workdir);
    command
}

/// Runs job `index`, its stdout and stderr into its log files, and records its status.
fn run_job(sweep: &Sweep, index: usize, workdir: &Path) -> Result<RunStatus, ExperimentError> {
    let job = &sweep.jobs[index];
    let mut status = RunStatus::running(&job.id);
    write_status(&sweep.dir, &status)?;
    let (out, err) = log_paths(&sweep.dir, &job.id);
    if let Some(logs) = out.parent() {
        std::fs::create_dir_all(logs).map_err(ExperimentError::io(logs))?;
    }
    let open = |p: &Path| std::fs::File::create(p).map_err(ExperimentError::io(p));
    let (out_file, err_file) = (open(&out)?, open(&err)?);
    let start = Instant::now();
    let child = command(&job.argv, workdir)
        .stdin(Stdio::null())
        .stdout(out_file)
        .stderr(err_file)
        .spawn();
    let exit = child.and_then(|mut c| c.wait());
    status.seconds = start.elapsed().as_secs_f64();
    match exit {
        Ok(exit) => {
            status.exit_code = exit.code();
            status.signal = signal(&exit);
            status.state = if exit.success() {
                RunState::Done
            } else {
                RunState::Failed
            };
            status.stderr_tail = tail(&err);
        }
        Err(e) => {
            status.state = RunState::Failed;
            status.stderr_tail = format!("could not run {}: {e}\n", job.argv[0]);
        }
    }
    write_status(&sweep.dir, &status)?;
    Ok(status)
}

/// The signal that ended a process.
#[cfg(unix)]
fn signal(exit: &std::process::ExitStatus) -> Option<i32> {
    std::os::unix::process::ExitStatusExt::signal(exit)
}

/// The signal that ended a process (none off Unix).
#[cfg(not(unix))]
fn signal(_: &std::process::ExitStatus) -> Option<i32> {
    None
}
