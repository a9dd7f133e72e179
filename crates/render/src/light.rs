//! Area lights: every triangle whose material emits is a diffuse area light, chosen in
//! proportion to its power and sampled uniformly by area; pdfs for MIS and for BDPT.

use glam::{Vec2, Vec3, Vec3A};

use crate::frame::Frame;
use crate::image::luminance;
use crate::mesh::Mesh;
use crate::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_triangle};

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
        std::f32::consts::PI * self.area * luminance(self.radiance.to_array()) * sides
    }

    /// A uniformly distributed point on the triangle from `u` in `[0, 1)^2`
    /// (pbrt-v4 `SampleUniformTriangle`; pdf `1 / area`).
    #[inline]
    #[must_use]
    pub fn sample_point(&self, u: Vec2) -> Vec3A {
        let [p0, p1, p2] = self.vertices;
        let [b0, b1, b2] = sample_uniform_triangle(u);
        p0 * b0 + p1 * b1 + p2 * b2
    }
}

/// A light sample seen from a reference point (next-event estimation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Index of the light in [`Lights::lights`].
    pub light: u32,
    /// The sampled point on the light.
    pub p: Vec3A,
    /// The light's front geometric normal.
    pub n: Vec3A,
    /// Unit direction from the reference point to `p`.
    pub wi: Vec3A,
    /// Distance from the reference point to `p`.
    pub dist: f32,
    /// Radiance arriving from `p` along `-wi` (zero if the reference point sees the back of a
    /// one-sided light).
    pub radiance: Vec3,
    /// Solid-angle pdf at the reference point, light selection included.
    pub pdf: f32,
}

/// A sampled emission: a point on a light and a direction leaving it (light tracing, BDPT).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeSample {
    /// Index of the light in [`Lights::lights`].
    pub light: u32,
    /// The point on the light.
    pub p: Vec3A,
    /// The light's geometric normal on the side `dir` leaves from.
    pub n: Vec3A,
    /// Unit emission direction.
    pub dir: Vec3A,
    /// Emitted radiance along `dir`.
    pub radiance: Vec3,
    /// Area-measure pdf of `p`, light selection included.
    pub pdf_pos: f32,
    /// Solid-angle pdf of `dir` given `p` (cosine-weighted, halved for two-sided lights).
    pub pdf_dir: f32,
}

/// All area lights of a scene with a power-proportional selection distribution.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    lights: Vec<AreaLight>,
    /// Selection probability of each light.
    pmf: Vec<f32>,
    /// Cumulative selection probabilities; `cdf[i]` = P(light <= i), last entry 1.
    cdf: Vec<f32>,
    /// Light index of each mesh triangle, `u32::MAX` for non-emitters.
    light_of_triangle: Vec<u32>,
}

impl Lights {
    /// Collects the emissive triangles of `mesh`. `emission(material)` returns the emitted
    /// radiance of a material and whether it emits from both sides. Triangles with zero power
    /// are not lights.
    #[must_use]
    pub fn build(mesh: &Mesh, emission: impl Fn(u32) -> (Vec3, bool)) -> Self {
        let mut lights = Vec::new();
        let mut light_of_triangle = vec![u32::MAX; mesh.triangle_count()];
        for (t, &material) in mesh.material_ids.iter().enumerate() {
            let (radiance, two_sided) = emission(material);
            let radiance = radiance.max(Vec3::ZERO);
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
            let light = AreaLight {
                triangle: t as u32,
                vertices,
                normal: cross.normalize(),
                area,
                radiance,
                two_sided,
            };
            let power = light.power();
            if !(power > 0.0 && power.is_finite()) {
                continue;
            }
            light_of_triangle[t] = lights.len() as u32;
            lights.push(light);
        }
        let total: f64 = lights.iter().map(|l| f64::from(l.power())).sum();
        let mut pmf = Vec::with_capacity(lights.len());
        let mut cdf = Vec::with_capacity(lights.len());
        let mut acc = 0.0f64;
        for l in &lights {
            let p = f64::from(l.power()) / total;
            acc += p;
            pmf.push(p as f32);
            cdf.push(acc as f32);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Self {
            lights,
            pmf,
            cdf,
            light_of_triangle,
        }
    }

    /// The lights.
    #[must_use]
    pub fn lights(&self) -> &[AreaLight] {
        &self.lights
    }

    /// True if the scene has no light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// The light index of mesh triangle `triangle`, if it emits.
    #[inline]
    #[must_use]
    pub fn light_of_triangle(&self, triangle: u32) -> Option<u32> {
        match self.light_of_triangle.get(triangle as usize) {
            Some(&l) if l != u32::MAX => Some(l),
            _ => None,
        }
    }

    /// Selection probability of light `light`.
    #[inline]
    #[must_use]
    pub fn selection_pmf(&self, light: u32) -> f32 {
        self.pmf.get(light as usize).copied().unwrap_or(0.0)
    }

    /// Chooses a light in proportion to power from `u` in `[0, 1)`: `(index, probability)`.
    #[inline]
    #[must_use]
    pub fn select(&self, u: f32) -> Option<(u32, f32)> {
        if self.lights.is_empty() {
            return None;
        }
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.lights.len() - 1);
        Some((i as u32, self.pmf[i]))
    }

