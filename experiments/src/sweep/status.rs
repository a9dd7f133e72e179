//! The recorded state of every job of a sweep: `status/<id>.json` (running, done, or failed
//! with its exit code and the tail of its stderr) and `logs/<id>.out` / `.err`, and the
//! sweep's [`Progress`] (how many done, failed, left).

use std::fmt;
use std::io::{Read as _, Seek as _, SeekFrom};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::sweep::joblist::{read_bounded, write_atomic, Sweep};
use crate::ExperimentError;

/// The folder of a sweep directory holding one `<id>.json` [`RunStatus`] per job that started.
pub const STATUS_DIR: &str = "status";
/// The folder of a sweep directory holding each job's `<id>.out` and `<id>.err`.
pub const LOG_DIR: &str = "logs";
/// How much of the end of a failed job's stderr its status keeps, in bytes.
const TAIL_BYTES: u64 = 2048;

/// Where a job is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RunState {
    /// Started and not finished (or its runner was killed: a resumed run starts it again).
    Running,
    /// Exited with code 0.
    Done,
    /// Exited with another code, was killed by a signal, or could not start.
    Failed,
}

/// `status/<id>.json`: what became of one job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunStatus {
    /// The job's id.
    pub id: String,
    /// Where it is.
    pub state: RunState,
    /// Its exit code, once it exited.
    pub exit_code: Option<i32>,
    /// The signal that killed it, if one did.
    pub signal: Option<i32>,
    /// Wall-clock seconds from start to exit (0 while running).
    pub seconds: f64,
    /// The machine it ran on.
    pub host: String,
    /// The last lines of its stderr (at most 2 KiB), or why it could not start.
    pub stderr_tail: String,
}

impl RunStatus {
    /// A job that just started on this machine.
    #[must_use]
    pub fn running(id: &str) -> Self {
        Self {
            id: id.to_owned(),
            state: RunState::Running,
            exit_code: None,
            signal: None,
            seconds: 0.0,
            host: hostname(),
            stderr_tail: String::new(),
        }
    }

    /// One line: `done in 4.2 s on node7`, `failed with exit code 3 ...: <last stderr line>`.
    #[must_use]
    pub fn summary(&self) -> String {
        let how = match (self.state, self.exit_code, self.signal) {
            (RunState::Running, ..) => return format!("running on {}", self.host),
            (RunState::Done, ..) => "done".to_owned(),
            (RunState::Failed, Some(code), _) => format!("failed with exit code {code}"),
            (RunState::Failed, None, Some(signal)) => format!("killed by signal {signal}"),
            (RunState::Failed, None, None) => "could not start".to_owned(),
        };
        let last = self
            .stderr_tail
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty());
        let mut line = format!("{how} in {:.1} s on {}", self.seconds, self.host);
        if let Some(last) = last.filter(|_| self.state == RunState::Failed) {
            line += &format!(": {}", last.trim());
        }
        line
    }
}

/// `dir/status/<id>.json`.
#[must_use]
pub fn status_path(dir: &Path, id: &str) -> PathBuf {
    dir.join(STATUS_DIR).join(format!("{id}.json"))
}

/// `dir/logs/<id>.out` and `dir/logs/<id>.err`.
#[must_use]
pub fn log_paths(dir: &Path, id: &str) -> (PathBuf, PathBuf) {
    let logs = dir.join(LOG_DIR);
    (
        logs.join(format!("{id}.out")),
        logs.join(format!("{id}.err")),
    )
}

/// The status of job `id`, `None` if it never started.
///
/// # Errors
/// [`ExperimentError::Io`] if the file exists but cannot be read, [`ExperimentError::Format`]
/// if it is not a status.
pub fn read_status(dir: &Path, id: &str) -> Result<Option<RunStatus>, ExperimentError> {
    let path = status_path(dir, id);
    if !path.exists() {
        return Ok(None);
    }
    let status: RunStatus = serde_json::from_str(&read_bounded(&path)?)
        .map_err(|e| ExperimentError::format(&path, e))?;
    if status.id != id {
        return Err(ExperimentError::format(
            &path,
            format!("holds the status of {:?}, not {id:?}", status.id),
        ));
    }
    Ok(Some(status))
}

/// Writes `status/<id>.json` (replaced atomically).
///
/// # Errors
/// [`ExperimentError::Io`] naming the file.
pub fn write_status(dir: &Path, status: &RunStatus) -> Result<(), ExperimentError> {
    let json = serde_json::to_string_pretty(status).expect("a status serialises");
    write_atomic(
        &status_path(dir, &status.id),
        format!("{json}\n").as_bytes(),
    )
}

