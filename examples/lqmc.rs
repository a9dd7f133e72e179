//! Local quasi-Monte Carlo exploration (Tessari, Hanika & Dachsbacher 2020): the 2-D toy of
//! Fig. 2 and an equal-time renderer comparison with temporal stability, every method over
//! the same sampler.
//!
//! The toy: `N = 128` points on the unit torus, the rank-1 lattice `g = (1, 12)` against a
//! Markov chain of uniform steps in `[-1/sqrt(N), 1/sqrt(N)]^2`, on the full torus and locally
//! (a 1/4 tile around a seed: the lattice shifted onto the seed, the chain's steps scaled to the
//! tile): `toy_full.png`, `toy_local.png` (lattice red, chain blue) and the cells of an 8 x 8
//! grid each set hits (`--no-toy` skips it).
//!
//! The renders (`--no-scenes` skips them), all over one base sampler, the unidirectional path
//! tracer with next-event estimation and no Russian roulette (LQMC's tracer has none; max
//! depth 5 bounds every path): Halton QMC (`QmcSettings` with roulette off), KMLT as the
//! authors' renderer runs it (`PssmltSettings::corona13_kmlt()`: PSSMLT over the path tracer,
//! large steps 0.2, a uniform small step of 0.01), LQMC by the paper's rule
//! (`LqmcSettings::tessari2020()`: NEE paths splatted unexplored) and by the authors' code
//! (`LqmcSettings::tessari2020_code()`: NEE paths explored with `N = 7`); `--bdpt-kmlt` adds
//! the earlier pairing, PSSMLT/K over all-strategy BDPT (`PssmltSettings::kelemen2002()`).
//! Scenes dof, caustic-pool, ajar-door; 30 s per render, 5 seeds, 128 x 128, every core.
//! The `experiments` harness writes per scene `<out>/<scene>/` (every seed's image, `run.json`,
//! `report.html`), `results.md` (its table: relMSE, MSE, rRMSE, MAD against the BDPT reference,
//! samples/s; then the temporal stability: the seeds' renders as the frames of a still
//! animation, as the paper's video loops frames rendered with different seeds: the per-pixel
//! luminance variance across frames next to the mean MSE, and the 8 x 8-block ratio, 1 for
//! uncorrelated noise, more for blotches; and both LQMC variants' counters, explored and
//! unexplored contributions, summed over the seeds) and `results.csv`. The paper's video has
//! 10 frames: `--seeds 10`. `--quick`: 0.25 s, 2 seeds, 16 x 16.
//!
//! `cargo run --release --example lqmc -- [--no-toy] [--no-scenes] [--bdpt-kmlt]` and the
//! shared flags (`--time 30`, `--seeds 5`, `--size 128`, `--threads`, `--out target/lqmc`,
//! `--no-report`, `--quick`, scenes; `--help`).

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
    /// Also render PSSMLT/K over all-strategy BDPT (the earlier, unequal pairing).
    #[arg(long)]
    bdpt_kmlt: bool,
}

/// The LQMC variants compared (their counters are reported).
const LQMC_PAPER: &str = "LQMC (paper: NEE unexplored)";
const LQMC_CODE: &str = "LQMC (code: NEE explored, N = 7)";

/// A compared method: a paper preset at max depth 5.
fn method(name: &str, slug: &str, preset: impl Into<MethodSettings>) -> Method {
    let mut settings = RenderSettings::default();
    (settings.method, settings.max_depth) = (preset.into(), 5);
    Method::new(name, settings).with_slug(slug)
}

fn main() -> Res<()> {
    let mut defaults = Defaults::new("lqmc", Regime::seconds(30.0));
    let scenes = ["dof", "caustic-pool", "ajar-door"];
    (defaults.scenes, defaults.seeds) = (scenes.map(String::from).to_vec(), 5);
    defaults.size = 128;
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
    let mut counters = RunValues::default();
    let qmc = QmcSettings {
        roulette: None,
        ..QmcSettings::default()
    };
    let mut methods = vec![
        method("Halton QMC", "qmc", qmc),
        method(
            "KMLT (corona-13, over PT)",
            "kmlt-pt",
            PssmltSettings::corona13_kmlt(),
        ),
        method(LQMC_PAPER, "lqmc", LqmcSettings::tessari2020()),
        method(LQMC_CODE, "lqmc-code", LqmcSettings::tessari2020_code()),
    ];
    if args.bdpt_kmlt {
        let kmlt = PssmltSettings::kelemen2002();
        methods.push(method("PSSMLT/K over BDPT", "pssmlt-k", kmlt));
    }
    let results = Experiment::new(plan)
        .methods(methods)
        .baseline("Halton QMC")
        .parameter("max depth", 5)
        .parameter("base sampler", "PT + NEE, no Russian roulette")
        .inspect(|record, output, _| output.lqmc.map_or((), |s| counters.push(record, s)))
        .run()?;
    results.write(&(toy + &temporal(&results, &counters)?))?;
    Ok(())
}

/// Per scene the temporal-stability table (8 x 8 blocks) and the LQMC variants' counters
/// summed over the seeds.
fn temporal(results: &Results, lqmc: &RunValues<LqmcStats>) -> Res<String> {
    let seeds = &results.plan.seeds;
    let mut md = format!(
        "\n## Temporal stability ({} seeds as frames)\n",
        seeds.len()
    );
    for scene in &results.scenes {
        let table = results.temporal_table(scene, 8)?.to_markdown();
        md += &format!("\n### {scene}\n\n{table}");
        for name in [LQMC_PAPER, LQMC_CODE] {
            let runs: Vec<LqmcStats> = seeds
                .iter()
                .filter_map(|&seed| lqmc.get(scene, name, seed).copied())
                .collect();
            if runs.is_empty() {
                continue;
            }
            let sum = |f: fn(&LqmcStats) -> u64| runs.iter().map(f).sum::<u64>();
            let n = runs.len() as u64;
            md += &format!(
                "\n{name}, per render (mean of {n}): {} seeds, {} contributions explored ({} NEE), {} splatted unexplored ({} NEE), {} members, {} rejected.\n",
                sum(|s| s.seeds) / n,
                sum(|s| s.explored) / n,
                sum(|s| s.explored_nee) / n,
                sum(|s| s.direct) / n,
                sum(|s| s.direct_nee) / n,
                sum(|s| s.members) / n,
                sum(|s| s.rejected) / n,
            );
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
