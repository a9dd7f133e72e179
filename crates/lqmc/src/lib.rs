//! Local quasi-Monte Carlo exploration (Tessari, Hanika & Dachsbacher, "Local Quasi-Monte
//! Carlo Exploration"): Halton seeds, rank-1 lattices, and the LQMC estimator.
//!
//! A seed point `u` of any integrand on `[0, 1)^s` (in rendering: the random numbers of a
//! path) is explored by the `N` points of a rank-1 lattice, Cranley-Patterson-shifted onto the
//! seed inside a local tile of the first `s_bar` dimensions, and every explored point is
//! weighted by the balance heuristic over the set (paper section 3, Alg. 1, eq. 8-9). This
//! crate is independent of any renderer and of `mcmc-core`:
//!
//! | item | paper |
//! |---|---|
//! | [`Halton`], [`radical_inverse`], [`Scrambling`] | seed sampling, section 3.4 |
//! | [`Rank1Lattice`], [`Rank1Lattice::closest_point`] | eq. 2; Alg. 1 line 3 |
//! | [`KorobovSpace`] (`P_alpha`, CBC), embedded tables ([`Rank1Lattice::from_table`]) | section 3.4, \[NC06\] |
//! | [`ShiftedLattice`] | eq. 3, Cranley-Patterson shift, Fig. 3 |
//! | [`Tiling`] | eq. 12, jittered tiling of section 3.4 |
//! | [`LocalQmc`], [`LocalIntegrand`], [`Rebuilt`], [`Splat`], [`ExploreScratch`] | Alg. 1, eq. 8-9 |
//! | [`sample_breakup`], [`breakup_probability`] | breakup point, section 3.3 |
//!
//! # Example
//!
//! A discontinuous integrand on `[0,1)^3` sampled with a non-uniform seed technique
//! (`x_0 = sqrt(u_0)`, density `2 x_0`), exploring the first two dimensions with the embedded
//! `N = 23` lattice in jittered tiles; the third dimension stays fixed (the "static suffix").
//!
//! ```
//! use lqmc::{Halton, LocalQmc, Rank1Lattice, Rebuilt, Scrambling, Tiling};
//!
//! // f(x) = [x0 > x1] (1 + x2); its integral over the unit cube is 0.75.
//! let path = |u: &[f64], u2: f64| {
//!     let x0 = u[0].sqrt();
//!     let p0 = 2.0 * x0; // density of x0; x1 = u1, x2 = u2 are uniform
//!     let f = if x0 > u[1] { 1.0 + u2 } else { 0.0 };
//!     Rebuilt { payload: (), contribution: f, prefix_jacobian: p0, density: p0, breakup_probability: 1.0 }
//! };
//!
//! let lattice = Rank1Lattice::from_table(23, 2).unwrap();
//! let tiling = Tiling::new(vec![3, 3]).unwrap().with_jitter(&[0.25, 0.5]).unwrap();
//! let lqmc = LocalQmc::new(lattice, tiling).unwrap();
//! let halton = Halton::new(Scrambling::Owen, 7);
//!
//! let (seeds, mut sum, mut splats) = (4000u64, 0.0, Vec::new());
//! for i in 0..seeds {
//!     let mut u = [0.0; 3];
//!     halton.fill(i, &mut u);
//!     let u2 = u[2];
//!     let mut rebuild = |v: &[f64]| Some(path(v, u2));
//!     splats.clear();
//!     lqmc.explore(&u[..2], path(&u[..2], u2), &mut rebuild, &mut splats);
//!     sum += splats.iter().map(|s| s.value).sum::<f64>();
//! }
//! assert!((sum / seeds as f64 - 0.75).abs() < 0.01);
//! ```

mod breakup;
mod cbc;
mod error;
mod estimator;
mod halton;
mod hash;
mod lattice;
mod shift;
mod tables;
mod tiling;
mod torus;

pub use breakup::{breakup_probability, sample_breakup};
pub use cbc::{table_source, KorobovSpace, TABLE_WEIGHT_DECAY, TABLE_WEIGHT_SCALE};
pub use error::LqmcError;
pub use estimator::{
    Exploration, ExploreScratch, LocalIntegrand, LocalQmc, LocalSet, Rebuilt, Splat,
};
pub use halton::{
    faure_permutation, radical_inverse, Halton, Scrambling, HALTON_DIMENSIONS, HALTON_PRIMES,
    ONE_MINUS_EPSILON,
};
pub use lattice::{ClosestPoint, Rank1Lattice, TABLE_MAX_DIMS, TABLE_SIZES};
pub use shift::ShiftedLattice;
pub use tiling::Tiling;
pub use torus::{torus_difference, wrap_unit};

#[cfg(test)]
mod table_tests {
    use super::*;

    /// The embedded table is what `table_source` generates (set `LQMC_BLESS=1` to rewrite it).
    #[test]
    fn embedded_tables_are_regenerated_exactly() {
        let generated = table_source(&TABLE_SIZES, TABLE_MAX_DIMS);
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/tables.rs");
        if std::env::var_os("LQMC_BLESS").is_some() {
            std::fs::write(path, &generated).unwrap();
        }
        assert_eq!(include_str!("tables.rs"), generated);
        // And the numbers: every (N, s) lattice is the CBC prefix.
        for n in TABLE_SIZES {
            let g = KorobovSpace::table(TABLE_MAX_DIMS).cbc(n).unwrap();
            for s in 1..=TABLE_MAX_DIMS {
                assert_eq!(Rank1Lattice::from_table(n, s).unwrap().generator(), &g[..s]);
            }
        }
    }
}
