//! Light-side sampling in path space: emission directions, the light random walk, and the
//! conversion of its densities into [`Path`]'s (eye-oriented) measure across specular vertices.

use std::f64::consts::{FRAC_1_PI, TAU};

use rand::{Rng, RngExt};

use crate::path::{direction, solid_angle_to_area, Path, Vertex};
use crate::scene::{Bsdfs, Emitters, PathScene, SpecularLobe, SurfacePoint};
use crate::vec3::Vec3;

/// A cosine-weighted direction about `n` from two uniform numbers.
pub(crate) fn cosine_hemisphere(n: Vec3, u: [f64; 2]) -> Vec3 {
    let (t, b) = n.orthonormal_basis();
    let r = u[0].sqrt();
    let phi = TAU * u[1];
    let z = (1.0 - u[0]).max(0.0).sqrt();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * z).normalize()
}

/// Which sides of the geometric normal emit at `p`: `(front, back)`.
fn emitting_sides<S: Emitters + ?Sized>(scene: &S, p: &SurfacePoint) -> (bool, bool) {
    let n = p.geometric_normal;
    (
        !scene.emitted(p, n).is_black(),
        !scene.emitted(p, -n).is_black(),
    )
}

/// The default of [`Emitters::sample_emission_direction`]: cosine-weighted about the
/// geometric normal on each emitting side.
pub(crate) fn cosine_emission_sample<S: Emitters + ?Sized>(
    scene: &S,
    p: &SurfacePoint,
    u: [f64; 2],
) -> Option<(Vec3, f64)> {
    let n = p.geometric_normal;
    let (front, back) = emitting_sides(scene, p);
    let (side, u0, share) = match (front, back) {
        (false, false) => return None,
        (true, false) => (n, u[0], 1.0),
        (false, true) => (-n, u[0], 1.0),
        (true, true) if u[0] < 0.5 => (n, 2.0 * u[0], 0.5),
        (true, true) => (-n, 2.0 * u[0] - 1.0, 0.5),
    };
    let w = cosine_hemisphere(side, [u0.min(1.0), u[1]]);
    let pdf = share * w.dot(side) * FRAC_1_PI;
    (pdf > 0.0).then_some((w, pdf))
}

/// The default of [`Emitters::emission_direction_pdf`].
pub(crate) fn cosine_emission_pdf<S: Emitters + ?Sized>(
    scene: &S,
    p: &SurfacePoint,
    w: Vec3,
) -> f64 {
    let c = w.dot(p.geometric_normal);
    let (front, back) = emitting_sides(scene, p);
    let share = if front && back { 0.5 } else { 1.0 };
    if (c > 0.0 && front) || (c < 0.0 && back) {
        share * c.abs() * FRAC_1_PI
    } else {
        0.0
    }
}

/// `sin^2` of the angle between unit `w` and unit `n`.
fn sin2(w: Vec3, n: Vec3) -> f64 {
    w.cross(n).length_squared()
}

/// The default of [`Bsdfs::specular_jacobian`]: `dω_i / dω_o` from Snell's law with the index
/// ratio read off the refracted direction (`η_o / η_i = sin θ_i / sin θ_o`), or off a probe
/// tilted from the normal when `wo` is too close to it for the ratio to be accurate.
pub(crate) fn snell_jacobian<S: Bsdfs + ?Sized>(
    scene: &S,
    p: &SurfacePoint,
    wo: Vec3,
    lobe: SpecularLobe,
) -> f64 {
    let Some(wi) = scene.specular_direction(p, wo, lobe) else {
        return 0.0;
    };
    if lobe == SpecularLobe::Reflection {
        return 1.0;
    }
    let n = p.shading_normal;
    let (cos_o, cos_i) = (wo.dot(n).abs(), wi.dot(n).abs());
    if !(cos_o > 0.0 && cos_i > 0.0) {
        return 0.0;
    }
    let so2 = sin2(wo, n);
    let ratio2 = if so2 > 1e-6 {
        sin2(wi, n) / so2
    } else {
        // Probe tilted directions on wo's side until one refracts.
        let side = if wo.dot(n) >= 0.0 { n } else { -n };
        let (t, _) = side.orthonormal_basis();
        let probe = [0.5f64, 0.2, 0.05].into_iter().find_map(|a| {
            let w = (side * a.cos() + t * a.sin()).normalize();
            let wt = scene.specular_direction(p, w, lobe)?;
            Some(sin2(wt, n) / sin2(w, n))
        });
        let Some(r) = probe else {
            return 0.0;
        };
        r
    };
    ratio2 * cos_o / cos_i
}

