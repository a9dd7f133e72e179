//! Rays and the perspective camera (pinhole or thin lens, optional linear motion blur), with the
//! importance function `We` and its sampling for light tracing and BDPT.
//!
//! # Conventions
//!
//! * **Raster space**: continuous pixel coordinates, `(0, 0)` is the top-left corner of the
//!   image, `x` right, `y` down; pixel `(i, j)` covers `[i, i+1) x [j, j+1)`. The image spans
//!   `[0, width) x [0, height)`.
//! * **Camera space**: `x` right, `y` up, `z` forward (the viewing direction). The film
//!   (image plane) is the rectangle at `z = 1` of half-size `(tan(vfov/2) * aspect,
//!   tan(vfov/2))` with `aspect = width / height`; its area is `A` ([`Camera::film_area`]).
//! * **Lens**: a disk of radius `r` ([`Camera::lens_radius`]) at the camera origin, normal to
//!   the viewing direction; `r = 0` is a pinhole. Rays through the lens point `p_lens` towards
//!   the focus point on the plane `z = focus_distance` (pbrt-v3 `PerspectiveCamera`).
//! * **Importance normalisation** (pbrt-v3 `PerspectiveCamera::We`, PBR 3rd ed. §16.1.1): for a
//!   ray leaving the lens at angle `theta` to the viewing direction,
//!   `We = 1 / (A * lens_area * cos^4 theta)` when it lands on the film, else 0, with
//!   `lens_area = pi r^2` (1 for a pinhole). Then `∫_lens ∫_dirs We cos theta dω dA = 1`: the
//!   measurement with `We` is the *average radiance over the whole film*. The measurement of
//!   pixel `j` uses `W_j = (width * height) * [ray lands in pixel j] * We`, which is the average
//!   radiance over pixel `j` (a box filter). Hence:
//!   - a **camera (path) tracer** samples `p_raster` uniformly in the pixel, calls
//!     [`Camera::generate_ray`] and averages the radiance (the ratio `We cos / pdf` is 1);
//!   - a **light tracer / BDPT `t = 1`** strategy that connects a vertex to the lens with
//!     [`Camera::sample_wi`] splats `importance * f * L * G-terms / pdf` at `p_raster`, and the
//!     film must scale the accumulated splats by `width * height / N`, where `N` is the total
//!     number of light paths traced for the whole image (pbrt-v3 divides splats by samples per
//!     pixel, which is the same thing when `N = spp * width * height`).
//! * **Time**: with a shutter interval `[open, close]`, `u_time ∈ [0,1)` maps linearly to
//!   `time = open + u_time (close - open)`; with motion ([`Camera::with_motion`]) the eye point
//!   and look-at target move linearly from the start pose to the end pose over the interval.

use crate::frame::Frame;
use crate::warp::sample_concentric_disk;
use glam::{Mat4, Vec2, Vec3A};
use std::f32::consts::PI;

/// A ray `origin + t dir` at a time inside the shutter interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin (world space).
    pub origin: Vec3A,
    /// Direction (world space); unit length for rays made by [`Camera`].
    pub dir: Vec3A,
    /// Time inside the shutter interval (0 for a static camera).
    pub time: f32,
}

impl Ray {
    /// A ray from its parts.
    #[must_use]
    #[inline]
    pub fn new(origin: Vec3A, dir: Vec3A, time: f32) -> Self {
        Self { origin, dir, time }
    }

    /// The point `origin + t dir`.
    #[must_use]
    #[inline]
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + t * self.dir
    }
}

/// Result of [`Camera::sample_wi`]: a lens point connected to a reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraWiSample {
    /// Unit direction from the reference point towards `p_lens`.
    pub wi: Vec3A,
    /// Density of having chosen `p_lens`, in solid angle at the reference point
    /// (`dist^2 / (|cos theta_lens| lens_area)`; pbrt-v3 `Sample_Wi`).
    pub pdf: f32,
    /// The sampled point on the lens (world space; the camera origin for a pinhole).
    pub p_lens: Vec3A,
    /// Raster position the reference point is seen at.
    pub p_raster: Vec2,
    /// Importance `We` of the ray from `p_lens` towards the reference point.
    pub importance: f32,
}