/// The last 2 KiB of a file, from the first whole line (empty if it cannot be read).
#[must_use]
pub fn tail(path: &Path) -> String {
    let Ok(mut file) = std::fs::File::open(path) else {
        return String::new();
    };
    let len = file.metadata().map_or(0, |m| m.len());
    let start = len.saturating_sub(TAIL_BYTES);
    let mut bytes = Vec::new();
    let read = file
        .seek(SeekFrom::Start(start))
        .and_then(|_| file.take(TAIL_BYTES).read_to_end(&mut bytes));
    if read.is_err() {
        return String::new();
    }
    let text = String::from_utf8_lossy(&bytes);
    let text = match text.find('\n') {
        Some(i) if start > 0 => &text[i + 1..],
        _ => &text,
    };
    text.to_owned()
}

/// This machine's host name (`unknown` if it cannot be read).
fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_owned())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// How far a sweep is: jobs done, failed, running, and not started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Progress {
    /// Jobs that exited with code 0.
    pub done: usize,
    /// Jobs that failed.
    pub failed: usize,
    /// Jobs started and not finished.
    pub running: usize,
    /// Jobs never started (or whose status file is unreadable: they run again).
    pub pending: usize,
}

impl Progress {
    /// Every job's status (`None`: never started or unreadable, reported on stderr) and the
    /// counts.
    #[must_use]
    pub fn of(sweep: &Sweep) -> (Self, Vec<Option<RunStatus>>) {
        let mut progress = Self::default();
        let statuses: Vec<Option<RunStatus>> = sweep
            .jobs
            .iter()
            .map(|job| {
                read_status(&sweep.dir, &job.id).unwrap_or_else(|e| {
                    eprintln!("{e}; the job counts as not started");
                    None
                })
            })
            .collect();
        for s in &statuses {
            match s.as_ref().map(|s| s.state) {
                Some(RunState::Done) => progress.done += 1,
                Some(RunState::Failed) => progress.failed += 1,
                Some(RunState::Running) => progress.running += 1,
                None => progress.pending += 1,
            }
        }
        (progress, statuses)
    }

    /// Jobs not finished: running or not started.
    #[must_use]
    pub fn left(&self) -> usize {
        self.running + self.pending
    }

    /// Every job.
    #[must_use]
    pub fn total(&self) -> usize {
        self.done + self.failed + self.left()
    }
}

impl fmt::Display for Progress {
    /// `done 3, failed 1, left 8 (2 running)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "done {}, failed {}, left {}",
            self.done,
            self.failed,
            self.left()
        )?;
        if self.running > 0 {
            write!(f, " ({} running)", self.running)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_round_trip_and_summarise() {
        let dir = std::env::temp_dir().join(format!("experiments-status-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(read_status(&dir, "a/seed1").unwrap(), None);
        let mut s = RunStatus::running("a/seed1");
        assert!(s.summary().starts_with("running on "));
        (s.state, s.exit_code, s.seconds) = (RunState::Failed, Some(3), 1.25);
        s.stderr_tail = "warming up\nerror: no such scene\n\n".into();
        write_status(&dir, &s).unwrap();
        assert_eq!(read_status(&dir, "a/seed1").unwrap(), Some(s.clone()));
        let line = s.summary();
        assert!(
            line.starts_with("failed with exit code 3 in 1.2 s on "),
            "{line}"
        );
        assert!(line.ends_with(": error: no such scene"), "{line}");
        // Negative control: a status file of another job is refused, not taken for this one.
        std::fs::copy(status_path(&dir, "a/seed1"), status_path(&dir, "a/seed2")).unwrap();
        let e = read_status(&dir, "a/seed2").unwrap_err().to_string();
        assert!(e.contains("not \"a/seed2\""), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_tail_starts_at_a_whole_line_and_is_bounded() {
        let path =
            std::env::temp_dir().join(format!("experiments-tail-{}.txt", std::process::id()));
        let long: String = (0..1000).map(|i| format!("line {i}\n")).collect();
        std::fs::write(&path, &long).unwrap();
        let t = tail(&path);
        assert!(
            t.len() <= TAIL_BYTES as usize && t.starts_with("line ") && t.ends_with("line 999\n")
        );
        std::fs::write(&path, "short\n").unwrap();
        assert_eq!(tail(&path), "short\n");
        std::fs::remove_file(&path).ok();
        assert_eq!(tail(&path), "");
    }

    #[test]
    fn progress_counts_and_prints() {
        let p = Progress {
            done: 3,
            failed: 1,
            running: 2,
            pending: 6,
        };
        assert_eq!((p.left(), p.total()), (8, 12));
        assert_eq!(p.to_string(), "done 3, failed 1, left 8 (2 running)");
    }
}
