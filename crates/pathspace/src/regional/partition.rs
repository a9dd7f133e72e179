//! Partitions of path space on low-dimensional canonical coordinates (regional-adaptive paper,
//! section 5.4 and 6): the screen position of the primary ray (2-D, for the lens
//! perturbation) and screen x the outgoing direction at the first non-specular vertex (4-D,
//! for the multi-chain perturbation).

use std::ops::Range;

use mcmc_core::Partition;

use super::plane::{PlanePartition, MAX_GRID_CELLS};
use crate::error::PathspaceError;
use crate::path::{direction, Path};
use crate::scene::Camera;
use crate::vec3::Vec3;

/// A camera behind a reference is a camera (so partitions can borrow the scene).
impl<C: Camera + ?Sized> Camera for &C {
    fn origin(&self) -> Vec3 {
        (**self).origin()
    }
    fn direction(&self, raster: [f64; 2]) -> Vec3 {
        (**self).direction(raster)
    }
    fn raster(&self, dir: Vec3) -> Option<[f64; 2]> {
        (**self).raster(dir)
    }
    fn importance(&self, dir: Vec3) -> f64 {
        (**self).importance(dir)
    }
    fn direction_pdf(&self, dir: Vec3) -> f64 {
        (**self).direction_pdf(dir)
    }
}

/// `rp(w_{x_1 -> x_2})` of section 5.4: the raster position of the primary ray in `[0, 1)^2`;
/// `[0, 0]` for a path without one (fewer than two vertices, or outside the image: such paths
/// have zero density and are never a chain's state).
#[must_use]
pub fn screen_coordinates<C: Camera + ?Sized>(camera: &C, x: &Path) -> [f64; 2] {
    if x.vertices.len() < 2 {
        return [0.0, 0.0];
    }
    camera.raster(x.primary_direction()).unwrap_or([0.0, 0.0])
}

/// `cy(w)` of eq. 7: a unit direction in 2-D cylindrical coordinates,
/// `((w_z + 1) / 2, phi / 2 pi)` with `phi = atan2(w_y, w_x)` in `[0, 2 pi)` (world frame).
/// Archimedes' map: equal areas on the sphere are equal areas in `[0, 1)^2`.
#[must_use]
pub fn cylindrical(w: Vec3) -> [f64; 2] {
    let u = (0.5 * (w.z + 1.0)).clamp(0.0, 1.0);
    let mut v = w.y.atan2(w.x) / std::f64::consts::TAU;
    if v < 0.0 {
        v += 1.0;
    }
    [u, if v >= 1.0 { 0.0 } else { v }]
}

/// The direction `x_c -> x_{c+1}` leaving the first non-specular vertex `x_c` after the camera
/// (section 5.4, eq. 7), or `None` if that vertex is the last one (a path
/// `camera -> specular* -> light`).
#[must_use]
pub fn first_nonspecular_direction(x: &Path) -> Option<Vec3> {
    let v = &x.vertices;
    let c = (1..v.len()).find(|&j| !v[j].is_specular())?;
    (c + 1 < v.len()).then(|| direction(v[c].position(), v[c + 1].position()))
}

/// The 4-D canonical point of eq. 7: `(rp(w_1), cy(w_c))`; paths without an outgoing
/// direction at `x_c` map to `cy = [0, 0]`.
#[must_use]
pub fn canonical_4d<C: Camera + ?Sized>(camera: &C, x: &Path) -> ([f64; 2], [f64; 2]) {
    let dir = first_nonspecular_direction(x).map_or([0.0, 0.0], cylindrical);
    (screen_coordinates(camera, x), dir)
}

/// The 2-D screen-space partition of the lens perturbation (section 5.4):
/// `P_k = { x : rp(w_{x_1 -> x_2}) in S_k }` with `{S_k}` a grid or a quadtree over the raster.
///
/// # Example
/// ```
/// use mcmc_core::Partition;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::regional::{PlanePartition, ScreenPartition};
/// use pathspace::{IndependentSampler, Path, UnidirectionalParams, UnidirectionalSampler};
/// use rand::SeedableRng;
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let grid = ScreenPartition::new(&scene, PlanePartition::grid(20).unwrap());
/// let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
/// let mut x = Path::new();
/// while !sampler.sample(&mut rng, &mut x) {}
/// let r = x.raster(&scene).unwrap();
/// let expected = (r[1] * 20.0) as usize * 20 + (r[0] * 20.0) as usize;
/// assert_eq!(grid.region(&x), expected);
/// ```
#[derive(Clone, Debug)]
pub struct ScreenPartition<C> {
    camera: C,
    plane: PlanePartition,
}

