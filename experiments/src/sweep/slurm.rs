//! The Slurm job-array script of a sweep (`slurm.sbatch`): array task `i` runs job `i` of the
//! job list through `chainlight sweep task`, which records its status in the sweep directory.

use std::fmt::Write as _;
use std::path::Path;

use crate::sweep::joblist::Sweep;
use crate::sweep::status::LOG_DIR;

/// The job-array script's file name in a sweep directory.
pub const SLURM_FILE: &str = "slurm.sbatch";
/// Slurm's default `MaxArraySize`: array indices must be below it.
const SLURM_DEFAULT_MAX_ARRAY_SIZE: usize = 1001;

/// The `sbatch` script running `sweep` as one job array: `--array=0-(N-1)`, one CPU per render
/// thread, the jobs' working directory as `--chdir`, each task's Slurm log in the sweep's
/// `logs/`. `sweep.dir` and the working directory must be absolute paths every node sees (a
/// shared filesystem, as on any cluster's home or scratch).
///
/// # Example
/// ```
/// use experiments::sweep::{slurm_script, Job, Sweep, SweepInfo, SWEEP_FORMAT};
///
/// let info = SweepInfo {
///     format: SWEEP_FORMAT.into(),
///     name: "zsolnai".into(),
///     cwd: "/home/me/chainlight".into(),
///     threads: 8,
///     collect: None,
///     runner: "target/release/chainlight".into(),
/// };
/// let job = |id: &str| Job { id: id.into(), argv: vec!["true".into()], out: None };
/// let sweep = Sweep::new("/home/me/chainlight/out/jobs", info, vec![job("a"), job("b")])?;
/// let script = slurm_script(&sweep);
/// assert!(script.contains("#SBATCH --array=0-1\n"));
/// assert!(script.contains("#SBATCH --cpus-per-task=8\n"));
/// assert!(script.contains("sweep task '/home/me/chainlight/out/jobs' \"$SLURM_ARRAY_TASK_ID\""));
/// # Ok::<(), experiments::ExperimentError>(())
/// ```
#[must_use]
pub fn slurm_script(sweep: &Sweep) -> String {
    let info = &sweep.info;
    let n = sweep.jobs.len();
    let dir = &sweep.dir;
    let mut s = String::from("#!/bin/bash\n");
    let _ = writeln!(
        s,
        "# The chainlight sweep {:?} as a Slurm job array: task i runs job i (line i + 1) of\n\
         # {}/jobs.jsonl through `chainlight sweep task`, which records its status in\n\
         # {}/status/. Submit: sbatch {}/{SLURM_FILE}\n\
         # (limit concurrent tasks: sbatch --array=0-{}%8 ...). Progress: chainlight sweep status DIR.\n\
         # Afterwards `chainlight sweep run DIR` re-runs what failed or never ran, then collects.",
        info.name,
        dir.display(),
        dir.display(),
        dir.display(),
        n - 1
    );
    if n > SLURM_DEFAULT_MAX_ARRAY_SIZE {
        let _ = writeln!(
            s,
            "# {n} tasks exceed Slurm's default MaxArraySize ({SLURM_DEFAULT_MAX_ARRAY_SIZE}): ask the\n\
             # administrators, or submit in slices (--array=0-999, then 1000-1999 after raising the limit)."
        );
    }
    let _ = writeln!(s, "#SBATCH --job-name={}", slurm_word(&info.name));
    let _ = writeln!(s, "#SBATCH --array=0-{}", n - 1);
    let _ = writeln!(s, "#SBATCH --ntasks=1");
    let _ = writeln!(s, "#SBATCH --cpus-per-task={}", info.threads.max(1));
    let _ = writeln!(s, "#SBATCH --chdir={}", info.cwd.display());
    let _ = writeln!(
        s,
        "#SBATCH --output={}/{LOG_DIR}/slurm-%A_%a.out",
        dir.display()
    );
    s.push_str("set -u\n");
    let _ = writeln!(
        s,
        "exec \"${{CHAINLIGHT:-{}}}\" sweep task {} \"$SLURM_ARRAY_TASK_ID\"",
        info.runner,
        shell_quote(dir)
    );
    s
}

/// `path` quoted for a POSIX shell.
fn shell_quote(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', "'\\''"))
}

/// `name` with every character other than an ASCII letter, digit, `-`, `_` or `.` replaced
/// by `_` (a job name without quoting).
fn slurm_word(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_survives_quotes_and_names_are_single_words() {
        assert_eq!(shell_quote(Path::new("/a b/it's")), "'/a b/it'\\''s'");
        assert_eq!(slurm_word("zsolnai large step!"), "zsolnai_large_step_");
    }
}
