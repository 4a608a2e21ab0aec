//! Erosion-based visibility (Décoret, Debunne, Sillion 2003), the four methods of its
//! Fig. 9: `erosion` (method 4: occluders eroded by the shaft-supporting segment,
//! occludees shrunk), `erosion-segment` (method 3: segments, occludees as is),
//! `erosion-cell` (method 2: occluders eroded by the cell) and `shrink-sphere`
//! (method 1: occluders eroded by the octagon around the cell's bounding disc, after
//! Wonka et al. 2000); and `erosion-rays`, the X-sampling ray test of §7.1 (Theorem
//! 2: occludees sampled by points, rays from the centre against occluders eroded by
//! the cell, see [`rays`]).
//!
//! **Guarantee**: the PVS contains every object visible from the cell's free space —
//! at any resolution (the parameter only trades tightness for time).
//!
//! Pipeline (one module per concern):
//! * [`field`]: the inner bounds of all objects fused into one height field (their union: touching buildings leave no gap),
//!   rasterized conservatively (inner rule on the union), with closed courtyards filled
//!   where that provably hides nothing visible.
//! * [`erode`]: erosion of that raster by the structuring elements (§3.1, §4.3) — a
//!   conservative min-filter — cached for every cell of the same *shape* (§5.1).
//! * [`tiles`]: that erosion done tile by tile, when the march first reads a tile, so
//!   the part of the city behind a closed horizon is never eroded (same values, same
//!   PVS).
//! * [`shrink`]: occludee pieces, the supporting segment of each (§3.3, §5.1), the
//!   shrunk occludee (§4.4) and the eye raise that makes §3.3 hold in 3D.
//! * [`rays`]: the X-sampling of occludees for `erosion-rays` (§7.1).
//! * [`occlusion`]: the from-centre test (§5) on a polar occlusion map: eroded
//!   occluders marched front to back with the inner rule and farthest depth, lazily:
//!   each direction only as far as the tests asked of it need, each test only until
//!   its answer is known (§7 "Scaling"); occludees with outer coverage and nearest
//!   depth.
//! * `crate::seed`: objects met first by exact rays from a few eyes of the cell are
//!   in the PVS without a test (the erosion would keep them anyway; no PVS changes).
//!
//! Hierarchy (§7 "Bad scenario" and "Viewcells"): Theorem 1 erodes every occluder by
//! the whole cell, so a 25 m cell in a city of 15 m deep building rows sees through
//! everything. The PVS of a cell is the union of the PVS of its parts, and what is
//! hidden from a cell is hidden from its parts: `refine` tests the cell, then its
//! quarters for what it may see, down to [`MAX_DEPTH`] levels (≥ [`MIN_SUBCELL_M`];
//! [`RAYS_MIN_SUBCELL_M`] for `erosion-rays`).
//!
//! Vertical erosion (§3.4): the occluders united with the ground form a height field
//! whose columns extend to −∞, so eroding by the cell's height segment only moves
//! the viewpoint: a height field blocks a sight line only if it blocks every lower
//! one, hence only the cell's top face `z = z1` matters as a viewpoint and only the
//! top faces of occludees as targets (the paper's "reduce the occludee by one half of
//! the viewcell height" is the same argument, less tight).
//!
//! Parameter: `resolution_px` = number of azimuth bins (default 4096); the occluder
//! raster's pixel is [`field::PIXEL_M`] (larger for huge scenes).

pub mod erode;
pub mod field;
pub mod occlusion;
pub mod rays;
pub mod shrink;
pub mod tiles;

use crate::seed::{SeedGrid, SeedScratch};
use erode::Element;
use field::{HeightField, MinPyramid};
use occlusion::{Bins, PolarMap, Target};
use shrink::Region;
use sightline_core::{ErosionOptions, Method, MethodError, MethodOptions, VisibilityMethod};
use sightline_geom::{Aabb2, Aabb3, DVec2, ViewCell};
use sightline_scene::occluders::{collect_occluders, local_origin};
use sightline_scene::Scene;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use tiles::{Occluders, TiledErosion};

