//! The continuous geometry of a path over [`Real`]: warps, shading frames, the camera, and
//! re-intersection of a known triangle. Each function restates the f32 renderer's
//! (`crate::warp`, `crate::frame`, `crate::camera`, `Scene::intersect`) with the same
//! branches, so that the value agrees with it to rounding.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use glam::Vec3A;

use crate::autodiff::{Real, V3};
use crate::camera::CameraParams;
use crate::mesh::Mesh;

/// `crate::warp::sample_concentric_disk` (Shirley-Chiu).
pub(super) fn concentric_disk<T: Real>(u: (T, T)) -> (T, T) {
    let o = (u.0 * 2.0 - 1.0, u.1 * 2.0 - 1.0);
    if o.0.value() == 0.0 && o.1.value() == 0.0 {
        return (T::cst(0.0), T::cst(0.0));
    }
    let (r, theta) = if o.0.value().abs() > o.1.value().abs() {
        (o.0, (o.1 / o.0) * FRAC_PI_4)
    } else {
        (o.1, -((o.0 / o.1) * FRAC_PI_4) + FRAC_PI_2)
    };
    let (s, c) = theta.sin_cos();
    (r * c, r * s)
}

/// `crate::warp::sample_cosine_hemisphere`.
pub(super) fn cosine_hemisphere<T: Real>(u: (T, T)) -> V3<T> {
    let (x, y) = concentric_disk(u);
    let z = (-(x * x + y * y) + 1.0).max_c(0.0).sqrt();
    V3::new(x, y, z)
}

/// `crate::warp::cosine_hemisphere_pdf`.
pub(super) fn cosine_hemisphere_pdf<T: Real>(cos: T) -> T {
    cos.max_c(0.0) / PI
}

/// `crate::warp::sample_uniform_triangle`: barycentrics `[b0, b1, b2]`.
pub(super) fn uniform_triangle<T: Real>(u: (T, T)) -> [T; 3] {
    let (b0, b1) = if u.0.value() < u.1.value() {
        let b0 = u.0 * 0.5;
        (b0, u.1 - b0)
    } else {
        let b1 = u.1 * 0.5;
        (u.0 - b1, b1)
    };
    [b0, b1, -(b0 + b1) + 1.0]
}

/// An orthonormal frame (`crate::frame::Frame`, Duff et al. 2017's construction).
#[derive(Clone, Copy, Debug)]
pub(super) struct Frame<T> {
    pub(super) s: V3<T>,
    pub(super) t: V3<T>,
    pub(super) n: V3<T>,
}

impl<T: Real> Frame<T> {
    /// `Frame::from_normal`.
    pub(super) fn from_normal(n: V3<T>) -> Self {
        let sign = 1.0f64.copysign(n.z.value());
        let a = (n.z + sign).recip() * -1.0;
        let b = n.x * n.y * a;
        let s = V3::new(n.x * n.x * a * sign + 1.0, b * sign, n.x * -sign);
        let t = V3::new(b, n.y * n.y * a + sign, -n.y);
        Self { s, t, n }
    }

