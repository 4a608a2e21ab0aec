//! Viewcells: a grid of square cells over the scene's bounding rectangle at
//! an eye-height range, keeping only cells whose *free space* — the part of the box
//! not inside any object's solid — is non-empty.
//!
//! Solids are the objects' *inner* bounds (blocks: the blocks themselves; meshes:
//! their conservative inner 2.5D bound; flat objects: none), so a cell is only ever
//! dropped when it is surely inside buildings.
//!
//! The test is exact up to the 1 mm grid of [`sightline_geom::boolean`]: a box
//! `R × [z0, z1]` has free space iff for some slab `[lo, hi]` between consecutive
//! prism bases/tops, `R` minus the union of the footprints of the prisms spanning the
//! whole slab has positive area (a free region thinner than a 1 mm band along the
//! cell's border does not count). Several stacked prisms that together fill the slab
//! (an arcade under an upper floor) are handled by the slabs.
//!
//! ```
//! use sightline_scene::{cells, Object, Scene};
//! use sightline_geom::{DVec2, Polygon};
//! let s = Scene::from_objects(vec![Object::block(None,
//!     Polygon::rect(DVec2::ZERO, DVec2::new(100.0, 40.0)), 0.0, 20.0)]);
//! let grid = cells::grid_cells(&s, 20.0, 1.5, 2.0).unwrap();
//! assert!(grid.is_empty()); // every cell is inside the building
//! ```

use crate::index::SceneIndex;
use crate::{Prism, Scene};
use rayon::prelude::*;
use sightline_geom::{boolean, grid, Aabb2, Aabb3, DVec2, Polygon, ViewCell};

/// Grids larger than this are refused (they would not fit a `.pvs` anyway).
pub const MAX_CELLS: u64 = 20_000_000;

/// Why a grid of cells cannot be made.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CellError {
    #[error("cell size must be a positive number of metres, got {0}")]
    BadSize(f64),
    #[error("eye-height range must be finite with 0 <= z0 <= z1, got {0}:{1}")]
    BadZ(f64, f64),
    #[error("the grid would have {0} cells (more than {MAX_CELLS}): use a larger cell size")]
    TooMany(u64),
    #[error("the scene is empty: no bounding rectangle to cover")]
    EmptyScene,
}

/// Columns and rows of the grid of side `size_m` over the scene's bounding rectangle
/// ([`grid::cover`], the numbering the walkthrough server shares).
pub fn grid_shape(scene: &Scene, size_m: f64) -> (u64, u64) {
    let b = scene.bounds.xy();
    if b.is_empty() || size_m.is_nan() || size_m <= 0.0 {
        return (0, 0);
    }
    let c = grid::cover(b, size_m);
    (c.nx as u64, c.ny as u64)
}

/// Cells of side `size_m` covering the scene's bounding rectangle ([`grid::cover`]: row
/// by row from its minimum corner rounded down to a multiple of `size_m`; the first and
/// last rows and columns may stick out), at heights `z0..z1`,
/// keeping those whose free space is non-empty.
pub fn grid_cells(
    scene: &Scene,
    size_m: f64,
    z0: f64,
    z1: f64,
) -> Result<Vec<ViewCell>, CellError> {
    grid_cells_clipped(scene, size_m, z0, z1, None)
}

