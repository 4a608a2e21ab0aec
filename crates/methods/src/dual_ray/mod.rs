//! Dual ray space from-region visibility — Koltun, Chrysanthou & Cohen-Or,
//! *Hardware-accelerated from-region visibility using a dual ray space* (EGWR 2001).
//!
//! **Guarantee**: the PVS of a viewcell contains every object visible from the cell's
//! free space; it may contain hidden ones.
//!
//! Methods:
//! * `dual-ray` — §3 + §4 + §5.2: kd-tree traversal, box-to-box tests reduced to the
//!   plane, planar visibility discretized in a ray space of `resolution` rows
//!   (default 128, refined hierarchically from 16);
//! * `dual-ray-exact` — the same with the exact planar algorithm of §5.1.
//!
//! Every `dual-ray` PVS contains the `dual-ray-exact` PVS of the same cell.
//!
//! Pipeline (one module per step):
//! * `occluders` — the ground-based inner prisms of `sightline_scene::occluders`, touching ones fused,
//!   decomposed into slabs along x and y, once per scene;
//! * `sightline_geom::kdtree` — the hierarchical subdivision of the occludees (§3): a node hidden
//!   from the cell stops the recursion; objects of visible leaves are tested one by one
//!   (their outer prisms' boxes); the nearer child first (front to back);
//!   a kd-node below a node its test left visible is tested only every
//!   [`TEST_EVERY_OPEN`]-th level (see there);
//! * `hidden` — every box proven hidden becomes an occluder of the later tests (its
//!   column is hidden, so it acts as a virtual occluder in the sense of Koltun et al.
//!   2000): a few large boxes stand for the thousands of slabs a long shaft crosses, and
//!   the slabs under them are not gathered; the PVS can only shrink;
//! * `plane` — reduction of a box-to-box test to a planar problem (§4): upper rims,
//!   shaft, ceiling plane `T`, occluders cut by `T`, dual ray space `RS`;
//! * `discrete` — §5.2 with exact union coverage per row (no cracks), most rows decided
//!   by bit-parallel `u128` rows, refined with per-band lists of the pieces that matter;
//! * `exact` — §5.1 with exact predicates;
//! * `crate::seed` — objects met first by rays from a few eyes of the cell are reported
//!   without a test, and so are the kd-nodes holding them (it changes no PVS);
//! * `witness` — a single ray verified clear (exact predicates) answers "visible"
//!   without gathering the whole shaft; it changes no answer of either planar method;
//! * aimed rays — a node or object the near occluders do not hide is aimed at by seed
//!   rays from the cell's eyes through the middle of its box and of its sides facing
//!   them (`crate::seed`'s march, stopping past the box): an object they meet first is
//!   visible, so is every node holding it, and the whole shaft is not gathered (no PVS
//!   changes: the seed's argument);
//! * `vo` — virtual occluders (Koltun et al. 2000), opt-in
//!   ([`DualRay::with_virtual_occluders`]): a long shaft the near occluders do not
//!   close is tried strip by strip of the cell, each strip with vertical rectangles on
//!   planes just beyond it, proven hidden by the box-to-box test (on demand, once per
//!   cell); they only drop provably hidden nodes.
//!
//! Order of one box-to-box test along an axis: the occluders next to the narrower box
//! are gathered first (within 60 m, then within a tenth of the shaft), with the hidden
//! boxes over the whole shaft; their coverage may already settle "hidden"; else a
//! witness ray from their gaps, checked along its own line through the rest of the
//! shaft, settles "visible" for this axis; rays aimed at the node or object may settle
//! "visible"; only then is the rest of the shaft gathered (the pieces gathered so far
//! are kept): the part at the other end, then the middle, each tested; between the
//! two, the ray in the widest gap the other end's test left is verified as a witness
//! (`witness::gap_visible`). With the
//! discrete test every step after the first gathers only the slabs meeting the rays the
//! pieces so far leave free (`discrete::free_hull`): the others cannot change the
//! answer, and on large cities they are most of the pieces.
//!
//! Degenerate configurations: boxes overlapping in both x and y (the cell inside a
//! node, an object straddling the cell) have no separating planes and count as visible;
//! boxes separated along both axes are tested along each (either one hiding suffices —
//! each yields a valid necessary condition, with its own supporting plane `T`); equal
//! heights give a horizontal `T`; touching boxes give an empty shaft (visible); cells
//! cutting through buildings see from their free part, which the shaft construction
//! respects because rays starting inside an occluder are blocked anyway.
//!
//! ```
//! use std::sync::Arc;
//! use sightline_methods::{create, MethodOptions};
//! use sightline_scene::{Scene, Object};
//! use sightline_geom::{Polygon, DVec2, ViewCell};
//! let r = |x0, y0, x1, y1| Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1));
//! let scene = Arc::new(Scene::from_objects(vec![
//!     Object::block(None, r(20.0, -50.0, 22.0, 50.0), 0.0, 10.0), // a long wall
//!     Object::block(None, r(40.0, 0.0, 50.0, 10.0), 0.0, 6.0),    // low house behind it
//! ]));
//! let m = create("dual-ray", scene, &MethodOptions::default()).unwrap();
//! let cell: ViewCell = "0,0,1.5,10,10,2".parse().unwrap();
//! assert_eq!(m.pvs(&cell).unwrap(), vec![0]);
//! ```

