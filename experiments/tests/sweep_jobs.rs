//! An experiment run as a job list (`--emit-jobs`, one `--run-one` per run, `--collect`)
//! gives the records, images and tables of the same experiment run in one process; collecting
//! refuses missing, mismatched and truncated records.

use std::path::{Path, PathBuf};

use experiments::sweep::{Sweep, JOBS_FILE, K8S_FILE, SLURM_FILE};
use experiments::{
    Column, Defaults, Experiment, JobMode, Measure, Method, Plan, Regime, Results, RunId,
    SceneCase, TableSpec,
};
use render::session::{IntegratorKind, RenderSettings};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("experiments-sweep-jobs-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn method(name: &str, integrator: IntegratorKind) -> Method {
    let settings = RenderSettings {
        method: integrator.settings(),
        max_depth: 4,
        ..RenderSettings::default()
    };
    Method::new(name, settings)
}

/// PT and PSSMLT (with acceptance statistics and convergence renders) on the Cornell box at
/// 8 x 8, seeds 3 and 4, 4 samples per pixel, in `mode`.
fn experiment(
    out: &Path,
    mode: JobMode,
    methods: &[(&str, IntegratorKind)],
) -> Experiment<'static> {
    let plan = Plan {
        seeds: vec![3, 4],
        size: 8,
        threads: 2,
        out: out.to_path_buf(),
        jobs: mode,
        ..Plan::from_defaults(&Defaults::new("sweep-test", Regime::EqualSamples(4)))
    };
    Experiment::new(plan)
        .methods(methods.iter().map(|&(n, i)| method(n, i)))
        .baseline("PT")
        .convergence(&[0.5])
        .scenes(vec![SceneCase::cornell_box(8, 16).unwrap()])
        .command_line([
            "target/release/examples/demo",
            "--spp",
            "4",
            "--emit-jobs",
            "jobs",
        ])
}

const METHODS: [(&str, IntegratorKind); 2] = [
    ("PT", IntegratorKind::Pt),
    ("PSSMLT", IntegratorKind::Pssmlt),
];

/// The error table without timing columns (the same for equal-sample runs anywhere).
fn error_table(results: &Results) -> String {
    let spec = TableSpec::new([
        Column::range(Measure::RelMse),
        Column::range(Measure::Mse),
        Column::range(Measure::Mad),
        Column::median(Measure::Acceptance),
        Column::ratio(Measure::RelMse),
    ]);
    results.table("cornell-box", &spec).to_markdown()
}

