//! Automatic cells and portals for any triangle level (an OBJ or glTF game level, a
//! building): conservative voxelization at a declared smallest hole, free space cut
//! into boxes, portals on their shared faces, then the PVS of every cell by portal
//! sequences a line can stab — Teller & Séquin, "Visibility preprocessing for
//! interactive walkthroughs" (SIGGRAPH 1991), with the flow of [`sightline_portals::flow`].
//!
//! Guarantee: a cluster is reported hidden from a cell only if no line from a point of
//! the cell's free space (outside every solid voxel's closed geometry) reaches one of
//! its triangles through open voxels; solid voxels lie wholly inside closed geometry,
//! so occluders only shrink.
//!
//! * [`voxels`] — surface, air and solid voxels, leaks;
//! * [`cells`] — greedy boxes of open voxels and the portals between them;
//! * [`soup`] — a Quake level's faces as a triangle soup, judged against the BSP path;
//! * [`AutoCells`] — the whole pipeline and the per-cell cluster PVS.
//!
//! ```
//! use sightline_autocells::{testlevel, AutoCells, Options};
//! let scene = testlevel::two_rooms_and_a_door(0.0);
//! let auto = AutoCells::build(&scene, &Options { smallest_hole: Some(0.45), ..Options::default() }).unwrap();
//! let pvs = auto.pvs_at([-4.0, 0.0, 1.5]).unwrap();
//! assert!(!pvs.is_empty() && pvs.len() < scene.objects.len());
//! ```

pub mod cells;
pub mod faces;
pub mod judge;
pub mod soup;
pub mod testlevel;
pub mod viewcells;
pub mod volumetric;
pub mod voxels;

use cells::{greedy_boxes, portals, world_box, Portal, VoxelBox};
use rayon::prelude::*;
use sightline_core::{Cell, VoxelCell};
use sightline_geom::{DVec3, ViewCell};
use sightline_portals::bits::Bits;
use sightline_portals::flow::{cell_pvs, flow_all_within, might_see_all, Graph};
use sightline_scene::Scene;
use std::time::Instant;
use voxels::{Grid, Leak, VoxelStats, Voxels, SURFACE};

/// Parameters (the knobs of a game engine's occlusion bake).
#[derive(Clone, Debug)]
pub struct Options {
    /// Voxel size (scene units). Openings are never closed, whatever their size;
    /// walls thinner than about twice this do not occlude. `None`: 0.5 (a person-sized
    /// walkthrough in metres), doubled until the grid fits `max_voxels`.
    pub smallest_hole: Option<f64>,
    /// Voxel budget; the smallest hole is raised to fit (reported).
    pub max_voxels: usize,
    /// Share of front-face hits an enclosed region may see and still be solid.
    pub backface_tolerance: f64,
    /// Rule 2 of [`voxels`]: voxels behind the geometry along every axis are solid
    /// (off by default: not conservative, see docs/methods/auto-cells.md).
    pub axis_rule: bool,
    /// Largest cell side, in voxels.
    pub max_box: usize,
    /// Cells stop at closed faces ([`faces`]) instead of growing through them: walls
    /// on the lattice then bound cells, which the full flow needs to see them as
    /// occluders; off by default, since the layer of voxels behind a closed face
    /// becomes thin cells that widen the base flood (portals never cross a closed face
    /// either way).
    pub walls_bound_cells: bool,
    /// With `full`: most cells one portal's flow may enter before it answers the
    /// portal's base flood instead (conservative either way; `None`: no bound).
    pub flow_budget: Option<usize>,
    /// `true`: the flow through portal sequences (`portals`); `false`: the base flood
    /// only (`portals-fast`).
    pub full: bool,
    /// The solver's cells when there are more than [`GROUP_ABOVE`] boxes: boxes
    /// connected within blocks of this many voxels a side ([`cells::group_boxes`]);
    /// 0 or 1: every box its own cell.
    pub group_block: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            smallest_hole: None,
            max_voxels: 1 << 24,
            backface_tolerance: 0.05,
            axis_rule: false,
            max_box: 64,
            walls_bound_cells: false,
            flow_budget: Some(DEFAULT_FLOW_BUDGET),
            full: true,
            group_block: 32,
        }
    }
}

/// Why a level cannot be cut into cells.
#[derive(Debug, thiserror::Error)]
pub enum AutoError {
    #[error("the scene has no triangles")]
    NoTriangles,
    #[error("the scene's bounds are not finite")]
    NotFinite,
    #[error("smallest hole {0} must be positive and finite")]
    BadHole(f64),
    #[error("smallest hole {hole} is larger than the level ({extent:.3} across its longest side): nothing could occlude")]
    HoleTooLarge { hole: f64, extent: f64 },
    #[error("no free space: every voxel is solid")]
    NoFreeSpace,
    #[error("point {0:?} is not in the level's free space (solid or outside the grid)")]
    NotFree([f64; 3]),
}