/// Cells are refined into quarters at most this many times (see `refine`). On real
/// street cells the size of the last quarters decides the tightness more than any
/// other parameter: a diagonal of the cell, the supporting segment of every shaft to a
/// corner region (§3.3), erodes a row of terraced houses by the quarter's size across
/// its depth (Den Haag's rows of 8–10 m are gone at 3 m quarters, kept at 1.5 m). The
/// level is adaptive as every level: only quarters with free space, for the objects
/// their parent may still see.
pub const MAX_DEPTH: usize = 4;
/// The same for `erosion-rays`.
pub const RAYS_MAX_DEPTH: usize = 4;
/// The first pass of each test uses this many times fewer azimuth bins.
const COARSE_FACTOR: usize = 16;
/// Sub-cells are not made smaller than this (m): a 25 m cell reaches 1.6 m quarters
/// at its 4th level, a 10 m cell 1.25 m ones at its 3rd.
pub const MIN_SUBCELL_M: f64 = 1.2;
/// The same for `erosion-rays` (a 25 m cell reaches 1.6 m quarters at its 4th level).
pub const RAYS_MIN_SUBCELL_M: f64 = 1.5;
/// Memory bound of the cache of eroded occluder rasters (bytes).
const CACHE_BYTES: usize = 3 << 29;

/// Default number of azimuth bins of the occlusion map.
pub const DEFAULT_BINS: u32 = 4096;

/// Which of the four methods of Fig. 9.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Method 4: segment erosion and shrunk occludees (`erosion`).
    Full,
    /// Method 3: segment erosion, occludees as is (`erosion-segment`).
    Segment,
    /// Method 2: erosion by the cell footprint (`erosion-cell`).
    Cell,
    /// Method 1: erosion by the octagon around the bounding disc (`shrink-sphere`).
    Sphere,
    /// §7.1: occludees X-sampled by points, rays against the erosion by the cell
    /// (`erosion-rays`).
    Rays,
}

/// Prepare `method` (one of the erosion family) for `scene`.
pub(crate) fn create(
    method: Method,
    scene: Arc<Scene>,
    opts: &ErosionOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    let variant = match method {
        Method::Erosion => Variant::Full,
        Method::ErosionSegment => Variant::Segment,
        Method::ErosionCell => Variant::Cell,
        Method::ShrinkSphere => Variant::Sphere,
        Method::ErosionRays => Variant::Rays,
        m => return Err(MethodError::Unknown(m.name().to_string())),
    };
    let settings = MethodOptions {
        resolution_px: opts.azimuth_bins,
        ..MethodOptions::default()
    };
    Ok(Box::new(ErosionMethod::new(
        method.name(),
        variant,
        scene,
        &settings,
    )?))
}

/// One occludee top face: an outer prism's exterior ring at its top height.
#[derive(Clone, Debug)]
struct Top {
    ring: Vec<DVec2>,
    t: f64,
}

/// An erosion method prepared for one scene.
pub struct ErosionMethod {
    name: &'static str,
    variant: Variant,
    scene: Arc<Scene>,
    field: Arc<HeightField>,
    tops: Vec<Vec<Top>>,
    /// The azimuth bins of the full and of the coarse pass (built once).
    fine: Bins,
    coarse: Bins,
    /// Eroded occluders per (cell half size in µm, element, fill threshold in dm), with
    /// the tick of their last use (least recently used evicted beyond `CACHE_BYTES`).
    cache: Mutex<(u64, ErodedCache)>,
    /// Seed rays (`crate::seed`) in a frame centred at `origin`; `use_seed` turns them
    /// on (the default) or off: the PVS is the same.
    seed: SeedGrid,
    origin: DVec2,
    use_seed: bool,
    /// Erode tile by tile as the march reads ([`tiles`], the default) or the whole
    /// raster at once: the PVS is the same.
    tiled: bool,
}

type CacheKey = (i64, i64, Element, u16);
/// Eroded occluders with the tick of their last use.
type ErodedCache = HashMap<CacheKey, (Arc<Eroded>, u64)>;

/// The eroded occluders of one element, cell shape and fill threshold.
enum Eroded {
    Whole(MinPyramid),
    Tiled(TiledErosion),
}

impl Eroded {
    fn bytes(&self) -> usize {
        match self {
            Eroded::Whole(p) => p.bytes(),
            Eroded::Tiled(t) => t.bytes(),
        }
    }
}

impl Occluders for Eroded {
    fn pixel_m(&self) -> f64 {
        match self {
            Eroded::Whole(p) => p.pixel_m(),
            Eroded::Tiled(t) => t.pixel_m(),
        }
    }
    fn min_over(&self, r: Aabb2) -> u16 {
        match self {
            Eroded::Whole(p) => Occluders::min_over(p, r),
            Eroded::Tiled(t) => t.min_over(r),
        }
    }
    fn max_at_most(&self, r: Aabb2, limit: u16) -> bool {
        match self {
            Eroded::Whole(p) => p.max_at_most(r, limit),
            Eroded::Tiled(t) => t.max_at_most(r, limit),
        }
    }
}