mod discrete;
mod exact;
mod hidden;
mod occluders;
mod plane;
mod table1;
mod vo;
mod witness;

pub use table1::{crossing_cells, table1, Table1Row};

use crate::seed::{SeedGrid, SeedScratch};
use hidden::HiddenSet;
use occluders::{Axis, Decomposition};
use plane::{Hidden, Planar, Scratch};
use rayon::prelude::*;
use sightline_core::{DualRayOptions, Method, MethodError, VisibilityMethod};
use sightline_geom::kdtree::{KdTree, NodeKind};
use sightline_geom::{Aabb3, DVec2, DVec3, ViewCell};
use sightline_scene::Scene;
use std::sync::Arc;
use vo::VirtualOccluders;

/// Default ray-space resolution of `dual-ray` (the paper's choice, §6).
pub(crate) const DEFAULT_RESOLUTION: u32 = 128;

/// The first, partial gathering of occluders covers this fraction of the shaft's length,
/// at least [`FIRST_MIN_M`], next to the narrower of the two boxes, where the shaft is
/// narrowest: a far object is most often hidden by what stands around it (its own
/// block), a kd-node wider than the cell by what stands around the cell. It is gathered
/// in two steps: first the occluders within [`FIRST_MIN_M`] of the box, then the rest of
/// the fraction over the rays they leave free ([`discrete::free_hull`]): most boxes
/// kilometres away are hidden by their own block. The order changes which test settles
/// an answer, never the answer (every gathered piece is a real occluder); the figures
/// behind the fractions are in `docs/methods/dual-ray.md`.
const FIRST_FRACTION: f64 = 0.1;
const FIRST_MIN_M: f64 = 60.0;

/// When the near part leaves a shaft open, the part of this fraction of its length at
/// the other end is gathered next (over the rays left free), before the middle: rays
/// from a cell wider than the street run inside the blocks beside it and are stopped
/// next to the cell, not next to a box kilometres away.
const END_FRACTION: f64 = 0.05;

/// Bands of `RS` over which the rays the near pieces leave free are bounded before the
/// rest of a shaft is gathered ([`discrete::free_hull`]).
const FREE_LEVEL: u32 = 4;

/// Strips of a cell ([`Strips`]): at least this wide (metres), at most this many.
const STRIP_MIN_M: f64 = 20.0;
const MAX_STRIPS: usize = 4;

/// An object with more outer prisms than this is tested by its single bounding box.
const MAX_BOXES_PER_OBJECT: usize = 8;

/// Below a kd-node its test did not hide, a node (inner or leaf) is tested only at
/// every `TEST_EVERY_OPEN`-th level of the run of such nodes; the others go straight to
/// their children (a leaf's to its objects). A node under a visible one is itself most
/// often visible — far away, a child's shaft is nearly its parent's — and a visible
/// answer is the dearest: the whole shaft gathered for nothing. Skipping a test never
/// drops an object (only a test proving hidden does), so the PVS keeps its guarantee;
/// it may differ by the odd object, as a leaf's box and its objects' boxes are tested
/// with different ceilings.
const TEST_EVERY_OPEN: u32 = 2;

/// Boxes per kd-leaf. Larger leaves mean fewer levels of nodes to find visible on the
/// way to each visible object; their objects are tested one by one anyway. Smaller
/// leaves cost more node tests, larger ones more object tests (`docs/methods/dual-ray.md`).
const LEAF_SIZE: usize = 8;

/// Which planar algorithm answers the box-to-box tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Planarity {
    /// §5.2, with this many rows (rounded up to 16·2^k).
    Discrete { resolution_px: u32 },
    /// §5.1.
    Exact,
}

