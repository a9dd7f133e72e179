//! The lights of a [`Scene`]: area lights from emissive materials, punctual lights, the
//! environment (the default one for scenes without a light), and light sampling with emissive
//! textures and alpha cut-outs applied.

use glam::{Vec2, Vec3, Vec3A};

use super::{Scene, SurfaceInteraction};
use crate::light::{
    collect_area_lights, Emission, EnvironmentLight, LeSample, LightSample, Lights, PunctualLight,
};

/// The radiance of the default environment that lights scenes without any light.
pub const DEFAULT_ENVIRONMENT_RADIANCE: f32 = 1.0;

/// How a scene's environment light was chosen.
#[derive(Clone, Debug)]
pub(super) enum EnvironmentChoice {
    /// No light in the scene: a uniform environment of [`DEFAULT_ENVIRONMENT_RADIANCE`]
    /// (dropped as soon as the scene gets a light).
    Default,
    /// Set by [`Scene::set_environment`] (`None`: no environment, even without lights).
    Explicit(Option<EnvironmentLight>),
}

impl Scene {
    /// Rebuilds the light list from the emissive materials, the punctual lights and the
    /// environment choice, and updates the note about the default environment.
    pub(super) fn rebuild_lights(&mut self) {
        let (area, light_of_triangle) = collect_area_lights(
            &self.mesh,
            |id| self.emission_of(id),
            |t| self.emission_texture_mean(t),
        );
        // A scene without geometry stays black: there is nothing for a default light to show.
        let own_lights =
            !area.is_empty() || !self.punctual.is_empty() || self.mesh.triangle_count() == 0;
        let environment = match &self.environment {
            EnvironmentChoice::Default if !own_lights => Some(EnvironmentLight::constant(
                Vec3::splat(DEFAULT_ENVIRONMENT_RADIANCE),
            )),
            EnvironmentChoice::Default => None,
            EnvironmentChoice::Explicit(e) => e.clone(),
        };
        let default_in_use = matches!(self.environment, EnvironmentChoice::Default) && !own_lights;
        const NOTE: &str = "the scene has no light: it is lit by a default uniform white environment of radiance 1 (`--env none` renders it without, `--env RGB|FILE` sets another)";
        self.notes.retain(|n| n != NOTE);
        if default_in_use {
            self.notes.push(NOTE.to_owned());
        }
        self.lights = Lights::new(
            area,
            light_of_triangle,
            self.punctual.clone(),
            environment,
            self.mesh.bounds(),
        );
    }

    /// What material `id` emits, for the area lights.
    fn emission_of(&self, id: u32) -> Emission {
        let m = &self.materials[id as usize];
        Emission {
            radiance: m.emission,
            two_sided: m.double_sided,
            textured: m.emissive_texture.is_some() || self.cutout[id as usize],
        }
    }

    /// Mean emissive-texture luminance factor over triangle `t` (for selection by power):
    /// the average over a fixed 6 x 6 stratified pattern of points.
    fn emission_texture_mean(&self, t: usize) -> f32 {
        let n = 6;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let [_, b1, b2] = crate::warp::sample_uniform_triangle(u);
                let f = self.emission_texture(t as u32, Vec2::new(b1, b2));
                sum += crate::image::luminance(f.to_array());
            }
        }
        sum / (n * n) as f32
    }

    /// Adds punctual lights (point, spot, directional) and rebuilds the light list. The
    /// default environment is dropped once the scene has a light of its own.
    pub fn add_punctual_lights(&mut self, lights: impl IntoIterator<Item = PunctualLight>) {
        self.punctual.extend(lights);
        self.rebuild_lights();
    }

    /// Sets the environment light (`None`: no environment; a scene without any other light
    /// then renders black), replacing the default one.
    pub fn set_environment(&mut self, environment: Option<EnvironmentLight>) {
        self.environment = EnvironmentChoice::Explicit(environment);
        self.rebuild_lights();
    }

    /// True if the scene is lit only by the default environment (it has no light of its own
    /// and none was set).
    #[must_use]
    pub fn uses_default_environment(&self) -> bool {
        matches!(self.environment, EnvironmentChoice::Default)
            && self.lights.environment().is_some()
    }

    /// Radiance emitted by the surface at `si` towards `w` (zero for non-emitters and for the
    /// back of one-sided emitters).
    #[inline]
    #[must_use]
    pub fn emitted(&self, si: &SurfaceInteraction, w: Vec3A) -> Vec3 {
        match self.lights.light_of_triangle(si.triangle) {
            Some(l) => self.area_le(l, si.barycentrics, w),
            None => Vec3::ZERO,
        }
    }

    /// Radiance emitted by area light `light` at barycentrics `b` (`(b1, b2)`) towards `w`
    /// (zero towards the back of a one-sided emitter): the material's emission times its
    /// emissive texture, zero where an alpha mask cuts the surface out.
    #[inline]
    #[must_use]
    pub fn area_le(&self, light: u32, b: Vec2, w: Vec3A) -> Vec3 {
        let Some(l) = self.lights.lights().get(light as usize) else {
            return Vec3::ZERO;
        };
        let le = l.le(w);
        if l.textured && le != Vec3::ZERO {
            le * self.emission_texture(l.triangle, b)
        } else {
            le
        }
    }

    /// The factor of the emissive texture of triangle `tri` at barycentrics `b` (1 without a
    /// texture; 0 where an alpha mask cuts the surface out).
    #[inline]
    fn emission_texture(&self, tri: u32, b: Vec2) -> Vec3 {
        if !self.surface_exists(tri, b) {
            return Vec3::ZERO;
        }
        let m = &self.materials[self.mesh.material_ids[tri as usize] as usize];
        match &m.emissive_texture {
            Some(t) => t.sample(&self.textures, self.mesh.tex_coords(tri as usize, b)),
            None => Vec3::ONE,
        }
    }

    /// Samples incident light at `p_ref` ([`Lights::sample_li`]) with the emissive texture
    /// of area lights applied to the radiance.
    #[inline]
    #[must_use]
    pub fn sample_li(&self, p_ref: Vec3A, u_light: f32, u_pos: Vec2) -> Option<LightSample> {
        let mut ls = self.lights.sample_li(p_ref, u_light, u_pos)?;
        if let Some(l) = self.lights.lights().get(ls.light as usize) {
            if l.textured {
                ls.radiance *= self.emission_texture(l.triangle, ls.barycentrics);
            }
        }
        Some(ls)
    }

    /// Samples an emitted ray ([`Lights::sample_le`]) with the emissive texture of area
    /// lights applied to the radiance.
    #[inline]
    #[must_use]
    pub fn sample_le(&self, u_light: f32, u_pos: Vec2, u_dir: Vec2) -> Option<LeSample> {
        let mut le = self.lights.sample_le(u_light, u_pos, u_dir)?;
        if let Some(l) = self.lights.lights().get(le.light as usize) {
            if l.textured {
                le.radiance *= self.emission_texture(l.triangle, le.barycentrics);
                if le.radiance == Vec3::ZERO {
                    return None;
                }
            }
        }
        Some(le)
    }
}
