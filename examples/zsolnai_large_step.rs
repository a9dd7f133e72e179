//! Automatic large-step control (Zsolnai & Szirmay-Kalos 2013) on the bundled scenes: does the
//! automatic `p_l` fall inside the optimal range of a fixed-`p_l` sweep (the paper's Table 1
//! test), with the plain estimator and with large-step MIS?
//!
//! For each scene and estimator (plain: Kelemen eq. 5; `mis`: large steps weighted by
//! Kelemen's MIS, as in LuxRender where the paper measured): PSSMLT with automatic control
//! (the measured `eta_s`, `eta_l`, `eta_0` and the chosen `p_l` are recorded), then a sweep of
//! fixed `p_l` in {0.1, ..., 1.0} at the same mutation count; relMSE against the scene's BDPT
//! reference (`scenes/references/<scene>.exr`, box-downsampled to the render size) over the
//! seeds.
//!
//! **The optimal range** (fixed before the results were seen): with `n` seeds, the best `p` is
//! the sweep value of least median relMSE; its median's standard error is estimated from the
//! seeds as `1.2533 * (IQR / 1.349) / sqrt(n)` (the normal-theory error of a median, with the
//! spread taken robustly from the interquartile range); the band is `[best median, best
//! median + 2 standard errors]` and the optimal range is every sweep `p` whose median relMSE
//! lies in it. The automatic control is **inside** when the sweep value nearest its chosen
//! `p_l` (median over seeds) is in the optimal range; the table also says whether the
//! automatic run's own median relMSE lies in the band.
//!
//! The `experiments` harness runs it: per scene a run directory `<out>/<scene>/` (default
//! `--out out/zsolnai_large_step`) with every method's image per seed, error-vs-time samples
//! from extra runs at 1/8, 1/4 and 1/2 of the budget, `run.json` and a self-contained
//! `report.html` (rebuild it with `chainlight report <out>/<scene>`); `results.md` (the
//! harness's table per scene, then this example's band tables) and `results.csv` in `<out>`.
//! `--no-report` skips the reports and the extra runs; `--quick` is a smoke run (16 x 16,
//! 8 mutations per pixel, 2 seeds, cornell and cornell-glass).
//!
//! `cargo run --release --example zsolnai_large_step -- [--size 64] [--mpp 64] [--runs 7]
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

/// The two estimators: the method-name suffix and whether large steps are MIS-weighted.
const ESTIMATORS: [(&str, bool); 2] = [("", false), (" mis", true)];

/// The name of the automatic run of an estimator.
fn auto_name(suffix: &str) -> String {
    format!("auto{suffix}")
}

/// The name of the fixed-`p` run of an estimator.
fn fixed_name(p: f64, suffix: &str) -> String {
    format!("p_l={p:.1}{suffix}")
}

/// PSSMLT over BDPT from a paper preset with 20 000 bootstrap samples, max depth 5: automatic
/// control is [`PssmltSettings::zsolnai2013`] (an estimation phase at `p_l = 0.5`, then
/// section 2's `p_l`), the sweep [`PssmltSettings::kelemen2002`] at a fixed `p_l`; `mis`
/// turns large-step MIS on for either.
fn pssmlt(name: String, mut preset: PssmltSettings, mis: bool) -> Method {
    preset.chain.bootstrap_samples = 20_000;
    preset.large_step_mis = mis;
    let mode = match preset.chain.large_step {
        LargeStepMode::Fixed(p) => format!("fixed p_large = {p}"),
        other => format!("{other:?}"),
    };
    let settings = RenderSettings {
        max_depth: 5,
        method: preset.into(),
        ..RenderSettings::default()
    };
    Method::new(name, settings)
        .with_parameter("large step", mode)
        .with_parameter("large-step MIS", mis)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let defaults = Defaults {
        first_seed: 100,
        seeds: 7,
        ..Defaults::new("zsolnai_large_step", Regime::EqualSamples(64))
    };
    let plan = experiments::parse::<CommonOptions>(&defaults).plan(&defaults)?;
    let mut methods = Vec::new();
    for (suffix, mis) in ESTIMATORS {
        methods.push(pssmlt(
            auto_name(suffix),
            PssmltSettings::zsolnai2013(),
            mis,
        ));
        methods.extend(sweep().into_iter().map(|p| {
            let mut fixed = PssmltSettings::kelemen2002();
            fixed.chain.large_step = LargeStepMode::Fixed(p);
            pssmlt(fixed_name(p, suffix), fixed, mis).with_baseline(auto_name(suffix))
        }));
    }
    let Some(results) = Experiment::new(plan)
        .methods(methods)
        .convergence(&[0.125, 0.25, 0.5])
        .parameter("integrator", "pssmlt over BDPT")
        .parameter("chains", 256)
        .parameter("max depth", 5)
        .parameter("bootstrap samples", 20_000)
        .scene_parameters(|results, scene| {
            ESTIMATORS
                .iter()
                .filter_map(|(suffix, _)| {
                    let e = etas(results, scene, suffix)?;
                    Some((
                        format!("{}: median eta_s, eta_l, eta_0, p_l", auto_name(suffix)),
                        format!("{:.3}, {:.3}, {:.3}, {:.3}", e[0], e[1], e[2], e[3]),
                    ))
                })
                .collect()
        })
        .execute()?
    else {
        return Ok(()); // a job list written, or one run of it recorded
    };
    let mut markdown = String::new();
    for (suffix, mis) in ESTIMATORS {
        markdown.push_str(&band_table(&results, suffix, mis));
        markdown.push('\n');
    }
    results.write(&markdown)?;
    Ok(())
}