impl<C: Camera> ScreenPartition<C> {
    /// `plane` over the raster of `camera` (pass `&scene`).
    pub fn new(camera: C, plane: PlanePartition) -> Self {
        Self { camera, plane }
    }

    /// The partition of the raster.
    #[must_use]
    pub fn plane(&self) -> &PlanePartition {
        &self.plane
    }
}

impl<C: Camera> Partition<Path> for ScreenPartition<C> {
    fn region(&self, x: &Path) -> usize {
        self.plane.region(screen_coordinates(&self.camera, x))
    }
    fn num_regions(&self) -> usize {
        self.plane.num_regions()
    }
    fn split(&mut self, region: usize) -> Option<Range<usize>> {
        self.plane.split(region)
    }
}

/// The 4-D partition of the multi-chain perturbation (section 5.4 eq. 7, section 6.3, Fig. 7):
/// an `N_top x N_top` grid over the screen whose cells each hold their own partition (a
/// quadtree, or an `N_bottom x N_bottom` grid) of the cylindrical coordinates of the direction
/// leaving the first non-specular vertex.
///
/// Region ids are global and dense: initially cell by cell (row-major top grid, then each
/// cell's local ids); a split appends the new leaves' ids at the end (the split id is reused
/// by the first child).
///
/// # Example
/// ```
/// use mcmc_core::Partition;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::regional::{DirectionPartition, PlanePartition};
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let mut tree = DirectionPartition::new(&scene, 20, PlanePartition::quadtree(8).unwrap()).unwrap();
/// assert_eq!(tree.num_regions(), 400);
/// assert_eq!(tree.split(37), Some(400..403)); // cell 37's root becomes four leaves
/// assert_eq!(tree.cell_of(400), (37, 1));
/// let grid = DirectionPartition::new(&scene, 20, PlanePartition::grid(50).unwrap()).unwrap();
/// assert_eq!(grid.num_regions(), 400 * 2500);
/// ```
#[derive(Clone, Debug)]
pub struct DirectionPartition<C> {
    camera: C,
    top: usize,
    cells: Vec<PlanePartition>,
    /// Per top cell: local id -> global id (empty until the first split).
    global_of: Vec<Vec<u32>>,
    /// Global id -> (top cell, local id) (empty until the first split).
    owner: Vec<(u32, u32)>,
    /// Regions per top cell while no cell has split: then the global id of local id `l` in
    /// cell `c` is `c * n + l`, and neither table is needed (a grid's 10^6 ids would miss
    /// the cache).
    unsplit_per_cell: Option<usize>,
}

impl<C: Camera> DirectionPartition<C> {
    /// An `n_top x n_top` screen grid (`1..=4096`), every cell holding a copy of `bottom`.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for `n_top` out of range or more than `2^32`
    /// regions.
    pub fn new(camera: C, n_top: usize, bottom: PlanePartition) -> Result<Self, PathspaceError> {
        PathspaceError::check_range("n_top", n_top as f64, 1.0, MAX_GRID_CELLS as f64)?;
        let per_cell = bottom.num_regions();
        let total = (n_top * n_top) as f64 * per_cell as f64;
        PathspaceError::check_range("regions", total, 1.0, f64::from(u32::MAX))?;
        Ok(Self {
            camera,
            top: n_top,
            cells: vec![bottom; n_top * n_top],
            global_of: Vec::new(),
            owner: Vec::new(),
            unsplit_per_cell: Some(per_cell),
        })
    }

    /// Builds the id tables of an unsplit partition (before its first split).
    fn build_tables(&mut self, per_cell: usize) {
        let cells = self.cells.len();
        self.global_of = (0..cells)
            .map(|c| (0..per_cell).map(|l| (c * per_cell + l) as u32).collect())
            .collect();
        self.owner = (0..cells)
            .flat_map(|c| (0..per_cell).map(move |l| (c as u32, l as u32)))
            .collect();
        self.unsplit_per_cell = None;
    }