/// An orthonormal camera pose: the eye point and the camera axes in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// Eye point (lens centre).
    pub origin: Vec3A,
    /// Camera `+x` (image right) in world space.
    pub right: Vec3A,
    /// Camera `+y` (image up) in world space.
    pub up: Vec3A,
    /// Camera `+z` (viewing direction) in world space.
    pub forward: Vec3A,
}

impl CameraPose {
    /// A pose at `from` looking at `to` with `up` as the approximate up vector. Degenerate input
    /// (`to == from`, `up` parallel to the view direction, non-finite values) falls back to
    /// looking down `-z` and/or an arbitrary perpendicular up vector instead of failing.
    #[must_use]
    pub fn look_at(from: Vec3A, to: Vec3A, up: Vec3A) -> Self {
        let origin = if from.is_finite() { from } else { Vec3A::ZERO };
        let forward = (to - origin)
            .try_normalize()
            .filter(|f| f.is_finite())
            .unwrap_or(-Vec3A::Z);
        let right = match forward.cross(up).try_normalize() {
            Some(r) if r.is_finite() => r,
            _ => Frame::from_normal(forward).s,
        };
        let up = right.cross(forward);
        Self {
            origin,
            right,
            up,
            forward,
        }
    }

    /// Camera-space direction `v` (x right, y up, z forward) to world space.
    #[must_use]
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.right * v.x + self.up * v.y + self.forward * v.z
    }

    /// World-space direction `v` to camera space.
    #[must_use]
    #[inline]
    pub fn to_camera(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }
}

/// Everything that defines a [`Camera`] (see [`Camera::params`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CameraParams {
    /// Start pose `(from, to, up)`.
    pub(crate) start: (Vec3A, Vec3A, Vec3A),
    /// End pose `(from, to)` (the up vector is shared).
    pub(crate) end: (Vec3A, Vec3A),
    /// True if the poses differ.
    pub(crate) moving: bool,
    /// The start pose's frame.
    pub(crate) pose: CameraPose,
    /// Shutter interval.
    pub(crate) shutter: (f32, f32),
    /// Image size in pixels.
    pub(crate) size: (u32, u32),
    /// Film half-size at `z = 1`.
    pub(crate) half: (f32, f32),
    /// Lens radius (0: pinhole).
    pub(crate) lens_radius: f32,
    /// Focus distance.
    pub(crate) focus_distance: f32,
}

/// A look-at triple, interpolated for camera motion.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LookAt {
    from: Vec3A,
    to: Vec3A,
    up: Vec3A,
}

/// A perspective camera: pinhole or thin lens, vertical field of view, look-at pose, optional
/// shutter interval with linear motion between two poses. See the module docs for the raster,
/// camera-space and importance conventions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    start: LookAt,
    end: LookAt,
    moving: bool,
    pose: CameraPose,
    shutter_open: f32,
    shutter_close: f32,
    width: u32,
    height: u32,
    half_width: f32,
    half_height: f32,
    lens_radius: f32,
    focus_distance: f32,
}

impl Camera {
    /// A pinhole camera at `from` looking at `to`, with vertical field of view `vfov_deg`
    /// degrees (clamped to `[1e-3, 179]`; non-finite -> 45) and an image of `width x height`
    /// pixels (each at least 1). Degenerate poses are repaired by [`CameraPose::look_at`].
    #[must_use]
    pub fn perspective(
        from: Vec3A,
        to: Vec3A,
        up: Vec3A,
        vfov_deg: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let vfov_deg = if vfov_deg.is_finite() {
            vfov_deg.clamp(1e-3, 179.0)
        } else {
            45.0
        };
        let (width, height) = (width.max(1), height.max(1));
        let half_height = (0.5 * vfov_deg.to_radians()).tan();
        let half_width = half_height * width as f32 / height as f32;
        let start = LookAt { from, to, up };
        Self {
            start,
            end: start,
            moving: false,
            pose: CameraPose::look_at(from, to, up),
            shutter_open: 0.0,
            shutter_close: 0.0,
            width,
            height,
            half_width,
            half_height,
            lens_radius: 0.0,
            focus_distance: 1.0,
        }
    }