    pub(super) fn to_local(self, v: V3<T>) -> V3<T> {
        V3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    pub(super) fn to_world(self, v: V3<T>) -> V3<T> {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

impl Frame<f64> {
    /// The constant frame over `T`.
    pub(super) fn over_t<T: Real>(self) -> Frame<T> {
        Frame {
            s: V3::cst(self.s),
            t: V3::cst(self.t),
            n: V3::cst(self.n),
        }
    }

    /// [`Frame::to_world`] of a constant frame: mixed products ([`V3::times`]).
    pub(super) fn to_world_c<T: Real>(self, v: V3<T>) -> V3<T> {
        self.s.times(v.x) + self.t.times(v.y) + self.n.times(v.z)
    }
}

/// `crate::frame::shading_consistent`, on values.
pub(super) fn shading_consistent<T: Real>(wo: V3<T>, wi: V3<T>, ng: V3<f64>, ns: V3<T>) -> bool {
    let geometric = wo.dot_c(ng).value() * wi.dot_c(ng).value();
    let shading = wo.dot(ns).value() * wi.dot(ns).value();
    geometric != 0.0 && (geometric > 0.0) == (shading > 0.0)
}

/// Veach's shading-normal correction (`bdpt::vertex::shading_normal_correction`).
pub(super) fn shading_normal_correction<T: Real>(
    wo: V3<T>,
    wi: V3<T>,
    ng: V3<f64>,
    ns: V3<T>,
) -> T {
    let denom = wo.dot_c(ng).abs() * wi.dot(ns).abs();
    if denom.value() == 0.0 {
        return T::cst(0.0);
    }
    wo.dot(ns).abs() * wi.dot_c(ng).abs() / denom
}

/// A camera pose (`crate::camera::CameraPose`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Pose<T> {
    origin: V3<T>,
    right: V3<T>,
    up: V3<T>,
    forward: V3<T>,
}

impl<T: Real> Pose<T> {
    fn to_world(self, v: V3<T>) -> V3<T> {
        self.right * v.x + self.up * v.y + self.forward * v.z
    }
    fn to_camera(self, v: V3<T>) -> V3<T> {
        V3::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }
}

/// The camera pose at a time: the renderer's constant frame (a static camera, or a moving
/// one at the shutter's opening), whose products with the path are mixed ([`V3::dot_c`]),
/// or a pose over `T` that moves with the time.
#[derive(Clone, Copy, Debug)]
pub(super) enum PoseAt<T> {
    /// A constant pose.
    Fixed(Pose<f64>),
    /// A pose carrying the time's derivative.
    Moving(Pose<T>),
}

impl<T: Real> PoseAt<T> {
    /// Camera to world (a direction).
    fn to_world(self, v: V3<T>) -> V3<T> {
        match self {
            Self::Fixed(p) => p.right.times(v.x) + p.up.times(v.y) + p.forward.times(v.z),
            Self::Moving(p) => p.to_world(v),
        }
    }

    /// World to camera (a direction).
    fn to_camera(self, v: V3<T>) -> V3<T> {
        match self {
            Self::Fixed(p) => V3::new(v.dot_c(p.right), v.dot_c(p.up), v.dot_c(p.forward)),
            Self::Moving(p) => p.to_camera(v),
        }
    }

    /// The pose's origin plus `v`.
    fn origin_plus(self, v: V3<T>) -> V3<T> {
        match self {
            Self::Fixed(p) => v.add_c(p.origin),
            Self::Moving(p) => p.origin + v,
        }
    }

    /// `v` minus the pose's origin.
    fn minus_origin(self, v: V3<T>) -> V3<T> {
        match self {
            Self::Fixed(p) => v.sub_c(p.origin),
            Self::Moving(p) => v - p.origin,
        }
    }

    /// The frame about the viewing direction (a camera vertex's).
    pub(super) fn frame(self) -> Frame<T> {
        match self {
            Self::Fixed(p) => Frame::from_normal(p.forward).over_t(),
            Self::Moving(p) => Frame::from_normal(p.forward),
        }
    }

    /// `forward . w`.
    fn forward_dot(self, w: V3<T>) -> T {
        match self {
            Self::Fixed(p) => w.dot_c(p.forward),
            Self::Moving(p) => p.forward.dot(w),
        }
    }
}

/// The perspective camera (`crate::camera::Camera`) over [`Real`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Camera {
    p: CameraParams,
}

/// Where a ray from the lens lands on the film: `(cos theta, raster position)`.
pub(super) struct FilmHit<T> {
    pub(super) cos: T,
    pub(super) raster: (T, T),
}

impl Camera {
    pub(super) fn new(p: CameraParams) -> Self {
        Self { p }
    }

    fn lens_area(&self) -> f64 {
        let r = f64::from(self.p.lens_radius);
        if r > 0.0 {
            PI * r * r
        } else {
            1.0
        }
    }

    fn film_area(&self) -> f64 {
        4.0 * f64::from(self.p.half.0) * f64::from(self.p.half.1)
    }

    /// `Camera::sample_time`.
    pub(super) fn time<T: Real>(&self, u: T) -> T {
        let (open, close) = self.p.shutter;
        u * f64::from(close - open) + f64::from(open)
    }

