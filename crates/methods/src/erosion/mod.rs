//! Erosion-based visibility (Décoret, Debunne, Sillion 2003), the four methods of its
//! Fig. 9: `erosion` (method 4: occluders eroded by the shaft-supporting segment,
//! occludees shrunk), `erosion-segment` (method 3: segments, occludees as is),
//! `erosion-cell` (method 2: occluders eroded by the cell) and `shrink-sphere`
//! (method 1: occluders eroded by the octagon around the cell's bounding disc, after
//! Wonka et al. 2000).
//!
//! **Guarantee**: the PVS contains every object visible from the cell's free space —
//! at any resolution (the parameter only trades tightness for time).
//!
//! Pipeline (one module per concern):
//! * [`levels`]: the inner bounds of all objects fused into one height field, as level
//!   sets (NOTES §1) per square tile; eroded per structuring element and cell *shape*,
//!   lazily per tile, cached for every cell of that shape (§5.1).
//! * [`erode`]: exact polygon erosion by equation (1) (§4.3), rounded inward.
//! * [`shrink`]: occludee pieces, the supporting segment of each (§3.3, §5.1), the
//!   shrunk occludee (§4.4) and the eye raise that makes §3.3 hold in 3D.
//! * [`occlusion`]: the from-centre test (§5) on a polar occlusion map: inner coverage
//!   of eroded occluders with farthest depth, occludees with outer coverage and nearest
//!   depth, front-to-back tile culling against the map.
//!
//! Vertical erosion (§3.4): the occluders united with the ground form a height field
//! whose columns extend to −∞, so eroding by the cell's height segment only moves
//! the viewpoint: a height field blocks a sight line only if it blocks every lower
//! one, hence only the cell's top face `z = z1` matters as a viewpoint and only the
//! top faces of occludees as targets (the paper's "reduce the occludee by one half of
//! the viewcell height" is the same argument, less tight).
//!
//! Parameter: `resolution_px` = number of azimuth bins (default 2048).

pub mod erode;
pub mod levels;
pub mod occlusion;
pub mod shrink;

use crate::{MethodError, MethodOptions, VisibilityMethod};
use erode::Element;
use levels::{ErodedField, HeightField};
use occlusion::{Bins, PolarMap, Target};
use shrink::Region;
use sightline_geom::{Aabb2, DVec2, ViewCell};
use sightline_scene::Scene;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Default number of azimuth bins of the occlusion map.
pub const DEFAULT_BINS: u32 = 2048;

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
}

/// Prepare `name` (one of the four erosion methods) for `scene`.
pub fn create(
    name: &'static str,
    scene: Arc<Scene>,
    opts: &MethodOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    let variant = match name {
        "erosion" => Variant::Full,
        "erosion-segment" => Variant::Segment,
        "erosion-cell" => Variant::Cell,
        "shrink-sphere" => Variant::Sphere,
        n => return Err(MethodError::Unknown(n.to_string())),
    };
    Ok(Box::new(ErosionMethod::new(name, variant, scene, opts)?))
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
    field: HeightField,
    tops: Vec<Vec<Top>>,
    bins: usize,
    cache: Mutex<HashMap<(i64, i64, Element), Arc<ErodedField>>>,
}