/// X-samplings of one (sub-)cell per (object, top face) (None: keep the object).
type SampleMemo = HashMap<(usize, usize), Option<Vec<DVec2>>>;

/// What one pass of [`ErosionMethod::decide`] shares with the others: the maps of the
/// coarser pass (seeds of the new maps), whether its own maps seed a finer pass (else
/// they are recycled, [`PolarMap::recycle`]) and the X-samplings.
struct Pass<'a> {
    seeds: Option<HashMap<Element, PolarMap>>,
    seeds_next: bool,
    memo: &'a mut SampleMemo,
}

/// One visibility test of an occludee piece.
struct Test {
    element: Element,
    target: Target,
    /// Other valid shrunk occludees of the same piece: the piece is hidden if one of
    /// them, or `target`, is.
    alts: Vec<Target>,
    eye: f64,
    t: f64,
}

impl ErosionMethod {
    pub fn new(
        name: &'static str,
        variant: Variant,
        scene: Arc<Scene>,
        opts: &MethodOptions,
    ) -> Result<Self, MethodError> {
        let bins = opts.resolution_px.unwrap_or(DEFAULT_BINS);
        if !(8..=1 << 20).contains(&bins) {
            return Err(MethodError::Other(format!(
                "resolution {bins} out of range (8..=1048576 azimuth bins)"
            )));
        }
        let origin = local_origin(&scene);
        let (field, seed) = rayon::join(
            || HeightField::build(&scene),
            || SeedGrid::new(&scene, origin, &collect_occluders(&scene, origin)),
        );
        let tops = scene
            .objects
            .iter()
            .map(|o| {
                o.outer
                    .iter()
                    .filter(|p| p.footprint.exterior.len() >= 3)
                    .map(|p| Top {
                        ring: p.footprint.exterior.clone(),
                        t: p.top.max(p.base),
                    })
                    .collect()
            })
            .collect();
        Ok(ErosionMethod {
            name,
            variant,
            scene,
            field: Arc::new(field),
            tops,
            fine: Bins::new(bins as usize),
            coarse: Bins::new(bins as usize / COARSE_FACTOR),
            cache: Mutex::new((0, HashMap::new())),
            seed,
            origin,
            use_seed: true,
            tiled: true,
        })
    }

    /// Turn the seed rays (`crate::seed`) on or off (on by default). The PVS is the
    /// same: the seed only spares the tests of objects a ray from the cell reaches.
    pub fn with_seed(mut self, on: bool) -> Self {
        self.use_seed = on;
        self
    }

    /// Erode the occluders tile by tile as the march reads them (`true`, the default)
    /// or the whole raster at once. The PVS is the same ([`tiles`]).
    pub fn with_tiles(mut self, on: bool) -> Self {
        self.tiled = on;
        self
    }

    /// The erosion of the scene's occluders (courtyards filled above `fill_dm`) by
    /// `element` for cells of half size `half`, shared by every cell of that shape.
    fn eroded(&self, element: Element, half: DVec2, fill_dm: u16) -> Arc<Eroded> {
        let key = (
            (half.x * 1e6).round() as i64,
            (half.y * 1e6).round() as i64,
            element,
            fill_dm,
        );
        {
            let mut c = self.cache.lock().unwrap_or_else(|e| e.into_inner());
            c.0 += 1;
            let tick = c.0;
            if let Some(e) = c.1.get_mut(&key) {
                e.1 = tick;
                return e.0.clone();
            }
        }
        // Computed outside the lock: two threads may race to the same field, harmlessly.
        let g = Arc::new(if self.tiled {
            Eroded::Tiled(TiledErosion::new(
                self.field.clone(),
                element,
                half,
                fill_dm,
            ))
        } else {
            Eroded::Whole(MinPyramid::new(erode::erode(
                &self.field.filled(fill_dm),
                element,
                half,
            )))
        });
        let mut c = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let tick = c.0;
        c.1.insert(key, (g.clone(), tick));
        let bytes = |m: &ErodedCache| -> usize { m.values().map(|(g, _)| g.bytes()).sum() };
        while c.1.len() > 1 && bytes(&c.1) > CACHE_BYTES {
            let oldest = c.1.iter().min_by_key(|(_, v)| v.1).map(|(k, _)| *k);
            if let Some(k) = oldest {
                c.1.remove(&k);
            }
        }
        g
    }

