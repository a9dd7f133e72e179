//! Langevin MCMC rendering (Luan et al. 2020): the four MALA adaptation variants against
//! PSSMLT, MMLT and cheap-then-expensive delayed rejection, at equal time on bundled scenes.
//!
//! Methods, each a paper preset at max depth 5 (large steps with probability 0.3):
//! - PSSMLT/K: [`PssmltSettings::kelemen2002_mis`] (Kelemen's small step, s1 = 1/1024,
//!   s2 = 1/64, large steps weighted by MIS);
//! - MMLT/K: [`MmltSettings::hachisuka2014`], the base MALA runs on and the baseline;
//! - MALA, MALA-online, MALA-cache, MALA-hybrid: [`MalaSettings::luan2020_variant`] (MALA on
//!   MMLT depths <= 3, Kelemen beyond; the paper's parameters);
//! - DR cheap-then-expensive: [`DrmltSettings::rioux_lavoie2020_with`] on MMLT with the
//!   paper's MALA as the expensive stage ([`MalaSettings::luan2020`]);
//! - MALA-online and MALA-hybrid (code preset): [`MalaSettings::luan2020_code`] (the authors'
//!   code: epsilon 0.005, K 5, H 3000, preconditioner clamped to [0.01, 100], shrink prior
//!   0.005) with the online and the hybrid variant.
//!
//! The `experiments` harness runs them interleaved (for seed, for scene, for method) and
//! writes `--out` (default `target/langevin`): `results.md` with per scene MSE (the paper's
//! metric) and relMSE against the scene's BDPT reference (median [min, max] over seeds),
//! samples per second, acceptance and MSE relative to MMLT/K; `results.csv`; and per scene a
//! run directory (every seed's image, `run.json`, `report.html`; each seed is one
//! error-vs-time sample). docs/methods/mala.md reports a run.
//!
//! Changes from the example before the harness: the table shows samples/s (was kmut/s) and
//! `results.csv` has the harness's columns (a superset); `results.md` names the regime,
//! commit and machine load; the shared flags (`--seeds`, `--size`, `--threads`, `--first-seed`, `--no-report`, ...), and
//! `--quick` (caustic-pool at 16 x 16, 8 mutations per pixel, 2 seeds).
//!
//! `cargo run --release --example langevin -- [--time 3 | --spp N] [--seeds 5] [--size 64]
//! [--out DIR] [--quick] [scene ...]` (`--spp`: equal mutations per pixel instead of equal
//! time, to separate a method's cost per mutation from its efficiency per mutation).

use experiments::TableSpec;
use experiments::{Column, CommonOptions, Defaults, Experiment, Measure, Method, Quick, Regime};
use render::methods::{DrmltSettings, MalaSettings, MethodSettings, MmltSettings, PssmltSettings};
use render::mlt::dr::{DrBase, DrVariant};
use render::mlt::mala::MalaVariant;
use render::session::RenderSettings;

/// `preset` at max depth 5, named `name`, its images `slug`.
fn method(name: &str, slug: &str, preset: impl Into<MethodSettings>) -> Method {
    let mut settings = RenderSettings::default();
    (settings.max_depth, settings.method) = (5, preset.into());
    Method::new(name, settings).with_slug(slug)
}

/// The authors' code's constants ([`MalaSettings::luan2020_code`]) with `variant`.
fn code(variant: MalaVariant) -> MalaSettings {
    let mut settings = MalaSettings::luan2020_code();
    settings.config.variant = variant;
    settings
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let defaults = Defaults {
        scenes: ["caustic-pool", "motion-blur", "glossy-highlight"]
            .map(String::from)
            .into(),
        seeds: 5,
        out: "target/langevin".into(),
        quick: Quick {
            scenes: Some(vec!["caustic-pool".into()]),
            ..Quick::default()
        },
        ..Defaults::new("langevin", Regime::seconds(3.0))
    };
    let plan = experiments::parse::<CommonOptions>(&defaults).plan(&defaults)?;
    let mut methods = vec![
        method("PSSMLT/K", "pssmlt-k", PssmltSettings::kelemen2002_mis()),
        method("MMLT/K", "mmlt-k", MmltSettings::hachisuka2014()),
    ];
    for (slug, variant) in MalaVariant::ALL {
        let name = slug.replacen("mala", "MALA", 1);
        methods.push(method(&name, slug, MalaSettings::luan2020_variant(variant)));
    }
    let cte = DrmltSettings::rioux_lavoie2020_with(DrVariant::CheapThenExpensive, DrBase::Mmlt);
    let cte = DrmltSettings {
        mala: MalaSettings::luan2020().config,
        ..cte
    };
    methods.push(method("DR cheap-then-expensive", "dr-cte", cte));
    let online = code(MalaVariant::Online);
    methods.push(method(
        "MALA-online (code preset)",
        "mala-online-code",
        online,
    ));
    let hybrid = code(MalaVariant::Hybrid);
    methods.push(method(
        "MALA-hybrid (code preset)",
        "mala-hybrid-code",
        hybrid,
    ));
    let table =
        TableSpec::errors([Measure::Mse, Measure::RelMse]).with(Column::ratio(Measure::Mse));
    let Some(results) = Experiment::new(plan)
        .methods(methods)
        .baseline("MMLT/K")
        .parameter("max depth", 5)
        .parameter("large-step probability", 0.3)
        .execute()?
    else {
        return Ok(()); // a job list written, or one run of it recorded
    };
    results.write_with(&[table], "")?;
    Ok(())
}
