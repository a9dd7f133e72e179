//! `chainlight sweep`: run a job list here (bounded, resumable, one job alone), run the one
//! job of a Slurm array task or Kubernetes pod, show a sweep's progress, or write its
//! Kubernetes manifest for an image.

use std::path::PathBuf;

use clap::{Args, Subcommand};
use experiments::sweep::{
    log_paths, run_local, run_task, write_k8s_manifest, K8sOptions, LocalRun, Progress, RunState,
    Sweep,
};

use super::CliResult;

/// The most failed jobs `sweep status` lists one by one.
const LISTED_FAILURES: usize = 20;

/// Arguments of `chainlight sweep`.
#[derive(Debug, Args)]
pub(crate) struct SweepArgs {
    #[command(subcommand)]
    command: SweepCommand,
}

/// The `sweep` subcommands; DIR is a sweep directory written by an example's `--emit-jobs`.
#[derive(Debug, Subcommand)]
enum SweepCommand {
    /// Run the jobs not done yet here, N at a time (a second run resumes), then the sweep's
    /// collect command; with --only, one job alone, whatever its state.
    Run {
        /// The sweep directory.
        #[arg(value_name = "DIR")]
        dir: PathBuf,
        /// Jobs running at once, 1..=256 (each job uses its own render threads).
        #[arg(short, long, value_name = "N", default_value_t = 1,
              value_parser = clap::value_parser!(u16).range(1..=256))]
        parallel: u16,
        /// Run only the job with this id (e.g. to re-run a failed run alone).
        #[arg(long, value_name = "ID")]
        only: Option<String>,
        /// Run the jobs in this directory instead of the one the sweep was written from.
        #[arg(long, value_name = "DIR")]
        workdir: Option<PathBuf>,
        /// Do not run the collect command after the last job.
        #[arg(long)]
        no_collect: bool,
    },
    /// Run one job: a Slurm array task or a Kubernetes Indexed Job pod. Skips a job already
    /// done unless --force.
    Task {
        /// The sweep directory.
        #[arg(value_name = "DIR")]
        dir: PathBuf,
        /// The job's index (line number from 0) [default: $JOB_COMPLETION_INDEX, else
        /// $SLURM_ARRAY_TASK_ID].
        #[arg(value_name = "INDEX")]
        index: Option<usize>,
        /// Run the job in this directory instead of the one the sweep was written from.
        #[arg(long, value_name = "DIR")]
        workdir: Option<PathBuf>,
        /// Run the job even if it is done.
        #[arg(long)]
        force: bool,
    },
    /// Show how many jobs are done, failed and left, and why each failed job failed.
    Status {
        /// The sweep directory.
        #[arg(value_name = "DIR")]
        dir: PathBuf,
    },
    /// Write DIR/k8s-job.json: the sweep as a Kubernetes Indexed Job running IMAGE.
    K8s {
        /// The sweep directory.
        #[arg(value_name = "DIR")]
        dir: PathBuf,
        /// The container image (the runtime, and the checkout unless a claim holds it).
        #[arg(long, value_name = "IMAGE")]
        image: String,
        /// Pods running at once, 1..=10000 (lowered to the number of jobs).
        #[arg(long, value_name = "N", default_value_t = 4,
              value_parser = clap::value_parser!(u16).range(1..=10_000))]
        parallelism: u16,
        /// A PersistentVolumeClaim with the shared files (the checkout or the outputs).
        #[arg(long, value_name = "NAME")]
        claim: Option<String>,
        /// Where the claim is mounted [default: the working directory].
        #[arg(long, value_name = "PATH", requires = "claim")]
        mount: Option<PathBuf>,
        /// The working directory in the container [default: the sweep's].
        #[arg(long, value_name = "PATH")]
        workdir: Option<PathBuf>,
    },
}

/// Runs a `sweep` subcommand.
pub(crate) fn run(args: SweepArgs) -> CliResult<()> {
    match args.command {
        SweepCommand::Run {
            dir,
            parallel,
            only,
            workdir,
            no_collect,
        } => {
            let sweep = Sweep::load(dir)?;
            let options = LocalRun {
                parallel: usize::from(parallel),
                only,
                workdir,
                collect: !no_collect,
            };
            let progress = run_local(&sweep, &options)?;
            if progress.failed > 0 {
                return Err(format!(
                    "sweep {}: {progress}; `chainlight sweep status {}` lists the failures",
                    sweep.info.name,
                    sweep.dir.display()
                )
                .into());
            }
            Ok(())
        }
        SweepCommand::Task {
            dir,
            index,
            workdir,
            force,
        } => {
            let sweep = Sweep::load(dir)?;
            let status = run_task(&sweep, index, workdir.as_deref(), force)?;
            if status.state != RunState::Done {
                return Err(format!("job {} {}", status.id, status.summary()).into());
            }
            Ok(())
        }
        SweepCommand::Status { dir } => status(&Sweep::load(dir)?),
        SweepCommand::K8s {
            dir,
            image,
            parallelism,
            claim,
            mount,
            workdir,
        } => {
            let sweep = Sweep::load(dir)?;
            let options = K8sOptions {
                image,
                parallelism: usize::from(parallelism),
                claim,
                mount,
                workdir,
            };
            let path = write_k8s_manifest(&sweep, &options)?;
            println!(
                "manifest   {}  (kubectl apply -f {})",
                path.display(),
                path.display()
            );
            Ok(())
        }
    }
}

/// Prints the sweep's progress, its failed jobs (with the end of their stderr) and the
/// running ones.
fn status(sweep: &Sweep) -> CliResult<()> {
    let (progress, statuses) = Progress::of(sweep);
    println!(
        "sweep {} ({} jobs): {progress}",
        sweep.info.name,
        progress.total()
    );
    let with = |state| {
        sweep
            .jobs
            .iter()
            .zip(&statuses)
            .filter_map(move |(job, s)| s.as_ref().filter(|s| s.state == state).map(|s| (job, s)))
    };
    for (job, s) in with(RunState::Failed).take(LISTED_FAILURES) {
        println!("failed   {}: {}", job.id, s.summary());
        println!(
            "         log: {}",
            log_paths(&sweep.dir, &job.id).1.display()
        );
        println!(
            "         re-run alone: chainlight sweep run {} --only {}",
            sweep.dir.display(),
            job.id
        );
    }
    if progress.failed > LISTED_FAILURES {
        println!(
            "...and {} more failed jobs",
            progress.failed - LISTED_FAILURES
        );
    }
    for (job, s) in with(RunState::Running) {
        println!("running  {}: {}", job.id, s.summary());
    }
    Ok(())
}