/// Counters of one PVS computation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Box-to-box tests that built a planar problem.
    pub planar_tests: u64,
    /// Tests answered without one (overlapping boxes).
    pub trivial_tests: u64,
    /// Occluder pieces gathered over all planar problems.
    pub pieces: u64,
    /// Axis tests hidden by the near occluders alone.
    pub near_hidden: u64,
    /// Axis tests hidden only by the full shaft.
    pub full_hidden: u64,
    /// Axis tests found visible.
    pub visible: u64,
    /// Of which settled by a witness ray (without gathering the whole shaft).
    pub witnessed: u64,
    /// Objects reported without a test: met first by a seed ray (`crate::seed`).
    pub seeded: u64,
    /// Box-to-box tests spent proving the virtual occluders of the cell's strips.
    pub vo_tests: u64,
    /// Segments of those virtual occluders proven hidden.
    pub vo_rects: u64,
    /// Boxes proven hidden and recorded as occluders of the later tests (`hidden`).
    pub hidden_boxes: u64,
    /// Pieces of the planar problems that were hidden boxes.
    pub hidden_pieces: u64,
    /// Boxes (nodes and objects) found visible by rays aimed at them (`crate::seed`),
    /// before their whole shaft was gathered.
    pub aimed: u64,
    /// Axis tests hidden strip by strip (the cell cut into strips, each with its own
    /// virtual occluders), without the whole shaft.
    pub vo_hidden: u64,
}

/// The dual ray space method prepared for one scene.
pub struct DualRay {
    name: &'static str,
    planarity: Planarity,
    scene: Arc<Scene>,
    /// Local frame: scene coordinates minus `origin` (precision).
    origin: DVec2,
    decomp_x: Decomposition,
    decomp_y: Decomposition,
    tree: KdTree,
    /// Objects without a usable bound: always reported.
    always: Vec<u32>,
    /// Rays from eyes of the cell that report what they meet first.
    seed: SeedGrid,
    /// Parent of each kd-node (`u32::MAX` for the root).
    parent: Vec<u32>,
    /// The leaves holding each object: `leaf_ids[leaf_start[o]..leaf_start[o + 1]]`.
    leaf_start: Vec<u32>,
    leaf_ids: Vec<u32>,
    use_seed: bool,
    use_vo: bool,
    use_hidden: bool,
}

/// Prepare `dual-ray` or `dual-ray-exact` for `scene`.
pub(crate) fn create(
    method: Method,
    scene: Arc<Scene>,
    opts: &DualRayOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    let planarity = match method {
        Method::DualRay => Planarity::Discrete {
            resolution_px: opts.resolution_px.unwrap_or(DEFAULT_RESOLUTION),
        },
        Method::DualRayExact => Planarity::Exact,
        m => return Err(MethodError::Unknown(m.name().to_string())),
    };
    Ok(Box::new(
        DualRay::new(method.name(), scene, planarity)
            .with_seed(opts.seed_rays)
            .with_virtual_occluders(opts.virtual_occluders)
            .with_hidden_occluders(opts.hidden_boxes),
    ))
}

impl DualRay {
    /// The occluder decomposition cut along `axis`.
    fn decomposition(&self, axis: Axis) -> &Decomposition {
        match axis {
            Axis::X => &self.decomp_x,
            Axis::Y => &self.decomp_y,
        }
    }

    /// Prepare the method: fused occluder decompositions along x and y, kd-tree of the
    /// occludees.
    pub fn new(name: &'static str, scene: Arc<Scene>, planarity: Planarity) -> Self {
        let origin = sightline_scene::occluders::local_origin(&scene);
        let occ = sightline_scene::occluders::collect_occluders(&scene, origin);
        let clusters = occluders::clusters(&occ);
        let ((decomp_x, decomp_y), seed) = rayon::join(
            || {
                rayon::join(
                    || occluders::decompose(&occ, &clusters, Axis::X),
                    || occluders::decompose(&occ, &clusters, Axis::Y),
                )
            },
            || SeedGrid::new(&scene, origin, &occ),
        );
        let o3 = origin.extend(0.0);
        let mut items = Vec::new();
        let mut always = Vec::new();
        for (id, o) in scene.objects.iter().enumerate() {
            let mut boxes: Vec<Aabb3> = o
                .outer
                .iter()
                .map(|p| p.aabb())
                .filter(|b| !b.is_empty())
                .collect();
            if boxes.is_empty() || boxes.len() > MAX_BOXES_PER_OBJECT {
                let b = boxes.iter().fold(o.bounds, |acc, b| acc.union(*b));
                boxes = vec![b];
            }
            let ok = boxes
                .iter()
                .all(|b| !b.is_empty() && b.min.is_finite() && b.max.is_finite());
            if !ok {
                always.push(id as u32);
                continue;
            }
            for b in boxes {
                items.push((id as u32, Aabb3::new(b.min - o3, b.max - o3)));
            }
        }
        let tree = KdTree::build(items, LEAF_SIZE);
        let (parent, leaf_start, leaf_ids) = node_links(&tree, scene.objects.len());
        DualRay {
            name,
            planarity,
            scene,
            origin,
            decomp_x,
            decomp_y,
            tree,
            always,
            seed,
            parent,
            leaf_start,
            leaf_ids,
            use_seed: true,
            use_vo: false,
            use_hidden: true,
        }
    }

