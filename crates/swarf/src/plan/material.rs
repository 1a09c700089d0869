//! The material model as the planner sees it: exactly the queries and updates the linker and
//! the adaptive engine make of it, so that they can be driven (and tested) against any model
//! that answers them. [`RasterSim`] is the one swarf plans with.
//!
//! The model is a raster: the planner reads its grid and, for whole-grid scans (the adaptive
//! engine's start search), the cell heights and the cells the tool can reach. Everything else
//! is a query about the tool at a point or along a path, or an update by a cut.

use crate::geom::{DVec2, DVec3};
use crate::sim::grid::Grid;
use crate::sim::raster::RasterSim;
use crate::sim::sweep::Path;

/// What the planner asks of the material model and tells it.
///
/// Heights are in mm; "material at `z`" means material standing more than the model's `eps`
/// above `z`. The methods carry the names of [`RasterSim`]'s, which documents each.
pub(crate) trait Material {
    // ---- the raster ------------------------------------------------------------------------

    /// The grid of the model's cells.
    fn grid(&self) -> Grid;
    /// Current stock height per cell (row-major, −∞ where there is no stock).
    fn heights(&self) -> &[f32];
    /// Cells the tool can reach.
    fn reach_mask(&self) -> &[bool];
    /// Cells of the part and fixtures (grown by the allowance).
    fn keep_mask(&self) -> Vec<bool>;

    // ---- the tool at a point ---------------------------------------------------------------

    /// The tool's circumference as sampled by [`Self::ring_material`]: offsets from the
    /// centre, counter-clockwise from +X.
    fn ring(&self) -> &[DVec2];
    /// `out[i]`: material at `z` at `c + ring[i]`.
    fn ring_material(&self, c: DVec2, z: f64, out: &mut Vec<bool>);
    /// Engagement (degrees) of the front half of the tool at `c` moving along `dir`, against
    /// the stock as it is.
    fn front_engagement(&self, c: DVec2, z: f64, dir: DVec2) -> f64;
    /// Area (mm²) of the reachable material at `z` within `rho` of `c`.
    fn material_area_near(&self, c: DVec2, z: f64, rho: f64) -> f64;

    // ---- the tool along a path -------------------------------------------------------------

    /// Highest material within `rho` of the path (−∞ when none).
    fn max_height_near(&self, path: &Path, rho: f64) -> f32;
    /// No material above the tool's tip anywhere along the path (radius plus `margin`).
    fn is_clear(&self, path: &Path, margin: f64) -> bool;
    /// A straight move leaving the material the tool touches at `a`: `None` when it meets
    /// other material, else how far along it the tool still touches what it touched at `a`.
    fn leaving_distance(&self, a: DVec3, b: DVec3, margin: f64) -> Option<f64>;
    /// Distance in plan from the path to the part and fixtures, capped at `max` (0 inside).
    fn keep_distance(&self, path: &Path, max: f64) -> f64;

    // ---- updates and the level's account ---------------------------------------------------

    /// Cuts a move into the model.
    fn cut(&mut self, path: &Path);
    /// Cuts a horizontal step from `a` to `b` at `z` with the radius `r`; the cells lowered.
    fn cut_step_r(&mut self, a: DVec2, b: DVec2, z: f64, r: f64) -> usize;
    /// Starts counting the reachable material above `z`.
    fn begin_level(&mut self, z: f64);
    /// Reachable cells still standing above the level of [`Self::begin_level`].
    fn reach_left(&self) -> usize;
    /// The box of cells (i0, i1, j0, j1) cleared at the level since the last call.
    fn take_dirty(&mut self) -> Option<(usize, usize, usize, usize)>;
}

impl Material for RasterSim {
    #[inline]
    fn grid(&self) -> Grid {
        self.grid
    }
    #[inline]
    fn heights(&self) -> &[f32] {
        RasterSim::heights(self)
    }
    #[inline]
    fn reach_mask(&self) -> &[bool] {
        RasterSim::reach_mask(self)
    }
    #[inline]
    fn keep_mask(&self) -> Vec<bool> {
        RasterSim::keep_mask(self)
    }
    #[inline]
    fn ring(&self) -> &[DVec2] {
        RasterSim::ring(self)
    }
    #[inline]
    fn ring_material(&self, c: DVec2, z: f64, out: &mut Vec<bool>) {
        RasterSim::ring_material(self, c, z, out)
    }
    #[inline]
    fn front_engagement(&self, c: DVec2, z: f64, dir: DVec2) -> f64 {
        RasterSim::front_engagement(self, c, z, dir)
    }
    #[inline]
    fn material_area_near(&self, c: DVec2, z: f64, rho: f64) -> f64 {
        RasterSim::material_area_near(self, c, z, rho)
    }
    #[inline]
    fn max_height_near(&self, path: &Path, rho: f64) -> f32 {
        RasterSim::max_height_near(self, path, rho)
    }
    #[inline]
    fn is_clear(&self, path: &Path, margin: f64) -> bool {
        RasterSim::is_clear(self, path, margin)
    }
    #[inline]
    fn leaving_distance(&self, a: DVec3, b: DVec3, margin: f64) -> Option<f64> {
        RasterSim::leaving_distance(self, a, b, margin)
    }
    #[inline]
    fn keep_distance(&self, path: &Path, max: f64) -> f64 {
        RasterSim::keep_distance(self, path, max)
    }
    #[inline]
    fn cut(&mut self, path: &Path) {
        RasterSim::cut(self, path)
    }
    #[inline]
    fn cut_step_r(&mut self, a: DVec2, b: DVec2, z: f64, r: f64) -> usize {
        RasterSim::cut_step_r(self, a, b, z, r)
    }
    #[inline]
    fn begin_level(&mut self, z: f64) {
        RasterSim::begin_level(self, z)
    }
    #[inline]
    fn reach_left(&self) -> usize {
        RasterSim::reach_left(self)
    }
    #[inline]
    fn take_dirty(&mut self) -> Option<(usize, usize, usize, usize)> {
        RasterSim::take_dirty(self)
    }
}
