//! A sweep directory's job list: `sweep.json` (what the sweep is and where its jobs run) and
//! `jobs.jsonl` (one self-contained command per line), read and written with validation.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::sweep::mode::RunId;
use crate::ExperimentError;

/// The job list in a sweep directory: one JSON object per line, a [`Job`] each.
pub const JOBS_FILE: &str = "jobs.jsonl";
/// The sweep's description in a sweep directory ([`SweepInfo`]).
pub const SWEEP_FILE: &str = "sweep.json";
/// The value of [`SweepInfo::format`] this version writes and reads.
pub const SWEEP_FORMAT: &str = "chainlight-sweep/1";
/// The most jobs a list may hold (a Kubernetes Indexed Job's limit on `completions`).
pub const MAX_JOBS: usize = 100_000;
/// The longest job id, in bytes.
const MAX_ID_LEN: usize = 200;
/// The largest `jobs.jsonl` or `sweep.json` read, in bytes.
const MAX_FILE_BYTES: u64 = 64 << 20;

/// One line of `jobs.jsonl`: a run that any machine with the same checkout can execute alone.
///
/// `{"id":"cornell/seed100","argv":["target/release/examples/zsolnai_large_step","--quick","--run-one","cornell/seed100"],"out":"out/zsolnai_large_step/cornell"}`
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Job {
    /// A stable id: `/`-separated parts of ASCII letters, digits, `-`, `_` and `.`, none
    /// empty or starting with `.` (it names the job's status and log files).
    pub id: String,
    /// The program and its arguments, run in the sweep's working directory
    /// ([`SweepInfo::cwd`]); a relative program path is relative to it.
    pub argv: Vec<String>,
    /// Where the job writes its results, relative to the working directory (informational).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub out: Option<PathBuf>,
}

/// `sweep.json`: what a sweep is and where its jobs run.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepInfo {
    /// [`SWEEP_FORMAT`].
    pub format: String,
    /// The sweep's name (the experiment's): the Slurm job name and the Kubernetes Job's.
    pub name: String,
    /// The working directory every job runs in (the repository root the sweep was written
    /// from); `--workdir` of the runners overrides it on a machine where the checkout lives
    /// elsewhere.
    pub cwd: PathBuf,
    /// Render threads of one job: the CPUs a scheduler should give each task.
    pub threads: usize,
    /// The command that reads every job's record and writes the sweep's results (run in
    /// [`SweepInfo::cwd`] after the last job), if the sweep has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collect: Option<Vec<String>>,
    /// The `chainlight` binary the generated scripts call (`chainlight sweep task`), relative
    /// to [`SweepInfo::cwd`] or found on `PATH`.
    pub runner: String,
}

/// A sweep directory: its description and its jobs, checked.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sweep {
    /// The sweep directory.
    pub dir: PathBuf,
    /// `sweep.json`.
    pub info: SweepInfo,
    /// `jobs.jsonl`, in order: job `i` is Slurm array task `i` and Kubernetes completion
    /// index `i`.
    pub jobs: Vec<Job>,
}

impl Sweep {
    /// A sweep of `jobs` in `dir`, checked.
    ///
    /// # Errors
    /// [`ExperimentError::Invalid`] for no jobs or more than [`MAX_JOBS`], a bad or duplicate
    /// id, an empty command, or a `sweep.json` of another format or without a name.
    pub fn new(
        dir: impl Into<PathBuf>,
        info: SweepInfo,
        jobs: Vec<Job>,
    ) -> Result<Self, ExperimentError> {
        let sweep = Self {
            dir: dir.into(),
            info,
            jobs,
        };
        sweep.check()?;
        Ok(sweep)
    }

    /// Reads `dir/sweep.json` and `dir/jobs.jsonl`.
    ///
    /// # Errors
    /// [`ExperimentError::Io`] for a missing or unreadable file; [`ExperimentError::Format`]
    /// naming the file and line of malformed JSON; [`ExperimentError::Invalid`] as
    /// [`Sweep::new`].
    pub fn load(dir: impl Into<PathBuf>) -> Result<Self, ExperimentError> {
        let dir = dir.into();
        let info_path = dir.join(SWEEP_FILE);
        let info: SweepInfo = serde_json::from_str(&read_bounded(&info_path)?)
            .map_err(|e| ExperimentError::format(&info_path, e))?;
        if info.format != SWEEP_FORMAT {
            return Err(ExperimentError::format(
                &info_path,
                format!("format {:?}, expected {SWEEP_FORMAT:?}", info.format),
            ));
        }
        let jobs_path = dir.join(JOBS_FILE);
        let text = read_bounded(&jobs_path)?;
        let mut jobs = Vec::new();
        for (i, line) in text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
        {
            let job: Job = serde_json::from_str(line)
                .map_err(|e| ExperimentError::format(&jobs_path, format!("line {}: {e}", i + 1)))?;
            jobs.push(job);
        }
        Self::new(dir, info, jobs).map_err(|e| match e {
            ExperimentError::Invalid(m) => ExperimentError::format(&jobs_path, m),
            other => other,
        })
    }

