//! Scan conversion of convex screen polygons under the three coverage rules, with
//! conservative per-pixel depth.
//!
//! A convex polygon is cut into horizontal *bands* (pixel rows `[j, j+1]`). Its
//! *chord* at height `y` is the exact x-interval `[left(y), right(y)]` it covers on that
//! line, computed from the edges in a canonical orientation (lower endpoint first), so
//! two pieces sharing an edge get bitwise the same x there (watertight).
//!
//! * **Standard**: pixel centres inside the closed polygon (dilated by [`EPS_PX`] so
//!   that T-junctions leave no crack).
//! * **Outer** (over-estimating): every pixel whose closed square meets the polygon:
//!   the x-range of the polygon over the band is spanned by its chords at the band's
//!   ends and its vertices inside the band.
//! * **Inner** (under-estimating): pixels whose whole square lies in the polygon. For
//!   a convex polygon `left(y)` is convex and `right(y)` concave, so over a band they
//!   reach their worst values at the band's ends: the fully covered x-set of a band is
//!   `chord(j) ∩ chord(j+1)`.
//! * **Inner union** of several pieces (shrinking each piece separately
//!   opens cracks along every shared edge): a band is cut at every vertex height of
//!   the pieces; on each sub-band every piece either spans it or not, the piece
//!   covers the vertical segments `{x} × [a, b]` for `x ∈ chord(a) ∩ chord(b)`; these
//!   intervals are merged over the pieces and the merged sets are intersected over the
//!   sub-bands. A pixel is covered when its x-extent lies in the result: every vertical
//!   segment of it then lies in some piece. Pieces sharing a vertical screen edge fuse
//!   exactly; along a shared *slanted* edge (e.g. a diagonal of a triangulated cap)
//!   the pixels the edge crosses are lost (still conservative) — pass walls as quads.
//!
//! Depth is `1/w`, with `w` affine on the polygon's plane. Over a pixel, `w` spans
//! `w(centre) ± (|∂w/∂x| + |∂w/∂y|)/2`; the part of the polygon inside the pixel also
//! lies within the polygon's vertex range `[w_min, w_max]`. Hence the farthest depth
//! of an occluder in a pixel is at most `1 / max(w_min, w(c) - h)` and the nearest of an
//! occludee at least `1 / min(w_max, w(c) + h)`; both are rounded outward to `f32`.

use crate::view::ScreenVertex;
use crate::MAX_VERTS;

/// Tolerance in pixels: standard coverage is dilated by it, inner coverage shrunk by
/// it, outer coverage grown by it. Intervals of a union closer than this are merged
/// (shared edges computed in different pieces differ by rounding only).
pub const EPS_PX: f64 = 1e-9;

#[derive(Clone, Copy, Debug, Default)]
struct Edge {
    /// Lower endpoint.
    px: f64,
    py: f64,
    /// Upper endpoint.
    qx: f64,
    qy: f64,
    /// dx/dy (unused for horizontal edges).
    dxdy: f64,
}

/// A convex screen polygon prepared for scan conversion.
#[derive(Clone, Debug)]
pub(crate) struct Prepared {
    edges: [Edge; MAX_VERTS],
    n: usize,
    ys: [f64; MAX_VERTS],
    pub ymin: f64,
    pub ymax: f64,
    pub xmin: f64,
    pub xmax: f64,
    wmin: f64,
    wmax: f64,
    /// `w = a x + b y + c`, if the polygon has area.
    plane: Option<(f64, f64, f64)>,
}

#[inline]
fn f32_up(v: f64) -> f32 {
    let f = v as f32;
    if (f as f64) < v {
        f.next_up()
    } else {
        f
    }
}

/// [`f32_up`] for `v > 0` (depths), branch-free: the next `f32` is one step of the
/// bit pattern (`+∞` stays).
#[inline(always)]
fn f32_up_pos(v: f64) -> f32 {
    let f = v as f32;
    f32::from_bits(f.to_bits() + ((f as f64) < v) as u32)
}

