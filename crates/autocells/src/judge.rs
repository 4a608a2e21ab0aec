//! The judge of the automatic cells: the item-buffer ground truth of `sightline-core`
//! (`TruthScene::ground_truth_in`), independent of voxels and portals, sampled in the
//! free space of a spread of cells ([`AutoCells::free_region`]); every cluster it sees
//! must be in the cell's PVS.

use crate::cells::{world_box, VoxelBox};
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
        self.judge_boxes(scene, &self.boxes, |c| self.pvs(c), k, opts)
    }

    /// Judge up to `k` of `boxes` (voxel boxes, e.g. walkable viewcells), spread over
    /// the list, whose PVS `pvs_of(i)` gives, against the truth of `scene` sampled in
    /// their free space ([`AutoCells::free_region_of`]).
    pub fn judge_boxes(
        &self,
        scene: &Scene,
        boxes: &[VoxelBox],
        pvs_of: impl Fn(usize) -> Vec<u32>,
        k: usize,
        opts: &TruthOptions,
    ) -> Vec<JudgedCell> {
        let truth = TruthScene::new(scene);
        let mut out = Vec::new();
        let step = (boxes.len() / (4 * k).max(1)).max(1);
        for c in (0..boxes.len()).step_by(step) {
            if out.len() >= k {
                break;
            }
            let Some(region) = self.free_region_of(&boxes[c], c as u32) else {
                continue;
            };
            let t = truth.ground_truth_in(&region, opts);
            if t.samples_used == 0 {
                continue;
            }
            let pvs = pvs_of(c);
            let missed = t
                .visible
                .iter()
                .zip(&t.witnesses)
                .filter(|(o, _)| pvs.binary_search(o).is_err())
                .map(|(_, w)| *w)
                .collect();
            out.push(JudgedCell {
                cell: c as u32,
                bounds: world_box(&self.voxels, &boxes[c]),
                viewpoints: t.samples_used,
                truth: t.visible.len(),
                pvs: pvs.len(),
                missed,
            });
        }
        out
    }
}
