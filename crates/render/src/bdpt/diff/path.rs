//! One MMLT strategy `(s, t)` over [`Real`]: the replayed primary samples, the scene as the
//! evaluator sees it with the light densities, and the driver that builds both subpaths and
//! connects them.
//!
//! Together with `vertex`, `subpath` and `connect` it restates `bdpt::{vertex, subpath,
//! connect}` line by line. Discrete decisions (which triangle a ray hits, visibility, which
//! light, which lobe) are taken by the f32 renderer's own queries on the rounded values;
//! everything continuous is recomputed in `T`.

use glam::{Vec2, Vec3A};

use super::bsdf;
use super::geometry::{Camera, Frame};
use super::vertex::Vertex;
use crate::autodiff::{Real, V3};
use crate::bdpt::{MisHeuristic, VertexKind};
use crate::light::{AreaLight, LightRef};
use crate::scene::Scene;

/// Replays the primary samples of one state: stream `s`'s `k`-th number is
/// `values[s + streams k]` (the interleaved layout of `pss::PssState`), made a variable of
/// lane `lanes[s] + j` if it is the `j`-th continuous number of its stream, a constant if bit
/// `k` of `discrete[s]` marks it discrete.
pub(super) struct Replay<'a, T> {
    pub(super) values: &'a [f64],
    pub(super) streams: usize,
    pub(super) lanes: [usize; 3],
    pub(super) discrete: [u64; 3],
    pub(super) make: fn(f64, usize) -> T,
    pub(super) stream: usize,
    pub(super) cursor: [usize; 3],
    /// Set when a number beyond `values` was requested.
    pub(super) overrun: bool,
    /// A hash of the discrete decisions taken (triangles hit, lights chosen, lobes).
    pub(super) decisions: u64,
}

impl<T: Real> Replay<'_, T> {
    pub(super) fn start(&mut self, stream: usize) {
        self.stream = stream.min(self.streams.saturating_sub(1)).min(2);
    }

    pub(super) fn next(&mut self) -> T {
        let s = self.stream;
        let k = self.cursor[s];
        self.cursor[s] += 1;
        let tags = self.discrete[s];
        match self.values.get(s + self.streams * k) {
            Some(&v) if k < 64 && tags & (1u64 << k) != 0 => T::cst(v),
            Some(&v) => {
                // Continuous numbers before this one in its stream.
                let below = if k < 64 { (1u64 << k) - 1 } else { u64::MAX };
                let j = k - (tags & below).count_ones() as usize;
                (self.make)(v, self.lanes[s] + j)
            }
            None => {
                self.overrun = true;
                T::cst(0.5)
            }
        }
    }

    /// Records a discrete decision.
    pub(super) fn decide(&mut self, what: u64) {
        self.decisions = mcmc_core::seed::mix64(self.decisions ^ what);
    }

    pub(super) fn next2(&mut self) -> (T, T) {
        let a = self.next();
        (a, self.next())
    }
}

/// Most vertices of a path the evaluator handles (depth 4): the subpaths live on the stack.
pub(super) const MAX_DIFF_VERTICES: usize = 6;

/// Why the evaluation gave no value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Stop {
    /// The strategy carries no light.
    Zero,
    /// The path meets something the evaluator does not restate.
    Unsupported,
}
/// The scene as the evaluator sees it.
#[derive(Clone, Copy)]
pub(super) struct Ctx<'s> {
    pub(super) scene: &'s Scene,
    pub(super) camera: Camera,
    /// The MIS weight is computed from the vertices' values and enters as a constant (its
    /// derivatives are not carried).
    pub(super) constant_mis: bool,
}

