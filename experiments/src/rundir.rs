//! A scene's run directory, `<out>/<scene>/`: the reference, every method's image per seed,
//! `run.json` (the [`RunManifest`] `chainlight report` reads) and `report.html`.
//!
//! Layout (paths in `run.json` are relative to the directory):
//!
//! | file | content |
//! |---|---|
//! | `reference.exr`, `reference.png` | the reference at the render size |
//! | `<slug>_seed<seed>.exr` | every method's final image of every seed |
//! | `<slug>.exr`, `<slug>.png` | the first seed's image, for a quick look |
//! | `<slug>_<name>_seed<seed>.exr`, `<slug>_<name>.exr`/`.png` | extra images of a run ([`crate::Experiment::extra_image`], e.g. `stage2`), not listed in `run.json` |
//! | `run.json`, `report.html` | the manifest and the self-contained report |
//! | `runs/seed<seed>.json` | a job-list run's record of every method on this scene with that seed, read by `--collect` ([`crate::JobMode`]) |

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use render::image::Image;
use render::image_io;

use crate::method::Method;
use crate::record::{Measure, RunRecord};
use crate::report::{write_report, ConvergenceSeries, MethodRun, RunManifest, SeedImage};
use crate::table::median;
use crate::ExperimentError;

/// The run directory of one scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunDirectory {
    dir: PathBuf,
}

impl RunDirectory {
    /// Creates `dir` (and its parents) if needed.
    ///
    /// # Errors
    /// [`ExperimentError::Io`] if the directory cannot be created.
    pub fn create(dir: impl Into<PathBuf>) -> Result<Self, ExperimentError> {
        let dir = dir.into();
        std::fs::create_dir_all(&dir).map_err(ExperimentError::io(&dir))?;
        Ok(Self { dir })
    }

    /// The directory.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Writes `reference.exr` and `reference.png`; returns the EXR's path relative to the
    /// directory.
    ///
    /// # Errors
    /// [`ExperimentError::Image`] if a file cannot be written.
    pub fn write_reference(&self, reference: &Image) -> Result<PathBuf, ExperimentError> {
        image_io::write_exr(self.dir.join("reference.exr"), reference)?;
        image_io::write_png(self.dir.join("reference.png"), reference, 0.0)?;
        Ok("reference.exr".into())
    }

    /// Writes `<slug>_seed<seed>.exr` (and, for the first seed, `<slug>.exr` and `<slug>.png`);
    /// returns the seed image's path relative to the directory.
    ///
    /// # Errors
    /// [`ExperimentError::Image`] if a file cannot be written.
    pub fn write_seed_image(
        &self,
        slug: &str,
        seed: u64,
        image: &Image,
        first_seed: bool,
    ) -> Result<PathBuf, ExperimentError> {
        let file = PathBuf::from(format!("{slug}_seed{seed}.exr"));
        image_io::write_exr(self.dir.join(&file), image)?;
        if first_seed {
            image_io::write_exr(self.dir.join(format!("{slug}.exr")), image)?;
            image_io::write_png(self.dir.join(format!("{slug}.png")), image, 0.0)?;
        }
        Ok(file)
    }

    /// Saves `run.json` and, with `report`, writes `report.html`; returns the report's path.
    ///
    /// # Errors
    /// [`ExperimentError::Report`] if the manifest or the report cannot be written.
    pub fn save(
        &self,
        manifest: &RunManifest,
        report: bool,
    ) -> Result<Option<PathBuf>, ExperimentError> {
        manifest.save(&self.dir)?;
        if !report {
            return Ok(None);
        }
        Ok(Some(write_report(
            manifest,
            &self.dir,
            self.dir.join("report.html"),
        )?))
    }
}