/// Counts and timings of a build.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Report {
    pub smallest_hole: f64,
    /// The smallest hole asked for, when the voxel budget raised it.
    pub smallest_hole_asked: Option<f64>,
    pub grid: [usize; 3],
    pub voxels: VoxelStats,
    pub cells: usize,
    pub portals: usize,
    /// The solver's cells (groups of boxes) and the portals between them.
    pub groups: usize,
    pub group_portals: usize,
    pub clusters: usize,
    pub seconds_voxels: f64,
    pub seconds_cells: f64,
    pub seconds_pvs: f64,
    pub leak: Option<Leak>,
}

/// A level cut into automatic cells, with the cluster PVS of every cell.
pub struct AutoCells {
    pub voxels: Voxels,
    pub boxes: Vec<VoxelBox>,
    /// Each voxel's cell (`u32::MAX` for solid voxels).
    pub owner: Vec<u32>,
    pub portals: Vec<Portal>,
    /// Cells visible from each cell (itself included).
    pub cell_pvs: Vec<Bits>,
    /// Clusters (scene objects) touching each cell's voxels, sorted.
    pub cell_clusters: Vec<Vec<u32>>,
    pub objects: usize,
    /// The scene's bounding box: viewpoints and targets lie in it.
    pub bounds: ViewCell,
    pub report: Report,
    /// The triangles voxelized, and each one's cluster (scene object).
    pub tris: Vec<[DVec3; 3]>,
    pub tri_object: Vec<u32>,
}

impl AutoCells {
    /// Voxelize `scene`, cut its free space into cells and portals, and solve every
    /// cell. Objects of `scene` are the clusters the PVS lists.
    pub fn build(scene: &Scene, opts: &Options) -> Result<AutoCells, AutoError> {
        let mut auto = AutoCells::cut(scene, opts)?;
        auto.solve(opts.full, opts.group_block, opts.flow_budget);
        Ok(auto)
    }

    /// The cells and portals without their PVS (every cell sees every cell until
    /// [`AutoCells::solve`]).
    pub fn cut(scene: &Scene, opts: &Options) -> Result<AutoCells, AutoError> {
        let t0 = Instant::now();
        let mut tris = Vec::new();
        let mut tri_object = Vec::new();
        for (id, o) in scene.objects.iter().enumerate() {
            for t in o.triangles() {
                tris.push(t);
                tri_object.push(id as u32);
            }
        }
        if tris.is_empty() {
            return Err(AutoError::NoTriangles);
        }
        let b = scene.bounds;
        if !(b.min.is_finite() && b.max.is_finite()) {
            return Err(AutoError::NotFinite);
        }
        let extent = b.max - b.min;
        let longest = extent.max_element();
        let asked = opts.smallest_hole.unwrap_or(0.5);
        if !(asked.is_finite() && asked > 0.0) {
            return Err(AutoError::BadHole(asked));
        }
        if asked > longest {
            return Err(AutoError::HoleTooLarge {
                hole: asked,
                extent: longest,
            });
        }
        let grid = lattice_grid(b.min, b.max, asked, opts.max_voxels);
        let h = grid.size;
        let voxels = voxels::voxelize_with(grid, &tris, opts.backface_tolerance, opts.axis_rule);
        let seconds_voxels = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let (boxes, owner) = greedy_boxes(&voxels, opts.max_box, opts.walls_bound_cells);
        if boxes.is_empty() {
            return Err(AutoError::NoFreeSpace);
        }
        let portals = portals(&voxels, &boxes, &owner);
        let mut cell_clusters = vec![Vec::new(); boxes.len()];
        for (v, &s) in voxels.state.iter().enumerate() {
            if s == SURFACE && owner[v] != u32::MAX {
                let list = &mut cell_clusters[owner[v] as usize];
                list.extend(
                    voxels
                        .triangles_in(v)
                        .iter()
                        .map(|&t| tri_object[t as usize]),
                );
            }
        }
        for l in &mut cell_clusters {
            l.sort_unstable();
            l.dedup();
        }
        let seconds_cells = t1.elapsed().as_secs_f64();
        let n = boxes.len();
        let mut all = Bits::new(n);
        (0..n).for_each(|c| all.set(c));
        let report = Report {
            smallest_hole: h,
            smallest_hole_asked: (h != asked).then_some(asked),
            grid: voxels.grid.dims,
            voxels: voxels.stats.clone(),
            cells: n,
            portals: portals.len(),
            groups: n,
            group_portals: portals.len(),
            clusters: scene.objects.len(),
            seconds_voxels,
            seconds_cells,
            seconds_pvs: 0.0,
            leak: voxels.leak.clone(),
        };
        Ok(AutoCells {
            voxels,
            boxes,
            owner,
            portals,
            cell_pvs: vec![all; n],
            cell_clusters,
            objects: scene.objects.len(),
            bounds: ViewCell {
                min: b.min,
                max: b.max,
            },
            report,
            tris,
            tri_object,
        })
    }

