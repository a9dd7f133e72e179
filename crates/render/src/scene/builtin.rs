//! The built-in Cornell box: the classic Cornell University measurements (millimetres, here
//! scaled to metres), diffuse white/red/green walls, two white boxes and an area light.

use glam::{Vec3, Vec3A};

use super::{CameraSpec, Material, Mesh, Scene};

/// Millimetres to metres.
const MM: f32 = 0.001;

fn p(x: f32, y: f32, z: f32) -> Vec3A {
    Vec3A::new(x, y, z) * MM
}

/// Adds the quad `q`, reversing its winding if needed so that its front side faces
/// `towards` (inwards-facing walls) or away from it (outwards-facing box sides).
fn add_oriented(mesh: &mut Mesh, q: [Vec3A; 4], material: u32, reference: Vec3A, towards: bool) {
    let n = (q[1] - q[0]).cross(q[2] - q[0]);
    let centre = (q[0] + q[1] + q[2] + q[3]) * 0.25;
    let faces_ref = n.dot(reference - centre) > 0.0;
    if faces_ref == towards {
        mesh.add_quad(q, material);
    } else {
        mesh.add_quad([q[3], q[2], q[1], q[0]], material);
    }
}

/// Material indices.
const WHITE: u32 = 0;
const RED: u32 = 1;
const GREEN: u32 = 2;
const LIGHT: u32 = 3;

/// Builds the scene (see [`Scene::cornell_box`]).
pub(super) fn cornell_box(width: u32, height: u32) -> Scene {
    let materials = vec![
        Material::diffuse("white", Vec3::splat(0.73), Vec3::ZERO),
        Material::diffuse("red", Vec3::new(0.65, 0.05, 0.05), Vec3::ZERO),
        Material::diffuse("green", Vec3::new(0.12, 0.45, 0.15), Vec3::ZERO),
        // Radiance of the usual RGB approximation of the Cornell light's spectrum.
        Material::diffuse("light", Vec3::splat(0.78), Vec3::new(17.0, 12.0, 4.0)),
    ];
    let mut mesh = Mesh::new();
    let inside = p(278.0, 274.4, 279.6);
    let walls: [([Vec3A; 4], u32); 5] = [
        // floor
        (
            [
                p(552.8, 0.0, 0.0),
                p(0.0, 0.0, 0.0),
                p(0.0, 0.0, 559.2),
                p(549.6, 0.0, 559.2),
            ],
            WHITE,
        ),
        // ceiling
        (
            [
                p(556.0, 548.8, 0.0),
                p(556.0, 548.8, 559.2),
                p(0.0, 548.8, 559.2),
                p(0.0, 548.8, 0.0),
            ],
            WHITE,
        ),
        // back wall
        (
            [
                p(549.6, 0.0, 559.2),
                p(0.0, 0.0, 559.2),
                p(0.0, 548.8, 559.2),
                p(556.0, 548.8, 559.2),
            ],
            WHITE,
        ),
        // right wall (green, x = 0)
        (
            [
                p(0.0, 0.0, 559.2),
                p(0.0, 0.0, 0.0),
                p(0.0, 548.8, 0.0),
                p(0.0, 548.8, 559.2),
            ],
            GREEN,
        ),
        // left wall (red)
        (
            [
                p(552.8, 0.0, 0.0),
                p(549.6, 0.0, 559.2),
                p(556.0, 548.8, 559.2),
                p(556.0, 548.8, 0.0),
            ],
            RED,
        ),
    ];
    for (q, m) in walls {
        add_oriented(&mut mesh, q, m, inside, true);
    }
    // The light, 0.1 mm below the ceiling to avoid coplanar surfaces, facing down.
    let y = 548.7;
    add_oriented(
        &mut mesh,
        [
            p(343.0, y, 227.0),
            p(343.0, y, 332.0),
            p(213.0, y, 332.0),
            p(213.0, y, 227.0),
        ],
        LIGHT,
        inside,
        true,
    );
    let short_block = [(130.0, 65.0), (82.0, 225.0), (240.0, 272.0), (290.0, 114.0)];
    let tall_block = [
        (423.0, 247.0),
        (265.0, 296.0),
        (314.0, 456.0),
        (472.0, 406.0),
    ];
    for (footprint, h) in [(short_block, 165.0), (tall_block, 330.0)] {
        add_block(&mut mesh, footprint, h);
    }
    let camera = CameraSpec::look_at(
        p(278.0, 273.0, -800.0),
        p(278.0, 273.0, 0.0),
        Vec3A::Y,
        // 35 mm lens on a 25 mm film.
        2.0 * (12.5f32 / 35.0).atan().to_degrees(),
    );
    Scene::new(mesh, materials, vec![], camera, width, height)
}

/// A white block standing on the floor over the quadrilateral `footprint` (x, z in mm).
fn add_block(mesh: &mut Mesh, footprint: [(f32, f32); 4], height: f32) {
    let top: Vec<Vec3A> = footprint.iter().map(|&(x, z)| p(x, height, z)).collect();
    let bottom: Vec<Vec3A> = footprint.iter().map(|&(x, z)| p(x, 0.0, z)).collect();
    let centre = top.iter().chain(&bottom).copied().sum::<Vec3A>() / 8.0;
    add_oriented(mesh, [top[0], top[1], top[2], top[3]], WHITE, centre, false);
    for i in 0..4 {
        let j = (i + 1) % 4;
        add_oriented(
            mesh,
            [bottom[i], bottom[j], top[j], top[i]],
            WHITE,
            centre,
            false,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_box_is_closed_lit_and_oriented() {
        let s = Scene::cornell_box(32, 32);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(s.mesh().triangle_count(), 2 * (5 + 1 + 5 + 5));
        assert_eq!(s.lights().lights().len(), 2);
        for l in s.lights().lights() {
            assert!(l.normal.y < -0.99, "light faces down");
            assert!(!l.two_sided);
        }
        // The centre pixel sees the back wall or a block; every corner ray hits something.
        let cam = s.camera();
        for (x, y) in [(16.0, 16.0), (2.5, 2.5), (29.5, 29.5), (2.5, 29.5)] {
            let ray = cam.generate_ray(glam::Vec2::new(x, y), glam::Vec2::ZERO, 0.0);
            let si = s.intersect(&ray).expect("hit");
            assert!(si.ng.dot(si.wo) > 0.0, "surfaces face the camera");
        }
        // Red on the left of the image, green on the right.
        let left = s
            .intersect(&cam.generate_ray(glam::Vec2::new(2.5, 16.0), glam::Vec2::ZERO, 0.0))
            .unwrap();
        let right = s
            .intersect(&cam.generate_ray(glam::Vec2::new(29.5, 16.0), glam::Vec2::ZERO, 0.0))
            .unwrap();
        assert_eq!(s.materials()[left.material as usize].name, "red");
        assert_eq!(s.materials()[right.material as usize].name, "green");
    }
}
