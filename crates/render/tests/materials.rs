//! glTF material textures, each on a small glTF document built in memory
//! ([`gltf_doc::Doc`]) and each with a negative control: the same document with the feature
//! removed fails the assertion the feature passes.
//!
//! - metallic-roughness texture: the halves of a quad become a mirror (black: it reflects the
//!   empty sky) and a lit diffuse surface in a path-traced render;
//! - normal map: the shading normal tilts by the encoded angle, towards +u (red) and image-up
//!   (green), with generated tangents, with `TANGENT`s, and under a mirroring node transform;
//!   extreme normal maps give valid normals and finite renders;
//! - `KHR_texture_transform`: an offset of half a texture swaps the halves of a checker; the
//!   transform's `texCoord` override and `TEXCOORD_1`;
//! - emissive texture and its transform through `Material::emission_at`.

mod gltf_doc;

use glam::{Vec3, Vec3A};
use gltf::json::Value;
use gltf_doc::{
    add_emitter, albedo, encode_normal, hit_down, j, render_down, two_texels, Attrs, Doc,
};
use render::camera::Ray;
use render::scene::{Scene, SurfaceInteraction};
use render::{IndependentSampler, Sampler};

// ---------------------------------------------------------------------------------------
// Metallic-roughness texture
// ---------------------------------------------------------------------------------------

/// Left texel: metallic (blue 255), roughness 0 (green 0): a mirror. Right texel: roughness 1,
/// metallic 0: diffuse. Both factors are 1, so without the texture the whole quad is a rough
/// metal.
fn mr_scene(with_texture: bool) -> Scene {
    let mut doc = Doc::new();
    let tex = doc.texture(2, 1, &two_texels([0, 0, 255, 255], [0, 255, 0, 255]), true);
    let mr = if with_texture {
        format!(r#", "metallicRoughnessTexture": {{"index": {tex}}}"#)
    } else {
        String::new()
    };
    let m = doc.material(&format!(
        r#"{{"name": "mr", "pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.8, 0.8, 1],
            "metallicFactor": 1, "roughnessFactor": 1{mr}}}}}"#
    ));
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    // The light is off to the side: the mirror half reflects the camera rays into the empty
    // sky, the diffuse half is lit.
    add_emitter(&mut doc, 1.5, 2.0);
    doc.scene()
}

/// The mirror half renders black and the diffuse half bright.
fn mr_halves_differ(scene: &Scene) -> bool {
    let left = render_down(scene, -0.5, 3.0, 4000);
    let right = render_down(scene, 0.5, 3.0, 4000);
    println!("metallic-roughness halves: left {left}, right {right}");
    left < 1e-6 && right > 0.05
}

#[test]
fn metallic_roughness_texture_switches_halves() {
    let s = mr_scene(true);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let l = hit_down(&s, -0.5, 0.0, 3.0).unwrap();
    let r = hit_down(&s, 0.5, 0.0, 3.0).unwrap();
    assert!(s.bsdf(&l).is_specular(), "left half: smooth metal");
    assert!(
        (albedo(&s, &r) - Vec3::splat(0.8)).length() < 1e-4,
        "right half: diffuse"
    );
    assert!(mr_halves_differ(&s));
    // Negative control: without the texture both halves are the same rough metal.
    let control = mr_scene(false);
    assert!(!mr_halves_differ(&control));
}

// ---------------------------------------------------------------------------------------
// Normal maps
// ---------------------------------------------------------------------------------------

