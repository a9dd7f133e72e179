//! A tiny analytic f64 scene (rectangles, spheres, a pinhole) implementing the scene traits,
//! so the crate's tests need no renderer.

mod camera;
mod material;

pub use camera::PinholeCamera;
pub use material::{fresnel_dielectric, Material};

use crate::error::PathspaceError;
use crate::scene::{BsdfSample, Bsdfs, Camera, Emitters, RayTracer, SpecularLobe, SurfacePoint};
use crate::vec3::{Rgb, Vec3};

/// Rays ignore hits closer than this (self-intersection); scenes are of unit scale.
const T_MIN: f64 = 1e-7;

/// The geometry of a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Geometry {
    /// The rectangle `corner + a u + b v`, `a, b` in `[0, 1]`, with `u` orthogonal to `v`;
    /// normal `u x v / |u x v|` (emission leaves on the normal side).
    Rectangle {
        /// A corner.
        corner: Vec3,
        /// First edge.
        u: Vec3,
        /// Second edge (orthogonal to `u`).
        v: Vec3,
    },
    /// A sphere with outward normals.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f64,
    },
}

/// A shape: geometry, material and emitted radiance (rectangles only; one-sided).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    /// The geometry.
    pub geometry: Geometry,
    /// The material.
    pub material: Material,
    /// Radiance emitted on the normal side (black for non-emitters).
    pub emission: Rgb,
}

impl Shape {
    fn area(&self) -> f64 {
        match self.geometry {
            Geometry::Rectangle { u, v, .. } => u.cross(v).length(),
            Geometry::Sphere { radius, .. } => 4.0 * std::f64::consts::PI * radius * radius,
        }
    }

    fn intersect(&self, o: Vec3, d: Vec3, t_max: f64) -> Option<(f64, Vec3)> {
        match self.geometry {
            Geometry::Rectangle { corner, u, v } => {
                let n = u.cross(v).normalize();
                let denom = d.dot(n);
                if denom == 0.0 {
                    return None;
                }
                let t = (corner - o).dot(n) / denom;
                if !(t > T_MIN && t < t_max) {
                    return None;
                }
                let p = o + d * t;
                let w = p - corner;
                let a = w.dot(u) / u.length_squared();
                let b = w.dot(v) / v.length_squared();
                ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some((t, n))
            }
            Geometry::Sphere { center, radius } => {
                let oc = o - center;
                let b = oc.dot(d);
                let c = oc.length_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let sq = disc.sqrt();
                // Numerically stable roots.
                let q = if b > 0.0 { -b - sq } else { -b + sq };
                let (mut t0, mut t1) = (q, c / q);
                if t0 > t1 {
                    std::mem::swap(&mut t0, &mut t1);
                }
                let t = if t0 > T_MIN { t0 } else { t1 };
                if !(t > T_MIN && t < t_max) {
                    return None;
                }
                let p = o + d * t;
                Some((t, ((p - center) / radius).normalize()))
            }
        }
    }
}

/// A scene of rectangles and spheres with a pinhole camera, in f64: the crate's test bed.
///
/// Implements [`RayTracer`], [`Bsdfs`], [`Emitters`] and [`Camera`] (hence
/// [`crate::PathScene`]) by brute force over its shapes. The [`SurfacePoint::material`] handle
/// is the shape index. Emitters are rectangles sampled uniformly by area.
///
/// # Example
/// ```
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{RayTracer, Camera};
///
/// let scene = AnalyticScene::furnace_box(0.5, 1.0).unwrap();
/// let hit = scene.intersect(scene.origin(), scene.direction([0.5, 0.5])).unwrap();
/// assert!((hit.position.z + 1.0).abs() < 1e-12); // the back wall
/// ```
#[derive(Clone, Debug)]
pub struct AnalyticScene {
    shapes: Vec<Shape>,
    camera: PinholeCamera,
    emitters: Vec<usize>,
    emitter_area: f64,
}