    /// Turn the cell's strips and their virtual occluders (`vo`) on or off
    /// (off by default: on the generated metropolis their proofs cost more than the
    /// shafts they spare). On, the PVS can only shrink, and stays a superset of the
    /// visible set and of `dual-ray-exact` with them on.
    pub fn with_virtual_occluders(mut self, on: bool) -> Self {
        self.use_vo = on;
        self
    }

    /// Turn the hidden boxes as occluders (`hidden`) on or off (on by default). Off, no
    /// test uses what an earlier one proved; on, the PVS can only shrink.
    pub fn with_hidden_occluders(mut self, on: bool) -> Self {
        self.use_hidden = on;
        self
    }

    /// Turn the seed rays (`crate::seed`) on or off (on by default). The PVS is the same
    /// either way; off, every object and node is proven by its own test.
    pub fn with_seed(mut self, on: bool) -> Self {
        self.use_seed = on;
        self
    }

    /// The PVS of `cell` and the counters of its traversal.
    pub fn pvs_with_stats(&self, cell: &ViewCell) -> (Vec<u32>, TraversalStats) {
        let a = self.local(cell);
        let mut scratch = Scratch::default();
        let mut stats = TraversalStats::default();
        let mut out: Vec<u32> = self.always.clone();
        let mut aimer = self.seed_marks(&a, &mut stats);
        let mut strips = match self.tree.nodes.first() {
            Some(root) if self.use_vo => Some(Strips::new(&a, &root.bbox)),
            _ => None,
        };
        // (node, levels in a row above it its test or the rule left visible).
        let mut stack: Vec<(u32, u32)> = Vec::new();
        let mut hidden = self
            .use_hidden
            .then(|| HiddenSet::new(&self.decomp_x, &self.decomp_y));
        if !self.tree.nodes.is_empty() {
            stack.push((0, 0));
        }
        while let Some((n, open)) = stack.pop() {
            let node = &self.tree.nodes[n as usize];
            let known = aimer.node_seen.get(n as usize).copied().unwrap_or(false);
            let test = !known && open.is_multiple_of(TEST_EVERY_OPEN);
            // A node seen by the seed resets the run: its children were not left open
            // by a test.
            let open = if known { 0 } else { open + 1 };
            match node.kind {
                NodeKind::Inner { left, right } => {
                    if test
                        && self.hidden_node(
                            &a,
                            &node.bbox,
                            hidden.as_ref(),
                            &mut || aimer.node_visible(self, n, &node.bbox),
                            strips.as_mut(),
                            &mut scratch,
                            &mut stats,
                        )
                    {
                        if let Some(h) = hidden.as_mut() {
                            h.insert(&node.bbox);
                        }
                        continue;
                    }
                    // Front to back: the nearer child first, so that what it proves
                    // hidden occludes the farther one.
                    let d = |c: u32| gap2(&a, &self.tree.nodes[c as usize].bbox);
                    if d(left) <= d(right) {
                        stack.push((right, open));
                        stack.push((left, open));
                    } else {
                        stack.push((left, open));
                        stack.push((right, open));
                    }
                }
                NodeKind::Leaf { first, len } => {
                    let items = self.tree.leaf_items(first, len);
                    // A leaf of one box is the object's own test.
                    if test
                        && items.len() > 1
                        && self.hidden_node(
                            &a,
                            &node.bbox,
                            hidden.as_ref(),
                            &mut || aimer.node_visible(self, n, &node.bbox),
                            strips.as_mut(),
                            &mut scratch,
                            &mut stats,
                        )
                    {
                        if let Some(h) = hidden.as_mut() {
                            h.insert(&node.bbox);
                        }
                        continue;
                    }
                    for (id, b) in items {
                        if out.last() == Some(id) {
                            continue;
                        }
                        let is_seen = aimer.seen.get(*id as usize).copied().unwrap_or(false);
                        if is_seen
                            || !self.hidden_node(
                                &a,
                                b,
                                hidden.as_ref(),
                                &mut || aimer.object_visible(self, *id, b),
                                strips.as_mut(),
                                &mut scratch,
                                &mut stats,
                            )
                        {
                            out.push(*id);
                        } else {
                            if let Some(h) = hidden.as_mut() {
                                h.insert(b);
                            }
                        }
                    }
                }
            }
        }
        stats.hidden_boxes = hidden.as_ref().map_or(0, |h| h.boxes.len() as u64);
        for (_, vo) in strips
            .iter()
            .flat_map(|s| s.across_x.iter().chain(&s.across_y))
        {
            stats.vo_tests += vo.tests;
            stats.vo_rects += vo.count() as u64;
        }
        out.sort_unstable();
        out.dedup();
        (out, stats)
    }

