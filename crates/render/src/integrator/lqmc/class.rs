//! Path classes, breakup-point weights and explored dimensions of LQMC rendering (Tessari et
//! al., section 3.3 "Adaptive number of samples" / "Adaptive dimensionality" and section 4
//! "Parameters"): every decision here is a function of the path alone, so every member of a
//! lattice set can recompute it and be rejected if it differs from the seed's.

use glam::Vec3A;

use super::LqmcParams;
use crate::camera::Camera;
use crate::integrator::vertex_path::{bounce_dim, positive, EventKind, PathEvent, PathVertex};

/// The class of a path (section 4 "Parameters"): it selects `N`, the tile counts and the
/// breakup rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PathClass {
    /// Everything else: `N = 23`.
    Normal,
    /// A (near) diffuse vertex followed by a (near) specular chain to the light: `N = 97`,
    /// finer image tiles, coarser direction tiles.
    Caustic,
    /// The first vertex is out of focus (circle of confusion above the threshold): `N = 23`,
    /// the breakup point prefers `b = 0` (a new lens point reconnected to `z_1`).
    DepthOfField,
    /// Next-event estimation that is neither caustic nor out of focus: splatted unexplored
    /// ("we are very careful not to explore the sample"), or with
    /// [`LqmcParams::explore_nee`] explored with `N = 7` and the normal tiles.
    Nee,
    /// Too short to explore (the camera sees an emitter, `L < 2`): splatted directly.
    Direct,
}

/// Roughness of a vertex for the breakup CDF: the BSDF's GGX alpha (Lambertian 1, smooth 0).
#[inline]
pub(crate) fn vertex_roughness(v: &PathVertex) -> f32 {
    v.bsdf.roughness()
}

/// Circle of confusion of a camera-ray hit point at `p` (world) in pixels:
/// `R |z - f| / (z f)` on the film at distance 1, scaled to raster units; 0 for a pinhole.
#[must_use]
pub(crate) fn circle_of_confusion(camera: &Camera, p: Vec3A, time: f32) -> f32 {
    let radius = camera.lens_radius();
    if radius <= 0.0 {
        return 0.0;
    }
    let pose = camera.pose_at(time);
    let z = pose.to_camera(p - pose.origin).z;
    let f = camera.focus_distance();
    if !positive(z) {
        return 0.0;
    }
    let pixels_per_unit =
        (camera.width() as f32 * camera.height() as f32 / camera.film_area()).sqrt();
    radius * (z - f).abs() / (z * f) * pixels_per_unit
}

/// The class of the path whose surface vertices have roughness `rough[k - 1]` (`k = 1..L-1`;
/// the last vertex `z_L`, an emitter or light sample, counts as rough) for an event of
/// length `L`, with circle of confusion `coc` (pixels) at `z_1`.
#[must_use]
pub(crate) fn classify(params: &LqmcParams, rough: &[f32], is_nee: bool, coc: f32) -> PathClass {
    let length = rough.len() + 1;
    if length < 2 {
        return PathClass::Direct;
    }
    let t = params.specular_roughness;
    // Caustic: the last scattering vertex is near specular and an earlier one is rough.
    let last = rough[rough.len() - 1];
    let caustic = last < t && rough[..rough.len() - 1].iter().any(|&r| r >= t);
    if caustic {
        PathClass::Caustic
    } else if coc > params.dof_coc_pixels {
        PathClass::DepthOfField
    } else if is_nee {
        PathClass::Nee
    } else {
        PathClass::Normal
    }
}

/// Breakup weights `w_b`, `b = 0..=L` into `weights[b]` (section 3.3: a CDF over the
/// minimum roughness of `z_b` and `z_{b+1}`; `z_L` counts as rough). `b = 0` (a new lens
/// point reconnected to the static `z_1`: only the aperture is explored) is for depth of
/// field only, with the authors' weight [`LqmcParams::dof_lens_weight`]; `b = L` (re-trace
/// the whole path, no static suffix) gets weight 1 only if every other weight is 0 (all
/// connections would touch a specular vertex: the authors' "force a full retrace").
pub(crate) fn breakup_weights(
    params: &LqmcParams,
    rough: &[f32],
    class: PathClass,
    weights: &mut Vec<f64>,
) {
    weights.clear();
    let length = rough.len() + 1;
    weights.push(if class == PathClass::DepthOfField {
        params.dof_lens_weight
    } else {
        0.0
    });
    for b in 1..length {
        let rb = rough[b - 1];
        let rn = if b + 1 < length { rough[b] } else { 1.0 };
        weights.push(f64::from(rb.min(rn)));
    }
    let any = weights.iter().any(|&w| w > 0.0);
    weights.push(if any { 0.0 } else { 1.0 });
}