impl Ctx<'_> {
    pub(super) fn area(&self, light: u32) -> Result<&AreaLight, Stop> {
        match self.scene.lights().get(light) {
            Some(LightRef::Area(l)) => Ok(l),
            _ => Err(Stop::Unsupported),
        }
    }

    pub(super) fn visible<T: Real>(&self, a: &Vertex<T>, b: &Vertex<T>) -> bool {
        let n = |v: &Vertex<T>| {
            if v.on_surface() {
                v.ng.to_a()
            } else {
                Vec3A::ZERO
            }
        };
        self.scene
            .unoccluded_between(a.p.to_a(), n(a), b.p.to_a(), n(b))
    }

    /// Radiance light `l` emits at barycentrics `bary` towards `dir` (`Scene::area_le`): a
    /// constant (texture lookups do not carry derivatives), zero behind one-sided lights.
    pub(super) fn area_le<T: Real>(&self, l: u32, bary: (T, T), dir: V3<T>) -> V3<f64> {
        let b = Vec2::new(bary.0.value() as f32, bary.1.value() as f32);
        V3::from_rgb(self.scene.area_le(l, b, dir.to_a()))
    }

    /// `Vertex::emitted_towards` for area lights (a constant).
    pub(super) fn emitted_towards<T: Real>(&self, v: &Vertex<T>, towards: V3<T>) -> V3<f64> {
        match v.light {
            Some(l) => self.area_le(l, v.bary, (towards - v.p).normalize_or_zero()),
            None => V3::zero(),
        }
    }

    /// `Vertex::pdf_light` for area lights.
    pub(super) fn pdf_light<T: Real>(&self, v: &Vertex<T>, next: &Vertex<T>) -> Result<T, Stop> {
        let Some(light) = v.light else {
            return Ok(T::cst(0.0));
        };
        let w = next.p - v.p;
        let d2 = w.length_squared();
        if d2.value() == 0.0 {
            return Ok(T::cst(0.0));
        }
        let w = w * d2.sqrt().recip();
        let mut pdf = self.light_pdf_dir(light, w)? / d2;
        if next.on_surface() {
            pdf *= w.dot_c(next.ng).abs();
        }
        Ok(pdf)
    }

    /// `Lights::pdf_le`'s directional density for an area light.
    fn light_pdf_dir<T: Real>(&self, light: u32, dir: V3<T>) -> Result<T, Stop> {
        let l = self.area(light)?;
        let cos = dir.dot_c(V3::from_a(l.normal));
        Ok(if l.two_sided {
            cos.abs() * (0.5 / std::f64::consts::PI)
        } else {
            cos.max_c(0.0) / std::f64::consts::PI
        })
    }

    /// `Vertex::pdf_light_origin` for area lights: selection probability over area.
    pub(super) fn pdf_light_origin(&self, light: u32) -> Result<f64, Stop> {
        let l = self.area(light)?;
        Ok(f64::from(self.scene.lights().selection_pmf(light)) / f64::from(l.area))
    }

    /// `Vertex::pdf`.
    pub(super) fn pdf<T: Real>(
        &self,
        v: &Vertex<T>,
        prev: Option<&Vertex<T>>,
        next: &Vertex<T>,
    ) -> Result<T, Stop> {
        if v.kind == VertexKind::Light {
            return self.pdf_light(v, next);
        }
        let wn = next.p - v.p;
        if wn.length_squared().value() == 0.0 {
            return Ok(T::cst(0.0));
        }
        let wn = wn.normalize_or_zero();
        let pdf = match v.kind {
            VertexKind::Camera => self.camera.pdf_dir(v.p, wn, v.time),
            _ => {
                let (Some(b), Some(prev)) = (v.bsdf, prev) else {
                    return Ok(T::cst(0.0));
                };
                let wp = (prev.p - v.p).normalize_or_zero();
                bsdf::pdf(&b, v.frame.to_local(wp), v.frame.to_local(wn))
            }
        };
        Ok(v.convert_density(pdf, next))
    }

    /// `bdpt::sample_strategy` for a fixed depth: the MIS-weighted contribution times the
    /// number of strategies, or why there is none.
    pub(super) fn sample_strategy<T: Real>(
        &self,
        u: &mut Replay<'_, T>,
        depth: usize,
        image_size: Vec2,
        heuristic: MisHeuristic,
    ) -> Result<(V3<T>, usize, usize), Stop> {
        if depth + 2 > MAX_DIFF_VERTICES {
            return Err(Stop::Unsupported);
        }
        u.start(2);
        let (n_strategies, s, t) = if depth == 0 {
            (1usize, 0usize, 2usize)
        } else {
            let n = depth + 2;
            let x = u.next().value() as f32;
            let s = ((x * n as f32) as usize).min(n - 1);
            (n, s, n - s)
        };
        u.start(0);
        let raster = u.next2();
        let raster = (
            raster.0 * f64::from(image_size.x),
            raster.1 * f64::from(image_size.y),
        );
        let z = Frame::<f64>::from_normal(V3::from_a(Vec3A::Z)).over_t();
        let blank = Vertex::camera(V3::zero(), z, V3::zero(), T::cst(0.0));
        // One array for both subpaths (`s + t <= MAX_DIFF_VERTICES`): half the vertices to
        // initialise, and a vertex of dual numbers is large.
        let mut vertices = [blank; MAX_DIFF_VERTICES];
        let (camera, light) = vertices.split_at_mut(t);
        if self.camera_subpath(u, raster, t, camera)? != t {
            return Err(Stop::Zero);
        }
        let time = camera[0].time;
        if s != 1 && self.light_subpath(u, time, s, light)? != s {
            return Err(Stop::Zero);
        }
        let l = self.connect(light, camera, s, t, u, heuristic)?;
        Ok((l.scale(n_strategies as f64), s, t))
    }
}