/// A quad with a constant normal map encoding `tangent_normal`, optionally with `TANGENT`s and
/// a node transform; `scale` is `normalTexture.scale`.
fn normal_scene(
    tangent_normal: Option<Vec3>,
    scale: f32,
    tangents: Option<[f32; 4]>,
    node_extra: Option<Value>,
) -> Scene {
    let mut doc = Doc::new();
    let nt = match tangent_normal {
        Some(n) => {
            let tex = doc.texture(1, 1, &encode_normal(n), false);
            format!(r#", "normalTexture": {{"index": {tex}, "scale": {scale}}}"#)
        }
        None => String::new(),
    };
    let m = doc.material(&format!(
        r#"{{"name": "bumpy", "pbrMetallicRoughness": {{"metallicFactor": 0}}{nt}}}"#
    ));
    let attrs = Attrs {
        tangents: tangents.map(|t| [t; 4]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &attrs, false, node_extra);
    doc.scene()
}

/// The shading normal seen by a ray straight down onto the quad.
fn shading_normal(s: &Scene) -> Vec3A {
    let si = hit_down(s, 0.3, 0.2, 3.0).expect("the quad");
    assert!((si.ng - Vec3A::Z).length() < 1e-6);
    si.ns
}

/// True if `ns` is tilted by `deg` degrees (within 0.5 degrees) from +z towards `towards`.
fn tilted(ns: Vec3A, deg: f32, towards: Vec3A) -> bool {
    let angle = ns.dot(Vec3A::Z).clamp(-1.0, 1.0).acos().to_degrees();
    let lateral = (ns - Vec3A::Z * ns.dot(Vec3A::Z)).normalize_or_zero();
    println!("ns {ns}: {angle} degrees towards {lateral}");
    (angle - deg).abs() < 0.5 && (deg == 0.0 || lateral.dot(towards) > 0.999)
}

#[test]
fn normal_map_tilts_the_shading_normal_by_a_known_angle() {
    let theta = 30f32.to_radians();
    let (s, c) = theta.sin_cos();
    // Red = +u = +x here; green = image up = decreasing v = +y here.
    let red = Vec3::new(s, 0.0, c);
    let green = Vec3::new(0.0, s, c);
    let scene = normal_scene(Some(red), 1.0, None, None);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(tilted(shading_normal(&scene), 30.0, Vec3A::X));
    assert!(tilted(
        shading_normal(&normal_scene(Some(green), 1.0, None, None)),
        30.0,
        Vec3A::Y
    ));
    // scale multiplies X and Y: 0 removes the tilt.
    assert!(tilted(
        shading_normal(&normal_scene(Some(red), 0.0, None, None)),
        0.0,
        Vec3A::X
    ));
    // Negative control: the same quad without the normal map is not tilted.
    assert!(!tilted(
        shading_normal(&normal_scene(None, 1.0, None, None)),
        30.0,
        Vec3A::X
    ));
}

#[test]
fn normal_map_uses_vertex_tangents_and_handedness() {
    let theta = 30f32.to_radians();
    let (s, c) = theta.sin_cos();
    let red = Vec3::new(s, 0.0, c);
    let green = Vec3::new(0.0, s, c);
    // Tangent +y: red tilts towards +y; bitangent = w (n x t) = w (-x).
    let t = Some([0.0, 1.0, 0.0, 1.0]);
    assert!(tilted(
        shading_normal(&normal_scene(Some(red), 1.0, t, None)),
        30.0,
        Vec3A::Y
    ));
    assert!(tilted(
        shading_normal(&normal_scene(Some(green), 1.0, t, None)),
        30.0,
        -Vec3A::X
    ));
    let t = Some([0.0, 1.0, 0.0, -1.0]);
    assert!(tilted(
        shading_normal(&normal_scene(Some(green), 1.0, t, None)),
        30.0,
        Vec3A::X
    ));
    // Negative control: the tangent is used, not the UVs (which would tilt red towards +x).
    let t = Some([0.0, 1.0, 0.0, 1.0]);
    assert!(!tilted(
        shading_normal(&normal_scene(Some(red), 1.0, t, None)),
        30.0,
        Vec3A::X
    ));
}

/// Under a mirroring node transform (x -> -x) the generated and the given tangents agree:
/// red (+u) now tilts towards -x, green (image up) still towards +y.
#[test]
fn normal_map_follows_a_mirroring_node() {
    let theta = 30f32.to_radians();
    let (s, c) = theta.sin_cos();
    let mirror = || Some(j(r#"{"scale": [-1, 1, 1]}"#));
    for tangents in [None, Some([1.0, 0.0, 0.0, 1.0])] {
        let red = normal_scene(Some(Vec3::new(s, 0.0, c)), 1.0, tangents, mirror());
        assert!(
            tilted(shading_normal(&red), 30.0, -Vec3A::X),
            "{tangents:?}"
        );
        let green = normal_scene(Some(Vec3::new(0.0, s, c)), 1.0, tangents, mirror());
        assert!(
            tilted(shading_normal(&green), 30.0, Vec3A::Y),
            "{tangents:?}"
        );
    }
    // Negative control: without the mirror red tilts towards +x.
    let plain = normal_scene(Some(Vec3::new(s, 0.0, c)), 1.0, None, None);
    assert!(!tilted(shading_normal(&plain), 30.0, -Vec3A::X));
}

/// Normal maps pointing below the surface (or along it) still give unit shading normals
/// inside the geometric hemisphere and finite renders.
#[test]
fn extreme_normal_maps_stay_valid() {
    for texel in [
        Vec3::new(1.0, 0.0, -1.0).normalize(),
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(0.7, 0.7, 0.1).normalize(),
    ] {
        let mut doc = Doc::new();
        let tex = doc.texture(1, 1, &encode_normal(texel), false);
        let m = doc.material(&format!(
            r#"{{"pbrMetallicRoughness": {{"metallicFactor": 0}}, "doubleSided": true,
                "normalTexture": {{"index": {tex}, "scale": 3}}}}"#
        ));
        doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
        add_emitter(&mut doc, -1.0, 2.0);
        let scene = doc.scene();
        let mut s = IndependentSampler::new(3);
        for i in 0..2000 {
            s.start_pixel_sample(i, 0);
            let u = s.next_2d();
            let target = Vec3A::new(u.x * 1.6 - 0.8, u.y * 1.6 - 0.8, 0.0);
            let v = s.next_2d();
            // Directions from both sides, down to grazing.
            let dir =
                Vec3A::new(v.x - 0.5, v.y - 0.5, if i % 2 == 0 { -0.05 } else { 0.05 }).normalize();
            let ray = Ray::new(target - dir * 0.5, dir, 0.0);
            let si = scene.intersect(&ray).expect("the quad");
            assert!((si.ns.length() - 1.0).abs() < 1e-4, "{}", si.ns);
            assert!(si.ns.dot(si.ng) > 0.005, "{} vs {}", si.ns, si.ng);
        }
        assert!(render_down(&scene, 0.0, 1.0, 2000).is_finite());
    }
}

// ---------------------------------------------------------------------------------------
// KHR_texture_transform, TEXCOORD_1
// ---------------------------------------------------------------------------------------

/// A quad with a black | white base-colour texture referenced through `info_extra` (extra
/// textureInfo JSON members), with `TEXCOORD_1 = (1 - u, v)` (mirrored).
fn checker_scene(info_extra: &str) -> Scene {
    let mut doc = Doc::new();
    let tex = doc.texture(
        2,
        1,
        &two_texels([0, 0, 0, 255], [255, 255, 255, 255]),
        true,
    );
    let m = doc.material(&format!(
        r#"{{"pbrMetallicRoughness": {{"metallicFactor": 0,
            "baseColorTexture": {{"index": {tex}{info_extra}}}}}}}"#
    ));
    let attrs = Attrs {
        uv1: Some([[1.0, 1.0], [0.0, 1.0], [0.0, 0.0], [1.0, 0.0]]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &attrs, false, None);
    doc.scene()
}