/// What a lattice set explores: `(dimension, tiles)` pairs in lattice order (section 3.3 /
/// the authors' order: image plane first, then aperture, time, then the BSDF directions at
/// `z_1 .. z_{b-1}`, and for a full re-trace of an NEE path the light position; for `b = 0`
/// the aperture only, Fig. 7's "aperture only"). Image dimensions are global image
/// coordinates (dimension 0 = x / width, 1 = y / height).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Layout {
    /// `(dimension of the seed's numbers, tiles)`.
    pub dims: Vec<(usize, u32)>,
}

impl Layout {
    /// The layout for breakup `b` of an event of length `L = event.length()` in `class`.
    pub(crate) fn build(
        &mut self,
        params: &LqmcParams,
        camera: &Camera,
        class: PathClass,
        event: &PathEvent,
        b: usize,
    ) {
        self.dims.clear();
        let caustic = class == PathClass::Caustic;
        if b == 0 {
            let k = if caustic {
                params.aperture_tiles_caustic
            } else {
                params.aperture_tiles
            };
            self.dims.push((2, k));
            self.dims.push((3, k));
            return;
        }
        let kx = if caustic {
            params.image_tiles_caustic
        } else {
            params.image_tiles
        };
        let ky = ((f64::from(kx) * f64::from(camera.height()) / f64::from(camera.width())).round()
            as u32)
            .max(1);
        self.dims.push((0, kx));
        self.dims.push((1, ky));
        if camera.lens_radius() > 0.0 {
            let k = if caustic {
                params.aperture_tiles_caustic
            } else {
                params.aperture_tiles
            };
            self.dims.push((2, k));
            self.dims.push((3, k));
        }
        let (open, close) = camera.shutter();
        if close > open {
            self.dims.push((4, params.time_tiles));
        }
        let kd = if caustic {
            params.direction_tiles_caustic
        } else {
            params.direction_tiles
        };
        for k in 1..b {
            self.dims.push((bounce_dim(k) + 4, kd));
            self.dims.push((bounce_dim(k) + 5, kd));
        }
        if let EventKind::Nee(_) = event.kind {
            if b == event.length() {
                let kl = params.light_tiles;
                self.dims.push((bounce_dim(event.vertex) + 1, kl));
                self.dims.push((bounce_dim(event.vertex) + 2, kl));
            }
        }
    }

    /// The tile counts in lattice order.
    pub(crate) fn tiles(&self) -> impl Iterator<Item = u32> + '_ {
        self.dims.iter().map(|&(_, k)| k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_and_breakup_weights() {
        let p = LqmcParams::default();
        // camera -> diffuse -> glass -> light: caustic; b = 1 touches glass, b = 2 too:
        // only the full re-trace is left.
        assert_eq!(classify(&p, &[1.0, 0.0], false, 0.0), PathClass::Caustic);
        let mut w = Vec::new();
        breakup_weights(&p, &[1.0, 0.0], PathClass::Caustic, &mut w);
        assert_eq!(w, [0.0, 0.0, 0.0, 1.0]);
        // diffuse -> diffuse -> light: normal, b = 1, 2 equally likely.
        assert_eq!(classify(&p, &[1.0, 1.0], false, 0.0), PathClass::Normal);
        breakup_weights(&p, &[1.0, 1.0], PathClass::Normal, &mut w);
        assert_eq!(w, [0.0, 1.0, 1.0, 0.0]);
        assert_eq!(classify(&p, &[1.0], true, 0.0), PathClass::Nee);
        assert_eq!(classify(&p, &[1.0], true, 5.0), PathClass::DepthOfField);
        assert_eq!(classify(&p, &[], false, 0.0), PathClass::Direct);
        breakup_weights(&p, &[1.0, 0.5], PathClass::DepthOfField, &mut w);
        assert_eq!(w, [p.dof_lens_weight, 0.5, 0.5, 0.0]);
    }
}
