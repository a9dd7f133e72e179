//! The local runner of a job list: bounded concurrency, per-job status with exit code and
//! stderr tail, resuming (jobs done are skipped), one job re-run alone, the collect command
//! only once every job is done; and the task runner of a cluster node.

use std::path::{Path, PathBuf};

use experiments::sweep::{
    read_status, run_local, run_task, Job, LocalRun, Progress, RunState, Sweep, SweepInfo,
    SWEEP_FORMAT,
};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("experiments-sweep-runner-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn sh(id: &str, script: &str) -> Job {
    Job {
        id: id.into(),
        argv: vec!["sh".into(), "-c".into(), script.into()],
        out: None,
    }
}

/// A sweep in `work/jobs` whose jobs run in `work`.
fn sweep(work: &Path, jobs: Vec<Job>) -> Sweep {
    let info = SweepInfo {
        format: SWEEP_FORMAT.into(),
        name: "runner-test".into(),
        cwd: work.to_path_buf(),
        threads: 1,
        collect: Some(vec![
            "sh".into(),
            "-c".into(),
            "echo collected > collected".into(),
        ]),
        runner: "chainlight".into(),
    };
    let sweep = Sweep::new(work.join("jobs"), info, jobs).unwrap();
    sweep.write().unwrap();
    Sweep::load(work.join("jobs")).unwrap()
}

fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |t| t.lines().count())
}

#[test]
fn failures_are_recorded_resumed_and_rerun_alone() {
    let work = scratch("resume");
    let jobs = vec![
        sh("ok/a", "echo run >> count-a"),
        sh(
            "bad/b",
            "echo warming up >&2; echo 'error: boom' >&2; exit 3",
        ),
        sh("ok/c", "echo run >> count-c"),
        Job {
            id: "missing".into(),
            argv: vec!["./no-such-program".into()],
            out: None,
        },
    ];
    let s = sweep(&work, jobs);
    let options = LocalRun {
        parallel: 2,
        ..LocalRun::default()
    };
    let p = run_local(&s, &options).unwrap();
    assert_eq!((p.done, p.failed, p.left()), (2, 2, 0));
    let b = read_status(&s.dir, "bad/b").unwrap().unwrap();
    assert_eq!((b.state, b.exit_code), (RunState::Failed, Some(3)));
    assert!(
        b.stderr_tail.ends_with("error: boom\n"),
        "{:?}",
        b.stderr_tail
    );
    assert!(b.summary().contains("exit code 3") && b.summary().ends_with("error: boom"));
    let m = read_status(&s.dir, "missing").unwrap().unwrap();
    assert_eq!((m.state, m.exit_code), (RunState::Failed, None));
    assert!(m.stderr_tail.contains("could not run ./no-such-program"));
    assert!(
        !work.join("collected").exists(),
        "collect waits for every job"
    );

    // Resuming skips the jobs done and runs the failed ones again.
    let p = run_local(&s, &options).unwrap();
    assert_eq!((p.done, p.failed), (2, 2));
    assert_eq!(
        (lines(&work.join("count-a")), lines(&work.join("count-c"))),
        (1, 1)
    );

    // The failed jobs fixed: one re-run alone (no collect), then the rest, then collect.
    let fixed = vec![
        sh("ok/a", "echo run >> count-a"),
        sh("bad/b", "true"),
        sh("ok/c", "echo run >> count-c"),
        sh("missing", "true"),
    ];
    let s = sweep(&work, fixed);
    let only = LocalRun {
        only: Some("bad/b".into()),
        ..LocalRun::default()
    };
    let p = run_local(&s, &only).unwrap();
    assert_eq!((p.done, p.failed), (3, 1));
    assert!(!work.join("collected").exists());
    let p = run_local(&s, &LocalRun::default()).unwrap();
    assert_eq!((p.done, p.failed, p.left()), (4, 0, 0));
    assert_eq!(Progress::of(&s).0, p);
    assert!(
        work.join("collected").is_file(),
        "collect after the last job"
    );
    assert_eq!(
        lines(&work.join("count-a")),
        1,
        "a job done never runs again"
    );

    // --only runs a job whatever its state.
    run_local(
        &s,
        &LocalRun {
            only: Some("ok/a".into()),
            ..LocalRun::default()
        },
    )
    .unwrap();
    assert_eq!(lines(&work.join("count-a")), 2);
    std::fs::remove_dir_all(&work).ok();
}

#[test]
fn parallel_jobs_overlap_and_sequential_ones_do_not() {
    // Each job records when it starts and ends (in the order of a shared log); two at a time
    // must interleave starts, one at a time must not. No clock is compared.
    for (parallel, overlap) in [(2, true), (1, false)] {
        let work = scratch(&format!("overlap-{parallel}"));
        let job = |id: &str| {
            // The job waits (bounded) until a partner has started, when one may run beside it.
            let wait = if parallel > 1 {
                "i=0; while [ $(grep -c start log) -lt 2 ] && [ $i -lt 200 ]; do sleep 0.05; i=$((i+1)); done"
            } else {
                "true"
            };
            sh(id, &format!("echo start >> log; {wait}; echo end >> log"))
        };
        let s = sweep(&work, vec![job("x"), job("y")]);
        let p = run_local(
            &s,
            &LocalRun {
                parallel,
                ..LocalRun::default()
            },
        )
        .unwrap();
        assert_eq!(p.done, 2);
        let log = std::fs::read_to_string(work.join("log")).unwrap();
        let order: Vec<&str> = log.lines().collect();
        assert_eq!(
            order == ["start", "start", "end", "end"],
            overlap,
            "{parallel}: {order:?}"
        );
        std::fs::remove_dir_all(&work).ok();
    }
}

#[test]
fn the_task_runner_runs_one_index_and_refuses_bad_ones() {
    let work = scratch("task");
    let s = sweep(&work, vec![sh("a", "echo run >> count"), sh("b", "exit 4")]);
    let status = run_task(&s, Some(0), None, false).unwrap();
    assert_eq!(status.state, RunState::Done);
    // Done: skipped unless forced.
    run_task(&s, Some(0), None, false).unwrap();
    assert_eq!(lines(&work.join("count")), 1);
    run_task(&s, Some(0), None, true).unwrap();
    assert_eq!(lines(&work.join("count")), 2);
    let failed = run_task(&s, Some(1), None, false).unwrap();
    assert_eq!(
        (failed.state, failed.exit_code),
        (RunState::Failed, Some(4))
    );
    let e = run_task(&s, Some(2), None, false).unwrap_err().to_string();
    assert!(e.contains("index 2 is beyond the 2 jobs"), "{e}");
    let e = run_task(&s, Some(0), Some(&work.join("nowhere")), false).unwrap_err();
    assert!(e.to_string().contains("does not exist here"), "{e}");
    let e = run_local(
        &s,
        &LocalRun {
            only: Some("zz".into()),
            ..LocalRun::default()
        },
    );
    assert!(e.unwrap_err().to_string().contains("no job \"zz\""));
    std::fs::remove_dir_all(&work).ok();
}
