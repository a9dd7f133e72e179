//! Punctual (delta) lights of `KHR_lights_punctual`: point, spot and directional lights.
//!
//! Units: the extension gives point and spot intensities in candela (lm/sr) and directional
//! illuminance in lux (lm/m²); emissive materials (`KHR_materials_emissive_strength`) are in
//! nits (cd/m²). We render photometric quantities as the renderer's radiometric ones with the
//! same factor for all three (1 nit ↔ radiance 1, 1 cd ↔ intensity 1, 1 lux ↔ irradiance 1),
//! so the brightness of punctual lights relative to emissive surfaces is as the file says; no
//! 683 lm/W conversion is applied (it would scale every light alike). A point light of
//! intensity `I` gives irradiance `I cos(theta) / d^2`; a directional light of illuminance `E`
//! gives `E cos(theta)`. The extension's `range` is ignored (physically, intensity falls off
//! with the inverse square law only), with a warning at load time.

use std::f32::consts::PI;

use glam::{Vec3, Vec3A};

use crate::image::luminance;

/// The kind and shape of a punctual light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PunctualKind {
    /// Emits equally in all directions from `position`.
    Point,
    /// Emits from `position` into a cone around `direction`, with the extension's smooth
    /// falloff between the inner and outer cone angles (stored as cosines).
    Spot {
        /// `cos(innerConeAngle)`.
        cos_inner: f32,
        /// `cos(outerConeAngle)`.
        cos_outer: f32,
    },
    /// Parallel light travelling along `direction` from infinitely far away.
    Directional,
}

/// One punctual light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PunctualLight {
    /// What it is.
    pub kind: PunctualKind,
    /// World position (point and spot).
    pub position: Vec3A,
    /// Unit world direction the light travels (spot axis; directional light direction).
    pub direction: Vec3A,
    /// Colour times intensity: radiant intensity for point and spot lights, irradiance on a
    /// surface facing the light for directional lights.
    pub intensity: Vec3,
}

impl PunctualLight {
    /// A point light.
    #[must_use]
    pub fn point(position: Vec3A, intensity: Vec3) -> Self {
        Self {
            kind: PunctualKind::Point,
            position,
            direction: -Vec3A::Y,
            intensity,
        }
    }

    /// A spot light with cone half-angles in radians (`0 <= inner < outer <= pi / 2`).
    #[must_use]
    pub fn spot(
        position: Vec3A,
        direction: Vec3A,
        intensity: Vec3,
        inner: f32,
        outer: f32,
    ) -> Self {
        let outer = outer.clamp(1e-4, PI / 2.0);
        let inner = inner.clamp(0.0, outer);
        Self {
            kind: PunctualKind::Spot {
                cos_inner: inner.cos(),
                cos_outer: outer.cos(),
            },
            position,
            direction: direction.normalize_or(-Vec3A::Z),
            intensity,
        }
    }

    /// A directional light travelling along `direction`.
    #[must_use]
    pub fn directional(direction: Vec3A, intensity: Vec3) -> Self {
        Self {
            kind: PunctualKind::Directional,
            position: Vec3A::ZERO,
            direction: direction.normalize_or(-Vec3A::Z),
            intensity,
        }
    }

    /// True for a directional light (delta in direction, at infinity).
    #[must_use]
    pub fn is_directional(&self) -> bool {
        self.kind == PunctualKind::Directional
    }

    /// The `KHR_lights_punctual` spot falloff for a unit emission direction `w`: 1 inside the
    /// inner cone, 0 outside the outer one, `t^2` in between with
    /// `t = (cos - cos_outer) / (cos_inner - cos_outer)` (the extension's recommended
    /// implementation; its `max(0.001, ...)` guards an empty penumbra). 1 for point lights.
    #[inline]
    #[must_use]
    pub fn falloff(&self, w: Vec3A) -> f32 {
        match self.kind {
            PunctualKind::Spot {
                cos_inner,
                cos_outer,
            } => {
                let cd = self.direction.dot(w);
                let scale = 1.0 / (cos_inner - cos_outer).max(0.001);
                let t = ((cd - cos_outer) * scale).clamp(0.0, 1.0);
                t * t
            }
            _ => 1.0,
        }
    }

    /// Radiant intensity leaving a point or spot light in unit direction `w`.
    #[inline]
    #[must_use]
    pub fn intensity_towards(&self, w: Vec3A) -> Vec3 {
        self.intensity * self.falloff(w)
    }

    /// Emitted power (luminance) for light selection; directional lights need the radius
    /// `scene_radius` of the scene's bounding sphere (power through its disc).
    #[must_use]
    pub fn power(&self, scene_radius: f32) -> f32 {
        let i = luminance(self.intensity.to_array()).max(0.0);
        match self.kind {
            PunctualKind::Point => 4.0 * PI * i,
            // Integral of the falloff over the sphere, approximated as pbrt-v3 does by the
            // cone halfway between inner and outer.
            PunctualKind::Spot {
                cos_inner,
                cos_outer,
            } => 2.0 * PI * i * (1.0 - 0.5 * (cos_inner + cos_outer)),
            PunctualKind::Directional => PI * scene_radius * scene_radius * i,
        }
    }

    /// The cosine of the cone that contains all emission (spot: outer cone; point: -1).
    #[must_use]
    pub fn cos_cone(&self) -> f32 {
        match self.kind {
            PunctualKind::Spot { cos_outer, .. } => cos_outer,
            _ => -1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falloff_follows_the_extension() {
        let s = PunctualLight::spot(Vec3A::ZERO, -Vec3A::Y, Vec3::ONE, 0.2, 0.4);
        assert_eq!(s.falloff(-Vec3A::Y), 1.0);
        let at = |a: f32| Vec3A::new(a.sin(), -a.cos(), 0.0);
        assert_eq!(s.falloff(at(0.19)), 1.0);
        assert_eq!(s.falloff(at(0.41)), 0.0);
        let mid = s.falloff(at(0.3));
        let t = (0.3f32.cos() - 0.4f32.cos()) / (0.2f32.cos() - 0.4f32.cos());
        assert!((mid - t * t).abs() < 1e-4);
        assert_eq!(
            PunctualLight::point(Vec3A::ZERO, Vec3::ONE).falloff(Vec3A::X),
            1.0
        );
    }
}
