//! Validation and repair of footprints.
//!
//! Every repair is a counted [`Warning`] with a stable `kind`:
//!
//! | kind | what was wrong | repair |
//! |---|---|---|
//! | `ring-not-closed` | first ≠ last position (GeoJSON requires closed rings) | closed |
//! | `duplicate-points` | consecutive equal positions | removed |
//! | `wrong-orientation` | exterior clockwise or hole counter-clockwise | reversed |
//! | `degenerate-ring` | fewer than 3 distinct positions | ring dropped |
//! | `zero-area` | a ring of (near) zero area (< 10⁻⁶ m²) | ring dropped |
//! | `tiny-ring` | a ring smaller than 1 cm² | ring dropped |
//! | `self-intersection` | crossing or overlapping edges, holes crossing the exterior or each other | boolean union (exterior) minus union (holes) |
//! | `hole-outside` | a hole not inside its exterior | hole dropped |
//!
//! What cannot be repaired (non-finite or absurd coordinates, nothing left after repair)
//! is an error naming the feature.

use crate::Warning;
use sightline_geom::polygon::ring_signed_area;
use sightline_geom::{boolean, orient2d, DVec2, Orientation, Polygon};

/// Largest accepted absolute coordinate, in metres (after projection): 10⁸ m is beyond
/// any projected CRS (UTM northings stay below 10⁷), and keeps the 1 mm boolean grid exact.
pub const MAX_COORD_M: f64 = 1e8;
/// Rings with less area than this are zero-area.
pub const ZERO_AREA_M2: f64 = 1e-6;
/// Rings with less area than this are dropped as tiny.
pub const TINY_AREA_M2: f64 = 1e-2;

/// Collects counted warnings for one input, and decides what a feature that cannot be
/// used does to the whole input.
///
/// Real data always holds a few broken features (an OSM part whose `min_height` is above
/// its `height`, a way cut at the extract's border). By default such a feature is
/// *skipped* with a counted `skipped-feature` warning naming it, and the rest of the city
/// loads; in strict mode ([`super::ImportOptions::strict`]) its error aborts the import.
/// When nothing usable is left, the first rejection is the error.
#[derive(Debug, Default)]
pub struct Diagnostics {
    pub warnings: Vec<Warning>,
    strict: bool,
    skipped: usize,
    first_rejection: Option<(usize, String)>,
}

impl Diagnostics {
    /// Diagnostics that abort on the first unusable feature when `strict`.
    pub fn new(strict: bool) -> Self {
        Diagnostics {
            strict,
            ..Diagnostics::default()
        }
    }

    /// Skip an unusable feature (a counted `skipped-feature` warning), or, in strict mode
    /// or for an error that is not about one feature, return the error.
    pub fn skip(&mut self, err: super::ImportError) -> Result<(), super::ImportError> {
        let super::ImportError::Feature { index, message } = err else {
            return Err(err);
        };
        if self.strict {
            return Err(super::ImportError::Feature { index, message });
        }
        self.skipped += 1;
        self.warn(
            "skipped-feature",
            Some(index),
            format!("skipped: {message}"),
        );
        self.first_rejection.get_or_insert((index, message));
        Ok(())
    }

    /// Features skipped so far.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// The error of an input with nothing usable left: the first rejected feature's
    /// error when some were rejected, else `empty` (a [`super::ImportError::Format`]).
    pub fn nothing_left(&self, empty: impl Into<String>) -> super::ImportError {
        match &self.first_rejection {
            Some((index, message)) => super::ImportError::Feature {
                index: *index,
                message: format!(
                    "{message} (nothing left to load: {} feature(s) rejected)",
                    self.skipped
                ),
            },
            None => super::ImportError::Format(empty.into()),
        }
    }

    pub fn warn(&mut self, kind: &str, feature: Option<usize>, message: impl Into<String>) {
        self.warnings.push(Warning {
            kind: kind.to_string(),
            feature,
            message: message.into(),
        });
    }
}

/// Check that a coordinate is finite and not absurd.
pub fn check_coord(v: f64) -> Result<f64, String> {
    if !v.is_finite() {
        return Err(format!("non-finite coordinate {v}"));
    }
    if v.abs() > MAX_COORD_M {
        return Err(format!(
            "coordinate {v} out of range (|c| > {MAX_COORD_M:e} m)"
        ));
    }
    Ok(v)
}

