//! The cost of regional adaptation's bookkeeping (Otsu et al. 2018): mutations per second of
//! pathmlt with `--adapt global|grid|quadtree` against FIXED at the same scale, at equal
//! mutations on one thread.
//!
//! To compare at the same scale, the adaptive run is a *probe*: the full controller (records,
//! pooling in job and chain order, one sign step per `L` visits written to the shared scales,
//! quadtree refinement, synchronisation every `ADAPT_ROUND_MUTATIONS` mutations per chain) with
//! `gamma_max = 1e-9`, so that `sigma` stays at FIXED's (0.02 rad) to within 10^-5 while every
//! update still runs. One render per process: `scripts/regional_overhead.sh` runs each case
//! under the measurement lock, interleaved, and the ratio is taken there.
//!
//! Time is the process's CPU time (user + system, from `/proc/self/stat`; wall-clock time where
//! that is unavailable): on a machine shared with other work, a one-thread render's CPU time
//! does not count the time other processes held the core.
//!
//! `cargo run --release --example regional_overhead -- <scene> <lens|multichain>
//! <fixed|global|grid|quadtree> [mutations per pixel, 100] [size, 64] [round mutations]
//! [frozen]` prints one CSV line (`frozen`: the regional kernel with adaptation frozen from the
//! start, i.e. the per-region scale lookups of eq. 2-3 without any bookkeeping; run it with
//! rounds of 1000 to separate what the regional kernel costs from what adapting costs):
//! `scene,perturbation,adapt,mutations,cpu_seconds,mutations_per_cpu_second,regions,wall_seconds`.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use mcmc_core::render_loop::Shard;
use pathspace::PerturbationKind;
use render::mlt::pathmlt::{
    adapt_params, render_scaled, AdaptRender, PathAdapt, ADAPT_ROUND_MUTATIONS, PATHMLT_SIGMA,
};
use render::mlt::{LargeStepMode, MltBudget, MltSettings};
use render::session::NoProgress;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: regional_overhead <scene> <lens|multichain> <fixed|global|grid|quadtree> [mpp] [size] [round mutations] [frozen]";
    let [scene_name, kind, adapt, ..] = args.as_slice() else {
        return Err(usage.into());
    };
    let kind = match kind.as_str() {
        "lens" => PerturbationKind::Lens,
        "multichain" => PerturbationKind::MultiChain,
        _ => return Err(usage.into()),
    };
    let adapt = match adapt.as_str() {
        "fixed" => PathAdapt::Fixed,
        "global" => PathAdapt::Global,
        "grid" => PathAdapt::Grid,
        "quadtree" => PathAdapt::Quadtree,
        _ => return Err(usage.into()),
    };
    let mpp: f64 = args.get(3).map_or(Ok(100.0), |s| s.parse())?;
    let size: u32 = args.get(4).map_or(Ok(64), |s| s.parse())?;
    let round: u64 = args
        .get(5)
        .map_or(Ok(ADAPT_ROUND_MUTATIONS), |s| s.parse())?;
    let (scene, _) = render::bundled::bundled(scene_name, size)?;
    let settings = MltSettings {
        width: size as usize,
        height: size as usize,
        chains: 256,
        bootstrap_samples: 100_000,
        budget: MltBudget::MutationsPerPixel(mpp),
        large_step: LargeStepMode::Fixed(0.0),
        seed: 1,
        streams: 1,
        stage_map: false,
        shard: Shard::default(),
        normalization: mcmc_core::render_loop::NormalizationMode::Pooled,
    };
    let frozen = match args.get(6).map(String::as_str) {
        None => false,
        Some("frozen") => true,
        Some(_) => return Err(usage.into()),
    };
    let mut params = adapt_params(adapt, kind, PATHMLT_SIGMA, &settings);
    params.adapt.gamma_max = 1e-9;
    if frozen {
        params.freeze_after_mutations = Some(0);
    }
    let run = AdaptRender {
        kind,
        adapt,
        sigma: PATHMLT_SIGMA,
        round_mutations: round,
        max_depth: 5,
        params,
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let (start, cpu_start) = (Instant::now(), cpu_seconds());
    let (out, _, summary) = pool.install(|| {
        render_scaled(
            &scene,
            &run,
            &settings,
            &NoProgress,
            &AtomicBool::new(false),
        )
    })?;
    let wall = start.elapsed().as_secs_f64();
    let seconds = match (cpu_start, cpu_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => wall,
    };
    println!(
        "{scene_name},{},{},{},{seconds:.3},{:.0},{},{wall:.3}",
        match kind {
            PerturbationKind::Lens => "lens",
            PerturbationKind::MultiChain => "multichain",
        },
        adapt.name(),
        out.mutations,
        out.mutations as f64 / seconds,
        summary.map_or(0, |s| s.regions)
    );
    Ok(())
}

/// CPU time of this process (all threads, user + system) in seconds, from `/proc/self/stat`.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at field 3.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    // Linux reports clock ticks of USER_HZ = 100.
    Some((utime + stime) / 100.0)
}