    /// The tests of one object (None: visible without testing).
    ///
    /// `memo` keeps the X-samplings of `erosion-rays` per (object, top face) for the
    /// passes of one (sub-)cell: they depend on the cell, not on the number of bins.
    fn tests(
        &self,
        id: usize,
        cell: &ViewCell,
        ctx: &CellCtx,
        memo: &mut SampleMemo,
    ) -> Option<Vec<Test>> {
        let obj = &self.scene.objects[id];
        if obj.bounds.intersects(&cell.aabb()) {
            return None;
        }
        let mut tests = Vec::new();
        for (k, top) in self.tops[id].iter().enumerate() {
            match self.variant {
                Variant::Rays => {
                    // Theorem 2: the samples are a valid shrunk occludee for X = the
                    // cell, so the test runs on the map of `Element::Cell`.
                    let samples = memo
                        .entry((id, k))
                        .or_insert_with(|| rays::x_sampling(&top.ring, ctx.half, ctx.s))
                        .as_ref()?;
                    let points: Vec<[DVec2; 1]> = samples.iter().map(|&p| [p - ctx.s]).collect();
                    let parts: Vec<(&[DVec2], bool)> =
                        points.iter().map(|p| (&p[..], false)).collect();
                    tests.push(Test {
                        element: Element::Cell,
                        target: Target::new(&ctx.bins, &parts),
                        eye: ctx.z1,
                        t: top.t,
                        alts: Vec::new(),
                    });
                }
                Variant::Cell | Variant::Sphere => {
                    let element = if self.variant == Variant::Cell {
                        Element::Cell
                    } else {
                        Element::Octagon
                    };
                    tests.push(Test {
                        element,
                        target: ctx.target_ring(&top.ring, DVec2::ZERO),
                        eye: ctx.z1,
                        t: top.t,
                        alts: Vec::new(),
                    });
                }
                Variant::Full | Variant::Segment => {
                    let pieces = shrink::pieces(&top.ring, ctx.rect);
                    if pieces.is_empty() {
                        // Degenerate (zero-area) top face: keep the object.
                        return None;
                    }
                    for piece in pieces {
                        let test = match piece.region {
                            Region::Centre => return None,
                            Region::Side(el) => {
                                let target = if self.variant == Variant::Full {
                                    let [a, b] = shrink::shrunk_side(el, &piece, ctx.rect);
                                    Target::new(&ctx.bins, &[(&[a - ctx.s, b - ctx.s], false)])
                                } else {
                                    ctx.target_ring(&piece.ring, el.midpoint(ctx.half))
                                };
                                Test {
                                    element: el,
                                    target,
                                    alts: Vec::new(),
                                    eye: ctx.z1
                                        + shrink::eye_raise(&piece, ctx.rect, top.t, ctx.z1),
                                    t: top.t,
                                }
                            }
                            Region::Corner(el) => {
                                if ctx.cell_meets_occluders {
                                    // An occluder inside the cell could block the
                                    // backward extension of a sight line: use the
                                    // whole cell (Theorem 1 needs no extension).
                                    Test {
                                        element: Element::Cell,
                                        target: ctx.target_ring(&piece.ring, DVec2::ZERO),
                                        alts: Vec::new(),
                                        eye: ctx.z1,
                                        t: top.t,
                                    }
                                } else {
                                    let alts = if self.variant == Variant::Full {
                                        shrink::shrunk_corner(el, &piece, ctx.rect)
                                            .iter()
                                            .filter(|segs| !segs.is_empty())
                                            .map(|segs| {
                                                let rel: Vec<[DVec2; 2]> = segs
                                                    .iter()
                                                    .map(|[a, b]| [*a - ctx.s, *b - ctx.s])
                                                    .collect();
                                                let parts: Vec<(&[DVec2], bool)> =
                                                    rel.iter().map(|s| (&s[..], false)).collect();
                                                Target::new(&ctx.bins, &parts)
                                            })
                                            .collect()
                                    } else {
                                        Vec::new()
                                    };
                                    let target = ctx.target_ring(&piece.ring, DVec2::ZERO);
                                    Test {
                                        element: el,
                                        target,
                                        alts,
                                        eye: ctx.z1
                                            + shrink::eye_raise(&piece, ctx.rect, top.t, ctx.z1),
                                        t: top.t,
                                    }
                                }
                            }
                        };
                        if test.target.at_eye || !test.eye.is_finite() {
                            return None;
                        }
                        tests.push(test);
                    }
                }
            }
        }
        if tests.is_empty() {
            // No usable top face: keep the object (conservative).
            return None;
        }
        Some(tests)
    }

