//! A per-scene calibration stored in a file with the inputs it was fitted on, so the many
//! processes of one sweep fit it once and a file fitted on other inputs is refitted.
//!
//! [`match_acceptance`] is deterministic (a sample budget, a fixed seed), so a stored fit is
//! exactly the fit a process would recompute; what makes a stored fit stale is a change of
//! its inputs: the scene (its geometry, materials and camera), the render size, the probe
//! settings, the reference method, the family of methods and the bisection. Those are
//! recorded per scene as text ([`CalibrationInputs`]) and compared in full, not by a hash.

use std::path::Path;

use render::methods::{MethodSettings, RenderSettings};
use serde::{Deserialize, Serialize};

use crate::calibrate::{match_acceptance, Bisection, Calibrated, Calibrations};
use crate::scene::SceneCase;
use crate::sweep::{read_bounded, write_atomic, Num};
use crate::ExperimentError;

/// The format tag of a calibration file.
pub const CALIBRATION_FORMAT: &str = "chainlight-calibration/1";

/// What one scene's fit depends on, as text: equal inputs give the identical fit.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CalibrationInputs {
    /// The scene's name.
    pub scene: String,
    /// A 64-bit FNV-1a digest of the scene's full `Debug` text (geometry, materials, camera),
    /// in hex.
    pub scene_digest: String,
    /// The render size, `WIDTHxHEIGHT`.
    pub size: String,
    /// The probe settings (budget, seed, threads, depth) with the method left out.
    pub probe: String,
    /// The reference method whose acceptance is matched.
    pub reference: String,
    /// The family at the bisection's two ends (the parameter's place in the settings).
    pub family: String,
    /// The bisection.
    pub bisection: String,
}

impl CalibrationInputs {
    /// The inputs of `case`'s fit by [`match_acceptance`] with the same arguments.
    #[must_use]
    pub fn new(
        case: &SceneCase,
        probe: &RenderSettings,
        reference: &MethodSettings,
        family: &dyn Fn(f64) -> MethodSettings,
        bisection: Bisection,
    ) -> Self {
        let probe = RenderSettings {
            method: MethodSettings::default(),
            ..probe.clone()
        };
        Self {
            scene: case.name.clone(),
            scene_digest: format!("{:016x}", debug_digest(&case.scene)),
            size: format!("{}x{}", case.reference.width, case.reference.height),
            probe: format!("{probe:?}"),
            reference: format!("{reference:?}"),
            family: format!("{:?} .. {:?}", family(bisection.lo), family(bisection.hi)),
            bisection: format!("{bisection:?}"),
        }
    }
}

/// One stored fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Entry {
    inputs: CalibrationInputs,
    value: Num,
    achieved: Num,
    target: Num,
    measurements: u32,
}

impl Entry {
    fn fit(&self) -> Calibrated {
        Calibrated {
            value: self.value.0,
            achieved: self.achieved.0,
            target: self.target.0,
            measurements: self.measurements,
        }
    }
}

/// The file: its format tag and the fits, one per scene.
#[derive(Debug, Default, Serialize, Deserialize)]
struct CalibrationFile {
    format: String,
    fits: Vec<Entry>,
}

/// How [`match_acceptance_cached`] came by each scene's fit.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CacheUse {
    /// Scenes whose stored fit had the same inputs and was reused.
    pub reused: Vec<String>,
    /// Scenes fitted now (no stored fit, or one on other inputs) and stored.
    pub fitted: Vec<String>,
}

/// [`match_acceptance`] with its fits stored in `path` (JSON): a scene whose stored fit has
/// the same [`CalibrationInputs`] reuses it (bit-identical to a refit, the fit being
/// deterministic); any other scene is fitted and stored, replacing a stale entry. A missing
/// file counts as empty; a file of another format is an error (not overwritten).
///
/// # Errors
/// [`ExperimentError::Format`] for an unreadable or foreign file, [`ExperimentError::Io`]
/// when it cannot be written, and the errors of [`match_acceptance`].
pub fn match_acceptance_cached(
    path: &Path,
    cases: &[SceneCase],
    probe: &RenderSettings,
    reference: MethodSettings,
    family: impl Fn(f64) -> MethodSettings,
    bisection: Bisection,
) -> Result<(Calibrations, CacheUse), ExperimentError> {
    let mut file = read_file(path)?;
    let mut fits = Vec::with_capacity(cases.len());
    let mut used = CacheUse::default();
    for case in cases {
        let inputs = CalibrationInputs::new(case, probe, &reference, &family, bisection);
        if let Some(entry) = file.fits.iter().find(|e| e.inputs == inputs) {
            fits.push((case.name.clone(), entry.fit()));
            used.reused.push(case.name.clone());
            continue;
        }
        let found = match_acceptance(
            std::slice::from_ref(case),
            probe,
            reference,
            &family,
            bisection,
        )?;
        let (name, fit) = found.0.into_iter().next().expect("one scene, one fit");
        file.fits.retain(|e| e.inputs.scene != name);
        file.fits.push(Entry {
            inputs,
            value: Num(fit.value),
            achieved: Num(fit.achieved),
            target: Num(fit.target),
            measurements: fit.measurements,
        });
        let json = serde_json::to_string_pretty(&file).expect("a calibration serialises");
        write_atomic(path, json.as_bytes())?;
        used.fitted.push(name.clone());
        fits.push((name, fit));
    }
    Ok((Calibrations(fits), used))
}