    /// `Camera::pose_at`: the start pose's f32 frame for a static camera (as the renderer),
    /// else the interpolated look-at, differentiated with respect to time.
    pub(super) fn pose_at<T: Real>(&self, time: T) -> PoseAt<T> {
        let fixed = PoseAt::Fixed(Pose {
            origin: V3::from_a(self.p.pose.origin),
            right: V3::from_a(self.p.pose.right),
            up: V3::from_a(self.p.pose.up),
            forward: V3::from_a(self.p.pose.forward),
        });
        if !self.p.moving {
            return fixed;
        }
        let (open, close) = self.p.shutter;
        let span = f64::from(close - open);
        let s = if span > 0.0 {
            ((time - f64::from(open)) / span).clamp_c(0.0, 1.0)
        } else {
            T::cst(0.0)
        };
        if s.value() == 0.0 {
            return fixed;
        }
        let lerp = |a: Vec3A, b: Vec3A| V3::from_a(a) + (V3::from_a(b) - V3::from_a(a)) * s;
        let (from, to, up) = self.p.start;
        let origin = lerp(from, self.p.end.0);
        let target = lerp(to, self.p.end.1);
        let Some(forward) = (target - origin).try_normalize() else {
            return fixed;
        };
        let Some(right) = forward.cross(V3::from_a(up)).try_normalize() else {
            return fixed;
        };
        PoseAt::Moving(Pose {
            origin,
            right,
            up: right.cross(forward),
            forward,
        })
    }

    fn lens_point<T: Real>(&self, u: (T, T)) -> V3<T> {
        let r = f64::from(self.p.lens_radius);
        if r > 0.0 {
            let (x, y) = concentric_disk(u);
            V3::new(x * r, y * r, T::cst(0.0))
        } else {
            V3::zero()
        }
    }

    /// `Camera::generate_ray`: `(origin, unit direction, time)`.
    pub(super) fn generate_ray<T: Real>(
        &self,
        raster: (T, T),
        u_lens: (T, T),
        u_time: T,
    ) -> (V3<T>, V3<T>, T) {
        let time = self.time(u_time);
        let pose = self.pose_at(time);
        let (w, h) = (f64::from(self.p.size.0), f64::from(self.p.size.1));
        let (hw, hh) = (f64::from(self.p.half.0), f64::from(self.p.half.1));
        let film = V3::new(
            (raster.0 * (2.0 / w) - 1.0) * hw,
            (-(raster.1 * (2.0 / h)) + 1.0) * hh,
            T::cst(1.0),
        );
        let (origin, dir) = if self.p.lens_radius > 0.0 {
            let lens = self.lens_point(u_lens);
            let focus = film.scale(f64::from(self.p.focus_distance));
            (lens, (focus - lens).normalize_or_zero())
        } else {
            (V3::zero(), film.normalize_or_zero())
        };
        (
            pose.origin_plus(pose.to_world(origin)),
            pose.to_world(dir),
            time,
        )
    }

    /// `Camera::ray_to_raster`.
    pub(super) fn ray_to_raster<T: Real>(
        &self,
        origin: V3<T>,
        dir: V3<T>,
        time: T,
    ) -> Option<FilmHit<T>> {
        let pose = self.pose_at(time);
        let dir = pose.to_camera(dir).try_normalize()?;
        let cos = dir.z;
        if cos.value() <= 0.0 {
            return None;
        }
        let o = pose.to_camera(pose.minus_origin(origin));
        let focal = if self.p.lens_radius > 0.0 {
            f64::from(self.p.focus_distance)
        } else {
            1.0
        };
        let p = o + dir * ((-o.z + focal) / cos);
        let (x, y) = (p.x / p.z, p.y / p.z);
        let (w, h) = (f64::from(self.p.size.0), f64::from(self.p.size.1));
        let (hw, hh) = (f64::from(self.p.half.0), f64::from(self.p.half.1));
        let raster = ((x / hw + 1.0) * (0.5 * w), (-(y / hh) + 1.0) * (0.5 * h));
        // The renderer tests the f32 raster position.
        let (rx, ry) = (raster.0.value() as f32, raster.1.value() as f32);
        let inside = rx >= 0.0
            && ry >= 0.0
            && rx < self.p.size.0 as f32
            && ry < self.p.size.1 as f32
            && rx.is_finite()
            && ry.is_finite();
        inside.then_some(FilmHit { cos, raster })
    }