    /// The cell PVS of every cell: the flow through portal sequences (`full`) or the
    /// base flood, on the boxes grouped by [`cells::group_boxes`] (`group_block`) when
    /// there are more than [`GROUP_ABOVE`]; a box sees every box of every group its
    /// group sees. The flow of a portal that would enter more than `flow_budget` cells
    /// answers the portal's flood instead (a superset).
    pub fn solve(&mut self, full: bool, group_block: usize, flow_budget: Option<usize>) {
        let t2 = Instant::now();
        let n = self.boxes.len();
        let (group, groups) = if group_block > 1 && n > GROUP_ABOVE {
            cells::group_boxes(&self.boxes, &self.portals, group_block)
        } else {
            ((0..n as u32).collect(), n)
        };
        let graph = Graph::from_portals(
            groups,
            self.portals.iter().filter_map(|p| {
                let [a, b] = p.cells.map(|c| group[c as usize]);
                (a != b).then_some((&p.winding, p.plane, [a, b]))
            }),
        );
        let mightsee = might_see_all(&graph);
        let sets = if full {
            flow_all_within(&graph, &mightsee, flow_budget)
        } else {
            mightsee
        };
        let group_pvs: Vec<Bits> = (0..groups)
            .into_par_iter()
            .map(|c| cell_pvs(&graph, &sets, c as u32))
            .collect();
        self.cell_pvs = (0..n)
            .into_par_iter()
            .map(|b| {
                let g = &group_pvs[group[b] as usize];
                let mut seen = Bits::new(n);
                for (other, &og) in group.iter().enumerate() {
                    if g.get(og as usize) {
                        seen.set(other);
                    }
                }
                seen
            })
            .collect();
        self.report.groups = groups;
        self.report.group_portals = graph.portals.len() / 2;
        self.report.seconds_pvs = t2.elapsed().as_secs_f64();
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }

    /// The world box of cell `c`.
    pub fn cell_box(&self, c: usize) -> ViewCell {
        world_box(&self.voxels, &self.boxes[c])
    }

    /// Every cell as its box, in cell order.
    pub fn cell_boxes(&self) -> Vec<ViewCell> {
        (0..self.len()).map(|c| self.cell_box(c)).collect()
    }

    /// The cell holding `p`.
    pub fn locate(&self, p: [f64; 3]) -> Option<u32> {
        let c = self.voxels.grid.locate(DVec3::from_array(p))?;
        let o = self.owner[self.voxels.grid.index(c[0], c[1], c[2])];
        (o != u32::MAX).then_some(o)
    }

    /// The clusters potentially visible from cell `c`, sorted.
    pub fn pvs(&self, c: usize) -> Vec<u32> {
        let mut seen = Bits::new(self.objects);
        for v in self.cell_pvs[c].ones() {
            for &o in &self.cell_clusters[v] {
                seen.set(o as usize);
            }
        }
        seen.ones().map(|o| o as u32).collect()
    }

    /// The clusters potentially visible from the cell holding `p`.
    pub fn pvs_at(&self, p: [f64; 3]) -> Result<Vec<u32>, AutoError> {
        let c = self.locate(p).ok_or(AutoError::NotFree(p))?;
        Ok(self.pvs(c as usize))
    }

    /// The free space of cell `c` for judging: its air voxels that meet the front of a
    /// triangle along some axis (a surface voxel may hold points inside walls, and air
    /// in the void around the level sees only backs: neither is a viewpoint), clipped
    /// to the scene's bounding box, as a voxel cell; `None` when it has none.
    pub fn free_region(&self, c: usize) -> Option<Cell> {
        self.free_region_of(&self.boxes[c], c as u32)
    }

    /// The free space of any voxel box, as [`AutoCells::free_region`] (cell id `id`).
    pub fn free_region_of(&self, b: &VoxelBox, id: u32) -> Option<Cell> {
        let g = &self.voxels.grid;
        let mut boxes = Vec::new();
        for z in b.lo[2]..b.hi[2] {
            for y in b.lo[1]..b.hi[1] {
                for x in b.lo[0]..b.hi[0] {
                    let v = g.index(x, y, z);
                    if self.voxels.state[v] == voxels::AIR && self.voxels.sees_front[v] {
                        let min = g.voxel_min([x, y, z]).max(self.bounds.min);
                        let max =
                            (g.voxel_min([x, y, z]) + DVec3::splat(g.size)).min(self.bounds.max);
                        if (0..3).all(|k| min[k] < max[k]) {
                            boxes.push(ViewCell { min, max });
                        }
                    }
                }
            }
        }
        VoxelCell::new(id, boxes).map(Cell::Voxels)
    }
}