/// [`f32_down`] for `v > 0`, branch-free (`f > v ≥ 0` implies `f > 0`, so the step
/// down stays positive).
#[inline(always)]
fn f32_down_pos(v: f64) -> f32 {
    let f = v as f32;
    f32::from_bits(f.to_bits() - ((f as f64) > v) as u32)
}

#[inline]
fn f32_down(v: f64) -> f32 {
    let f = v as f32;
    if (f as f64) > v {
        f.next_down()
    } else {
        f
    }
}

impl Prepared {
    /// Prepare a convex polygon (either orientation, at most [`MAX_VERTS`] vertices).
    pub fn new(v: &[ScreenVertex]) -> Option<Prepared> {
        let n = v.len().min(MAX_VERTS);
        if n < 3 {
            return None;
        }
        let mut p = Prepared {
            edges: [Edge::default(); MAX_VERTS],
            n,
            ys: [0.0; MAX_VERTS],
            ymin: f64::INFINITY,
            ymax: f64::NEG_INFINITY,
            xmin: f64::INFINITY,
            xmax: f64::NEG_INFINITY,
            wmin: f64::INFINITY,
            wmax: f64::NEG_INFINITY,
            plane: None,
        };
        for k in 0..n {
            let a = v[k];
            let b = v[(k + 1) % n];
            if !(a.x.is_finite() && a.y.is_finite() && a.w.is_finite()) {
                return None;
            }
            let (lo, hi) = if (a.y, a.x) <= (b.y, b.x) {
                (a, b)
            } else {
                (b, a)
            };
            let dy = hi.y - lo.y;
            p.edges[k] = Edge {
                px: lo.x,
                py: lo.y,
                qx: hi.x,
                qy: hi.y,
                dxdy: if dy > 0.0 { (hi.x - lo.x) / dy } else { 0.0 },
            };
            p.ys[k] = a.y;
            p.ymin = p.ymin.min(a.y);
            p.ymax = p.ymax.max(a.y);
            p.xmin = p.xmin.min(a.x);
            p.xmax = p.xmax.max(a.x);
            p.wmin = p.wmin.min(a.w);
            p.wmax = p.wmax.max(a.w);
        }
        // Plane of w through the vertex triple of largest area.
        let o = v[0];
        let mut best = (0.0f64, 1usize);
        for k in 1..n - 1 {
            let d =
                ((v[k].x - o.x) * (v[k + 1].y - o.y) - (v[k + 1].x - o.x) * (v[k].y - o.y)).abs();
            if d > best.0 {
                best = (d, k);
            }
        }
        let scale = (p.xmax - p.xmin).max(p.ymax - p.ymin).max(1e-300);
        if best.0 > 1e-12 * scale * scale {
            let (a, b) = (v[best.1], v[best.1 + 1]);
            let (x1, y1, w1) = (a.x - o.x, a.y - o.y, a.w - o.w);
            let (x2, y2, w2) = (b.x - o.x, b.y - o.y, b.w - o.w);
            let det = x1 * y2 - x2 * y1;
            let ga = (w1 * y2 - w2 * y1) / det;
            let gb = (x1 * w2 - x2 * w1) / det;
            p.plane = Some((ga, gb, o.w - ga * o.x - gb * o.y));
        }
        Some(p)
    }

    /// The exact chord `[left, right]` at height `y`, if the line meets the polygon.
    #[inline]
    pub fn chord(&self, y: f64) -> Option<(f64, f64)> {
        let mut l = f64::INFINITY;
        let mut r = f64::NEG_INFINITY;
        for e in &self.edges[..self.n] {
            if e.py <= y && y <= e.qy {
                if e.qy == e.py {
                    l = l.min(e.px.min(e.qx));
                    r = r.max(e.px.max(e.qx));
                } else {
                    let x = if y == e.py {
                        e.px
                    } else if y == e.qy {
                        e.qx
                    } else {
                        e.px + (y - e.py) * e.dxdy
                    };
                    l = l.min(x);
                    r = r.max(x);
                }
            }
        }
        (l <= r).then_some((l, r))
    }

