//! Adaptive preprocess (Durand et al. 2000, §6.1 "Adaptive preprocess").
//!
//! "If we are satisfied with the size of the PVS, we proceed to the next cell.
//! Otherwise, the cell is subdivided and we recurse on the sub-cells. Nonetheless,
//! occlusion culling is only performed on the remaining visible objects, i.e. those
//! contained in the PVS of the parent." Smaller cells see more similar views, so their
//! occluder Projections are larger and their occludee Projections smaller.
//!
//! For a query on one cell, every viewpoint of the cell lies in some leaf sub-cell, so
//! the union of the leaves' PVSs is a conservative PVS of the cell, contained in the
//! parent's. The termination criterion is the paper's polygon budget, counted here in
//! objects, down to a minimum horizontal cell size.

use super::ExtProj;
use sightline_geom::ViewCell;

/// PVS of `cell` among `candidates`, subdividing while it exceeds `budget` objects.
pub fn pvs(ext: &ExtProj, cell: &ViewCell, candidates: &[u32], budget: usize) -> Vec<u32> {
    let parent = ext.pvs_among(cell, candidates);
    if parent.len() <= budget {
        return parent;
    }
    let s = cell.size();
    let axis = if s.x >= s.y { 0 } else { 1 };
    if s[axis] * 0.5 < ext.params.adaptive_min_m {
        return parent;
    }
    let mid = 0.5 * (cell.min[axis] + cell.max[axis]);
    let mut lo_max = cell.max;
    lo_max[axis] = mid;
    let mut hi_min = cell.min;
    hi_min[axis] = mid;
    let halves = [(cell.min, lo_max), (hi_min, cell.max)];
    let mut out: Vec<u32> = Vec::with_capacity(parent.len());
    for (a, b) in halves {
        match ViewCell::new(a, b) {
            Ok(child) => out.extend(pvs(ext, &child, &parent, budget)),
            Err(_) => return parent,
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}
