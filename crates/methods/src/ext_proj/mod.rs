//! `ext-proj`: conservative from-region occlusion culling with extended projections
//! (Durand, Drettakis, Thollot, Puech, *Conservative Visibility Preprocessing using
//! Extended Projections*, SIGGRAPH 2000).
//!
//! **Guarantee**: an object is left out of the PVS only when, on some projection plane,
//! the extended projection of (a box around) it lies inside the extended projections
//! of occluders that are nearer than it from *every* point of the cell (§2.2, the
//! chain of inclusions after Definition 2). It may report a hidden object as visible,
//! never a visible object as hidden.
//!
//! Pipeline per cell (§6.1):
//! 1. occluder selection by solid angle through a precomputed relevance tree
//!    (`occluders`); occluders are the fused inner prisms of the objects;
//! 2. for each of the six directions of the cell, a projection plane placed by the
//!    filled-pixels heuristic and extended by [`DEFAULT_EXTENSION`] (`planes`);
//! 3. extended projections of convex occluder pieces (intersection of the views from
//!    the cell's vertices) and slices of the pieces cut by the plane (`projection`),
//!    drawn with union-aware inner coverage into an extended depth map and its
//!    max pyramid (`depth_map`);
//! 4. occludee boxes projected with separating / supporting lines, or the improved
//!    projection of §4 (`occludee`), tested hierarchically against the pyramid:
//!    through a box hierarchy over the objects that stops at hidden and at fully
//!    visible nodes (`hierarchy`), then within each object by splitting its boxes;
//! 5. with `sweep`, the occlusion sweep of §5 ([`Sweep`]): successive planes, the
//!    previous occlusion map re-projected (eroded by the inverse image of the
//!    equivalent planar cell) and new occluders — including every mesh triangle, the
//!    leaves of a forest — added at each plane;
//! 6. the adaptive subdivision of §6.1 (`adaptive`); by default (budget 0, minimum
//!    25 m) it splits only cells wider than 50 m, down to 25 m.
//!
//! Parameters: `resolution_px` (default 512 — the paper's 256 of §7.1 leaves 25 m city
//! cells' far planes with pixels of several metres; rounded up to a power of two as
//! the pyramid needs), `extension` (default 1.2 rather than the paper's 1.5: every
//! pixel grows with it, see [`DEFAULT_EXTENSION`]), `sweep`, `planes` (number of sweep
//! planes per direction, default 15 as in §7.2).

mod adaptive;
mod depth_map;
pub mod experiments;
mod hierarchy;
mod occludee;
mod occluders;
mod planes;
mod projection;
mod sweep;

// The entry type is `ExtProj` with its `Params`; the rest is the surface the ext-proj
// tests, debugging examples and benchmarks look through (planes, maps, the sweep).
pub use adaptive::pvs as adaptive_pvs;
pub use depth_map::{depth_down, pixel_range, DepthMap, OcclusionMap};
pub use occludee::occludee_projection;
pub use occluders::{OccluderSet, Piece};
pub use planes::{Direction, LocalBox, Plane};
pub use projection::{extended_projection, ConvexOccluder};
pub use sweep::{Sweep, SweepPlane};

use depth_map::{clipped_pixel_range, depth_up, CoverageBuilder};
use hierarchy::{Hierarchy, Verdict};
use planes::candidate_positions;
use projection::{plane_safe_projections, FACE_CLEARANCE_M};
use sightline_core::{ExtProjOptions, Method, MethodError, MethodOptions, VisibilityMethod};
use sightline_geom::{Aabb3, DVec2, DVec3, ViewCell};
use sightline_scene::Scene;
use std::sync::Arc;