/// One step of a light random walk at `p`: from an emitter point (`toward_light == None`) an
/// emission direction, else a BSDF direction sampled with the direction toward the light-side
/// neighbour `toward_light` as `wo`. Returns the lobe chosen at `p` (for its specular flag) and
/// the hit, or `None` on failure (absorbed, missed the scene).
pub(crate) fn light_step<S: PathScene + ?Sized, R: Rng + ?Sized>(
    scene: &S,
    rng: &mut R,
    p: &SurfacePoint,
    toward_light: Option<Vec3>,
) -> Option<(Option<SpecularLobe>, SurfacePoint)> {
    let (lobe, dir) = match toward_light {
        None => {
            let u = [rng.random(), rng.random()];
            match scene.sample_emission_direction(p, u) {
                Some((w, pdf)) if pdf > 0.0 => (None, w),
                _ => return None,
            }
        }
        Some(neighbour) => {
            let wo = direction(p.position, neighbour);
            let u = [rng.random(), rng.random(), rng.random()];
            let s = scene.sample(p, wo, u)?;
            if s.pdf.is_nan() || s.pdf <= 0.0 {
                return None;
            }
            (s.lobe, s.wi)
        }
    };
    let hit = scene.intersect(p.position, dir)?;
    Some((lobe, hit))
}

/// Extends a light random walk whose vertices are stored in *light order* at
/// `path.vertices[start..]` (`start` holds the emitter point) by one [`light_step`] from the
/// last vertex (setting its specular flag) and pushes the hit. Returns false on failure.
pub(crate) fn extend_light_walk<S: PathScene + ?Sized, R: Rng + ?Sized>(
    scene: &S,
    rng: &mut R,
    path: &mut Path,
    start: usize,
) -> bool {
    let i = path.vertices.len() - 1;
    let toward = (i > start).then(|| path.vertices[i - 1].position());
    let Some((lobe, hit)) = light_step(scene, rng, &path.vertices[i].point, toward) else {
        return false;
    };
    path.vertices[i].specular = lobe;
    path.vertices.push(Vertex {
        point: hit,
        specular: None,
    });
    true
}

/// `ln` of the density, with respect to [`Path`]'s measure, with which a light random walk at
/// `v[j]` (`1 <= j`, `v` camera first, `v[len - 1]` the emitter) produces `v[j - 1]`:
///
/// - at the emitter: the emission direction pdf times `J = |cos θ_{j-1}| / r^2`;
/// - at a non-specular vertex: the BSDF pdf with the light-side direction as `wo`, times `J`;
/// - at a specular vertex: the lobe probability times the Jacobian between the light walk's
///   measure and [`Path`]'s, `|∂x_{j+1} / ∂x_{j-1}|` at fixed `x_j`
///   `= J(x_j -> x_{j-1}) / J(x_j -> x_{j+1}) dω_{j+1} / dω_{j-1}`. [`Path`]'s measure is
///   area at the vertex after each non-specular one; a light walk measures area at the vertex
///   *before* each non-specular one, so across a specular vertex the two swap which
///   neighbour carries the area; along a chain of specular vertices the Jacobians multiply
///   (each map between consecutive pairs `(x_{j-1}, x_j) -> (x_j, x_{j+1})` is triangular), so
///   curvature never enters (Veach 1997, section 8.2).
pub(crate) fn log_light_scatter_density<S: PathScene + ?Sized>(
    scene: &S,
    v: &[Vertex],
    j: usize,
) -> f64 {
    let k = v.len();
    let p = &v[j].point;
    let to_eye = direction(p.position, v[j - 1].position());
    let j_eye = solid_angle_to_area(p.position, &v[j - 1].point);
    let q = if j == k - 1 {
        scene.emission_direction_pdf(p, to_eye) * j_eye
    } else {
        let to_light = direction(p.position, v[j + 1].position());
        match v[j].specular {
            Some(lobe) => {
                scene.specular_pdf(p, to_light, lobe) * log_specular_conversion(scene, v, j).exp()
            }
            None => scene.pdf(p, to_light, to_eye) * j_eye,
        }
    };
    if q.is_nan() {
        f64::NEG_INFINITY
    } else {
        q.ln()
    }
}

/// `ln` of the Jacobian from a light walk's measure to [`Path`]'s across the specular vertex
/// `v[j]` (`1 <= j < len - 1`): `J(x_j -> x_{j-1}) / J(x_j -> x_{j+1}) dω_{j+1} / dω_{j-1}`
/// (see [`log_light_scatter_density`]); `NEG_INFINITY` if `v[j]` is not specular or a factor
/// vanishes.
pub(crate) fn log_specular_conversion<S: PathScene + ?Sized>(
    scene: &S,
    v: &[Vertex],
    j: usize,
) -> f64 {
    let Some(lobe) = v[j].specular else {
        return f64::NEG_INFINITY;
    };
    let p = &v[j].point;
    let j_light = solid_angle_to_area(p.position, &v[j + 1].point);
    if j_light.is_nan() || j_light <= 0.0 {
        return f64::NEG_INFINITY;
    }
    let j_eye = solid_angle_to_area(p.position, &v[j - 1].point);
    let to_eye = direction(p.position, v[j - 1].position());
    let q = j_eye / j_light * scene.specular_jacobian(p, to_eye, lobe);
    if q.is_nan() {
        f64::NEG_INFINITY
    } else {
        q.ln()
    }
}
