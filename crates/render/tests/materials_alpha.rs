//! glTF vertex colours and alpha masks, each on a small glTF document built in memory
//! ([`gltf_doc::Doc`]) with a negative control, the one warning naming unsupported material
//! features, and every integrator on a scene using all supported features at once.
//!
//! - `COLOR_0` (float vec3, normalised u8 vec4, normalised u16 vec3) multiplies the base colour;
//! - alpha `MASK`: camera rays, shadow rays (both visibility queries) and a path-traced render
//!   pass through the cut-out half only; `alphaCutoff`, `baseColorFactor` alpha, `COLOR_0`
//!   alpha, `BLEND` (as MASK 0.5, with a warning);
//! - unsupported material features are named in one warning.

mod gltf_doc;

use glam::{Vec3, Vec3A};
use gltf_doc::{add_emitter, albedo, encode_normal, hit_down, render_down, two_texels, Attrs, Doc};
use render::scene::{AlphaMode, Scene, SurfaceInteraction};

// ---------------------------------------------------------------------------------------
// COLOR_0
// ---------------------------------------------------------------------------------------

fn colored_scene(attrs: &Attrs) -> Scene {
    let mut doc = Doc::new();
    let m = doc.material(
        r#"{"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0}}"#,
    );
    doc.quad((0.0, 0.0, 0.0), 2.0, m, attrs, false, None);
    doc.scene()
}

fn centre_albedo(s: &Scene) -> Vec3 {
    albedo(s, &hit_down(s, 0.1, 0.1, 3.0).unwrap())
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    let red = Attrs {
        colors_f32: Some(vec![vec![1.0, 0.0, 0.0]; 4]),
        ..Attrs::default()
    };
    let a = centre_albedo(&colored_scene(&red));
    assert!((a - Vec3::X).length() < 1e-5, "{a}");
    // Normalised unsigned bytes, VEC4 (alpha ignored without a mask).
    let bytes = [255u8, 0, 0, 128].repeat(4);
    let u8s = Attrs {
        colors_norm: Some((5121, "VEC4", bytes)),
        ..Attrs::default()
    };
    let a = centre_albedo(&colored_scene(&u8s));
    assert!((a - Vec3::X).length() < 1e-5, "{a}");
    // Normalised unsigned shorts, VEC3: half green.
    let shorts: Vec<u8> = [0u16, 32768, 0]
        .repeat(4)
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let u16s = Attrs {
        colors_norm: Some((5123, "VEC3", shorts)),
        ..Attrs::default()
    };
    let a = centre_albedo(&colored_scene(&u16s));
    assert!((a - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-4, "{a}");
    // Interpolated across the quad: red on the left vertices, blue on the right.
    let ramp = Attrs {
        colors_f32: Some(vec![
            vec![1.0, 0.0, 0.0],
            vec![0.0, 0.0, 1.0],
            vec![0.0, 0.0, 1.0],
            vec![1.0, 0.0, 0.0],
        ]),
        ..Attrs::default()
    };
    let s = colored_scene(&ramp);
    let a = albedo(&s, &hit_down(&s, -0.5, 0.3, 3.0).unwrap());
    assert!((a - Vec3::new(0.75, 0.0, 0.25)).length() < 1e-4, "{a}");
    // Negative control: no COLOR_0, white.
    let a = centre_albedo(&colored_scene(&Attrs::default()));
    assert!((a - Vec3::ONE).length() < 1e-5, "{a}");
}

// ---------------------------------------------------------------------------------------
// Alpha mask
// ---------------------------------------------------------------------------------------

/// A black quad at z = 0 whose base-colour texture is transparent on the left half (alpha 0)
/// and opaque on the right, with alpha mode `mode`; a white floor at z = -1; a light at
/// z = 2 covering the quad.
fn mask_scene(mode: &str) -> Scene {
    let mut doc = Doc::new();
    let tex = doc.texture(2, 1, &two_texels([0, 0, 0, 0], [0, 0, 0, 255]), true);
    let m = doc.material(&format!(
        r#"{{"name": "leaf", "alphaMode": "{mode}", "doubleSided": true,
            "pbrMetallicRoughness": {{"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0,
            "baseColorTexture": {{"index": {tex}}}}}}}"#
    ));
    let floor = doc.material(
        r#"{"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0}}"#,
    );
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    doc.quad((0.0, 0.0, -1.0), 4.0, floor, &Attrs::default(), false, None);
    add_emitter(&mut doc, -1.0, 2.0);
    doc.scene()
}