    /// The objects the seed rays of `cell` meet first (sorted): reported without a test.
    /// Every one of them is in the `dual-ray-exact` PVS of the cell.
    pub fn seed_objects(&self, cell: &ViewCell) -> Vec<u32> {
        let mut seen = vec![false; self.scene.objects.len()];
        self.seed
            .mark(&self.local(cell), &mut seen, &mut SeedScratch::default());
        (0..seen.len() as u32)
            .filter(|i| seen[*i as usize])
            .collect()
    }

    /// `cell` in the local frame (scene coordinates minus `origin`).
    fn local(&self, cell: &ViewCell) -> Aabb3 {
        let o3 = self.origin.extend(0.0);
        Aabb3::new(cell.min - o3, cell.max - o3)
    }

    /// The objects met first by the seed rays from `a` (local frame) and the kd-nodes
    /// holding one of them, with the eyes and scratch the aimed rays go on with.
    fn seed_marks(&self, a: &Aabb3, stats: &mut TraversalStats) -> Aimer {
        let mut aimer = Aimer {
            eyes: Vec::new(),
            z: a.max.z,
            seen: Vec::new(),
            node_seen: Vec::new(),
            scratch: SeedScratch::default(),
        };
        if !self.use_seed {
            return aimer;
        }
        aimer.eyes = self.seed.eyes(a);
        aimer.seen = vec![false; self.scene.objects.len()];
        aimer.node_seen = vec![false; self.tree.nodes.len()];
        stats.seeded =
            self.seed
                .mark_from(&aimer.eyes, aimer.z, &mut aimer.seen, &mut aimer.scratch)
                as u64;
        aimer.mark_nodes(self);
        aimer
    }

    /// The PVS of `cell` and of its 8 neighbours (the cells translated by ±1 cell size in
    /// x and y), computed in parallel: the building block of the remote walkthrough of
    /// §6 (Fig. 5). Row-major from the lowest `y`, the cell itself at index 4.
    pub fn pvs_with_neighbours(&self, cell: &ViewCell) -> [(ViewCell, Vec<u32>); 9] {
        let s = cell.size();
        let cells: Vec<ViewCell> = (0..9)
            .map(|k| {
                let d = DVec3::new(
                    ((k % 3) as f64 - 1.0) * s.x,
                    ((k / 3) as f64 - 1.0) * s.y,
                    0.0,
                );
                ViewCell {
                    min: cell.min + d,
                    max: cell.max + d,
                }
            })
            .collect();
        let pvs: Vec<Vec<u32>> = cells.par_iter().map(|c| self.pvs_with_stats(c).0).collect();
        let mut it = cells.into_iter().zip(pvs);
        std::array::from_fn(|_| it.next().expect("nine cells"))
    }

    /// A node's or an object's test from the cell `a`, with the cell's strips when
    /// given.
    #[allow(clippy::too_many_arguments)]
    fn hidden_node(
        &self,
        a: &Aabb3,
        b: &Aabb3,
        hidden: Option<&HiddenSet>,
        aim: &mut dyn FnMut() -> bool,
        strips: Option<&mut Strips>,
        scratch: &mut Scratch,
        stats: &mut TraversalStats,
    ) -> bool {
        self.hidden_first(a, b, None, hidden, aim, strips, scratch, stats)
    }

