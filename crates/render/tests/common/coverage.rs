//! Small scenes written to cover the light-transport paths a renderer can miss (Heckbert's
//! regular expressions: `L` light, `S` specular, `D` diffuse, `E` eye). Each isolates one class
//! of paths that a sampler reaching the scene from one side only finds rarely or never:
//!
//! - [`caustic`]: `L S+ D E`, a small light shining through a glass ball onto a diffuse floor
//!   (and nowhere else);
//! - [`two_mirror_room`]: `L S S D E`, a floor lit only via two mirrors (the light faces away
//!   from it);
//! - [`mirror_light`]: `E S L`, a light behind the camera seen only in a mirror;
//! - [`small_light`]: a closed diffuse box lit by a tiny, very bright ceiling light;
//! - [`sky_room`]: a closed room lit by a constant environment through a ceiling window.
//!
//! Every scene is a few dozen triangles; the glass ball is the only curved object.

use glam::{Vec3, Vec3A};

use render::light::EnvironmentLight;
use render::scene::{CameraSpec, Material, Mesh, Scene};

/// One coverage scene: its name (for messages), the path class it isolates and a builder.
#[derive(Clone, Copy, Debug)]
pub struct CoverageScene {
    /// Short name used in failure messages.
    pub name: &'static str,
    /// The path class the scene isolates (Heckbert's notation).
    pub paths: &'static str,
    /// Builds the scene at `size x size` pixels.
    pub build: fn(u32) -> Scene,
}

/// Every coverage scene.
pub const SCENES: [CoverageScene; 5] = [
    CoverageScene {
        name: "caustic",
        paths: "L S+ D E",
        build: caustic,
    },
    CoverageScene {
        name: "two-mirror-room",
        paths: "L S S D E",
        build: two_mirror_room,
    },
    CoverageScene {
        name: "mirror-light",
        paths: "E S L",
        build: mirror_light,
    },
    CoverageScene {
        name: "small-light",
        paths: "L D+ E (tiny light)",
        build: small_light,
    },
    CoverageScene {
        name: "sky-room",
        paths: "environment through a window",
        build: sky_room,
    },
];

fn v(x: f32, y: f32, z: f32) -> Vec3A {
    Vec3A::new(x, y, z)
}

/// Adds the parallelogram centred at `c` with half-edges `u` and `v`; its front (the side
/// that emits, for a one-sided light) faces `u x v`.
fn quad(mesh: &mut Mesh, c: Vec3A, u: Vec3A, w: Vec3A, material: u32) {
    mesh.add_quad([c - u - w, c + u - w, c + u + w, c - u + w], material);
}

/// An axis-aligned closed room `[-h, h] x [0, 2h] x [-h, h]` with every wall facing inwards;
/// `ceiling_hole` leaves a square opening of that half-width in the middle of the ceiling.
fn room(mesh: &mut Mesh, h: f32, walls: [u32; 3], ceiling_hole: Option<f32>) {
    let [white, red, green] = walls;
    // Floor (faces +y), back wall (+z), front wall (-z), left (+x, red), right (-x, green).
    quad(
        mesh,
        v(0.0, 0.0, 0.0),
        v(h, 0.0, 0.0),
        v(0.0, 0.0, -h),
        white,
    );
    quad(mesh, v(0.0, h, -h), v(h, 0.0, 0.0), v(0.0, h, 0.0), white);
    quad(mesh, v(0.0, h, h), v(0.0, h, 0.0), v(h, 0.0, 0.0), white);
    quad(mesh, v(-h, h, 0.0), v(0.0, h, 0.0), v(0.0, 0.0, h), red);
    quad(mesh, v(h, h, 0.0), v(0.0, 0.0, h), v(0.0, h, 0.0), green);
    // Ceiling (faces -y), around the hole if there is one.
    let y = 2.0 * h;
    match ceiling_hole {
        None => quad(mesh, v(0.0, y, 0.0), v(h, 0.0, 0.0), v(0.0, 0.0, h), white),
        Some(a) => holed_square(mesh, y, h, a, white),
    }
}

/// The horizontal square `[-h, h]^2` at height `y`, facing -y, with a square hole of
/// half-width `a` in its middle.
fn holed_square(mesh: &mut Mesh, y: f32, h: f32, a: f32, material: u32) {
    let band = (h - a) / 2.0;
    // Strips along x at z < -a and z > a, then the two pieces beside the hole.
    for z in [-(a + band), a + band] {
        quad(
            mesh,
            v(0.0, y, z),
            v(h, 0.0, 0.0),
            v(0.0, 0.0, band),
            material,
        );
    }
    for x in [-(a + band), a + band] {
        quad(
            mesh,
            v(x, y, 0.0),
            v(band, 0.0, 0.0),
            v(0.0, 0.0, a),
            material,
        );
    }
}

fn glass() -> Material {
    Material {
        name: "glass".to_owned(),
        base_color: Vec3::ONE,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.5,
        ..Material::default()
    }
}

fn mirror() -> Material {
    Material {
        name: "mirror".to_owned(),
        base_color: Vec3::splat(0.95),
        metallic: 1.0,
        roughness: 0.0,
        ..Material::default()
    }
}

fn light(radiance: f32) -> Material {
    Material::diffuse("light", Vec3::ZERO, Vec3::splat(radiance))
}