/// [`grid_cells`], keeping only cells whose free space meets the `clip` polygons
/// (e.g. the streets), when given.
pub fn grid_cells_clipped(
    scene: &Scene,
    size_m: f64,
    z0: f64,
    z1: f64,
    clip: Option<&[Polygon]>,
) -> Result<Vec<ViewCell>, CellError> {
    if !(size_m.is_finite() && size_m > 0.0) {
        return Err(CellError::BadSize(size_m));
    }
    if !(z0.is_finite() && z1.is_finite() && z0 >= 0.0 && z0 <= z1) {
        return Err(CellError::BadZ(z0, z1));
    }
    if scene.is_empty() || scene.bounds.is_empty() {
        return Err(CellError::EmptyScene);
    }
    let (nx, ny) = grid_shape(scene, size_m);
    let total = nx.saturating_mul(ny);
    if total > MAX_CELLS {
        return Err(CellError::TooMany(total));
    }
    let grid = grid::cover(scene.bounds.xy(), size_m).grid();
    let clip_bbox = clip.map(|c| c.iter().fold(Aabb2::EMPTY, |a, p| a.union(p.bbox())));
    let free = FreeSpace::new(scene);
    let cells: Vec<ViewCell> = (0..total)
        .into_par_iter()
        .filter_map(|k| {
            let (i, j) = grid.coords(k as u32)?;
            let cell = ViewCell::from_rect(grid.rect(i, j), z0, z1).ok()?;
            let keep = match (clip, clip_bbox) {
                (Some(c), Some(cb)) => {
                    cb.intersects(&cell.aabb().xy()) && free.is_free_in(&cell, c)
                }
                _ => free.is_free(&cell),
            };
            keep.then_some(cell)
        })
        .collect();
    Ok(cells)
}

/// Whether `cell` has non-empty free space in `scene` (a cell entirely inside
/// buildings is not a place to stand). Scans every object; for many cells use
/// [`FreeSpace`].
pub fn cell_is_free(scene: &Scene, cell: &ViewCell) -> bool {
    let r = cell.aabb().xy();
    let prisms: Vec<&Prism> = scene
        .objects
        .iter()
        .filter(|o| o.bounds.xy().intersects(&r))
        .flat_map(|o| &o.inner)
        .collect();
    box_is_free(
        &[Polygon::rect(r.min, r.max)],
        r,
        cell.min.z,
        cell.max.z,
        &prisms,
    )
}

/// Free-space tests for many cells of one scene, through a spatial index of the
/// objects' inner bounds.
pub struct FreeSpace<'a> {
    scene: &'a Scene,
    index: SceneIndex,
}

impl<'a> FreeSpace<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let index = SceneIndex::from_boxes(scene.objects.iter().enumerate().map(|(i, o)| {
            let b = o.inner.iter().fold(Aabb3::EMPTY, |b, p| b.union(p.aabb()));
            (i, b)
        }));
        FreeSpace { scene, index }
    }

    fn prisms(&self, cell: &ViewCell) -> Vec<&'a Prism> {
        let scene = self.scene;
        self.index
            .query_rect(&cell.aabb().xy())
            .into_iter()
            .flat_map(|id| &scene.objects[id as usize].inner)
            .collect()
    }

    /// Whether the cell's free space is non-empty.
    pub fn is_free(&self, cell: &ViewCell) -> bool {
        let r = cell.aabb().xy();
        let rect = [Polygon::rect(r.min, r.max)];
        box_is_free(&rect, r, cell.min.z, cell.max.z, &self.prisms(cell))
    }

    /// Whether the cell's free space meets the `clip` polygons.
    pub fn is_free_in(&self, cell: &ViewCell, clip: &[Polygon]) -> bool {
        let r = cell.aabb().xy();
        let region = boolean::intersection(&[Polygon::rect(r.min, r.max)], clip);
        if region.iter().map(Polygon::area).sum::<f64>() <= tolerance(r) {
            return false;
        }
        box_is_free(&region, r, cell.min.z, cell.max.z, &self.prisms(cell))
    }
}

/// Free area below this does not count: a 1 mm band along the cell's border (the
/// polygon booleans snap to 1 mm).
fn tolerance(r: Aabb2) -> f64 {
    boolean::GRID_M * 2.0 * (r.size().x + r.size().y)
}