/// Clean one ring: closing position removed, consecutive duplicates removed. Returns
/// `None` (with a warning) when fewer than 3 distinct positions remain.
fn clean_ring(
    mut ring: Vec<DVec2>,
    closed_input: bool,
    feature: usize,
    what: &str,
    diag: &mut Diagnostics,
) -> Option<Vec<DVec2>> {
    if closed_input {
        if ring.len() >= 2 && ring.first() == ring.last() {
            ring.pop();
        } else if !ring.is_empty() {
            diag.warn(
                "ring-not-closed",
                Some(feature),
                format!("{what}: ring not closed; closed it"),
            );
        }
    }
    let before = ring.len();
    ring.dedup();
    while ring.len() > 1 && ring.first() == ring.last() {
        ring.pop();
    }
    if ring.len() != before {
        diag.warn(
            "duplicate-points",
            Some(feature),
            format!(
                "{what}: {} duplicate position(s) removed",
                before - ring.len()
            ),
        );
    }
    if ring.len() < 3 {
        diag.warn(
            "degenerate-ring",
            Some(feature),
            format!(
                "{what}: ring with {} distinct position(s) dropped",
                ring.len()
            ),
        );
        return None;
    }
    Some(ring)
}

/// Whether segments `ab` and `cd` cross or overlap in a way that makes a polygon
/// invalid: a proper crossing, or collinear overlap of positive length. Touching at a
/// single point (a vertex on another edge) is allowed, as in OGC simple features.
fn segments_conflict(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o1 = orient2d(a, b, c);
    let o2 = orient2d(a, b, d);
    let o3 = orient2d(c, d, a);
    let o4 = orient2d(c, d, b);
    use Orientation::*;
    let opposite = |x: Orientation, y: Orientation| matches!((x, y), (Left, Right) | (Right, Left));
    if opposite(o1, o2) && opposite(o3, o4) {
        return true;
    }
    if o1 == Collinear && o2 == Collinear {
        // Collinear: overlap of positive length along the common line?
        let dir = b - a;
        let t = |p: DVec2| (p - a).dot(dir);
        let (t0, t1) = (0.0, dir.dot(dir));
        let (u0, u1) = {
            let (x, y) = (t(c), t(d));
            (x.min(y), x.max(y))
        };
        return u0.max(t0) < u1.min(t1);
    }
    false
}

/// Whether the rings (exterior first) have conflicting edges: within a ring between
/// non-adjacent edges, or between different rings. Sweep over x-sorted edge boxes.
fn has_conflicts(rings: &[Vec<DVec2>]) -> bool {
    struct E {
        a: DVec2,
        b: DVec2,
        ring: usize,
        idx: usize,
        minx: f64,
        maxx: f64,
    }
    let mut edges: Vec<E> = Vec::new();
    for (ri, r) in rings.iter().enumerate() {
        let n = r.len();
        for i in 0..n {
            let (a, b) = (r[i], r[(i + 1) % n]);
            edges.push(E {
                a,
                b,
                ring: ri,
                idx: i,
                minx: a.x.min(b.x),
                maxx: a.x.max(b.x),
            });
        }
    }
    edges.sort_by(|p, q| p.minx.total_cmp(&q.minx));
    for i in 0..edges.len() {
        let e = &edges[i];
        let (eminy, emaxy) = (e.a.y.min(e.b.y), e.a.y.max(e.b.y));
        for f in &edges[i + 1..] {
            if f.minx > e.maxx {
                break;
            }
            if f.a.y.max(f.b.y) < eminy || f.a.y.min(f.b.y) > emaxy {
                continue;
            }
            if e.ring == f.ring {
                let n = rings[e.ring].len();
                let adjacent = (e.idx + 1) % n == f.idx || (f.idx + 1) % n == e.idx;
                if adjacent {
                    // Adjacent edges conflict only by folding back onto each other.
                    let (shared, p, q) = if (e.idx + 1) % n == f.idx {
                        (e.b, e.a, f.b)
                    } else {
                        (e.a, e.b, f.a)
                    };
                    if orient2d(p, shared, q) == Orientation::Collinear
                        && (p - shared).dot(q - shared) > 0.0
                    {
                        return true;
                    }
                    continue;
                }
            }
            if segments_conflict(e.a, e.b, f.a, f.b) {
                return true;
            }
        }
    }
    false
}

