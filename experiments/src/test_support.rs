//! Shared fixtures of the package's unit tests: a tiny experiment on the built-in Cornell box.

use std::path::PathBuf;

use render::session::{IntegratorKind, RenderSettings};

use crate::{Defaults, Experiment, Method, Plan, Regime, Results, SceneCase};

/// A scratch output directory named `name`, emptied.
pub(crate) fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("experiments-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// PT and BDPT at 8 x 8, 2 samples per pixel, 3 seeds, one thread, no report.
pub(crate) fn tiny_plan(name: &str) -> Plan {
    Plan {
        seeds: vec![1, 2, 3],
        size: 8,
        threads: 1,
        out: scratch(name),
        report: false,
        ..Plan::from_defaults(&Defaults::new(name, Regime::EqualSamples(2)))
    }
}

/// The methods of [`tiny_experiment`].
pub(crate) fn tiny_methods() -> [Method; 2] {
    let method = |name: &str, integrator: IntegratorKind| {
        let method = integrator.settings();
        Method::new(
            name,
            RenderSettings {
                method,
                max_depth: 3,
                ..RenderSettings::default()
            },
        )
    };
    [
        method("PT", IntegratorKind::Pt),
        method("BDPT", IntegratorKind::Bdpt),
    ]
}

/// The built-in Cornell box at 8 x 8 with a 16-spp reference.
pub(crate) fn tiny_scene() -> SceneCase {
    SceneCase::cornell_box(8, 16).expect("cornell box")
}

/// Runs [`tiny_plan`] with [`tiny_methods`] on [`tiny_scene`]; returns the results and the
/// output directory.
pub(crate) fn tiny_experiment(name: &str) -> (Results, PathBuf) {
    let plan = tiny_plan(name);
    let out = plan.out.clone();
    let results = Experiment::new(plan)
        .methods(tiny_methods())
        .baseline("PT")
        .scenes(vec![tiny_scene()])
        .run()
        .expect("tiny experiment");
    (results, out)
}