impl AnalyticScene {
    /// An empty scene seen by `camera`.
    #[must_use]
    pub fn new(camera: PinholeCamera) -> Self {
        Self {
            shapes: Vec::new(),
            camera,
            emitters: Vec::new(),
            emitter_area: 0.0,
        }
    }

    /// Adds a rectangle `corner + a u + b v` (`u` orthogonal to `v`).
    ///
    /// # Errors
    /// [`PathspaceError::InvalidScene`] for degenerate or non-orthogonal edges or a negative
    /// or non-finite emission.
    pub fn add_rectangle(
        &mut self,
        corner: Vec3,
        u: Vec3,
        v: Vec3,
        material: Material,
        emission: Rgb,
    ) -> Result<&mut Self, PathspaceError> {
        let area = u.cross(v).length();
        if area.is_nan() || area <= 0.0 || u.dot(v).abs() > 1e-12 * u.length() * v.length() {
            return Err(PathspaceError::InvalidScene(
                "rectangle edges must be nonzero and orthogonal".into(),
            ));
        }
        if emission.0.iter().any(|e| !(e.is_finite() && *e >= 0.0)) {
            return Err(PathspaceError::InvalidScene(format!(
                "emission {:?} must be finite and non-negative",
                emission.0
            )));
        }
        if !emission.is_black() {
            self.emitters.push(self.shapes.len());
            self.emitter_area += area;
        }
        self.shapes.push(Shape {
            geometry: Geometry::Rectangle { corner, u, v },
            material,
            emission,
        });
        Ok(self)
    }