    /// The x-range of the polygon over `[a, b]` (a sub-range of its y-extent).
    #[inline]
    fn span(&self, a: f64, b: f64) -> Option<(f64, f64)> {
        let a = a.max(self.ymin);
        let b = b.min(self.ymax);
        if a > b {
            return None;
        }
        let (mut l, mut r) = self.chord(a)?;
        if let Some((l2, r2)) = self.chord(b) {
            l = l.min(l2);
            r = r.max(r2);
        }
        for k in 0..self.n {
            let e = &self.edges[k];
            if a < e.py && e.py < b {
                l = l.min(e.px);
                r = r.max(e.px);
            }
        }
        Some((l, r))
    }

    /// Vertical segments `{x} × [a, b]` inside the polygon, as an x-interval.
    #[inline]
    fn inner_chord(&self, a: f64, b: f64) -> Option<(f64, f64)> {
        if self.ymin > a || self.ymax < b {
            return None;
        }
        let (l1, r1) = self.chord(a)?;
        let (l2, r2) = self.chord(b)?;
        let (l, r) = (l1.max(l2), r1.min(r2));
        (l <= r).then_some((l, r))
    }

    /// Nearest depth over the whole polygon.
    pub fn min_depth(&self) -> f32 {
        f32_down(1.0 / self.wmax * (1.0 - 1e-12))
    }

    /// Depths of the pixels `(i0 + k, j)`, `k < out.len()`, of one row, into `out`.
    ///
    /// `w` at a pixel centre is `a x + b y + c` evaluated as `(a x + b y) + c`, with `b y`
    /// computed once per row and `x = (i0 + 0.5) + k` (exact), so every value is bitwise
    /// the one of the direct per-pixel formula. The loops are branch-free (they
    /// vectorize).
    /// * [`Depth::Centre`]: the depth at the centre (clamped to the vertex range).
    /// * [`Depth::Far`]: an upper bound of the polygon's depth in the pixel.
    /// * [`Depth::Near`]: a lower bound of it.
    #[inline]
    pub fn row_depths(&self, kind: Depth, j: u32, i0: u32, out: &mut [f32]) {
        let (wmin, wmax) = (self.wmin, self.wmax);
        match self.plane {
            Some((a, b, c)) => {
                let by = b * (j as f64 + 0.5);
                let h = 0.5 * (a.abs() + b.abs());
                let x0 = i0 as f64 + 0.5;
                match kind {
                    Depth::Centre => {
                        for (k, o) in out.iter_mut().enumerate() {
                            let x = x0 + k as u32 as f64;
                            let w = (a * x + by + c).max(wmin).min(wmax);
                            *o = (1.0 / w) as f32;
                        }
                    }
                    Depth::Far => {
                        for (k, o) in out.iter_mut().enumerate() {
                            let x = x0 + k as u32 as f64;
                            let w = (a * x + by + c - h).max(wmin);
                            *o = f32_up_pos(1.0 / w * (1.0 + 1e-12));
                        }
                    }
                    Depth::Near => {
                        for (k, o) in out.iter_mut().enumerate() {
                            let x = x0 + k as u32 as f64;
                            let w = (a * x + by + c + h).min(wmax);
                            *o = f32_down_pos(1.0 / w * (1.0 - 1e-12));
                        }
                    }
                }
            }
            None => out.fill(match kind {
                Depth::Centre => (1.0 / wmax) as f32,
                Depth::Far => f32_up(1.0 / wmin * (1.0 + 1e-12)),
                Depth::Near => f32_down(1.0 / wmax * (1.0 - 1e-12)),
            }),
        }
    }