/// Camera and shadow rays pass the left (cut-out) half and are stopped by the right half.
fn cutout_works(s: &Scene) -> bool {
    let name = |si: &SurfaceInteraction| s.materials()[si.material as usize].name.clone();
    // Camera rays.
    let left = hit_down(s, -0.5, 0.0, 3.0 - 1.5).unwrap();
    let right = hit_down(s, 0.5, 0.0, 1.5).unwrap();
    let camera_ok = name(&left) == "floor" && name(&right) == "leaf";
    // Shadow rays between free points (BDPT's query) ...
    let free = |x: f32| {
        s.unoccluded_between(
            Vec3A::new(x, 0.0, 1.0),
            Vec3A::ZERO,
            Vec3A::new(x, 0.0, -0.5),
            Vec3A::ZERO,
        )
    };
    // ... and from a surface point on the floor up to the light (PT's query).
    let floor_at = |x: f32| hit_down(s, x, 0.0, -0.5).unwrap();
    let lit = |x: f32| s.unoccluded(&floor_at(x), Vec3A::new(x, 0.0, 2.0));
    println!(
        "camera {} {}, free {} {}, lit {} {}",
        name(&left),
        name(&right),
        free(-0.5),
        free(0.5),
        lit(-0.5),
        lit(0.5)
    );
    camera_ok && free(-0.5) && !free(0.5) && lit(-0.5) && !lit(0.5)
}

#[test]
fn alpha_mask_cuts_out_camera_and_shadow_rays() {
    let s = mask_scene("MASK");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.materials()[0].alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    assert!(cutout_works(&s));
    // Path traced from between the quad and the light: the floor under the cut-out half is
    // lit (camera ray and shadow rays pass), the opaque half is black.
    let left = render_down(&s, -0.5, 1.0, 2000);
    let right = render_down(&s, 0.5, 1.0, 2000);
    println!("mask render: left {left}, right {right}");
    assert!(left > 0.1 && right < 1e-6);
    // Negative control: the same texture and material, opaque.
    let opaque = mask_scene("OPAQUE");
    assert!(!cutout_works(&opaque));
    assert!(render_down(&opaque, -0.5, 1.0, 500) < 1e-6);
}

#[test]
fn blend_is_a_mask_with_a_warning() {
    let s = mask_scene("BLEND");
    let w: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("alpha mode BLEND"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    assert!(w[0].contains("'leaf'"), "{}", w[0]);
    assert!(cutout_works(&s));
}

/// `alpha = baseColorFactor.a x texture alpha x COLOR_0.a`, compared with `alphaCutoff`.
#[test]
fn alpha_sources_and_cutoff() {
    let quad_with = |factor_alpha: f32, cutoff: Option<f32>, color_alpha: Option<f32>| {
        let mut doc = Doc::new();
        // Texture alpha 0.8 everywhere.
        let tex = doc.texture(1, 1, &[255, 255, 255, 204], true);
        let cutoff = cutoff.map_or(String::new(), |c| format!(r#", "alphaCutoff": {c}"#));
        let m = doc.material(&format!(
            r#"{{"alphaMode": "MASK"{cutoff}, "pbrMetallicRoughness": {{
                "baseColorFactor": [1, 1, 1, {factor_alpha}], "baseColorTexture": {{"index": {tex}}}}}}}"#
        ));
        let attrs = Attrs {
            colors_f32: color_alpha.map(|a| vec![vec![1.0, 1.0, 1.0, a]; 4]),
            ..Attrs::default()
        };
        doc.quad((0.0, 0.0, 0.0), 2.0, m, &attrs, false, None);
        let s = doc.scene();
        hit_down(&s, 0.1, 0.1, 3.0).is_some()
    };
    assert!(quad_with(1.0, None, None)); // 0.8 >= 0.5
    assert!(!quad_with(1.0, Some(0.85), None)); // 0.8 < 0.85
    assert!(!quad_with(0.5, None, None)); // 0.4 < 0.5
    assert!(quad_with(0.7, Some(0.55), None)); // 0.56 >= 0.55
    assert!(!quad_with(1.0, None, Some(0.5))); // 0.4 < 0.5
    assert!(quad_with(1.0, None, Some(0.7))); // 0.56 >= 0.5
}

// ---------------------------------------------------------------------------------------
// Unsupported features
// ---------------------------------------------------------------------------------------

