//! No lost samples on a scene with a small, very bright emissive quad over a diffuse floor: for
//! every integrator of the table, with the quad alone and with each kind of the other lights
//! added (point, spot, directional, an environment map with hot texels), a render drops no
//! sample as NaN/inf and its image is finite and lit; and a pixel sample's raster position
//! stays inside its pixel.
//!
//! What the issue saw: BDPT's "non-finite samples dropped" count was not NaN or inf at all, but
//! finite camera-side contributions of pixel samples whose raster position `x + u` had rounded
//! up, in f32, to `x + 1` (`1 - u` at most half an ulp of `x`, e.g. `63 + (1 - 2^-24) ==
//! 64.0`): at the right or bottom edge that is off the image, and the splat buffer of the time
//! refused and counted it. Since camera-side samples go to per-band film tiles the film drops
//! such a sample silently (off the image, or past the band's last row), and PT does the same at
//! its tile edges. The fix, `render::film::pixel_sample_position` used by both, clamps the
//! position into the pixel; `pixel_sample_stays_in_its_pixel` checks it through PT's public
//! pixel sampler (BDPT's band loop is not reachable from outside).
//!
//! Run with `cargo test -p render --release --test non_finite` (5-8 s on 2 cores).

use std::sync::atomic::AtomicBool;

use glam::{UVec2, Vec2, Vec3, Vec3A};
use render::image::Image;
use render::integrator::pt::sample_pixel;
use render::light::{EnvironmentLight, PunctualLight};
use render::sampler::{Sampler, Stream};
use render::scene::{CameraSpec, Material, Mesh, Scene};
use render::session::{render, Budget, NoProgress, RenderSettings};
use render::INTEGRATORS;

/// Image side.
const SIZE: u32 = 32;

/// Radiance of the emissive quad.
const QUAD_RADIANCE: f32 = 1e5;

/// A 4 m x 4 m diffuse floor at y = 0 under a 0.1 m x 0.1 m (0.01 m²) one-sided quad of
/// radiance [`QUAD_RADIANCE`] facing down from 0.5 m, seen from above and in front.
fn small_bright_quad() -> Scene {
    let mut mesh = Mesh::new();
    let f = 2.0;
    mesh.add_quad(
        [
            Vec3A::new(-f, 0.0, f),
            Vec3A::new(f, 0.0, f),
            Vec3A::new(f, 0.0, -f),
            Vec3A::new(-f, 0.0, -f),
        ],
        0,
    );
    let (h, y) = (0.05, 0.5);
    mesh.add_quad(
        [
            Vec3A::new(-h, y, -h),
            Vec3A::new(h, y, -h),
            Vec3A::new(h, y, h),
            Vec3A::new(-h, y, h),
        ],
        1,
    );
    let floor = Material::diffuse("floor", Vec3::splat(0.8), Vec3::ZERO);
    let light = Material::diffuse("light", Vec3::ZERO, Vec3::splat(QUAD_RADIANCE));
    let camera = CameraSpec::look_at(
        Vec3A::new(0.0, 1.5, 3.0),
        Vec3A::new(0.0, 0.2, 0.0),
        Vec3A::Y,
        40.0,
    );
    Scene::new(mesh, vec![floor, light], vec![], camera, SIZE, SIZE)
}

/// A 16 x 8 equirectangular map: radiance 0.5, with a few texels of 1e4 and some black ones
/// (zero density directions).
fn hot_environment_map() -> EnvironmentLight {
    let (w, h) = (16, 8);
    let pixels = (0..w * h)
        .map(|i| {
            let v = if i % 7 == 0 {
                1e4
            } else if i % 3 == 0 {
                0.0
            } else {
                0.5
            };
            [v; 3]
        })
        .collect();
    EnvironmentLight::from_map(Image::from_pixels(w, h, pixels).unwrap(), 1.0, 30.0)
}