    /// Mark in `found` the objects of `candidates` that `cell` may see.
    ///
    /// The PVS of a cell is the union of the PVS of its parts (each is a viewcell), and
    /// an object hidden from a cell is hidden from every part of it. So the cell is
    /// tested first as a whole — which culls most of a city cheaply — and then, for what
    /// it may see, in quarters, recursively: deeper cells erode the occluders by a few
    /// metres instead of the whole cell, which is Theorem 1's price (§7 "Bad
    /// scenario"). Cells of one depth share one shape, hence one set of eroded
    /// occluders (§5.1); an object found visible is not tested again; a part with no
    /// free space sees nothing (visibility is defined from free space).
    fn refine(
        &self,
        cell: &ViewCell,
        rect: Aabb2,
        candidates: Vec<u32>,
        depth: usize,
        found: &mut [bool],
    ) {
        let mut undecided: Vec<u32> = candidates
            .into_iter()
            .filter(|&i| !found[i as usize])
            .collect();
        if undecided.is_empty() || !self.field.has_free_space(rect, cell.max.z) {
            return;
        }
        let mut visible = Vec::new();
        self.decide(cell, rect, &mut undecided, &mut visible);
        let size = rect.size();
        let (max_depth, min_m) = if self.variant == Variant::Rays {
            (RAYS_MAX_DEPTH, RAYS_MIN_SUBCELL_M)
        } else {
            (MAX_DEPTH, MIN_SUBCELL_M)
        };
        if depth >= max_depth || size.max_element() < 2.0 * min_m || visible.is_empty() {
            for i in visible {
                found[i as usize] = true;
            }
            return;
        }
        let c = rect.center();
        for (lo, hi) in [
            (rect.min, c),
            (DVec2::new(c.x, rect.min.y), DVec2::new(rect.max.x, c.y)),
            (DVec2::new(rect.min.x, c.y), DVec2::new(c.x, rect.max.y)),
            (c, rect.max),
        ] {
            let Ok(sub) = ViewCell::from_array([lo.x, lo.y, cell.min.z, hi.x, hi.y, cell.max.z])
            else {
                // Cannot happen for a valid cell; keep the objects rather than lose them.
                for &i in &visible {
                    found[i as usize] = true;
                }
                return;
            };
            self.refine(&sub, Aabb2::new(lo, hi), visible.clone(), depth + 1, found);
        }
    }

    /// Move the objects of `undecided` that `cell` (footprint `rect`) may see to
    /// `visible`: the two-pass from-centre test of §5.
    ///
    /// A first pass at 1/[`COARSE_FACTOR`] of the azimuth bins hides part of what will be
    /// hidden for a fraction of the cost (its blockers also seed the full pass); only
    /// what it leaves is tested at full resolution
    /// (the test is conservative at any resolution, so either pass may hide).
    fn decide(
        &self,
        cell: &ViewCell,
        rect: Aabb2,
        undecided: &mut Vec<u32>,
        visible: &mut Vec<u32>,
    ) {
        let mut memo = SampleMemo::new();
        if self.fine.n / COARSE_FACTOR < 64 {
            let pass = Pass {
                seeds: None,
                seeds_next: false,
                memo: &mut memo,
            };
            self.decide_at(&self.fine, cell, rect, undecided, visible, pass);
            return;
        }
        let mut maybe = Vec::new();
        let pass = Pass {
            seeds: None,
            seeds_next: true,
            memo: &mut memo,
        };
        let coarse_maps = self.decide_at(&self.coarse, cell, rect, undecided, &mut maybe, pass);
        let mut hidden = std::mem::take(undecided);
        self.decide_at(
            &self.fine,
            cell,
            rect,
            &mut maybe,
            visible,
            Pass {
                seeds: Some(coarse_maps),
                seeds_next: false,
                memo: &mut memo,
            },
        );
        hidden.append(&mut maybe);
        hidden.sort_unstable();
        *undecided = hidden;
    }

