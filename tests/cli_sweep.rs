//! CLI tests of `chainlight sweep`: a job list run here with a failure reported and re-run
//! alone, the progress shown by `status`, a cluster task's index, the Kubernetes manifest,
//! and bad input named by the flag or file at fault.

mod common;

use std::path::Path;
use std::process::Command;

use common::{assert_fails_with, chainlight, path_str, stderr, stdout, temp_dir};
use experiments::sweep::{Job, Sweep, SweepInfo, K8S_FILE, SWEEP_FORMAT};

/// A sweep in `work/jobs` of shell jobs run in `work`.
fn write_sweep(work: &Path, jobs: &[(&str, &str)]) -> String {
    let info = SweepInfo {
        format: SWEEP_FORMAT.into(),
        name: "cli-sweep".into(),
        cwd: work.to_path_buf(),
        threads: 1,
        collect: Some(vec![
            "sh".into(),
            "-c".into(),
            "echo collected > collected".into(),
        ]),
        runner: "chainlight".into(),
    };
    let jobs = jobs
        .iter()
        .map(|(id, script)| Job {
            id: (*id).into(),
            argv: vec!["sh".into(), "-c".into(), (*script).into()],
            out: None,
        })
        .collect();
    let sweep = Sweep::new(work.join("jobs"), info, jobs).unwrap();
    sweep.write().unwrap();
    path_str(&sweep.dir).to_owned()
}

#[test]
fn a_failed_job_is_reported_and_rerun_alone() {
    let work = temp_dir("sweep-run");
    let dir = write_sweep(
        &work,
        &[("ok", "true"), ("bad", "echo 'error: boom' >&2; exit 3")],
    );
    let run = chainlight(&["sweep", "run", &dir, "--parallel", "2"]);
    assert!(!run.status.success());
    let err = stderr(&run);
    assert!(
        err.contains("failed: bad (failed with exit code 3"),
        "{err}"
    );
    assert!(
        err.contains("error: boom") && err.contains("--only bad"),
        "{err}"
    );
    assert!(err.contains("done 1, failed 1, left 0"), "{err}");
    assert!(!work.join("collected").exists());
    let status = stdout(&chainlight(&["sweep", "status", &dir]));
    assert!(
        status.contains("(2 jobs): done 1, failed 1, left 0"),
        "{status}"
    );
    assert!(
        status.contains("failed   bad: failed with exit code 3"),
        "{status}"
    );

    // The job fixed, re-run alone; then the sweep completes and collects.
    write_sweep(&work, &[("ok", "true"), ("bad", "true")]);
    let only = chainlight(&["sweep", "run", &dir, "--only", "bad"]);
    assert!(only.status.success(), "{}", stderr(&only));
    assert!(!work.join("collected").exists(), "--only does not collect");
    let rest = chainlight(&["sweep", "run", &dir]);
    assert!(rest.status.success(), "{}", stderr(&rest));
    assert!(stderr(&rest).contains("running 0"), "{}", stderr(&rest));
    assert!(work.join("collected").is_file());
    std::fs::remove_dir_all(&work).ok();
}

#[test]
fn a_task_takes_its_index_from_the_argument_or_the_scheduler() {
    let work = temp_dir("sweep-task");
    let dir = write_sweep(&work, &[("a", "echo a >> ran"), ("b", "echo b >> ran")]);
    let task = |index: Option<&str>, env: Option<(&str, &str)>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_chainlight"));
        c.args(["sweep", "task", &dir]).args(index);
        c.env_remove("JOB_COMPLETION_INDEX")
            .env_remove("SLURM_ARRAY_TASK_ID");
        if let Some((k, v)) = env {
            c.env(k, v);
        }
        c.output().unwrap()
    };
    let none = task(None, None);
    assert!(!none.status.success());
    assert!(
        stderr(&none).contains("JOB_COMPLETION_INDEX"),
        "{}",
        stderr(&none)
    );
    assert!(task(Some("1"), None).status.success());
    assert!(task(None, Some(("JOB_COMPLETION_INDEX", "0")))
        .status
        .success());
    let ran = std::fs::read_to_string(work.join("ran")).unwrap();
    assert_eq!(ran, "b\na\n");
    let beyond = task(Some("2"), None);
    assert!(
        stderr(&beyond).contains("index 2 is beyond the 2 jobs"),
        "{}",
        stderr(&beyond)
    );
    std::fs::remove_dir_all(&work).ok();
}

#[test]
fn the_manifest_is_written_and_bad_input_is_named() {
    let work = temp_dir("sweep-k8s");
    let dir = write_sweep(&work, &[("a", "true")]);
    let out = chainlight(&["sweep", "k8s", &dir, "--image", "registry.example/cl:1"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let manifest = std::fs::read_to_string(Path::new(&dir).join(K8S_FILE)).unwrap();
    assert!(
        manifest.contains("\"completionMode\": \"Indexed\""),
        "{manifest}"
    );
    assert!(manifest.contains("registry.example/cl:1"));
    assert_fails_with(&["sweep", "k8s", &dir, "--image", ""], &["--image"]);
    assert_fails_with(&["sweep", "run", &dir, "--parallel", "0"], &["--parallel"]);
    assert_fails_with(&["sweep", "run", &dir, "--only", "zz"], &["no job \"zz\""]);
    let missing = work.join("nowhere");
    assert_fails_with(&["sweep", "status", path_str(&missing)], &["sweep.json"]);
    std::fs::write(
        Path::new(&dir).join("jobs.jsonl"),
        "{\"id\": \"a\", \"argv\": [\n",
    )
    .unwrap();
    assert_fails_with(&["sweep", "run", &dir], &["jobs.jsonl", "line 1"]);
    std::fs::remove_dir_all(&work).ok();
}
