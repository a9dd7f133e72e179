//! The toy target and state source the render-loop tests share: a ramp on the unit square
//! splatted on a one-row image, and uniform points from a key.

#![allow(dead_code)]

use mcmc_core::render_loop::{IndependentStates, Splat};
use mcmc_core::Target;

/// `f(u) = gain (1 + u0)` on the unit square where `u0 >= cut` (zero elsewhere), splatted at
/// `(pixels u0, 0.5)` on a `pixels` x 1 image.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ramp {
    /// Where the support starts along `u0`.
    pub(crate) cut: f64,
    /// The factor of the density.
    pub(crate) gain: f64,
    /// Width of the image in pixels.
    pub(crate) pixels: f32,
}

/// A ramp over the whole square on a 4 x 1 image.
pub(crate) const RAMP: Ramp = Ramp {
    cut: 0.0,
    gain: 1.0,
    pixels: 4.0,
};

impl Target for Ramp {
    type State = Vec<f64>;
    type Payload = Option<Splat>;
    fn evaluate(&self, u: &mut Vec<f64>, out: &mut Option<Splat>) -> f64 {
        if !u.iter().all(|v| (0.0..1.0).contains(v)) || u[0] < self.cut {
            *out = None;
            return f64::NEG_INFINITY;
        }
        let f = self.gain * (1.0 + u[0]);
        *out = Some(Splat {
            raster: [self.pixels * u[0] as f32, 0.5],
            rgb: [f as f32; 3],
        });
        f.ln()
    }
}

/// Independent uniform points of the unit square from a key.
pub(crate) struct Uniform;

impl IndependentStates<Vec<f64>> for Uniform {
    fn empty(&self) -> Vec<f64> {
        vec![0.0; 2]
    }
    fn independent(&self, key: u64, u: &mut Vec<f64>) {
        let h = |k: u64| (mcmc_core::seed::mix64(k) >> 11) as f64 / (1u64 << 53) as f64;
        u.clear();
        u.extend([h(key), h(key ^ 0x55)]);
    }
}