    /// [`Self::decide`] with `bins` azimuth bins; the maps of a pass with fewer bins
    /// from the same eye, if given, seed the new maps with their blockers
    /// ([`PolarMap::seeded`]). Returns the maps built if they seed a finer pass
    /// (`pass.seeds_next`; else none: they are recycled).
    fn decide_at(
        &self,
        bins: &Bins,
        cell: &ViewCell,
        rect: Aabb2,
        undecided: &mut Vec<u32>,
        visible: &mut Vec<u32>,
        pass: Pass<'_>,
    ) -> HashMap<Element, PolarMap> {
        let Pass {
            mut seeds,
            seeds_next,
            memo,
        } = pass;
        let ctx = CellCtx {
            rect,
            half: rect.size() * 0.5,
            s: rect.center(),
            z1: cell.max.z,
            bins: bins.clone(),
            cell_meets_occluders: matches!(self.variant, Variant::Full | Variant::Segment)
                && self.field.meets_rect(rect),
            fill_dm: self.field.fill_threshold(rect, cell.max.z),
        };
        let mut pending: Vec<(u32, Vec<Test>)> = Vec::new();
        for &id in undecided.iter() {
            match self.tests(id as usize, cell, &ctx, memo) {
                None => visible.push(id),
                Some(t) => pending.push((id, t)),
            }
        }
        // One map per element, marched lazily by the tests (`PolarMap`).
        let mut maps: HashMap<Element, (PolarMap, Arc<Eroded>)> = HashMap::new();
        for (_, tests) in &pending {
            for t in tests {
                let (map, _) = maps.entry(t.element).or_insert_with(|| {
                    let map = match seeds.as_mut().and_then(|s| s.remove(&t.element)) {
                        Some(coarse) => PolarMap::seeded(ctx.bins.clone(), coarse),
                        None => PolarMap::new(ctx.bins.clone()),
                    };
                    (map, self.eroded(t.element, ctx.half, ctx.fill_dm))
                });
                map.need(&t.target, t.eye);
                for a in &t.alts {
                    map.need(a, t.eye);
                }
            }
        }
        undecided.clear();
        for (id, tests) in pending {
            let hidden = tests.iter().all(|t| {
                maps.get_mut(&t.element).is_some_and(|(m, occ)| {
                    let occ = &**occ;
                    m.hidden(occ, ctx.s, &t.target, t.eye, t.t, 0)
                        || t.alts
                            .iter()
                            .any(|a| m.hidden(occ, ctx.s, a, t.eye, t.t, 0))
                })
            });
            if hidden {
                undecided.push(id);
            } else {
                visible.push(id);
            }
        }
        // The coarse maps no test of this pass asked for, and this pass's own unless
        // they seed the next.
        for (_, m) in seeds.into_iter().flatten() {
            m.recycle();
        }
        let mut out = HashMap::new();
        for (el, (m, _)) in maps {
            if seeds_next {
                out.insert(el, m);
            } else {
                m.recycle();
            }
        }
        out
    }
}

/// Per-cell quantities shared by all tests.
struct CellCtx {
    rect: Aabb2,
    half: DVec2,
    s: DVec2,
    z1: f64,
    bins: Bins,
    cell_meets_occluders: bool,
    /// Courtyards whose walls rise above this (dm) are filled (see `field`).
    fill_dm: u16,
}

impl CellCtx {
    /// A closed ring translated by `-shift`, relative to the eye.
    fn target_ring(&self, ring: &[DVec2], shift: DVec2) -> Target {
        let pts: Vec<DVec2> = ring.iter().map(|v| *v - shift - self.s).collect();
        Target::new(&self.bins, &[(&pts, true)])
    }
}

impl VisibilityMethod for ErosionMethod {
    fn name(&self) -> &'static str {
        self.name
    }

    fn params(&self) -> Vec<(String, String)> {
        vec![
            ("bins".into(), self.fine.n.to_string()),
            ("pixel_m".into(), self.field.g.pixel_m.to_string()),
        ]
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        let a = cell.to_array();
        if a.iter().any(|v| !v.is_finite()) || !(a[0] < a[3] && a[1] < a[4] && a[2] <= a[5]) {
            return Err(MethodError::BadCell(cell.to_string()));
        }
        let rect = Aabb2::new(cell.min.truncate(), cell.max.truncate());
        let mut found = vec![false; self.scene.objects.len()];
        if self.use_seed {
            let o3 = self.origin.extend(0.0);
            let local = Aabb3::new(cell.min - o3, cell.max - o3);
            self.seed
                .mark(&local, &mut found, &mut SeedScratch::default());
        }
        let all: Vec<u32> = (0..self.scene.objects.len() as u32).collect();
        self.refine(cell, rect, all, 0, &mut found);
        let visible: Vec<u32> = (0..found.len() as u32)
            .filter(|&i| found[i as usize])
            .collect();
        Ok(visible)
    }
}
