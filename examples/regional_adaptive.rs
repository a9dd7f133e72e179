//! Regional adaptive path-space MLT (Otsu et al. 2018): FIXED, GLOBAL, RA-GRID and RA-QUADTREE
//! for the lens and the multi-chain perturbation, equal time.
//!
//! Each configuration is the paper's `PathMltSettings::otsu2018(perturbation, adapt)`, max
//! depth 5, on cornell, glossy-diffuse, ajar-door: 5 s per render (`--spp`: equal mutations, no
//! ladder), 5 seeds, 64 x 64, one thread. A time budget leaves the mutation count unknown, so
//! RA-QUADTREE scales `M_refine`, `M_split` to the mutations its FIXED reached just before it on
//! the same scene and seed (`--m-split N` sets `M_split`).
//!
//! The `experiments` harness writes per scene `<out>/<scene>/` (every seed's image, `run.json`,
//! `report.html`, the first seed's `<slug>_error.png` and `<slug>_sigma.png`, viridis log
//! 1e-3..1, 3x), `results.md` (the harness's table with rRMSE, the paper's metric; then rRMSE /
//! FIXED, the learned sigma's pixel median, the paper's orderings, the first seed's adaptation
//! summaries), `results.csv`, and the rRMSE-vs-time ladder (Fig. 10; glossy-diffuse, 1-60 s, 3
//! seeds from 1000): `<out>/ladder/`, `ladder.csv`, `convergence.svg`. `--quick`: 0.5 s, 2
//! seeds, 32 x 32, ladder 0.25, 0.5 s, 1 seed. Changed: rRMSE, relMSE, samples/s, acceptance are
//! in the harness's table and CSVs (no sigma column); the ladder runs rung by rung (was seed by
//! seed) with run directories; its plot shows every seed; one line per ordering.
//!
//! `cargo run --release --example regional_adaptive -- [--m-split N] [--ladder 1,4,15,60]
//! [--ladder-seeds 3] [--ladder-scene glossy-diffuse]` and the shared flags (`--help`).

use clap::Parser;
use experiments::maps::{write_run_map, LOG_SCALE};
use experiments::{median, CommonOptions, Defaults, Experiment, LadderDefaults, LadderOptions};
use experiments::{Measure, Method, Regime, Results, RunValues, Table};
use pathspace::PerturbationKind::{self, Lens, MultiChain};
use render::methods::PathMltSettings;
use render::mlt::pathmlt::{AdaptSummary, PathAdapt, PATHMLT_SIGMA};
use render::session::RenderSettings;

#[derive(Parser)]
struct Args {
    #[command(flatten)]
    common: CommonOptions,
    #[command(flatten)]
    ladder: LadderOptions,
    /// RA-QUADTREE's M_split instead of the budget-scaled one.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    m_split: Option<u64>,
}

const LADDER: LadderDefaults = LadderDefaults {
    scene: "glossy-diffuse",
    seconds: &[1.0, 4.0, 15.0, 60.0],
    seeds: 3,
    first_seed: 1000,
    quick_seconds: &[0.25, 0.5],
    quick_seeds: 1,
};
const KINDS: [(PerturbationKind, &str); 2] = [(Lens, "lens"), (MultiChain, "multichain")];
/// The paper's orderings (lower rRMSE first).
const CLAIMS: [(&str, &str); 2] = [("RA-QUADTREE", "RA-GRID"), ("GLOBAL", "FIXED")];
const ADAPTS: [(PathAdapt, &str); 4] = [
    (PathAdapt::Fixed, "FIXED"),
    (PathAdapt::Global, "GLOBAL"),
    (PathAdapt::Grid, "RA-GRID"),
    (PathAdapt::Quadtree, "RA-QUADTREE"),
];

