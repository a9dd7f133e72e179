//! The lights of a scene and their sampling: emissive triangles (area lights), the punctual
//! lights of `KHR_lights_punctual` (point, spot, directional: delta lights) and an environment
//! light (constant or an importance-sampled equirectangular map).
//!
//! One light is chosen in proportion to its power ([`Lights::select`]), then a point or
//! direction on it. Light indices: area lights first (`0..area_count`, in triangle order),
//! then punctual lights, then the environment. Densities follow pbrt-v3 (section 16.3) so
//! that BDPT's MIS handles every kind:
//! - area lights: uniform by area, cosine-weighted emission;
//! - point and spot lights are delta in position: [`LightSample::delta`] is set, their
//!   "pdf" is the selection probability only, and no strategy can hit them;
//! - the environment and directional lights are *infinite*: positions at infinity are
//!   represented by points `2 R` away (R = radius of the scene's bounding sphere), densities
//!   towards them stay in solid angle, and emitted rays start on a disc of radius `R`
//!   perpendicular to their direction (area density `1 / (pi R^2)`);
//! - directional lights are delta in direction.

mod area;
mod distribution;
mod environment;
mod punctual;

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec3A};

pub use area::{collect as collect_area_lights, AreaLight, Emission};
pub use distribution::{Distribution1D, Distribution2D};
pub use environment::{DroppedTexels, EnvironmentLight, EnvironmentSample};
pub use punctual::{PunctualKind, PunctualLight};

use crate::frame::Frame;
use crate::mesh::Mesh;
use crate::warp::{
    cosine_hemisphere_pdf, sample_concentric_disk, sample_cosine_hemisphere, sample_uniform_cone,
    sample_uniform_sphere, uniform_cone_pdf, uniform_sphere_pdf,
};

/// A light, by kind.
#[derive(Clone, Copy, Debug)]
pub enum LightRef<'a> {
    /// An emissive triangle.
    Area(&'a AreaLight),
    /// A point, spot or directional light.
    Punctual(&'a PunctualLight),
    /// The environment.
    Environment(&'a EnvironmentLight),
}

/// A light sample seen from a reference point (next-event estimation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Index of the light.
    pub light: u32,
    /// The sampled point: on an area light, the position of a point or spot light, or a point
    /// `2 R` away along `wi` for infinite lights (outside the scene, for shadow rays).
    pub p: Vec3A,
    /// The light's front geometric normal (area lights; zero otherwise).
    pub n: Vec3A,
    /// Unit direction from the reference point to `p`.
    pub wi: Vec3A,
    /// Distance from the reference point to `p`.
    pub dist: f32,
    /// Radiance arriving along `-wi` (area and environment lights; zero if the reference
    /// point sees the back of a one-sided emitter), or for delta lights the intensity divided
    /// by `dist^2` (point, spot) or the irradiance (directional) — the integrand's light term
    /// either way. Area lights with an emissive texture: the factor only, see
    /// [`crate::scene::Scene::sample_li`].
    pub radiance: Vec3,
    /// Solid-angle pdf at the reference point, light selection included; for delta lights
    /// the selection probability alone.
    pub pdf: f32,
    /// True for delta lights (point, spot, directional): no MIS with BSDF sampling.
    pub delta: bool,
    /// True for infinite lights (environment, directional).
    pub infinite: bool,
    /// Barycentrics `(b1, b2)` of the point on an area light.
    pub barycentrics: Vec2,
}

/// A sampled emission: a point on a light and a direction leaving it (light tracing, BDPT).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeSample {
    /// Index of the light.
    pub light: u32,
    /// The ray origin: on an area light, at a punctual light, or on the disc of radius `R`
    /// perpendicular to the direction of an infinite light.
    pub p: Vec3A,
    /// The light's geometric normal on the side `dir` leaves from (area lights; zero
    /// otherwise).
    pub n: Vec3A,
    /// Unit emission direction.
    pub dir: Vec3A,
    /// Emitted radiance along `dir` (area, environment), intensity (point, spot) or
    /// irradiance (directional).
    pub radiance: Vec3,
    /// Positional density incl. selection: area measure on an area light or the disc of an
    /// infinite light; the selection probability alone for point and spot lights.
    pub pdf_pos: f32,
    /// Solid-angle density of `dir` (1 for directional lights, delta in direction).
    pub pdf_dir: f32,
    /// `|cos|` between `n` and `dir` for area lights, 1 otherwise: the subpath throughput is
    /// `radiance * cos / (pdf_pos * pdf_dir)`.
    pub cos: f32,
    /// Barycentrics `(b1, b2)` of the point on an area light.
    pub barycentrics: Vec2,
}