/// Validate and repair one polygon given as rings (exterior first). `closed_input`:
/// the format closes rings explicitly (GeoJSON), so a missing closing position is a
/// repair. Returns the repaired polygons (a self-intersecting one may become several;
/// an empty result means every ring was dropped with a warning).
pub fn polygon(
    rings: Vec<Vec<DVec2>>,
    closed_input: bool,
    feature: usize,
    diag: &mut Diagnostics,
) -> Result<Vec<Polygon>, String> {
    for r in &rings {
        for p in r {
            check_coord(p.x)?;
            check_coord(p.y)?;
        }
    }
    let mut rings = rings.into_iter();
    let Some(ext) = rings.next() else {
        return Err("polygon without rings".into());
    };
    let Some(ext) = clean_ring(ext, closed_input, feature, "exterior", diag) else {
        return Ok(vec![]);
    };
    let mut all = vec![ext];
    for (k, h) in rings.enumerate() {
        if let Some(h) = clean_ring(h, closed_input, feature, &format!("hole {k}"), diag) {
            all.push(h);
        }
    }
    // Crossing rings first: their shoelace areas and orientations mean nothing.
    if has_conflicts(&all) {
        return Ok(repair_by_union(all, feature, diag));
    }
    let mut it = all.into_iter();
    let mut ext = it.next().unwrap_or_default();
    let ext_area = ring_signed_area(&ext);
    if !keep_area(ext_area, feature, "exterior", diag) {
        return Ok(vec![]);
    }
    let mut reoriented = false;
    if ext_area < 0.0 {
        ext.reverse();
        reoriented = true;
    }
    let probe = Polygon::new(ext.clone(), vec![]);
    let mut holes = Vec::new();
    for (k, mut h) in it.enumerate() {
        let what = format!("hole {k}");
        let a = ring_signed_area(&h);
        if !keep_area(a, feature, &what, diag) {
            continue;
        }
        // No crossings: the hole is inside iff some vertex is strictly inside.
        if !h.iter().any(|p| probe.contains(*p)) {
            diag.warn(
                "hole-outside",
                Some(feature),
                format!("{what}: outside its exterior, dropped"),
            );
            continue;
        }
        if a > 0.0 {
            h.reverse();
            reoriented = true;
        }
        holes.push(h);
    }
    if reoriented {
        diag.warn(
            "wrong-orientation",
            Some(feature),
            "ring orientation reversed (exterior counter-clockwise, holes clockwise)",
        );
    }
    Ok(vec![Polygon::new(ext, holes)])
}

/// Repair crossing rings: the non-zero union of the exterior minus the union of the
/// holes (i_overlay on the 1 mm grid), keeping parts of at least [`TINY_AREA_M2`].
fn repair_by_union(all: Vec<Vec<DVec2>>, feature: usize, diag: &mut Diagnostics) -> Vec<Polygon> {
    let mut it = all.into_iter();
    let ext = it.next().unwrap_or_default();
    let holes: Vec<Polygon> = it.map(|h| Polygon::new(h, vec![]).normalized()).collect();
    let outer = boolean::union(&[Polygon::new(ext, vec![]).normalized()]);
    let repaired = if holes.is_empty() {
        outer
    } else {
        boolean::difference(&outer, &boolean::union(&holes))
    };
    let repaired: Vec<Polygon> = repaired
        .into_iter()
        .filter(|p| p.area() >= TINY_AREA_M2)
        .collect();
    if repaired.is_empty() {
        diag.warn(
            "zero-area",
            Some(feature),
            "self-intersecting polygon encloses no area, dropped",
        );
    } else {
        diag.warn(
            "self-intersection",
            Some(feature),
            format!(
                "self-intersecting polygon repaired by a boolean union into {} part(s)",
                repaired.len()
            ),
        );
    }
    repaired
}

