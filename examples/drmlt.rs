//! Delayed-rejection MLT (Rioux-Lavoie, Litalien et al. 2020): the three second-stage rules
//! on PSSMLT and MMLT against one-stage chains at equal time, and the 1-D toy of Fig. 3.
//!
//! Methods, paper presets at max depth 5: PSSMLT/K ([`PssmltSettings::kelemen2002`]);
//! PSSMLT/G, the same with a Gaussian small step whose sigma matches DR orbital's acceptance
//! on PSSMLT per scene (9 bisections of log sigma in [1e-4, 0.5] at 16 mutations per pixel,
//! seed 7, 20 000 bootstrap samples; fitted once and stored with its inputs in
//! `--calibration FILE`, default `OUT/pssmlt-g-calibration.json`); MMLT/K ([`MmltSettings::hachisuka2014`]); DR
//! Tierney-Mira, Green-Mira and orbital on PSSMLT and MMLT
//! ([`DrmltSettings::rioux_lavoie2020_with`]). In `--out` (default `target/drmlt`):
//! `results.md` (per scene relMSE and MAD median [min, max] over seeds, samples/s, acceptance,
//! step cost and relMSE relative to PSSMLT/K; the DR methods' acceptance per stage; the
//! calibration; the toy), `results.csv`, per scene a run directory with every image, the DR
//! stage maps (Fig. 1, 9: `<method>_stage2_seed<seed>.exr`, first seed also `.png`) and
//! `report.html`. The toy (eq. 8): MH with sigma 1 and 0.1 and Tierney-Mira DR (1 then 0.1),
//! 16 chains of 5x10^4 steps: acceptance, IAT, `toy_trace.png`, `toy_hist.png`.
//!
//! Changes from before the harness: acceptance per stage comes from the timed renders
//! (`--stats-only` is the old separate run: 16 mpp, seed 7, DR only) and counts candidates per
//! step (not Green-Mira's ghost); samples/s replaces Mmut/s; `results.csv` has the harness's
//! columns; PSSMLT/G's sigma is in the calibration table, not its name; every seed's stage map
//! is saved; the toy comes last; `--quick`: 16 x 16, 8 mpp, 2 seeds, cornell, cornell-glass.
//!
//! `cargo run --release --example drmlt -- [--time 4] [--seeds 5] [--size 64] [--out DIR]
//! [--no-toy] [--no-scenes] [--stats-only] [--quick] [--calibration FILE] [scene ...]`

use clap::Parser;
use experiments::match_acceptance_cached;
use experiments::{Bisection, Column, CommonOptions, Defaults, Experiment, Measure, Method};
use experiments::{Regime, RunContext, TableSpec, ToyStudy};
use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::toy::UniformMixture;
use mcmc_core::{DelayedRejection, GaussianRandomWalk, Mh};
use pss::SmallMutation;
use render::methods::{DrmltSettings, MethodSettings, MmltSettings, PssmltSettings};
use render::mlt::dr::{DrBase, DrVariant};
use render::session::{Budget, RenderSettings};

#[derive(Parser)]
struct Args {
    #[command(flatten)]
    common: CommonOptions,
    /// Skip the 1-D toy.
    #[arg(long)]
    no_toy: bool,
    /// Only the 1-D toy.
    #[arg(long)]
    no_scenes: bool,
    /// The calibration and the DR methods' acceptance per stage from one 16-mpp render each.
    #[arg(long)]
    stats_only: bool,
    /// Step cost only: DR orbital against one-stage Kelemen on the same base (PSSMLT over
    /// BDPT, PSSMLT over the path tracer, MMLT), no calibration, no toy; the table's
    /// samples/s give the ratios.
    #[arg(long)]
    step_cost: bool,
    /// One footing for every method (docs/methods/drmlt.md's required tables): DR orbital,
    /// Tierney-Mira and Green-Mira over PSSMLT (BDPT), PSSMLT over the path tracer and MMLT
    /// against PSSMLT/K, PSSMLT/G (both bases) and MMLT/K, all with the same direct pass
    /// (16 samples per pixel, depths 0-1), the same normalisation per scene (the mean
    /// luminance of `scenes/references/SCENE.exr`), large steps 0.3 without MIS.
    #[arg(long)]
    footing: bool,
    /// Where PSSMLT/G's calibration is stored with its inputs (default
    /// `OUT/pssmlt-g-calibration.json`): fitted by the first process that needs it and
    /// reused by the others (`--emit-jobs`, each `--run-one`, `--collect`); a stored fit on
    /// other inputs (scene, size, probe, bisection) is refitted.
    #[arg(long, value_name = "FILE")]
    calibration: Option<std::path::PathBuf>,
}