    /// Rows `j0..=j1` of the screen the polygon may touch (empty if `j0 > j1`).
    #[inline]
    fn rows(&self, height: u32) -> (i64, i64) {
        let j0 = floor_i(self.ymin - EPS_PX).max(0);
        let j1 = floor_i(self.ymax + EPS_PX).min(height as i64 - 1);
        (j0, j1)
    }

    /// Whether the polygon lies entirely off the screen.
    #[inline]
    pub fn off_screen(&self, width: u32, height: u32) -> bool {
        self.xmax < 0.0 || self.ymax < 0.0 || self.xmin > width as f64 || self.ymin > height as f64
    }
}

/// `v.floor() as i64` without a libm call (the x86-64 baseline has no `roundsd`):
/// exact for every `f64`, saturating like `as`.
#[inline(always)]
pub(crate) fn floor_i(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `v.ceil() as i64`, see [`floor_i`].
#[inline(always)]
pub(crate) fn ceil_i(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) < v {
        t.saturating_add(1)
    } else {
        t
    }
}

/// Chunk of pixels whose depths are computed at once (stack buffer).
pub(crate) const CHUNK: usize = 64;

/// Call `f(k, depth)` for the `n` pixels `(i0 + k, j)` in chunks of [`CHUNK`].
#[inline]
pub(crate) fn for_row_depths(
    p: &Prepared,
    kind: Depth,
    j: u32,
    i0: u32,
    n: usize,
    mut f: impl FnMut(usize, f32),
) {
    let mut buf = [0f32; CHUNK];
    let mut s = 0usize;
    while s < n {
        let m = (n - s).min(CHUNK);
        p.row_depths(kind, j, i0 + s as u32, &mut buf[..m]);
        for (k, &z) in buf[..m].iter().enumerate() {
            f(s + k, z);
        }
        s += m;
    }
}

/// Which depth a rule writes (see `Prepared::row_depths`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Depth {
    Centre,
    Far,
    Near,
}

#[inline]
fn clamp_cols(l: i64, r: i64, width: u32) -> (u32, u32, bool) {
    let l = l.max(0);
    let r = r.min(width as i64 - 1);
    (l as u32, r.max(0) as u32, l <= r)
}

/// Standard rule: pixels whose centre lies in the (closed, dilated) polygon, as spans
/// `f(j, i0, i1)` (inclusive); their depth is [`Depth::Centre`].
pub(crate) fn standard(p: &Prepared, width: u32, height: u32, mut f: impl FnMut(u32, u32, u32)) {
    let j0 = ceil_i(p.ymin - EPS_PX - 0.5).max(0);
    let j1 = floor_i(p.ymax + EPS_PX - 0.5).min(height as i64 - 1);
    for j in j0..=j1 {
        let yc = (j as f64 + 0.5).clamp(p.ymin, p.ymax);
        let Some((l, r)) = p.chord(yc) else { continue };
        let (i0, i1, ok) = clamp_cols(ceil_i(l - EPS_PX - 0.5), floor_i(r + EPS_PX - 0.5), width);
        if ok {
            f(j as u32, i0, i1);
        }
    }
}

/// A chord at height `y`, reusing the previous row's when `y` is the same (rows share
/// their boundary line): bitwise the value of [`Prepared::chord`].
struct ChordCache {
    y: f64,
    c: Option<(f64, f64)>,
}

impl ChordCache {
    fn new() -> Self {
        ChordCache {
            y: f64::NAN,
            c: None,
        }
    }

    #[inline]
    fn get(&mut self, p: &Prepared, y: f64) -> Option<(f64, f64)> {
        if y != self.y {
            self.y = y;
            self.c = p.chord(y);
        }
        self.c
    }
}