/// One visibility test of an occludee piece.
struct Test {
    element: Element,
    target: Target,
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
        let field = HeightField::build(&scene);
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
            field,
            tops,
            bins: bins as usize,
            cache: Mutex::new(HashMap::new()),
        })
    }

    /// The erosion of the scene's occluders by `element` for cells of half size `half`.
    fn eroded(&self, element: Element, half: DVec2) -> Arc<ErodedField> {
        let key = (
            (half.x * 1e6).round() as i64,
            (half.y * 1e6).round() as i64,
            element,
        );
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        cache
            .entry(key)
            .or_insert_with(|| Arc::new(ErodedField::new(&self.field, element, half)))
            .clone()
    }

    /// The tests of one object (None: visible without testing).
    fn tests(&self, id: usize, cell: &ViewCell, ctx: &CellCtx) -> Option<Vec<Test>> {
        let obj = &self.scene.objects[id];
        if obj.bounds.intersects(&cell.aabb()) {
            return None;
        }
        let mut tests = Vec::new();
        for top in &self.tops[id] {
            match self.variant {
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
                                    Target::new(&ctx.bins, &[(vec![a - ctx.s, b - ctx.s], false)])
                                } else {
                                    ctx.target_ring(&piece.ring, el.midpoint(ctx.half))
                                };
                                Test {
                                    element: el,
                                    target,
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
                                        eye: ctx.z1,
                                        t: top.t,
                                    }
                                } else {
                                    Test {
                                        element: el,
                                        target: ctx.target_ring(&piece.ring, DVec2::ZERO),
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

    /// Build the occlusion map of `element`: eroded tiles front to back, skipping
    /// those that cannot add a useful blocker to any needed bin (hierarchical culling
    /// against the map, §5.1 / §7 "Scaling").
    fn render(&self, map: &mut PolarMap, element: Element, ctx: &CellCtx) {
        let eroded = self.eroded(element, ctx.half);
        let mut order: Vec<(f64, usize)> = (0..eroded.tiles.len())
            .map(|i| (rect_distance(eroded.piece_rect(i), ctx.s), i))
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (d, ti) in order {
            let h_max = eroded.h_max(&self.field, ti);
            if h_max <= ctx.z1 {
                continue;
            }
            if d > 0.0 {
                let bb = eroded.piece_rect(ti);
                let corners = [
                    bb.min - ctx.s,
                    DVec2::new(bb.max.x, bb.min.y) - ctx.s,
                    bb.max - ctx.s,
                    DVec2::new(bb.min.x, bb.max.y) - ctx.s,
                ];
                if !map.could_improve(&corners, d, h_max) {
                    continue;
                }
            }
            for level in eroded.tile(&self.field, ti) {
                if level.h <= ctx.z1 {
                    break;
                }
                let polys: Vec<Vec<Vec<DVec2>>> = level
                    .polys
                    .iter()
                    .map(|p| {
                        p.rings()
                            .map(|r| r.iter().map(|v| *v - ctx.s).collect())
                            .collect()
                    })
                    .collect();
                map.add_level(&polys, level.h);
            }
        }
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
}

impl CellCtx {
    /// A closed ring translated by `-shift`, relative to the eye.
    fn target_ring(&self, ring: &[DVec2], shift: DVec2) -> Target {
        let pts: Vec<DVec2> = ring.iter().map(|v| *v - shift - self.s).collect();
        Target::new(&self.bins, &[(pts, true)])
    }
}

/// Distance from `p` to the rectangle (0 inside).
fn rect_distance(r: Aabb2, p: DVec2) -> f64 {
    let dx = (r.min.x - p.x).max(p.x - r.max.x).max(0.0);
    let dy = (r.min.y - p.y).max(p.y - r.max.y).max(0.0);
    (dx * dx + dy * dy).sqrt()
}

impl VisibilityMethod for ErosionMethod {
    fn name(&self) -> &'static str {
        self.name
    }

    fn params(&self) -> Vec<(String, String)> {
        vec![
            ("bins".into(), self.bins.to_string()),
            ("height_step_m".into(), levels::HEIGHT_STEP_M.to_string()),
        ]
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        let a = cell.to_array();
        if a.iter().any(|v| !v.is_finite()) || !(a[0] < a[3] && a[1] < a[4] && a[2] <= a[5]) {
            return Err(MethodError::BadCell(cell.to_string()));
        }
        let rect = Aabb2::new(cell.min.truncate(), cell.max.truncate());
        let ctx = CellCtx {
            rect,
            half: rect.size() * 0.5,
            s: rect.center(),
            z1: cell.max.z,
            bins: Bins::new(self.bins),
            cell_meets_occluders: matches!(self.variant, Variant::Full | Variant::Segment)
                && self.field.meets_rect(rect),
        };
        let mut visible = Vec::new();
        let mut pending: Vec<(u32, Vec<Test>)> = Vec::new();
        for id in 0..self.scene.objects.len() {
            match self.tests(id, cell, &ctx) {
                None => visible.push(id as u32),
                Some(t) => pending.push((id as u32, t)),
            }
        }
        // One map per element, rasterized only in the bins some test needs.
        let mut maps: HashMap<Element, PolarMap> = HashMap::new();
        for (_, tests) in &pending {
            for t in tests {
                maps.entry(t.element)
                    .or_insert_with(|| PolarMap::new(ctx.bins.clone()))
                    .need(&t.target);
            }
        }
        let mut elements: Vec<Element> = maps.keys().copied().collect();
        elements.sort();
        for el in elements {
            if let Some(map) = maps.get_mut(&el) {
                self.render(map, el, &ctx);
            }
        }
        for (id, tests) in pending {
            let hidden = tests.iter().all(|t| {
                maps.get(&t.element)
                    .is_some_and(|m| m.hidden(&t.target, t.eye, t.t))
            });
            if !hidden {
                visible.push(id);
            }
        }
        visible.sort_unstable();
        Ok(visible)
    }
}
