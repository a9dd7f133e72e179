//! Automatic large-step control (Zsolnai & Szirmay-Kalos 2013) on the bundled scenes.
//!
//! For each scene: PSSMLT with automatic control (the measured `eta_s`, `eta_l`, `eta_0` and
//! the chosen `p_l` are printed), then a sweep of fixed `p_l` in {0.1, ..., 1.0} at the same
//! mutation count; relMSE against the scene's BDPT reference (`scenes/references/<scene>.exr`,
//! box-downsampled to the render size), median over the seeds (MCMC errors are heavy tailed;
//! the DRMLT paper reports medians too), and where the automatic choice falls in the sweep.
//!
//! The `experiments` harness runs it: per scene a run directory `<out>/<scene>/` (default
//! `--out out/zsolnai_large_step`) with every method's image per seed, error-vs-time samples
//! from extra runs at 1/8, 1/4 and 1/2 of the budget, `run.json` and a self-contained
//! `report.html` (rebuild it with `chainlight report <out>/<scene>`); `results.md` (the
//! harness's table per scene, then this example's sweep table) and `results.csv` in `<out>`.
//! `--no-report` skips the reports and the extra runs; `--quick` is a smoke run (16 x 16,
//! 8 mutations per pixel, 2 seeds, cornell and cornell-glass).
//!
//! `cargo run --release --example zsolnai_large_step -- [--size 64] [--mpp 64] [--runs 3]
//! [--out DIR] [--no-report] [--quick] [scene ...]` (`--help` lists the shared flags).
//!
//! Beyond one machine: `--emit-jobs DIR` writes the runs (one per scene and seed) as a job
//! list with a Slurm array script and a Kubernetes Indexed Job; `chainlight sweep run DIR`
//! (or the cluster) runs them, and the same command with `--collect` writes the same
//! `results.md` (docs/cluster.md).

use experiments::{CommonOptions, Defaults, Experiment, Measure, Method, Regime, Results, Table};
use render::methods::PssmltSettings;
use render::mlt::LargeStepMode;
use render::session::RenderSettings;

/// The fixed large-step probabilities of the sweep.
fn sweep() -> Vec<f64> {
    (1..=10).map(|i| f64::from(i) / 10.0).collect()
}

/// PSSMLT over BDPT from a paper preset with 20 000 bootstrap samples, max depth 5: automatic
/// control is [`PssmltSettings::zsolnai2013`] (1000 mutations per chain at `p_l = 0.5`, then
/// section 2's `p_l`), the sweep [`PssmltSettings::kelemen2002`] at a fixed `p_l`.
fn pssmlt(name: String, mut preset: PssmltSettings) -> Method {
    preset.chain.bootstrap_samples = 20_000;
    let mode = match preset.chain.large_step {
        LargeStepMode::Fixed(p) => format!("fixed p_large = {p}"),
        other => format!("{other:?}"),
    };
    let settings = RenderSettings {
        max_depth: 5,
        method: preset.into(),
        ..RenderSettings::default()
    };
    Method::new(name, settings).with_parameter("large step", mode)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let defaults = Defaults {
        first_seed: 100,
        ..Defaults::new("zsolnai_large_step", Regime::EqualSamples(64))
    };
    let plan = experiments::parse::<CommonOptions>(&defaults).plan(&defaults)?;
    let mut methods = vec![pssmlt("auto".into(), PssmltSettings::zsolnai2013())];
    methods.extend(sweep().into_iter().map(|p| {
        let mut fixed = PssmltSettings::kelemen2002();
        fixed.chain.large_step = LargeStepMode::Fixed(p);
        pssmlt(format!("p_l={p:.1}"), fixed)
    }));
    let Some(results) = Experiment::new(plan)
        .methods(methods)
        .baseline("auto")
        .convergence(&[0.125, 0.25, 0.5])
        .parameter("integrator", "pssmlt over BDPT")
        .parameter("chains", 256)
        .parameter("max depth", 5)
        .parameter("bootstrap samples", 20_000)
        .scene_parameters(|results, scene| {
            let Some(eta) = etas(results, scene) else {
                return Vec::new();
            };
            let seed = results.plan.seeds[0];
            vec![
                (
                    "auto: measured eta_s, eta_l, eta_0".into(),
                    format!("{:.3}, {:.3}, {:.3}", eta[0], eta[1], eta[2]),
                ),
                (
                    format!("auto: chosen p_l (seed {seed})"),
                    format!("{:.3}", eta[3]),
                ),
            ]
        })
        .execute()?
    else {
        return Ok(()); // a job list written, or one run of it recorded
    };
    results.write(&sweep_table(&results))?;
    Ok(())
}

/// `eta_s`, `eta_l`, `eta_0` and `p_l` of the automatic run with the first seed.
fn etas(results: &Results, scene: &str) -> Option<[f64; 4]> {
    let run = results.run(scene, "auto", results.plan.seeds[0])?;
    let l = run.stats.large_step?;
    Some([l.eta_s, l.eta_l, l.eta_0, l.p_large])
}

/// One row per scene: the automatic control's estimate, the sweep's median relMSE (`*` at the
/// sweep value nearest the automatic `p_l`), the best sweep value and the automatic run's rank.
fn sweep_table(results: &Results) -> String {
    let sweep = sweep();
    let mut headers: Vec<String> = [
        "scene",
        "eta_s",
        "eta_l",
        "eta_0",
        "eta_l/eta_0",
        "auto p_l",
    ]
    .map(String::from)
    .to_vec();
    headers.extend(sweep.iter().map(|p| format!("p={p:.1}")));
    headers.extend(["auto relMSE", "best sweep p", "auto rank"].map(String::from));
    let mut table = Table::new(headers);
    for scene in &results.scenes {
        let [s, l, z, p] = etas(results, scene).unwrap_or([f64::NAN; 4]);
        let auto = results.median(scene, "auto", Measure::RelMse);
        let errs: Vec<f64> = sweep
            .iter()
            .map(|q| results.median(scene, &format!("p_l={q:.1}"), Measure::RelMse))
            .collect();
        let best = (0..errs.len()).min_by(|&a, &b| errs[a].total_cmp(&errs[b]));
        let mut row = vec![scene.clone()];
        row.extend([s, l, z, l / z].map(|v| format!("{v:.3}")));
        row.push(format!("**{p:.2}**"));
        for (q, e) in sweep.iter().zip(&errs) {
            let mark = if (q - p).abs() <= 0.05 { "*" } else { "" };
            row.push(format!("{e:.4}{mark}"));
        }
        row.push(format!("{auto:.4}"));
        row.push(best.map_or("-".into(), |i| format!("{:.1}", sweep[i])));
        let rank = errs.iter().filter(|&&e| e < auto).count() + 1;
        row.push(format!("{rank} of {}", sweep.len() + 1));
        table.push_row(row);
    }
    format!(
        "## Automatic p_l vs the fixed sweep (PSSMLT over BDPT, {}, median relMSE of {} seeds)\n\n{}\n`*` marks the sweep value nearest the automatic p_l; rank 1 = the automatic run beat every fixed p_l.\n",
        results.plan.regime,
        results.plan.seeds.len(),
        table.to_markdown()
    )
}