    /// Adds a sphere.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidScene`] for a non-positive radius.
    pub fn add_sphere(
        &mut self,
        center: Vec3,
        radius: f64,
        material: Material,
    ) -> Result<&mut Self, PathspaceError> {
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(PathspaceError::InvalidScene(format!(
                "sphere radius {radius} must be positive"
            )));
        }
        self.shapes.push(Shape {
            geometry: Geometry::Sphere { center, radius },
            material,
            emission: Rgb::BLACK,
        });
        Ok(self)
    }

    /// The shapes.
    #[must_use]
    pub fn shapes(&self) -> &[Shape] {
        &self.shapes
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &PinholeCamera {
        &self.camera
    }

    /// Total emitter area.
    #[must_use]
    pub fn emitter_area(&self) -> f64 {
        self.emitter_area
    }

    fn shape(&self, p: &SurfacePoint) -> &Shape {
        &self.shapes[p.material as usize]
    }

    /// Adds the six inward-facing walls of the box `[-h, h]^3`, all with `material` and
    /// `emission`.
    fn add_box_walls(
        &mut self,
        h: f64,
        material: impl Fn(usize) -> Material,
        emission: impl Fn(usize) -> Rgb,
    ) -> Result<(), PathspaceError> {
        let e = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        // For each axis a, the wall at -h (normal +a) and at +h (normal -a); edges chosen so
        // that u x v points inward.
        let mut wall = 0;
        for a in 0..3 {
            let (b, c) = (e[(a + 1) % 3], e[(a + 2) % 3]);
            let lo = Vec3::new(-h, -h, -h);
            // wall at -h along axis a: corner lo, u = 2h b, v = 2h c -> b x c = +e[a] (inward).
            self.add_rectangle(
                lo,
                b * (2.0 * h),
                c * (2.0 * h),
                material(wall),
                emission(wall),
            )?;
            wall += 1;
            // wall at +h: corner lo + 2h e[a], u = 2h c, v = 2h b -> c x b = -e[a] (inward).
            self.add_rectangle(
                lo + e[a] * (2.0 * h),
                c * (2.0 * h),
                b * (2.0 * h),
                material(wall),
                emission(wall),
            )?;
            wall += 1;
        }
        Ok(())
    }

    /// The white furnace box: the closed cube `[-1, 1]^3`, every wall Lambertian with albedo
    /// `albedo` and emitting `emission` (gray) toward the inside; the camera at
    /// `(0.2, -0.1, 0.5)` looks down the `-z` axis (60° vertical field of view, aspect 4:3).
    ///
    /// Radiance arriving at the camera along any ray through paths of at most `n` edges is
    /// exactly `emission * sum_{j < n} albedo^j`: the closed-form value convergence tests use.
    ///
    /// # Errors
    /// [`PathspaceError`] for albedo outside `[0, 1]` or negative emission.
    pub fn furnace_box(albedo: f64, emission: f64) -> Result<Self, PathspaceError> {
        PathspaceError::check_range("albedo", albedo, 0.0, 1.0)?;
        let camera = PinholeCamera::look_at(
            Vec3::new(0.2, -0.1, 0.5),
            Vec3::new(0.2, -0.1, -1.0),
            Vec3::new(0.0, 1.0, 0.0),
            60.0,
            4.0 / 3.0,
        )?;
        let mut scene = Self::new(camera);
        scene.add_box_walls(
            1.0,
            |_| Material::Diffuse {
                albedo: Rgb::gray(albedo),
            },
            |_| Rgb::gray(emission),
        )?;
        Ok(scene)
    }

    /// A closed test box `[-1, 1]^3` with every kind of material: a Lambertian floor,
    /// ceiling and front wall, a red Lambertian left wall, a glossy Phong back wall, a mirror
    /// right wall, a small square emitter (radiance 8) just below the ceiling facing down, a
    /// glass sphere (ior 1.5), a mirror sphere and a glossy sphere. The camera at
    /// `(0, 0, 0.9)` looks at the back wall.
    ///
    /// # Errors
    /// Never (kept for symmetry with the other constructors).
    pub fn test_box() -> Result<Self, PathspaceError> {
        let camera = PinholeCamera::look_at(
            Vec3::new(0.0, 0.0, 0.9),
            Vec3::new(0.0, -0.1, -1.0),
            Vec3::new(0.0, 1.0, 0.0),
            65.0,
            1.0,
        )?;
        let mut scene = Self::new(camera);
        let white = Material::Diffuse {
            albedo: Rgb::gray(0.7),
        };
        // Wall order of add_box_walls: x=-1 (left), x=+1 (right), y=-1 (floor),
        // y=+1 (ceiling), z=-1 (back), z=+1 (front).
        scene.add_box_walls(
            1.0,
            |wall| match wall {
                0 => Material::Diffuse {
                    albedo: Rgb([0.7, 0.15, 0.1]),
                },
                1 => Material::Mirror {
                    reflectance: Rgb::gray(0.9),
                },
                4 => Material::Phong {
                    diffuse: Rgb::gray(0.3),
                    specular: Rgb::gray(0.5),
                    exponent: 30.0,
                },
                _ => white,
            },
            |_| Rgb::BLACK,
        )?;
        // The emitter: a 0.6 x 0.6 square at y = 0.98 facing down.
        scene.add_rectangle(
            Vec3::new(-0.3, 0.98, -0.6),
            Vec3::new(0.6, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.6),
            Material::Black,
            Rgb::gray(8.0),
        )?;
        scene.add_sphere(
            Vec3::new(-0.4, -0.6, -0.3),
            0.35,
            Material::Dielectric {
                ior: 1.5,
                tint: Rgb::gray(1.0),
            },
        )?;
        scene.add_sphere(
            Vec3::new(0.45, -0.65, -0.45),
            0.3,
            Material::Mirror {
                reflectance: Rgb::gray(0.95),
            },
        )?;
        scene.add_sphere(
            Vec3::new(0.3, 0.2, -0.7),
            0.2,
            Material::Phong {
                diffuse: Rgb([0.2, 0.4, 0.6]),
                specular: Rgb::gray(0.3),
                exponent: 10.0,
            },
        )?;
        Ok(scene)
    }

    fn closest(&self, o: Vec3, d: Vec3, t_max: f64) -> Option<(usize, f64, Vec3)> {
        let mut best = None;
        let mut t_best = t_max;
        for (i, s) in self.shapes.iter().enumerate() {
            if let Some((t, n)) = s.intersect(o, d, t_best) {
                t_best = t;
                best = Some((i, t, n));
            }
        }
        best
    }
}