    /// §3–§5: whether the boxes `a` (the cell) and `b` are hidden from each other, in
    /// local coordinates, trying the axis `first` before the other (else the one of the
    /// larger gap): either axis hiding suffices, so the order changes only the cost.
    /// With `strips`, a long shaft the near occluders do not close is first tried
    /// strip by strip ([`Strips`]) before it is gathered whole.
    #[allow(clippy::too_many_arguments)]
    fn hidden_first(
        &self,
        a: &Aabb3,
        b: &Aabb3,
        first: Option<Axis>,
        hidden: Option<&HiddenSet>,
        aim: &mut dyn FnMut() -> bool,
        mut strips: Option<&mut Strips>,
        scratch: &mut Scratch,
        stats: &mut TraversalStats,
    ) -> bool {
        let gap_x = (b.min.x - a.max.x).max(a.min.x - b.max.x);
        let gap_y = (b.min.y - a.max.y).max(a.min.y - b.max.y);
        if gap_x <= 0.0 && gap_y <= 0.0 {
            // Overlapping (or touching) footprints: no separating planes F_A, F_B.
            stats.trivial_tests += 1;
            return false;
        }
        let mut axes = [(gap_x, Axis::X), (gap_y, Axis::Y)];
        if first.map_or(gap_y > gap_x, |f| f == Axis::Y) {
            axes.swap(0, 1);
        }
        let mut aimed = false;
        for (gap, axis) in axes {
            if gap <= 0.0 {
                continue;
            }
            let Some(pair) = plane::orient(a, b, axis) else {
                continue;
            };
            let decomp = self.decomposition(axis);
            let hid = Hidden { set: hidden, axis };
            // First only the occluders next to the narrower box, where every ray of the
            // shaft converges: they often hide it on their own, at a fraction of the
            // cost (a subset covering is enough).
            let len = pair.len();
            let near = (len * FIRST_FRACTION).max(FIRST_MIN_M);
            if near < len {
                let side = |d: f64| if pair.narrow_lo() { d } else { -d };
                let res = match self.planarity {
                    Planarity::Discrete { resolution_px } => resolution_px,
                    Planarity::Exact => discrete::FIRST_LEVEL * 16,
                };
                // The box's own surroundings first, then the rest of the near part over
                // the rays they leave free.
                Planar::build(scratch, decomp, &pair, Some(side(FIRST_MIN_M)), hid);
                stats.planar_tests += 1;
                stats.pieces += scratch.planar.pieces.len() as u64;
                stats.hidden_pieces += scratch.planar.hidden_pieces as u64;
                if FIRST_MIN_M < near {
                    if discrete::hidden(scratch, res) {
                        stats.near_hidden += 1;
                        return true;
                    }
                    let rays = self.free_rays(scratch);
                    Planar::extend(scratch, decomp, hid, Some(side(near)), rays);
                    stats.planar_tests += 1;
                    stats.pieces += scratch.planar.pieces.len() as u64;
                }
                if discrete::hidden(scratch, res) {
                    stats.near_hidden += 1;
                    return true;
                }
                if witness::visible(scratch, decomp, hid) {
                    stats.visible += 1;
                    stats.witnessed += 1;
                    continue;
                }
                // Before the whole shaft: rays aimed at the box from the seed's eyes.
                if !aimed {
                    aimed = true;
                    if aim() {
                        stats.aimed += 1;
                        return false;
                    }
                }
                if let Some(st) = strips.as_deref_mut() {
                    if self.strips_hide(st, b, axis, scratch, stats) {
                        stats.vo_hidden += 1;
                        return true;
                    }
                }
            }
            // The near shaft built last (unless the strips built their own) is extended
            // to the whole shaft.
            if near < len && strips.is_none() {
                // The rest over the rays the near pieces leave free: first the part at
                // the other end (a ray running inside the blocks beside a street is
                // stopped there), then the middle.
                let p = &scratch.planar;
                let end = len * END_FRACTION;
                if let Planarity::Discrete { resolution_px } = self.planarity {
                    if end + (p.gb - p.ga) < len {
                        let rays = self.free_rays(scratch);
                        Planar::extend_other_end(scratch, decomp, hid, end, rays);
                        stats.planar_tests += 1;
                        stats.pieces += scratch.planar.pieces.len() as u64;
                        if discrete::hidden(scratch, resolution_px) {
                            stats.full_hidden += 1;
                            return true;
                        }
                        // Both ends gathered: the gap the test left is a good witness.
                        if witness::gap_visible(scratch, decomp, hid) {
                            stats.visible += 1;
                            stats.witnessed += 1;
                            continue;
                        }
                    }
                }
                let rays = self.free_rays(scratch);
                Planar::extend(scratch, decomp, hid, None, rays);
            } else {
                Planar::build(scratch, decomp, &pair, None, hid);
            }
            stats.planar_tests += 1;
            stats.pieces += scratch.planar.pieces.len() as u64;
            stats.hidden_pieces += scratch.planar.hidden_pieces as u64;
            let hidden = match self.planarity {
                Planarity::Discrete { resolution_px } => discrete::hidden(scratch, resolution_px),
                Planarity::Exact => exact::hidden(scratch),
            };
            if hidden {
                stats.full_hidden += 1;
                return true;
            }
            stats.visible += 1;
        }
        false
    }
}

impl DualRay {
    /// The rays the pieces gathered so far may leave free, with the discrete test
    /// ([`discrete::free_hull`]; `None`: all of them).
    fn free_rays(&self, scratch: &Scratch) -> Option<[f64; 4]> {
        match self.planarity {
            Planarity::Discrete { .. } => discrete::free_hull(scratch, FREE_LEVEL),
            Planarity::Exact => None,
        }
    }

