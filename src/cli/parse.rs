//! Value parsers for flags clap cannot range-check by itself (floating-point durations, stops).

use std::time::Duration;

/// The largest `--time` budget: one week.
pub(crate) const MAX_SECONDS: f64 = 7.0 * 24.0 * 3600.0;

/// Parses `--time` seconds: a finite number in (0, one week].
pub(crate) fn seconds(text: &str) -> Result<Duration, String> {
    let value: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("expected a number of seconds in (0, {MAX_SECONDS}], got '{text}'"))?;
    if value.is_finite() && value > 0.0 && value <= MAX_SECONDS {
        Ok(Duration::from_secs_f64(value))
    } else {
        Err(format!(
            "must be in (0, {MAX_SECONDS}] seconds, got {value}"
        ))
    }
}

/// Parses `--exposure` stops: a finite number in [-64, 64].
/// `--large-step`: `auto`, a probability in 0..=1, or `P1,P2` (a warm-up schedule, both
/// in 0..=1).
pub(crate) fn large_step(text: &str) -> Result<render::mlt::LargeStepMode, String> {
    use render::mlt::LargeStepMode;
    if text.eq_ignore_ascii_case("auto") {
        return Ok(LargeStepMode::Auto {
            initial: 0.5,
            estimation_steps: 1_000,
        });
    }
    let probability = |t: &str| match t.trim().parse::<f64>() {
        Ok(p) if (0.0..=1.0).contains(&p) => Some(p),
        _ => None,
    };
    let parsed = match text.split_once(',') {
        Some((a, b)) => probability(a)
            .zip(probability(b))
            .map(|(initial, then)| LargeStepMode::Schedule { initial, then }),
        None => probability(text).map(LargeStepMode::Fixed),
    };
    parsed.ok_or_else(|| {
        format!("expected `auto`, a probability in 0..=1 or two of them as P1,P2, got '{text}'")
    })
}

/// `--direct-share`: `auto` (the balanced pass) or a share of the budget in 0.01..=0.9.
pub(crate) fn direct_share(text: &str) -> Result<render::mlt::direct::DirectPass, String> {
    if text.eq_ignore_ascii_case("auto") {
        return Ok(render::mlt::direct::DirectPass::PSSMLT_DEFAULT);
    }
    match text.parse::<f64>() {
        Ok(s) if (0.01..=0.9).contains(&s) => {
            Ok(render::mlt::direct::DirectPass::with_time_share(s))
        }
        _ => Err(format!(
            "expected `auto` or a share of the budget in 0.01..=0.9, got '{text}'"
        )),
    }
}

/// `--normalization`: `pooled`, `bootstrap`, a number `b > 0`, or an image file whose mean
/// Rec. 709 luminance is `b` (a reference rendering: every method then has its brightness).
pub(crate) fn normalization(
    text: &str,
) -> Result<mcmc_core::render_loop::NormalizationMode, String> {
    use mcmc_core::render_loop::NormalizationMode;
    if text.eq_ignore_ascii_case("pooled") {
        return Ok(NormalizationMode::Pooled);
    }
    if text.eq_ignore_ascii_case("bootstrap") {
        return Ok(NormalizationMode::Bootstrap);
    }
    if let Ok(b) = text.trim().parse::<f64>() {
        return if b.is_finite() && b > 0.0 {
            Ok(NormalizationMode::Given(b))
        } else {
            Err(format!(
                "a given normalisation must be a finite number > 0, got '{text}'"
            ))
        };
    }
    let path = std::path::Path::new(text);
    if !path.is_file() {
        return Err(format!(
            "expected `pooled`, `bootstrap`, a number > 0 or an image file (.exr, .hdr, .pfm), got '{text}' (no such file)"
        ));
    }
    let image = render::image_io::read_image(path)
        .map_err(|e| format!("cannot read the reference image '{text}': {e}"))?;
    let b = image.mean_luminance();
    if b.is_finite() && b > 0.0 {
        Ok(NormalizationMode::Given(b))
    } else {
        Err(format!(
            "the reference image '{text}' has mean luminance {b}: a normalisation needs a finite mean > 0"
        ))
    }
}