    /// A pinhole camera from a glTF camera node: `world_from_camera` is the node's world
    /// transform (the camera looks down its local `-z` with `+y` up; scale is ignored) and
    /// `yfov_rad` the vertical field of view in radians. The aspect ratio comes from the image
    /// size (glTF's `aspectRatio` is only a hint). A non-invertible or non-finite matrix gives
    /// a camera at the origin looking down `-z`.
    #[must_use]
    pub fn from_matrix(world_from_camera: Mat4, yfov_rad: f32, width: u32, height: u32) -> Self {
        let origin = Vec3A::from(world_from_camera.transform_point3(glam::Vec3::ZERO));
        let forward = Vec3A::from(world_from_camera.transform_vector3(glam::Vec3::NEG_Z));
        let up = Vec3A::from(world_from_camera.transform_vector3(glam::Vec3::Y));
        let valid = origin.is_finite() && forward.is_finite() && up.is_finite();
        let (from, to, up) = match (valid, forward.try_normalize()) {
            (true, Some(f)) => (origin, origin + f, up),
            _ => (Vec3A::ZERO, -Vec3A::Z, Vec3A::Y),
        };
        Self::perspective(from, to, up, yfov_rad.to_degrees(), width, height)
    }

    /// Turns the camera into a thin lens of radius `aperture_radius` focused on the plane at
    /// `focus_distance` along the viewing direction. A radius `<= 0` (or non-finite) keeps the
    /// pinhole; a non-positive focus distance is replaced by 1.
    #[must_use]
    pub fn with_thin_lens(mut self, aperture_radius: f32, focus_distance: f32) -> Self {
        self.lens_radius = if aperture_radius.is_finite() {
            aperture_radius.max(0.0)
        } else {
            0.0
        };
        self.focus_distance = if focus_distance.is_finite() && focus_distance > 0.0 {
            focus_distance
        } else {
            1.0
        };
        self
    }

    /// Adds linear camera motion: the eye moves from the start pose's `from` to `end_from` and
    /// the target from its `to` to `end_to` while the shutter is open, `[shutter_open,
    /// shutter_close]` (swapped if reversed). The up vector is shared. Non-finite input leaves
    /// the camera static.
    #[must_use]
    pub fn with_motion(
        mut self,
        end_from: Vec3A,
        end_to: Vec3A,
        shutter_open: f32,
        shutter_close: f32,
    ) -> Self {
        if !(end_from.is_finite()
            && end_to.is_finite()
            && shutter_open.is_finite()
            && shutter_close.is_finite())
        {
            return self;
        }
        self.end = LookAt {
            from: end_from,
            to: end_to,
            up: self.start.up,
        };
        self.shutter_open = shutter_open.min(shutter_close);
        self.shutter_close = shutter_open.max(shutter_close);
        self.moving = self.end != self.start;
        self
    }

    /// Sets the shutter interval without motion (the time still varies per ray, for moving
    /// scene content). Reversed bounds are swapped; non-finite bounds are ignored.
    #[must_use]
    pub fn with_shutter(mut self, open: f32, close: f32) -> Self {
        if open.is_finite() && close.is_finite() {
            self.shutter_open = open.min(close);
            self.shutter_close = open.max(close);
        }
        self
    }

    /// The camera's parameters, for code that restates its maths over another scalar type
    /// (the differentiable path evaluator, [`crate::bdpt::diff`]).
    #[must_use]
    pub(crate) fn params(&self) -> CameraParams {
        CameraParams {
            start: (self.start.from, self.start.to, self.start.up),
            end: (self.end.from, self.end.to),
            moving: self.moving,
            pose: self.pose,
            shutter: (self.shutter_open, self.shutter_close),
            size: (self.width, self.height),
            half: (self.half_width, self.half_height),
            lens_radius: self.lens_radius,
            focus_distance: self.focus_distance,
        }
    }