fn keep_area(a: f64, feature: usize, what: &str, diag: &mut Diagnostics) -> bool {
    if a.abs() < ZERO_AREA_M2 {
        diag.warn(
            "zero-area",
            Some(feature),
            format!("{what}: zero-area ring dropped"),
        );
        false
    } else if a.abs() < TINY_AREA_M2 {
        diag.warn(
            "tiny-ring",
            Some(feature),
            format!("{what}: ring of {:.2e} m² dropped", a.abs()),
        );
        false
    } else {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(p: &[(f64, f64)]) -> Vec<DVec2> {
        p.iter().map(|&(x, y)| DVec2::new(x, y)).collect()
    }

    fn kinds(d: &Diagnostics) -> Vec<&str> {
        d.warnings.iter().map(|w| w.kind.as_str()).collect()
    }

    #[test]
    fn valid_square_passes_untouched() {
        let mut d = Diagnostics::default();
        let sq = v(&[(0., 0.), (4., 0.), (4., 4.), (0., 4.), (0., 0.)]);
        let out = polygon(vec![sq], true, 0, &mut d).unwrap();
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].exterior.len(), 4);
        assert!(d.warnings.is_empty());
    }

    #[test]
    fn unclosed_duplicate_and_clockwise_are_repaired() {
        let mut d = Diagnostics::default();
        let r = v(&[(0., 0.), (0., 4.), (0., 4.), (4., 4.), (4., 0.)]);
        let out = polygon(vec![r], true, 3, &mut d).unwrap();
        assert_eq!(out[0].exterior.len(), 4);
        assert_eq!(out[0].area(), 16.0);
        assert!(ring_signed_area(&out[0].exterior) > 0.0);
        assert_eq!(
            kinds(&d),
            ["ring-not-closed", "duplicate-points", "wrong-orientation"]
        );
        assert!(d.warnings.iter().all(|w| w.feature == Some(3)));
    }

    #[test]
    fn bowtie_becomes_two_triangles() {
        let mut d = Diagnostics::default();
        let r = v(&[(0., 0.), (4., 4.), (4., 0.), (0., 4.), (0., 0.)]);
        let out = polygon(vec![r], true, 0, &mut d).unwrap();
        assert_eq!(out.len(), 2);
        let area: f64 = out.iter().map(Polygon::area).sum();
        assert!((area - 8.0).abs() < 1e-3);
        assert!(kinds(&d).contains(&"self-intersection"));
    }

    #[test]
    fn hole_crossing_exterior_is_cut_out() {
        let mut d = Diagnostics::default();
        let ext = v(&[(0., 0.), (10., 0.), (10., 10.), (0., 10.), (0., 0.)]);
        let hole = v(&[(8., 4.), (12., 4.), (12., 6.), (8., 6.), (8., 4.)]);
        let out = polygon(vec![ext, hole], true, 0, &mut d).unwrap();
        let area: f64 = out.iter().map(Polygon::area).sum();
        assert!((area - 96.0).abs() < 1e-3, "{area}");
        assert!(kinds(&d).contains(&"self-intersection"));
    }

    #[test]
    fn touching_hole_is_valid() {
        let mut d = Diagnostics::default();
        let ext = v(&[(0., 0.), (10., 0.), (10., 10.), (0., 10.), (0., 0.)]);
        let hole = v(&[(0., 5.), (3., 4.), (3., 6.), (0., 5.)]);
        let out = polygon(vec![ext, hole], true, 0, &mut d).unwrap();
        assert_eq!(out[0].holes.len(), 1);
        assert!(!kinds(&d).contains(&"self-intersection"), "{:?}", kinds(&d));
    }

    #[test]
    fn spike_is_a_conflict() {
        let mut d = Diagnostics::default();
        let r = v(&[(0., 0.), (4., 0.), (4., 4.), (6., 4.), (4., 4.), (0., 4.)]);
        let out = polygon(vec![r], false, 0, &mut d).unwrap();
        assert!((out[0].area() - 16.0).abs() < 1e-3);
        assert!(kinds(&d).contains(&"self-intersection"));
    }

    #[test]
    fn degenerate_and_zero_area_are_dropped() {
        let mut d = Diagnostics::default();
        let line = v(&[(0., 0.), (4., 0.), (8., 0.), (0., 0.)]);
        assert!(polygon(vec![line], true, 0, &mut d).unwrap().is_empty());
        let two = v(&[(0., 0.), (4., 0.), (0., 0.)]);
        assert!(polygon(vec![two], true, 0, &mut d).unwrap().is_empty());
        assert_eq!(kinds(&d), ["zero-area", "degenerate-ring"]);
        // A ring folding back on itself encloses nothing either.
        let fold = v(&[(0., 0.), (4., 0.), (4., 4.), (4., 0.), (0., 0.)]);
        assert!(polygon(vec![fold], true, 0, &mut d).unwrap().is_empty());
    }

    #[test]
    fn non_finite_and_absurd_are_errors() {
        let mut d = Diagnostics::default();
        let r = v(&[(0., 0.), (f64::NAN, 0.), (4., 4.), (0., 0.)]);
        assert!(polygon(vec![r], true, 0, &mut d).is_err());
        let r = v(&[(0., 0.), (1e300, 0.), (4., 4.), (0., 0.)]);
        let e = polygon(vec![r], true, 0, &mut d).unwrap_err();
        assert!(e.contains("out of range"), "{e}");
    }
}