/// Parameters of `ext-proj`.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Depth-map resolution (pixels per side, a power of two).
    pub resolution_px: usize,
    /// Use the improved occludee projection of §4.
    pub improved: bool,
    /// Extension of the planes for the corner directions (§6.1: 1.5).
    pub extension: f64,
    /// Run the occlusion sweep of §5.
    pub sweep: bool,
    /// Sweep planes per direction.
    pub sweep_planes: usize,
    /// Kernel size K of §5 (pixels), which sets the spacing of the sweep planes.
    pub kernel_px: usize,
    /// The first sweep plane lies at least this far beyond the cell's far face (m).
    /// The §5.2 spacing grows as the square of the distance: from a plane hugging the
    /// cell the requested planes would all fall within centimetres of it, where
    /// nothing can be hidden yet (occluders there Project to almost nothing).
    pub sweep_start_m: f64,
    /// The sweep planes reach at least this far beyond the cell's far face (m): with
    /// too few planes for the §5.2 spacing of `kernel_px` to get there, the kernel is
    /// enlarged until they do (`sweep::plane_positions`).
    pub sweep_reach_m: f64,
    /// Solid-angle threshold (sr) of occluder relevance (§6.1).
    pub solid_angle: f64,
    /// At most this many occluder pieces per direction (largest solid angle first).
    pub max_occluders: usize,
    /// Candidate plane positions evaluated by the placement heuristic.
    pub plane_candidates: usize,
    /// Planes kept per direction (the paper uses one; more catch both nearby slices
    /// and the umbra of farther rows).
    pub planes_per_direction: usize,
    /// Occludee boxes that fail are split in two, recursively, this many times.
    pub occludee_splits: u32,
    /// Adaptive subdivision (§6.1): split a cell while its PVS has more objects than
    /// this (None = off), down to `adaptive_min_m`.
    pub adaptive_budget: Option<usize>,
    /// A cell is not split when its halves would be narrower than this (m).
    pub adaptive_min_m: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            resolution_px: DEFAULT_RESOLUTION_PX,
            improved: true,
            extension: DEFAULT_EXTENSION,
            sweep: false,
            sweep_planes: 15,
            kernel_px: 5,
            sweep_start_m: 2.0,
            sweep_reach_m: 20.0,
            solid_angle: 0.002,
            max_occluders: 3000,
            plane_candidates: 12,
            planes_per_direction: 3,
            occludee_splits: 3,
            // By default every cell wider than 50 m is split down to halves of at least
            // 25 m: a deep cell's occludee Projections (which contain the cell's
            // cross-section) are too large for street fronts with gaps to cover.
            adaptive_budget: Some(0),
            adaptive_min_m: 25.0,
        }
    }
}

impl Params {
    /// The parameters for user settings (validated through the registry's knobs).
    pub fn from_options(opts: &MethodOptions) -> Self {
        Self::from_typed(&ExtProjOptions {
            resolution_px: opts.resolution_px,
            sweep: opts.sweep,
            planes: opts.planes,
        })
    }

    /// The parameters for the typed options of the registry.
    pub fn from_typed(opts: &ExtProjOptions) -> Self {
        let mut p = Params {
            sweep: opts.sweep,
            ..Params::default()
        };
        if p.sweep {
            p.resolution_px = SWEEP_RESOLUTION_PX;
        }
        if let Some(r) = opts.resolution_px {
            p.resolution_px = (r.clamp(8, 4096) as usize).next_power_of_two();
        }
        if let Some(k) = opts.planes {
            p.sweep_planes = (k as usize).clamp(1, 256);
        }
        p
    }
}

/// Default depth-map resolution: the knee of the PVS-size/time curve of the paper's
/// Fig. 12 on street cells (each doubling past it buys a few per cent of PVS for about
/// half again the time; the measured curve is in the benchmark report).
pub(crate) const DEFAULT_RESOLUTION_PX: usize = 512;

/// Default extension of the planes for the corner directions. The paper's 1.5
/// (§6.1: "extended (e.g., by 1.5 used in our tests)") makes every pixel 1.5 times the frustum's;
/// an occludee's Projection must only fit inside some plane, which 1.2 still allows
/// at the diagonals, and smaller pixels give a tighter PVS
/// (`docs/methods/ext-proj.md`).
pub const DEFAULT_EXTENSION: f64 = 1.2;

/// Default resolution with the sweep (`--resolution` overrides it): the sweep fuses
/// leaves only where their Projections stay several pixels wide after the K-pixel
/// kernel of each step, and at 256 px few of a dense forest's leaves do
/// (`docs/methods/ext-proj.md`).
pub(crate) const SWEEP_RESOLUTION_PX: usize = 512;

/// Resolution (pixels per side) of the depth maps on which candidate planes are scored.
pub(crate) const SCORING_PX: usize = 128;

/// Candidate planes are scored with at most this many occluder pieces (the largest).
pub(crate) const SCORING_PIECES: usize = 1500;

/// Candidate planes just inside an occluder's near face lie this far behind it (m).
pub(crate) const SLICE_INSET_M: f64 = 0.25;

