//! Two-stage delayed rejection: the kernel, its three acceptance rules, the ghost-state
//! arithmetic, and pairwise stages on `Vec<f64>` (DR paper, section 4; docs/methods/drmlt.md).
//!
//! | item | what it is |
//! |---|---|
//! | [`DelayedRejection`] | the kernel: first-stage [`crate::Proposal`], second-stage [`crate::proposal::ConditionalProposal`] |
//! | [`DrRule`] | Tierney-Mira (eq. 6/7), Green-Mira (eq. 12-14), orbital (eq. 11) |
//! | [`StateArithmetic`], [`Euclidean`], [`Torus`], [`NoGhost`] | the ghost `y* = z - (y - x)` of Green-Mira |
//! | [`RadialKelemen`], [`OrbitalWalk`], [`WrappedCauchy`] | the pairwise polar Kelemen first stage and the orbital second stage (section 4.4), in the plane or on the torus; `pss` runs the same maths on primary-sample-space layouts |
//! | [`Group`], [`pairs`] | how the pairwise stages group coordinates |
//! | [`IndependentSecondStage`], [`WrappedGaussianWalk`] | a second stage that ignores `y`; a Gaussian walk on the torus |

mod arithmetic;
mod kernel;
mod orbital;
mod pairwise;
mod proposals;
mod radial_kelemen;
pub(crate) mod rule;
mod wrapped_cauchy;

pub use arithmetic::{Euclidean, NoGhost, StateArithmetic, Torus};
pub use kernel::DelayedRejection;
pub use orbital::{OrbitalWalk, ORBIT_TOLERANCE};
pub use pairwise::{pairs, Group};
pub use proposals::{IndependentSecondStage, WrappedGaussianWalk};
pub use radial_kelemen::RadialKelemen;
pub use rule::DrRule;
pub use wrapped_cauchy::{WrappedCauchy, RIOUX_LAVOIE2020_RHO};