/// The quad scene alone and with each kind of the other lights added, by name.
fn scenes() -> Vec<(&'static str, Scene)> {
    let bright = Vec3::splat(1e3);
    let with = |name, add: &dyn Fn(&mut Scene)| {
        let mut scene = small_bright_quad();
        add(&mut scene);
        (name, scene)
    };
    vec![
        with("quad", &|_| {}),
        with("quad + point", &|s| {
            s.add_punctual_lights([PunctualLight::point(Vec3A::new(0.3, 0.05, 0.2), bright)]);
        }),
        with("quad + spot", &|s| {
            s.add_punctual_lights([PunctualLight::spot(
                Vec3A::new(-0.3, 0.8, 0.0),
                Vec3A::new(0.2, -1.0, 0.1),
                bright,
                0.1,
                0.4,
            )]);
        }),
        with("quad + directional", &|s| {
            s.add_punctual_lights([PunctualLight::directional(
                Vec3A::new(0.3, -1.0, -0.2),
                Vec3::splat(10.0),
            )]);
        }),
        with("quad + environment map", &|s| {
            s.set_environment(Some(hot_environment_map()));
        }),
    ]
}

#[test]
fn no_integrator_drops_a_sample_on_the_small_bright_light_scenes() {
    for (name, scene) in scenes() {
        for info in INTEGRATORS {
            let settings = RenderSettings {
                width: SIZE,
                height: SIZE,
                // MCMC: mutations per pixel.
                budget: Budget::SamplesPerPixel(if info.is_mcmc { 256 } else { 512 }),
                threads: 2,
                seed: 1,
                max_depth: 3,
                method: info.kind.settings().with_chains(64, 10_000),
            };
            let result = render(&scene, &settings, &NoProgress, &AtomicBool::new(false));
            let lights = scene.lights();
            if info.kind == render::IntegratorKind::PathMlt
                && (!lights.punctual().is_empty() || lights.environment().is_some())
            {
                // pathmlt supports area lights only: an error naming the feature, no image.
                assert!(
                    matches!(result, Err(render::RenderError::InvalidSetting { .. })),
                    "pathmlt on {name}: {result:?}"
                );
                continue;
            }
            let out = result.unwrap_or_else(|e| panic!("{} on {name}: {e}", info.name));
            assert_eq!(
                out.dropped_nonfinite, 0,
                "{} on {name}: {} of {} samples dropped as non-finite",
                info.name, out.dropped_nonfinite, out.samples
            );
            assert_eq!(
                out.image.count_nonfinite(),
                0,
                "{} on {name}: non-finite pixels",
                info.name
            );
            assert!(
                out.image.mean_luminance() > 0.0,
                "{} on {name}: black image",
                info.name
            );
        }
    }
}

/// Returns the largest f32 below 1 (`1 - 2^-24`, the samplers' largest uniform) for every
/// number: the worst case for `x + u` rounding up to `x + 1`.
struct LargestUniform;

impl Sampler for LargestUniform {
    fn start_stream(&mut self, _stream: Stream) {}
    fn next_1d(&mut self) -> f32 {
        1.0f32.next_down()
    }
    fn next_2d(&mut self) -> Vec2 {
        Vec2::splat(1.0f32.next_down())
    }
}

#[test]
fn pixel_sample_stays_in_its_pixel() {
    let scene = small_bright_quad();
    let camera = scene.camera_spec().build(65_536, 65_536);
    // 0 never rounds up; 1 + (1 - 2^-24) is a tie that rounds to 2.0, and from x = 2 on half
    // an ulp of x exceeds 2^-24. 31, 63: the last column of 32- and 64-pixel images; 15, 127:
    // the last row of a PT tile or of a BDPT band.
    for x in [0u32, 1, 2, 3, 15, 31, 63, 127, 1023, 4095, 65_535] {
        let pixel = UVec2::new(x, x);
        let (p, l) = sample_pixel(&scene, &camera, pixel, &mut LargestUniform, 1);
        assert!(
            p.x.floor() as u32 == x && p.y.floor() as u32 == x,
            "pixel {pixel}: its sample is at {p}, outside the pixel"
        );
        assert!(p.x > x as f32 + 0.99 && p.y > x as f32 + 0.99, "{p}");
        assert!(l.is_finite());
    }
}