/// Outer rule: every pixel whose closed square meets the polygon, as spans
/// `f(j, i0, i1)`; their depth is [`Depth::Near`]. Stops (and returns true) as soon as
/// `f` returns true.
pub(crate) fn outer(
    p: &Prepared,
    width: u32,
    height: u32,
    mut f: impl FnMut(u32, u32, u32) -> bool,
) -> bool {
    let (j0, j1) = p.rows(height);
    let (mut lo, mut hi) = (ChordCache::new(), ChordCache::new());
    for j in j0..=j1 {
        // The x-range over the band [j, j+1] (see `Prepared::span`), chords shared with
        // the neighbouring rows.
        let a = (j as f64).max(p.ymin);
        let b = (j as f64 + 1.0).min(p.ymax);
        if a > b {
            continue;
        }
        std::mem::swap(&mut lo, &mut hi);
        let Some((mut l, mut r)) = lo.get(p, a) else {
            continue;
        };
        if let Some((l2, r2)) = hi.get(p, b) {
            l = l.min(l2);
            r = r.max(r2);
        }
        for e in &p.edges[..p.n] {
            if a < e.py && e.py < b {
                l = l.min(e.px);
                r = r.max(e.px);
            }
        }
        let (i0, i1, ok) = clamp_cols(floor_i(l - EPS_PX), floor_i(r + EPS_PX), width);
        if ok && f(j as u32, i0, i1) {
            return true;
        }
    }
    false
}

/// Pixels `[l, r]` whose whole x-extent lies in the interval `(lo, hi)` shrunk by EPS.
#[inline]
fn inner_cols(lo: f64, hi: f64, width: u32) -> Option<(u32, u32)> {
    let (i0, i1, ok) = clamp_cols(ceil_i(lo + EPS_PX), floor_i(hi - EPS_PX) - 1, width);
    ok.then_some((i0, i1))
}

/// Inner rule for one convex polygon: pixels entirely inside, as spans `f(j, i0, i1)`;
/// their depth is [`Depth::Far`].
pub(crate) fn inner(p: &Prepared, width: u32, height: u32, mut f: impl FnMut(u32, u32, u32)) {
    let (j0, j1) = p.rows(height);
    let (mut lo, mut hi) = (ChordCache::new(), ChordCache::new());
    for j in j0..=j1 {
        let (a, b) = (j as f64, j as f64 + 1.0);
        if p.ymin > a || p.ymax < b {
            continue;
        }
        std::mem::swap(&mut lo, &mut hi);
        let (Some((l1, r1)), Some((l2, r2))) = (lo.get(p, a), hi.get(p, b)) else {
            continue;
        };
        let (l, r) = (l1.max(l2), r1.min(r2));
        if l > r {
            continue;
        }
        if let Some((i0, i1)) = inner_cols(l, r, width) {
            f(j as u32, i0, i1);
        }
    }
}

/// Merge intervals sorted by their left end, fusing those closer than EPS.
fn merge(iv: &mut Vec<(f64, f64)>) {
    iv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = 0usize;
    for k in 0..iv.len() {
        if out > 0 && iv[k].0 <= iv[out - 1].1 + EPS_PX {
            iv[out - 1].1 = iv[out - 1].1.max(iv[k].1);
        } else {
            iv[out] = iv[k];
            out += 1;
        }
    }
    iv.truncate(out);
}

/// Intersection of two sorted lists of disjoint intervals.
fn intersect(a: &[(f64, f64)], b: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
    out.clear();
    let (mut i, mut k) = (0, 0);
    while i < a.len() && k < b.len() {
        let l = a[i].0.max(b[k].0);
        let r = a[i].1.min(b[k].1);
        if l <= r {
            out.push((l, r));
        }
        if a[i].1 < b[k].1 {
            i += 1;
        } else {
            k += 1;
        }
    }
}

/// Reusable buffers of [`inner_union`] (no allocation per draw once warm).
#[derive(Clone, Debug, Default)]
pub(crate) struct UnionScratch {
    order: Vec<usize>,
    active: Vec<usize>,
    events: Vec<f64>,
    ivs: Vec<(f64, f64)>,
    acc: Vec<(f64, f64)>,
    tmp: Vec<(f64, f64)>,
    far: Vec<f32>,
}

