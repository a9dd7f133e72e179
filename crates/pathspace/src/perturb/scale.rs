//! Where a perturbation's angular scale comes from: a fixed pair, or any function of the
//! state (the hook for regional adaptation).

use crate::path::Path;

/// The angular scales `(sigma_1, sigma_2)` a perturbation uses when it perturbs *from* a given
/// path (regional-adaptive paper, section 5.2: `sigma_1` for the primary ray, `sigma_2` for the
/// directions leaving later non-specular vertices, used by the multi-chain perturbation).
///
/// A perturbation asks its source for `sigmas(x)` when it proposes `y` from `x`, and for
/// `sigmas(y)` when it evaluates the reverse density `T(x | y)`: with a state-dependent
/// source (a per-region scale) the kernel is asymmetric across region borders and the
/// Hastings term accounts for it (eq. 2-3; the reference-notes pitfall 6).
///
/// Implemented by [`FixedScale`] and by every closure `Fn(&Path) -> [f64; 2]`.
pub trait ScaleSource {
    /// `[sigma_1, sigma_2]` (radians, positive) at state `x`.
    fn sigmas(&self, x: &Path) -> [f64; 2];

    /// [`Self::sigmas`] at the chain's current state `x`, which a proposal perturbs from.
    /// A source may remember the region of the current state between steps (the regional
    /// scales do when their controller tracks it), so only call this with the state the
    /// chain is at.
    fn current_sigmas(&self, x: &Path) -> [f64; 2] {
        self.sigmas(x)
    }

    /// [`Self::sigmas`] at a candidate `y` proposed from the current state (for the reverse
    /// density); a source may remember its region for when the candidate is accepted.
    fn candidate_sigmas(&self, y: &Path) -> [f64; 2] {
        self.sigmas(y)
    }
}

/// The same scales everywhere (the paper's FIXED variant).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedScale(pub [f64; 2]);

impl FixedScale {
    /// The paper's initial scale `lambda = log sigma^2 = 1` for both directions (section 8.1),
    /// `sigma = e^{1/2} ≈ 1.65` rad.
    #[must_use]
    pub fn otsu2018() -> Self {
        let s = 0.5f64.exp();
        Self([s, s])
    }

    /// `sigma` for both directions.
    #[must_use]
    pub const fn uniform(sigma: f64) -> Self {
        Self([sigma, sigma])
    }
}

impl ScaleSource for FixedScale {
    fn sigmas(&self, _x: &Path) -> [f64; 2] {
        self.0
    }
}

impl<F: Fn(&Path) -> [f64; 2]> ScaleSource for F {
    fn sigmas(&self, x: &Path) -> [f64; 2] {
        self(x)
    }
}
