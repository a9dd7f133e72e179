//! Regional adaptive path-space MLT (Otsu et al. 2018): FIXED, GLOBAL, RA-GRID and RA-QUADTREE
//! for the lens and the multi-chain perturbation, equal time, as the paper compares them.
//!
//! Each configuration is the paper's `PathMltSettings::otsu2018(perturbation, adapt)`: FIXED at
//! `lambda = 1` (sigma = e^0.5 = 1.6487 rad) and every adaptive variant starting there, one sign
//! step per `L` visits, `M_split`, `M_refine` from the pixel count; max depth 5. Besides them,
//! chainlight's own "tuned FIXED" frontier: FIXED at each `--sweep` sigma (default 0.005, 0.02,
//! 0.1 rad), for both perturbations. `--target-acceptance 0.8` is the paper's
//! Necklace setting (glossy scenes). Defaults: cornell, glossy-diffuse, ajar-door; 5 s per
//! render (`--spp`: equal mutations), 5 seeds, 128 x 128, one thread.
//!
//! The `experiments` harness writes per scene `<out>/<scene>/` (every seed's image, `run.json`,
//! `report.html`, the first seed's `<slug>_error.png` and `<slug>_sigma.png`), `results.md`
//! (rRMSE and the harness's columns; then rRMSE / FIXED, the learned sigma's pixel median, the
//! share of visited regions whose acceptance is within 0.1 of the target, the paper's
//! orderings and the first seed's adaptation summaries), `results.csv`, and with `--ladder` the
//! rRMSE-vs-time ladder (Fig. 10): `<out>/ladder/`, `ladder.csv`, `convergence.svg`. Each render
//! can run as its own process (`--emit-jobs`, `--run-one`, `--collect`), which is how
//! `scripts/regional_adaptive.sh` takes the measurement lock per render.
//!
//! `cargo run --release --example regional_adaptive -- [--m-split N] [--sweep 0.01,0.02]
//! [--target-acceptance 0.8] [--ladder 1,2,5,10,20,60] [--ladder-seeds 5] [--ladder-scene
//! cornell-glass]` and the shared flags (`--help`).

use clap::Parser;
use experiments::maps::{write_run_map, LOG_SCALE};
use experiments::{median, CommonOptions, Defaults, Experiment, LadderDefaults, LadderOptions};
use experiments::{Measure, Method, Regime, Results, RunValues, Table};
use pathspace::PerturbationKind::{self, Lens, MultiChain};
use render::methods::PathMltSettings;
use render::mlt::pathmlt::{AdaptSummary, PathAdapt};
use render::session::RenderSettings;

#[derive(Parser)]
struct Args {
    #[command(flatten)]
    common: CommonOptions,
    #[command(flatten)]
    ladder: LadderOptions,
    /// RA-QUADTREE's M_split instead of the pixel schedule's.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    m_split: Option<u64>,
    /// The tuned-FIXED frontier: FIXED at each of these scales (radians, comma-separated;
    /// empty: none).
    #[arg(
        long,
        value_name = "RAD,..",
        value_delimiter = ',',
        default_value = "0.005,0.02,0.1"
    )]
    sweep: Vec<f64>,
    /// The adaptive variants' target acceptance (the paper's 0.5; 0.8 for its Necklace).
    #[arg(long, value_name = "ALPHA", default_value_t = 0.5)]
    target_acceptance: f64,
    /// Run only these configurations (slugs, comma-separated, e.g. `lens-grid,lens-fixed-0.02`):
    /// one render per process, for the measurement lock.
    #[arg(long, value_name = "SLUG,..", value_delimiter = ',')]
    only: Vec<String>,
}

const LADDER: LadderDefaults = LadderDefaults {
    scene: "ajar-door",
    seconds: &[1.0, 2.0, 5.0, 10.0, 20.0, 60.0],
    seeds: 5,
    first_seed: 0,
    quick_seconds: &[0.25, 0.5],
    quick_seeds: 1,
};
const KINDS: [(PerturbationKind, &str); 2] = [(Lens, "lens"), (MultiChain, "multichain")];
/// The paper's orderings (lower rRMSE first): RA-QUADTREE <= RA-GRID <= GLOBAL <= FIXED.
const CLAIMS: [(&str, &str); 4] = [
    ("RA-QUADTREE", "RA-GRID"),
    ("RA-GRID", "GLOBAL"),
    ("GLOBAL", "FIXED"),
    ("RA-QUADTREE", "FIXED"),
];
const ADAPTS: [(PathAdapt, &str); 4] = [
    (PathAdapt::Fixed, "FIXED"),
    (PathAdapt::Global, "GLOBAL"),
    (PathAdapt::Grid, "RA-GRID"),
    (PathAdapt::Quadtree, "RA-QUADTREE"),
];