/// `preset` at max depth 5.
fn at_depth_5(method: MethodSettings) -> RenderSettings {
    let mut settings = RenderSettings::default();
    (settings.max_depth, settings.method) = (5, method);
    settings
}

/// `preset` at max depth 5, its images named `slug`.
fn method(name: &str, slug: &str, preset: impl Into<MethodSettings>) -> Method {
    Method::new(name, at_depth_5(preset.into())).with_slug(slug)
}

/// Kelemen's PSSMLT with a Gaussian small step of `sigma`.
fn gaussian(sigma: f64) -> MethodSettings {
    let mut s = PssmltSettings::kelemen2002();
    s.chain.small_step = SmallMutation::Gaussian { sigma };
    s.into()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let defaults = Defaults {
        scenes: ["glossy-highlight", "caustic-pool", "cornell-glass"]
            .map(String::from)
            .into(),
        seeds: 5,
        out: "target/drmlt".into(),
        ..Defaults::new("drmlt", Regime::seconds(4.0))
    };
    let args: Args = experiments::parse(&defaults);
    let mut plan = args.common.plan(&defaults)?;
    std::fs::create_dir_all(&plan.out)?;
    let toy = toy(&plan.out, !args.no_toy)?;
    if args.no_scenes {
        println!("{toy}");
        return Ok(render::files::write_bytes_atomic(
            plan.out.join("results.md"),
            toy,
        )?);
    }
    if args.stats_only {
        (plan.regime, plan.seeds, plan.report) = (Regime::EqualSamples(16), vec![7], false);
    }
    if args.step_cost {
        return step_cost(plan);
    }
    let footing = args
        .footing
        .then(|| Footing::for_scenes(&plan.scenes))
        .transpose()?;
    let cases = experiments::load_bundled(&plan.scenes, plan.size);
    let mut probe = at_depth_5(MethodSettings::default());
    (probe.budget, probe.threads, probe.seed) = (Budget::SamplesPerPixel(16), plan.threads, 7);
    let orbital = MethodSettings::from(DrmltSettings::rioux_lavoie2020()).with_chains(256, 20_000);
    let family = |sigma| gaussian(sigma).with_chains(256, 20_000);
    let bisect = Bisection::log(1e-4, 0.5, 9);
    let default_cache = plan.out.join("pssmlt-g-calibration.json");
    let cache = args.calibration.clone().unwrap_or(default_cache);
    let (fits, used) = match_acceptance_cached(&cache, &cases, &probe, orbital, family, bisect)?;
    if !used.reused.is_empty() {
        eprintln!(
            "PSSMLT/G calibration of {:?} read from {}",
            used.reused,
            cache.display()
        );
    }
    let sigma = fits.clone();
    let gaussian = move |c: &RunContext| at_depth_5(gaussian(sigma.value(c.scene)));
    let mut methods = vec![
        method("PSSMLT/K", "pssmlt-k", PssmltSettings::kelemen2002()),
        Method::from_fn("PSSMLT/G", gaussian).with_slug("pssmlt-g"),
    ];
    let mut dr = Vec::new();
    for (base, on) in [(DrBase::Pssmlt, "pssmlt"), (DrBase::Mmlt, "mmlt")] {
        if base == DrBase::Mmlt {
            methods.push(method("MMLT/K", "mmlt-k", MmltSettings::hachisuka2014()));
        }
        for &(rule, variant) in &DrVariant::ALL[..3] {
            let name = format!("DR {rule} on {}", on.to_uppercase());
            let preset = DrmltSettings::rioux_lavoie2020_with(variant, base);
            methods.push(method(&name, &format!("dr-{rule}-{on}"), preset));
            dr.push(name);
        }
    }
    if let Some(footing) = &footing {
        (methods, dr) = footing.methods(&fits);
    }
    methods.retain(|m| !args.stats_only || dr.contains(&m.name().to_owned()));
    let errors = TableSpec::errors([Measure::RelMse, Measure::Mad]).with(Column::step_cost());
    let errors = errors.with(Column::ratio(Measure::RelMse));
    let tables = [errors, TableSpec::acceptance_by_stage().only(dr.clone())];
    let Some(results) = Experiment::new(plan)
        .methods(methods)
        .baseline(if args.stats_only { &dr[2] } else { "PSSMLT/K" })
        .scenes(cases)
        .extra_image("stage2", |out| out.stage_map.clone())
        .parameter("max depth", 5)
        .parameter("chains", 256)
        .parameter("large-step probability", 0.3)
        .execute()?
    else {
        return Ok(()); // a job list written, or one run of it recorded
    };
    let calibration = fits.table("PSSMLT/G sigma").to_markdown();
    let extra = format!("## PSSMLT/G: sigma matched to DR orbital's acceptance on PSSMLT (16 mpp, seed 7)\n\n{calibration}{toy}");
    results.write_with(&tables[usize::from(args.stats_only)..], &extra)?;
    Ok(())
}

