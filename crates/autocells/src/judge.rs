//! The judge of the automatic cells: the item-buffer ground truth of `sightline-core`
//! (`TruthScene::ground_truth_in`), independent of voxels and portals, sampled in the
//! free space of a spread of cells ([`AutoCells::free_region`]); every cluster it sees
//! must be in the cell's PVS.

use crate::AutoCells;
use serde::Serialize;
use sightline_core::check::{TruthOptions, TruthScene, Witness};
use sightline_geom::ViewCell;
use sightline_scene::Scene;

/// One judged cell.
#[derive(Clone, Debug, Serialize)]
pub struct JudgedCell {
    pub cell: u32,
    pub bounds: ViewCell,
    /// Viewpoints the truth used (free voxels of the cell).
    pub viewpoints: u32,
    /// Clusters the truth sees, and the PVS's size.
    pub truth: usize,
    pub pvs: usize,
    /// Clusters the truth sees and the PVS lacks, with the truth's witness rays.
    pub missed: Vec<Witness>,
}

impl AutoCells {
    /// Judge up to `k` cells spread over the cell list (cells with no free voxel
    /// that sees a front are skipped) against the truth of `scene`, the clustered
    /// scene the cells were cut from.
    pub fn judge(&self, scene: &Scene, k: usize, opts: &TruthOptions) -> Vec<JudgedCell> {
        let truth = TruthScene::new(scene);
        let mut out = Vec::new();
        let step = (self.len() / (4 * k).max(1)).max(1);
        for c in (0..self.len()).step_by(step) {
            if out.len() >= k {
                break;
            }
            let Some(region) = self.free_region(c) else {
                continue;
            };
            let t = truth.ground_truth_in(&region, opts);
            if t.samples_used == 0 {
                continue;
            }
            let pvs = self.pvs(c);
            let missed = t
                .visible
                .iter()
                .zip(&t.witnesses)
                .filter(|(o, _)| pvs.binary_search(o).is_err())
                .map(|(_, w)| *w)
                .collect();
            out.push(JudgedCell {
                cell: c as u32,
                bounds: self.cell_box(c),
                viewpoints: t.samples_used,
                truth: t.visible.len(),
                pvs: pvs.len(),
                missed,
            });
        }
        out
    }
}
