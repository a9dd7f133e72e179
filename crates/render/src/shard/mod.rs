//! A render split into shards: what a shard keeps (its accumulators, not its image), how
//! parts add up, and how the image is made from them.
//!
//! Every integrator renders a fixed list of work units (tiles of pixels, row bands, chain
//! jobs) that does not depend on the thread count. Shard `k` of `n`
//! ([`mcmc_core::render_loop::Shard`]) renders only the units `u` with `u * n / units == k`
//! and keeps their sums as [`Component`]s:
//!
//! * pixel-sample sums (`Σ w L`, `Σ w`) of the pixels its tiles own: a pixel belongs to one
//!   tile, so the parts' sums add up (`0 + x = x`) to the whole render's bit for bit;
//! * splat sums in an [`ExactSplatGrid`], whose 128-bit fixed-point sums do not depend on
//!   the order of the splats, so the parts' grids add up to the whole render's bit for bit;
//! * the counts the image is normalised by (samples, mutations), which add up exactly.
//!
//! The image is made from the (merged) components by [`Partial::image`], the same function
//! the single-process render uses, so a merged render is bit-identical to the one-process
//! render at the same seed and sample budget. Everything that must be equal across parts
//! (the MCMC normalisation `b`, LQMC's progression count) is recomputed deterministically by
//! every shard and checked when merging.

mod file;

pub use file::{fingerprint, read_part, write_part, PartHeader, PART_EXTENSION};
pub use mcmc_core::render_loop::Shard;

use mcmc_core::render_loop::{ExactSplatGrid, Normalization};

use crate::film::{Film, Filter};
use crate::image::{add_into, Image};

/// One additive part of an image (see the module documentation).
#[derive(Clone, Debug)]
pub enum Component {
    /// Pixel-sample sums (box filter; `Σ w L`, `Σ w` per pixel) and optionally a light-tracing
    /// splat layer scaled by `pixels / light_samples` (BDPT).
    Film {
        /// `Σ w L` per pixel, row-major.
        sum: Vec<[f64; 3]>,
        /// `Σ w` per pixel.
        weight: Vec<f64>,
        /// Light-tracing splats, if any.
        light: Option<ExactSplatGrid>,
        /// Camera samples taken (the light layer's normaliser).
        light_samples: u64,
    },
    /// Markov chain splats: `grid * (b / mutations) * pixels` (Kelemen et al. 2002, eq. 5),
    /// `b` the estimate of the parts' normalisations added ([`Normalization::estimate`]).
    Chains {
        /// The splat sums `Σ w rgb / f`.
        grid: ExactSplatGrid,
        /// What `b` rests on: the bootstrap (equal in every part) and each job's large-step
        /// sums (zero for the jobs a part does not own).
        normalization: Normalization,
        /// Mutations counted.
        mutations: u64,
    },
    /// Splat sums averaged over `divisor` progressions (LQMC): `grid / divisor`.
    Mean {
        /// The splat sums.
        grid: ExactSplatGrid,
        /// Progressions (equal in every part).
        divisor: u32,
    },
}

/// The accumulators of a render or of one shard of it: components whose images are added in
/// order (PSSMLT: the chains, then the direct-lighting pass).
#[derive(Clone, Debug)]
pub struct Partial {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The components, in the order their images are added.
    pub components: Vec<Component>,
}