/// A method's settings per scene.
type MakeMethod = std::sync::Arc<dyn Fn(&str) -> MethodSettings + Send + Sync>;

/// `--footing`: the per-scene normalisation and the shared settings of every method.
struct Footing {
    /// The mean luminance of each scene's reference.
    b: std::collections::HashMap<String, f64>,
}

impl Footing {
    /// The normalisations of `scenes` from their references.
    fn for_scenes(scenes: &[String]) -> Result<Self, Box<dyn std::error::Error>> {
        let mut b = std::collections::HashMap::new();
        for scene in scenes {
            let path = format!("scenes/references/{scene}.exr");
            let image = render::image_io::read_exr(&path).map_err(|e| format!("{path}: {e}"))?;
            b.insert(scene.clone(), image.mean_luminance());
        }
        Ok(Self { b })
    }

    /// `method` at max depth 5 on the footing of `scene`: the direct pass, the given b,
    /// large steps 0.3 without MIS.
    fn apply(&self, scene: &str, method: MethodSettings) -> RenderSettings {
        use mcmc_core::render_loop::NormalizationMode;
        use render::methods::direct_pass::DirectSettings;
        use render::mlt::direct::DirectPass;
        let pass = DirectSettings {
            pass: DirectPass::Fixed(16),
            depth: 1,
            ..DirectSettings::OFF
        };
        let given = NormalizationMode::Given(self.b.get(scene).copied().unwrap_or(1.0));
        let mut method = method;
        match &mut method {
            MethodSettings::Pssmlt(s) => {
                (s.direct, s.direct_depth, s.sampler) = (pass.pass, pass.depth, pass.sampler);
                (s.large_step_mis, s.chain.normalization) = (false, given);
            }
            MethodSettings::Mmlt(s) => {
                (s.direct, s.large_step_mis, s.chain.normalization) = (pass, false, given);
            }
            MethodSettings::Drmlt(s) => {
                (s.direct, s.large_step_mis, s.chain.normalization) = (pass, false, given);
            }
            _ => {}
        }
        at_depth_5(method)
    }