/// The occluders of the volumetric test ([`volumetric`]) and the voxels of every
/// cluster, built once per level.
pub struct Volumetric {
    pub occluders: volumetric::Occluders,
    pub clusters: volumetric::ClusterVoxels,
    pub seconds: f64,
}

impl AutoCells {
    /// The walkable viewcells of the level ([`viewcells`]), in voxel coordinates.
    pub fn viewcells(&self, walker: &viewcells::Walker) -> Vec<VoxelBox> {
        viewcells::walkable(&self.voxels, &self.tris, walker)
    }

    /// The occluders and cluster voxels of the volumetric test.
    pub fn volumetric(&self) -> Volumetric {
        let t = Instant::now();
        let occluders = volumetric::Occluders::new(&self.voxels, &self.tris);
        let clusters = volumetric::ClusterVoxels::new(&self.voxels, &self.tri_object, self.objects);
        Volumetric {
            occluders,
            clusters,
            seconds: t.elapsed().as_secs_f64(),
        }
    }

    /// The clusters potentially visible from the voxel box `b` (a viewcell), sorted:
    /// those the automatic cells it meets see through portals that the volumetric
    /// test does not hide — the intersection of two conservative answers.
    pub fn viewcell_pvs(&self, vol: &Volumetric, b: &VoxelBox) -> Vec<u32> {
        let g = &self.voxels.grid;
        let mut meets = Bits::new(self.len());
        for z in b.lo[2]..b.hi[2] {
            for y in b.lo[1]..b.hi[1] {
                for x in b.lo[0]..b.hi[0] {
                    let o = self.owner[g.index(x, y, z)];
                    if o != u32::MAX {
                        meets.set(o as usize);
                    }
                }
            }
        }
        let mut sees = Bits::new(self.len());
        for c in meets.ones() {
            sees.or(&self.cell_pvs[c]);
        }
        let mut candidates = Bits::new(self.objects);
        for c in sees.ones() {
            for &o in &self.cell_clusters[c] {
                candidates.set(o as usize);
            }
        }
        candidates
            .ones()
            .filter(|&o| !vol.clusters.hidden(&vol.occluders, b, o))
            .map(|o| o as u32)
            .collect()
    }
}

/// Above this many boxes the solver works on groups of boxes (`Options::group_block`):
/// the portal flood costs the square of the portals.
pub const GROUP_ABOVE: usize = 2000;

/// The default [`Options::flow_budget`]: cells entered per portal's flow.
pub const DEFAULT_FLOW_BUDGET: usize = 100_000;

/// Clusters hold at most this many triangles.
pub const MAX_CLUSTER_TRIANGLES: usize = 2048;

/// The voxel grid of a level: on the world's lattice of multiples of `h` (origin
/// included). `h` = `asked` when the grid fits `max_voxels`; otherwise the smallest
/// `asked` × 1.05ᵏ that fits, or `asked` × 2ʲ (a power-of-two multiple, on a level's
/// lattice: its walls fall on voxel faces and close them, [`faces`]) when that is at
/// most [`LATTICE_SLACK`] times coarser. One layer of padding: the border layer lies
/// outside the bounding box (rule 3).
pub fn lattice_grid(min: DVec3, max: DVec3, asked: f64, max_voxels: usize) -> Grid {
    let lattice = |h: f64| {
        let lo = (min / h).floor() - DVec3::ONE;
        let hi = (max / h).ceil() + DVec3::ONE;
        (lo * h, (hi - lo).to_array().map(|d| d as usize))
    };
    let fits = |h: f64| lattice(h).1.iter().product::<usize>() <= max_voxels.max(27);
    let mut fine = asked;
    while !fits(fine) {
        fine *= 1.05;
    }
    let mut two = asked;
    while !fits(two) {
        two *= 2.0;
    }
    let h = if two <= LATTICE_SLACK * fine {
        two
    } else {
        fine
    };
    let (origin, dims) = lattice(h);
    Grid {
        origin,
        size: h,
        dims,
    }
}

/// How much coarser than the finest voxel size the budget allows a power-of-two size
/// may be and still be preferred ([`lattice_grid`]).
pub const LATTICE_SLACK: f64 = 1.25;

/// The cluster grid's side: 16 × the smallest hole the voxel budget allows for this
/// scene (rooms-sized on a level, a few metres in a metric scene).
pub fn default_cluster_size(scene: &Scene, opts: &Options) -> f64 {
    let b = scene.bounds;
    let h = opts.smallest_hole.unwrap_or(0.5);
    if !(h.is_finite() && h > 0.0 && b.min.is_finite() && b.max.is_finite()) {
        return 4.0;
    }
    16.0 * lattice_grid(b.min, b.max, h, opts.max_voxels).size
}