/// Whether the local box `b` meets the frustum of the planes of a direction: the
/// cell's cross-section grown by the distance from its near face and scaled by
/// `extension` about its centre, as [`Plane::new`] does, at `b`'s far depth.
fn in_frustum(lc: &LocalBox, b: &LocalBox, extension: f64) -> bool {
    let grow = (b.max.x - lc.min.x).max(0.0);
    let (cu, cv) = (0.5 * (lc.min.y + lc.max.y), 0.5 * (lc.min.z + lc.max.z));
    let hu = (0.5 * (lc.max.y - lc.min.y) + grow) * extension;
    let hv = (0.5 * (lc.max.z - lc.min.z) + grow) * extension;
    b.max.y >= cu - hu && b.min.y <= cu + hu && b.max.z >= cv - hv && b.min.z <= cv + hv
}

/// `ext-proj` prepared for a scene.
pub struct ExtProj {
    pub scene: Arc<Scene>,
    pub params: Params,
    pub occluders: OccluderSet,
    /// Occludee boxes per object (outer prisms' boxes, or the bounds).
    boxes: Vec<Vec<Aabb3>>,
    /// Per object, the vertices of each outer prism (parallel to `boxes`; the box's
    /// corners when the object has no outer prism).
    hulls: Vec<Vec<Vec<DVec3>>>,
}

/// Prepare `ext-proj` for `scene`.
pub(crate) fn create(
    method: Method,
    scene: Arc<Scene>,
    opts: &ExtProjOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    if method != Method::ExtProj {
        return Err(MethodError::Unknown(method.name().to_string()));
    }
    Ok(Box::new(ExtProj::new(scene, Params::from_typed(opts))))
}

/// Whether the Projection of box `b` (world) on `plane` — its standard rectangle and,
/// with `improved`, its improved one (§4), clipped to an `n`-pixel map — meets no pixel
/// for which `touched` holds on the range it covers (§6.1 "fully visible"). `false` when
/// the box is not beyond the far face of `cell` (its views are unbounded).
pub(crate) fn projection_touches_nothing(
    plane: &Plane,
    cell: &LocalBox,
    n: usize,
    b: &Aabb3,
    improved: bool,
    touched: impl Fn([usize; 4]) -> bool,
) -> bool {
    let occ = plane.dir.box_to_local(b.min, b.max);
    [false, improved].iter().all(|&imp| {
        let Some((rect, _)) = occludee_projection(cell, &occ, plane.x, imp) else {
            return false;
        };
        let (lo, hi) = (plane.to_px(rect.min), plane.to_px(rect.max));
        clipped_pixel_range(lo, hi, n).is_none_or(|r| !touched(r))
    })
}

/// One plane of one direction, ready for occludee tests.
pub struct PlaneMap {
    pub plane: Plane,
    pub cell: LocalBox,
    pub map: DepthMap,
}

impl PlaneMap {
    /// Whether the occludee box (world) is hidden on this plane.
    pub fn hides(&self, b: &Aabb3, improved: bool) -> bool {
        self.hides_local(&self.plane.dir.box_to_local(b.min, b.max), improved)
    }

