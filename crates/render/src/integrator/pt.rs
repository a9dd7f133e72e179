//! Unidirectional path tracing with next-event estimation and MIS (power heuristic) between
//! light sampling and BSDF sampling (area and environment lights; delta lights — point, spot,
//! directional — by light sampling only), Russian roulette and a maximum depth (pbrt-v4's
//! `PathIntegrator`, Pharr et al. 2023, section 13.4).
//!
//! Random numbers: after the camera numbers (pixel position 2, lens 2, time 1 — see
//! [`sample_pixel`]), every bounce draws exactly six numbers from [`Stream::Camera`] in a
//! fixed order (light choice 1, light position 2, BSDF lobe 1, BSDF direction 2) plus one for
//! Russian roulette, whether or not they are used, so a primary-sample-space chain sees a
//! stable mapping from coordinates to decisions.

use glam::{UVec2, Vec2, Vec3};

use super::power_heuristic;
use crate::camera::{Camera, Ray};
use crate::film::pixel_sample_position;
use crate::frame::{shading_consistent, Frame};
use crate::material::TransportMode;
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// Russian roulette starts after this many bounces (the default of [`li_with`]'s `roulette`).
pub const ROULETTE_DEPTH: u32 = 3;

/// Radiance arriving along `ray` (towards its origin), estimated by a path of at most
/// `max_depth` bounces: `max_depth = 0` only sees emitters directly, `1` adds direct lighting.
///
/// Emission found by BSDF sampling is MIS-weighted against next-event estimation (power
/// heuristic); after a specular bounce (or for camera rays) it counts fully. NEE is skipped at
/// specular surfaces. The result may be non-finite only if the scene data is; callers drop
/// such samples.
#[inline]
pub fn li<S: Sampler + ?Sized>(scene: &Scene, ray: Ray, sampler: &mut S, max_depth: u32) -> Vec3 {
    li_with(scene, ray, sampler, max_depth, Some(ROULETTE_DEPTH))
}

/// [`li`] with Russian roulette from bounce `roulette` on: `Some(n)` may end the path after
/// every bounce beyond the `n`-th, continuing with probability `min(1, max component of
/// beta * eta_scale)` (pbrt-v4, section 13.4.2: the throughput with the radiance scaling of
/// refraction undone) and dividing the throughput by it; `None` turns roulette off (the path
/// ends only at `max_depth`, on a miss or an absorbing bounce). The roulette number is drawn
/// either way, so the number layout does not depend on the setting.
#[inline]
pub fn li_with<S: Sampler + ?Sized>(
    scene: &Scene,
    ray: Ray,
    sampler: &mut S,
    max_depth: u32,
    roulette: Option<u32>,
) -> Vec3 {
    li_depths(scene, ray, sampler, 0, max_depth, roulette)
}

