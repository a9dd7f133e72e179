//! The image-plane (raster) mutation: a step that moves only the two primary samples a path
//! generator turns into the raster position, by a wider kernel measured in pixels.

use mcmc_core::seed::mix64;
use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::mutation::{KelemenParams, SmallMutation};
use crate::noise::uniform;
use crate::state::{Pending, PssState};
use crate::PssError;

/// Salt that separates the raster step's own draws from the catch-up draws of its candidate.
const RASTER_SALT: u64 = 0x7261_7374_6572_2121;

/// Default raster-step probability (`--raster-mutation on`, and the renderer's PSSMLT
/// default): the fraction of the small steps of [`crate::PssmltProposal`] that become raster
/// steps. Chosen over 0.25 by the equal-mutation comparison in `docs/performance.md`,
/// "Raster mutation".
pub const RASTER_DEFAULT_PROBABILITY: f64 = 0.5;

/// Parameters of the raster mutation ([`RasterStep`]), in image units.
///
/// # The reading chosen
///
/// Kelemen et al. 2002 (section 4.1) perturb every primary sample by the same exponential
/// kernel, so the raster position of a path moves by at most `s2` of the image side per step
/// (1/64: 2 pixels at 128 pixels), however smooth the contribution is across the image.
/// LuxCore's METROPOLIS sampler (`src/slg/samplers/metropolis.cpp`, property
/// `sampler.metropolis.imagemutationrate`, default 0.1) mutates the first two samples, the
/// image x and y, with their own range, a fraction of the image, in *every* small step
/// together with the other samples. We read it as a separate move instead: with probability
/// `probability` a small step of [`crate::PssmltProposal`] becomes a **raster step** that
/// moves only those two samples and keeps every other primary sample, so that a chain can slide
/// a path across the image without perturbing its scattering decisions (the primary-sample
/// analogue of Veach's lens perturbation). Each raster coordinate moves by Kelemen's kernel
/// with a magnitude log-uniform between `min_pixels` pixels and `max_fraction` of that image
/// side, with a uniform sign, wrapped on the torus: symmetric, with the exact density of
/// [`RasterStep`]. The mixture keeps a state-independent selection, so it stays symmetric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterParams {
    /// Probability that a small step is a raster step instead, in `[0, 1]`. Default 0: off
    /// (the library default; the renderer turns it on for PSSMLT,
    /// `render::methods::PssmltSettings::raster`).
    pub probability: f64,
    /// Smallest displacement, in pixels (default 1).
    pub min_pixels: f64,
    /// Largest displacement, as a fraction of the image side in `(0, 0.5]` (default 0.1,
    /// LuxCore's `imagemutationrate`).
    pub max_fraction: f64,
}

impl RasterParams {
    /// The option turned off (probability 0, range 1 pixel to 10% of the image).
    #[must_use]
    pub const fn off() -> Self {
        Self {
            probability: 0.0,
            min_pixels: 1.0,
            max_fraction: 0.1,
        }
    }

    /// Raster steps with the given probability and LuxCore's range (10% of the image side),
    /// from 1 pixel.
    #[must_use]
    pub const fn with_probability(probability: f64) -> Self {
        Self {
            probability,
            ..Self::off()
        }
    }

    /// Validated parameters: `probability` in `[0, 1]`, `min_pixels > 0` and finite,
    /// `max_fraction` in `(0, 0.5]`.
    pub fn new(probability: f64, min_pixels: f64, max_fraction: f64) -> Result<Self, PssError> {
        if !(0.0..=1.0).contains(&probability) {
            return Err(PssError::InvalidParameter {
                name: "raster probability",
                value: probability.to_string(),
                allowed: "[0, 1]",
            });
        }
        if !(min_pixels > 0.0 && min_pixels.is_finite()) {
            return Err(PssError::InvalidParameter {
                name: "raster min_pixels",
                value: min_pixels.to_string(),
                allowed: "(0, inf)",
            });
        }
        if !(max_fraction > 0.0 && max_fraction <= 0.5) {
            return Err(PssError::InvalidParameter {
                name: "raster max_fraction",
                value: max_fraction.to_string(),
                allowed: "(0, 0.5]",
            });
        }
        Ok(Self {
            probability,
            min_pixels,
            max_fraction,
        })
    }