/// `--small-step`: `kelemen`, `kelemen=S1,S2`, `gaussian=SIGMA` or `uniform=A`.
pub(crate) fn small_step(text: &str) -> Result<pss::SmallMutation, String> {
    if text.eq_ignore_ascii_case("kelemen") {
        return pss::SmallMutation::kelemen(pss::KelemenParams::kelemen2002())
            .map_err(|e| e.to_string());
    }
    let expected = || {
        format!(
            "expected `kelemen`, `kelemen=S1,S2`, `gaussian=SIGMA` or `uniform=A`, got '{text}'"
        )
    };
    if let Some(pair) = text.strip_prefix("kelemen=") {
        let (s1, s2) = pair.split_once(',').ok_or_else(expected)?;
        let s1 = s1.trim().parse::<f64>().map_err(|_| expected())?;
        let s2 = s2.trim().parse::<f64>().map_err(|_| expected())?;
        return pss::SmallMutation::kelemen(pss::KelemenParams { s1, s2 })
            .map_err(|e| e.to_string());
    }
    if let Some(amount) = text.strip_prefix("uniform=") {
        let amount = amount.trim().parse::<f64>().map_err(|_| expected())?;
        return pss::SmallMutation::uniform(amount).map_err(|e| e.to_string());
    }
    let sigma = text
        .strip_prefix("gaussian=")
        .and_then(|v| v.parse::<f64>().ok())
        .ok_or_else(expected)?;
    pss::SmallMutation::gaussian(sigma).map_err(|e| e.to_string())
}

pub(crate) fn stops(text: &str) -> Result<f32, String> {
    let value: f32 = text
        .trim()
        .parse()
        .map_err(|_| format!("expected a number of stops in -64..=64, got '{text}'"))?;
    if value.is_finite() && (-64.0..=64.0).contains(&value) {
        Ok(value)
    } else {
        Err(format!("must be in -64..=64 stops, got {value}"))
    }
}

/// Parses a finite, strictly positive number (error-map bounds).
pub(crate) fn positive(text: &str) -> Result<f32, String> {
    let value: f32 = text
        .trim()
        .parse()
        .map_err(|_| format!("expected a positive number, got '{text}'"))?;
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(format!("must be finite and > 0, got {value}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges() {
        assert_eq!(seconds("1.5"), Ok(Duration::from_millis(1500)));
        for bad in ["0", "-1", "nan", "inf", "1e9", "abc", ""] {
            assert!(seconds(bad).is_err(), "{bad}");
        }
        assert_eq!(stops("-2"), Ok(-2.0));
        assert!(stops("100").is_err() && stops("NaN").is_err());
        assert_eq!(positive("1e-3"), Ok(1e-3));
        assert!(positive("0").is_err() && positive("-1").is_err() && positive("inf").is_err());
    }

    #[test]
    fn large_step_schedules() {
        use render::mlt::LargeStepMode;
        assert_eq!(large_step("0.3"), Ok(LargeStepMode::Fixed(0.3)));
        assert_eq!(
            large_step("0.05, 0.2"),
            Ok(LargeStepMode::Schedule {
                initial: 0.05,
                then: 0.2
            })
        );
        for bad in [
            "0.05,",
            ",0.2",
            "0.05,1.5",
            "0.05,0.2,0.3",
            "-1,0.2",
            "often",
        ] {
            let err = large_step(bad).expect_err(bad);
            assert!(err.contains("P1,P2"), "{bad}: {err}");
        }
    }
}

/// The value of `--env`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum EnvArg {
    /// No environment.
    None,
    /// A constant radiance.
    Rgb([f32; 3]),
    /// An equirectangular map file.
    File(std::path::PathBuf),
}

/// The largest radiance component `--env R,G,B` accepts.
const MAX_ENV_RADIANCE: f32 = 1e6;