    /// The methods of the footing tables and the DR ones among them, PSSMLT/G's sigma from
    /// `fits` per scene.
    fn methods(&self, fits: &experiments::Calibrations) -> (Vec<Method>, Vec<String>) {
        let pt = render::methods::PathBase::Pt;
        let mut one_stage: Vec<(String, String, MakeMethod)> = Vec::new();
        let sigma = fits.clone();
        let sigma_pt = fits.clone();
        one_stage.push((
            "PSSMLT/K".into(),
            "pssmlt-k".into(),
            std::sync::Arc::new(|_: &str| PssmltSettings::kelemen2002().into()),
        ));
        one_stage.push((
            "PSSMLT/G".into(),
            "pssmlt-g".into(),
            std::sync::Arc::new(move |sc: &str| gaussian(sigma.value(sc))),
        ));
        one_stage.push((
            "PSSMLT-PT/K".into(),
            "pssmlt-pt-k".into(),
            std::sync::Arc::new(move |_: &str| PssmltSettings::kelemen2002().on(pt).into()),
        ));
        one_stage.push((
            "PSSMLT-PT/G".into(),
            "pssmlt-pt-g".into(),
            std::sync::Arc::new(move |sc: &str| {
                let mut s = PssmltSettings::kelemen2002().on(pt);
                s.chain.small_step = SmallMutation::Gaussian {
                    sigma: sigma_pt.value(sc),
                };
                s.into()
            }),
        ));
        one_stage.push((
            "MMLT/K".into(),
            "mmlt-k".into(),
            std::sync::Arc::new(|_: &str| MmltSettings::hachisuka2014().into()),
        ));
        let mut dr = Vec::new();
        for (base, on) in [
            (DrBase::Pssmlt, "pssmlt"),
            (DrBase::PssmltPt, "pssmlt-pt"),
            (DrBase::Mmlt, "mmlt"),
        ] {
            for &(rule, variant) in &DrVariant::ALL[..3] {
                let name = format!("DR {rule} on {}", on.to_uppercase());
                let slug = format!("dr-{rule}-{on}");
                one_stage.push((
                    name.clone(),
                    slug,
                    std::sync::Arc::new(move |_: &str| {
                        DrmltSettings::rioux_lavoie2020_with(variant, base).into()
                    }),
                ));
                dr.push(name);
            }
        }
        let methods = one_stage
            .into_iter()
            .map(|(name, slug, make)| {
                let b = self.b.clone();
                let footing = Footing { b };
                Method::from_fn(&name, move |c: &RunContext| {
                    footing.apply(c.scene, make(c.scene))
                })
                .with_slug(&slug)
            })
            .collect();
        (methods, dr)
    }
}

/// `--step-cost`: DR orbital and one-stage Kelemen (PSSMLT/K's small step, large steps 0.3,
/// plain estimator, no direct pass) on each base, interleaved per seed.
fn step_cost(plan: experiments::Plan) -> Result<(), Box<dyn std::error::Error>> {
    let cases = experiments::load_bundled(&plan.scenes, plan.size);
    let pt = PssmltSettings::kelemen2002().on(render::methods::PathBase::Pt);
    let dr = DrmltSettings::rioux_lavoie2020_with;
    let methods = vec![
        method("PSSMLT/K", "pssmlt-k", PssmltSettings::kelemen2002()),
        method(
            "DR orbital on PSSMLT",
            "dr-pssmlt",
            dr(DrVariant::Orbital, DrBase::Pssmlt),
        ),
        method("PSSMLT-PT/K", "pssmlt-pt-k", pt),
        method(
            "DR orbital on PSSMLT-PT",
            "dr-pssmlt-pt",
            dr(DrVariant::Orbital, DrBase::PssmltPt),
        ),
        method("MMLT/K", "mmlt-k", MmltSettings::hachisuka2014()),
        method(
            "DR orbital on MMLT",
            "dr-mmlt",
            dr(DrVariant::Orbital, DrBase::Mmlt),
        ),
    ];
    let table = TableSpec::errors([Measure::RelMse]).with(Column::step_cost());
    let Some(results) = Experiment::new(plan)
        .methods(methods)
        .baseline("PSSMLT/K")
        .scenes(cases)
        .parameter("max depth", 5)
        .parameter("chains", 256)
        .parameter("large-step probability", 0.3)
        .execute()?
    else {
        return Ok(());
    };
    results.write_with(&[table], "")?;
    Ok(())
}

/// The 1-D toy of Fig. 3 (if `run`): `toy_trace.png` and `toy_hist.png`, and its markdown.
fn toy(out: &std::path::Path, run: bool) -> Result<String, experiments::ExperimentError> {
    let grw = |s| GaussianRandomWalk::new(s).expect("sigma > 0");
    let dr = DelayedRejection::tierney_mira(grw(1.0), IndependentSecondStage(grw(0.1)))
        .with_symmetric_second_stage();
    if !run {
        return Ok(String::new());
    }
    ToyStudy::new(UniformMixture::rioux_lavoie2020(), 16, 50_000)
        .kernel("MH, sigma 1 (large)", &Mh::new(grw(1.0)), 81)?
        .kernel("MH, sigma 0.1 (small)", &Mh::new(grw(0.1)), 82)?
        .kernel("DR Tierney-Mira, 1 then 0.1", &dr, 83)?
        .write(out, "toy", "Fig. 3 toy: alpha = 1/10, beta = 1", 110)
}