#[test]
fn a_job_list_run_collects_to_the_results_of_a_run_here() {
    let (local_out, jobs_out) = (scratch("local"), scratch("jobs"));
    let local = experiment(&local_out, JobMode::Local, &METHODS)
        .execute()
        .unwrap()
        .expect("results of a run here");

    let dir = jobs_out.join("jobs");
    let emitted = experiment(&jobs_out, JobMode::Emit(dir.clone()), &METHODS).execute();
    assert!(emitted.unwrap().is_none());
    let sweep = Sweep::load(&dir).unwrap();
    let ids: Vec<&str> = sweep.jobs.iter().map(|j| j.id.as_str()).collect();
    assert_eq!(ids, ["cornell-box/seed3", "cornell-box/seed4"]);
    for job in &sweep.jobs {
        let tail = ["--spp", "4", "--run-one", job.id.as_str()];
        assert_eq!(job.argv[0], "target/release/examples/demo");
        assert_eq!(
            job.argv[1..],
            tail,
            "the emit option is dropped, --run-one added"
        );
    }
    let collect = sweep.info.collect.clone().unwrap();
    assert_eq!(collect.last().map(String::as_str), Some("--collect"));
    let script = std::fs::read_to_string(dir.join(SLURM_FILE)).unwrap();
    assert!(script.contains("#SBATCH --array=0-1\n"), "{script}");
    assert!(dir.join(K8S_FILE).is_file() && dir.join(JOBS_FILE).is_file());

    // Negative control: nothing to collect before the runs.
    let e = experiment(&jobs_out, JobMode::Collect, &METHODS)
        .execute()
        .map(drop);
    let e = e.unwrap_err().to_string();
    assert!(e.contains("2 of the 2 runs have no record"), "{e}");

    // The runs, in the opposite order of a run here: the order changes nothing.
    for seed in [4, 3] {
        let id = RunId::new("cornell-box", seed);
        let done = experiment(&jobs_out, JobMode::RunOne(id), &METHODS).execute();
        assert!(done.unwrap().is_none());
    }
    let collected = experiment(&jobs_out, JobMode::Collect, &METHODS)
        .execute()
        .unwrap()
        .expect("collected results");

    assert_eq!(collected.records.len(), 4);
    for (a, b) in local.records.iter().zip(&collected.records) {
        let what = format!("{} seed {}", a.method, a.seed);
        assert_eq!((&a.scene, &a.method, a.seed), (&b.scene, &b.method, b.seed));
        assert_eq!(a.samples, b.samples, "{what}");
        assert_eq!(a.metrics, b.metrics, "{what}");
        assert_eq!(a.stats, b.stats, "{what}");
        assert_eq!(a.image, b.image, "{what}");
        assert_eq!(a.convergence.len(), b.convergence.len(), "{what}");
        let image = |out: &Path| std::fs::read(out.join("cornell-box").join(&a.image)).unwrap();
        assert!(
            image(&local_out) == image(&jobs_out),
            "{what}: the EXRs differ"
        );
    }
    assert!(local.records.iter().any(|r| r.stats.acceptance.is_some()));
    assert_eq!(error_table(&local), error_table(&collected));
    assert!(collected.markdown().contains("collected from 2 runs"));
    assert!(jobs_out.join("cornell-box/run.json").is_file());
    assert!(jobs_out.join("cornell-box/report.html").is_file());

    // Negative controls: a record of another method list, a tampered size, a truncated file.
    let more = [METHODS[0], METHODS[1], ("BDPT", IntegratorKind::Bdpt)];
    let e = experiment(&jobs_out, JobMode::Collect, &more)
        .execute()
        .map(drop);
    let e = e.unwrap_err().to_string();
    assert!(e.contains("seed3.json") && e.contains("the methods"), "{e}");
    let record = jobs_out.join("cornell-box/runs/seed4.json");
    let text = std::fs::read_to_string(&record).unwrap();
    std::fs::write(&record, text.replace("\"size\": 8", "\"size\": 16")).unwrap();
    let e = experiment(&jobs_out, JobMode::Collect, &METHODS)
        .execute()
        .map(drop);
    let e = e.unwrap_err().to_string();
    assert!(e.contains("seed4.json") && e.contains("the size 16"), "{e}");
    std::fs::write(&record, &text[..text.len() / 2]).unwrap();
    let e = experiment(&jobs_out, JobMode::Collect, &METHODS)
        .execute()
        .map(drop);
    let e = e.unwrap_err().to_string();
    assert!(e.contains("seed4.json"), "{e}");
    std::fs::remove_dir_all(local_out.parent().unwrap()).ok();
}

#[test]
fn job_modes_are_refused_where_they_cannot_work() {
    let out = scratch("refused");
    let e = experiment(&out, JobMode::Collect, &METHODS)
        .inspect(|_, _, _| {})
        .execute()
        .map(drop)
        .unwrap_err();
    assert!(e.to_string().contains("inspects every render"), "{e}");
    let e = experiment(&out, JobMode::Emit(out.join("j")), &METHODS)
        .run()
        .map(drop)
        .unwrap_err();
    assert!(e.to_string().contains("does not take --emit-jobs"), "{e}");
    let id = RunId::new("cornell-box", 99);
    let e = experiment(&out, JobMode::RunOne(id), &METHODS)
        .execute()
        .map(drop);
    assert!(e.unwrap_err().to_string().contains("seed 99 is not one of"));
    let id = RunId::new("other", 3);
    let e = experiment(&out, JobMode::RunOne(id), &METHODS)
        .execute()
        .map(drop);
    assert!(e.unwrap_err().to_string().contains("scene \"other\""));
    // Positive control: the same experiment runs here.
    assert!(experiment(&out, JobMode::Local, &METHODS[..1])
        .run()
        .is_ok());
    std::fs::remove_dir_all(&out).ok();
}