impl RayTracer for AnalyticScene {
    fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<SurfacePoint> {
        let (i, t, n) = self.closest(origin, dir, f64::INFINITY)?;
        Some(SurfacePoint {
            position: origin + dir * t,
            shading_normal: n,
            geometric_normal: n,
            material: i as u32,
        })
    }

    fn visible(&self, a: Vec3, b: Vec3) -> bool {
        let d = b - a;
        let dist = d.length();
        if dist.is_nan() || dist <= 0.0 {
            return false;
        }
        self.closest(a, d / dist, dist * (1.0 - 1e-9) - T_MIN)
            .is_none()
    }
}

impl Bsdfs for AnalyticScene {
    fn is_specular(&self, p: &SurfacePoint) -> bool {
        self.shape(p).material.is_specular()
    }
    fn eval(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> Rgb {
        self.shape(p).material.eval(p.shading_normal, wo, wi)
    }
    fn pdf(&self, p: &SurfacePoint, wo: Vec3, wi: Vec3) -> f64 {
        self.shape(p).material.pdf(p.shading_normal, wo, wi)
    }
    fn sample(&self, p: &SurfacePoint, wo: Vec3, u: [f64; 3]) -> Option<BsdfSample> {
        self.shape(p).material.sample(p.shading_normal, wo, u)
    }
    fn specular_direction(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Option<Vec3> {
        self.shape(p)
            .material
            .specular_direction(p.shading_normal, wo, lobe)
    }
    fn specular_weight(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> Rgb {
        self.shape(p)
            .material
            .specular_weight(p.shading_normal, wo, lobe)
    }
    fn specular_pdf(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> f64 {
        self.shape(p)
            .material
            .specular_pdf(p.shading_normal, wo, lobe)
    }
    fn specular_jacobian(&self, p: &SurfacePoint, wo: Vec3, lobe: SpecularLobe) -> f64 {
        self.shape(p)
            .material
            .specular_jacobian(p.shading_normal, wo, lobe)
    }
}

impl Emitters for AnalyticScene {
    fn emitted(&self, p: &SurfacePoint, w: Vec3) -> Rgb {
        let s = self.shape(p);
        if w.dot(p.geometric_normal) > 0.0 {
            s.emission
        } else {
            Rgb::BLACK
        }
    }

    fn is_emitter(&self, p: &SurfacePoint) -> bool {
        !self.shape(p).emission.is_black()
    }

    fn sample_emitter(&self, u: [f64; 3]) -> Option<(SurfacePoint, f64)> {
        if self.emitters.is_empty() {
            return None;
        }
        let mut target = u[0] * self.emitter_area;
        let mut chosen = *self.emitters.last()?;
        for &i in &self.emitters {
            let a = self.shapes[i].area();
            if target < a {
                chosen = i;
                break;
            }
            target -= a;
        }
        let Geometry::Rectangle {
            corner,
            u: eu,
            v: ev,
        } = self.shapes[chosen].geometry
        else {
            return None;
        };
        let n = eu.cross(ev).normalize();
        Some((
            SurfacePoint {
                position: corner + eu * u[1] + ev * u[2],
                shading_normal: n,
                geometric_normal: n,
                material: chosen as u32,
            },
            1.0 / self.emitter_area,
        ))
    }

    fn emitter_pdf(&self, p: &SurfacePoint) -> f64 {
        if self.is_emitter(p) {
            1.0 / self.emitter_area
        } else {
            0.0
        }
    }
}

impl Camera for AnalyticScene {
    fn origin(&self) -> Vec3 {
        self.camera.origin()
    }
    fn direction(&self, raster: [f64; 2]) -> Vec3 {
        self.camera.direction(raster)
    }
    fn raster(&self, dir: Vec3) -> Option<[f64; 2]> {
        self.camera.raster(dir)
    }
    fn importance(&self, dir: Vec3) -> f64 {
        self.camera.direction_pdf(dir)
    }
    fn direction_pdf(&self, dir: Vec3) -> f64 {
        self.camera.direction_pdf(dir)
    }
}
