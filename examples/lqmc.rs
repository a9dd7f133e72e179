//! Local quasi-Monte Carlo exploration (Tessari, Hanika & Dachsbacher 2020): the 2-D toy of
//! Fig. 2 and an equal-time renderer comparison with temporal stability.
//!
//! The toy: `N = 128` points on the unit torus, the rank-1 lattice `g = (1, 12)` against a
//! Markov chain of uniform steps in `[-1/sqrt(N), 1/sqrt(N)]^2`, on the full torus and locally
//! (a 1/4 tile around a seed: the lattice shifted onto the seed, the chain's steps scaled to the
//! tile): `toy_full.png`, `toy_local.png` (lattice red, chain blue) and the cells of an 8 x 8
//! grid each set hits (`--no-toy` skips it).
//!
//! The renders (`--no-scenes` skips them): `QmcSettings::default()` (Halton points),
//! `PssmltSettings::kelemen2002()` (the paper's KMLT) and `LqmcSettings::tessari2020()`, max
//! depth 5, on dof, caustic-pool, ajar-door: 2 s per render, 10 seeds, 64 x 64, every core.
//! The `experiments` harness writes per scene `<out>/<scene>/` (every seed's image, `run.json`,
//! `report.html`), `results.md` (its table: relMSE, MSE, rRMSE, MAD against the BDPT reference,
//! samples/s; then this example's temporal stability: per-pixel luminance variance across the
//! seeds' renders, the frames of a still animation, next to the mean MSE, and its 8 x 8-block
//! ratio, 1 for uncorrelated noise, more for blotches; and LQMC's counters for the first seed)
//! and `results.csv`. `--quick`: 0.25 s, 2 seeds, 16 x 16.
//!
//! Changed from the hand-written example: relMSE, MAD and samples/s (wall clock of the render
//! call) are in the harness's table, which comes first in `results.md`, then the toy, then the
//! temporal table; `results.csv` has the harness's columns; the LQMC line comes from typed
//! statistics (`RenderOutput::lqmc`); one seed is allowed (temporal columns `-`); the shared
//! flags (`--spp`, `--threads`, `--first-seed`, `--no-report`, `--quick`) are new.
//!
//! `cargo run --release --example lqmc -- [--no-toy] [--no-scenes]` and the shared flags
//! (`--time 2`, `--seeds 10`, `--size 64`, `--out target/lqmc`, `--quick`, scenes; `--help`).

use std::path::Path;

use clap::Parser;
use experiments::scatter::{coverage_table, keyed_uniform as uniform, point_panels};
use experiments::scatter::{torus_walk, PointSet, Window};
use experiments::{CommonOptions, Defaults, Experiment, Method, Regime, Results, RunValues};
use lqmc::{torus_difference, Rank1Lattice, ShiftedLattice};
use render::image_io::write_png;
use render::methods::{LqmcSettings, LqmcStats, MethodSettings, PssmltSettings, QmcSettings};
use render::session::RenderSettings;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

#[derive(Parser)]
struct Args {
    #[command(flatten)]
    common: CommonOptions,
    /// Skip the 2-D toy (Fig. 2).
    #[arg(long)]
    no_toy: bool,
    /// Skip the renders.
    #[arg(long)]
    no_scenes: bool,
}

/// A compared method: a paper preset at max depth 5.
fn method(name: &str, slug: &str, preset: impl Into<MethodSettings>) -> Method {
    let mut settings = RenderSettings::default();
    (settings.method, settings.max_depth) = (preset.into(), 5);
    Method::new(name, settings).with_slug(slug)
}