/// Inner rule for the union of convex pieces (see the module doc), as spans
/// `f(j, i0, depths)` where `depths[k]` is an upper bound of the union's depth in pixel
/// `(i0 + k, j)`.
pub(crate) fn inner_union(
    pieces: &[Prepared],
    width: u32,
    height: u32,
    sc: &mut UnionScratch,
    mut f: impl FnMut(u32, u32, &[f32]),
) {
    if pieces.is_empty() {
        return;
    }
    if pieces.len() == 1 {
        let p = &pieces[0];
        let far = &mut sc.far;
        return inner(p, width, height, |j, i0, i1| {
            let n = (i1 - i0 + 1) as usize;
            far.clear();
            far.resize(n, 0.0);
            p.row_depths(Depth::Far, j, i0, far);
            f(j, i0, far);
        });
    }
    let UnionScratch {
        order,
        active,
        events,
        ivs,
        acc,
        tmp,
        far,
    } = sc;
    order.clear();
    order.extend(0..pieces.len());
    order.sort_by(|&a, &b| pieces[a].ymin.total_cmp(&pieces[b].ymin));
    let ymin = pieces.iter().map(|p| p.ymin).fold(f64::INFINITY, f64::min);
    let ymax = pieces
        .iter()
        .map(|p| p.ymax)
        .fold(f64::NEG_INFINITY, f64::max);
    let j0 = floor_i(ymin).max(0);
    let j1 = (ceil_i(ymax) - 1).min(height as i64 - 1);
    active.clear();
    let mut next = 0usize;
    far.clear();
    far.resize(width as usize, f32::NEG_INFINITY);
    for j in j0..=j1 {
        let (a, b) = (j as f64, j as f64 + 1.0);
        while next < order.len() && pieces[order[next]].ymin < b {
            active.push(order[next]);
            next += 1;
        }
        active.retain(|&k| pieces[k].ymax > a);
        if active.is_empty() {
            continue;
        }
        events.clear();
        events.push(a);
        events.push(b);
        for &k in active.iter() {
            let p = &pieces[k];
            events.extend(p.ys[..p.n].iter().copied().filter(|&y| a < y && y < b));
        }
        events.sort_by(f64::total_cmp);
        events.dedup();
        let mut first = true;
        acc.clear();
        for s in events.windows(2) {
            ivs.clear();
            ivs.extend(
                active
                    .iter()
                    .filter_map(|&k| pieces[k].inner_chord(s[0], s[1])),
            );
            merge(ivs);
            if first {
                std::mem::swap(acc, ivs);
                first = false;
            } else {
                intersect(acc, ivs, tmp);
                std::mem::swap(acc, tmp);
            }
            if acc.is_empty() {
                break;
            }
        }
        if acc.is_empty() {
            continue;
        }
        // Upper bound of the depth: the farthest depth of any piece touching the pixel.
        let mut touched = (u32::MAX, 0u32);
        for &k in active.iter() {
            let p = &pieces[k];
            if let Some((l, r)) = p.span(a, b) {
                let (i0, i1, ok) = clamp_cols(floor_i(l - EPS_PX), floor_i(r + EPS_PX), width);
                if ok {
                    touched = (touched.0.min(i0), touched.1.max(i1));
                    let row = &mut far[i0 as usize..=i1 as usize];
                    for_row_depths(p, Depth::Far, j as u32, i0, row.len(), |k, d| {
                        row[k] = row[k].max(d);
                    });
                }
            }
        }
        for &(l, r) in acc.iter() {
            if let Some((i0, i1)) = inner_cols(l, r, width) {
                f(j as u32, i0, &far[i0 as usize..=i1 as usize]);
            }
        }
        if touched.0 <= touched.1 {
            far[touched.0 as usize..=touched.1 as usize].fill(f32::NEG_INFINITY);
        }
    }
}