    /// Whether the convex hull of the occludee points (world) is hidden on this plane:
    /// the bounding rectangle of its Projection (§3.1) spans the views of its vertices
    /// from the cell's corners — for a fixed viewpoint the view is a linear-fractional
    /// map, extreme at the hull's vertices; for a fixed point it is monotone in each
    /// coordinate of the viewpoint, extreme at the cell's corners. Tighter than the
    /// box for a rotated building; its extended depth is its nearest vertex's. With
    /// `improved`, a hull between the cell and the plane uses the improved Projection
    /// of §4 on its vertices' 2D projections (`occludee::improved_segment_points`).
    pub fn hides_points(&self, points: &[DVec3], improved: bool) -> bool {
        let x = self.plane.x;
        if points.is_empty() {
            return false;
        }
        let local: Vec<DVec3> = points.iter().map(|p| self.plane.dir.to_local(*p)).collect();
        let mut near = f64::INFINITY;
        let mut far = f64::NEG_INFINITY;
        for p in &local {
            if !(p.x > self.cell.max.x) {
                return false;
            }
            near = near.min(p.x);
            far = far.max(p.x);
        }
        let mut rect: Option<(DVec2, DVec2)> = None;
        if improved && far <= x {
            let cw = [self.cell.min.x, self.cell.max.x];
            let wu: Vec<DVec2> = local.iter().map(|p| DVec2::new(p.x, p.y)).collect();
            let wv: Vec<DVec2> = local.iter().map(|p| DVec2::new(p.x, p.z)).collect();
            let su =
                occludee::improved_segment_points(cw, [self.cell.min.y, self.cell.max.y], &wu, x);
            let sv =
                occludee::improved_segment_points(cw, [self.cell.min.z, self.cell.max.z], &wv, x);
            if let (Some(su), Some(sv)) = (su, sv) {
                rect = Some((DVec2::new(su[0], sv[0]), DVec2::new(su[1], sv[1])));
            }
        }
        let (lo, hi) = rect.unwrap_or_else(|| {
            let mut lo = DVec2::splat(f64::INFINITY);
            let mut hi = DVec2::splat(f64::NEG_INFINITY);
            let corners = self.cell.corners();
            for p in &local {
                for e in &corners {
                    let q = planes::view(*e, *p, x);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
            (lo, hi)
        });
        let (a, b) = (self.plane.to_px(lo), self.plane.to_px(hi));
        let Some(r) = pixel_range(a, b, self.map.n) else {
            return false;
        };
        self.map
            .all_below(r[0], r[1], r[2], r[3], depth_down(near - x))
    }

    /// Whether the Projection of the box (world) meets no occluder Projection on this
    /// plane (§6.1 "fully visible"): its rectangles — standard and, with `improved`,
    /// improved — clipped to the map touch no covered pixel. `false` when the box is
    /// not beyond the cell's far face (its views are unbounded).
    pub(crate) fn touches_nothing(&self, b: &Aabb3, improved: bool) -> bool {
        projection_touches_nothing(&self.plane, &self.cell, self.map.n, b, improved, |r| {
            self.map.any_covered(r)
        })
    }

    /// Whether the occludee box (in this plane's local frame) is hidden on this plane.
    pub fn hides_local(&self, occ: &LocalBox, improved: bool) -> bool {
        let Some((rect, depth)) = occludee_projection(&self.cell, occ, self.plane.x, improved)
        else {
            return false;
        };
        let (lo, hi) = (self.plane.to_px(rect.min), self.plane.to_px(rect.max));
        let Some(r) = pixel_range(lo, hi, self.map.n) else {
            return false;
        };
        self.map
            .all_below(r[0], r[1], r[2], r[3], depth_down(depth))
    }
}

/// A convex occluder piece in one direction's local frame.
pub struct LocalPiece {
    pub index: u32,
    pub vertices: Vec<DVec3>,
    pub near: f64,
    pub far: f64,
    /// Solid-angle proxy from the cell.
    pub weight: f64,
}

impl ExtProj {
    pub fn new(scene: Arc<Scene>, params: Params) -> Self {
        let occluders = OccluderSet::build(&scene, params.solid_angle);
        let mut boxes = Vec::with_capacity(scene.objects.len());
        let mut hulls = Vec::with_capacity(scene.objects.len());
        for o in &scene.objects {
            let (b, h): (Vec<Aabb3>, Vec<Vec<DVec3>>) = o
                .outer
                .iter()
                .filter(|p| !p.aabb().is_empty())
                .map(|p| {
                    let v: Vec<DVec3> = [p.base, p.top]
                        .iter()
                        .flat_map(|&z| p.footprint.exterior.iter().map(move |q| q.extend(z)))
                        .collect();
                    (p.aabb(), v)
                })
                .unzip();
            if b.is_empty() {
                boxes.push(vec![o.bounds]);
                hulls.push(vec![o.bounds.corners().to_vec()]);
            } else {
                boxes.push(b);
                hulls.push(h);
            }
        }
        ExtProj {
            scene,
            params,
            occluders,
            boxes,
            hulls,
        }
    }

    /// The occluder pieces relevant to `cell` in direction `dir`, clipped beyond the
    /// cell's far face, largest solid angle first, at most `max_occluders`. Pieces
    /// outside the direction's extended frustum are left to the other directions: their
    /// Projections fall outside this direction's planes.
    pub fn local_pieces(&self, cell: &ViewCell, dir: Direction, ids: &[u32]) -> Vec<LocalPiece> {
        let lc = dir.box_to_local(cell.min, cell.max);
        let w_min = lc.max.x + FACE_CLEARANCE_M;
        let mut out: Vec<LocalPiece> = Vec::new();
        for &i in ids {
            let piece = &self.occluders.pieces[i as usize];
            let lb = dir.box_to_local(piece.bounds.min, piece.bounds.max);
            if lb.max.x <= w_min || !in_frustum(&lc, &lb, self.params.extension) {
                continue;
            }
            let vertices = piece.occluder.local_vertices(dir, w_min);
            if vertices.len() < 3 {
                continue;
            }
            let near = vertices.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
            let far = vertices
                .iter()
                .map(|p| p.x)
                .fold(f64::NEG_INFINITY, f64::max);
            let dist = (near - lc.max.x).max(0.5);
            out.push(LocalPiece {
                index: i,
                vertices,
                near,
                far,
                weight: piece.area / (dist * dist),
            });
        }
        out.sort_by(|a, b| b.weight.total_cmp(&a.weight).then(a.index.cmp(&b.index)));
        out.truncate(self.params.max_occluders);
        out
    }

    /// §6.1 "Choice of the projection plane": candidate planes just behind each
    /// occluder (the paper) and just inside its near face (a slice of the whole
    /// street front, §3.3), at most `plane_candidates` of them. The paper scores a
    /// candidate by the pixels its Projections fill; that favours planes hugging the
    /// cell, whose few filled pixels are useless as soon as one gap faces the cell
    /// (every occludee's Projection then contains the cell's cross-section). We score
    /// each candidate by what the filled pixels are for: the occludee boxes it hides,
    /// on a depth map at reduced resolution drawn with the largest pieces. The planes are then kept greedily, each
    /// maximizing the boxes not hidden by the planes kept before it (at most
    /// `planes_per_direction`; none when no candidate hides anything).
    pub(crate) fn choose_planes(
        &self,
        dir: Direction,
        lc: &LocalBox,
        pieces: &[LocalPiece],
        occludees: &[LocalBox],
    ) -> Vec<f64> {
        let occludees: Vec<&LocalBox> = occludees.iter().filter(|o| o.min.x > lc.max.x).collect();
        if occludees.is_empty() || pieces.is_empty() {
            return vec![];
        }
        let mut depths: Vec<f64> = pieces.iter().map(|p| p.far + 1e-3).collect();
        depths.extend(pieces.iter().map(|p| p.near + SLICE_INSET_M));
        let cands = candidate_positions(&depths, self.params.plane_candidates);
        let n = self.params.resolution_px.min(SCORING_PX);
        let hidden: Vec<(f64, Vec<bool>)> = cands
            .into_iter()
            .filter(|&x| x > lc.max.x)
            .map(|x| {
                let plane = Plane::new(dir, lc, x, n, self.params.extension);
                let pm = PlaneMap {
                    plane,
                    cell: *lc,
                    map: self.depth_map(&plane, lc, &pieces[..pieces.len().min(SCORING_PIECES)]),
                };
                let h = occludees
                    .iter()
                    .map(|o| pm.hides_local(o, self.params.improved))
                    .collect();
                (x, h)
            })
            .collect();
        let mut done = vec![false; occludees.len()];
        let mut kept: Vec<f64> = Vec::new();
        while kept.len() < self.params.planes_per_direction {
            let gain = |h: &[bool]| h.iter().zip(&done).filter(|(h, d)| **h && !**d).count();
            let best = hidden
                .iter()
                .filter(|(x, _)| !kept.contains(x))
                .map(|(x, h)| (gain(h), *x, h))
                .max_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
            let Some((g, x, h)) = best else { break };
            if g == 0 {
                break;
            }
            kept.push(x);
            for (d, h) in done.iter_mut().zip(h) {
                *d |= *h;
            }
        }
        kept
    }

    /// Draw the Projections (and slices) of `pieces` on `plane` into a depth map.
    pub fn depth_map(&self, plane: &Plane, lc: &LocalBox, pieces: &[LocalPiece]) -> DepthMap {
        let mut b = CoverageBuilder::new(plane.n);
        for p in pieces {
            for (poly, depth) in plane_safe_projections(&p.vertices, lc, plane.x) {
                let px: Vec<DVec2> = poly.iter().map(|q| plane.to_px(*q)).collect();
                b.add_convex(&px, depth_up(depth));
            }
            if p.near < plane.x && plane.x < p.far {
                if let Some(s) = self.occluders.pieces[p.index as usize]
                    .occluder
                    .slice(plane.dir, plane.x)
                {
                    let px: Vec<DVec2> = s.iter().map(|q| plane.to_px(*q)).collect();
                    b.add_convex(&px, 0.0);
                }
            }
        }
        b.finish()
    }

    /// The depth-mapped planes of `cell` (§6.1), chosen for all the scene's objects.
    pub fn plane_maps(&self, cell: &ViewCell) -> Vec<PlaneMap> {
        let all: Vec<u32> = (0..self.scene.objects.len() as u32).collect();
        self.plane_maps_for(cell, &all)
    }

    /// The objects of `candidates` (sorted ids) as an occluder filter: `None` when
    /// they are all the scene's objects.
    fn occluder_filter<'a>(&self, candidates: &'a [u32]) -> Option<&'a [u32]> {
        (candidates.len() < self.scene.objects.len()).then_some(candidates)
    }

