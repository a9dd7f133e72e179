//! Area lights: every triangle whose material emits is a diffuse (Lambertian) emitter,
//! sampled uniformly by area, emitting cosine-weighted.

use glam::{Vec2, Vec3, Vec3A};

use crate::image::luminance;
use crate::mesh::Mesh;
use crate::warp::sample_uniform_triangle;

/// One emissive triangle: a Lambertian emitter of constant radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    /// The mesh triangle.
    pub triangle: u32,
    /// Its vertices.
    pub vertices: [Vec3A; 3],
    /// Unit geometric normal of the front side (`(p1 - p0) x (p2 - p0)`, glTF winding).
    pub normal: Vec3A,
    /// Area.
    pub area: f32,
    /// Emitted radiance (RGB).
    pub radiance: Vec3,
    /// Emits from both sides (glTF `doubleSided` materials); otherwise the front side only.
    pub two_sided: bool,
    /// Material index (for emissive textures).
    pub material: u32,
    /// True if the emission varies over the triangle (an emissive texture, or an alpha mask
    /// that cuts parts out): the radiance at a point is `radiance` times the texture there,
    /// zero where cut out ([`crate::scene::Scene::area_le`] evaluates it).
    pub textured: bool,
    /// Mean of the texture's luminance factor over the triangle (1 if untextured), for the
    /// selection by power.
    pub power_scale: f32,
}

impl AreaLight {
    /// Radiance leaving the light towards `w` (a direction away from the surface).
    #[inline]
    #[must_use]
    pub fn le(&self, w: Vec3A) -> Vec3 {
        if self.two_sided || self.normal.dot(w) > 0.0 {
            self.radiance
        } else {
            Vec3::ZERO
        }
    }

    /// Emitted power `Φ = π A L (× 2 if two-sided)`, in luminance.
    #[must_use]
    pub fn power(&self) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        std::f32::consts::PI
            * self.area
            * luminance(self.radiance.to_array())
            * sides
            * self.power_scale
    }

    /// A uniformly distributed point on the triangle from `u` in `[0, 1)^2`
    /// (pbrt-v4 `SampleUniformTriangle`; pdf `1 / area`).
    #[inline]
    #[must_use]
    pub fn sample_point(&self, u: Vec2) -> Vec3A {
        self.sample_point_bary(u).0
    }

    /// As [`AreaLight::sample_point`], with the barycentrics `(b1, b2)` of the point (the
    /// convention of [`crate::scene::SurfaceInteraction::barycentrics`]).
    #[inline]
    #[must_use]
    pub fn sample_point_bary(&self, u: Vec2) -> (Vec3A, Vec2) {
        let [p0, p1, p2] = self.vertices;
        let [b0, b1, b2] = sample_uniform_triangle(u);
        (p0 * b0 + p1 * b1 + p2 * b2, Vec2::new(b1, b2))
    }
}

/// What a material emits, as [`collect`] needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    /// Emitted radiance (times the texture, if any).
    pub radiance: Vec3,
    /// Emits from both sides.
    pub two_sided: bool,
    /// Varies over the surface (an emissive texture or a cut-out mask).
    pub textured: bool,
}

/// The area lights of `mesh`: one per triangle whose material emits (`emission(material)`),
/// with nonzero finite area and power. `texture_mean(triangle)` is the mean texture
/// luminance factor over a textured emitter (a triangle whose mean is 0 still becomes a light
/// with a small selection weight, so that light sampling can reach every emitting point).
/// Returns the lights and the light index of each triangle (`u32::MAX` for none).
pub fn collect(
    mesh: &Mesh,
    emission: impl Fn(u32) -> Emission,
    texture_mean: impl Fn(usize) -> f32,
) -> (Vec<AreaLight>, Vec<u32>) {
    let mut lights = Vec::new();
    let mut light_of_triangle = vec![u32::MAX; mesh.triangle_count()];
    for (t, &material) in mesh.material_ids.iter().enumerate() {
        let e = emission(material);
        let radiance = e.radiance.max(Vec3::ZERO);
        if !radiance.is_finite() || radiance == Vec3::ZERO {
            continue;
        }
        let vertices = mesh.vertices(t);
        let [p0, p1, p2] = vertices;
        let cross = (p1 - p0).cross(p2 - p0);
        let area = 0.5 * cross.length();
        if !(area > 0.0 && area.is_finite()) {
            continue;
        }
        let power_scale = if e.textured {
            let m = texture_mean(t);
            if m.is_finite() {
                m.max(1e-3)
            } else {
                1.0
            }
        } else {
            1.0
        };
        let light = AreaLight {
            triangle: t as u32,
            vertices,
            normal: cross.normalize(),
            area,
            radiance,
            two_sided: e.two_sided,
            material,
            textured: e.textured,
            power_scale,
        };
        let power = light.power();
        if !(power > 0.0 && power.is_finite()) {
            continue;
        }
        light_of_triangle[t] = lights.len() as u32;
        lights.push(light);
    }
    (lights, light_of_triangle)
}
