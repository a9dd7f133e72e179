//! `KHR_lights_punctual` in glTF files: point, spot and directional lights on nodes with
//! their world transforms and units; invalid lights are skipped with a warning naming them.

use std::path::Path;

use glam::{Vec3, Vec3A};
use gltf::json::Value;
use render::light::PunctualKind;
use render::scene::Scene;

/// The tiny embedded fixture with lights added: `lights` (the extension's array) and one
/// node per light (`nodes` JSON objects carrying the light index).
fn with_lights(lights: Value, nodes: Vec<Value>) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny-embedded.gltf");
    let mut v: Value = gltf::json::deserialize::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push("KHR_lights_punctual".into());
    v["extensions"] = serde_json_object("KHR_lights_punctual", serde_json_object("lights", lights));
    let first = v["nodes"].as_array().unwrap().len();
    for (i, n) in nodes.into_iter().enumerate() {
        v["nodes"].as_array_mut().unwrap().push(n);
        v["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push((first + i).into());
    }
    let bytes = gltf::json::serialize::to_vec(&v).unwrap();
    Scene::from_gltf_slice(&bytes, None).expect("loads")
}

fn serde_json_object(key: &str, value: Value) -> Value {
    let mut m = gltf::json::Value::Object(Default::default());
    m[key] = value;
    m
}

fn parse(text: &str) -> Value {
    gltf::json::deserialize::from_str(text).unwrap()
}

#[test]
fn point_spot_and_directional_lights_with_transforms_and_units() {
    let lights = parse(
        r#"[
        {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 20.0},
        {"type": "spot", "intensity": 5.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
        {"type": "directional", "intensity": 3.0}
    ]"#,
    );
    let nodes = vec![
        parse(
            r#"{"name": "bulb", "translation": [1.0, 2.0, 3.0], "extensions": {"KHR_lights_punctual": {"light": 0}}}"#,
        ),
        // Rotated -90 degrees about +X: local -Z points down (-Y).
        parse(
            r#"{"name": "spot", "translation": [0.0, 1.5, 0.0], "rotation": [-0.70710678, 0.0, 0.0, 0.70710678], "extensions": {"KHR_lights_punctual": {"light": 1}}}"#,
        ),
        parse(r#"{"name": "sun", "extensions": {"KHR_lights_punctual": {"light": 2}}}"#),
    ];
    let scene = with_lights(lights, nodes);
    let p = scene.lights().punctual();
    assert_eq!(p.len(), 3, "{:?}", scene.warnings);
    assert_eq!(p[0].kind, PunctualKind::Point);
    assert!((p[0].position - Vec3A::new(1.0, 2.0, 3.0)).length() < 1e-5);
    assert_eq!(p[0].intensity, Vec3::new(20.0, 10.0, 5.0));
    let PunctualKind::Spot {
        cos_inner,
        cos_outer,
    } = p[1].kind
    else {
        panic!("{:?}", p[1].kind)
    };
    assert!((cos_inner - 0.2f32.cos()).abs() < 1e-6 && (cos_outer - 0.5f32.cos()).abs() < 1e-6);
    assert!(
        (p[1].direction - Vec3A::NEG_Y).length() < 1e-5,
        "{}",
        p[1].direction
    );
    assert_eq!(p[2].kind, PunctualKind::Directional);
    assert!((p[2].direction - Vec3A::NEG_Z).length() < 1e-6);
    assert_eq!(p[2].intensity, Vec3::splat(3.0));
    assert!(!scene
        .warnings
        .iter()
        .any(|w| w.contains("KHR_lights_punctual is")));
    // The emissive quad of the fixture stays a light, and no default environment is added.
    assert!(!scene.lights().lights().is_empty());
    assert!(scene.lights().environment().is_none() && !scene.uses_default_environment());
}

#[test]
fn invalid_lights_are_skipped_with_named_warnings() {
    let lights = parse(
        r#"[
        {"type": "spot", "spot": {"innerConeAngle": 0.9, "outerConeAngle": 0.5}},
        {"type": "point", "intensity": -1.0},
        {"type": "laser"},
        {"type": "point", "range": 4.0}
    ]"#,
    );
    let nodes = (0..4)
        .map(|i| {
            parse(&format!(
                r#"{{"extensions": {{"KHR_lights_punctual": {{"light": {i}}}}}}}"#
            ))
        })
        .chain([parse(
            r#"{"extensions": {"KHR_lights_punctual": {"light": 9}}}"#,
        )])
        .collect();
    let scene = with_lights(lights, nodes);
    assert_eq!(
        scene.lights().punctual().len(),
        1,
        "only the point light with a range"
    );
    let w = scene.warnings.join("\n");
    for needle in [
        "light 0 (node 4): spot cone angles",
        "light 1 (node 5): intensity",
        "light 2 (node 6): unknown type 'laser'",
        "light 3 (node 7): `range` is ignored",
        "light 9 (node 8) does not exist",
    ] {
        assert!(w.contains(needle), "missing '{needle}' in:\n{w}");
    }
}