/// Parses `--env`: `none`, `R,G,B` or `V` (finite, 0..=1e6), or an existing .exr/.hdr/.pfm
/// file.
pub(crate) fn environment(text: &str) -> Result<EnvArg, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("none") {
        return Ok(EnvArg::None);
    }
    let parts: Vec<&str> = t.split(',').map(str::trim).collect();
    let numbers: Option<Vec<f32>> = parts.iter().map(|p| p.parse::<f32>().ok()).collect();
    if let Some(v) = numbers {
        let rgb = match v.as_slice() {
            [g] => [*g; 3],
            [r, g, b] => [*r, *g, *b],
            _ => {
                return Err(format!(
                    "expected `none`, `R,G,B`, a grey value or a file, got '{text}'"
                ))
            }
        };
        if rgb
            .iter()
            .all(|c| c.is_finite() && (0.0..=MAX_ENV_RADIANCE).contains(c))
        {
            return Ok(EnvArg::Rgb(rgb));
        }
        return Err(format!(
            "radiance components must be in 0..={MAX_ENV_RADIANCE}, got '{text}'"
        ));
    }
    let path = std::path::PathBuf::from(t);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("exr" | "hdr" | "pfm")) {
        return Err(format!(
            "expected `none`, `R,G,B`, a grey value or an .exr/.hdr/.pfm map, got '{text}'"
        ));
    }
    render::files::regular_file_metadata(&path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => format!("environment map '{text}': no such file"),
        _ => format!("environment map '{text}': {e}"),
    })?;
    Ok(EnvArg::File(path))
}

/// Parses `--env-rotate` degrees: finite, -360..=360.
pub(crate) fn env_rotation(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && (-360.0..=360.0).contains(&v) => Ok(v),
        _ => Err(format!("expected degrees in -360..=360, got '{text}'")),
    }
}

/// Parses `--env-strength`: finite, 0..=1e6.
pub(crate) fn env_strength(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && (0.0..=MAX_ENV_RADIANCE).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected a multiplier in 0..={MAX_ENV_RADIANCE}, got '{text}'"
        )),
    }
}

/// Parses `--dr-variant`.
pub(crate) fn dr_variant(text: &str) -> Result<render::mlt::dr::DrVariant, String> {
    render::mlt::dr::DrVariant::ALL
        .iter()
        .find(|(name, _)| name.eq_ignore_ascii_case(text.trim()))
        .map(|&(_, v)| v)
        .ok_or_else(|| {
            let names: Vec<&str> = render::mlt::dr::DrVariant::ALL
                .iter()
                .map(|&(name, _)| name)
                .collect();
            format!("expected one of {}, got '{text}'", names.join(", "))
        })
}

/// Parses `--mala-preset`: `paper` (the paper's text), `paper-values` (its values with the
/// authors' code's semantics) or `code` (the authors' code).
pub(crate) fn mala_preset(text: &str) -> Result<render::mlt::mala::MalaParams, String> {
    use render::mlt::mala::MalaParams;
    match text.trim().to_ascii_lowercase().as_str() {
        "paper" => Ok(MalaParams::luan2020()),
        "paper-values" => Ok(MalaParams::luan2020_values()),
        "code" => Ok(MalaParams::luan2020_code()),
        _ => Err(format!(
            "expected paper, paper-values or code, got '{text}'"
        )),
    }
}

/// Parses `--lqmc-preset`: `paper` (Tessari et al. 2020, NEE paths splatted unexplored) or
/// `code` (the authors' code: NEE paths explored with `N = 7`).
pub(crate) fn lqmc_preset(text: &str) -> Result<render::methods::LqmcSettings, String> {
    use render::methods::LqmcSettings;
    match text.trim().to_ascii_lowercase().as_str() {
        "paper" => Ok(LqmcSettings::tessari2020()),
        "code" => Ok(LqmcSettings::tessari2020_code()),
        _ => Err(format!("expected paper or code, got '{text}'")),
    }
}

/// Parses `--large-step-mis`: `on` or `off`.
pub(crate) fn on_off(text: &str) -> Result<bool, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("expected on or off, got '{text}'")),
    }
}

/// `--roulette`: `off` or the first bounce where roulette may stop a subpath, 0..=1024.
pub(crate) fn roulette(text: &str) -> Result<render::bdpt::Roulette, String> {
    if text == "off" {
        return Ok(render::bdpt::Roulette { start: None });
    }
    match text.parse::<u32>() {
        Ok(n) if n <= 1024 => Ok(render::bdpt::Roulette { start: Some(n) }),
        _ => Err(format!(
            "expected `off` or a bounce count in 0..=1024, got `{text}`"
        )),
    }
}