    /// The depth-mapped planes of `cell` (§6.1), chosen to hide the occludees of
    /// `candidates` (sorted object ids: the objects not yet known hidden from `cell`).
    /// Occluders made only of other objects are left out: they are hidden from a
    /// parent cell, hence from `cell` (§6.1, "we also use the PVS of the parent cell to
    /// cull hidden occluders"), and leaving occluders out is always conservative.
    pub(crate) fn plane_maps_for(&self, cell: &ViewCell, candidates: &[u32]) -> Vec<PlaneMap> {
        let ids = self
            .occluders
            .relevant_among(&cell.aabb(), self.occluder_filter(candidates));
        let mut maps = Vec::new();
        for dir in Direction::ALL {
            let lc = dir.box_to_local(cell.min, cell.max);
            let pieces = self.local_pieces(cell, dir, &ids);
            if pieces.is_empty() {
                continue;
            }
            let occludees: Vec<LocalBox> = candidates
                .iter()
                .flat_map(|&id| self.boxes[id as usize].iter())
                .map(|b| dir.box_to_local(b.min, b.max))
                .collect();
            for x in self.choose_planes(dir, &lc, &pieces, &occludees) {
                let plane = Plane::new(
                    dir,
                    &lc,
                    x,
                    self.params.resolution_px,
                    self.params.extension,
                );
                let map = self.depth_map(&plane, &lc, &pieces);
                maps.push(PlaneMap {
                    plane,
                    cell: lc,
                    map,
                });
            }
        }
        maps
    }

