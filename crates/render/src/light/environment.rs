//! The environment light: radiance arriving from infinitely far away in every direction, either
//! constant or an equirectangular (latitude-longitude) map importance-sampled by luminance
//! (pbrt-v3 section 12.6 and 14.2.4: a 2-D piecewise-constant distribution over the map,
//! weighted by `sin(theta)` for the equal-area correction).
//!
//! Map convention (documented in docs/scenes.md): `+Y` is up; row 0 of the image is the
//! zenith (`theta = 0`), the last row the nadir; column `u = 0.5` looks towards `-Z`, `u = 0.75`
//! towards `+X`. `rotation` turns the environment about `+Y` (counter-clockwise seen from
//! above, right-handed).

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3, Vec3A};

use super::distribution::Distribution2D;
use crate::image::{luminance, Image};
use crate::warp::{sample_uniform_sphere, uniform_sphere_pdf};

/// An environment light.
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// The map (linear RGB), or `None` for a constant environment.
    map: Option<Image>,
    /// Radiance of a constant environment, or the multiplier of the map.
    scale: Vec3,
    /// `(sin, cos)` of the rotation about `+Y`.
    rotation: (f32, f32),
    /// Sampling distribution over the map (`None` for a constant environment).
    distribution: Option<Distribution2D>,
    /// Mean radiance over the sphere (luminance), for light selection by power.
    mean_luminance: f32,
    /// Texels of the map that were counted as 0.
    dropped: DroppedTexels,
}

/// Texels of an environment map that [`EnvironmentLight::from_map`] counted as 0 (a texel with
/// both kinds of bad channel counts as non-finite).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DroppedTexels {
    /// Texels with a NaN or infinite channel.
    pub non_finite: usize,
    /// Texels with a negative (finite) channel.
    pub negative: usize,
}

impl DroppedTexels {
    /// True if no texel was dropped.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.non_finite == 0 && self.negative == 0
    }
}

/// A direction sampled towards the environment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentSample {
    /// Unit direction towards the environment.
    pub wi: Vec3A,
    /// Radiance arriving from `wi`.
    pub radiance: Vec3,
    /// Solid-angle density of `wi`.
    pub pdf: f32,
}

impl EnvironmentLight {
    /// A constant environment of radiance `radiance` (uniform sphere sampling).
    #[must_use]
    pub fn constant(radiance: Vec3) -> Self {
        let radiance = radiance.max(Vec3::ZERO);
        Self {
            map: None,
            scale: radiance,
            rotation: (0.0, 1.0),
            distribution: None,
            mean_luminance: luminance(radiance.to_array()),
            dropped: DroppedTexels::default(),
        }
    }

    /// An equirectangular map times `strength`, rotated by `rotation_deg` about `+Y`.
    /// Negative and non-finite channels count as 0; [`EnvironmentLight::dropped_texels`] says
    /// how many texels had them.
    #[must_use]
    pub fn from_map(map: Image, strength: f32, rotation_deg: f32) -> Self {
        let (w, h) = (map.width.max(1), map.height.max(1));
        let mut map = map;
        let mut dropped = DroppedTexels::default();
        for p in &mut map.pixels {
            if p.iter().any(|c| !c.is_finite()) {
                dropped.non_finite += 1;
            } else if p.iter().any(|&c| c < 0.0) {
                dropped.negative += 1;
            }
            for c in p.iter_mut() {
                if !(c.is_finite() && *c > 0.0) {
                    *c = 0.0;
                }
            }
        }
        let mut func = Vec::with_capacity(w * h);
        let mut weighted = 0.0f64;
        let mut weights = 0.0f64;
        for y in 0..h {
            let sin_theta = (PI * (y as f32 + 0.5) / h as f32).sin();
            for x in 0..w {
                let lum = map.pixels.get(y * w + x).map_or(0.0, |&p| luminance(p));
                func.push(lum.max(0.0) * sin_theta);
                weighted += f64::from(lum.max(0.0) * sin_theta);
                weights += f64::from(sin_theta);
            }
        }
        let strength = if strength.is_finite() {
            strength.max(0.0)
        } else {
            0.0
        };
        let mean = if weights > 0.0 {
            weighted / weights
        } else {
            0.0
        } as f32;
        let r = rotation_deg.to_radians();
        Self {
            distribution: Some(Distribution2D::new(&func, w)),
            map: Some(map),
            scale: Vec3::splat(strength),
            rotation: r.sin_cos(),
            mean_luminance: mean * strength,
            dropped,
        }
    }

    /// The map's texels that were counted as 0 because a channel was NaN, infinite or negative
    /// (none for a constant environment).
    #[must_use]
    pub fn dropped_texels(&self) -> DroppedTexels {
        self.dropped
    }

