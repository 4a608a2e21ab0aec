//! The portal solver as a [`VisibilityMethod`] (`portals`, `portals-fast`): a viewcell
//! is answered by the leaves it meets.

use crate::{LeafPvs, Mode, Portals};
use sightline_core::{Cell, Method, MethodError, VisibilityMethod};
use sightline_geom::ViewCell;
use std::sync::OnceLock;

/// `portals` or `portals-fast` prepared for one level; leaf PVS are computed on first
/// use and kept. `portals` answers a leaf from the flows of its own portals
/// ([`Portals::solve_local`]: well under a second, no level-wide precomputation);
/// [`Portals::solve_all`] is the tighter level-wide answer for whole-level builds.
pub struct PortalMethod {
    portals: Portals,
    mode: Mode,
    cache: Vec<OnceLock<LeafPvs>>,
}

impl PortalMethod {
    pub fn new(portals: Portals, mode: Mode) -> Self {
        let cache = (0..portals.level().leaves.len())
            .map(|_| OnceLock::new())
            .collect();
        PortalMethod {
            portals,
            mode,
            cache,
        }
    }

    pub fn portals(&self) -> &Portals {
        &self.portals
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The PVS of one leaf (computed once).
    pub fn leaf_pvs(&self, leaf: u32) -> LeafPvs {
        match self.cache.get(leaf as usize) {
            Some(c) => c
                .get_or_init(|| match self.mode {
                    Mode::Full => self.portals.solve_local(leaf),
                    Mode::Fast => self.portals.solve(leaf, Mode::Fast),
                })
                .clone(),
            None => LeafPvs {
                leaf,
                ..LeafPvs::default()
            },
        }
    }

    /// The PVS of the leaf holding `p`.
    pub fn at(&self, p: [f64; 3]) -> LeafPvs {
        self.leaf_pvs(self.portals.level().point_leaf(p))
    }
}

impl VisibilityMethod for PortalMethod {
    fn name(&self) -> &'static str {
        match self.mode {
            Mode::Full => Method::Portals.name(),
            Mode::Fast => Method::PortalsFast.name(),
        }
    }

    /// The union of the face PVS of every open leaf whose box meets `cell` (a
    /// superset of the leaves the cell meets).
    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        let level = self.portals.level();
        let mut faces = Vec::new();
        for leaf in 1..=level.visleafs {
            let l = &level.leaves[leaf as usize];
            let meets = (0..3).all(|k| l.mins[k] <= cell.max[k] && l.maxs[k] >= cell.min[k]);
            if meets && l.is_open() {
                faces.extend(self.leaf_pvs(leaf).faces);
            }
        }
        faces.sort_unstable();
        faces.dedup();
        Ok(faces)
    }

    /// A convex cell is a leaf (its id): the leaf's face PVS.
    fn pvs_cell(&self, cell: &Cell) -> Result<Vec<u32>, MethodError> {
        match cell {
            Cell::Convex(c) if (c.id as usize) < self.cache.len() => Ok(self.leaf_pvs(c.id).faces),
            other => self.pvs(&other.bounds()),
        }
    }
}
