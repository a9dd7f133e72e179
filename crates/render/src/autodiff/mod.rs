//! Forward-mode automatic differentiation for the differentiable path evaluator
//! ([`crate::bdpt::diff`]): a scalar trait [`Real`] implemented by `f64` and by the dual number
//! [`Dual`] (one value and `N` derivative lanes of `f64` or `f32`, [`Lane`]), and the small
//! vector type [`V3`] over it.
//!
//! Code written once over `T: Real` runs in plain `f64` (the evaluator's reference value, and
//! the finite differences its gradients are tested against) and in `Dual<N>` (value and
//! gradient in one pass). A foundation module: it knows nothing of scenes.
//!
//! # Example
//! ```
//! use render::autodiff::{Dual, Real};
//!
//! // d/dx (x^2 sin x) at x = 1.5, one lane.
//! let x = Dual::<1>::variable(1.5, 0);
//! let y = x * x * x.sin();
//! let exact = 2.0 * 1.5 * 1.5f64.sin() + 1.5 * 1.5 * 1.5f64.cos();
//! assert!((y.value() - 1.5 * 1.5 * 1.5f64.sin()).abs() < 1e-15);
//! assert!((y.d[0] - exact).abs() < 1e-14);
//! ```

mod dual;
mod lane;
mod real;
mod vec;

pub use dual::Dual;
pub use lane::Lane;
pub use real::Real;
pub use vec::V3;