/// The eight paper configurations (FIXED first per perturbation and the baseline of its
/// others), then FIXED at each sweep scale.
fn methods(args: &Args) -> Vec<Method> {
    let (m_split, target) = (args.m_split, args.target_acceptance);
    let mut methods = Vec::new();
    for ((kind, k), (adapt, a)) in KINDS.into_iter().flat_map(|k| ADAPTS.map(|a| (k, a))) {
        let fixed = format!("{k} FIXED");
        let method = Method::from_fn(format!("{k} {a}"), move |_| {
            let mut method = PathMltSettings::otsu2018(kind, adapt);
            method.target_acceptance = target;
            if adapt == PathAdapt::Quadtree {
                method.split_after_visits = m_split;
            }
            let mut settings = RenderSettings::default();
            (settings.method, settings.max_depth) = (method.into(), 5);
            settings
        });
        let slug = format!("{k}-{}", adapt.name());
        methods.push(method.with_slug(slug).with_baseline(fixed));
    }
    for ((kind, k), sigma) in KINDS
        .into_iter()
        .flat_map(|k| args.sweep.iter().map(move |&s| (k, s)))
    {
        let method = Method::from_fn(format!("{k} FIXED {sigma}"), move |_| {
            let mut method = PathMltSettings::otsu2018(kind, PathAdapt::Fixed);
            method.sigma = sigma;
            let mut settings = RenderSettings::default();
            (settings.method, settings.max_depth) = (method.into(), 5);
            settings
        });
        let slug = format!("{k}-fixed-{sigma}");
        methods.push(method.with_slug(slug).with_baseline(format!("{k} FIXED")));
    }
    if args.only.is_empty() {
        return methods;
    }
    // One configuration per process: its own baseline.
    methods
        .into_iter()
        .filter(|m| args.only.contains(&m.slug().to_string()))
        .map(|m| {
            let name = m.name().to_string();
            m.with_baseline(name)
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut defaults = Defaults::new("regional_adaptive", Regime::seconds(5.0));
    let scenes = ["cornell", "glossy-diffuse", "ajar-door"];
    defaults.scenes = scenes.map(String::from).to_vec();
    (defaults.seeds, defaults.threads, defaults.size) = (5, Some(1), 128);
    defaults.out = "target/regional_adaptive".into();
    (defaults.quick.scenes, defaults.quick.regime) = (None, Regime::seconds(0.5));
    (defaults.quick.seeds, defaults.quick.size) = (2, 32);
    let args = experiments::parse::<Args>(&defaults);
    let plan = args.common.plan(&defaults)?;
    let (first, size) = (plan.seeds[0], plan.size as usize);
    let (mut sigma, mut adapt) = (RunValues::default(), RunValues::default());
    let m_split = args
        .m_split
        .map_or("pixel schedule".into(), |m| m.to_string());
    let results = Experiment::new(plan.clone())
        .methods(methods(&args))
        .parameter("max depth", 5)
        .parameter("RA-QUADTREE M_split", m_split)
        .parameter("target acceptance", args.target_acceptance)
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
        let ladder = ladder.run(|p| Experiment::new(p).methods(methods(&args)))?;
        extra += &ladder.write(&plan.out, Measure::RRmse)?;
    }
    results.write(&extra)?;
    Ok(())
}

type Adapt = RunValues<Option<AdaptSummary>>;

/// Per scene: rRMSE / FIXED, the learned sigma, the paper's orderings, the adaptation summaries.
fn adaptation(results: &Results, sigma: &RunValues<f64>, adapt: &Adapt, first: u64) -> String {
    let mut md = String::from("## Regional adaptation\n");
    let headers = [
        "configuration",
        "rRMSE / FIXED",
        "sigma median (rad)",
        "acceptance near target",
    ];
    for scene in &results.scenes {
        let mut table = Table::new(headers);
        let rrmse = |m: &str| results.median(scene, m, Measure::RRmse);
        let mut notes = String::new();
        for method in &results.methods {
            let ratio = rrmse(method) / rrmse(&results.baselines[method]);
            let s = Some(sigma.median(scene, method)).filter(|s| !s.is_nan());
            let s = s.map_or("(fixed)".into(), |s| format!("{s:.3e}"));
            let near = match adapt.get(scene, method, first) {
                Some(Some(a)) => format!("{} of {} regions", a.near_target, a.visited),
                _ => "-".into(),
            };
            table.push_row([method.clone(), format!("{ratio:.3}"), s, near]);
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