/// The manifest of one scene's runs: `methods` in order, each with its images and convergence
/// samples over seeds from `records` (other scenes' records are ignored), its own parameters
/// and the medians of its statistics over seeds.
#[must_use]
pub fn scene_manifest(
    title: String,
    commit: String,
    parameters: BTreeMap<String, String>,
    scene: &str,
    methods: &[Method],
    records: &[RunRecord],
) -> RunManifest {
    let methods = methods
        .iter()
        .map(|m| {
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.scene == scene && r.method == m.name())
                .collect();
            let mut parameters: BTreeMap<String, String> = m.parameters().iter().cloned().collect();
            for measure in [Measure::SamplesPerSecond, Measure::Acceptance, Measure::B] {
                let value = median(&runs.iter().map(|r| measure.of(r)).collect::<Vec<_>>());
                if !value.is_nan() {
                    parameters.insert(
                        format!("{} (median over seeds)", measure.label()),
                        measure.format(value),
                    );
                }
            }
            MethodRun {
                name: m.name().to_owned(),
                parameters,
                images: runs
                    .iter()
                    .map(|r| SeedImage {
                        seed: r.seed,
                        path: r.image.clone(),
                    })
                    .collect(),
                convergence: runs
                    .iter()
                    .map(|r| ConvergenceSeries {
                        seed: r.seed,
                        points: r.convergence.clone(),
                    })
                    .collect(),
            }
        })
        .filter(|m| !m.images.is_empty())
        .collect();
    RunManifest {
        title,
        commit,
        parameters,
        reference: "reference.exr".into(),
        methods,
    }
}

#[cfg(test)]
mod tests {
    use render::metrics::Metrics;
    use render::session::RenderSettings;

    use super::*;
    use crate::report::ConvergencePoint;
    use crate::stats::RunStats;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir()
            .join(format!("experiments-rundir-{}", std::process::id()))
            .join(name);
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn gradient(w: usize, h: usize, gain: f32) -> Image {
        let mut img = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let v = gain * (0.1 + (x + y) as f32 / (w + h) as f32);
                img.set(x, y, [v, 0.5 * v, 0.25 + v]);
            }
        }
        img
    }

    #[test]
    fn written_run_directory_round_trips_and_reports() {
        let dir = RunDirectory::create(scratch("round-trip")).unwrap();
        let reference = gradient(12, 8, 1.0);
        dir.write_reference(&reference).unwrap();
        let methods = [
            Method::new("A", RenderSettings::default()).with_parameter("k", 1),
            Method::new("B b", RenderSettings::default()),
        ];
        let mut records = Vec::new();
        for (m, gain) in methods.iter().zip([1.05f32, 1.3]) {
            for seed in [3u64, 4] {
                let image = gradient(12, 8, gain + seed as f32 * 0.01);
                let path = dir
                    .write_seed_image(m.slug(), seed, &image, seed == 3)
                    .unwrap();
                let metrics = render::metrics::compare(&image, &reference).unwrap();
                records.push(RunRecord {
                    scene: "s".into(),
                    method: m.name().into(),
                    seed,
                    seconds: 0.5,
                    samples: 1000,
                    metrics,
                    stats: RunStats {
                        acceptance: Some(0.25),
                        ..RunStats::default()
                    },
                    load: None,
                    image: path,
                    convergence: vec![ConvergencePoint {
                        time_s: 0.5,
                        relmse: metrics.relmse,
                    }],
                });
            }
        }
        // A record of another scene does not leak into this one.
        records.push(RunRecord {
            scene: "other".into(),
            metrics: Metrics {
                mse: 0.0,
                rmse: 0.0,
                relmse: 0.0,
                rrmse: 0.0,
                mad: 0.0,
            },
            ..records[0].clone()
        });
        let params = [("size".to_string(), "12x8".to_string())].into();
        let m = scene_manifest("t: s".into(), "abc".into(), params, "s", &methods, &records);
        assert_eq!(m.methods.len(), 2);
        assert_eq!(m.methods[1].images[0].path, PathBuf::from("B_b_seed3.exr"));
        assert_eq!(m.methods[0].parameters["k"], "1");
        assert_eq!(
            m.methods[0].parameters["acceptance (median over seeds)"],
            "0.250"
        );
        let html = dir.save(&m, true).unwrap().unwrap();
        assert_eq!(RunManifest::load(dir.path()).unwrap(), m);
        let page = std::fs::read_to_string(html).unwrap();
        assert!(page.contains("B b") && page.contains("12x8"));
        for file in ["reference.png", "A.exr", "A.png", "B_b_seed4.exr"] {
            assert!(dir.path().join(file).is_file(), "{file}");
        }
        assert!(!dir.path().join("A_seed4.png").exists());
    }
}