/// All lights of a scene with a power-proportional selection distribution.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    area: Vec<AreaLight>,
    punctual: Vec<PunctualLight>,
    environment: Option<EnvironmentLight>,
    /// Selection probability of each light.
    pmf: Vec<f32>,
    /// Cumulative selection probabilities; `cdf[i]` = P(light <= i), last entry 1.
    cdf: Vec<f32>,
    /// Light index of each mesh triangle, `u32::MAX` for non-emitters.
    light_of_triangle: Vec<u32>,
    /// Centre of the scene's bounding sphere.
    center: Vec3A,
    /// Radius of the scene's bounding sphere (at least 1e-3).
    radius: f32,
}

impl Lights {
    /// The untextured emissive triangles of `mesh` as the only lights: `emission(material)`
    /// returns the emitted radiance of a material and whether it emits from both sides.
    #[must_use]
    pub fn build(mesh: &Mesh, emission: impl Fn(u32) -> (Vec3, bool)) -> Self {
        let (area, light_of_triangle) = collect_area_lights(
            mesh,
            |m| {
                let (radiance, two_sided) = emission(m);
                Emission {
                    radiance,
                    two_sided,
                    textured: false,
                }
            },
            |_| 1.0,
        );
        Self::new(area, light_of_triangle, Vec::new(), None, mesh.bounds())
    }