    /// `Camera::pdf_we`'s directional density of a ray (0 off the film).
    pub(super) fn pdf_dir<T: Real>(&self, origin: V3<T>, dir: V3<T>, time: T) -> T {
        match self.ray_to_raster(origin, dir, time) {
            Some(hit) => (hit.cos * hit.cos * hit.cos * self.film_area()).recip(),
            None => T::cst(0.0),
        }
    }

    /// `Camera::sample_wi`: `(wi towards the lens, pdf, lens point, raster, importance)`.
    #[allow(clippy::type_complexity)]
    pub(super) fn sample_wi<T: Real>(
        &self,
        reference: V3<T>,
        u: (T, T),
        time: T,
    ) -> Option<(V3<T>, T, V3<T>, (T, T), T)> {
        let pose = self.pose_at(time);
        let p_lens = pose.origin_plus(pose.to_world(self.lens_point(u)));
        let to_lens = p_lens - reference;
        let dist2 = to_lens.length_squared();
        if !(dist2.value() > 0.0 && dist2.is_finite()) {
            return None;
        }
        let wi = to_lens * dist2.sqrt().recip();
        let hit = self.ray_to_raster(p_lens, -wi, time)?;
        let cos2 = hit.cos * hit.cos;
        let importance = (cos2 * cos2 * (self.film_area() * self.lens_area())).recip();
        let cos_lens = pose.forward_dot(wi).abs();
        let pdf = dist2 / (cos_lens * self.lens_area());
        (pdf.is_finite() && importance.value() > 0.0)
            .then_some((wi, pdf, p_lens, hit.raster, importance))
    }
}

/// A surface point re-intersected on a known triangle.
pub(super) struct TriangleHit<T> {
    pub(super) p: V3<T>,
    /// The triangle's geometric normal: a constant.
    pub(super) ng: V3<f64>,
    pub(super) ns: V3<T>,
    pub(super) bary: (T, T),
}

/// Intersects the ray `origin + t dir` with triangle `tri` of `mesh` (Moller-Trumbore, no
/// range test: the f32 BVH already chose the triangle) and interpolates position and shading
/// normal as `Scene::intersect` does. `None` for a ray parallel to the triangle. The
/// triangle's vertices and normals are constants: every product with one is a mixed product
/// ([`V3::dot_c`]).
pub(super) fn intersect_triangle<T: Real>(
    mesh: &Mesh,
    tri: usize,
    origin: V3<T>,
    dir: V3<T>,
) -> Option<TriangleHit<T>> {
    let [i0, i1, i2] = mesh.triangles.get(tri)?.map(|i| i as usize);
    let (p0, p1, p2) = (
        V3::<f64>::from_a(mesh.positions[i0]),
        V3::<f64>::from_a(mesh.positions[i1]),
        V3::<f64>::from_a(mesh.positions[i2]),
    );
    let (e1, e2) = (p1 - p0, p2 - p0);
    let pvec = dir.cross_c(e2);
    let det = pvec.dot_c(e1);
    if det.value().abs() < 1e-300 {
        return None;
    }
    let inv = det.recip();
    let tvec = origin.sub_c(p0);
    let b1 = tvec.dot(pvec) * inv;
    let qvec = tvec.cross_c(e1);
    let b2 = dir.dot(qvec) * inv;
    let b0 = (-(b1 + b2) + 1.0).max_c(0.0);
    let p = p0.times(b0) + p1.times(b1) + p2.times(b2);
    let ng = V3::<f64>::from_a(
        (mesh.positions[i1] - mesh.positions[i0])
            .cross(mesh.positions[i2] - mesh.positions[i0])
            .normalize_or_zero(),
    );
    let n = &mesh.normals;
    let ns = if n.len() > i0.max(i1).max(i2) {
        let ns = V3::<f64>::from_a(n[i0]).times(b0)
            + V3::<f64>::from_a(n[i1]).times(b1)
            + V3::<f64>::from_a(n[i2]).times(b2);
        match ns.try_normalize() {
            Some(ns) if ns.dot_c(ng).value() < 0.0 => -ns,
            Some(ns) => ns,
            None => V3::cst(ng),
        }
    } else {
        V3::cst(ng)
    };
    Some(TriangleHit {
        p,
        ng,
        ns,
        bary: (b1, b2),
    })
}