    /// Image width in pixels.
    #[must_use]
    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    #[must_use]
    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Area `A` of the film rectangle at distance 1 (see the module docs).
    #[must_use]
    #[inline]
    pub fn film_area(&self) -> f32 {
        4.0 * self.half_width * self.half_height
    }

    /// Lens radius (0 for a pinhole).
    #[must_use]
    #[inline]
    pub fn lens_radius(&self) -> f32 {
        self.lens_radius
    }

    /// Distance of the plane in focus (1 for a pinhole, where it is irrelevant).
    #[must_use]
    #[inline]
    pub fn focus_distance(&self) -> f32 {
        self.focus_distance
    }

    /// Lens area `pi r^2`, or 1 for a pinhole (pbrt-v3's convention for the position pdf).
    #[must_use]
    #[inline]
    pub fn lens_area(&self) -> f32 {
        if self.lens_radius > 0.0 {
            PI * self.lens_radius * self.lens_radius
        } else {
            1.0
        }
    }

    /// True if the pose changes during the shutter interval (the time of a ray matters).
    #[must_use]
    #[inline]
    pub fn is_moving(&self) -> bool {
        self.moving && self.shutter_close > self.shutter_open
    }

    /// The shutter interval `(open, close)`.
    #[must_use]
    #[inline]
    pub fn shutter(&self) -> (f32, f32) {
        (self.shutter_open, self.shutter_close)
    }

    /// The time `open + u_time (close - open)` for a uniform `u_time`.
    #[must_use]
    #[inline]
    pub fn sample_time(&self, u_time: f32) -> f32 {
        self.shutter_open + u_time * (self.shutter_close - self.shutter_open)
    }