    /// Writes `sweep.json` and `jobs.jsonl` (each replaced atomically), creating the directory.
    ///
    /// # Errors
    /// [`ExperimentError::Io`] naming the file that could not be written.
    pub fn write(&self) -> Result<(), ExperimentError> {
        std::fs::create_dir_all(&self.dir).map_err(ExperimentError::io(&self.dir))?;
        let info = serde_json::to_string_pretty(&self.info).expect("sweep.json serialises");
        write_atomic(&self.dir.join(SWEEP_FILE), format!("{info}\n").as_bytes())?;
        let mut lines = String::new();
        for job in &self.jobs {
            lines += &serde_json::to_string(job).expect("a job serialises");
            lines.push('\n');
        }
        write_atomic(&self.dir.join(JOBS_FILE), lines.as_bytes())
    }

    /// The index of the job with `id`.
    #[must_use]
    pub fn index_of(&self, id: &str) -> Option<usize> {
        self.jobs.iter().position(|j| j.id == id)
    }

    /// The directory the jobs run in: `workdir` if given, else [`SweepInfo::cwd`].
    #[must_use]
    pub fn workdir(&self, workdir: Option<&Path>) -> PathBuf {
        workdir.map_or_else(|| self.info.cwd.clone(), Path::to_path_buf)
    }

    /// Checks what [`Sweep::new`] promises.
    fn check(&self) -> Result<(), ExperimentError> {
        let invalid = |m: String| Err(ExperimentError::Invalid(m));
        if self.info.format != SWEEP_FORMAT {
            return invalid(format!(
                "sweep format {:?}, expected {SWEEP_FORMAT:?}",
                self.info.format
            ));
        }
        if self.info.name.trim().is_empty() {
            return invalid("the sweep has no name".into());
        }
        if self.jobs.is_empty() || self.jobs.len() > MAX_JOBS {
            return invalid(format!(
                "{} jobs; a job list holds 1..={MAX_JOBS}",
                self.jobs.len()
            ));
        }
        let mut ids: Vec<&str> = Vec::with_capacity(self.jobs.len());
        for (i, job) in self.jobs.iter().enumerate() {
            if !is_job_id(&job.id) {
                return invalid(format!(
                    "job {i}: id {:?} is not 1..={MAX_ID_LEN} bytes of '/'-separated parts of ASCII letters, digits, '-', '_', '.' (none empty or starting with '.')",
                    job.id
                ));
            }
            if job.argv.first().is_none_or(|p| p.is_empty()) {
                return invalid(format!("job {:?} has no program", job.id));
            }
            ids.push(&job.id);
        }
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return invalid(format!("job id {:?} appears twice", w[0]));
        }
        Ok(())
    }
}

/// Whether `id` can name a job (and its status and log files).
#[must_use]
pub fn is_job_id(id: &str) -> bool {
    id.len() <= MAX_ID_LEN && id.split('/').all(RunId::is_scene_name)
}

/// Reads a text file of at most [`MAX_FILE_BYTES`].
pub(crate) fn read_bounded(path: &Path) -> Result<String, ExperimentError> {
    use std::io::Read as _;
    let file = std::fs::File::open(path).map_err(ExperimentError::io(path))?;
    let mut text = String::new();
    file.take(MAX_FILE_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(ExperimentError::io(path))?;
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(ExperimentError::format(
            path,
            format!("larger than {MAX_FILE_BYTES} bytes"),
        ));
    }
    Ok(text)
}

/// Writes `bytes` to `path` through a temporary file renamed over it, so a reader never sees
/// a half-written file and concurrent writers leave one whole version.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ExperimentError> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(ExperimentError::io(parent))?;
    }
    let name = path
        .file_name()
        .map_or_else(Default::default, |n| n.to_string_lossy());
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let written = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    written.map_err(ExperimentError::io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(ExperimentError::io(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info() -> SweepInfo {
        SweepInfo {
            format: SWEEP_FORMAT.into(),
            name: "t".into(),
            cwd: "/tmp".into(),
            threads: 2,
            collect: None,
            runner: "chainlight".into(),
        }
    }

    fn job(id: &str) -> Job {
        Job {
            id: id.into(),
            argv: vec!["true".into()],
            out: None,
        }
    }

    #[test]
    fn a_written_sweep_loads_back() {
        let dir = std::env::temp_dir().join(format!("experiments-joblist-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let sweep = Sweep::new(&dir, info(), vec![job("a/seed1"), job("b")]).unwrap();
        sweep.write().unwrap();
        assert_eq!(Sweep::load(&dir).unwrap(), sweep);
        assert_eq!(sweep.index_of("b"), Some(1));
        // Negative control: a truncated line is a format error naming the file and line.
        let text = std::fs::read_to_string(dir.join(JOBS_FILE)).unwrap();
        std::fs::write(dir.join(JOBS_FILE), &text[..text.len() - 5]).unwrap();
        let e = Sweep::load(&dir).unwrap_err().to_string();
        assert!(e.contains("jobs.jsonl") && e.contains("line 2"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn bad_job_lists_are_refused_naming_the_job() {
        let new = |jobs| {
            Sweep::new("d", info(), jobs)
                .map(drop)
                .unwrap_err()
                .to_string()
        };
        assert!(new(vec![]).contains("0 jobs"));
        assert!(new(vec![job("a"), job("a")]).contains("appears twice"));
        for bad in ["", "a//b", "../a", "/a", "a b", ".a", "a/.."] {
            assert!(new(vec![job(bad)]).contains("is not 1..="), "{bad:?}");
        }
        let mut empty = job("x");
        empty.argv.clear();
        assert!(new(vec![empty]).contains("\"x\" has no program"));
        let mut other = info();
        other.format = "chainlight-sweep/0".into();
        assert!(Sweep::new("d", other, vec![job("a")]).is_err());
    }
}