/// Median over seeds of `eta_s`, `eta_l`, `eta_0` and `p_l` of an estimator's automatic runs.
fn etas(results: &Results, scene: &str, suffix: &str) -> Option<[f64; 4]> {
    let estimates: Vec<_> = results
        .runs(scene, &auto_name(suffix))
        .filter_map(|r| r.stats.large_step)
        .collect();
    if estimates.is_empty() {
        return None;
    }
    let med = |f: fn(&experiments::LargeStepStats) -> f64| {
        experiments::median(&estimates.iter().map(f).collect::<Vec<_>>())
    };
    Some([
        med(|e| e.eta_s),
        med(|e| e.eta_l),
        med(|e| e.eta_0),
        med(|e| e.p_large),
    ])
}

/// The `q`-quantile of `values` (linear interpolation between order statistics; NaN for none).
fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let x = q * (v.len() - 1) as f64;
    let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (x - lo as f64)
}

/// The seed-noise band of a sweep: the best value's index, the band's upper end (best median
/// plus two standard errors of that median, `1.2533 * (IQR / 1.349) / sqrt(n)`) and which
/// sweep values have their median inside it. `errors[i]` holds sweep value `i`'s per-seed
/// errors.
fn seed_noise_band(errors: &[Vec<f64>]) -> Option<(usize, f64, Vec<bool>)> {
    let medians: Vec<f64> = errors.iter().map(|e| experiments::median(e)).collect();
    let best = (0..medians.len())
        .filter(|&i| medians[i].is_finite())
        .min_by(|&a, &b| medians[a].total_cmp(&medians[b]))?;
    let e = &errors[best];
    let iqr = quantile(e, 0.75) - quantile(e, 0.25);
    let standard_error = 1.2533 * (iqr / 1.349) / (e.len() as f64).sqrt();
    let upper = medians[best] + 2.0 * standard_error;
    let inside = medians.iter().map(|&m| m <= upper).collect();
    Some((best, upper, inside))
}

/// One row per scene for one estimator: the automatic estimate, the sweep's median relMSE
/// (`+` marks the optimal range), the best `p`, the band, and whether the automatic control is
/// inside it; then the count of scenes with the automatic choice inside.
fn band_table(results: &Results, suffix: &str, mis: bool) -> String {
    let sweep = sweep();
    let mut headers: Vec<String> = ["scene", "eta_s", "eta_l", "eta_0", "auto p_l"]
        .map(String::from)
        .to_vec();
    headers.extend(sweep.iter().map(|p| format!("p={p:.1}")));
    headers.extend(
        [
            "best p",
            "band (relMSE)",
            "optimal range",
            "auto relMSE",
            "auto p in range",
            "auto relMSE in band",
        ]
        .map(String::from),
    );
    let mut table = Table::new(headers);
    let (mut inside_p, mut inside_err, mut scenes) = (0, 0, 0);
    for scene in &results.scenes {
        let [s, l, z, p] = etas(results, scene, suffix).unwrap_or([f64::NAN; 4]);
        let auto = results.median(scene, &auto_name(suffix), Measure::RelMse);
        let errors: Vec<Vec<f64>> = sweep
            .iter()
            .map(|&q| results.values(scene, &fixed_name(q, suffix), Measure::RelMse))
            .collect();
        let Some((best, upper, inside)) = seed_noise_band(&errors) else {
            continue;
        };
        scenes += 1;
        let mut row = vec![scene.clone()];
        row.extend([s, l, z].map(|v| format!("{v:.3}")));
        row.push(format!("**{p:.2}**"));
        for (e, &member) in errors.iter().zip(&inside) {
            let mark = if member { "+" } else { "" };
            row.push(format!("{:.4}{mark}", experiments::median(e)));
        }
        let members: Vec<f64> = sweep
            .iter()
            .zip(&inside)
            .filter(|(_, &m)| m)
            .map(|(&q, _)| q)
            .collect();
        // The sweep value nearest the automatic p_l (ties go to the lower value).
        let nearest =
            (0..sweep.len()).min_by(|&a, &b| (sweep[a] - p).abs().total_cmp(&(sweep[b] - p).abs()));
        let p_inside = nearest.is_some_and(|i| inside[i]);
        let err_inside = auto <= upper;
        inside_p += usize::from(p_inside);
        inside_err += usize::from(err_inside);
        row.push(format!("{:.1}", sweep[best]));
        row.push(format!(
            "{:.4}..{upper:.4}",
            experiments::median(&errors[best])
        ));
        row.push(
            members
                .iter()
                .map(|q| format!("{q:.1}"))
                .collect::<Vec<_>>()
                .join(", "),
        );
        row.push(format!("{auto:.4}"));
        row.push(if p_inside { "**yes**" } else { "no" }.to_owned());
        row.push(if err_inside { "yes" } else { "no" }.to_owned());
        table.push_row(row);
    }
    format!(
        "## Automatic p_l vs the optimal range, {} (PSSMLT over BDPT, {}, relMSE over {} seeds)\n\n{}\n`+` marks the optimal range: sweep values whose median relMSE lies within the best's median plus two standard errors of that median (1.2533 IQR / 1.349 / sqrt(n)). **Auto p_l inside the optimal range on {inside_p} of {scenes} scenes**; auto's own median relMSE inside the band on {inside_err} of {scenes}.\n",
        if mis { "large-step MIS" } else { "plain estimator" },
        results.plan.regime,
        results.plan.seeds.len(),
        table.to_markdown()
    )
}