fn main() -> Res<()> {
    let mut defaults = Defaults::new("lqmc", Regime::seconds(2.0));
    let scenes = ["dof", "caustic-pool", "ajar-door"];
    (defaults.scenes, defaults.seeds) = (scenes.map(String::from).to_vec(), 10);
    defaults.out = "target/lqmc".into();
    (defaults.quick.scenes, defaults.quick.regime) = (None, Regime::seconds(0.25));
    let args = experiments::parse::<Args>(&defaults);
    let plan = args.common.plan(&defaults)?;
    std::fs::create_dir_all(&plan.out)?;
    let toy = (!args.no_toy).then(|| toy(&plan.out)).transpose()?;
    let toy = toy.unwrap_or_default();
    if args.no_scenes {
        render::files::write_bytes_atomic(plan.out.join("results.md"), &toy)?;
        println!("{toy}");
        return Ok(());
    }
    let first = plan.seeds[0];
    let mut counters = RunValues::default();
    let results = Experiment::new(plan)
        .methods([
            method("Halton QMC", "qmc", QmcSettings::default()),
            method("PSSMLT/K (KMLT)", "pssmlt-k", PssmltSettings::kelemen2002()),
            method("LQMC", "lqmc", LqmcSettings::tessari2020()),
        ])
        .baseline("Halton QMC")
        .parameter("max depth", 5)
        .inspect(|record, output, _| output.lqmc.map_or((), |s| counters.push(record, s)))
        .run()?;
    results.write(&(toy + &temporal(&results, &counters, first)?))?;
    Ok(())
}

/// Per scene the temporal-stability table (8 x 8 blocks) and LQMC's counters.
fn temporal(results: &Results, lqmc: &RunValues<LqmcStats>, first: u64) -> Res<String> {
    let seeds = results.plan.seeds.len();
    let mut md = format!("\n## Temporal stability ({seeds} seeds as frames)\n");
    for scene in &results.scenes {
        let table = results.temporal_table(scene, 8)?.to_markdown();
        md += &format!("\n### {scene}\n\n{table}");
        if let Some(s) = lqmc.get(scene, "LQMC", first) {
            md += &format!("\nLQMC, seed {first}: {s}.\n");
        }
    }
    Ok(md)
}

/// The toy of Fig. 2: writes the two figures, returns their markdown.
fn toy(out: &Path) -> Res<String> {
    let n = 128u32;
    let lattice = Rank1Lattice::new(n, vec![1, 12])?;
    let r = 1.0 / f64::from(n).sqrt();
    // Full torus: the lattice with a random Cranley-Patterson shift, the chain from a random start.
    let shift = [uniform(1, 0), uniform(1, 1)];
    let on_torus = |j| [0, 1].map(|d| (lattice.point(j)[d] + shift[d]).rem_euclid(1.0));
    let full_chain = torus_walk([uniform(2, 0), uniform(2, 1)], r, n as usize, 3);
    // Local: the seed's 1/4 tile, the lattice shifted onto the seed (Alg. 1 lines 3 and 7).
    let seed = [0.43, 0.61];
    let tile = Window::grid_cell(seed, 0.25);
    let t_seed = tile.local(seed).ok_or("the seed is outside its tile")?;
    let shifted = ShiftedLattice::through(&lattice, &t_seed);
    let to_tile = |t: [f64; 2]| [0, 1].map(|d| tile.origin[d] + t[d] * tile.side);
    let member = |j| {
        let mut t = [0.0; 2];
        shifted.member(&lattice, j, &mut t);
        to_tile(t)
    };
    let mut local_chain = torus_walk(t_seed, r, n as usize, 4);
    local_chain.iter_mut().for_each(|p| *p = to_tile(*p));
    let (red, blue) = ([0.8, 0.1, 0.1], [0.1, 0.3, 0.9]);
    let (full_lattice, local_lattice) =
        ((0..n).map(on_torus).collect(), (0..n).map(member).collect());
    let sets = [
        PointSet::new("lattice, full torus", full_lattice, red, Window::UNIT),
        PointSet::new("chain, full torus", full_chain, blue, Window::UNIT),
        PointSet::new("lattice, local tile", local_lattice, red, tile),
        PointSet::new("chain, local tile", local_chain, blue, tile),
    ];
    let png = |name: &str, s| write_png(out.join(name), &point_panels(s, 320), 0.0);
    png("toy_full.png", &sets[..2])?;
    png("toy_local.png", &sets[2..])?;
    let index = shifted.seed_index();
    let err = torus_difference(sets[2].points[index as usize][0], seed[0]).abs();
    Ok(format!(
        "## Toy (Fig. 2): N = {n}, rank-1 lattice g = (1, 12) vs a Markov chain with uniform steps in [-1/sqrt(N), 1/sqrt(N)]\n\n`toy_full.png` (unit torus) and `toy_local.png` (tile of side 1/4 around the seed ({}, {}); the lattice member {index} is the seed, |error| {err:.1e}); lattice red (left), chain blue (right).\n\n{}",
        seed[0], seed[1], coverage_table(&sets, 8).to_markdown()
    ))
}
