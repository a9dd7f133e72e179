//! PSS negative controls: an asymmetric proposal (correct only with its Hastings term) and a
//! small step that clamps at the torus seam instead of wrapping; PSS coordinates for the
//! Langevin kernels with part of their candidate check left out.

use mcmc_core::langevin::{LangevinSpace, ProposalGaussian};
use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::langevin::PssCoordinates;
use crate::{KelemenParams, PssError, PssState, SmallMutation, SmallStep};

/// An honest *asymmetric* PSS proposal: the wrapped Gaussian small step with a sigma that
/// depends on the current state's first stored coordinate (`narrow` on `[0, 1/2)`, `wide` on
/// `[1/2, 1)`: a regional scale), reporting its exact Hastings term
/// `log q(y -> x) - log q(x -> y)`.
///
/// The candidate is materialised in `propose`, since the Hastings term needs its coordinates;
/// the region is read from `x`'s *stored* first coordinate, which targets that always read
/// coordinate 0 keep up to date. With MH it is a correct kernel; wrapped in
/// [`mcmc_core::testing::TreatedAsSymmetric`] (the "Hastings term of the wrong sigma" bug) or
/// run by [`mcmc_core::testing::MhWithoutHastings`], it is a negative control that must fail
/// the harness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionalGaussian {
    narrow: f64,
    wide: f64,
}

impl RegionalGaussian {
    /// Sigmas for the two halves of `[0, 1)`, each in `(0, 10]`.
    pub fn new(narrow: f64, wide: f64) -> Result<Self, PssError> {
        SmallMutation::gaussian(narrow)?;
        SmallMutation::gaussian(wide)?;
        Ok(Self { narrow, wide })
    }

    /// The small step used from `x`.
    #[must_use]
    pub fn step_at(&self, x: &PssState) -> SmallStep {
        let first = x.raw_values().first().copied().unwrap_or(0.0);
        let sigma = if first < 0.5 { self.narrow } else { self.wide };
        SmallStep::new(SmallMutation::Gaussian { sigma })
    }
}

impl Proposal<PssState> for RegionalGaussian {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        self.step_at(x).propose(x, y, rng);
        y.materialize();
        Proposed::hastings(self.log_q(y, x) - self.log_q(x, y))
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        self.step_at(from).log_q(from, to)
    }
}

/// A Kelemen-like small step that does not wrap around the torus but clamps at the boundary
/// (`[0, 1 - 2^-53]`) while claiming the symmetric torus density of
/// [`SmallMutation::Kelemen`]. Its candidates are fully materialised states.
///
/// The bug: a perturbation written as `clamp(x + d)`. It piles mass onto the boundary points
/// and never crosses the seam. Its `log_q` is the claimed (correct) density, so pairwise and
/// finite-state checks cannot see it; the stationarity test does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClampedKelemen(KelemenParams);

impl ClampedKelemen {
    /// With Kelemen parameters `0 < s1 < s2 <= 0.5`.
    pub fn new(params: KelemenParams) -> Result<Self, PssError> {
        SmallMutation::kelemen(params)?;
        Ok(Self(params))
    }
}

impl Proposal<PssState> for ClampedKelemen {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        let KelemenParams { s1, s2 } = self.0;
        let values: Vec<f64> = x
            .raw_values()
            .iter()
            .map(|&v| {
                let d = s2 * ((s1 / s2).ln() * rng.random::<f64>()).exp();
                let moved = if rng.random::<bool>() { v + d } else { v - d };
                // The bug: clamp instead of wrap.
                moved.clamp(0.0, 1.0 - f64::EPSILON / 2.0)
            })
            .collect();
        *y = PssState::from_values(&values);
        Proposed::symmetric()
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        // The claim: the wrapped Kelemen density.
        SmallStep::new(SmallMutation::Kelemen(self.0)).log_q(from, to)
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

/// Which part of [`PssCoordinates`]'s candidate check [`BlindPssCoordinates`] leaves out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blindness {
    /// Every candidate keeps the read set (the layout and slice checks always pass): a
    /// cheap-then-expensive first stage then accepts moves between read sets.
    ReadSet,
    /// The layout check compares read counts only, not the discrete tags: a move may
    /// differentiate, as continuous, a number that was a discrete choice where it started.
    Tags,
}

/// [`PssCoordinates`] with part of its candidate check left out: a negative control for
/// the Langevin kernels' read-set and continuous-coordinate rules (it must fail the
/// stationarity tests; pairwise flows use the same wrong density at both ends and balance).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlindPssCoordinates(pub Blindness);

impl LangevinSpace<PssState> for BlindPssCoordinates {
    fn read(&self, x: &PssState, out: &mut Vec<f64>) {
        PssCoordinates.read(x, out);
    }
    fn write(&self, x: &PssState, coords: &[f64], y: &mut PssState) -> bool {
        PssCoordinates.write(x, coords, y)
    }
    fn log_q(&self, q: &ProposalGaussian, from: &[f64], to: &[f64]) -> f64 {
        PssCoordinates.log_q(q, from, to)
    }
    fn wraps(&self) -> bool {
        true
    }
    fn ghost(&self, x: &[f64], y: &[f64], z: &[f64], out: &mut Vec<f64>) {
        PssCoordinates.ghost(x, y, z, out);
    }
    fn same_layout(&self, x: &PssState, y: &PssState) -> bool {
        match self.0 {
            Blindness::ReadSet => true,
            Blindness::Tags => x.read_counts() == y.read_counts(),
        }
    }
    fn same_slice(&self, x: &PssState, y: &PssState) -> bool {
        match self.0 {
            Blindness::ReadSet => true,
            Blindness::Tags => PssCoordinates.same_slice(x, y),
        }
    }
}
