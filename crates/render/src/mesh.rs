//! Indexed triangle meshes in world space: positions, shading normals, UVs and a material per
//! triangle (optionally vertex colours, tangents and a second UV set), plus a few procedural
//! shapes (quads, boxes, spheres) for built-in scenes and tests.

use glam::{Mat3, Mat4, Vec2, Vec3, Vec3A, Vec4};

/// An indexed triangle mesh in world space.
///
/// Every vertex has a position, a shading normal (`Vec3A::ZERO` = none: the geometric normal
/// is used) and a texture coordinate. Triangles are counter-clockwise seen from their front
/// side (glTF's convention), so the geometric normal is `(p1 - p0) x (p2 - p0)`.
///
/// Vertex colours, tangents and the second UV set are optional: each of these vectors is
/// either empty (no vertex has one; nothing is stored) or has one entry per vertex, vertices
/// without one holding the neutral value (white, zero tangent, zero UV). The `set_*` methods
/// create a vector on first use and [`Mesh::add_vertex`] keeps existing ones in step.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3A>,
    /// Per-vertex unit shading normals, or zero where the file gave none.
    pub normals: Vec<Vec3A>,
    /// Per-vertex texture coordinates (glTF convention: `(0, 0)` = top-left of the image).
    pub uvs: Vec<Vec2>,
    /// Second per-vertex texture coordinates (glTF `TEXCOORD_1`), or empty.
    pub uvs1: Vec<Vec2>,
    /// Per-vertex linear RGBA colours (glTF `COLOR_0`, white = none), or empty.
    pub colors: Vec<Vec4>,
    /// Per-vertex tangents (glTF `TANGENT`): `xyz` a unit tangent along increasing `u`, `w` the
    /// handedness `±1` (bitangent `= w (normal x tangent)`); zero = none. Or empty.
    pub tangents: Vec<Vec4>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle (into [`crate::scene::Scene::materials`]).
    pub material_ids: Vec<u32>,
}

impl Mesh {
    /// An empty mesh.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Adds a vertex and returns its index.
    pub fn add_vertex(&mut self, position: Vec3A, normal: Vec3A, uv: Vec2) -> u32 {
        let index = self.positions.len() as u32;
        self.positions.push(position);
        self.normals.push(normal);
        self.uvs.push(uv);
        if !self.uvs1.is_empty() {
            self.uvs1.push(Vec2::ZERO);
        }
        if !self.colors.is_empty() {
            self.colors.push(Vec4::ONE);
        }
        if !self.tangents.is_empty() {
            self.tangents.push(Vec4::ZERO);
        }
        index
    }

    /// Sets the second UV set of vertex `v` (creating the set on first use).
    pub fn set_uv1(&mut self, v: u32, uv: Vec2) {
        set_attribute(&mut self.uvs1, self.positions.len(), Vec2::ZERO, v, uv);
    }

    /// Sets the colour of vertex `v` (creating the colours on first use).
    pub fn set_color(&mut self, v: u32, color: Vec4) {
        set_attribute(&mut self.colors, self.positions.len(), Vec4::ONE, v, color);
    }

    /// Sets the tangent of vertex `v` (creating the tangents on first use).
    pub fn set_tangent(&mut self, v: u32, tangent: Vec4) {
        set_attribute(
            &mut self.tangents,
            self.positions.len(),
            Vec4::ZERO,
            v,
            tangent,
        );
    }

    /// Adds a triangle over existing vertices.
    pub fn add_triangle(&mut self, indices: [u32; 3], material: u32) {
        self.triangles.push(indices);
        self.material_ids.push(material);
    }

    /// Adds the planar quad `p0 p1 p2 p3` (counter-clockwise seen from the front) as two
    /// triangles with flat shading normals and UVs spanning `[0, 1]^2`.
    pub fn add_quad(&mut self, p: [Vec3A; 4], material: u32) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let uv = [
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        let i: Vec<u32> = (0..4).map(|k| self.add_vertex(p[k], n, uv[k])).collect();
        self.add_triangle([i[0], i[1], i[2]], material);
        self.add_triangle([i[0], i[2], i[3]], material);
    }

