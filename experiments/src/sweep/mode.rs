//! Where an experiment's renders run ([`JobMode`]: here, or as a job list) and the id of one
//! run of a job list ([`RunId`]: a scene and a seed).

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

/// One run of an experiment's job list: every method, in order, on one scene with one seed.
///
/// A run is a (scene, seed) slot rather than a single render because a method's settings may
/// depend on the methods before it in the same slot ([`crate::RunContext::previous`]). Its
/// text form, `<scene>/seed<seed>`, is the job's id in `jobs.jsonl` and the value of
/// `--run-one`.
///
/// # Example
/// ```
/// use experiments::RunId;
///
/// let id: RunId = "cornell-glass/seed101".parse()?;
/// assert_eq!((id.scene.as_str(), id.seed), ("cornell-glass", 101));
/// assert_eq!(id.to_string(), "cornell-glass/seed101");
/// assert!("cornell/101".parse::<RunId>().is_err());
/// # Ok::<(), String>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RunId {
    /// The scene's name (a file stem: ASCII letters, digits, `-`, `_` and `.`, not starting
    /// with `.`).
    pub scene: String,
    /// The seed.
    pub seed: u64,
}

impl RunId {
    /// The run of `scene` with `seed`.
    #[must_use]
    pub fn new(scene: impl Into<String>, seed: u64) -> Self {
        Self {
            scene: scene.into(),
            seed,
        }
    }

    /// Whether `scene` can name a run (and a run directory): a non-empty file stem of ASCII
    /// letters, digits, `-`, `_` and `.` that does not start with `.`.
    #[must_use]
    pub fn is_scene_name(scene: &str) -> bool {
        let safe = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
        !scene.is_empty() && !scene.starts_with('.') && scene.chars().all(safe)
    }
}

impl fmt::Display for RunId {
    /// `<scene>/seed<seed>`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/seed{}", self.scene, self.seed)
    }
}

impl FromStr for RunId {
    type Err = String;

    /// Parses `<scene>/seed<seed>`.
    fn from_str(text: &str) -> Result<Self, String> {
        let bad = || format!("expected a run id SCENE/seedN (e.g. cornell/seed100), got {text:?}");
        let (scene, seed) = text.split_once('/').ok_or_else(bad)?;
        let seed = seed.strip_prefix("seed").ok_or_else(bad)?;
        if !Self::is_scene_name(scene)
            || seed.is_empty()
            || !seed.bytes().all(|b| b.is_ascii_digit())
        {
            return Err(bad());
        }
        let seed = seed.parse().map_err(|_| bad())?;
        Ok(Self::new(scene, seed))
    }
}

/// How [`crate::Experiment::execute`] runs an experiment: the `--emit-jobs`, `--run-one` and
/// `--collect` options of [`crate::CommonOptions`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum JobMode {
    /// Every render here, in this process (the default).
    #[default]
    Local,
    /// Render nothing: write the experiment's runs as a job list into this directory
    /// (`jobs.jsonl`, `sweep.json`, `slurm.sbatch`, `k8s-job.json`).
    Emit(PathBuf),
    /// Render one run of the job list and record it in the scene's run directory.
    RunOne(RunId),
    /// Render nothing: read the recorded runs of every scene and seed and write the results
    /// as a local run would.
    Collect,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_ids_round_trip_and_bad_ids_are_refused() {
        for text in ["cornell/seed0", "a.b_c-d/seed18446744073709551615"] {
            assert_eq!(text.parse::<RunId>().unwrap().to_string(), text);
        }
        for bad in [
            "",
            "cornell",
            "cornell/seed",
            "cornell/seed-1",
            "cornell/seed+1",
            "cornell/100",
            "/seed1",
            "../x/seed1",
            "a/b/seed1",
            ".hidden/seed1",
            "cornell/seed18446744073709551616",
        ] {
            let e = bad.parse::<RunId>().unwrap_err();
            assert!(e.contains("SCENE/seedN"), "{bad}: {e}");
        }
    }
}