/// Whether `region` (inside rectangle `r`) × `[z0, z1]` has free space among `prisms`.
fn box_is_free(region: &[Polygon], r: Aabb2, z0: f64, z1: f64, prisms: &[&Prism]) -> bool {
    let relevant: Vec<&Prism> = prisms
        .iter()
        .copied()
        .filter(|p| p.footprint.bbox().intersects(&r))
        .filter(|p| {
            if z0 < z1 {
                p.base < z1 && p.top > z0
            } else {
                p.base < z0 && p.top > z0
            }
        })
        .collect();
    if relevant.is_empty() {
        return true;
    }
    // Slabs between consecutive bases/tops inside (z0, z1).
    let mut breaks: Vec<f64> = vec![z0, z1];
    for p in &relevant {
        breaks.extend([p.base, p.top].into_iter().filter(|z| *z > z0 && *z < z1));
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup();
    let slabs: Vec<(f64, f64)> = if z0 < z1 {
        breaks.windows(2).map(|w| (w[0], w[1])).collect()
    } else {
        vec![(z0, z0)]
    };
    let plain_rect =
        region.len() == 1 && region[0].holes.is_empty() && region[0].exterior.len() == 4 && {
            let bb = region[0].bbox();
            bb == r
        };
    slabs.into_iter().any(|(lo, hi)| {
        let covering: Vec<&Polygon> = relevant
            .iter()
            .filter(|p| {
                if lo < hi {
                    p.base <= lo && p.top >= hi
                } else {
                    p.base < lo && p.top > lo
                }
            })
            .map(|p| &p.footprint)
            .collect();
        if covering.is_empty() {
            return true;
        }
        // Fast path: a sample point of the rectangle clearly outside every footprint.
        if plain_rect {
            let c = r.center();
            let samples = [
                c,
                r.min,
                r.max,
                DVec2::new(r.min.x, r.max.y),
                DVec2::new(r.max.x, r.min.y),
            ];
            if samples
                .iter()
                .any(|&q| covering.iter().all(|f| clearly_outside(f, q)))
            {
                return true;
            }
        }
        let footprints: Vec<Polygon> = covering.into_iter().cloned().collect();
        let rest = boolean::difference(region, &footprints);
        rest.iter().map(Polygon::area).sum::<f64>() > tolerance(r)
    })
}

/// `q` is outside `f` and more than a micrometre from its boundary.
fn clearly_outside(f: &Polygon, q: DVec2) -> bool {
    if f.contains(q) {
        return false;
    }
    f.edges().all(|(a, b)| {
        let ab = b - a;
        let t = if ab.length_squared() > 0.0 {
            ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + ab * t).distance_squared(q) > 1e-12
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Object;

    fn block(x0: f64, y0: f64, x1: f64, y1: f64, base: f64, top: f64) -> Object {
        Object::block(
            None,
            Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1)),
            base,
            top,
        )
    }

    fn cell(a: [f64; 6]) -> ViewCell {
        ViewCell::from_array(a).unwrap()
    }

    #[test]
    fn inside_touching_and_street_cells() {
        // Two touching buildings 0..40 × 0..20 (party wall at x = 20), a street beyond.
        let s = Scene::from_objects(vec![
            block(0.0, 0.0, 20.0, 20.0, 0.0, 15.0),
            block(20.0, 0.0, 40.0, 20.0, 0.0, 12.0),
            block(0.0, 30.0, 40.0, 40.0, 0.0, 10.0),
        ]);
        // Straddling the party wall, fully inside the union: not free.
        assert!(!cell_is_free(&s, &cell([15.0, 5.0, 1.5, 25.0, 15.0, 2.0])));
        // Exactly the first building's footprint: not free.
        assert!(!cell_is_free(&s, &cell([0.0, 0.0, 1.5, 20.0, 20.0, 2.0])));
        // Touching the facade y = 20 from the street: free.
        assert!(cell_is_free(&s, &cell([5.0, 20.0, 1.5, 15.0, 30.0, 2.0])));
        // Overlapping the facade by 1 m: free (the street part).
        assert!(cell_is_free(&s, &cell([5.0, 19.0, 1.5, 15.0, 29.0, 2.0])));
        // Above the lower roof (12 m) but inside the taller building's x range: free.
        assert!(cell_is_free(&s, &cell([25.0, 5.0, 13.0, 35.0, 15.0, 14.0])));
        // Standing on a roof (flat cell at the roof's height): free.
        assert!(cell_is_free(&s, &cell([25.0, 5.0, 12.0, 35.0, 15.0, 12.0])));
        // Flat cell inside: not free.
        assert!(!cell_is_free(&s, &cell([25.0, 5.0, 2.0, 35.0, 15.0, 2.0])));
    }

    #[test]
    fn stacked_prisms_fill_a_slab_together() {
        // An arcade 0..1.7 and an upper part 1.7..20 of the same footprint.
        let s = Scene::from_objects(vec![
            block(0.0, 0.0, 10.0, 10.0, 0.0, 1.7),
            block(0.0, 0.0, 10.0, 10.0, 1.7, 20.0),
        ]);
        assert!(!cell_is_free(&s, &cell([1.0, 1.0, 1.5, 9.0, 9.0, 2.0])));
        // With a gap between them, the cell is free.
        let s = Scene::from_objects(vec![
            block(0.0, 0.0, 10.0, 10.0, 0.0, 1.6),
            block(0.0, 0.0, 10.0, 10.0, 1.8, 20.0),
        ]);
        assert!(cell_is_free(&s, &cell([1.0, 1.0, 1.5, 9.0, 9.0, 2.0])));
    }

    #[test]
    fn grid_drops_inside_cells_and_keeps_facade_cells() {
        // A 100 × 100 scene: one building 0..60 × 0..60 and a marker block far away.
        let s = Scene::from_objects(vec![
            block(0.0, 0.0, 60.0, 60.0, 0.0, 20.0),
            block(99.0, 99.0, 100.0, 100.0, 0.0, 5.0),
        ]);
        let cells = grid_cells(&s, 20.0, 1.5, 2.0).unwrap();
        // 5 × 5 cells; the 3 × 3 inside the building are dropped (those touching its
        // facades from outside stay), and so is none of the others.
        assert_eq!(cells.len(), 25 - 9);
        assert!(cells.iter().all(|c| c.min.x >= 60.0 || c.min.y >= 60.0));
        assert_eq!(cells[0].to_array(), [60.0, 0.0, 1.5, 80.0, 20.0, 2.0]);
        // Same answer from the one-off test.
        for c in &cells {
            assert!(cell_is_free(&s, c));
        }
        // Clipped to a street polygon along y = 70: only the row at 60..80 stays.
        let street = Polygon::rect(DVec2::new(-10.0, 65.0), DVec2::new(110.0, 75.0));
        let clipped = grid_cells_clipped(&s, 20.0, 1.5, 2.0, Some(&[street])).unwrap();
        assert_eq!(clipped.len(), 5);
        assert!(clipped.iter().all(|c| c.min.y == 60.0));
    }

    #[test]
    fn bad_parameters_are_errors() {
        let s = Scene::from_objects(vec![block(0.0, 0.0, 10.0, 10.0, 0.0, 5.0)]);
        assert_eq!(grid_cells(&s, 0.0, 1.5, 2.0), Err(CellError::BadSize(0.0)));
        assert!(matches!(
            grid_cells(&s, f64::NAN, 1.5, 2.0),
            Err(CellError::BadSize(_))
        ));
        assert_eq!(
            grid_cells(&s, 5.0, 2.0, 1.5),
            Err(CellError::BadZ(2.0, 1.5))
        );
        assert!(matches!(
            grid_cells(&s, 1e-4, 1.5, 2.0),
            Err(CellError::TooMany(_))
        ));
        assert_eq!(
            grid_cells(&Scene::from_objects(vec![]), 5.0, 1.5, 2.0),
            Err(CellError::EmptyScene)
        );
    }
}
