//! The scene queries BDPT needs, in one place: intersection with resolved BSDF and emitter,
//! visibility between points, the camera, and the lights. A leaf of the `bdpt` module: it
//! knows nothing of vertices.

use glam::{Vec2, Vec3, Vec3A};

use crate::camera::{CameraWiSample, Ray};
use crate::material::Bsdf;
use crate::scene::Scene;

/// The scene BDPT traces.
pub type SceneRef<'a> = &'a Scene;

/// A surface hit with everything a vertex needs.
pub(crate) struct Hit {
    pub(crate) p: Vec3A,
    pub(crate) p_error: Vec3A,
    pub(crate) ng: Vec3A,
    pub(crate) ns: Vec3A,
    pub(crate) bsdf: Bsdf,
    pub(crate) light: Option<u32>,
}

#[inline]
pub(crate) fn intersect(scene: SceneRef<'_>, ray: &Ray) -> Option<Hit> {
    let si = scene.intersect(ray)?;
    Some(Hit {
        p: si.p,
        p_error: si.p_error,
        ng: si.ng,
        ns: si.ns,
        bsdf: scene.bsdf(&si),
        light: scene.lights().light_of_triangle(si.triangle),
    })
}

/// Mutual visibility of the points `a` and `b`; a nonzero normal marks a surface point, whose
/// end of the shadow ray is offset off the surface.
#[inline]
pub(crate) fn visible(scene: SceneRef<'_>, a: Vec3A, na: Vec3A, b: Vec3A, nb: Vec3A) -> bool {
    scene.unoccluded_between(a, na, b, nb)
}

#[inline]
pub(crate) fn generate_ray(scene: SceneRef<'_>, p_raster: Vec2, u_lens: Vec2, u_time: f32) -> Ray {
    scene.camera().generate_ray(p_raster, u_lens, u_time)
}

/// Solid-angle density of the camera emitting `ray` (0 outside the image).
#[inline]
pub(crate) fn camera_pdf_dir(scene: SceneRef<'_>, ray: &Ray) -> f32 {
    scene.camera().pdf_we(ray).1
}

#[inline]
pub(crate) fn camera_forward(scene: SceneRef<'_>, time: f32) -> Vec3A {
    scene.camera().pose_at(time).forward
}

#[inline]
pub(crate) fn camera_sample_wi(
    scene: SceneRef<'_>,
    reference: Vec3A,
    u: Vec2,
    time: f32,
) -> Option<CameraWiSample> {
    scene.camera().sample_wi(reference, u, time)
}

/// A point sampled on an emitter (light choice by power, uniform by area).
pub(crate) struct LightPoint {
    pub(crate) p: Vec3A,
    /// The light's front normal.
    pub(crate) n: Vec3A,
    pub(crate) light: u32,
    /// Area density including the light selection probability.
    pub(crate) pdf_area: f32,
}

#[inline]
pub(crate) fn sample_light_point(
    scene: SceneRef<'_>,
    u_light: f32,
    u_pos: Vec2,
) -> Option<LightPoint> {
    let lights = scene.lights();
    let (index, pmf) = lights.select(u_light)?;
    let light = &lights.lights()[index as usize];
    Some(LightPoint {
        p: light.sample_point(u_pos),
        n: light.normal,
        light: index,
        pdf_area: pmf / light.area,
    })
}

/// Area density of a light-subpath origin on light `light` (selection included).
#[inline]
pub(crate) fn light_pdf_area(scene: SceneRef<'_>, light: u32) -> f32 {
    scene.lights().pdf_le(light, Vec3A::Z).0
}

/// Solid-angle density of light `light` emitting towards `dir`.
#[inline]
pub(crate) fn light_pdf_dir(scene: SceneRef<'_>, light: u32, dir: Vec3A) -> f32 {
    scene.lights().pdf_le(light, dir).1
}

/// Radiance light `light` emits towards `dir`.
#[inline]
pub(crate) fn light_le(scene: SceneRef<'_>, light: u32, dir: Vec3A) -> Vec3 {
    scene
        .lights()
        .lights()
        .get(light as usize)
        .map_or(Vec3::ZERO, |l| l.le(dir))
}
