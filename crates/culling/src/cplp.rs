//! `cplp`: prioritized-layered projection made conservative (Klosowski & Silva, PLP,
//! IEEE TVCG 2000; cPLP, 2001; survey §6 and slides "PLP"/"cPLP").
//!
//! The scene is tessellated once into a uniform grid of cells ([`CplpOptions::cell_m`]);
//! each occluder prism and each occludee box belongs to the cell of its centre, and a
//! cell's box is the union of its members' boxes. A cell's *solidity* is the footprint
//! area of its occluders over the cell's area (capped at 1), PLP's estimate of how much
//! it blocks.
//!
//! Per frame the cells in the frustum are visited front to back (by distance from the eye
//! to the cell's box: PLP's priority; the solidity-accumulated priority of the paper
//! orders cells only for its time budget, which conservative culling has no use for). A
//! cell whose box is already hidden in the masked depth buffer of [`crate::hzb`] is
//! skipped whole: none of its occludees is visible and its occluders are not drawn.
//! Otherwise its occluders are drawn (those of cells at least
//! [`CplpOptions::min_solidity`] solid) and its occludees tested one by one. This is the
//! cPLP answer: PLP's front finds the candidates, the occlusion tests of what it reaches
//! make it conservative.
//!
//! Guarantee: an object reported hidden is hidden (every test is against a conservative
//! buffer of a subset of the occluders, which only over-estimates what is visible).

use crate::frustum::{box_in_view, clip_project, BoxInView, Frustum};
use crate::masked::MaskedBuffer;
use crate::scene::CullScene;
use crate::{Culler, Frame};
use glam::DVec3;
use std::sync::Arc;

/// Knobs of cPLP.
#[derive(Clone, Debug, PartialEq)]
pub struct CplpOptions {
    /// Side of the grid cells (metres).
    pub cell_m: f64,
    /// Cells less solid than this draw no occluders.
    pub min_solidity: f64,
}

impl Default for CplpOptions {
    fn default() -> Self {
        CplpOptions {
            cell_m: 40.0,
            min_solidity: 0.0,
        }
    }
}

#[derive(Clone, Debug)]
struct Cell {
    lo: DVec3,
    hi: DVec3,
    occluders: Vec<u32>,
    occludees: Vec<u32>,
    solidity: f64,
}

/// The `cplp` culler.
#[derive(Clone, Debug)]
pub struct Cplp {
    scene: Arc<CullScene>,
    opts: CplpOptions,
    cells: Vec<Cell>,
}

impl Cplp {
    pub fn new(scene: Arc<CullScene>, opts: CplpOptions) -> Cplp {
        let cell_m = if opts.cell_m > 0.0 { opts.cell_m } else { 40.0 };
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for &(a, b) in &scene.boxes {
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let mut cells: Vec<Cell> = Vec::new();
        if scene.boxes.is_empty() {
            return Cplp { scene, opts, cells };
        }
        let nx = (((hi.x - lo.x) / cell_m).ceil() as usize).clamp(1, 4096);
        let ny = (((hi.y - lo.y) / cell_m).ceil() as usize).clamp(1, 4096);
        let mut grid: Vec<Option<usize>> = vec![None; nx * ny];
        let mut cell_of = |c: DVec3, cells: &mut Vec<Cell>| -> usize {
            let x = (((c.x - lo.x) / cell_m) as usize).min(nx - 1);
            let y = (((c.y - lo.y) / cell_m) as usize).min(ny - 1);
            *grid[y * nx + x].get_or_insert_with(|| {
                cells.push(Cell {
                    lo: DVec3::splat(f64::MAX),
                    hi: DVec3::splat(f64::MIN),
                    occluders: Vec::new(),
                    occludees: Vec::new(),
                    solidity: 0.0,
                });
                cells.len() - 1
            })
        };
        for (k, o) in scene.occluders.iter().enumerate() {
            let c = cell_of((o.lo + o.hi) / 2.0, &mut cells);
            let cell = &mut cells[c];
            cell.lo = cell.lo.min(o.lo);
            cell.hi = cell.hi.max(o.hi);
            cell.occluders.push(k as u32);
            cell.solidity += (o.hi.x - o.lo.x) * (o.hi.y - o.lo.y) / (cell_m * cell_m);
        }
        for (id, &(a, b)) in scene.boxes.iter().enumerate() {
            let c = cell_of((a + b) / 2.0, &mut cells);
            let cell = &mut cells[c];
            cell.lo = cell.lo.min(a);
            cell.hi = cell.hi.max(b);
            cell.occludees.push(id as u32);
        }
        for c in &mut cells {
            c.solidity = c.solidity.min(1.0);
        }
        Cplp { scene, opts, cells }
    }

    /// Number of non-empty cells of the tessellation.
    pub fn cell_count(&self) -> usize {
        self.cells.len()
    }
}

impl Culler for Cplp {
    fn name(&self) -> &'static str {
        "cplp"
    }

    fn paper(&self) -> &'static str {
        "Klosowski & Silva 2000 (PLP) and 2001 (cPLP), survey §6"
    }

    fn cull(&self, frustum: &Frustum, candidates: Option<&[u32]>) -> Frame {
        let view = frustum.view();
        let eye = frustum.eye;
        let allowed = candidates.map(|c| crate::mask_of(c, self.scene.objects()));
        let is_candidate = |id: u32| allowed.as_ref().is_none_or(|a| a[id as usize]);
        let mut frame = Frame::new(self.scene.objects(), candidates);
        let mut order: Vec<(f64, u32, BoxInView)> = Vec::new();
        for (k, c) in self.cells.iter().enumerate() {
            match box_in_view(view, c.lo, c.hi) {
                BoxInView::Outside => {
                    frame.frustum_culled +=
                        c.occludees.iter().filter(|&&i| is_candidate(i)).count();
                }
                b => order.push((eye.clamp(c.lo, c.hi).distance_squared(eye), k as u32, b)),
            }
        }
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut buf = MaskedBuffer::new(view.width_px, view.height_px);
        let mut scratch = Vec::with_capacity(16);
        for &(_, k, b) in &order {
            let cell = &self.cells[k as usize];
            if let Some(([i0, j0, i1, j1], z_near)) = b.rect() {
                if buf.rect_occluded(i0, j0, i1, j1, z_near) {
                    frame.occlusion_culled +=
                        cell.occludees.iter().filter(|&&i| is_candidate(i)).count();
                    continue;
                }
            }
            if cell.solidity >= self.opts.min_solidity {
                for &o in &cell.occluders {
                    let o = &self.scene.occluders[o as usize];
                    if !is_candidate(o.object) {
                        continue;
                    }
                    // Outside, or already hidden: it hides nothing more.
                    let b = box_in_view(view, o.lo, o.hi);
                    let hidden = b
                        .rect()
                        .is_some_and(|([i0, j0, i1, j1], z)| buf.rect_occluded(i0, j0, i1, j1, z));
                    if b == BoxInView::Outside || hidden {
                        continue;
                    }
                    for (f, verts) in self.scene.front_faces(o, eye) {
                        frame.occluder_tris += f.tris as u64;
                        if clip_project(view, verts, &mut scratch) {
                            buf.draw_polygon(&scratch);
                        }
                    }
                }
            }
            for &id in cell.occludees.iter().filter(|&&i| is_candidate(i)) {
                frame.test_box(
                    view,
                    id,
                    self.scene.boxes[id as usize],
                    |[i0, j0, i1, j1], z| buf.rect_occluded(i0, j0, i1, j1, z),
                );
            }
        }
        frame.finish();
        frame
    }
}