    /// All lights: area lights with the light index of each triangle (from
    /// [`collect_area_lights`]), punctual lights (those with zero or non-finite power are
    /// dropped), an environment, and the scene bounds (for infinite lights).
    #[must_use]
    pub fn new(
        area: Vec<AreaLight>,
        light_of_triangle: Vec<u32>,
        punctual: Vec<PunctualLight>,
        environment: Option<EnvironmentLight>,
        bounds: Option<(Vec3A, Vec3A)>,
    ) -> Self {
        let (center, radius) = match bounds {
            Some((lo, hi)) if lo.is_finite() && hi.is_finite() => {
                ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3))
            }
            _ => (Vec3A::ZERO, 1.0),
        };
        let punctual: Vec<PunctualLight> = punctual
            .into_iter()
            .filter(|l| {
                let p = l.power(radius);
                p > 0.0 && p.is_finite() && l.position.is_finite() && l.direction.is_finite()
            })
            .collect();
        let environment =
            environment.filter(|e| e.mean_luminance() > 0.0 && e.mean_luminance().is_finite());
        let mut powers: Vec<f64> = area.iter().map(|l| f64::from(l.power())).collect();
        powers.extend(punctual.iter().map(|l| f64::from(l.power(radius))));
        if let Some(env) = &environment {
            powers.push(f64::from(PI * PI * radius * radius * env.mean_luminance()));
        }
        let total: f64 = powers.iter().sum();
        let mut pmf = Vec::with_capacity(powers.len());
        let mut cdf = Vec::with_capacity(powers.len());
        let mut acc = 0.0f64;
        for p in powers {
            let p = if total > 0.0 && total.is_finite() {
                p / total
            } else {
                0.0
            };
            acc += p;
            pmf.push(p as f32);
            cdf.push(acc as f32);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Self {
            area,
            punctual,
            environment,
            pmf,
            cdf,
            light_of_triangle,
            center,
            radius,
        }
    }

    /// A bound on the scene's emission, for choosing the resolution of fixed-point splat sums
    /// (`ExactSplatGrid`): the largest radiance component of any area light or the
    /// environment, or the largest intensity component of a punctual light; 1 when the scene
    /// has no light or only non-finite values.
    #[must_use]
    pub fn emission_bound(&self) -> f32 {
        let area = self.area.iter().map(|l| l.radiance.max_element());
        let punctual = self.punctual.iter().map(|l| l.intensity.max_element());
        let env = self.environment.iter().map(EnvironmentLight::max_radiance);
        let bound = area
            .chain(punctual)
            .chain(env)
            .filter(|v| v.is_finite())
            .fold(0.0f32, f32::max);
        if bound > 0.0 {
            bound
        } else {
            1.0
        }
    }

    /// The area lights (their light indices are `0..len`).
    #[must_use]
    pub fn lights(&self) -> &[AreaLight] {
        &self.area
    }

    /// The punctual lights (light indices follow the area lights).
    #[must_use]
    pub fn punctual(&self) -> &[PunctualLight] {
        &self.punctual
    }

    /// The environment light, if any.
    #[must_use]
    pub fn environment(&self) -> Option<&EnvironmentLight> {
        self.environment.as_ref()
    }

    /// The light index of the environment, if any.
    #[inline]
    #[must_use]
    pub fn environment_index(&self) -> Option<u32> {
        self.environment
            .as_ref()
            .map(|_| (self.area.len() + self.punctual.len()) as u32)
    }

    /// Number of lights of every kind.
    #[must_use]
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// True if the scene has no light at all.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Centre and radius of the scene's bounding sphere (the geometry infinite lights use).
    #[must_use]
    pub fn scene_sphere(&self) -> (Vec3A, f32) {
        (self.center, self.radius)
    }

    /// Light `index` by kind.
    #[inline]
    #[must_use]
    pub fn get(&self, index: u32) -> Option<LightRef<'_>> {
        let i = index as usize;
        let na = self.area.len();
        let np = self.punctual.len();
        if i < na {
            Some(LightRef::Area(&self.area[i]))
        } else if i < na + np {
            Some(LightRef::Punctual(&self.punctual[i - na]))
        } else if i == na + np {
            self.environment.as_ref().map(LightRef::Environment)
        } else {
            None
        }
    }

    /// True for lights delta in position or direction (point, spot, directional).
    #[inline]
    #[must_use]
    pub fn is_delta(&self, index: u32) -> bool {
        matches!(self.get(index), Some(LightRef::Punctual(_)))
    }

    /// True for lights at infinity (environment, directional).
    #[inline]
    #[must_use]
    pub fn is_infinite(&self, index: u32) -> bool {
        match self.get(index) {
            Some(LightRef::Environment(_)) => true,
            Some(LightRef::Punctual(p)) => p.is_directional(),
            _ => false,
        }
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
        if self.pmf.is_empty() {
            return None;
        }
        let mut i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.pmf.len() - 1);
        // Never a light of zero probability (a zero-width cdf step at u).
        while self.pmf[i] == 0.0 && i + 1 < self.pmf.len() {
            i += 1;
        }
        (self.pmf[i] > 0.0).then_some((i as u32, self.pmf[i]))
    }

    /// Radiance arriving from the environment along unit direction `wi` (zero without one).
    #[inline]
    #[must_use]
    pub fn environment_le(&self, wi: Vec3A) -> Vec3 {
        self.environment.as_ref().map_or(Vec3::ZERO, |e| e.le(wi))
    }

    /// Solid-angle pdf, selection included, with which [`Lights::sample_li`] samples the
    /// environment in direction `wi` (0 without an environment).
    #[inline]
    #[must_use]
    pub fn pdf_environment(&self, wi: Vec3A) -> f32 {
        match (&self.environment, self.environment_index()) {
            (Some(e), Some(i)) => self.pmf[i as usize] * e.pdf(wi),
            _ => 0.0,
        }
    }

    /// Samples incident light at the reference point `p_ref` (next-event estimation): light
    /// chosen by `u_light`, then a point uniform by area (area lights) or a direction (the
    /// environment) from `u_pos`. Area pdfs are converted to solid angle at `p_ref`:
    /// `pmf / area * dist^2 / |cos θ_light|`.
    #[inline]
    #[must_use]
    pub fn sample_li(&self, p_ref: Vec3A, u_light: f32, u_pos: Vec2) -> Option<LightSample> {
        let (index, pmf) = self.select(u_light)?;
        let far = 2.0 * self.radius + (p_ref - self.center).length();
        match self.get(index)? {
            LightRef::Area(light) => {
                let (p, bary) = light.sample_point_bary(u_pos);
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
                    delta: false,
                    infinite: false,
                    barycentrics: bary,
                })
            }
            LightRef::Punctual(light) => {
                let (wi, dist, radiance) = if light.is_directional() {
                    (-light.direction, far, light.intensity)
                } else {
                    let d = light.position - p_ref;
                    let dist2 = d.length_squared();
                    if !(dist2 > 0.0 && dist2.is_finite()) {
                        return None;
                    }
                    let dist = dist2.sqrt();
                    let wi = d / dist;
                    (wi, dist, light.intensity_towards(-wi) / dist2)
                };
                if radiance == Vec3::ZERO || !radiance.is_finite() {
                    return None;
                }
                Some(LightSample {
                    light: index,
                    p: p_ref + wi * dist,
                    n: Vec3A::ZERO,
                    wi,
                    dist,
                    radiance,
                    pdf: pmf,
                    delta: true,
                    infinite: light.is_directional(),
                    barycentrics: Vec2::ZERO,
                })
            }
            LightRef::Environment(env) => {
                let s = env.sample(u_pos)?;
                let pdf = pmf * s.pdf;
                if !(pdf > 0.0 && pdf.is_finite()) {
                    return None;
                }
                Some(LightSample {
                    light: index,
                    p: p_ref + s.wi * far,
                    n: Vec3A::ZERO,
                    wi: s.wi,
                    dist: far,
                    radiance: s.radiance,
                    pdf,
                    delta: false,
                    infinite: true,
                    barycentrics: Vec2::ZERO,
                })
            }
        }
    }

    /// The solid-angle pdf with which [`Lights::sample_li`] from `p_ref` would have produced
    /// the point `p_light` on area light `light` (0 if it cannot; see
    /// [`Lights::pdf_environment`] for the environment; 0 for delta lights).
    #[inline]
    #[must_use]
    pub fn pdf_li(&self, p_ref: Vec3A, light: u32, p_light: Vec3A) -> f32 {
        match self.get(light) {
            Some(LightRef::Area(l)) => {
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
            Some(LightRef::Environment(_)) => {
                self.pdf_environment((p_light - p_ref).normalize_or_zero())
            }
            _ => 0.0,
        }
    }

    /// A point on the disc of radius `R` perpendicular to `dir`, on the side rays along
    /// `dir` come from: where rays of an infinite light start.
    #[inline]
    fn disc_origin(&self, dir: Vec3A, u: Vec2) -> Vec3A {
        let frame = Frame::from_normal(dir);
        let d = sample_concentric_disk(u) * self.radius;
        self.center + frame.s * d.x + frame.t * d.y - dir * self.radius
    }

    /// Samples an emitted ray: light by `u_light` (power-proportional); area lights: point
    /// uniform by area from `u_pos`, direction cosine-weighted from `u_dir` (two-sided lights
    /// use `u_dir.x < 0.5` to pick the side); point lights: direction uniform on the sphere,
    /// spot lights uniform in the outer cone, both from `u_dir`; the environment: direction
    /// by its sampling from `u_dir`, origin on the disc from `u_pos`; directional lights:
    /// origin on the disc from `u_pos`.
    #[inline]
    #[must_use]
    pub fn sample_le(&self, u_light: f32, u_pos: Vec2, u_dir: Vec2) -> Option<LeSample> {
        let (index, pmf) = self.select(u_light)?;
        let disc_pdf = 1.0 / (PI * self.radius * self.radius);
        let sample = match self.get(index)? {
            LightRef::Area(light) => {
                let (p, bary) = light.sample_point_bary(u_pos);
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
                LeSample {
                    light: index,
                    p,
                    n,
                    dir,
                    radiance: light.radiance,
                    pdf_pos: pmf / light.area,
                    pdf_dir: side_pdf * cosine_hemisphere_pdf(local.z),
                    cos: n.dot(dir).abs(),
                    barycentrics: bary,
                }
            }
            LightRef::Punctual(light) => match light.kind {
                PunctualKind::Directional => LeSample {
                    light: index,
                    p: self.disc_origin(light.direction, u_pos),
                    n: Vec3A::ZERO,
                    dir: light.direction,
                    radiance: light.intensity,
                    pdf_pos: pmf * disc_pdf,
                    pdf_dir: 1.0,
                    cos: 1.0,
                    barycentrics: Vec2::ZERO,
                },
                PunctualKind::Point => {
                    let dir = sample_uniform_sphere(u_dir);
                    LeSample {
                        light: index,
                        p: light.position,
                        n: Vec3A::ZERO,
                        dir,
                        radiance: light.intensity,
                        pdf_pos: pmf,
                        pdf_dir: uniform_sphere_pdf(),
                        cos: 1.0,
                        barycentrics: Vec2::ZERO,
                    }
                }
                PunctualKind::Spot { cos_outer, .. } => {
                    let local = sample_uniform_cone(u_dir, cos_outer);
                    let dir = Frame::from_normal(light.direction)
                        .to_world(local)
                        .normalize();
                    LeSample {
                        light: index,
                        p: light.position,
                        n: Vec3A::ZERO,
                        dir,
                        radiance: light.intensity_towards(dir),
                        pdf_pos: pmf,
                        pdf_dir: uniform_cone_pdf(cos_outer),
                        cos: 1.0,
                        barycentrics: Vec2::ZERO,
                    }
                }
            },
            LightRef::Environment(env) => {
                let s = env.sample(u_dir)?;
                let dir = -s.wi;
                LeSample {
                    light: index,
                    p: self.disc_origin(dir, u_pos),
                    n: Vec3A::ZERO,
                    dir,
                    radiance: s.radiance,
                    pdf_pos: pmf * disc_pdf,
                    pdf_dir: s.pdf,
                    cos: 1.0,
                    barycentrics: Vec2::ZERO,
                }
            }
        };
        let ok = sample.pdf_pos > 0.0
            && sample.pdf_pos.is_finite()
            && sample.pdf_dir > 0.0
            && sample.pdf_dir.is_finite()
            && sample.radiance != Vec3::ZERO
            && sample.radiance.is_finite();
        ok.then_some(sample)
    }

    /// The pdfs `(pdf_pos, pdf_dir)` with which [`Lights::sample_le`] produces a ray leaving
    /// light `light` in direction `dir` (positional density incl. selection; solid angle).
    /// Delta directions (directional lights) report `pdf_dir = 0`: no other strategy can
    /// produce them.
    #[inline]
    #[must_use]
    pub fn pdf_le(&self, light: u32, dir: Vec3A) -> (f32, f32) {
        let pmf = self.selection_pmf(light);
        let disc_pdf = 1.0 / (PI * self.radius * self.radius);
        match self.get(light) {
            None => (0.0, 0.0),
            Some(LightRef::Area(l)) => {
                let pdf_pos = pmf / l.area;
                let cos = l.normal.dot(dir);
                let pdf_dir = if l.two_sided {
                    0.5 * cos.abs() * std::f32::consts::FRAC_1_PI
                } else {
                    cos.max(0.0) * std::f32::consts::FRAC_1_PI
                };
                (pdf_pos, pdf_dir)
            }
            Some(LightRef::Punctual(p)) => match p.kind {
                PunctualKind::Directional => (pmf * disc_pdf, 0.0),
                PunctualKind::Point => (pmf, uniform_sphere_pdf()),
                PunctualKind::Spot { cos_outer, .. } => {
                    let inside = p.direction.dot(dir) >= cos_outer;
                    (
                        pmf,
                        if inside {
                            uniform_cone_pdf(cos_outer)
                        } else {
                            0.0
                        },
                    )
                }
            },
            Some(LightRef::Environment(e)) => (pmf * disc_pdf, e.pdf(-dir)),
        }
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