    /// `N_top`.
    #[must_use]
    pub fn top_cells_per_axis(&self) -> usize {
        self.top
    }

    /// The top-grid cell and the local id (within that cell's partition) of a region.
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    #[must_use]
    pub fn cell_of(&self, region: usize) -> (usize, usize) {
        if let Some(per_cell) = self.unsplit_per_cell {
            assert!(region < self.num_regions(), "region {region}");
            return (region / per_cell, region % per_cell);
        }
        let (c, l) = self.owner[region];
        (c as usize, l as usize)
    }

    /// The direction partition of top cell `cell`.
    ///
    /// # Panics
    /// If `cell >= N_top^2`.
    #[must_use]
    pub fn cell_partition(&self, cell: usize) -> &PlanePartition {
        &self.cells[cell]
    }

    /// The region of a 4-D canonical point `(screen, cylindrical)`.
    #[must_use]
    pub fn region_of_point(&self, screen: [f64; 2], dir: [f64; 2]) -> usize {
        let n = self.top;
        let cell = |v: f64| ((v.clamp(0.0, 1.0) * n as f64) as usize).min(n - 1);
        let c = cell(screen[1]) * n + cell(screen[0]);
        let local = self.cells[c].region(dir);
        match self.unsplit_per_cell {
            Some(per_cell) => c * per_cell + local,
            None => self.global_of[c][local] as usize,
        }
    }
}

impl<C: Camera> Partition<Path> for DirectionPartition<C> {
    fn region(&self, x: &Path) -> usize {
        let (screen, dir) = canonical_4d(&self.camera, x);
        self.region_of_point(screen, dir)
    }
    fn num_regions(&self) -> usize {
        match self.unsplit_per_cell {
            Some(per_cell) => self.cells.len() * per_cell,
            None => self.owner.len(),
        }
    }
    fn split(&mut self, region: usize) -> Option<Range<usize>> {
        let (c, l) = self.cell_of(region);
        let local = self.cells[c].split(l)?;
        if let Some(per_cell) = self.unsplit_per_cell {
            self.build_tables(per_cell);
        }
        let c = c as u32;
        let fresh = self.owner.len();
        for l in local {
            let g = self.owner.len() as u32;
            self.owner.push((c, l as u32));
            debug_assert_eq!(self.global_of[c as usize].len(), l);
            self.global_of[c as usize].push(g);
        }
        Some(fresh..self.owner.len())
    }
}

/// The partitions of the paper's four variants behind one type, for run-time choice:
/// FIXED and GLOBAL use [`PathPartition::Single`], RA-GRID and RA-QUADTREE a
/// [`ScreenPartition`] (lens) or a [`DirectionPartition`] (multi-chain).
#[derive(Clone, Debug)]
pub enum PathPartition<C> {
    /// One region covering path space (GLOBAL, section 8.1).
    Single,
    /// The 2-D screen partition.
    Screen(ScreenPartition<C>),
    /// The 4-D screen x direction partition.
    Direction(DirectionPartition<C>),
}

impl<C: Camera> Partition<Path> for PathPartition<C> {
    fn region(&self, x: &Path) -> usize {
        match self {
            Self::Single => 0,
            Self::Screen(p) => p.region(x),
            Self::Direction(p) => p.region(x),
        }
    }
    fn num_regions(&self) -> usize {
        match self {
            Self::Single => 1,
            Self::Screen(p) => p.num_regions(),
            Self::Direction(p) => p.num_regions(),
        }
    }
    fn split(&mut self, region: usize) -> Option<Range<usize>> {
        match self {
            Self::Single => None,
            Self::Screen(p) => p.split(region),
            Self::Direction(p) => p.split(region),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cylindrical_is_in_unit_square() {
        let dirs = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(-1.0, -1e-300, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.0, -1.0, 0.0),
        ];
        for d in dirs {
            let c = cylindrical(d);
            assert!(
                (0.0..=1.0).contains(&c[0]) && (0.0..1.0).contains(&c[1]),
                "{d:?} -> {c:?}"
            );
        }
        assert!((cylindrical(Vec3::new(0.0, -1.0, 0.0))[1] - 0.75).abs() < 1e-15);
    }
}