/// `L S+ D E`: a 0.2 x 0.2 light (radiance 60) above a black plate whose 0.3 x 0.3 hole lets
/// its light fall only on a glass ball of radius 0.3, whose focus lies near the diffuse floor:
/// the floor is lit only by the caustic. The camera looks at the caustic under the ball,
/// below the ball's silhouette; nothing else is lit (rays leaving the floor see black).
pub fn caustic(size: u32) -> Scene {
    let mut mesh = Mesh::new();
    quad(
        &mut mesh,
        v(0.0, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(0.0, 0.0, -1.0),
        0,
    );
    mesh.add_sphere(v(0.0, 0.6, 0.0), 0.3, 16, 32, 1, false);
    quad(
        &mut mesh,
        v(0.0, 1.8, 0.0),
        v(0.1, 0.0, 0.0),
        v(0.0, 0.0, 0.1),
        2,
    );
    holed_square(&mut mesh, 1.2, 1.0, 0.15, 3);
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.7), Vec3::ZERO),
        glass(),
        light(60.0),
        Material::diffuse("plate", Vec3::ZERO, Vec3::ZERO),
    ];
    let camera = CameraSpec::look_at(v(0.0, 0.5, 2.0), v(0.0, 0.15, 0.0), Vec3A::Y, 40.0);
    Scene::new(mesh, materials, vec![], camera, size, size)
}

/// `L S S D E`: a one-sided 0.2 x 0.2 light (radiance 50) facing up, a mirror above it turning
/// its light towards +x, a second mirror turning it down onto a diffuse floor. No direct path
/// joins the light and the floor.
pub fn two_mirror_room(size: u32) -> Scene {
    let mut mesh = Mesh::new();
    let s = 0.4 / std::f32::consts::SQRT_2;
    quad(
        &mut mesh,
        v(1.5, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(0.0, 0.0, -1.0),
        0,
    );
    quad(
        &mut mesh,
        v(0.0, 2.0, 0.0),
        v(0.1, 0.0, 0.0),
        v(0.0, 0.0, -0.1),
        2,
    );
    // Mirror 1 faces (1, -1, 0): light going up leaves towards +x.
    quad(
        &mut mesh,
        v(0.0, 2.6, 0.0),
        v(s, s, 0.0),
        v(0.0, 0.0, 0.4),
        1,
    );
    // Mirror 2 faces (-1, -1, 0): light going +x leaves downwards.
    quad(
        &mut mesh,
        v(1.5, 2.6, 0.0),
        v(s, -s, 0.0),
        v(0.0, 0.0, 0.4),
        1,
    );
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.7), Vec3::ZERO),
        mirror(),
        light(50.0),
    ];
    let camera = CameraSpec::look_at(v(1.5, 1.2, 2.5), v(1.5, 0.0, 0.0), Vec3A::Y, 45.0);
    Scene::new(mesh, materials, vec![], camera, size, size)
}

/// `E S L`: a 0.3 x 0.3 light (radiance 30) behind the camera facing the scene, seen only in a
/// vertical mirror; it also lights a diffuse floor directly.
pub fn mirror_light(size: u32) -> Scene {
    let mut mesh = Mesh::new();
    quad(
        &mut mesh,
        v(0.0, 0.0, 1.5),
        v(2.0, 0.0, 0.0),
        v(0.0, 0.0, -2.0),
        0,
    );
    quad(
        &mut mesh,
        v(0.0, 1.0, 0.0),
        v(0.6, 0.0, 0.0),
        v(0.0, 0.6, 0.0),
        1,
    );
    quad(
        &mut mesh,
        v(0.0, 1.3, 4.0),
        v(0.0, 0.15, 0.0),
        v(0.15, 0.0, 0.0),
        2,
    );
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.7), Vec3::ZERO),
        mirror(),
        light(30.0),
    ];
    let camera = CameraSpec::look_at(v(0.0, 1.0, 3.0), v(0.0, 0.8, 0.0), Vec3A::Y, 40.0);
    Scene::new(mesh, materials, vec![], camera, size, size)
}

/// A closed 2 x 2 x 2 diffuse box (white, a red and a green side wall) lit only by a
/// 0.04 x 0.04 ceiling light of radiance 2500; the camera is inside, near the front wall.
pub fn small_light(size: u32) -> Scene {
    let mut mesh = Mesh::new();
    room(&mut mesh, 1.0, [0, 1, 2], None);
    quad(
        &mut mesh,
        v(0.0, 1.99, 0.0),
        v(0.02, 0.0, 0.0),
        v(0.0, 0.0, 0.02),
        3,
    );
    let materials = vec![
        Material::diffuse("white", Vec3::splat(0.7), Vec3::ZERO),
        Material::diffuse("red", Vec3::new(0.6, 0.1, 0.1), Vec3::ZERO),
        Material::diffuse("green", Vec3::new(0.1, 0.5, 0.1), Vec3::ZERO),
        light(2500.0),
    ];
    let camera = CameraSpec::look_at(v(0.0, 1.0, 0.9), v(0.0, 0.8, -1.0), Vec3A::Y, 60.0);
    Scene::new(mesh, materials, vec![], camera, size, size)
}

/// A closed 2 x 2 x 2 diffuse room with a 0.6 x 0.6 ceiling window, lit only by a constant
/// environment of radiance 1 through the window; the camera is inside.
pub fn sky_room(size: u32) -> Scene {
    let mut mesh = Mesh::new();
    room(&mut mesh, 1.0, [0, 1, 2], Some(0.3));
    let materials = vec![
        Material::diffuse("white", Vec3::splat(0.7), Vec3::ZERO),
        Material::diffuse("red", Vec3::new(0.6, 0.1, 0.1), Vec3::ZERO),
        Material::diffuse("green", Vec3::new(0.1, 0.5, 0.1), Vec3::ZERO),
    ];
    let camera = CameraSpec::look_at(v(0.0, 1.0, 0.9), v(0.0, 0.7, -1.0), Vec3A::Y, 60.0);
    let mut scene = Scene::new(mesh, materials, vec![], camera, size, size);
    scene.set_environment(Some(EnvironmentLight::constant(Vec3::ONE)));
    scene
}
