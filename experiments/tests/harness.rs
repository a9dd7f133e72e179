//! End to end: a 2-method x 2-seed equal-samples comparison on the built-in Cornell box at
//! 16 x 16 — the run directory, its manifest as `chainlight report` reads it, the tables and
//! the CSV.

use std::path::{Path, PathBuf};

use experiments::report::{write_report, RunManifest};
use experiments::{Defaults, Experiment, Measure, Method, Plan, Regime, SceneCase};
use render::session::{IntegratorKind, RenderSettings};

/// A fresh directory under Cargo's per-test scratch space.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("experiments")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn method(name: &str, integrator: IntegratorKind) -> Method {
    Method::new(
        name,
        RenderSettings {
            method: integrator.settings(),
            max_depth: 4,
            ..RenderSettings::default()
        },
    )
    .with_parameter("integrator", format!("{integrator:?}"))
}

#[test]
fn two_methods_two_seeds_equal_samples_on_the_cornell_box() {
    let out = scratch("cornell");
    let plan = Plan {
        seeds: vec![7, 8],
        size: 16,
        threads: 2,
        out: out.clone(),
        ..Plan::from_defaults(&Defaults::new("e2e", Regime::EqualSamples(8)))
    };
    let mut inspected = Vec::new();
    let results = Experiment::new(plan)
        .methods([
            method("PT", IntegratorKind::Pt),
            method("PSSMLT/K", IntegratorKind::Pssmlt).with_slug("pssmlt-k"),
        ])
        .baseline("PT")
        .convergence(&[0.25, 0.5])
        .parameter("max depth", 4)
        .scene_parameters(|r, scene| {
            let b = r.median(scene, "PSSMLT/K", Measure::B);
            vec![("b (PSSMLT/K)".into(), format!("{b:.4}"))]
        })
        .inspect(|record, output, dir| {
            inspected.push((record.method.clone(), record.seed, output.samples));
            assert!(dir.join("reference.exr").is_file());
        })
        .scenes(vec![SceneCase::cornell_box(16, 64).unwrap()])
        .run()
        .unwrap();

    // Interleaved: for seed, for scene, for method.
    let order: Vec<(String, u64)> = results
        .records
        .iter()
        .map(|r| (r.method.clone(), r.seed))
        .collect();
    assert_eq!(
        order,
        [("PT", 7), ("PSSMLT/K", 7), ("PT", 8), ("PSSMLT/K", 8)].map(|(m, s)| (m.to_owned(), s))
    );
    assert_eq!(inspected.len(), 4);
    assert_eq!(inspected[0].2, 16 * 16 * 8, "PT: 8 samples per pixel");
    for r in &results.records {
        assert!(
            r.metrics.relmse > 0.0 && r.metrics.relmse.is_finite(),
            "{r:?}"
        );
        assert_eq!(r.convergence.len(), 3, "1/4, 1/2 and the final render");
        assert!(r.convergence.windows(2).all(|w| w[0].time_s > 0.0));
    }
    // Statistics: PSSMLT reports b and acceptance through run_stats, PT nothing.
    let mcmc = results.run("cornell-box", "PSSMLT/K", 7).unwrap();
    assert!(mcmc.stats.b.is_some_and(|b| b > 0.0));
    assert!(mcmc.stats.acceptance.is_some_and(|a| a > 0.0 && a <= 1.0));
    assert_eq!(results.run("cornell-box", "PT", 7).unwrap().stats.b, None);

    // The run directory: reference, images per seed, first-seed previews, run.json, report.
    let dir = results.scene_dir("cornell-box");
    for file in [
        "reference.exr",
        "reference.png",
        "PT_seed7.exr",
        "PT_seed8.exr",
        "pssmlt-k_seed7.exr",
        "pssmlt-k_seed8.exr",
        "PT.png",
        "pssmlt-k.png",
        "run.json",
        "report.html",
    ] {
        assert!(dir.join(file).is_file(), "missing {file}");
    }
    let manifest = RunManifest::load(&dir).unwrap();
    assert_eq!(manifest.title, "e2e: cornell-box");
    assert_eq!(manifest.methods.len(), 2);
    assert_eq!(manifest.methods[1].images.len(), 2);
    assert_eq!(manifest.methods[1].convergence[0].points.len(), 3);
    assert_eq!(manifest.parameters["max depth"], "4");
    assert!(manifest.parameters.contains_key("b (PSSMLT/K)"));
    assert!(manifest.parameters["budget"].contains("8 samples"));
    assert_eq!(manifest.methods[0].parameters["integrator"], "Pt");
    // What `chainlight report <dir>` does with it.
    let html = write_report(&manifest, &dir, dir.join("again.html")).unwrap();
    assert!(std::fs::read_to_string(html).unwrap().contains("PSSMLT/K"));

    // The table: medians over the two seeds, ratio to the baseline.
    let table = results.scene_table("cornell-box");
    let rows = table.rows();
    assert_eq!(rows.len(), 2);
    let relmse = results.values("cornell-box", "PT", Measure::RelMse);
    let (median, min, max) = render::metrics::median_min_max(&relmse).unwrap();
    assert_eq!(
        rows[0][1],
        format!(
            "{} [{}, {}]",
            Measure::RelMse.format(median),
            Measure::RelMse.format(min),
            Measure::RelMse.format(max)
        )
    );
    assert_eq!(rows[0].last().unwrap(), "1.00 (PT)");
    assert!(rows[1].last().unwrap().ends_with("(PT)"));
    assert!(table.headers().iter().any(|h| h == "acceptance"));

    // results.md and results.csv.
    let md_path = results.write("## extra\n").unwrap();
    let md = std::fs::read_to_string(md_path).unwrap();
    assert!(
        md.starts_with("# e2e\n") && md.contains("### cornell-box") && md.ends_with("## extra\n")
    );
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5);
    assert!(csv
        .lines()
        .nth(2)
        .unwrap()
        .starts_with("cornell-box,PSSMLT/K,7,8spp,"));
}

#[test]
fn inconsistent_experiments_are_refused_before_rendering() {
    let plan = Plan {
        size: 8,
        out: scratch("refused"),
        ..Plan::from_defaults(&Defaults::new("bad", Regime::EqualSamples(1)))
    };
    let case = || vec![SceneCase::cornell_box(8, 1).unwrap()];
    let e = Experiment::new(plan.clone())
        .scenes(case())
        .run()
        .unwrap_err();
    assert!(e.to_string().contains("no methods"), "{e}");
    let e = Experiment::new(plan.clone())
        .methods([
            method("A", IntegratorKind::Pt),
            method("A", IntegratorKind::Pt),
        ])
        .scenes(case())
        .run()
        .unwrap_err();
    assert!(e.to_string().contains("appears twice"), "{e}");
    let e = Experiment::new(plan.clone())
        .methods([
            method("a b", IntegratorKind::Pt),
            method("a-b", IntegratorKind::Pt),
        ])
        .scenes(case())
        .run()
        .unwrap_err();
    assert!(e.to_string().contains("file stem"), "{e}");
    let e = Experiment::new(plan.clone())
        .method(method("A", IntegratorKind::Pt))
        .baseline("B")
        .scenes(case())
        .run()
        .unwrap_err();
    assert!(e.to_string().contains("baseline \"B\""), "{e}");
    let e = Experiment::new(Plan { size: 16, ..plan })
        .method(method("A", IntegratorKind::Pt))
        .scenes(case())
        .run()
        .unwrap_err();
    assert!(e.to_string().contains("8x8"), "{e}");
}