    /// Reads an equirectangular map (`.exr`, `.hdr` or `.pfm`) and makes it an environment of
    /// strength `strength` rotated by `rotation_deg` about `+Y`.
    ///
    /// # Errors
    /// What [`crate::image_io::read_image`] reports (the error names the file).
    pub fn from_file(
        path: &std::path::Path,
        strength: f32,
        rotation_deg: f32,
    ) -> Result<Self, crate::image_io::ImageError> {
        let map = crate::image_io::read_image(path)?;
        Ok(Self::from_map(map, strength, rotation_deg))
    }

    /// Rotates the environment by `rotation_deg` about `+Y` (replacing any rotation).
    #[must_use]
    pub fn rotated(mut self, rotation_deg: f32) -> Self {
        self.rotation = rotation_deg.to_radians().sin_cos();
        self
    }

    /// Mean emitted radiance (luminance) over the sphere of directions.
    #[must_use]
    pub fn mean_luminance(&self) -> f32 {
        self.mean_luminance
    }

    /// The largest radiance component over all directions (the map's brightest finite texel
    /// times the multiplier, or the constant's largest channel).
    #[must_use]
    pub fn max_radiance(&self) -> f32 {
        let scale = self.scale.max_element();
        match &self.map {
            None => scale,
            Some(map) => {
                let texel = map
                    .pixels
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|c| c.is_finite())
                    .fold(0.0f32, f32::max);
                texel * scale
            }
        }
    }

    /// True for a constant environment.
    #[must_use]
    pub fn is_constant(&self) -> bool {
        self.map.is_none()
    }

    /// World direction to the environment's local frame (undoing the rotation).
    #[inline]
    fn to_local(&self, w: Vec3A) -> Vec3A {
        let (s, c) = self.rotation;
        Vec3A::new(c * w.x - s * w.z, w.y, s * w.x + c * w.z)
    }

    #[inline]
    fn to_world(&self, w: Vec3A) -> Vec3A {
        let (s, c) = self.rotation;
        Vec3A::new(c * w.x + s * w.z, w.y, -s * w.x + c * w.z)
    }

    /// Map coordinates `(u, v)` in `[0, 1)^2` of a local unit direction.
    #[inline]
    fn uv(w: Vec3A) -> Vec2 {
        let theta = w.y.clamp(-1.0, 1.0).acos();
        let phi = w.x.atan2(-w.z);
        let u = (0.5 + phi / TAU).rem_euclid(1.0);
        Vec2::new(
            u.min(1.0 - f32::EPSILON / 2.0),
            (theta / PI).min(1.0 - f32::EPSILON / 2.0),
        )
    }

    /// Local unit direction of map coordinates `(u, v)`, with `sin(theta)`.
    #[inline]
    fn direction(uv: Vec2) -> (Vec3A, f32) {
        let theta = PI * uv.y;
        let phi = TAU * (uv.x - 0.5);
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        (Vec3A::new(st * sp, ct, -st * cp), st)
    }

    /// Radiance arriving from the unit world direction `wi`.
    #[inline]
    #[must_use]
    pub fn le(&self, wi: Vec3A) -> Vec3 {
        match &self.map {
            None => self.scale,
            Some(map) => {
                let uv = Self::uv(self.to_local(wi));
                let x = ((uv.x * map.width as f32) as usize).min(map.width.saturating_sub(1));
                let y = ((uv.y * map.height as f32) as usize).min(map.height.saturating_sub(1));
                map.pixels
                    .get(y * map.width + x)
                    .map_or(Vec3::ZERO, |&p| Vec3::from(p) * self.scale)
            }
        }
    }

    /// Samples a direction towards the environment from `u` in `[0, 1)^2`: by the map's
    /// luminance (density `p(u, v) / (2 pi^2 sin theta)`), or uniformly for a constant one.
    #[inline]
    #[must_use]
    pub fn sample(&self, u: Vec2) -> Option<EnvironmentSample> {
        let Some(dist) = &self.distribution else {
            let wi = sample_uniform_sphere(u);
            return Some(EnvironmentSample {
                wi,
                radiance: self.scale,
                pdf: uniform_sphere_pdf(),
            });
        };
        let (uv, pdf_uv) = dist.sample(u);
        let (local, sin_theta) = Self::direction(uv);
        if !(sin_theta > 0.0 && pdf_uv > 0.0) {
            return None;
        }
        let wi = self.to_world(local);
        let pdf = pdf_uv / (2.0 * PI * PI * sin_theta);
        if !(pdf.is_finite() && pdf > 0.0) {
            return None;
        }
        Some(EnvironmentSample {
            wi,
            radiance: self.le(wi),
            pdf,
        })
    }

    /// Solid-angle density with which [`EnvironmentLight::sample`] returns `wi`.
    #[inline]
    #[must_use]
    pub fn pdf(&self, wi: Vec3A) -> f32 {
        let Some(dist) = &self.distribution else {
            return uniform_sphere_pdf();
        };
        let local = self.to_local(wi);
        let sin_theta = (1.0 - local.y * local.y).max(0.0).sqrt();
        if sin_theta == 0.0 {
            return 0.0;
        }
        let pdf = dist.pdf(Self::uv(local)) / (2.0 * PI * PI * sin_theta);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient_map() -> Image {
        let mut img = Image::new(16, 8);
        for y in 0..8 {
            for x in 0..16 {
                let v = if (4..6).contains(&x) && y == 2 {
                    50.0
                } else {
                    (x + 1) as f32 * 0.1
                };
                img.set(x, y, [v, v * 0.5, 0.2]);
            }
        }
        img
    }

    #[test]
    fn dropped_texels_are_counted() {
        let mut map = gradient_map();
        map.set(0, 0, [f32::NAN, 1.0, 1.0]);
        map.set(1, 0, [1.0, f32::INFINITY, -1.0]);
        map.set(2, 0, [1.0, -0.5, 1.0]);
        let env = EnvironmentLight::from_map(map, 1.0, 0.0);
        assert_eq!(
            env.dropped_texels(),
            DroppedTexels {
                non_finite: 2,
                negative: 1
            }
        );
        // Negative control: the unmodified map drops nothing.
        let clean = EnvironmentLight::from_map(gradient_map(), 1.0, 0.0);
        assert!(clean.dropped_texels().is_empty());
        assert!(EnvironmentLight::constant(Vec3::ONE)
            .dropped_texels()
            .is_empty());
    }

    #[test]
    fn uv_direction_round_trip_and_convention() {
        for &(u, v) in &[(0.1f32, 0.3f32), (0.5, 0.5), (0.9, 0.95), (0.75, 0.5)] {
            let (w, _) = EnvironmentLight::direction(Vec2::new(u, v));
            let back = EnvironmentLight::uv(w);
            assert!(
                (back - Vec2::new(u, v)).length() < 1e-4,
                "{u} {v} -> {back}"
            );
        }
        let (w, _) = EnvironmentLight::direction(Vec2::new(0.5, 0.5));
        assert!((w - Vec3A::NEG_Z).length() < 1e-5);
        let (w, _) = EnvironmentLight::direction(Vec2::new(0.75, 0.5));
        assert!((w - Vec3A::X).length() < 1e-5);
        let (w, _) = EnvironmentLight::direction(Vec2::new(0.3, 0.0));
        assert!((w - Vec3A::Y).length() < 1e-5);
    }

    #[test]
    fn rotation_turns_the_map() {
        let env = EnvironmentLight::from_map(gradient_map(), 1.0, 0.0);
        let rotated = EnvironmentLight::from_map(gradient_map(), 1.0, 90.0);
        // Rotating by 90 degrees about +Y (counter-clockwise from above) brings what was at
        // -Z to -X.
        let a = env.le(Vec3A::new(0.0, 0.1, -1.0).normalize());
        let b = rotated.le(Vec3A::new(-1.0, 0.1, 0.0).normalize());
        assert_eq!(a, b);
        for i in 1..50 {
            let u = Vec2::new((i as f32 * 0.618) % 1.0, (i as f32 * 0.414) % 1.0);
            let s = rotated.sample(u).unwrap();
            assert!((rotated.pdf(s.wi) - s.pdf).abs() <= 2e-3 * s.pdf);
            assert_eq!(rotated.le(s.wi), s.radiance);
        }
    }

    #[test]
    fn pdf_integrates_to_one_over_the_sphere() {
        let env = EnvironmentLight::from_map(gradient_map(), 2.0, 30.0);
        // Stratified uniform-sphere quadrature of the pdf.
        let n = 400;
        let mut sum = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let w = sample_uniform_sphere(u);
                sum += f64::from(env.pdf(w) / uniform_sphere_pdf());
            }
        }
        let integral = sum / f64::from(n * n);
        assert!((integral - 1.0).abs() < 0.01, "{integral}");
    }

    #[test]
    fn constant_environment() {
        let env = EnvironmentLight::constant(Vec3::ONE);
        assert!(env.is_constant());
        let s = env.sample(Vec2::new(0.3, 0.6)).unwrap();
        assert_eq!(s.radiance, Vec3::ONE);
        assert!((s.pdf - 1.0 / (4.0 * PI)).abs() < 1e-7);
        assert_eq!(env.pdf(Vec3A::Y), s.pdf);
    }
}