    /// Samples a point on a light for the reference point `p_ref` (next-event estimation):
    /// light chosen by `u_light`, point uniform by area from `u_pos`. The pdf is converted to
    /// solid angle at `p_ref`: `pmf / area * dist^2 / |cos θ_light|`.
    #[inline]
    #[must_use]
    pub fn sample_li(&self, p_ref: Vec3A, u_light: f32, u_pos: Vec2) -> Option<LightSample> {
        let (index, pmf) = self.select(u_light)?;
        let light = &self.lights[index as usize];
        let p = light.sample_point(u_pos);
        let d = p - p_ref;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0 && dist2.is_finite()) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_light = light.normal.dot(wi).abs();
        if cos_light <= 0.0 {
            return None;
        }
        let pdf = pmf * dist2 / (light.area * cos_light);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(LightSample {
            light: index,
            p,
            n: light.normal,
            wi,
            dist,
            radiance: light.le(-wi),
            pdf,
        })
    }

    /// The solid-angle pdf with which [`Lights::sample_li`] from `p_ref` would have produced the
    /// point `p_light` on light `light` (0 if it cannot).
    #[inline]
    #[must_use]
    pub fn pdf_li(&self, p_ref: Vec3A, light: u32, p_light: Vec3A) -> f32 {
        let Some(l) = self.lights.get(light as usize) else {
            return 0.0;
        };
        let d = p_light - p_ref;
        let dist2 = d.length_squared();
        let cos_light = l.normal.dot(d).abs() / dist2.sqrt();
        let pdf = self.pmf[light as usize] * dist2 / (l.area * cos_light);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Samples an emitted ray: light by `u_light` (power-proportional), point uniform by area
    /// from `u_pos`, direction cosine-weighted about the normal from `u_dir` (two-sided lights
    /// use `u_dir.x < 0.5` to pick the side).
    #[inline]
    #[must_use]
    pub fn sample_le(&self, u_light: f32, u_pos: Vec2, u_dir: Vec2) -> Option<LeSample> {
        let (index, pmf) = self.select(u_light)?;
        let light = &self.lights[index as usize];
        let p = light.sample_point(u_pos);
        let (mut u, mut n, mut side_pdf) = (u_dir, light.normal, 1.0);
        if light.two_sided {
            side_pdf = 0.5;
            if u.x < 0.5 {
                u.x *= 2.0;
            } else {
                u.x = (u.x - 0.5) * 2.0;
                n = -n;
            }
            u.x = u.x.min(1.0 - f32::EPSILON / 2.0);
        }
        let local = sample_cosine_hemisphere(u);
        let dir = Frame::from_normal(n).to_world(local).normalize();
        let pdf_dir = side_pdf * cosine_hemisphere_pdf(local.z);
        if pdf_dir.is_nan() || pdf_dir <= 0.0 {
            return None;
        }
        Some(LeSample {
            light: index,
            p,
            n,
            dir,
            radiance: light.radiance,
            pdf_pos: pmf / light.area,
            pdf_dir,
        })
    }

    /// The pdfs `(pdf_pos, pdf_dir)` with which [`Lights::sample_le`] produces a ray leaving
    /// light `light` in direction `dir` (area measure incl. selection; solid angle).
    #[inline]
    #[must_use]
    pub fn pdf_le(&self, light: u32, dir: Vec3A) -> (f32, f32) {
        let Some(l) = self.lights.get(light as usize) else {
            return (0.0, 0.0);
        };
        let pdf_pos = self.pmf[light as usize] / l.area;
        let cos = l.normal.dot(dir);
        let pdf_dir = if l.two_sided {
            0.5 * cos.abs() * std::f32::consts::FRAC_1_PI
        } else {
            cos.max(0.0) * std::f32::consts::FRAC_1_PI
        };
        (pdf_pos, pdf_dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::{IndependentSampler, Sampler};

    /// Two lights: a unit-square (two triangles) with radiance 1 and a small one with 10.
    fn two_lights() -> (Mesh, Lights) {
        let mut m = Mesh::new();
        m.add_quad(
            [
                Vec3A::new(0.0, 1.0, 0.0),
                Vec3A::new(1.0, 1.0, 0.0),
                Vec3A::new(1.0, 1.0, 1.0),
                Vec3A::new(0.0, 1.0, 1.0),
            ],
            0,
        );
        m.add_quad(
            [
                Vec3A::new(0.0, 2.0, 0.0),
                Vec3A::new(0.1, 2.0, 0.0),
                Vec3A::new(0.1, 2.0, 0.1),
                Vec3A::new(0.0, 2.0, 0.1),
            ],
            1,
        );
        m.add_quad(
            [
                Vec3A::new(0.0, 0.0, 0.0),
                Vec3A::new(1.0, 0.0, 0.0),
                Vec3A::new(1.0, 0.0, 1.0),
                Vec3A::new(0.0, 0.0, 1.0),
            ],
            2,
        );
        let lights = Lights::build(&m, |mat| match mat {
            0 => (Vec3::ONE, false),
            1 => (Vec3::splat(10.0), true),
            _ => (Vec3::ZERO, false),
        });
        (m, lights)
    }

    #[test]
    fn selection_is_power_proportional() {
        let (_, lights) = two_lights();
        assert_eq!(lights.lights().len(), 4);
        assert_eq!(lights.light_of_triangle(4), None);
        // Powers: big light π * 0.5 * 1 per triangle, small one π * 0.005 * 10 * 2.
        let big = 0.5;
        let small = 0.005 * 10.0 * 2.0;
        let total = 2.0 * big + 2.0 * small;
        assert!((lights.selection_pmf(0) - big / total).abs() < 1e-6);
        assert!((lights.selection_pmf(2) - small / total).abs() < 1e-6);
        let sum: f32 = (0..4).map(|i| lights.selection_pmf(i)).sum();
        assert!((sum - 1.0).abs() < 1e-6);
        assert_eq!(lights.select(0.0).unwrap().0, 0);
        assert_eq!(lights.select(0.999_999).unwrap().0, 3);
    }

    /// Monte Carlo estimate of the solid angle of the lights seen from a point, via sample_li:
    /// E[1 / pdf] over samples that hit the light = total solid angle (visible + back sides).
    #[test]
    fn sample_li_pdf_integrates_solid_angle() {
        let (_, lights) = two_lights();
        let p_ref = Vec3A::new(0.5, -3.0, 0.5);
        let mut s = IndependentSampler::new(1);
        let n = 200_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            s.start_pixel_sample(i, 0);
            let ls = lights.sample_li(p_ref, s.next_1d(), s.next_2d()).unwrap();
            let pdf = lights.pdf_li(p_ref, ls.light, ls.p);
            assert!((pdf - ls.pdf).abs() <= 1e-4 * ls.pdf, "{pdf} vs {}", ls.pdf);
            // Only the first (big) light, counted through its two triangles.
            if lights.lights()[ls.light as usize].triangle < 2 {
                sum += 1.0 / f64::from(ls.pdf);
            }
        }
        let estimate = sum / n as f64;
        // Solid angle of a unit square at distance 4 seen head-on, exact formula
        // 4 asin(a b / sqrt((a^2 + 4 d^2)(b^2 + 4 d^2))) with a = b = 1, d = 4.
        let exact = 4.0 * (1.0f64 / (1.0f64 + 64.0)).asin();
        assert!(
            (estimate - exact).abs() < 0.01 * exact,
            "{estimate} vs {exact}"
        );
    }

    #[test]
    fn sample_le_directions_and_pdfs() {
        let (_, lights) = two_lights();
        let mut s = IndependentSampler::new(2);
        let mut back = 0;
        let n = 20_000;
        for i in 0..n {
            s.start_pixel_sample(i, 0);
            let le = lights
                .sample_le(s.next_1d(), s.next_2d(), s.next_2d())
                .unwrap();
            let l = &lights.lights()[le.light as usize];
            assert!(le.dir.dot(le.n) >= 0.0);
            let (pp, pd) = lights.pdf_le(le.light, le.dir);
            assert!((pp - le.pdf_pos).abs() <= 1e-5 * pp);
            assert!((pd - le.pdf_dir).abs() <= 1e-4, "{pd} vs {}", le.pdf_dir);
            if l.two_sided && le.n.dot(l.normal) < 0.0 {
                back += 1;
            }
            if !l.two_sided {
                assert!(le.dir.dot(l.normal) >= 0.0);
            }
        }
        assert!(back > 0);
    }

    #[test]
    fn no_lights() {
        let lights = Lights::build(&Mesh::new(), |_| (Vec3::ONE, false));
        assert!(lights.is_empty());
        assert!(lights
            .sample_li(Vec3A::ZERO, 0.5, Vec2::splat(0.5))
            .is_none());
        assert!(lights.sample_le(0.5, Vec2::ZERO, Vec2::ZERO).is_none());
        assert_eq!(lights.pdf_li(Vec3A::ZERO, 0, Vec3A::X), 0.0);
    }
}
