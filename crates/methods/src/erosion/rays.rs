//! The X-sampling ray test of §7.1 (Theorem 2), method `erosion-rays`.
//!
//! An *X-sampling* of an occludee `O` is a set of points `I` with `O ⊂ I ⊕ X`. With
//! `X` the cell footprint relative to its centre `S` (the cell is `S ⊕ X`), a finite
//! set `I` is a valid shrunk occludee `R` for Theorem 1, so `O` is hidden from the
//! cell as soon as every *ray* `[S, I_j]` is blocked by the eroded occluders
//! `O_k ⊖ X`: the from-region query becomes a finite number of point-to-point ones.
//!
//! Why it holds (the paper's Theorem 1 argument, for points): a sight line `[v, o]`
//! with `v = S + x` and `o = I_j + y` (`x, y ∈ X`) is, at parameter `λ`, the point of
//! `[S, I_j]` moved by `(1 − λ)x + λy`, which lies in `X` (convex) — horizontally, at
//! the same height. If `[S, I_j]` passes inside `O_k ⊖ X` at `λ`, that point of
//! `[v, o]` is inside `O_k`. The occludee itself may be among the `O_k`: a visible
//! occludee is seen along some line that reaches its top face from outside it (see
//! `mod.rs` for why only the cell's top face and the occludees' top faces matter), and
//! that line meets no occluder's interior, so not every sample ray can be blocked.
//!
//! **Sampling condition.** `X` is the rectangle `[−a, a] × [−b, b]`: a point `I` covers
//! a piece of `O` iff the piece's bounding box `B` fits in `I + X`, i.e. `I` lies in the
//! rectangle `[B.max.x − a, B.min.x + a] × [B.max.y − b, B.min.y + b]`, non-empty when
//! `B` is at most `2a × 2b`. The top face is cut into tiles of at most `2a × 2b` (a
//! hair less, so that rounding never leaves a gap) and each non-empty piece gets the
//! point of that rectangle farthest from `S` — the farther along its ray a sample is,
//! the more occluders can block it (any point of the rectangle is valid). A piece with
//! zero area lies on a tile line, whose points belong (closed) to the neighbouring
//! pieces as well: it is dropped, as in [`super::shrink::pieces`].
//!
//! The rays are tested on the polar occlusion map of `Element::Cell` (shared with
//! `erosion-cell`): each sample is a one-point target whose bin and nearest distance
//! are those of the ray, so a ray counts as blocked only by sectors of the eroded
//! raster that stand high enough over its whole wedge (the inner rule, farthest depth)
//! — conservative at any number of bins. The hierarchy of `mod.rs` (the cell, then its
//! quarters) applies unchanged: a sub-cell is a smaller `X`, hence denser samples and
//! less erosion.
//!
//! **Compared with its siblings.** The points shrink the occludee, so `erosion-rays` is
//! never looser than `erosion-cell`, which erodes by the same element. Against
//! `erosion` (segment erosion, shrunk occludees) it depends on the occluders: an erosion
//! by the whole cell empties rows of buildings thinner than the cell that an erosion by
//! one side keeps, which the deeper quarters make up for: `erosion-rays` refines to
//! [`super::RAYS_MAX_DEPTH`] levels (sub-cells down to [`super::RAYS_MIN_SUBCELL_M`]),
//! its samples denser with every level. The measurements behind these choices are in
//! `docs/methods/erosion.md`.
//!

use super::shrink::clip_ring;
use sightline_geom::polygon::ring_signed_area;
use sightline_geom::{Aabb2, DVec2};

/// At most this many tiles per top face; beyond, the occludee is kept (visible).
pub const MAX_SAMPLES: usize = 1 << 14;
/// Tiles are this fraction of `2a × 2b` at most, so rounding never opens a gap.
const TILE_SHRINK: f64 = 1.0 - 1e-9;

/// An X-sampling of the top face `ring` for the cell footprint of half sizes `half`
/// centred on `eye` (absolute coordinates): points `I_j` with `ring ⊂ ∪ (I_j + X)`.
///
/// `None` when no finite sampling is produced: a degenerate ring (zero area, or not
/// finite), a degenerate cell, or more than [`MAX_SAMPLES`] tiles. The caller keeps
/// the occludee then.
pub fn x_sampling(ring: &[DVec2], half: DVec2, eye: DVec2) -> Option<Vec<DVec2>> {
    if ring.len() < 3 || !(half.x > 0.0 && half.y > 0.0) || !half.is_finite() {
        return None;
    }
    if ring.iter().any(|p| !p.is_finite()) || !(ring_signed_area(ring).abs() > 0.0) {
        return None;
    }
    let bb = Aabb2::from_points(ring);
    let size = bb.size();
    let tile = 2.0 * half * TILE_SHRINK;
    let nx = (size.x / tile.x).ceil().max(1.0);
    let ny = (size.y / tile.y).ceil().max(1.0);
    if nx * ny > MAX_SAMPLES as f64 {
        return None;
    }
    let (nx, ny) = (nx as usize, ny as usize);
    let step = DVec2::new(size.x / nx as f64, size.y / ny as f64);
    let inf = f64::INFINITY;
    let mut out = Vec::new();
    for j in 0..ny {
        let (y0, y1) = band(j, ny, bb.min.y, step.y);
        let row = clip_ring(ring, DVec2::new(-inf, y0), DVec2::new(inf, y1));
        if row.len() < 3 || ring_signed_area(&row).abs() <= 1e-12 {
            continue;
        }
        for i in 0..nx {
            let (x0, x1) = band(i, nx, bb.min.x, step.x);
            let piece = clip_ring(&row, DVec2::new(x0, -inf), DVec2::new(x1, inf));
            if piece.len() < 3 || ring_signed_area(&piece).abs() <= 1e-12 {
                continue;
            }
            out.push(farthest_cover(Aabb2::from_points(&piece), half, eye)?);
        }
    }
    if out.is_empty() {
        None
    } else {
        Some(out)
    }
}

