//! The three second-stage acceptance rules of two-stage delayed rejection (DR paper, section 4).

use super::arithmetic::NoGhost;

/// The second-stage acceptance rule of a [`super::DelayedRejection`] kernel.
///
/// With the first stage proposing `y ~ Q1(. | x)` through mixture component `j` (density
/// `Q1_j(y | x) = s(j | x) T_j(y | x)`, accepted with `a1_j(x, y)` by eq. 5) and, after its
/// rejection, the second stage proposing `z ~ Q2(. | x, y)`, the rules accept `z` with
/// (`1 ^ r = min(1, r)`):
///
/// - [`DrRule::TierneyMira`] (Tierney & Mira 1999; DR paper eq. 6):
///   `a2 = 1 ^ [pi(z) Q1_j(y|z) Q2(x|z,y) (1 - a1_j(z,y))] /
///             [pi(x) Q1_j(y|x) Q2(z|x,y) (1 - a1_j(x,y))]`.
///   The reverse path passes through the same rejected `y`. With a symmetric second stage
///   (`Q2(z|x,y) = Q2(x|z,y)`, [`super::DelayedRejection::with_symmetric_second_stage`]) the
///   `Q2` terms are dropped: eq. 7. The `Q1` ratio never cancels, even for a symmetric `Q1`:
///   it vanishes when `z` lands where `Q1` cannot reach `y` (section 4.3).
/// - [`DrRule::GreenMira`] (Green & Mira 2001; eq. 12-13): the reverse path passes through
///   the fictional state `y* = z - (y - x)` given by the rule's [`super::StateArithmetic`]:
///   `a2 = 1 ^ [pi(z) Q1_j(y*|z) Q2(x|z,y*) (1 - a1_j(z,y*))] /
///             [pi(x) Q1_j(y|x) Q2(z|x,y) (1 - a1_j(x,y))]`.
///   It costs one more target evaluation (at `y*`). For a translation-invariant symmetric
///   `Q1`, `Q1_j(y*|z) = Q1_j(y|x)` and the ratio is eq. 14; the kernel still evaluates both
///   densities (exact for any `Q1`, at the price of two `log_q` calls).
/// - [`DrRule::Orbital`] (the pairwise orbital rule, section 4.4, eq. 11):
///   `a2 = 1 ^ [pi(z) (1 - a1_j(z,y))] / [pi(x) (1 - a1_j(x,y))]`,
///   which for a symmetric `Q1` is `1 ^ [0 v (pi(z) - pi(y))] / (pi(x) - pi(y))`. Exact
///   only when the second stage keeps `Q1_j(y|z) = Q1_j(y|x)` and `Q2(z|x,y) = Q2(x|z,y)`:
///   `z` on the orbit `|z - y| = |x - y|` (per coordinate pair) of a first stage that is a
///   product of radially symmetric pair densities with a state-independent component choice,
///   and a second stage symmetric on that orbit ([`super::OrbitalWalk`]). The kernel does not
///   (cannot cheaply) check this; the pairwise flow check of `testing` does.
///
/// The type parameter is the ghost arithmetic; [`NoGhost`] (uninhabited) for kernels that
/// only use the other two rules.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DrRule<A = NoGhost> {
    /// Tierney & Mira 1999, eq. 6 (eq. 7 with a symmetric second stage).
    TierneyMira,
    /// Green & Mira 2001, eq. 12-14, with the ghost arithmetic.
    GreenMira(A),
    /// The pairwise orbital rule, eq. 11.
    Orbital,
}

impl<A> DrRule<A> {
    /// A short name: `"tierney-mira"`, `"green-mira"` or `"orbital"` (the renderer's
    /// `--dr-variant` values).
    #[must_use]
    pub const fn name(&self) -> &'static str {
        match self {
            DrRule::TierneyMira => "tierney-mira",
            DrRule::GreenMira(_) => "green-mira",
            DrRule::Orbital => "orbital",
        }
    }

    /// The ghost arithmetic, for [`DrRule::GreenMira`].
    #[must_use]
    pub const fn arithmetic(&self) -> Option<&A> {
        match self {
            DrRule::GreenMira(a) => Some(a),
            _ => None,
        }
    }

    /// True if the rule evaluates the target at a ghost state (one extra evaluation per
    /// second stage whose candidate has positive density).
    #[must_use]
    pub const fn uses_ghost(&self) -> bool {
        matches!(self, DrRule::GreenMira(_))
    }
}

/// `ln(1 - a)` for a probability `a`.
#[inline]
pub(crate) fn ln_one_minus(a: f64) -> f64 {
    (-a).ln_1p()
}

/// `ln min(1, exp(num - den))` for the log numerator and denominator of a second-stage ratio:
/// `-inf` for a zero numerator, 0 for a zero denominator with a positive numerator (only
/// reachable on paths the kernel never takes, whose forward flow is zero anyway), NaN if
/// either is NaN (the kernel reports it as non-finite and rejects).
#[inline]
pub(crate) fn ln_accept_from_ratio(num: f64, den: f64) -> f64 {
    if num.is_nan() || den.is_nan() {
        f64::NAN
    } else if num == f64::NEG_INFINITY {
        f64::NEG_INFINITY
    } else if den == f64::NEG_INFINITY {
        0.0
    } else {
        let r = num - den;
        if r.is_nan() {
            f64::NAN
        } else {
            r.min(0.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::delayed_rejection::Torus;

    #[test]
    fn names_and_arithmetic() {
        let r: DrRule = DrRule::TierneyMira;
        assert_eq!(r.name(), "tierney-mira");
        assert!(r.arithmetic().is_none() && !r.uses_ghost());
        let g = DrRule::GreenMira(Torus);
        assert_eq!(g.name(), "green-mira");
        assert_eq!(g.arithmetic(), Some(&Torus));
        assert!(g.uses_ghost());
        assert_eq!(DrRule::<Torus>::Orbital.name(), "orbital");
    }

    #[test]
    fn ratio_edge_cases() {
        assert_eq!(
            ln_accept_from_ratio(f64::NEG_INFINITY, -1.0),
            f64::NEG_INFINITY
        );
        assert_eq!(ln_accept_from_ratio(-1.0, f64::NEG_INFINITY), 0.0);
        assert_eq!(
            ln_accept_from_ratio(f64::NEG_INFINITY, f64::NEG_INFINITY),
            f64::NEG_INFINITY
        );
        assert!(ln_accept_from_ratio(f64::NAN, 0.0).is_nan());
        assert!(ln_accept_from_ratio(f64::INFINITY, f64::INFINITY).is_nan());
        assert_eq!(ln_accept_from_ratio(-1.0, -3.0), 0.0);
        assert_eq!(ln_accept_from_ratio(-3.0, -1.0), -2.0);
        assert_eq!(ln_one_minus(0.0), 0.0);
        assert_eq!(ln_one_minus(1.0), f64::NEG_INFINITY);
    }
}
