//! The camera description of a scene ([`CameraSpec`]): pose, field of view, thin lens and
//! motion, turned into a [`Camera`] once the image size is known.

use glam::{Mat4, Vec3, Vec3A};

use crate::camera::Camera;

/// Where a camera sits, before the image size is known: [`CameraSpec::build`] makes the
/// [`Camera`] for a resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    /// Eye point.
    pub from: Vec3A,
    /// Look-at point.
    pub to: Vec3A,
    /// Up vector.
    pub up: Vec3A,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
    /// Thin lens `(aperture_radius, focus_distance)`, or `None` for a pinhole.
    pub thin_lens: Option<(f32, f32)>,
    /// Linear motion `(end_from, end_to, shutter_open, shutter_close)`, if any.
    pub motion: Option<(Vec3A, Vec3A, f32, f32)>,
}

impl CameraSpec {
    /// A pinhole camera at `from` looking at `to`.
    #[must_use]
    pub fn look_at(from: Vec3A, to: Vec3A, up: Vec3A, vfov_deg: f32) -> Self {
        Self {
            from,
            to,
            up,
            vfov_deg,
            thin_lens: None,
            motion: None,
        }
    }

    /// A pinhole camera from a glTF camera node's world transform (looking down local `-z`,
    /// `+y` up) and vertical field of view in radians.
    ///
    /// `None` if the transform cannot place a camera: a singular or non-finite matrix (e.g. a
    /// node `scale` with a 0), a zero viewing direction or up vector, or an up vector parallel
    /// to the viewing direction. There is no fallback pose: the caller reports it.
    #[must_use]
    pub fn from_matrix(world_from_camera: Mat4, yfov_rad: f32) -> Option<Self> {
        let origin = Vec3A::from(world_from_camera.transform_point3(Vec3::ZERO));
        let forward = Vec3A::from(world_from_camera.transform_vector3(Vec3::NEG_Z));
        let up = Vec3A::from(world_from_camera.transform_vector3(Vec3::Y));
        let det = world_from_camera.determinant();
        if !(origin.is_finite() && det.is_finite() && det != 0.0) {
            return None;
        }
        let f = forward.try_normalize()?;
        let u = up.try_normalize()?;
        // A usable up vector is not (nearly) parallel to the viewing direction.
        if f.cross(u).length_squared() < 1e-12 {
            return None;
        }
        Some(Self::look_at(origin, origin + f, up, yfov_rad.to_degrees()))
    }

    /// A camera framing the box `(lo, hi)`: looking at its centre from the front (`+z`),
    /// raised by 25° and turned by 20° about `+y` so that flat models lying in any axis plane
    /// are not seen edge-on, from far enough that the bounding sphere fits a 45° vertical
    /// field of view.
    #[must_use]
    pub fn framing(lo: Vec3A, hi: Vec3A) -> Self {
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let vfov = 45.0f32;
        let dist = radius / (vfov.to_radians() * 0.5).sin() * 1.05;
        let (elevation, azimuth) = (25f32.to_radians(), 20f32.to_radians());
        let dir = Vec3A::new(
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
            elevation.cos() * azimuth.cos(),
        );
        Self::look_at(center + dir * dist, center, Vec3A::Y, vfov)
    }

    /// The camera for a `width x height` image.
    #[must_use]
    pub fn build(&self, width: u32, height: u32) -> Camera {
        let mut c = Camera::perspective(self.from, self.to, self.up, self.vfov_deg, width, height);
        if let Some((radius, focus)) = self.thin_lens {
            c = c.with_thin_lens(radius, focus);
        }
        if let Some((end_from, end_to, open, close)) = self.motion {
            c = c.with_motion(end_from, end_to, open, close);
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_sees_the_whole_box() {
        let spec = CameraSpec::framing(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        assert!(spec.from.z > 1.0);
        assert_eq!(spec.to, Vec3A::ZERO);
    }
}
