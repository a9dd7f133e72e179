//! The base colour of a textured material over [`Real`]: UVs interpolated with the hit's
//! barycentrics, the glTF texture transform, and the bilinear filter, so the albedo (or F0, or
//! transmission tint) carries derivatives with respect to the hit point (`Material::bsdf_at`
//! and `Texture::sample` restated).

use glam::Vec2;

use crate::autodiff::{Real, V3};
use crate::scene::Scene;

/// The sanitised base colour of triangle `tri`'s material at barycentrics `(b1, b2)` if the
/// material has a base-colour texture; `None` otherwise (the BSDF's constant colour applies).
/// Vertex colours enter as constants.
pub(super) fn base_color<T: Real>(scene: &Scene, tri: usize, bary: (T, T)) -> Option<V3<T>> {
    let mesh = scene.mesh();
    let material = scene
        .materials()
        .get(*mesh.material_ids.get(tri)? as usize)?;
    let tref = material.base_color_texture.as_ref()?;
    let texture = scene.textures().get(tref.texture as usize)?;
    let [i0, i1, i2] = mesh.triangles.get(tri)?.map(|i| i as usize);
    let set = if tref.tex_coord >= 1 && !mesh.uvs1.is_empty() {
        &mesh.uvs1
    } else {
        &mesh.uvs
    };
    let (b1, b2) = bary;
    let b0 = (-(b1 + b2) + 1.0).max_c(0.0);
    let c = |v: Vec2| (f64::from(v.x), f64::from(v.y));
    let (a, b, d) = (c(*set.get(i0)?), c(*set.get(i1)?), c(*set.get(i2)?));
    let uv = (
        b0 * a.0 + b1 * b.0 + b2 * d.0,
        b0 * a.1 + b1 * b.1 + b2 * d.1,
    );
    let m = tref.transform;
    let uv = (
        uv.0 * f64::from(m.matrix2.x_axis.x)
            + uv.1 * f64::from(m.matrix2.y_axis.x)
            + f64::from(m.translation.x),
        uv.0 * f64::from(m.matrix2.x_axis.y)
            + uv.1 * f64::from(m.matrix2.y_axis.y)
            + f64::from(m.translation.y),
    );
    let fp = texture.footprint(Vec2::new(uv.0.value() as f32, uv.1.value() as f32))?;
    let [t00, t10, t01, t11] = fp.texels.map(V3::<f64>::from_rgb);
    let tex = if fp.bilinear {
        let fx = uv.0 * fp.size[0] - 0.5 - fp.origin[0];
        let fy = uv.1 * fp.size[1] - 0.5 - fp.origin[1];
        // Texels are constants: the row lerps take mixed products.
        let lerp_c = |p: V3<f64>, q: V3<f64>, f: T| (q - p).times(f).add_c(p);
        let lerp = |p: V3<T>, q: V3<T>, f: T| p + (q - p) * f;
        lerp(lerp_c(t00, t10, fx), lerp_c(t01, t11, fx), fy)
    } else {
        V3::cst(t00)
    };
    let vertex_color = mesh
        .color_at(tri, Vec2::new(b1.value() as f32, b2.value() as f32))
        .truncate();
    let base = tex.mul_c(V3::from_rgb(material.base_color * vertex_color));
    Some(V3::new(
        base.x.clamp_c(0.0, 1.0),
        base.y.clamp_c(0.0, 1.0),
        base.z.clamp_c(0.0, 1.0),
    ))
}