impl Component {
    /// A short name of the component's kind (for messages and the part file).
    #[must_use]
    pub fn kind(&self) -> &'static str {
        match self {
            Component::Film { .. } => "film",
            Component::Chains { .. } => "chains",
            Component::Mean { .. } => "mean",
        }
    }

    /// This component's image and the number of pixels dropped (black) because a channel
    /// overflows f32.
    #[must_use]
    pub fn image(&self, width: usize, height: usize) -> (Image, u64) {
        let pixels = (width * height) as f64;
        match self {
            Component::Film {
                sum,
                weight,
                light,
                light_samples,
            } => {
                let Some(mut film) =
                    Film::from_sums(width, height, Filter::BOX, sum.clone(), weight.clone())
                else {
                    return (Image::new(width, height), 0);
                };
                let scale = match light {
                    Some(grid) => {
                        film.merge_exact_splats(grid);
                        if *light_samples == 0 {
                            0.0
                        } else {
                            pixels / *light_samples as f64
                        }
                    }
                    None => 0.0,
                };
                film.image_checked(scale)
            }
            Component::Chains {
                grid,
                normalization,
                mutations,
            } => {
                let splat_scale = if *mutations == 0 {
                    0.0
                } else {
                    normalization.estimate().b / *mutations as f64
                };
                grid_image(grid, splat_scale * pixels)
            }
            Component::Mean { grid, divisor } => {
                grid_image(grid, 1.0 / f64::from((*divisor).max(1)))
            }
        }
    }

    /// Adds `other` (the same kind of component of another shard of the same render).
    ///
    /// # Errors
    /// A message naming what differs (kind, size, normalisation).
    pub fn add(&mut self, other: &Component) -> Result<(), String> {
        match (self, other) {
            (
                Component::Film {
                    sum,
                    weight,
                    light,
                    light_samples,
                },
                Component::Film {
                    sum: s2,
                    weight: w2,
                    light: l2,
                    light_samples: n2,
                },
            ) => {
                if sum.len() != s2.len() || weight.len() != w2.len() {
                    return Err("film sizes differ".into());
                }
                for (a, b) in sum.iter_mut().zip(s2) {
                    for c in 0..3 {
                        a[c] += b[c];
                    }
                }
                for (a, b) in weight.iter_mut().zip(w2) {
                    *a += b;
                }
                match (light, l2) {
                    (Some(a), Some(b)) => add_grid(a, b)?,
                    (None, None) => {}
                    _ => return Err("one part has a light-tracing layer, the other not".into()),
                }
                *light_samples += n2;
                Ok(())
            }
            (
                Component::Chains {
                    grid,
                    normalization,
                    mutations,
                },
                Component::Chains {
                    grid: g2,
                    normalization: n2,
                    mutations: m2,
                },
            ) => {
                if let Err(e) = normalization.add(n2) {
                    return Err(format!(
                        "the MCMC normalisation differs (bootstrap b {} vs {}; {e}): the parts are not of one render",
                        normalization.bootstrap_b.iter().sum::<f64>(),
                        n2.bootstrap_b.iter().sum::<f64>()
                    ));
                }
                add_grid(grid, g2)?;
                *mutations += m2;
                Ok(())
            }
            (
                Component::Mean { grid, divisor },
                Component::Mean {
                    grid: g2,
                    divisor: d2,
                },
            ) => {
                if divisor != d2 {
                    return Err(format!(
                        "the progression counts differ ({divisor} vs {d2}): a time budget or a cancelled part"
                    ));
                }
                add_grid(grid, g2)
            }
            (a, b) => Err(format!(
                "component kinds differ ({} vs {})",
                a.kind(),
                b.kind()
            )),
        }
    }
}

fn add_grid(a: &ExactSplatGrid, b: &ExactSplatGrid) -> Result<(), String> {
    if a.add_grid(b) {
        Ok(())
    } else {
        Err("splat grids differ in size or resolution".into())
    }
}

/// `grid * scale` as an image, with the pixels dropped because they overflow f32.
fn grid_image(grid: &ExactSplatGrid, scale: f64) -> (Image, u64) {
    let (pixels, dropped) = grid.to_rgb32_checked(scale);
    (
        Image {
            width: grid.width(),
            height: grid.height(),
            pixels,
        },
        dropped,
    )
}

impl Partial {
    /// The image: the components' images added in order (f32 adds, as the single-process
    /// render does), and the number of pixels dropped because they overflow f32.
    #[must_use]
    pub fn image(&self) -> (Image, u64) {
        let mut image = Image::new(self.width, self.height);
        let mut dropped = 0;
        for (i, c) in self.components.iter().enumerate() {
            let (img, d) = c.image(self.width, self.height);
            dropped += d;
            if i == 0 {
                image = img;
            } else {
                add_into(&mut image, &img);
            }
        }
        (image, dropped)
    }

    /// Adds another shard's accumulators of the same render.
    ///
    /// # Errors
    /// A message naming what differs.
    pub fn add(&mut self, other: &Partial) -> Result<(), String> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(format!(
                "image sizes differ ({}x{} vs {}x{})",
                self.width, self.height, other.width, other.height
            ));
        }
        if self.components.len() != other.components.len() {
            return Err(format!(
                "component counts differ ({} vs {})",
                self.components.len(),
                other.components.len()
            ));
        }
        for (a, b) in self.components.iter_mut().zip(&other.components) {
            a.add(b)?;
        }
        Ok(())
    }
}