/// [`li_with`] counting only paths of `min_depth..=max_depth` bounces (emitters seen directly
/// have depth 0, direct lighting depth 1): the random walk and the numbers it reads are those
/// of [`li_with`], shorter paths' contributions are left out (for a separate pass that renders
/// them). An emitter hit and the next-event estimate it is weighted against have the same
/// depth, so every depth keeps its MIS pair whole.
#[inline]
pub fn li_depths<S: Sampler + ?Sized>(
    scene: &Scene,
    ray: Ray,
    sampler: &mut S,
    min_depth: u32,
    max_depth: u32,
    roulette: Option<u32>,
) -> Vec3 {
    let lights = scene.lights();
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let mut ray = ray;
    let mut specular_bounce = false;
    let mut prev_bsdf_pdf = 0.0f32;
    let mut prev_p = ray.origin;
    let mut eta_scale = 1.0f32;
    let mut depth = 0u32;
    sampler.start_stream(Stream::Camera);
    loop {
        let Some(si) = scene.intersect(&ray) else {
            // The ray leaves the scene: the environment, MIS-weighted against its sampling
            // by next-event estimation.
            let le = lights.environment_le(ray.dir);
            if le != Vec3::ZERO && depth >= min_depth {
                if depth == 0 || specular_bounce {
                    l += beta * le;
                } else {
                    let light_pdf = lights.pdf_environment(ray.dir);
                    l += beta * le * power_heuristic(prev_bsdf_pdf, light_pdf);
                }
            }
            break;
        };
        let le = scene.emitted(&si, si.wo);
        if le != Vec3::ZERO && depth >= min_depth {
            if depth == 0 || specular_bounce {
                l += beta * le;
            } else if let Some(light) = lights.light_of_triangle(si.triangle) {
                let light_pdf = lights.pdf_li(prev_p, light, si.p);
                l += beta * le * power_heuristic(prev_bsdf_pdf, light_pdf);
            }
        }
        if depth >= max_depth {
            break;
        }
        depth += 1;
        let u_light = sampler.next_1d();
        let u_light_pos = sampler.next_2d();
        let u_lobe = sampler.next_1d();
        let u_bsdf = sampler.next_2d();
        let u_roulette = sampler.next_1d();

        let bsdf = scene.bsdf(&si);
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(si.wo);
        if wo.z == 0.0 {
            break;
        }
        if !bsdf.is_specular() && depth >= min_depth {
            if let Some(ls) = scene.sample_li(si.p, u_light, u_light_pos) {
                if ls.radiance != Vec3::ZERO {
                    let wi = frame.to_local(ls.wi);
                    let f = if shading_consistent(si.wo, ls.wi, si.ng, si.ns) {
                        bsdf.eval(wo, wi, TransportMode::Radiance) * wi.z.abs()
                    } else {
                        Vec3::ZERO
                    };
                    let visible = || {
                        if ls.infinite {
                            scene.unoccluded_towards(&si, ls.wi)
                        } else {
                            scene.unoccluded(&si, ls.p)
                        }
                    };
                    if f != Vec3::ZERO && visible() {
                        // Delta lights cannot be hit by BSDF sampling: no MIS.
                        let w = if ls.delta {
                            1.0
                        } else {
                            power_heuristic(ls.pdf, bsdf.pdf(wo, wi, TransportMode::Radiance))
                        };
                        l += beta * f * ls.radiance * (w / ls.pdf);
                    }
                }
            }
        }
        let Some(bs) = bsdf.sample(wo, u_lobe, u_bsdf, TransportMode::Radiance) else {
            break;
        };
        if bs.pdf.is_nan() || bs.pdf <= 0.0 {
            break;
        }
        beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
        specular_bounce = bs.is_specular;
        prev_bsdf_pdf = bs.pdf;
        eta_scale *= bs.eta * bs.eta;
        prev_p = si.p;
        let Some(dir) = frame.to_world(bs.wi).try_normalize() else {
            break;
        };
        if !shading_consistent(si.wo, dir, si.ng, si.ns) {
            break;
        }
        ray = si.spawn_ray(dir, ray.time);
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            break;
        }
        if roulette.is_some_and(|start| depth > start) {
            let q = (1.0 - (beta * eta_scale).max_element()).max(0.0);
            if u_roulette < q {
                break;
            }
            beta /= 1.0 - q;
        }
    }
    l
}

/// One path-traced sample of pixel `pixel`: draws the pixel position (2 numbers), lens (2) and
/// time (1) from [`Stream::Camera`], traces the camera ray and returns the raster position and
/// the radiance estimate.
#[inline]
pub fn sample_pixel<S: Sampler + ?Sized>(
    scene: &Scene,
    camera: &Camera,
    pixel: UVec2,
    sampler: &mut S,
    max_depth: u32,
) -> (Vec2, Vec3) {
    sample_pixel_with(
        scene,
        camera,
        pixel,
        sampler,
        max_depth,
        Some(ROULETTE_DEPTH),
    )
}

/// [`sample_pixel`] with the Russian roulette setting of [`li_with`].
#[inline]
pub fn sample_pixel_with<S: Sampler + ?Sized>(
    scene: &Scene,
    camera: &Camera,
    pixel: UVec2,
    sampler: &mut S,
    max_depth: u32,
    roulette: Option<u32>,
) -> (Vec2, Vec3) {
    sampler.start_stream(Stream::Camera);
    let p_raster = pixel_sample_position(pixel, sampler.next_2d());
    let u_lens = sampler.next_2d();
    let u_time = sampler.next_1d();
    let ray = camera.generate_ray(p_raster, u_lens, u_time);
    (p_raster, li_with(scene, ray, sampler, max_depth, roulette))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::IndependentSampler;

    #[test]
    fn cornell_pixels_are_finite_and_lit() {
        let scene = Scene::cornell_box(16, 16);
        let mut s = IndependentSampler::new(1);
        let mut sum = Vec3::ZERO;
        for i in 0..256u32 {
            s.start_pixel_sample(u64::from(i), 0);
            let (p, l) = sample_pixel(
                &scene,
                scene.camera(),
                UVec2::new(i % 16, i / 16),
                &mut s,
                5,
            );
            assert!(l.is_finite() && l.min_element() >= 0.0, "{l}");
            assert!(p.x >= 0.0 && p.x < 16.0);
            sum += l;
        }
        assert!(sum.max_element() > 0.0);
    }

    #[test]
    fn depth_zero_sees_only_emitters() {
        let scene = Scene::cornell_box(16, 16);
        let mut s = IndependentSampler::new(2);
        // The centre of the top row sees the ceiling; the light's radiance or 0 only.
        for i in 0..64 {
            s.start_pixel_sample(i, 0);
            let (_, l) = sample_pixel(&scene, scene.camera(), UVec2::new(8, 8), &mut s, 0);
            assert!(l == Vec3::ZERO || l == Vec3::new(17.0, 12.0, 4.0));
        }
    }
}
