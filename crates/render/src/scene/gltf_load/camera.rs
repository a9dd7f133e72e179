//! The camera of a glTF node: the perspective projection, the node's world pose, and the
//! thin-lens and motion-blur parameters read from the node's extras.

use glam::{Mat4, Quat, Vec3};

use super::Loader;
use crate::error::RenderError;
use crate::scene::CameraSpec;

impl Loader<'_> {
    /// The camera of node `node_index` if it is perspective: its spec and aspect ratio.
    ///
    /// Nothing falls back silently: a world transform that cannot place a camera (a scale of
    /// 0, non-finite values) and invalid thin-lens or motion extras (non-numeric or
    /// non-finite values, a negative aperture radius, a focus distance <= 0, a shutter that
    /// closes before it opens, an end translation that is not 3 finite numbers) are errors
    /// naming the node and field; an incomplete set of extras (one of `aperture_radius` /
    /// `focus_distance`, or motion without all of `shutter_open`, `shutter_close` and
    /// `motion_end_translation`), a `yfov` outside (0, pi) and an `aspectRatio` outside
    /// [0.01, 100] are warnings saying what is used instead.
    pub(super) fn camera(
        &mut self,
        doc: &gltf::Document,
        raw: &gltf::json::Value,
        camera_index: usize,
        node_index: usize,
        world: Mat4,
    ) -> Result<Option<(CameraSpec, f32)>, RenderError> {
        let Some(json) = doc.as_json().cameras.get(camera_index) else {
            return Ok(None);
        };
        let Some(p) = json.perspective.as_ref() else {
            self.warn(format!(
                "cameras[{camera_index}] is not a perspective camera and is ignored"
            ));
            return Ok(None);
        };
        let yfov = if p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI {
            p.yfov
        } else {
            self.warn(format!(
                "cameras[{camera_index}].perspective.yfov {} (used by nodes[{node_index}]) is outside (0, pi); 0.8 is used",
                p.yfov
            ));
            0.8
        };
        let aspect = match p.aspect_ratio {
            Some(a) if !(a.is_finite() && (0.01..=100.0).contains(&a)) => {
                self.warn(format!(
                    "cameras[{camera_index}].perspective.aspectRatio {a} is outside [0.01, 100]; 1 is used"
                ));
                1.0
            }
            a => a.unwrap_or(1.0),
        };
        let mut spec = CameraSpec::from_matrix(world, yfov).ok_or_else(|| {
            self.err(format!(
                "nodes[{node_index}] (camera cameras[{camera_index}]): its world transform cannot place a camera (a scale of 0, non-finite values or a degenerate matrix)"
            ))
        })?;
        let extras = &raw["nodes"][node_index]["extras"];
        let field = |key: &str| format!("nodes[{node_index}].extras.{key}");
        // A present extras number as a finite f32 (absent or null: None).
        let file = self.file;
        let num = |key: &str| -> Result<Option<f32>, RenderError> {
            match &extras[key] {
                gltf::json::Value::Null => Ok(None),
                v => match v.as_f64().map(|x| x as f32) {
                    Some(x) if x.is_finite() => Ok(Some(x)),
                    _ => Err(RenderError::gltf(
                        file,
                        format!("{} = {v} is not a finite number", field(key)),
                    )),
                },
            }
        };
        match (num("aperture_radius")?, num("focus_distance")?) {
            (Some(radius), Some(focus)) => {
                if radius < 0.0 {
                    return Err(self.err(format!(
                        "{} = {radius} is negative (the lens radius in metres, >= 0)",
                        field("aperture_radius")
                    )));
                }
                if focus <= 0.0 {
                    return Err(self.err(format!(
                        "{} = {focus} must be > 0 (metres along the view direction)",
                        field("focus_distance")
                    )));
                }
                spec.thin_lens = Some((radius, focus));
            }
            (None, None) => {}
            (r, _) => {
                let (given, missing) = if r.is_some() {
                    ("aperture_radius", "focus_distance")
                } else {
                    ("focus_distance", "aperture_radius")
                };
                self.warn(format!(
                    "nodes[{node_index}].extras has {given} but no {missing}: the camera is a pinhole"
                ));
            }
        }
        let open = num("shutter_open")?;
        let close = num("shutter_close")?;
        let end = &extras["motion_end_translation"];
        let end = if end.is_null() {
            None
        } else {
            let t = end.as_array().filter(|a| a.len() == 3).map(|a| {
                a.iter()
                    .map(|v| v.as_f64().map(|x| x as f32).filter(|x| x.is_finite()))
                    .collect::<Option<Vec<f32>>>()
            });
            match t {
                Some(Some(t)) => Some(Vec3::new(t[0], t[1], t[2])),
                _ => {
                    return Err(self.err(format!(
                        "{} = {end} is not an array of 3 finite numbers",
                        field("motion_end_translation")
                    )))
                }
            }
        };
        match (open, close, end) {
            (None, None, None) => {}
            (Some(open), Some(close), Some(end)) => {
                if close < open {
                    return Err(self.err(format!(
                        "{} = {close} is before {} = {open}",
                        field("shutter_close"),
                        field("shutter_open")
                    )));
                }
                // The end pose: the node's rotation and scale with the end translation.
                let node = doc
                    .nodes()
                    .nth(node_index)
                    .ok_or_else(|| self.err(format!("nodes[{node_index}] does not exist")))?;
                let (_, r, s) = node.transform().decomposed();
                let local0 = Mat4::from_cols_array_2d(&node.transform().matrix());
                // Invertible: from_matrix accepted world = parent * local0.
                let parent = world * local0.inverse();
                let q = Quat::from_array(r);
                if !(q.is_finite() && q.length() > 1e-6) {
                    return Err(self.err(format!(
                        "nodes[{node_index}].rotation {r:?} is not a rotation quaternion: the motion end pose cannot be built"
                    )));
                }
                let local1 =
                    Mat4::from_scale_rotation_translation(Vec3::from(s), q.normalize(), end);
                let end_spec = CameraSpec::from_matrix(parent * local1, yfov).ok_or_else(|| {
                    self.err(format!(
                        "{}: the camera's end pose is degenerate (non-finite or singular transform)",
                        field("motion_end_translation")
                    ))
                })?;
                spec.motion = Some((end_spec.from, end_spec.to, open, close));
            }
            (o, c, e) => {
                let missing: Vec<&str> = [
                    ("shutter_open", o.is_none()),
                    ("shutter_close", c.is_none()),
                    ("motion_end_translation", e.is_none()),
                ]
                .iter()
                .filter(|m| m.1)
                .map(|m| m.0)
                .collect();
                self.warn(format!(
                    "nodes[{node_index}].extras: camera motion needs shutter_open, shutter_close and motion_end_translation; {} missing: the camera is static",
                    missing.join(", ")
                ));
            }
        }
        Ok(Some((spec, aspect)))
    }
}
