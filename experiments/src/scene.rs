//! A scene under test with its reference image: the bundled glTF scenes with their BDPT
//! references (`scenes/references/<name>.exr`), or any scene with a reference supplied.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use render::image::Image;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};
use render::Scene;

use crate::ExperimentError;

/// Where the bundled scenes live, relative to the repository root (run the examples from there).
pub const SCENES_DIR: &str = "scenes";

/// A scene, its reference at the render size, and where the reference came from.
#[derive(Clone, Debug)]
pub struct SceneCase {
    /// Name used in tables, progress lines and as the run directory's name.
    pub name: String,
    /// The scene, its camera set to the reference's resolution.
    pub scene: Scene,
    /// The reference image every render of the scene is compared with.
    pub reference: Image,
    /// Where the reference came from, for the run's parameters.
    pub reference_source: String,
}

impl SceneCase {
    /// `scene` with `reference` (whose size sets the camera's resolution).
    #[must_use]
    pub fn new(
        name: impl Into<String>,
        mut scene: Scene,
        reference: Image,
        reference_source: impl Into<String>,
    ) -> Self {
        scene.set_resolution(reference.width as u32, reference.height as u32);
        Self {
            name: name.into(),
            scene,
            reference,
            reference_source: reference_source.into(),
        }
    }

    /// The bundled scene `scenes/<name>.gltf` at `size x size` with its reference
    /// `scenes/references/<name>.exr` box-downsampled to that size
    /// ([`render::bundled::bundled`]).
    ///
    /// # Errors
    /// [`ExperimentError::Scene`] naming the file: the scene or its reference is missing or
    /// unreadable, or `size` does not divide the reference's resolution.
    pub fn bundled(name: &str, size: u32) -> Result<Self, ExperimentError> {
        let (scene, reference) =
            render::bundled::bundled(name, size).map_err(ExperimentError::Scene)?;
        let source = Path::new(SCENES_DIR)
            .join("references")
            .join(format!("{name}.exr"));
        Ok(Self::new(
            name,
            scene,
            reference,
            format!("{} box-downsampled", source.display()),
        ))
    }

    /// The built-in Cornell box (`Scene::cornell_box`) at `size x size`, named `cornell-box`,
    /// with a path-traced reference of `reference_spp` samples per pixel (seed 1, one thread).
    /// Meant for tests and documentation: unlike the bundled references it is not converged.
    ///
    /// # Errors
    /// [`ExperimentError::Render`] if the reference render fails (a size of 0, say).
    pub fn cornell_box(size: u32, reference_spp: u32) -> Result<Self, ExperimentError> {
        let scene = Scene::cornell_box(size, size);
        let settings = RenderSettings {
            method: IntegratorKind::Pt.settings(),
            width: size,
            height: size,
            budget: Budget::SamplesPerPixel(reference_spp),
            threads: 1,
            seed: 1,
            ..RenderSettings::default()
        };
        let name = "cornell-box";
        let reference = render(&scene, &settings, &NoProgress, &AtomicBool::new(false))
            .map_err(|source| ExperimentError::Render {
                scene: name.into(),
                method: "reference (pt)".into(),
                seed: 1,
                source,
            })?
            .image;
        Ok(Self::new(
            name,
            scene,
            reference,
            format!("path tracing, {reference_spp} spp"),
        ))
    }
}

/// The bundled scenes `names` at `size x size` ([`SceneCase::bundled`]), in order; a scene
/// that cannot be loaded is skipped with a message on stderr (what [`crate::Experiment`] does
/// with the plan's scenes). For an example that works on the scenes before the comparison
/// (a per-scene calibration, say) and then passes them to [`crate::Experiment::scenes`].
#[must_use]
pub fn load_bundled(names: &[String], size: u32) -> Vec<SceneCase> {
    names
        .iter()
        .filter_map(|name| match SceneCase::bundled(name, size) {
            Ok(case) => Some(case),
            Err(e) => {
                eprintln!("{e}; skipped");
                None
            }
        })
        .collect()
}

/// The names of the bundled scenes (`scenes/*.gltf`), sorted; empty when the directory is
/// missing (not run from the repository root).
#[must_use]
pub fn bundled_scene_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(SCENES_DIR)
        .map(|dir| {
            dir.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
                .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_box_case_is_sized_and_lit() {
        let case = SceneCase::cornell_box(8, 4).unwrap();
        assert_eq!((case.reference.width, case.reference.height), (8, 8));
        assert_eq!(
            (case.scene.camera().width(), case.scene.camera().height()),
            (8, 8)
        );
        assert!(case.reference.mean_luminance() > 0.0);
    }

    #[test]
    fn missing_bundled_scene_names_the_file() {
        let e = SceneCase::bundled("no-such-scene", 16).unwrap_err();
        assert!(e.to_string().contains("no-such-scene"), "{e}");
        assert!(load_bundled(&["no-such-scene".into()], 16).is_empty());
    }
}
