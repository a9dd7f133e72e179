//! The scene queries BDPT needs, in one place: intersection with resolved BSDF and emitter,
//! visibility between points, the camera, and the lights. A leaf of the `bdpt` module: it
//! knows nothing of vertices.

use glam::{Vec2, Vec3, Vec3A};

use crate::camera::{CameraWiSample, Ray};
use crate::light::{LeSample, LightSample};
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
    pub(crate) barycentrics: Vec2,
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
        barycentrics: si.barycentrics,
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

/// True if the camera does not use its lens numbers (a pinhole).
#[inline]
pub(crate) fn lens_is_inert(scene: SceneRef<'_>) -> bool {
    scene.camera().lens_radius() <= 0.0
}

/// True if the time number changes nothing (the camera does not move; scene geometry is
/// static).
#[inline]
pub(crate) fn time_is_inert(scene: SceneRef<'_>) -> bool {
    !scene.camera().is_moving()
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

/// Samples incident light at `p` for a connection with `s = 1` (next-event estimation).
#[inline]
pub(crate) fn sample_li(
    scene: SceneRef<'_>,
    p: Vec3A,
    u_light: f32,
    u_pos: Vec2,
) -> Option<LightSample> {
    scene.sample_li(p, u_light, u_pos)
}

/// Samples an emitted ray for a light subpath's origin.
#[inline]
pub(crate) fn sample_le(
    scene: SceneRef<'_>,
    u_light: f32,
    u_pos: Vec2,
    u_dir: Vec2,
) -> Option<LeSample> {
    scene.sample_le(u_light, u_pos, u_dir)
}

/// True for lights at infinity (environment, directional).
#[inline]
pub(crate) fn light_is_infinite(scene: SceneRef<'_>, light: u32) -> bool {
    scene.lights().is_infinite(light)
}

/// True for lights delta in position or direction.
#[inline]
pub(crate) fn light_is_delta(scene: SceneRef<'_>, light: u32) -> bool {
    scene.lights().is_delta(light)
}

/// The environment's light index, if the scene has one.
#[inline]
pub(crate) fn environment_index(scene: SceneRef<'_>) -> Option<u32> {
    scene.lights().environment_index()
}

/// Radius of the scene's bounding sphere and the distance at which points stand in for
/// "infinitely far" from `p` (outside the sphere).
#[inline]
pub(crate) fn far_distance(scene: SceneRef<'_>, p: Vec3A) -> f32 {
    let (center, radius) = scene.lights().scene_sphere();
    2.0 * radius + (p - center).length()
}

/// Area density `1 / (pi R^2)` of the disc infinite lights emit from.
#[inline]
pub(crate) fn infinite_disc_pdf(scene: SceneRef<'_>) -> f32 {
    let (_, radius) = scene.lights().scene_sphere();
    1.0 / (std::f32::consts::PI * radius * radius)
}

/// Density, selection included, of choosing an infinite light's emission direction `dir`
/// (the direction light travels): the environment's sampling density of `-dir`; 0 for
/// directional lights (delta in direction).
#[inline]
pub(crate) fn infinite_origin_pdf(scene: SceneRef<'_>, light: u32, dir: Vec3A) -> f32 {
    if scene.lights().environment_index() == Some(light) {
        scene.lights().pdf_environment(-dir)
    } else {
        0.0
    }
}

/// Positional density (selection included) of a light subpath origin on a finite light
/// `light`: `pmf / area` for area lights, `pmf` for point and spot lights.
#[inline]
pub(crate) fn light_pdf_pos(scene: SceneRef<'_>, light: u32) -> f32 {
    scene.lights().pdf_le(light, Vec3A::Z).0
}

/// Solid-angle density of light `light` emitting towards `dir`.
#[inline]
pub(crate) fn light_pdf_dir(scene: SceneRef<'_>, light: u32, dir: Vec3A) -> f32 {
    scene.lights().pdf_le(light, dir).1
}

/// Radiance an area light emits at barycentrics `b` towards `dir`.
#[inline]
pub(crate) fn area_le(scene: SceneRef<'_>, light: u32, b: Vec2, dir: Vec3A) -> Vec3 {
    scene.area_le(light, b, dir)
}

/// Radiance arriving from the environment along `wi` (towards the environment).
#[inline]
pub(crate) fn environment_le(scene: SceneRef<'_>, wi: Vec3A) -> Vec3 {
    scene.lights().environment_le(wi)
}