    /// Whether a box is hidden on some plane; boxes that fail are split along their
    /// longest axis and both halves tried (hierarchical occludee test).
    pub(crate) fn box_hidden(
        &self,
        b: &Aabb3,
        maps: &[PlaneMap],
        extra: &dyn Fn(&Aabb3) -> bool,
        splits: u32,
    ) -> bool {
        if maps.iter().any(|m| m.hides(b, self.params.improved)) || extra(b) {
            return true;
        }
        if splits == 0 {
            return false;
        }
        let s = b.size();
        let axis = if s.x >= s.y && s.x >= s.z {
            0
        } else if s.y >= s.z {
            1
        } else {
            2
        };
        let mid = 0.5 * (b.min[axis] + b.max[axis]);
        let (mut lo, mut hi) = (*b, *b);
        lo.max[axis] = mid;
        hi.min[axis] = mid;
        self.box_hidden(&lo, maps, extra, splits - 1)
            && self.box_hidden(&hi, maps, extra, splits - 1)
    }

    /// PVS of `cell` restricted to `candidates` (sorted object ids: all the objects,
    /// or the PVS of a parent cell — the other objects, hidden, do not occlude either).
    pub fn pvs_among(&self, cell: &ViewCell, candidates: &[u32]) -> Vec<u32> {
        let maps = self.plane_maps_for(cell, candidates);
        let sweep = if self.params.sweep {
            sweep::Sweep::run(self, cell, self.occluder_filter(candidates))
        } else {
            sweep::Sweep::empty()
        };
        let improved = self.params.improved;
        let extra = |b: &Aabb3| sweep.hides(b, improved);
        let hierarchy = Hierarchy::build(candidates, |id| {
            let boxes = &self.boxes[id as usize];
            boxes.iter().skip(1).fold(boxes[0], |acc, b| acc.union(*b))
        });
        hierarchy.visible(
            |b| {
                if maps.iter().any(|m| m.hides(b, improved)) || extra(b) {
                    Verdict::Hidden
                } else if maps.iter().all(|m| m.touches_nothing(b, improved))
                    && sweep.touches_nothing(b, improved)
                {
                    Verdict::FullyVisible
                } else {
                    Verdict::Unknown
                }
            },
            |id| !self.object_hidden(id, &maps, &extra),
        )
    }

