//! The viewcells of a BSP level: each open leaf a viewer can stand in is the convex
//! polyhedron cut out by the half-spaces of the node planes on its path from the root
//! (its [`Cell::Convex`], numbered by its leaf), so a `.pvs` of a level answers
//! `query --at` by the leaf's own shape, as the tree's point location does.

use sightline_core::{Cell, ConvexCell, HalfSpace};
use sightline_geom::{DVec3, ViewCell};
use sightline_scene::import::bsp::{BspLevel, Child};

/// How far a leaf's stored box is widened (Quake units): the file keeps it in whole
/// units, cut towards zero, so it may fall short of the leaf by less than one unit.
const BOX_SLACK: f64 = 1.0;

/// The open view leaves (`1 ..= visleafs`) of `level`, ascending, as convex cells.
pub fn leaf_cells(level: &BspLevel) -> Vec<Cell> {
    let mut out: Vec<(u32, Vec<HalfSpace>)> = Vec::new();
    // Depth-first from the root with the half-spaces of the path.
    let mut stack: Vec<(Child, Vec<HalfSpace>)> = vec![(level.headnode, Vec::new())];
    let mut guard = 0usize;
    while let Some((c, path)) = stack.pop() {
        guard += 1;
        if guard > 4 * (level.nodes.len() + level.leaves.len()) + 4 {
            break; // The importer checks the tree; this only bounds a damaged one.
        }
        match c {
            Child::Leaf(l) => {
                if level.is_view_leaf(l) {
                    out.push((l, path));
                }
            }
            Child::Node(n) => {
                let Some(node) = level.nodes.get(n as usize) else {
                    continue;
                };
                let Some(p) = level.planes.get(node.plane as usize) else {
                    continue;
                };
                let normal = DVec3::from(p.normal);
                // Front: n·x >= d (point location sends d > 0 there); back: n·x <= d.
                let mut front = path.clone();
                front.push(HalfSpace {
                    normal: -normal,
                    offset: -p.dist,
                });
                let mut back = path;
                back.push(HalfSpace {
                    normal,
                    offset: p.dist,
                });
                stack.push((node.children[0], front));
                stack.push((node.children[1], back));
            }
        }
    }
    out.sort_by_key(|(l, _)| *l);
    out.into_iter()
        .filter_map(|(l, planes)| {
            let leaf = level.leaves.get(l as usize)?;
            let lo = DVec3::from(leaf.mins) - DVec3::splat(BOX_SLACK);
            let hi = DVec3::from(leaf.maxs) + DVec3::splat(BOX_SLACK);
            let bounds = ViewCell::from_array([lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]).ok()?;
            Some(Cell::Convex(ConvexCell::new(l, bounds, planes)))
        })
        .collect()
}
