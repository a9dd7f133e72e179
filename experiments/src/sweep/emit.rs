//! Writing an experiment as a job list: one job per (scene, seed) run, each the example's own
//! command line with `--run-one <id>` in place of `--emit-jobs DIR`, plus the Slurm script and
//! the Kubernetes manifest of the list.

use std::path::{Path, PathBuf};

use crate::plan::Plan;
use crate::sweep::joblist::write_atomic;
use crate::sweep::joblist::{Job, Sweep, SweepInfo, SWEEP_FORMAT};
use crate::sweep::k8s::{write_k8s_manifest, K8sOptions};
use crate::sweep::mode::RunId;
use crate::sweep::slurm::{slurm_script, SLURM_FILE};
use crate::sweep::status::LOG_DIR;
use crate::ExperimentError;

/// The image the emitted Kubernetes manifest names until `chainlight sweep k8s --image` says
/// otherwise.
pub const DEFAULT_IMAGE: &str = "chainlight:latest";

/// The sweep of `plan` on `scenes` into `dir`: a job per seed and scene (in the harness's
/// order, for seed, for scene), each `command_line` (the example's program and arguments)
/// without `--emit-jobs DIR` and with `--run-one <id>`; the collect command the same with
/// `--collect`. The program path is made relative to the working directory when it lies
/// inside it, so the list works wherever the checkout is.
pub(crate) fn experiment_sweep(
    plan: &Plan,
    scenes: &[String],
    dir: &Path,
    command_line: &[String],
) -> Result<Sweep, ExperimentError> {
    let cwd = std::env::current_dir().map_err(ExperimentError::io("."))?;
    std::fs::create_dir_all(dir).map_err(ExperimentError::io(dir))?;
    let dir = std::fs::canonicalize(dir).map_err(ExperimentError::io(dir))?;
    let Some((program, args)) = command_line.split_first() else {
        return Err(ExperimentError::Invalid("an empty command line".into()));
    };
    let program = relative_program(program, &cwd);
    let args = without_emit(args);
    let command = |extra: &[String]| {
        let mut argv = vec![program.clone()];
        argv.extend(args.iter().cloned());
        argv.extend(extra.iter().cloned());
        argv
    };
    let mut jobs = Vec::new();
    for &seed in &plan.seeds {
        for scene in scenes {
            let id = RunId::new(scene.clone(), seed).to_string();
            jobs.push(Job {
                argv: command(&["--run-one".into(), id.clone()]),
                id,
                out: Some(plan.out.join(scene)),
            });
        }
    }
    let info = SweepInfo {
        format: SWEEP_FORMAT.into(),
        name: plan.name.clone(),
        runner: runner(&program, &cwd),
        cwd,
        threads: plan.threads,
        collect: Some(command(&["--collect".into()])),
    };
    Sweep::new(dir, info, jobs)
}

/// Writes `sweep`'s job list, its Slurm script and its Kubernetes manifest (image
/// [`DEFAULT_IMAGE`]) and creates its log folder.
///
/// # Errors
/// [`ExperimentError::Io`] naming a file that cannot be written.
pub fn write_sweep_files(sweep: &Sweep) -> Result<(), ExperimentError> {
    sweep.write()?;
    let logs = sweep.dir.join(LOG_DIR);
    std::fs::create_dir_all(&logs).map_err(ExperimentError::io(&logs))?;
    write_atomic(&sweep.dir.join(SLURM_FILE), slurm_script(sweep).as_bytes())?;
    write_k8s_manifest(sweep, &K8sOptions::new(DEFAULT_IMAGE)).map(drop)
}

/// `args` without `--emit-jobs DIR` / `--emit-jobs=DIR`.
fn without_emit(args: &[String]) -> Vec<String> {
    let mut kept = Vec::with_capacity(args.len());
    let mut skip_value = false;
    for arg in args {
        if std::mem::take(&mut skip_value) {
            continue;
        }
        if arg == "--emit-jobs" {
            skip_value = true;
        } else if !arg.starts_with("--emit-jobs=") {
            kept.push(arg.clone());
        }
    }
    kept
}

/// The program as the jobs name it: relative to `cwd` when it lies inside it, absolute when
/// it is a path elsewhere, a bare name (looked up on `PATH`) as it is.
fn relative_program(program: &str, cwd: &Path) -> String {
    if !program.contains('/') {
        return program.to_owned();
    }
    let absolute = std::fs::canonicalize(program).unwrap_or_else(|_| cwd.join(program));
    absolute
        .strip_prefix(cwd)
        .map_or(absolute.clone(), Path::to_path_buf)
        .display()
        .to_string()
}

/// The `chainlight` binary next to the example's (`target/<profile>/chainlight` for
/// `target/<profile>/examples/<name>`), else `chainlight` on `PATH`.
fn runner(program: &str, cwd: &Path) -> String {
    let program = Path::new(program);
    let beside = program
        .parent()
        .filter(|p| p.ends_with("examples"))
        .and_then(Path::parent)
        .map(|profile| profile.join("chainlight"));
    match beside {
        Some(bin) if cwd.join(&bin).is_file() => bin.display().to_string(),
        _ => "chainlight".into(),
    }
}

/// The sweep directory's path as the jobs' messages show it.
pub(crate) fn shown(dir: &Path) -> PathBuf {
    std::env::current_dir()
        .ok()
        .and_then(|cwd| dir.strip_prefix(cwd).ok().map(Path::to_path_buf))
        .unwrap_or_else(|| dir.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_emit_option_is_removed_in_both_spellings() {
        let args: Vec<String> = [
            "--quick",
            "--emit-jobs",
            "d",
            "cornell",
            "--emit-jobs=e",
            "--spp",
            "4",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(without_emit(&args), ["--quick", "cornell", "--spp", "4"]);
    }

    #[test]
    fn programs_inside_the_checkout_become_relative() {
        let cwd = std::env::current_dir().unwrap();
        let inside = cwd.join("target/x/examples/demo");
        assert_eq!(
            relative_program(&inside.display().to_string(), &cwd),
            "target/x/examples/demo"
        );
        assert_eq!(
            relative_program("/elsewhere/bin/demo", &cwd),
            "/elsewhere/bin/demo"
        );
        assert_eq!(relative_program("demo", &cwd), "demo");
        assert_eq!(runner("/nowhere/examples/demo", &cwd), "chainlight");
    }
}