/// The albedo (red channel) of the left and right halves.
fn checker_halves(s: &Scene) -> (f32, f32) {
    let l = albedo(s, &hit_down(s, -0.5, 0.0, 3.0).unwrap()).x;
    let r = albedo(s, &hit_down(s, 0.5, 0.0, 3.0).unwrap()).x;
    (l, r)
}

#[test]
fn texture_transform_offset_shifts_a_checker() {
    let plain = checker_scene("");
    assert_eq!(checker_halves(&plain), (0.0, 1.0));
    let shifted =
        checker_scene(r#", "extensions": {"KHR_texture_transform": {"offset": [0.5, 0]}}"#);
    assert!(shifted.warnings.is_empty(), "{:?}", shifted.warnings);
    assert_eq!(checker_halves(&shifted), (1.0, 0.0));
    // Scale 2 repeats the checker twice across the quad: u in [0.25, 0.5) reads white.
    let scaled = checker_scene(r#", "extensions": {"KHR_texture_transform": {"scale": [2, 1]}}"#);
    let at = |x: f32| albedo(&scaled, &hit_down(&scaled, x, 0.0, 3.0).unwrap()).x;
    assert_eq!(
        (at(-0.75), at(-0.25), at(0.25), at(0.75)),
        (0.0, 1.0, 0.0, 1.0)
    );
}

#[test]
fn texcoord_1_and_the_transform_override() {
    // texCoord 1 reads the mirrored set: the halves swap.
    assert_eq!(
        checker_halves(&checker_scene(r#", "texCoord": 1"#)),
        (1.0, 0.0)
    );
    // The transform's texCoord overrides the textureInfo's.
    let over = checker_scene(r#", "extensions": {"KHR_texture_transform": {"texCoord": 1}}"#);
    assert_eq!(checker_halves(&over), (1.0, 0.0));
    // Negative control: texCoord 0.
    assert_eq!(
        checker_halves(&checker_scene(r#", "texCoord": 0"#)),
        (0.0, 1.0)
    );
}

// ---------------------------------------------------------------------------------------
// Emissive texture
// ---------------------------------------------------------------------------------------

#[test]
fn emissive_texture_is_loaded_with_its_transform() {
    let mut doc = Doc::new();
    // sRGB: 188 decodes to about 0.5.
    let tex = doc.texture(
        2,
        1,
        &two_texels([0, 0, 0, 255], [188, 255, 255, 255]),
        true,
    );
    let m = doc.material(&format!(
        r#"{{"name": "screen", "emissiveFactor": [1, 1, 1],
            "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": 4}}}},
            "emissiveTexture": {{"index": {tex},
                "extensions": {{"KHR_texture_transform": {{"offset": [0.5, 0]}}}}}}}}"#
    ));
    doc.use_extension("KHR_materials_emissive_strength");
    doc.use_extension("KHR_texture_transform");
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    let s = doc.scene();
    let mat = &s.materials()[0];
    let et = mat.emissive_texture.expect("emissive texture loaded");
    assert_eq!(et.tex_coord, 0);
    let left = hit_down(&s, -0.5, 0.0, 3.0).unwrap();
    let right = hit_down(&s, 0.5, 0.0, 3.0).unwrap();
    let e = |si: &SurfaceInteraction| mat.emission_at(s.textures(), s.tex_coord(si, et.tex_coord));
    // The offset swaps the halves: the left half reads the right texel.
    let l = e(&left);
    assert!((l.x - 2.0).abs() < 0.05 && (l.y - 4.0).abs() < 1e-4, "{l}");
    assert_eq!(e(&right), Vec3::ZERO);
    // Negative control: the factor alone is uniform.
    assert_eq!(mat.emission, Vec3::splat(4.0));
}
