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
/// `--large-step`: `auto` or a probability in 0..=1.
pub(crate) fn large_step(text: &str) -> Result<render::mlt::LargeStepMode, String> {
    if text.eq_ignore_ascii_case("auto") {
        return Ok(render::mlt::LargeStepMode::Auto {
            initial: 0.5,
            estimation_steps: 1_000,
        });
    }
    match text.parse::<f64>() {
        Ok(p) if (0.0..=1.0).contains(&p) => Ok(render::mlt::LargeStepMode::Fixed(p)),
        _ => Err(format!(
            "expected `auto` or a probability in 0..=1, got '{text}'"
        )),
    }
}

/// `--small-step`: `kelemen` or `gaussian=SIGMA`.
pub(crate) fn small_step(text: &str) -> Result<pss::SmallMutation, String> {
    if text.eq_ignore_ascii_case("kelemen") {
        return pss::SmallMutation::kelemen(pss::KelemenParams::kelemen2002())
            .map_err(|e| e.to_string());
    }
    let sigma = text
        .strip_prefix("gaussian=")
        .and_then(|v| v.parse::<f64>().ok())
        .ok_or_else(|| format!("expected `kelemen` or `gaussian=SIGMA`, got '{text}'"))?;
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
}