    /// The camera pose at `time` (clamped to the shutter interval).
    #[must_use]
    pub fn pose_at(&self, time: f32) -> CameraPose {
        if !self.moving {
            return self.pose;
        }
        let span = self.shutter_close - self.shutter_open;
        let s = if span > 0.0 {
            ((time - self.shutter_open) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        if s == 0.0 {
            return self.pose;
        }
        CameraPose::look_at(
            self.start.from.lerp(self.end.from, s),
            self.start.to.lerp(self.end.to, s),
            self.start.up,
        )
    }

    /// Raster position to the point on the film at `z = 1` (camera space).
    #[inline]
    fn raster_to_film(&self, p: Vec2) -> Vec3A {
        Vec3A::new(
            (2.0 * p.x / self.width as f32 - 1.0) * self.half_width,
            (1.0 - 2.0 * p.y / self.height as f32) * self.half_height,
            1.0,
        )
    }

    /// Camera-space point with `z > 0` projected through the pinhole to raster space.
    #[inline]
    fn camera_to_raster(&self, p: Vec3A) -> Vec2 {
        let (x, y) = (p.x / p.z, p.y / p.z);
        Vec2::new(
            0.5 * (x / self.half_width + 1.0) * self.width as f32,
            0.5 * (1.0 - y / self.half_height) * self.height as f32,
        )
    }

    /// Camera-space lens point for uniform `u_lens` (the origin for a pinhole).
    #[inline]
    fn lens_point(&self, u_lens: Vec2) -> Vec3A {
        if self.lens_radius > 0.0 {
            let d = self.lens_radius * sample_concentric_disk(u_lens);
            Vec3A::new(d.x, d.y, 0.0)
        } else {
            Vec3A::ZERO
        }
    }

    /// The primary ray through raster position `p_raster` (pixels, `(0,0)` = top-left corner),
    /// lens sample `u_lens ∈ [0,1)^2` (ignored by a pinhole) and time sample `u_time ∈ [0,1)`.
    /// The direction is unit length. Deterministic in its inputs.
    #[must_use]
    pub fn generate_ray(&self, p_raster: Vec2, u_lens: Vec2, u_time: f32) -> Ray {
        let time = self.sample_time(u_time);
        let pose = self.pose_at(time);
        let film = self.raster_to_film(p_raster);
        let (origin, dir) = if self.lens_radius > 0.0 {
            let lens = self.lens_point(u_lens);
            let focus = film * self.focus_distance;
            (lens, (focus - lens).normalize())
        } else {
            (Vec3A::ZERO, film.normalize())
        };
        Ray {
            origin: pose.origin + pose.to_world(origin),
            dir: pose.to_world(dir),
            time,
        }
    }

    /// Camera-space cosine and the raster position for a ray, or `None` if it points away from
    /// the film or lands outside it.
    fn ray_to_raster(&self, ray: &Ray) -> Option<(f32, Vec2)> {
        let pose = self.pose_at(ray.time);
        let dir = pose.to_camera(ray.dir).try_normalize()?;
        let cos_theta = dir.z;
        if cos_theta <= 0.0 {
            return None;
        }
        let origin = pose.to_camera(ray.origin - pose.origin);
        let focal = if self.lens_radius > 0.0 {
            self.focus_distance
        } else {
            1.0
        };
        // Where the ray meets the plane in focus, seen through the lens centre (pbrt-v3 `We`).
        let p_focus = origin + dir * ((focal - origin.z) / cos_theta);
        let p = self.camera_to_raster(p_focus);
        let inside = p.x >= 0.0
            && p.y >= 0.0
            && p.x < self.width as f32
            && p.y < self.height as f32
            && p.is_finite();
        inside.then_some((cos_theta, p))
    }

    /// Importance `We` of a ray leaving the lens (see the module docs for the normalisation)
    /// and the raster position it corresponds to; `None` if it misses the film.
    #[must_use]
    pub fn we(&self, ray: &Ray) -> Option<(f32, Vec2)> {
        let (cos_theta, p) = self.ray_to_raster(ray)?;
        let cos2 = cos_theta * cos_theta;
        Some((1.0 / (self.film_area() * self.lens_area() * cos2 * cos2), p))
    }

    /// Densities with which [`Camera::generate_ray`] with uniform raster and lens samples
    /// produces `ray`: `pdf_pos = 1 / lens_area` (per area on the lens) and
    /// `pdf_dir = 1 / (A cos^3 theta)` (per solid angle); `(0, 0)` if it misses the film
    /// (pbrt-v3 `PerspectiveCamera::Pdf_We`).
    #[must_use]
    pub fn pdf_we(&self, ray: &Ray) -> (f32, f32) {
        match self.ray_to_raster(ray) {
            Some((cos_theta, _)) => (
                1.0 / self.lens_area(),
                1.0 / (self.film_area() * cos_theta * cos_theta * cos_theta),
            ),
            None => (0.0, 0.0),
        }
    }

    /// Samples a lens point with `u_lens` and connects it to `reference` at `time` (absolute
    /// time, not a uniform sample): the importance arriving at `reference`, the raster
    /// position it contributes to and the solid-angle pdf at `reference` (pbrt-v3
    /// `PerspectiveCamera::Sample_Wi`). `None` if the point is behind the camera, off the film,
    /// or on the lens.
    #[must_use]
    pub fn sample_wi(&self, reference: Vec3A, u_lens: Vec2, time: f32) -> Option<CameraWiSample> {
        let pose = self.pose_at(time);
        let p_lens = pose.origin + pose.to_world(self.lens_point(u_lens));
        let to_lens = p_lens - reference;
        let dist2 = to_lens.length_squared();
        if !(dist2 > 0.0 && dist2.is_finite()) {
            return None;
        }
        let wi = to_lens / dist2.sqrt();
        let ray = Ray::new(p_lens, -wi, time);
        let (importance, p_raster) = self.we(&ray)?;
        let cos_lens = pose.forward.dot(wi).abs();
        let pdf = dist2 / (cos_lens * self.lens_area());
        (pdf.is_finite() && importance > 0.0).then_some(CameraWiSample {
            wi,
            pdf,
            p_lens,
            p_raster,
            importance,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::warp::sample_uniform_sphere;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64;

    fn cameras() -> Vec<(&'static str, Camera)> {
        let from = Vec3A::new(1.0, 2.0, 5.0);
        let to = Vec3A::new(0.0, 0.5, 0.0);
        let pinhole = Camera::perspective(from, to, Vec3A::Y, 40.0, 64, 48);
        vec![
            ("pinhole", pinhole),
            ("thin lens", pinhole.with_thin_lens(0.2, 4.0)),
            (
                "moving thin lens",
                pinhole.with_thin_lens(0.1, 3.0).with_motion(
                    Vec3A::new(1.5, 2.0, 5.0),
                    Vec3A::new(0.2, 0.5, 0.0),
                    0.0,
                    1.0,
                ),
            ),
        ]
    }

    #[test]
    fn generate_ray_and_sample_wi_round_trip() {
        let mut rng = Pcg64::seed_from_u64(7);
        for (name, cam) in cameras() {
            for _ in 0..2000 {
                let p = Vec2::new(
                    0.01 + rng.random::<f32>() * 63.98,
                    0.01 + rng.random::<f32>() * 47.98,
                );
                let u_lens = Vec2::new(rng.random(), rng.random());
                let ray = cam.generate_ray(p, u_lens, rng.random());
                assert!((ray.dir.length() - 1.0).abs() < 1e-5);
                let (we, p_we) = cam.we(&ray).expect("primary rays land on the film");
                assert!(we > 0.0);
                assert!(
                    (p_we - p).length() < 2e-3,
                    "{name}: we raster {p_we} vs {p}"
                );
                for dist in [0.5f32, 2.0, 10.0] {
                    let x = ray.at(dist);
                    let s = cam.sample_wi(x, u_lens, ray.time);
                    let s = s.expect("visible point connects to the lens");
                    assert!(
                        (s.p_raster - p).length() < 2e-3,
                        "{name}: {} vs {p}",
                        s.p_raster
                    );
                    assert!((s.p_lens - ray.origin).length() < 1e-4, "{name}");
                    assert!((s.wi + ray.dir).length() < 1e-4, "{name}");
                    assert!((s.importance - we).abs() <= 1e-3 * we, "{name}");
                    let pdf = dist * dist
                        / (cam.pose_at(ray.time).forward.dot(ray.dir))
                        / cam.lens_area();
                    assert!(
                        (s.pdf - pdf).abs() <= 1e-3 * pdf,
                        "{name}: {} vs {pdf}",
                        s.pdf
                    );
                }
            }
        }
    }

    #[test]
    fn focus_plane_is_sharp() {
        let cam = cameras()[1].1;
        let mut rng = Pcg64::seed_from_u64(8);
        for _ in 0..50 {
            let p = Vec2::new(
                0.01 + rng.random::<f32>() * 63.98,
                0.01 + rng.random::<f32>() * 47.98,
            );
            let chief = cam.generate_ray(p, Vec2::splat(0.5), 0.0);
            let cos = cam.pose_at(0.0).forward.dot(chief.dir);
            let on_plane = chief.at(cam.focus_distance() / cos);
            let off_plane = chief.at(0.5 * cam.focus_distance() / cos);
            let mut blur: f32 = 0.0;
            for _ in 0..32 {
                let u_lens = Vec2::new(rng.random(), rng.random());
                if let Some(s) = cam.sample_wi(on_plane, u_lens, 0.0) {
                    assert!((s.p_raster - p).length() < 2e-3, "{} vs {p}", s.p_raster);
                }
                // Every lens ray through the focused point comes from the same pixel.
                let ray = cam.generate_ray(p, u_lens, 0.0);
                let t = (on_plane - ray.origin).dot(ray.dir);
                assert!((ray.at(t) - on_plane).length() < 1e-3);
                if let Some(s) = cam.sample_wi(off_plane, u_lens, 0.0) {
                    blur = blur.max((s.p_raster - p).length());
                }
            }
            assert!(blur > 1.0, "out-of-focus point should blur, got {blur} px");
        }
    }

    #[test]
    fn importance_integrates_to_one() {
        // ∫_lens ∫_S2 We cos dω dA = 1: uniform lens point (pdf 1/lens_area), uniform sphere
        // direction (pdf 1/4pi). 400k samples; the relative standard error is about 0.5%.
        let mut rng = Pcg64::seed_from_u64(9);
        for (name, cam) in cameras() {
            let n = 400_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let time = cam.sample_time(rng.random());
                let pose = cam.pose_at(time);
                let lens = cam.lens_point(Vec2::new(rng.random(), rng.random()));
                let dir = sample_uniform_sphere(Vec2::new(rng.random(), rng.random()));
                let ray = Ray::new(pose.origin + pose.to_world(lens), dir, time);
                if let Some((we, _)) = cam.we(&ray) {
                    let cos = pose.forward.dot(dir);
                    sum += f64::from(we * cos * cam.lens_area() * 4.0 * PI);
                }
            }
            let mean = sum / n as f64;
            assert!((mean - 1.0).abs() < 0.03, "{name}: {mean}");
        }
    }

    #[test]
    fn pdf_we_matches_uniform_raster_sampling() {
        for (name, cam) in cameras() {
            for p in [
                Vec2::new(0.5, 0.5),
                Vec2::new(32.0, 24.0),
                Vec2::new(63.0, 10.0),
            ] {
                let ray = cam.generate_ray(p, Vec2::new(0.3, 0.8), 0.25);
                let (pdf_pos, pdf_dir) = cam.pdf_we(&ray);
                let (we, _) = cam.we(&ray).expect("on film");
                let cos = cam.pose_at(ray.time).forward.dot(ray.dir);
                // We cos / (pdf_pos pdf_dir) = 1: a camera tracer's weight is the radiance.
                assert!(
                    (we * cos / (pdf_pos * pdf_dir) - 1.0).abs() < 1e-4,
                    "{name}"
                );
                // Solid angle of a tiny raster square around p, measured by generate_ray.
                let h = 1e-2;
                let d = |q: Vec2| cam.generate_ray(q, Vec2::new(0.3, 0.8), 0.25).dir;
                let dx = d(p + Vec2::new(h, 0.0)) - d(p - Vec2::new(h, 0.0));
                let dy = d(p + Vec2::new(0.0, h)) - d(p - Vec2::new(0.0, h));
                let d_omega = dx.cross(dy).length() / (4.0 * h * h);
                let pixels = (cam.width() * cam.height()) as f32;
                // Uniform raster density is 1 / pixels per pixel^2.
                let expected = 1.0 / (pixels * d_omega);
                assert!(
                    (pdf_dir - expected).abs() < 1e-2 * expected,
                    "{name}: {pdf_dir} {expected}"
                );
            }
        }
    }

    #[test]
    fn raster_orientation_and_points_behind() {
        let cam = Camera::perspective(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 90.0, 200, 100);
        let centre = cam.generate_ray(Vec2::new(100.0, 50.0), Vec2::ZERO, 0.0);
        assert!((centre.dir - -Vec3A::Z).length() < 1e-6);
        let top_left = cam.generate_ray(Vec2::ZERO, Vec2::ZERO, 0.0);
        assert!(top_left.dir.x < 0.0 && top_left.dir.y > 0.0);
        // vfov 90: the top edge centre is at 45 degrees.
        let top = cam.generate_ray(Vec2::new(100.0, 0.0), Vec2::ZERO, 0.0);
        assert!((top.dir.y - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-5);
        assert!((cam.film_area() - 8.0).abs() < 1e-5);
        assert!(cam
            .sample_wi(Vec3A::new(0.0, 0.0, 1.0), Vec2::ZERO, 0.0)
            .is_none());
        assert!(cam.sample_wi(Vec3A::ZERO, Vec2::ZERO, 0.0).is_none());
        // Outside the field of view.
        assert!(cam
            .sample_wi(Vec3A::new(0.0, 5.0, -1.0), Vec2::ZERO, 0.0)
            .is_none());
    }

    #[test]
    fn from_matrix_matches_look_at() {
        let look = Camera::perspective(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 50.0, 32, 32);
        let gltf = Camera::from_matrix(Mat4::IDENTITY, 50f32.to_radians(), 32, 32);
        let p = Vec2::new(3.0, 29.0);
        let (a, b) = (
            look.generate_ray(p, Vec2::ZERO, 0.0),
            gltf.generate_ray(p, Vec2::ZERO, 0.0),
        );
        assert!((a.dir - b.dir).length() < 1e-5);

        // A rotated, translated and scaled node.
        let m = Mat4::from_scale_rotation_translation(
            glam::Vec3::splat(2.0),
            glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            glam::Vec3::new(1.0, 2.0, 3.0),
        );
        let cam = Camera::from_matrix(m, 0.8, 16, 16);
        let pose = cam.pose_at(0.0);
        assert!((pose.origin - Vec3A::new(1.0, 2.0, 3.0)).length() < 1e-5);
        // Rotating -z by +90 degrees about y gives -x.
        assert!((pose.forward - -Vec3A::X).length() < 1e-5);
        assert!((pose.up - Vec3A::Y).length() < 1e-5);

        let broken = Camera::from_matrix(Mat4::from_cols_array(&[f32::NAN; 16]), 0.8, 0, 0);
        let ray = broken.generate_ray(Vec2::splat(0.5), Vec2::ZERO, 0.0);
        assert!(ray.dir.is_finite() && ray.origin.is_finite());
        assert_eq!((broken.width(), broken.height()), (1, 1));
    }

    #[test]
    fn motion_interpolates_poses_and_is_deterministic() {
        let cam = cameras()[2].1;
        assert_eq!(cam.shutter(), (0.0, 1.0));
        let start = cam.pose_at(0.0);
        let end = cam.pose_at(1.0);
        let mid = cam.pose_at(0.5);
        assert!((start.origin - Vec3A::new(1.0, 2.0, 5.0)).length() < 1e-6);
        assert!((end.origin - Vec3A::new(1.5, 2.0, 5.0)).length() < 1e-6);
        assert!((mid.origin - Vec3A::new(1.25, 2.0, 5.0)).length() < 1e-6);
        let r1 = cam.generate_ray(Vec2::new(10.5, 20.25), Vec2::new(0.1, 0.9), 0.75);
        let r2 = cam.generate_ray(Vec2::new(10.5, 20.25), Vec2::new(0.1, 0.9), 0.75);
        assert_eq!(r1, r2);
        assert_eq!(r1.time, 0.75);
        // A static camera puts every ray at time 0 unless a shutter is set.
        assert_eq!(
            cameras()[0].1.generate_ray(Vec2::ONE, Vec2::ZERO, 0.6).time,
            0.0
        );
        let shuttered = cameras()[0].1.with_shutter(1.0, 0.0);
        assert_eq!(shuttered.generate_ray(Vec2::ONE, Vec2::ZERO, 0.5).time, 0.5);
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let cam = Camera::perspective(Vec3A::ONE, Vec3A::ONE, Vec3A::ZERO, f32::NAN, 0, 0)
            .with_thin_lens(f32::NAN, -1.0)
            .with_motion(Vec3A::splat(f32::NAN), Vec3A::ZERO, 0.0, 1.0);
        let ray = cam.generate_ray(Vec2::splat(0.5), Vec2::splat(0.5), 0.5);
        assert!(ray.dir.is_finite() && (ray.dir.length() - 1.0).abs() < 1e-5);
        assert_eq!(cam.lens_radius(), 0.0);
        assert_eq!(cam.focus_distance(), 1.0);
        // Up parallel to the view direction.
        let cam = Camera::perspective(Vec3A::ZERO, Vec3A::Y, Vec3A::Y, 60.0, 8, 8);
        let pose = cam.pose_at(0.0);
        assert!(pose.right.dot(pose.forward).abs() < 1e-6 && pose.up.is_finite());
    }
}