/// The eight configurations, FIXED first per perturbation and the baseline of its others.
fn methods(m_split: Option<u64>) -> Vec<Method> {
    let mut methods = Vec::new();
    for ((kind, k), (adapt, a)) in KINDS.into_iter().flat_map(|k| ADAPTS.map(|a| (k, a))) {
        let fixed = format!("{k} FIXED");
        let of_fixed = fixed.clone();
        let method = Method::from_fn(format!("{k} {a}"), move |run| {
            let mut method = PathMltSettings::otsu2018(kind, adapt);
            if adapt == PathAdapt::Quadtree {
                let reached = run.previous.iter().find(|r| r.method == of_fixed);
                method.refine_for_mutations = Some(reached.map_or(1, |r| r.samples));
                method.split_after_visits = m_split;
            }
            let mut settings = RenderSettings::default();
            (settings.method, settings.max_depth) = (method.into(), 5);
            settings
        });
        let slug = format!("{k}-{}", adapt.name());
        methods.push(method.with_slug(slug).with_baseline(fixed));
    }
    methods
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut defaults = Defaults::new("regional_adaptive", Regime::seconds(5.0));
    let scenes = ["cornell", "glossy-diffuse", "ajar-door"];
    defaults.scenes = scenes.map(String::from).to_vec();
    (defaults.seeds, defaults.threads) = (5, Some(1));
    defaults.out = "target/regional_adaptive".into();
    (defaults.quick.scenes, defaults.quick.regime) = (None, Regime::seconds(0.5));
    (defaults.quick.seeds, defaults.quick.size) = (2, 32);
    let args = experiments::parse::<Args>(&defaults);
    let plan = args.common.plan(&defaults)?;
    let (first, size) = (plan.seeds[0], plan.size as usize);
    let (mut sigma, mut adapt) = (RunValues::default(), RunValues::default());
    let m_split = args.m_split.map_or("scaled".into(), |m| m.to_string());
    let results = Experiment::new(plan.clone())
        .methods(methods(args.m_split))
        .parameter("max depth", 5)
        .parameter("RA-QUADTREE M_split", m_split)
        .inspect(|record, output, dir| {
            let map = output.sigma_map.as_deref().unwrap_or_default();
            sigma.push(record, median(map));
            adapt.push(record, output.mcmc.as_ref().and_then(|m| m.regional_adapt));
            if record.seed == first && !map.is_empty() {
                let written = write_run_map(dir, record, "sigma", map, size, LOG_SCALE, 3);
                written.map_or_else(|e| eprintln!("{e}"), drop);
            }
        })
        .run()?;
    results.write_error_maps(3)?;
    let mut extra = adaptation(&results, &sigma, &adapt, first);
    if let Some(ladder) = args.ladder.ladder(&plan, &LADDER) {
        let ladder = ladder.run(|p| Experiment::new(p).methods(methods(args.m_split)))?;
        extra += &ladder.write(&plan.out, Measure::RRmse)?;
    }
    results.write(&extra)?;
    Ok(())
}

type Adapt = RunValues<Option<AdaptSummary>>;

/// Per scene: rRMSE / FIXED, the learned sigma, the paper's orderings, the adaptation summaries.
fn adaptation(results: &Results, sigma: &RunValues<f64>, adapt: &Adapt, first: u64) -> String {
    let mut md = String::from("## Regional adaptation\n");
    let headers = ["configuration", "rRMSE / FIXED", "sigma median (rad)"];
    for scene in &results.scenes {
        let mut table = Table::new(headers);
        let rrmse = |m: &str| results.median(scene, m, Measure::RRmse);
        let mut notes = String::new();
        for method in &results.methods {
            let ratio = rrmse(method) / rrmse(&results.baselines[method]);
            let s = Some(sigma.median(scene, method)).filter(|s| !s.is_nan());
            let s = s.map_or(format!("{PATHMLT_SIGMA} (fixed)"), |s| format!("{s:.3e}"));
            table.push_row([method.clone(), format!("{ratio:.3}"), s]);
            if let Some(Some(summary)) = adapt.get(scene, method, first) {
                notes += &format!("- {method}: {}\n", summary.note());
            }
        }
        md += &format!("\n### {scene}\n\n{}\n", table.to_markdown());
        for ((_, k), (a, b)) in KINDS.into_iter().flat_map(|k| CLAIMS.map(|c| (k, c))) {
            let (a, b) = (format!("{k} {a}"), format!("{k} {b}"));
            let c = results.compare(scene, &a, &b, Measure::RRmse);
            md += &format!("- rRMSE: {a} <= {b} {c}\n");
        }
        md += &format!("\nAdaptation (seed {first}):\n\n{notes}");
    }
    md
}
