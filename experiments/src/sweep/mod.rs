//! Sweeps beyond one process: an experiment written as a job list (one self-contained
//! command per (scene, seed) run), the Slurm job-array script and the Kubernetes Indexed Job
//! manifest that run the list on a cluster, the local runner that runs it on one machine, and
//! the per-job status that shows a sweep's progress wherever it runs.
//!
//! A sweep directory holds:
//!
//! | file | content |
//! |---|---|
//! | `sweep.json` | [`SweepInfo`]: name, working directory, threads per job, the collect command |
//! | `jobs.jsonl` | one [`Job`] per line: `{"id": ..., "argv": [...], "out": ...}`; line `i` is Slurm array task `i` and Kubernetes completion index `i` |
//! | `slurm.sbatch` | [`slurm_script`]: `sbatch --array=0-(N-1)`, each task `chainlight sweep task DIR $SLURM_ARRAY_TASK_ID` |
//! | `k8s-job.json` | [`k8s_manifest`]: a `batch/v1` Job, `completionMode: Indexed`, each pod `chainlight sweep task DIR` (index from `JOB_COMPLETION_INDEX`) |
//! | `status/<id>.json` | [`RunStatus`]: running, done, or failed with its exit code and stderr tail |
//! | `logs/<id>.out`, `logs/<id>.err` | each job's output |
//!
//! [`run_local`] runs the list here with a bounded number of jobs at once, skipping jobs
//! already done (so it resumes) or running one job alone; [`run_task`] runs the one job of a
//! cluster task. An example writes its list with `--emit-jobs DIR` ([`crate::JobMode`],
//! [`crate::Experiment::execute`]).

mod emit;
mod experiment;
mod joblist;
mod k8s;
mod mode;
mod records;
mod runner;
mod slurm;
mod status;

pub use emit::{write_sweep_files, DEFAULT_IMAGE};
pub use joblist::{
    is_job_id, Job, Sweep, SweepInfo, JOBS_FILE, MAX_JOBS, SWEEP_FILE, SWEEP_FORMAT,
};
pub(crate) use joblist::{read_bounded, write_atomic};
pub use k8s::{k8s_manifest, write_k8s_manifest, K8sOptions, K8S_FILE};
pub use mode::{JobMode, RunId};
pub(crate) use records::Num;
pub use runner::{run_local, run_task, LocalRun, INDEX_VARIABLES};
pub use slurm::{slurm_script, SLURM_FILE};
pub use status::{
    log_paths, read_status, status_path, tail, write_status, Progress, RunState, RunStatus,
    LOG_DIR, STATUS_DIR,
};