    /// True if raster steps are never taken.
    #[must_use]
    pub fn is_off(&self) -> bool {
        self.probability.is_nan() || self.probability <= 0.0
    }
}

impl Default for RasterParams {
    /// [`RasterParams::off`].
    fn default() -> Self {
        Self::off()
    }
}

/// The raster step: moves primary sample 0 of stream 0 (the horizontal raster coordinate)
/// and primary sample 1 of stream 0 (the vertical one) by independent one-dimensional kernels,
/// and keeps every other coordinate (see [`RasterParams`] for the reading of Kelemen et al.
/// 2002 and LuxCore behind it).
///
/// # Density
///
/// With `S` streams the raster coordinates are `i_h = 0` and `i_v = S` (stream 0's first two
/// numbers in [`PssState`]'s interleaving). For fully materialised states of equal length,
///
/// ```text
/// q_R(x -> y) = k_h(x_{i_h} -> y_{i_h}) k_v(x_{i_v} -> y_{i_v}) prod_{i != i_h, i_v} delta(y_i - x_i)
/// k(u -> v)   = sum_{m in Z} [s1 <= |v - u + m| <= s2] / (2 |v - u + m| ln(s2 / s1))
/// ```
///
/// (`k` is [`SmallMutation::Kelemen`]'s wrapped density, [`SmallMutation::log_density`]),
/// symmetric; `log_q` returns `log k_h + log k_v` when every other coordinate agrees and
/// `-inf` otherwise (the Dirac factors are common to both directions).
///
/// # Lazy exactness
///
/// The step must not change coordinates it does not move, *including* the small steps that
/// the chain's history left pending on stale coordinates ([`PssState`], "Why lazy equals
/// eager"). Its candidate is a copy of `x` with the identity pending mutation
/// ([`Pending::Small`] with an empty stream mask, the catch-up kernel `catch_up`): no stream's
/// iteration counter advances, so a coordinate the target reads later is `x`'s own value,
/// caught up (and logged for `absorb_rejected`) if `x` holds it stale. The two raster
/// coordinates are read through [`PssState::get`] (catching up `x`'s value the same way) and
/// written with [`PssState::set`]. `catch_up` must be the small-step kernel of the chain
/// ([`crate::PssmltProposal`] uses its own). No allocation once the state's buffers have grown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterStep {
    /// Kernel of the horizontal raster coordinate (in units of the image width).
    pub horizontal: SmallMutation,
    /// Kernel of the vertical raster coordinate (in units of the image height).
    pub vertical: SmallMutation,
    /// The chain's small-step kernel, with which stale coordinates are caught up.
    pub catch_up: SmallMutation,
}

impl RasterStep {
    /// The raster step for a `width x height` image: per axis, Kelemen's kernel on
    /// `[min_pixels / side, max_fraction]`. Out-of-range parameters are clamped rather than
    /// rejected (validate them with [`RasterParams::new`]): `max_fraction` to `[1e-6, 0.5]`,
    /// and the lower end to at most half the upper one (tiny images, where one pixel is more
    /// than `max_fraction` of the side).
    #[must_use]
    pub fn for_image(
        params: &RasterParams,
        width: u32,
        height: u32,
        catch_up: SmallMutation,
    ) -> Self {
        let s2 = if params.max_fraction.is_nan() {
            0.1
        } else {
            params.max_fraction.clamp(1e-6, 0.5)
        };
        let min_pixels = if params.min_pixels > 0.0 && params.min_pixels.is_finite() {
            params.min_pixels
        } else {
            1.0
        };
        let axis = |side: u32| {
            let s1 = (min_pixels / f64::from(side.max(1))).min(0.5 * s2);
            SmallMutation::Kelemen(KelemenParams { s1, s2 })
        };
        Self {
            horizontal: axis(width),
            vertical: axis(height),
            catch_up,
        }
    }

    /// The indices of the raster coordinates in a state with `streams` streams.
    #[must_use]
    pub const fn indices(streams: usize) -> [usize; 2] {
        [0, streams]
    }
}

