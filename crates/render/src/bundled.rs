//! The bundled scenes with their BDPT references, as the paper examples load them.

use std::path::Path;

use crate::image::Image;
use crate::scene::Scene;

/// Loads the glTF scene at `scene_path` and the reference `<references>/<stem>.exr` next to the
/// bundled scenes (`scenes/references/`, relative to the working directory: run the examples
/// from the repository root), box-downsampled to `size x size`.
///
/// # Errors
/// A message naming the file: the reference is missing or unreadable, `size` does not divide
/// its resolution, or the scene does not load.
pub fn scene_and_reference(scene_path: &Path, size: u32) -> Result<(Scene, Image), String> {
    let name = scene_path
        .file_stem()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned();
    let reference_path = Path::new("scenes/references").join(format!("{name}.exr"));
    let reference = crate::image_io::read_exr(&reference_path)
        .map_err(|e| format!("{name}: cannot read the reference {}: {e}", reference_path.display()))?
        .box_downsample(size as usize, size as usize)
        .ok_or_else(|| {
            format!(
                "{name}: the reference {} cannot be box-downsampled to {size}x{size} (the size must divide its resolution)",
                reference_path.display()
            )
        })?;
    let scene = Scene::load(scene_path).map_err(|e| format!("{name}: {e}"))?;
    Ok((scene, reference))
}

/// [`scene_and_reference`] for the bundled scene `scenes/<name>.gltf`.
///
/// # Errors
/// As [`scene_and_reference`].
pub fn bundled(name: &str, size: u32) -> Result<(Scene, Image), String> {
    scene_and_reference(&Path::new("scenes").join(format!("{name}.gltf")), size)
}