    /// Adds an axis-aligned unit cube `[-0.5, 0.5]^3` transformed by `transform`, faces
    /// pointing outwards.
    pub fn add_box(&mut self, transform: Mat4, material: u32) {
        let c =
            |x: f32, y: f32, z: f32| Vec3A::from(transform.transform_point3(Vec3::new(x, y, z)));
        let h = 0.5;
        let faces = [
            [c(-h, -h, h), c(h, -h, h), c(h, h, h), c(-h, h, h)], // +z
            [c(h, -h, -h), c(-h, -h, -h), c(-h, h, -h), c(h, h, -h)], // -z
            [c(h, -h, h), c(h, -h, -h), c(h, h, -h), c(h, h, h)], // +x
            [c(-h, -h, -h), c(-h, -h, h), c(-h, h, h), c(-h, h, -h)], // -x
            [c(-h, h, h), c(h, h, h), c(h, h, -h), c(-h, h, -h)], // +y
            [c(-h, -h, -h), c(h, -h, -h), c(h, -h, h), c(-h, -h, h)], // -y
        ];
        for f in faces {
            self.add_quad(f, material);
        }
    }

    /// Adds a UV sphere with `rings >= 2` latitude bands and `segments >= 3` longitude
    /// segments (`2 * segments * (rings - 1)` triangles) with smooth shading normals.
    /// `inward` makes the triangles and normals face the centre (the inside of a closed sphere).
    pub fn add_sphere(
        &mut self,
        center: Vec3A,
        radius: f32,
        rings: u32,
        segments: u32,
        material: u32,
        inward: bool,
    ) {
        let rings = rings.max(2);
        let segments = segments.max(3);
        let sign = if inward { -1.0 } else { 1.0 };
        let base = self.positions.len() as u32;
        for r in 0..=rings {
            let v = r as f32 / rings as f32;
            let theta = v * std::f32::consts::PI;
            for s in 0..=segments {
                let u = s as f32 / segments as f32;
                let phi = u * std::f32::consts::TAU;
                let d = Vec3A::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                self.add_vertex(center + d * radius, d * sign, Vec2::new(u, v));
            }
        }
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let a = base + r * row + s;
                let b = a + 1;
                let c = a + row;
                let d = c + 1;
                // Outward-facing (counter-clockwise seen from outside) order is (a, b, d) and
                // (a, d, c); the degenerate triangle at each pole is skipped.
                let tris = [[a, b, d], [a, d, c]];
                for (k, t) in tris.into_iter().enumerate() {
                    if (r == 0 && k == 0) || (r == rings - 1 && k == 1) {
                        continue;
                    }
                    let t = if inward { [t[0], t[2], t[1]] } else { t };
                    self.add_triangle(t, material);
                }
            }
        }
    }

    /// Appends `other` transformed by `transform` (normals by its inverse transpose, tangents
    /// by its linear part with the handedness flipped by a mirroring transform), shifting its
    /// material ids by `material_offset`. Optional attributes present in either mesh are kept
    /// (neutral values where one mesh had none).
    pub fn append_transformed(&mut self, other: &Mesh, transform: Mat4, material_offset: u32) {
        let base = self.positions.len() as u32;
        let linear = Mat3::from_mat4(transform);
        let normal_matrix = linear.inverse().transpose();
        let flip = transform.determinant() < 0.0;
        for i in 0..other.positions.len() {
            let p = transform.transform_point3(Vec3::from(other.positions[i]));
            let n = normal_matrix * Vec3::from(other.normals[i]);
            let v = self.add_vertex(p.into(), n.normalize_or_zero().into(), other.uvs[i]);
            if let Some(&uv) = other.uvs1.get(i) {
                self.set_uv1(v, uv);
            }
            if let Some(&c) = other.colors.get(i) {
                self.set_color(v, c);
            }
            if let Some(&t) = other.tangents.get(i) {
                let xyz = (linear * t.truncate()).normalize_or_zero();
                let w = if flip { -t.w } else { t.w };
                let t = if xyz == Vec3::ZERO {
                    Vec4::ZERO
                } else {
                    xyz.extend(w)
                };
                self.set_tangent(v, t);
            }
        }
        for (t, &m) in other.triangles.iter().zip(&other.material_ids) {
            let t = t.map(|i| i + base);
            let t = if flip { [t[0], t[2], t[1]] } else { t };
            self.add_triangle(t, m + material_offset);
        }
    }

    /// The three vertex positions of triangle `tri`.
    #[inline]
    #[must_use]
    pub fn vertices(&self, tri: usize) -> [Vec3A; 3] {
        let [a, b, c] = self.triangles[tri];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Interpolates the per-vertex values `attr` of triangle `tri` at barycentrics `b`
    /// (`(b1, b2)`, with `b0 = max(1 - b1 - b2, 0)` as in the hit point).
    #[inline]
    fn interpolate<T>(&self, attr: &[T], tri: usize, b: Vec2) -> T
    where
        T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        let [i0, i1, i2] = self.triangles[tri].map(|i| i as usize);
        let b0 = (1.0 - b.x - b.y).max(0.0);
        attr[i0] * b0 + attr[i1] * b.x + attr[i2] * b.y
    }

    /// `TEXCOORD_0` of triangle `tri` at barycentrics `b`.
    #[inline]
    #[must_use]
    pub fn uv_at(&self, tri: usize, b: Vec2) -> Vec2 {
        self.interpolate(&self.uvs, tri, b)
    }

    /// `TEXCOORD_1` of triangle `tri` at barycentrics `b` (`TEXCOORD_0` if the mesh has no
    /// second UV set).
    #[inline]
    #[must_use]
    pub fn uv1_at(&self, tri: usize, b: Vec2) -> Vec2 {
        if self.uvs1.is_empty() {
            self.uv_at(tri, b)
        } else {
            self.interpolate(&self.uvs1, tri, b)
        }
    }

    /// Both UV sets `[TEXCOORD_0, TEXCOORD_1]` of triangle `tri` at barycentrics `b` (see
    /// [`Mesh::uv1_at`]).
    #[inline]
    #[must_use]
    pub fn tex_coords(&self, tri: usize, b: Vec2) -> [Vec2; 2] {
        let uv0 = self.uv_at(tri, b);
        if self.uvs1.is_empty() {
            [uv0; 2]
        } else {
            [uv0, self.interpolate(&self.uvs1, tri, b)]
        }
    }

    /// The vertex colour (linear RGBA) of triangle `tri` at barycentrics `b`; white if the mesh
    /// has no colours.
    #[inline]
    #[must_use]
    pub fn color_at(&self, tri: usize, b: Vec2) -> Vec4 {
        if self.colors.is_empty() {
            Vec4::ONE
        } else {
            self.interpolate(&self.colors, tri, b)
        }
    }

    /// The area of triangle `tri`.
    #[must_use]
    pub fn area(&self, tri: usize) -> f32 {
        let [a, b, c] = self.vertices(tri);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Removes triangles that cannot be rendered: an index out of range, a non-finite or
    /// absurdly large (> 1e18) coordinate, or zero area. Vertex attributes that are not finite
    /// are reset (normals and tangents to zero, UVs to the origin, colours to white); colours
    /// are clamped to `[0, inf)` (alpha to `[0, 1]`) and tangents normalised with a handedness
    /// of `±1`. Returns the number of triangles removed.
    pub fn remove_invalid(&mut self) -> usize {
        let n = self.positions.len();
        self.normals.resize(n, Vec3A::ZERO);
        self.uvs.resize(n, Vec2::ZERO);
        if !self.uvs1.is_empty() {
            self.uvs1.resize(n, Vec2::ZERO);
        }
        for uv in &mut self.uvs1 {
            if !uv.is_finite() {
                *uv = Vec2::ZERO;
            }
        }
        if !self.colors.is_empty() {
            self.colors.resize(n, Vec4::ONE);
        }
        for c in &mut self.colors {
            *c = if c.is_finite() {
                let rgb = c.truncate().max(Vec3::ZERO);
                rgb.extend(c.w.clamp(0.0, 1.0))
            } else {
                Vec4::ONE
            };
        }
        if !self.tangents.is_empty() {
            self.tangents.resize(n, Vec4::ZERO);
        }
        for t in &mut self.tangents {
            let xyz = if t.is_finite() {
                t.truncate().normalize_or_zero()
            } else {
                Vec3::ZERO
            };
            *t = if xyz == Vec3::ZERO {
                Vec4::ZERO
            } else {
                xyz.extend(if t.w < 0.0 { -1.0 } else { 1.0 })
            };
        }
        for nrm in &mut self.normals {
            *nrm = if nrm.is_finite() {
                nrm.normalize_or_zero()
            } else {
                Vec3A::ZERO
            };
        }
        for uv in &mut self.uvs {
            if !uv.is_finite() {
                *uv = Vec2::ZERO;
            }
        }
        let before = self.triangles.len();
        let mut keep_tris = Vec::with_capacity(before);
        let mut keep_mats = Vec::with_capacity(before);
        for (t, &m) in self.triangles.iter().zip(&self.material_ids) {
            if t.iter().any(|&i| i as usize >= n) {
                continue;
            }
            let p = t.map(|i| self.positions[i as usize]);
            let sane = p
                .iter()
                .all(|v| v.is_finite() && v.abs().max_element() < 1e18);
            if !sane {
                continue;
            }
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let len2 = cross.length_squared();
            if !(len2 > 0.0 && len2.is_finite()) {
                continue;
            }
            keep_tris.push(*t);
            keep_mats.push(m);
        }
        self.triangles = keep_tris;
        self.material_ids = keep_mats;
        before - self.triangles.len()
    }

    /// The axis-aligned bounds `(min, max)` of all referenced vertices, or `None` for an empty
    /// mesh.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3A, Vec3A)> {
        let mut it = self.triangles.iter().flatten();
        let first = self.positions[*it.next()? as usize];
        let (mut lo, mut hi) = (first, first);
        for &i in it {
            let p = self.positions[i as usize];
            lo = lo.min(p);
            hi = hi.max(p);
        }
        Some((lo, hi))
    }
}