    /// Whether every occludee box of object `id` is hidden on some plane: by its outer
    /// prism's hull, or by the box itself or its halves ([`ExtProj::box_hidden`]).
    fn object_hidden(&self, id: u32, maps: &[PlaneMap], extra: &dyn Fn(&Aabb3) -> bool) -> bool {
        let (boxes, hulls) = (&self.boxes[id as usize], &self.hulls[id as usize]);
        boxes.iter().zip(hulls).all(|(b, h)| {
            maps.iter().any(|m| m.hides_points(h, self.params.improved))
                || self.box_hidden(b, maps, extra, self.params.occludee_splits)
        })
    }
}

impl VisibilityMethod for ExtProj {
    fn name(&self) -> &'static str {
        "ext-proj"
    }

    fn params(&self) -> Vec<(String, String)> {
        let p = &self.params;
        let mut v = vec![
            ("resolution".to_string(), p.resolution_px.to_string()),
            ("improved".to_string(), p.improved.to_string()),
            ("extension".to_string(), p.extension.to_string()),
            (
                "planes_per_direction".to_string(),
                p.planes_per_direction.to_string(),
            ),
            ("sweep".to_string(), p.sweep.to_string()),
        ];
        if p.sweep {
            v.push(("planes".to_string(), p.sweep_planes.to_string()));
            v.push(("kernel".to_string(), p.kernel_px.to_string()));
            v.push(("sweep_start".to_string(), p.sweep_start_m.to_string()));
            v.push(("sweep_reach".to_string(), p.sweep_reach_m.to_string()));
        }
        if let Some(b) = p.adaptive_budget {
            v.push(("adaptive_budget".to_string(), b.to_string()));
        }
        v
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        if !cell.min.is_finite() || !cell.max.is_finite() {
            return Err(MethodError::BadCell(cell.to_string()));
        }
        let all: Vec<u32> = (0..self.scene.objects.len() as u32).collect();
        Ok(match self.params.adaptive_budget {
            Some(budget) => adaptive::pvs(self, cell, &all, budget),
            None => self.pvs_among(cell, &all),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_geom::Polygon;
    use sightline_scene::Object;

    #[test]
    fn frustum_of_a_direction() {
        let lc = Direction::PosX.box_to_local(DVec3::ZERO, DVec3::new(10.0, 10.0, 2.0));
        let b = |u0: f64, u1: f64| LocalBox {
            min: DVec3::new(20.0, u0, 0.0),
            max: DVec3::new(30.0, u1, 10.0),
        };
        // At depth 30 the frustum spans 5 ± 1.5 × (5 + 30) in u.
        assert!(in_frustum(&lc, &b(50.0, 57.0), 1.5));
        assert!(!in_frustum(&lc, &b(58.0, 70.0), 1.5));
        assert!(!in_frustum(&lc, &b(-70.0, -48.0), 1.5));
    }

    /// A deep cell facing a street front with a gap and a wall behind it: the planes
    /// kept in +y are those that hide occludees (none between the cell and the street
    /// front, where nothing can be hidden), the building behind the wall is culled, and
    /// no plane is kept in -y, where there is nothing to hide.
    #[test]
    fn planes_are_chosen_by_the_occludees_they_hide() {
        let scene = Arc::new(Scene::from_objects(vec![
            Object::rect_block(-60.0, 12.0, 18.0, 30.0, 10.0), // 0 street front, left of the gap
            Object::rect_block(22.0, 12.0, 100.0, 30.0, 10.0), // 1 street front, right of the gap
            Object::rect_block(-200.0, 40.0, 240.0, 45.0, 20.0), // 2 solid wall behind
            Object::rect_block(15.0, 60.0, 25.0, 70.0, 8.0),   // 3 behind the wall
        ]));
        let params = Params {
            adaptive_budget: None,
            ..Params::default()
        };
        let ext = ExtProj::new(scene.clone(), params);
        let c = ViewCell::new(DVec3::new(0.0, -30.0, 1.5), DVec3::new(40.0, 10.0, 2.0)).unwrap();
        let all: Vec<u32> = (0..4).collect();
        let maps = ext.plane_maps_for(&c, &all);
        let py: Vec<&PlaneMap> = maps
            .iter()
            .filter(|m| m.plane.dir == Direction::PosY)
            .collect();
        assert!(!py.is_empty());
        assert!(
            py.iter().all(|m| m.plane.x > 12.0),
            "{:?}",
            py.iter().map(|m| m.plane.x).collect::<Vec<_>>()
        );
        let pvs = ext.pvs_among(&c, &all);
        assert_eq!(pvs, vec![0, 1, 2]);
        // Nothing to hide in -y: no plane is kept there.
        assert!(maps.iter().all(|m| m.plane.dir != Direction::NegY));
        // The hull test on a box's corners is the plain box test (same rectangle).
        let mut agree = 0;
        for m in &maps {
            for o in &scene.objects {
                let b = o.bounds;
                let local = m.plane.dir.box_to_local(b.min, b.max);
                assert_eq!(
                    m.hides_points(&b.corners(), false),
                    m.hides_local(&local, false)
                );
                assert_eq!(
                    m.hides_points(&b.corners(), true),
                    m.hides_local(&local, true)
                );
                agree += m.hides_local(&local, false) as usize;
            }
        }
        assert!(agree > 0);
    }

    /// The occludee hierarchy (§6.1) stops at hidden and fully visible nodes without
    /// changing the PVS: on a grid of blocks of mixed heights, from cells in several
    /// streets, it equals the object-by-object test on the same planes.
    #[test]
    fn hierarchy_gives_the_object_by_object_pvs() {
        let mut objects = Vec::new();
        for i in 0..8 {
            for j in 0..8 {
                let (x, y) = (30.0 * i as f64, 30.0 * j as f64);
                let h = 6.0 + ((i * 7 + j * 3) % 5) as f64 * 6.0;
                objects.push(Object::rect_block(x, y, x + 9.0, y + 18.0, h));
                objects.push(Object::rect_block(x + 9.0, y, x + 18.0, y + 18.0, h * 0.5));
            }
        }
        let scene = Arc::new(Scene::from_objects(objects));
        let params = Params {
            resolution_px: 128,
            adaptive_budget: None,
            ..Params::default()
        };
        let ext = ExtProj::new(scene.clone(), params);
        let all: Vec<u32> = (0..scene.objects.len() as u32).collect();
        let mut hidden = 0;
        for (x, y) in [(20.0, 40.0), (81.0, 110.0), (140.0, 200.0), (200.0, 22.0)] {
            let c =
                ViewCell::new(DVec3::new(x, y, 1.5), DVec3::new(x + 8.0, y + 6.0, 2.0)).unwrap();
            let maps = ext.plane_maps_for(&c, &all);
            let flat: Vec<u32> = all
                .iter()
                .copied()
                .filter(|&id| !ext.object_hidden(id, &maps, &|_| false))
                .collect();
            assert_eq!(ext.pvs_among(&c, &all), flat, "from {c}");
            hidden += all.len() - flat.len();
        }
        assert!(hidden > 0);
    }

    /// A building rotated by 45° behind a wall is hidden by the test of its hull.
    #[test]
    fn rotated_occludee_is_tested_by_its_hull() {
        let diamond = Polygon::new(
            vec![
                DVec2::new(10.0, 60.0),
                DVec2::new(20.0, 50.0),
                DVec2::new(30.0, 60.0),
                DVec2::new(20.0, 70.0),
            ],
            vec![],
        );
        let scene = Arc::new(Scene::from_objects(vec![
            Object::rect_block(-200.0, 40.0, 240.0, 45.0, 12.0),
            Object::block(None, diamond, 0.0, 13.0),
        ]));
        let ext = ExtProj::new(scene.clone(), Params::default());
        let c = ViewCell::new(DVec3::new(15.0, 20.0, 1.5), DVec3::new(25.0, 30.0, 2.0)).unwrap();
        let maps = ext.plane_maps_for(&c, &[0, 1]);
        let h = &ext.hulls[1][0];
        assert!(maps.iter().any(|m| m.hides_points(h, false)));
        assert_eq!(ext.pvs_among(&c, &[0, 1]), vec![0]);
    }
}