/// The stored fits of `path`; empty when it does not exist.
fn read_file(path: &Path) -> Result<CalibrationFile, ExperimentError> {
    if !path.exists() {
        return Ok(CalibrationFile {
            format: CALIBRATION_FORMAT.to_owned(),
            fits: Vec::new(),
        });
    }
    let file: CalibrationFile = serde_json::from_str(&read_bounded(path)?)
        .map_err(|e| ExperimentError::format(path, format!("not a calibration file: {e}")))?;
    if file.format != CALIBRATION_FORMAT {
        return Err(ExperimentError::format(
            path,
            format!("format {:?}, expected {CALIBRATION_FORMAT:?}", file.format),
        ));
    }
    Ok(file)
}

/// The 64-bit FNV-1a digest of `value`'s `Debug` text, streamed (no text is built).
fn debug_digest(value: &impl std::fmt::Debug) -> u64 {
    struct Fnv(u64);
    impl std::fmt::Write for Fnv {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            for b in s.bytes() {
                self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
            }
            Ok(())
        }
    }
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    std::fmt::write(&mut h, format_args!("{value:?}")).expect("Debug into a digest");
    h.0
}

#[cfg(test)]
mod tests {
    use render::session::Budget;

    use super::*;

    fn probe() -> RenderSettings {
        RenderSettings {
            budget: Budget::SamplesPerPixel(2),
            threads: 1,
            seed: 7,
            ..RenderSettings::default()
        }
    }

    fn pss(sigma: f64) -> MethodSettings {
        crate::calibrate::small_pssmlt(sigma, 8, 500)
    }

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "chainlight-calibration-{}-{name}",
            std::process::id()
        ));
        std::fs::remove_dir_all(&dir).ok();
        dir.join("calibration.json")
    }

    #[test]
    fn a_stored_fit_equals_a_refit_and_other_inputs_are_refitted() {
        let case = SceneCase::cornell_box(8, 2).unwrap();
        let cases = [case.clone()];
        let bisect = Bisection::log(1e-4, 0.5, 4);
        let path = temp("reuse");
        let fresh = match_acceptance(&cases, &probe(), pss(0.0), pss, bisect).unwrap();
        let (first, used) =
            match_acceptance_cached(&path, &cases, &probe(), pss(0.0), pss, bisect).unwrap();
        assert_eq!(used.fitted, ["cornell-box"]);
        let (second, used) =
            match_acceptance_cached(&path, &cases, &probe(), pss(0.0), pss, bisect).unwrap();
        assert_eq!(used.reused, ["cornell-box"]);
        for fits in [&first, &second] {
            let (a, b) = (&fits.0[0].1, &fresh.0[0].1);
            assert_eq!(a.value.to_bits(), b.value.to_bits());
            assert_eq!(a.achieved.to_bits(), b.achieved.to_bits());
            assert_eq!(
                (a.target.to_bits(), a.measurements),
                (b.target.to_bits(), 4)
            );
        }
        // Negative control: other inputs (the probe's seed, the bisection, the scene) are not
        // served the stored fit.
        let other_seed = RenderSettings { seed: 8, ..probe() };
        let (_, used) =
            match_acceptance_cached(&path, &cases, &other_seed, pss(0.0), pss, bisect).unwrap();
        assert_eq!(used.fitted, ["cornell-box"], "a stale file was reused");
        let (_, used) = match_acceptance_cached(
            &path,
            &cases,
            &other_seed,
            pss(0.0),
            pss,
            Bisection::log(1e-4, 0.5, 3),
        )
        .unwrap();
        assert_eq!(used.fitted, ["cornell-box"], "a stale file was reused");
        let mut moved = case;
        moved.scene.set_resolution(8, 9);
        let inputs = |c: &SceneCase| CalibrationInputs::new(c, &probe(), &pss(0.0), &pss, bisect);
        assert_ne!(inputs(&moved), inputs(&cases[0]));
        std::fs::remove_dir_all(path.parent().unwrap()).ok();
    }

    #[test]
    fn a_foreign_file_is_an_error_naming_it() {
        let path = temp("foreign");
        write_atomic(&path, br#"{"format": "something-else/1", "fits": []}"#).unwrap();
        let cases = [SceneCase::cornell_box(4, 1).unwrap()];
        let bisect = Bisection::log(1e-4, 0.5, 1);
        let e = match_acceptance_cached(&path, &cases, &probe(), pss(0.0), pss, bisect)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("calibration.json") && e.contains("something-else"),
            "{e}"
        );
        write_atomic(&path, b"not json").unwrap();
        let e = match_acceptance_cached(&path, &cases, &probe(), pss(0.0), pss, bisect)
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a calibration file"), "{e}");
        std::fs::remove_dir_all(path.parent().unwrap()).ok();
    }
}
