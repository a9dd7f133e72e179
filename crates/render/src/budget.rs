//! How long a render runs: a sample count per pixel or a wall-clock budget.

use std::time::Duration;

/// How long to render: a sample count per pixel or a wall-clock budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Samples (or, for MCMC integrators, mutations) per pixel.
    SamplesPerPixel(u32),
    /// Wall-clock time; the image is not bit-reproducible under this budget.
    Time(Duration),
}