    /// Whether every strip of the cell across `axis` is proven to have `m` hidden: by
    /// its virtual occluders, or by the occluders near the narrower box of its own shaft.
    fn strips_hide(
        &self,
        strips: &mut Strips,
        m: &Aabb3,
        axis: Axis,
        scratch: &mut Scratch,
        stats: &mut TraversalStats,
    ) -> bool {
        let list = match axis {
            Axis::X => &mut strips.across_x,
            Axis::Y => &mut strips.across_y,
        };
        for (s, vo) in list.iter_mut() {
            let s = *s;
            let by_vo = vo.hides(m, |t, normal| {
                self.hidden_first(
                    &s,
                    t,
                    Some(normal),
                    None,
                    &mut || false,
                    None,
                    scratch,
                    stats,
                )
            });
            if !by_vo && !self.near_hidden(&s, m, axis, scratch, stats) {
                return false;
            }
        }
        true
    }

    /// The test of `b` from `a` along `axis` with only the occluders near the narrower
    /// box (all of them for a short shaft), by the method's planar algorithm.
    fn near_hidden(
        &self,
        a: &Aabb3,
        b: &Aabb3,
        axis: Axis,
        scratch: &mut Scratch,
        stats: &mut TraversalStats,
    ) -> bool {
        let Some(pair) = plane::orient(a, b, axis) else {
            return false;
        };
        let len = pair.len();
        let near = (len * FIRST_FRACTION).max(FIRST_MIN_M);
        let gather = (near < len).then_some(if pair.narrow_lo() { near } else { -near });
        let decomp = self.decomposition(axis);
        Planar::build(scratch, decomp, &pair, gather, Hidden::NONE);
        stats.planar_tests += 1;
        stats.pieces += scratch.planar.pieces.len() as u64;
        match self.planarity {
            Planarity::Discrete { resolution_px } => discrete::hidden(scratch, resolution_px),
            Planarity::Exact => exact::hidden(scratch),
        }
    }
}

/// The cell cut into strips, each with its own virtual occluders ([`vo`]).
///
/// A far node beside a street the cell opens onto is hidden by the row of buildings
/// along the street, but a cell larger than the street straddles the row's facade, so
/// no plane separates the cell from the node, and the node's own shaft must gather the
/// whole row, kilometres of it. Cut into strips along the street, each strip has the
/// node hidden either by a plane parallel to the street just beyond it (for the strips
/// in the street: the row hides the plane far along, proven once per strip and cell
/// for every node behind the row) or by the occluders around the strip itself (the
/// strips inside the row). A node hidden from every strip is hidden from the cell:
/// the strips cover it.
struct Strips {
    /// Strips cut along `y` with their virtual occluders on planes normal to `y`: for
    /// the shafts along `x`.
    across_x: Vec<(Aabb3, VirtualOccluders)>,
    /// The same with `x` and `y` exchanged.
    across_y: Vec<(Aabb3, VirtualOccluders)>,
}