#[test]
fn unsupported_material_features_are_one_warning() {
    let mut doc = Doc::new();
    let tex = doc.texture(1, 1, &[255, 255, 255, 255], false);
    doc.material(&format!(
        r#"{{"name": "car paint", "occlusionTexture": {{"index": {tex}}},
            "extensions": {{"KHR_materials_clearcoat": {{"clearcoatFactor": 1}},
                           "KHR_materials_sheen": {{"sheenColorFactor": [1, 1, 1]}}}}}}"#
    ));
    let m = doc.material(&format!(
        r#"{{"name": "velvet", "emissiveFactor": [1, 1, 1],
            "emissiveTexture": {{"index": {tex}, "texCoord": 2}},
            "extensions": {{"KHR_materials_sheen": {{"sheenColorFactor": [1, 0, 0]}}}}}}"#
    ));
    doc.use_extension("KHR_materials_clearcoat");
    doc.use_extension("KHR_materials_sheen");
    doc.quad((0.0, 0.0, 0.0), 2.0, m, &Attrs::default(), false, None);
    let s = doc.scene();
    let material_warnings: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("material features"))
        .collect();
    assert_eq!(material_warnings.len(), 1, "{:?}", s.warnings);
    let w = material_warnings[0];
    for needle in [
        "occlusionTexture",
        "KHR_materials_clearcoat (in 'car paint')",
        "KHR_materials_sheen (in 'car paint', 'velvet')",
        "emissiveTexture.texCoord 2",
    ] {
        assert!(w.contains(needle), "missing {needle}: {w}");
    }
    // The extensions are not named again, one warning each.
    let others = s
        .warnings
        .iter()
        .filter(|w| !w.contains("material features") && w.contains("KHR_materials_"))
        .count();
    assert_eq!(others, 0, "{:?}", s.warnings);
    // TEXCOORD_0 is used instead of set 2.
    assert_eq!(s.materials()[1].emissive_texture.unwrap().tex_coord, 0);
}

// ---------------------------------------------------------------------------------------
// Every integrator
// ---------------------------------------------------------------------------------------

/// A scene using every supported material feature at once (a tilted normal map with its own
/// tangents, a metallic-roughness texture, a cut-out mask, vertex colours, a texture
/// transform) renders through PT, BDPT, PSSMLT and MMLT without a non-finite sample and not
/// black.
#[test]
fn every_integrator_renders_the_features_finitely() {
    use render::{Budget, IntegratorKind, NoProgress, RenderSettings};
    let mut doc = Doc::new();
    let normal = doc.texture(
        2,
        1,
        &[
            encode_normal(Vec3::new(0.7, 0.0, 0.7).normalize()),
            encode_normal(Vec3::new(0.0, -0.9, 0.1).normalize()),
        ]
        .concat(),
        false,
    );
    let mr = doc.texture(
        2,
        1,
        &two_texels([0, 40, 255, 255], [0, 200, 0, 255]),
        false,
    );
    let base = doc.texture(
        2,
        1,
        &two_texels([200, 90, 30, 0], [90, 200, 90, 255]),
        true,
    );
    let leaf = doc.material(&format!(
        r#"{{"name": "leaf", "alphaMode": "MASK", "doubleSided": true,
            "normalTexture": {{"index": {normal}, "scale": 1.5}},
            "pbrMetallicRoughness": {{"metallicFactor": 1, "roughnessFactor": 1,
                "metallicRoughnessTexture": {{"index": {mr},
                    "extensions": {{"KHR_texture_transform": {{"scale": [3, 3], "rotation": 0.4}}}}}},
                "baseColorTexture": {{"index": {base},
                    "extensions": {{"KHR_texture_transform": {{"scale": [4, 4]}}}}}}}}}}"#
    ));
    let floor = doc.material(
        r#"{"name": "floor", "pbrMetallicRoughness": {"metallicFactor": 0},
            "normalTexture": {"index": 0}}"#,
    );
    doc.use_extension("KHR_texture_transform");
    let tangents = Attrs {
        tangents: Some([[0.6, 0.8, 0.0, -1.0]; 4]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, 0.0), 2.0, leaf, &tangents, false, None);
    let colours = Attrs {
        colors_f32: Some(vec![
            vec![1.0, 0.2, 0.2],
            vec![0.2, 1.0, 0.2],
            vec![0.2, 0.2, 1.0],
            vec![1.0, 1.0, 1.0],
        ]),
        ..Attrs::default()
    };
    doc.quad((0.0, 0.0, -0.7), 4.0, floor, &colours, false, None);
    add_emitter(&mut doc, 1.2, 1.5);
    let scene = doc.scene();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    for integrator in [
        IntegratorKind::Pt,
        IntegratorKind::Bdpt,
        IntegratorKind::Pssmlt,
        IntegratorKind::Mmlt,
    ] {
        let settings = RenderSettings {
            method: integrator.settings(),
            width: 24,
            height: 24,
            budget: Budget::SamplesPerPixel(32),
            threads: 2,
            seed: 3,
            max_depth: 5,
        };
        let out = render::render(
            &scene,
            &settings,
            &NoProgress,
            &std::sync::atomic::AtomicBool::new(false),
        )
        .unwrap();
        let mean = out.image.mean_luminance();
        println!(
            "{integrator:?}: mean {mean}, {} samples, {} non-finite",
            out.samples, out.dropped_nonfinite
        );
        assert_eq!(out.dropped_nonfinite, 0, "{integrator:?}");
        assert!(mean.is_finite() && mean > 1e-3, "{integrator:?}: {mean}");
    }
}