impl Proposal<PssState> for RasterStep {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        let key: u64 = rng.random();
        y.clone_from(x);
        y.set_pending(
            Pending::Small {
                mutation: self.catch_up,
                stream_mask: 0,
            },
            key,
        );
        let own = mix64(key ^ RASTER_SALT);
        let [h, v] = Self::indices(y.streams());
        for (index, kernel) in [(h, self.horizontal), (v, self.vertical)] {
            let parent = y.get(index);
            let moved = kernel.apply(parent, 1, |d| uniform(own, index as u64, d));
            y.set(index, moved);
        }
        Proposed::symmetric()
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        let (a, b) = (from.raw_values(), to.raw_values());
        let [h, v] = Self::indices(from.streams());
        if a.len() != b.len() || from.streams() != to.streams() || a.len() <= v {
            return f64::NEG_INFINITY;
        }
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            if i != h && i != v && x != y {
                return f64::NEG_INFINITY;
            }
        }
        self.horizontal.log_density(a[h], b[h]) + self.vertical.log_density(a[v], b[v])
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_pcg::Pcg64;

    fn step(width: u32, height: u32) -> RasterStep {
        RasterStep::for_image(
            &RasterParams::with_probability(1.0),
            width,
            height,
            SmallMutation::Kelemen(KelemenParams::kelemen2002()),
        )
    }

    #[test]
    fn validates_parameters() {
        assert!(RasterParams::new(0.25, 1.0, 0.1).is_ok());
        assert!(RasterParams::new(1.5, 1.0, 0.1).is_err());
        assert!(RasterParams::new(f64::NAN, 1.0, 0.1).is_err());
        assert!(RasterParams::new(0.5, 0.0, 0.1).is_err());
        assert!(RasterParams::new(0.5, 1.0, 0.6).is_err());
        assert!(RasterParams::off().is_off());
        assert!(!RasterParams::with_probability(0.1).is_off());
    }

    #[test]
    fn kernels_are_in_pixels() {
        let s = step(128, 64);
        assert_eq!(
            s.horizontal,
            SmallMutation::Kelemen(KelemenParams {
                s1: 1.0 / 128.0,
                s2: 0.1
            })
        );
        assert_eq!(
            s.vertical,
            SmallMutation::Kelemen(KelemenParams {
                s1: 1.0 / 64.0,
                s2: 0.1
            })
        );
        // A 4-pixel image: one pixel is more than 10% of the side; the range stays valid.
        let tiny = step(4, 4);
        let SmallMutation::Kelemen(p) = tiny.horizontal else {
            unreachable!()
        };
        assert!(SmallMutation::kelemen(p).is_ok(), "{p:?}");
    }

    /// Only the two raster coordinates move; stale coordinates of `x` stay as `x` holds them
    /// (no stream's iteration advances), and the density is that of the two moves.
    #[test]
    fn moves_only_the_raster_coordinates() {
        let mut x = PssState::new(3, 11);
        for i in 0..12 {
            x.get(i);
        }
        let before = x.raw_values().to_vec();
        let s = step(64, 64);
        let mut rng = Pcg64::seed_from_u64(3);
        let mut y = x.clone();
        for _ in 0..100 {
            s.propose(&x, &mut y, &mut rng);
            y.materialize();
            for (i, (a, b)) in before.iter().zip(y.raw_values()).enumerate() {
                if i == 0 || i == 3 {
                    let d = (b - a) - (b - a).round();
                    let support = (1.0 / 64.0 - 1e-12)..=(0.1 + 1e-12);
                    assert!(support.contains(&d.abs()), "{d}");
                } else {
                    assert_eq!(a, b, "coordinate {i} moved");
                }
            }
            let lq = s.log_q(&x, &y);
            assert!(lq.is_finite());
            assert!((lq - s.log_q(&y, &x)).abs() < 1e-12);
        }
        // A small step elsewhere makes the same coordinates move: the density is then zero.
        let mut z = y.clone();
        z.set(1, 0.5);
        assert_eq!(s.log_q(&x, &z), f64::NEG_INFINITY);
    }
}