/// Sets `attr[v] = value`, first growing an empty `attr` to `n` entries of `neutral`. A vertex
/// index out of range is ignored.
fn set_attribute<T: Copy>(attr: &mut Vec<T>, n: usize, neutral: T, v: u32, value: T) {
    if attr.len() < n {
        attr.resize(n, neutral);
    }
    if let Some(slot) = attr.get_mut(v as usize) {
        *slot = value;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_winding_and_area() {
        let mut m = Mesh::new();
        m.add_sphere(Vec3A::ZERO, 2.0, 32, 64, 0, false);
        assert_eq!(m.triangle_count(), 2 * 64 * 31);
        let mut area = 0.0f64;
        for t in 0..m.triangle_count() {
            let [a, b, c] = m.vertices(t);
            let n = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            assert!(n.dot(centroid) > 0.0, "triangle {t} faces inwards");
            area += f64::from(m.area(t));
        }
        let exact = 4.0 * std::f64::consts::PI * 4.0;
        assert!((area - exact).abs() / exact < 0.01, "{area} vs {exact}");

        let mut inner = Mesh::new();
        inner.add_sphere(Vec3A::ZERO, 1.0, 8, 16, 0, true);
        for t in 0..inner.triangle_count() {
            let [a, b, c] = inner.vertices(t);
            assert!((b - a).cross(c - a).dot(a + b + c) < 0.0);
        }
    }

    #[test]
    fn box_faces_point_outwards() {
        let mut m = Mesh::new();
        m.add_box(Mat4::from_scale(Vec3::splat(2.0)), 3);
        assert_eq!(m.triangle_count(), 12);
        for t in 0..12 {
            let [a, b, c] = m.vertices(t);
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
            assert!((m.area(t) - 2.0).abs() < 1e-5);
        }
        assert_eq!(m.material_ids, vec![3; 12]);
    }

    #[test]
    fn invalid_triangles_are_removed() {
        let mut m = Mesh::new();
        let a = m.add_vertex(Vec3A::ZERO, Vec3A::Z, Vec2::ZERO);
        let b = m.add_vertex(Vec3A::X, Vec3A::splat(f32::NAN), Vec2::splat(f32::INFINITY));
        let c = m.add_vertex(Vec3A::Y, Vec3A::Z, Vec2::ZERO);
        let d = m.add_vertex(Vec3A::splat(f32::NAN), Vec3A::Z, Vec2::ZERO);
        m.add_triangle([a, b, c], 0); // fine
        m.add_triangle([a, a, c], 0); // degenerate
        m.add_triangle([a, b, d], 0); // NaN
        m.add_triangle([a, b, 99], 0); // out of range
        assert_eq!(m.remove_invalid(), 3);
        assert_eq!(m.triangle_count(), 1);
        assert_eq!(m.normals[1], Vec3A::ZERO);
        assert_eq!(m.uvs[1], Vec2::ZERO);
    }

    #[test]
    fn attribute_interpolation() {
        let mut m = Mesh::new();
        let a = m.add_vertex(Vec3A::ZERO, Vec3A::Z, Vec2::ZERO);
        let b = m.add_vertex(Vec3A::X, Vec3A::Z, Vec2::X);
        let c = m.add_vertex(Vec3A::Y, Vec3A::Z, Vec2::Y);
        m.add_triangle([a, b, c], 0);
        let bc = Vec2::new(0.25, 0.5);
        assert_eq!(m.uv_at(0, bc), Vec2::new(0.25, 0.5));
        assert_eq!(m.tex_coords(0, bc), [Vec2::new(0.25, 0.5); 2]);
        assert_eq!(m.color_at(0, bc), Vec4::ONE);
        m.set_uv1(c, Vec2::splat(2.0));
        m.set_color(a, Vec4::new(0.0, 0.0, 0.0, 0.0));
        assert_eq!(m.uv1_at(0, bc), Vec2::splat(1.0));
        assert_eq!(m.color_at(0, bc), Vec4::new(0.75, 0.75, 0.75, 0.75));
    }

    #[test]
    fn optional_attributes_stay_in_step() {
        let mut m = Mesh::new();
        let a = m.add_vertex(Vec3A::ZERO, Vec3A::Z, Vec2::ZERO);
        assert!(m.colors.is_empty() && m.tangents.is_empty() && m.uvs1.is_empty());
        let b = m.add_vertex(Vec3A::X, Vec3A::Z, Vec2::X);
        m.set_color(b, Vec4::new(1.0, 0.0, 0.0, 0.5));
        assert_eq!(m.colors, vec![Vec4::ONE, Vec4::new(1.0, 0.0, 0.0, 0.5)]);
        let c = m.add_vertex(Vec3A::Y, Vec3A::Z, Vec2::Y);
        assert_eq!(m.colors[c as usize], Vec4::ONE);
        m.set_tangent(a, Vec4::new(2.0, 0.0, 0.0, -3.0));
        m.set_uv1(c, Vec2::splat(f32::NAN));
        m.set_color(a, Vec4::new(-1.0, f32::NAN, 0.0, 1.0));
        m.add_triangle([a, b, c], 0);
        assert_eq!(m.remove_invalid(), 0);
        assert_eq!(m.tangents[0], Vec4::new(1.0, 0.0, 0.0, -1.0));
        assert_eq!(m.tangents[1], Vec4::ZERO);
        assert_eq!(m.uvs1[2], Vec2::ZERO);
        assert_eq!(m.colors[0], Vec4::ONE);
    }

    /// Tangents follow the surface under scaling and rotation, and a mirror flips their
    /// handedness so the bitangent `w (n x t)` is the transformed bitangent.
    #[test]
    fn append_transforms_tangents() {
        let mut src = Mesh::new();
        let v = src.add_vertex(Vec3A::ZERO, Vec3A::Z, Vec2::ZERO);
        src.set_tangent(v, Vec4::new(1.0, 0.0, 0.0, 1.0));
        src.set_color(v, Vec4::new(0.2, 0.3, 0.4, 1.0));
        let bitangent = |m: &Mesh, i: usize| {
            let t = m.tangents[i];
            Vec3::from(m.normals[i]).cross(t.truncate()) * t.w
        };
        assert!((bitangent(&src, 0) - Vec3::Y).length() < 1e-6);
        // Mirror in x plus a non-uniform scale and a rotation about z.
        let xf = Mat4::from_rotation_z(0.3) * Mat4::from_scale(Vec3::new(-2.0, 3.0, 1.0));
        let mut dst = Mesh::new();
        dst.add_vertex(Vec3A::ONE, Vec3A::Z, Vec2::ZERO); // a vertex without attributes
        dst.append_transformed(&src, xf, 0);
        assert_eq!(dst.colors.len(), 2);
        assert_eq!(dst.colors[0], Vec4::ONE);
        assert_eq!(dst.colors[1], src.colors[0]);
        assert_eq!(dst.tangents[0], Vec4::ZERO);
        let t = dst.tangents[1];
        let want_t = xf.transform_vector3(Vec3::X).normalize();
        assert!((t.truncate() - want_t).length() < 1e-6, "{t}");
        let want_b = xf.transform_vector3(Vec3::Y).normalize();
        assert!((bitangent(&dst, 1) - want_b).length() < 1e-5);
        assert!(dst.uvs1.is_empty());
    }
}
