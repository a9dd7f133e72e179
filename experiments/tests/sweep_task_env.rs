//! A cluster task finds its job index in the environment: `JOB_COMPLETION_INDEX` (Kubernetes
//! Indexed Job) before `SLURM_ARRAY_TASK_ID` (Slurm array). Alone in its test binary: it sets
//! environment variables, which no other thread may read meanwhile.

use experiments::sweep::{run_task, Job, RunState, Sweep, SweepInfo, SWEEP_FORMAT};

#[test]
fn the_index_comes_from_kubernetes_then_slurm() {
    let work = std::env::temp_dir().join(format!("experiments-sweep-env-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    let job = |id: &str| Job {
        id: id.into(),
        argv: vec!["sh".into(), "-c".into(), format!("echo {id} >> ran")],
        out: None,
    };
    let info = SweepInfo {
        format: SWEEP_FORMAT.into(),
        name: "env".into(),
        cwd: work.clone(),
        threads: 1,
        collect: None,
        runner: "chainlight".into(),
    };
    let sweep = Sweep::new(work.join("jobs"), info, vec![job("a"), job("b"), job("c")]).unwrap();
    let ran = || std::fs::read_to_string(work.join("ran")).unwrap_or_default();
    // Negative control: no index anywhere.
    let e = run_task(&sweep, None, None, false).unwrap_err().to_string();
    assert!(
        e.contains("JOB_COMPLETION_INDEX") && e.contains("SLURM_ARRAY_TASK_ID"),
        "{e}"
    );
    std::env::set_var("SLURM_ARRAY_TASK_ID", "2");
    assert_eq!(
        run_task(&sweep, None, None, false).unwrap().state,
        RunState::Done
    );
    assert_eq!(ran(), "c\n");
    std::env::set_var("JOB_COMPLETION_INDEX", "1");
    run_task(&sweep, None, None, false).unwrap();
    assert_eq!(ran(), "c\nb\n", "Kubernetes' index wins");
    std::env::set_var("JOB_COMPLETION_INDEX", "one");
    let e = run_task(&sweep, None, None, false).unwrap_err().to_string();
    assert!(
        e.contains("JOB_COMPLETION_INDEX=\"one\" is not a job index"),
        "{e}"
    );
    std::fs::remove_dir_all(&work).ok();
}