impl Strips {
    fn new(a: &Aabb3, scene: &Aabb3) -> Self {
        let cut = |axis: Axis| -> Vec<(Aabb3, VirtualOccluders)> {
            let k = match axis {
                Axis::X => a.max.y - a.min.y,
                Axis::Y => a.max.x - a.min.x,
            };
            let n = ((k / STRIP_MIN_M).floor() as usize).clamp(1, MAX_STRIPS);
            (0..n)
                .map(|i| {
                    let (f0, f1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
                    let mut s = *a;
                    match axis {
                        Axis::X => {
                            s.min.y = a.min.y + f0 * k;
                            s.max.y = if i + 1 == n {
                                a.max.y
                            } else {
                                a.min.y + f1 * k
                            };
                        }
                        Axis::Y => {
                            s.min.x = a.min.x + f0 * k;
                            s.max.x = if i + 1 == n {
                                a.max.x
                            } else {
                                a.min.x + f1 * k
                            };
                        }
                    }
                    let normal = match axis {
                        Axis::X => Axis::Y,
                        Axis::Y => Axis::X,
                    };
                    (s, VirtualOccluders::new(&s, scene, &[normal]))
                })
                .collect()
        };
        Strips {
            across_x: cut(Axis::X),
            across_y: cut(Axis::Y),
        }
    }
}

/// The parent of every kd-node and the leaves holding each of `objects` objects (CSR).
fn node_links(tree: &KdTree, objects: usize) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let mut parent = vec![u32::MAX; tree.nodes.len()];
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for (n, node) in tree.nodes.iter().enumerate() {
        match node.kind {
            NodeKind::Inner { left, right } => {
                parent[left as usize] = n as u32;
                parent[right as usize] = n as u32;
            }
            NodeKind::Leaf { first, len } => {
                pairs.extend(
                    tree.leaf_items(first, len)
                        .iter()
                        .map(|(id, _)| (*id, n as u32)),
                );
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    let mut start = vec![0u32; objects + 1];
    for (id, _) in &pairs {
        start[*id as usize + 1] += 1;
    }
    for i in 0..objects {
        start[i + 1] += start[i];
    }
    (parent, start, pairs.into_iter().map(|(_, n)| n).collect())
}

/// The objects and kd-nodes of one cell known visible (met first by a seed ray), and the
/// rays aimed at a box before its whole shaft is gathered ([`SeedGrid::aim`]): what
/// they meet first is visible from the cell, so the box holding it is too, in both
/// planar methods (the seed's argument), and the PVS does not change.
struct Aimer {
    eyes: Vec<DVec2>,
    z: f64,
    seen: Vec<bool>,
    node_seen: Vec<bool>,
    scratch: SeedScratch,
}

impl Aimer {
    /// Aim at the box `b` of object `id` from every eye until the object is marked. The
    /// other objects the rays meet first are marked too, with the kd-nodes above them.
    fn object_visible(&mut self, m: &DualRay, id: u32, b: &Aabb3) -> bool {
        self.box_visible(m, b, |s| s.seen[id as usize])
    }

    /// Aim at the box of node `n` until it holds a marked object.
    fn node_visible(&mut self, m: &DualRay, n: u32, b: &Aabb3) -> bool {
        self.box_visible(m, b, |s| s.node_seen[n as usize])
    }

    /// Mark the kd-nodes above the leaves of the objects just marked (`scratch.marked`):
    /// a node holding a visible object is visible. Each node is marked once, so the
    /// cost follows the marked objects, not the tree.
    fn mark_nodes(&mut self, m: &DualRay) {
        for &id in &self.scratch.marked {
            let (s, e) = (m.leaf_start[id as usize], m.leaf_start[id as usize + 1]);
            for &leaf in &m.leaf_ids[s as usize..e as usize] {
                let mut n = leaf;
                while n != u32::MAX && !self.node_seen[n as usize] {
                    self.node_seen[n as usize] = true;
                    n = m.parent[n as usize];
                }
            }
        }
    }

    /// Aim at `b` from every eye until `done`.
    fn box_visible(&mut self, m: &DualRay, b: &Aabb3, done: impl Fn(&Aimer) -> bool) -> bool {
        if self.seen.is_empty() {
            return false;
        }
        let (lo, hi) = (b.min.truncate(), b.max.truncate());
        let mid = 0.5 * (lo + hi);
        for k in 0..self.eyes.len() {
            let eye = self.eyes[k];
            // The middle of the box and of each of its sides facing the eye (a facade
            // seen at a grazing angle along a street is entered through its own side).
            let mut points = [Some(mid), None, None];
            if eye.x < lo.x || eye.x > hi.x {
                let x = if eye.x < lo.x { lo.x } else { hi.x };
                points[1] = Some(DVec2::new(x, mid.y));
            }
            if eye.y < lo.y || eye.y > hi.y {
                let y = if eye.y < lo.y { lo.y } else { hi.y };
                points[2] = Some(DVec2::new(mid.x, y));
            }
            for at in points.into_iter().flatten() {
                if m.seed
                    .aim(eye, self.z, b, at, &mut self.seen, &mut self.scratch)
                    == 0
                {
                    continue;
                }
                self.mark_nodes(m);
                if done(self) {
                    return true;
                }
            }
        }
        false
    }
}

/// Squared distance between the footprints of two boxes (0 when they overlap).
fn gap2(a: &Aabb3, b: &Aabb3) -> f64 {
    let dx = (b.min.x - a.max.x).max(a.min.x - b.max.x).max(0.0);
    let dy = (b.min.y - a.max.y).max(a.min.y - b.max.y).max(0.0);
    dx * dx + dy * dy
}

impl VisibilityMethod for DualRay {
    fn name(&self) -> &'static str {
        self.name
    }

    /// The resolution, and the switches that change the PVS when they differ from their
    /// defaults (the seed rays do not change it), so a default build's header is as it
    /// always was.
    fn params(&self) -> Vec<(String, String)> {
        let mut p = match self.planarity {
            Planarity::Discrete { resolution_px } => {
                vec![("resolution".to_string(), resolution_px.to_string())]
            }
            Planarity::Exact => Vec::new(),
        };
        let d = sightline_core::DualRayOptions::default();
        if self.use_vo != d.virtual_occluders {
            p.push(("virtual_occluders".into(), self.use_vo.to_string()));
        }
        if self.use_hidden != d.hidden_boxes {
            p.push(("hidden_boxes".into(), self.use_hidden.to_string()));
        }
        p
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        if !(cell.min.is_finite() && cell.max.is_finite()) || cell.min.cmpgt(cell.max).any() {
            return Err(MethodError::BadCell(cell.to_string()));
        }
        Ok(self.pvs_with_stats(cell).0)
    }
}