/// The point `I` farthest from `eye` with `b ⊂ I + [−a, a] × [−b, b]` (None if `b`
/// does not fit, which the tiling rules out).
fn farthest_cover(b: Aabb2, half: DVec2, eye: DVec2) -> Option<DVec2> {
    let lo = b.max - half;
    let hi = b.min + half;
    if !(lo.x <= hi.x && lo.y <= hi.y) {
        return None;
    }
    let pick = |lo: f64, hi: f64, e: f64| {
        if (lo - e).abs() > (hi - e).abs() {
            lo
        } else {
            hi
        }
    };
    Some(DVec2::new(pick(lo.x, hi.x, eye.x), pick(lo.y, hi.y, eye.y)))
}

/// Bounds of band `k` of `n` bands of `step` from `min`; the outer bands are open-ended
/// so a ring's extreme points fall in a band whatever the rounding of `min + k·step`.
fn band(k: usize, n: usize, min: f64, step: f64) -> (f64, f64) {
    let lo = if k == 0 {
        f64::NEG_INFINITY
    } else {
        min + step * k as f64
    };
    let hi = if k + 1 == n {
        f64::INFINITY
    } else {
        min + step * (k + 1) as f64
    };
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(pts: &[(f64, f64)]) -> Vec<DVec2> {
        pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect()
    }

    /// Every probe point of the ring's region lies in `I_j + X` for some sample.
    fn covers(r: &[DVec2], half: DVec2, samples: &[DVec2]) -> bool {
        let bb = Aabb2::from_points(r);
        let poly = sightline_geom::Polygon::new(r.to_vec(), vec![]);
        let n = 60;
        for i in 0..=n {
            for j in 0..=n {
                let p = bb.min + bb.size() * DVec2::new(i as f64 / n as f64, j as f64 / n as f64);
                let on_boundary = r.iter().zip(r.iter().cycle().skip(1)).any(|(&a, &b)| {
                    let e = b - a;
                    let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
                    (a + e * t - p).length() < 1e-12
                });
                if !(poly.contains(p) || on_boundary) {
                    continue;
                }
                let ok = samples.iter().any(|s| {
                    let d = (p - *s).abs();
                    d.x <= half.x + 1e-9 && d.y <= half.y + 1e-9
                });
                if !ok {
                    return false;
                }
            }
        }
        true
    }

    #[test]
    fn samples_cover_an_l_shaped_block() {
        let r = ring(&[
            (10.0, 0.0),
            (40.0, 0.0),
            (40.0, 8.0),
            (18.0, 8.0),
            (18.0, 30.0),
            (10.0, 30.0),
        ]);
        for half in [
            DVec2::new(5.0, 5.0),
            DVec2::new(1.3, 2.7),
            DVec2::new(20.0, 20.0),
        ] {
            let s = x_sampling(&r, half, DVec2::ZERO).expect("sampling");
            assert!(covers(&r, half, &s), "half {half:?}: {s:?}");
        }
    }

    #[test]
    fn a_small_block_is_one_sample_pushed_away_from_the_eye() {
        // A 4 × 2 block seen from the origin with a 10 × 10 cell: one sample, at the
        // corner of the covering rectangle [24 − 5, 20 + 5] × [5 − 5, 3 + 5] farthest
        // from the eye.
        let r = ring(&[(20.0, 3.0), (24.0, 3.0), (24.0, 5.0), (20.0, 5.0)]);
        let s = x_sampling(&r, DVec2::splat(5.0), DVec2::ZERO).expect("sampling");
        assert_eq!(s, vec![DVec2::new(25.0, 8.0)]);
        assert!(covers(&r, DVec2::splat(5.0), &s));
    }

    #[test]
    fn degenerate_inputs_give_no_sampling() {
        let flat = ring(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]);
        assert!(x_sampling(&flat, DVec2::splat(5.0), DVec2::ZERO).is_none());
        let sq = ring(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        assert!(x_sampling(&sq, DVec2::ZERO, DVec2::ZERO).is_none());
        let huge = ring(&[(0.0, 0.0), (1e5, 0.0), (1e5, 1e5), (0.0, 1e5)]);
        assert!(x_sampling(&huge, DVec2::splat(1.0), DVec2::ZERO).is_none());
    }
}
