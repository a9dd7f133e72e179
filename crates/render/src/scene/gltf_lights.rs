//! `KHR_lights_punctual`: point, spot and directional lights attached to glTF nodes, read from
//! the raw JSON (the `gltf` crate's support is behind a feature we do not need).
//!
//! A light shines from its node's world position along the node's local `-Z`. Properties as
//! the extension specifies: `color` (linear RGB, default white), `intensity` (default 1;
//! candela for point and spot lights, lux for directional lights — see
//! [`crate::light::punctual`] for how the units map to ours), `spot.innerConeAngle` (default
//! 0) and `spot.outerConeAngle` (default pi/4) with `0 <= inner < outer <= pi/2`. `range` is
//! ignored with a warning. Invalid lights are skipped with a warning naming the light.

use glam::{Mat4, Vec3, Vec3A};

use crate::light::PunctualLight;

/// The punctual light of node `node_index` (world transform `world`), if it has a valid one;
/// problems are pushed to `warnings`.
pub(super) fn node_light(
    raw: &gltf::json::Value,
    node_index: usize,
    world: Mat4,
    warnings: &mut Vec<String>,
) -> Option<PunctualLight> {
    let index = raw["nodes"][node_index]["extensions"]["KHR_lights_punctual"]["light"].as_u64()?;
    let what = format!("KHR_lights_punctual light {index} (node {node_index})");
    let light = &raw["extensions"]["KHR_lights_punctual"]["lights"][index as usize];
    if !light.is_object() {
        warnings.push(format!("{what} does not exist: the node has no light"));
        return None;
    }
    if !light["range"].is_null() {
        warnings.push(format!(
            "{what}: `range` is ignored (lights fall off with the inverse square law only)"
        ));
    }
    match parse(light, world) {
        Ok(l) => Some(l),
        Err(why) => {
            warnings.push(format!("{what}: {why}; the light is skipped"));
            None
        }
    }
}

/// A finite number, or `default` if absent.
fn number(v: &gltf::json::Value, default: f64) -> Option<f32> {
    if v.is_null() {
        Some(default as f32)
    } else {
        v.as_f64().map(|x| x as f32).filter(|x| x.is_finite())
    }
}

/// The light described by `light` on a node with world transform `world`.
fn parse(light: &gltf::json::Value, world: Mat4) -> Result<PunctualLight, String> {
    let color = match &light["color"] {
        gltf::json::Value::Null => Vec3::ONE,
        gltf::json::Value::Array(a) if a.len() == 3 => {
            let c: Vec<f32> = a.iter().filter_map(|v| number(v, 0.0)).collect();
            if c.len() != 3 || c.iter().any(|&x| x < 0.0) {
                return Err("color must be three finite values >= 0".to_owned());
            }
            Vec3::new(c[0], c[1], c[2])
        }
        _ => return Err("color must be an array of three numbers".to_owned()),
    };
    let Some(intensity) = number(&light["intensity"], 1.0).filter(|&i| i >= 0.0) else {
        return Err("intensity must be a finite number >= 0".to_owned());
    };
    let position = Vec3A::from(world.transform_point3(Vec3::ZERO));
    let direction = Vec3A::from(world.transform_vector3(Vec3::NEG_Z)).try_normalize();
    let kind = light["type"].as_str().unwrap_or("");
    let degenerate = || "its node's transform is degenerate or not finite".to_owned();
    if !position.is_finite() {
        return Err(degenerate());
    }
    match kind {
        "point" => Ok(PunctualLight::point(position, color * intensity)),
        "directional" => Ok(PunctualLight::directional(
            direction.ok_or_else(degenerate)?,
            color * intensity,
        )),
        "spot" => {
            let direction = direction.ok_or_else(degenerate)?;
            let spot = &light["spot"];
            let inner = number(&spot["innerConeAngle"], 0.0);
            let outer = number(&spot["outerConeAngle"], std::f64::consts::FRAC_PI_4);
            match (inner, outer) {
                (Some(i), Some(o)) if 0.0 <= i && i < o && o <= std::f32::consts::FRAC_PI_2 => Ok(
                    PunctualLight::spot(position, direction, color * intensity, i, o),
                ),
                _ => Err(
                    "spot cone angles must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2"
                        .to_owned(),
                ),
            }
        }
        other => Err(format!(
            "unknown type '{other}' (expected point, spot or directional)"
        )),
    }
}
