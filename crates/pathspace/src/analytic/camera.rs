//! A pinhole camera for the analytic scene.

use crate::error::PathspaceError;
use crate::vec3::Vec3;

/// A pinhole camera with a film plane at distance 1: raster `(u, v)` in `[0, 1)^2` maps to the
/// film point `f + r (2u - 1) w + up (1 - 2v) h` (`w`, `h` the half extents).
///
/// Its direction pdf for a uniform raster point is `1 / (A cos^3 θ)` with `A = 4 w h` the film
/// area and `θ` the angle to the view axis; the importance (times the lens cosine) equals it,
/// so that the raster measurement is the mean radiance over the raster (pbrt-v4's
/// `PerspectiveCamera::We`, with the film normalised to unit raster area).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    origin: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    half_width: f64,
    half_height: f64,
}

impl PinholeCamera {
    /// A camera at `origin` looking at `target`, with `up` hinting the vertical, a vertical
    /// field of view in degrees (in `(0, 179)`) and aspect ratio width / height.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for a bad field of view or aspect, or a degenerate
    /// view frame.
    pub fn look_at(
        origin: Vec3,
        target: Vec3,
        up: Vec3,
        vertical_fov_degrees: f64,
        aspect: f64,
    ) -> Result<Self, PathspaceError> {
        PathspaceError::check_range("vertical_fov_degrees", vertical_fov_degrees, 1e-3, 179.0)?;
        PathspaceError::check_range("aspect", aspect, 1e-3, 1e3)?;
        let degenerate = || PathspaceError::InvalidScene("degenerate camera frame".into());
        let forward = (target - origin).try_normalize().ok_or_else(degenerate)?;
        let right = forward.cross(up).try_normalize().ok_or_else(degenerate)?;
        let up = right.cross(forward);
        let half_height = (0.5 * vertical_fov_degrees.to_radians()).tan();
        Ok(Self {
            origin,
            forward,
            right,
            up,
            half_width: half_height * aspect,
            half_height,
        })
    }

    /// The pinhole.
    #[must_use]
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// The unit view axis.
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// Direction through raster point `raster`.
    #[must_use]
    pub fn direction(&self, raster: [f64; 2]) -> Vec3 {
        (self.forward
            + self.right * ((2.0 * raster[0] - 1.0) * self.half_width)
            + self.up * ((1.0 - 2.0 * raster[1]) * self.half_height))
            .normalize()
    }

    /// Raster point of a direction, if inside the image.
    #[must_use]
    pub fn raster(&self, dir: Vec3) -> Option<[f64; 2]> {
        let c = dir.dot(self.forward);
        if c <= 0.0 {
            return None;
        }
        let p = dir / c;
        let u = 0.5 * (p.dot(self.right) / self.half_width + 1.0);
        let v = 0.5 * (1.0 - p.dot(self.up) / self.half_height);
        ((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)).then_some([u, v])
    }

    /// `1 / (A cos^3 θ)` inside the image, else 0.
    #[must_use]
    pub fn direction_pdf(&self, dir: Vec3) -> f64 {
        if self.raster(dir).is_none() {
            return 0.0;
        }
        let c = dir.dot(self.forward);
        1.0 / (4.0 * self.half_width * self.half_height * c * c * c)
    }
}