/// `--chain-allocation`: `joint` or `per-depth`.
pub(crate) fn chain_allocation(
    text: &str,
) -> Result<mcmc_core::render_loop::ChainAllocation, String> {
    use mcmc_core::render_loop::ChainAllocation;
    match text.trim().to_ascii_lowercase().as_str() {
        "joint" => Ok(ChainAllocation::Joint),
        "per-depth" => Ok(ChainAllocation::PerTarget),
        _ => Err(format!("expected joint or per-depth, got '{text}'")),
    }
}

/// Parses `--mala-gradient`.
pub(crate) fn mala_gradient(text: &str) -> Result<render::mlt::mala::GradientMethod, String> {
    let t = text.trim().to_ascii_lowercase();
    render::mlt::mala::GradientMethod::ALL
        .iter()
        .find(|(name, _)| *name == t)
        .map(|(_, m)| *m)
        .ok_or_else(|| format!("expected dual, dual-constant-mis or fd, got '{text}'"))
}

/// `--mala-kernel`: true for `cheap-then-expensive`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct CheapThenExpensive(pub(crate) bool);

/// Parses `--mala-kernel`.
pub(crate) fn mala_kernel(text: &str) -> Result<CheapThenExpensive, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "mala" => Ok(CheapThenExpensive(false)),
        "cheap-then-expensive" => Ok(CheapThenExpensive(true)),
        _ => Err(format!(
            "expected mala or cheap-then-expensive, got '{text}'"
        )),
    }
}

/// Parses `--perturbation`.
pub(crate) fn perturbation(text: &str) -> Result<pathspace::PerturbationKind, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "lens" => Ok(pathspace::PerturbationKind::Lens),
        "multichain" | "multi-chain" => Ok(pathspace::PerturbationKind::MultiChain),
        _ => Err(format!("expected lens or multichain, got '{text}'")),
    }
}

/// Parses pathmlt's `--sigma`: `paper` (`lambda = 1`), `tuned` (0.02 rad) or radians in
/// `(0, pi]`.
pub(crate) fn pathmlt_sigma(text: &str) -> Result<f64, String> {
    use render::mlt::pathmlt::{PATHMLT_PAPER_SIGMA, PATHMLT_SIGMA};
    match text.trim().to_ascii_lowercase().as_str() {
        "paper" => Ok(PATHMLT_PAPER_SIGMA),
        "tuned" => Ok(PATHMLT_SIGMA),
        other => match other.parse::<f64>() {
            Ok(v) if v > 0.0 && v <= std::f64::consts::PI => Ok(v),
            _ => Err(format!(
                "expected paper, tuned or radians in (0, pi], got '{text}'"
            )),
        },
    }
}

/// Parses `--adapt`.
pub(crate) fn adapt(text: &str) -> Result<render::mlt::pathmlt::PathAdapt, String> {
    use render::mlt::pathmlt::PathAdapt;
    match text.trim().to_ascii_lowercase().as_str() {
        "fixed" => Ok(PathAdapt::Fixed),
        "global" => Ok(PathAdapt::Global),
        "grid" => Ok(PathAdapt::Grid),
        "quadtree" => Ok(PathAdapt::Quadtree),
        _ => Err(format!(
            "expected fixed, global, grid or quadtree, got '{text}'"
        )),
    }
}

/// Parses `--dr-on`.
pub(crate) fn dr_on(text: &str) -> Result<render::mlt::dr::DrBase, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "pssmlt" => Ok(render::mlt::dr::DrBase::Pssmlt),
        "pssmlt-pt" => Ok(render::mlt::dr::DrBase::PssmltPt),
        "mmlt" => Ok(render::mlt::dr::DrBase::Mmlt),
        _ => Err(format!("expected pssmlt, pssmlt-pt or mmlt, got '{text}'")),
    }
}

/// Parses `--raster-mutation`: `off`, `on` (probability [`pss::RASTER_DEFAULT_PROBABILITY`])
/// or the probability `P` in 0..=1 that a small step is a raster step.
pub(crate) fn raster_mutation(text: &str) -> Result<f64, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "off" => Ok(0.0),
        "on" => Ok(pss::RASTER_DEFAULT_PROBABILITY),
        t => match t.parse::<f64>() {
            Ok(p) if (0.0..=1.0).contains(&p) => Ok(p),
            _ => Err(format!(
                "expected `off`, `on` or a probability in 0..=1, got '{text}'"
            )),
        },
    }
}
