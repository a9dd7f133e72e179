//! End to end: delayed rejection against one-stage PSSMLT on the built-in Cornell box — the
//! stage maps saved as extra images, the acceptance-per-stage table from the typed statistics,
//! and the experiments the harness refuses for their extra images.

use std::path::{Path, PathBuf};

use experiments::TableSpec;
use experiments::{Column, Defaults, Experiment, Measure, Method, Plan, Regime, SceneCase};
use render::methods::{DrmltSettings, MethodSettings, PssmltSettings};
use render::session::RenderSettings;

/// A fresh directory under Cargo's per-test scratch space.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("experiments-stages")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `preset` with 16 chains and a small bootstrap (a test-sized run).
fn method(name: &str, preset: impl Into<MethodSettings>) -> Method {
    let settings = RenderSettings {
        method: preset.into().with_chains(16, 2_000),
        max_depth: 4,
        ..RenderSettings::default()
    };
    Method::new(name, settings)
}

fn plan(name: &str) -> Plan {
    Plan {
        seeds: vec![3, 4],
        size: 8,
        threads: 2,
        out: scratch(name),
        report: false,
        ..Plan::from_defaults(&Defaults::new("stages", Regime::EqualSamples(4)))
    }
}

#[test]
fn stage_maps_and_acceptance_per_stage() {
    let results = Experiment::new(plan("run"))
        .methods([
            method("PSSMLT/K", PssmltSettings::kelemen2002()).with_slug("pssmlt-k"),
            method("DR", DrmltSettings::rioux_lavoie2020()),
        ])
        .baseline("PSSMLT/K")
        .extra_image("stage2", |out| out.stage_map.clone())
        .scenes(vec![SceneCase::cornell_box(8, 16).unwrap()])
        .run()
        .unwrap();
    let dir = results.scene_dir("cornell-box");
    for file in [
        "DR_stage2_seed3.exr",
        "DR_stage2_seed4.exr",
        "DR_stage2.exr",
        "DR_stage2.png",
    ] {
        assert!(dir.join(file).is_file(), "missing {file}");
    }
    // Negative control: one-stage PSSMLT has no stage map, so no extra image.
    assert!(!dir.join("pssmlt-k_stage2_seed3.exr").exists());
    assert!(
        !dir.join("DR_stage2_seed4.png").exists(),
        "only the first seed's PNG"
    );

    let stages = results.table("cornell-box", &TableSpec::acceptance_by_stage());
    let (pss, dr) = (&stages.rows()[0], &stages.rows()[1]);
    let tried: f64 = dr[3].parse().unwrap();
    assert!(tried > 0.0 && tried < 1.0, "{dr:?}");
    let candidates: f64 = dr[6].parse().unwrap();
    assert!((candidates - (1.0 + tried)).abs() < 0.02, "{dr:?}");
    assert_eq!(pss[3], "0.000", "PSSMLT never tries a second stage");
    assert_eq!(pss[4], "-", "so it has no stage-2 acceptance");
    assert_eq!(pss[6], "1.00");
    let run = results.run("cornell-box", "DR", 3).unwrap();
    let counts = run.stats.acceptance_counts.unwrap();
    assert_eq!(counts.steps, run.stats.mutations.unwrap());

    let cost = results.table("cornell-box", &TableSpec::new([Column::step_cost()]));
    assert_eq!(cost.rows()[0][1], "1.00 (PSSMLT/K)");
    assert!(cost.rows()[1][1].ends_with("(PSSMLT/K)"));
    let md = results.markdown_with(&[
        TableSpec::errors([Measure::RelMse]),
        TableSpec::acceptance_by_stage(),
    ]);
    assert!(md.contains("**acceptance per stage**"), "{md}");
}

#[test]
fn extra_images_that_are_not_file_stems_or_overwrite_a_method_are_refused() {
    let case = || vec![SceneCase::cornell_box(8, 1).unwrap()];
    for (name, methods, message) in [
        ("a/b", vec!["A"], "not a file stem"),
        ("", vec!["A"], "not a file stem"),
        ("map", vec!["A", "A_map"], "would overwrite"),
    ] {
        let e = Experiment::new(plan("refused"))
            .methods(
                methods
                    .iter()
                    .map(|m| method(m, PssmltSettings::kelemen2002())),
            )
            .extra_image(name, |out| out.stage_map.clone())
            .scenes(case())
            .run()
            .unwrap_err();
        assert!(e.to_string().contains(message), "{name:?}: {e}");
    }
    let e = Experiment::new(plan("refused"))
        .method(method("A", PssmltSettings::kelemen2002()))
        .extra_image("m", |out| out.stage_map.clone())
        .extra_image("m", |_| None)
        .scenes(case())
        .run()
        .unwrap_err();
    assert!(e.to_string().contains("appears twice"), "{e}");
}
