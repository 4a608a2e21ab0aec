//! Reduction of a box-to-box visibility query to a planar problem (§4 of Koltun et al.
//! 2001) and its dual ray space (§5.1).
//!
//! Two boxes `A` (the viewcell) and `B` (a kd-node or an object's bound) are separated
//! along an axis: faces `F_A: x = xa` and `F_B: x = xb` (`xa < xb`, `x` the *along*
//! coordinate of the axis, `y` the across one; the box on the low side is called `lo`,
//! the other `hi`, whichever of `A`, `B` it is — visibility is symmetric).
//!
//! * **Observation 1** (upper rims): if a segment `s` from `A` to `B` misses every
//!   occluder, so does the vertical wall above it, because the occluders are 2.5D and
//!   stand on the ground.
//! * **Ceiling `T`**: any non-vertical plane above both boxes meets that wall in a
//!   segment `s'` that misses every occluder. We take the lowest plane through two
//!   parallel horizontal top edges (one per box) that supports both boxes from above:
//!   through the far edge of the lower box and the near edge of the higher one
//!   ([`Ceiling::new`]); with equal heights it is horizontal. `T` then depends on `x`
//!   only, so it cuts each occluder of height `h` along a line `x = x*(h)`.
//! * **Planar problem**: `s'` crosses `F_A` at `(xa, u)` and `F_B` at `(xb, w)` inside
//!   the shaft (the convex hull of the two rectangles, bounded by the planes `L`, `R`).
//!   So `A`, `B` are mutually visible only if some ray `(u, w)` of the *dual ray space*
//!   `RS = [u_lo, u_hi] × [w_lo, w_hi]` misses every occluder piece `{h > T}` between
//!   `F_A` and `F_B` and passes through both rectangles.
//!
//! For a convex piece `C` with vertices `p = (x_p, y_p)`, the ray `(u, w)` meets
//! the line through `p` iff `(1 - t_p) u + t_p w = y_p`, `t_p = (x_p - xa) / (xb - xa)`
//! — the segment `T(p)` of the paper. The ray misses `C` iff all vertices lie strictly
//! on one side, so for a fixed `w` the rays blocked by `C` are the interval
//! `u ∈ [H_C(w), G_C(w)]`, `H_C = min_p g_p`, `G_C = max_p g_p`,
//! `g_p(w) = (y_p - t_p w) / (1 - t_p)`. Every `g_p` is non-increasing in `w`, so the
//! rays blocked by `C` for *every* `w` of a band `[w0, w1]` are exactly
//! `u ∈ [H_C(w0), G_C(w1)]` ([`Planar::piece_band`]). This is what makes the union
//! coverage of `discrete` exact per row, without cracks.

use super::hidden::{Cover, HiddenSet};
use super::occluders::{local_rect, Axis, Decomposition, Rect, Slab, Trap};
use sightline_geom::{orient2d, Aabb3, DVec2, Orientation};
use sightline_scene::occluders::Stamps;

/// Kept pieces of the ceiling cut are shrunk by this much along `x` (metres): rounding
/// in `x*(h)` must never make an occluder larger than it is.
const CUT_MARGIN_M: f64 = 1e-8;

/// The ceiling plane `T`: height `z0 + slope * (x - x_anchor)`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Ceiling {
    pub x_anchor: f64,
    pub z0: f64,
    pub slope: f64,
    /// `1 / slope` (0 for a level plane): [`Ceiling::below`] runs for every trapezoid
    /// gathered, and a product rounds within a few ulps of the quotient, far under
    /// [`CUT_MARGIN_M`] anywhere in a scene.
    inv_slope: f64,
}

impl Ceiling {
    /// The plane through the far top edge of the lower box and the near top edge of
    /// the higher one (§4, Fig. 2): it supports both boxes from above and is the lowest
    /// such plane between them.
    pub(crate) fn new(lo: &Rect, lo_top: f64, hi: &Rect, hi_top: f64) -> Self {
        if lo_top < hi_top {
            // Rising towards `hi`: through lo's far edge (x0) and hi's near edge (x0).
            let slope = (hi_top - lo_top) / (hi.x0 - lo.x0);
            Ceiling {
                x_anchor: lo.x0,
                z0: lo_top,
                slope,
                inv_slope: 1.0 / slope,
            }
        } else if lo_top > hi_top {
            // Falling towards `hi`: through lo's near edge (x1) and hi's far edge (x1).
            let slope = (hi_top - lo_top) / (hi.x1 - lo.x1);
            Ceiling {
                x_anchor: lo.x1,
                z0: lo_top,
                slope,
                inv_slope: 1.0 / slope,
            }
        } else {
            Ceiling {
                x_anchor: lo.x1,
                z0: lo_top,
                slope: 0.0,
                inv_slope: 0.0,
            }
        }
    }

    #[inline]
    pub(crate) fn at(&self, x: f64) -> f64 {
        self.z0 + self.slope * (x - self.x_anchor)
    }

    /// The part `[k0, k1]` of `[x0, x1]` where `T < h`, shrunk by [`CUT_MARGIN_M`], or
    /// `None`.
    #[inline]
    fn below(&self, h: f64, x0: f64, x1: f64) -> Option<(f64, f64)> {
        let (k0, k1) = if self.slope == 0.0 {
            if h > self.z0 {
                (x0, x1)
            } else {
                return None;
            }
        } else {
            let xs = self.x_anchor + (h - self.z0) * self.inv_slope;
            if self.slope > 0.0 {
                (x0, x1.min(xs - CUT_MARGIN_M))
            } else {
                (x0.max(xs + CUT_MARGIN_M), x1)
            }
        };
        (k1 > k0).then_some((k0, k1))
    }
}

/// A convex occluder piece between `x0 < x1`: bottom line `yb0 → yb1`, top line
/// `yt0 → yt1` (`yb <= yt`), in the planar problem's coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Piece {
    pub x0: f64,
    pub x1: f64,
    pub yb0: f64,
    pub yb1: f64,
    pub yt0: f64,
    pub yt1: f64,
}

/// `g_p(w) = alpha - beta * w` for a vertex with `x_p < xb`; vertices on `F_B` are
/// flagged with `on_fb` (their `g` is ±∞ depending on `w`).
#[derive(Clone, Copy, Debug)]
struct Dual {
    alpha: f64,
    beta: f64,
    y: f64,
    on_fb: bool,
}

impl Dual {
    #[inline]
    fn new(x: f64, y: f64, len: f64) -> Self {
        // Local coordinates: xa = 0, xb = len.
        if x >= len {
            Dual {
                alpha: 0.0,
                beta: 0.0,
                y,
                on_fb: true,
            }
        } else {
            let d = len - x;
            Dual {
                alpha: y * len / d,
                beta: x / d,
                y,
                on_fb: false,
            }
        }
    }
    /// Contribution to `H` (a minimum) at `w`.
    #[inline]
    fn h_at(&self, w: f64) -> f64 {
        if self.on_fb {
            if self.y <= w {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            }
        } else {
            self.alpha - self.beta * w
        }
    }
    /// Contribution to `G` (a maximum) at `w`.
    #[inline]
    fn g_at(&self, w: f64) -> f64 {
        if self.on_fb {
            if self.y >= w {
                f64::INFINITY
            } else {
                f64::NEG_INFINITY
            }
        } else {
            self.alpha - self.beta * w
        }
    }
}

/// A piece prepared for the dual ray space: its two bottom and two top vertices.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DualPiece {
    b: [Dual; 2],
    t: [Dual; 2],
}

/// The planar problem of one shaft, in local coordinates: `xa = 0`, `xb = len`, `y`
/// relative to the shaft's centre line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Planar {
    pub len: f64,
    /// The two rectangles (`lo` ends at `x = 0`, `hi` starts at `x = len`).
    pub lo: Rect,
    pub hi: Rect,
    /// `RS`: rays cross `F_A` at `u ∈ [u_lo, u_hi]`, `F_B` at `w ∈ [w_lo, w_hi]`.
    pub u_lo: f64,
    pub u_hi: f64,
    pub w_lo: f64,
    pub w_hi: f64,
    pub pieces: Vec<Piece>,
    pub duals: Vec<DualPiece>,
    /// Per piece, the lines `g = alpha - beta·w` of its two bottom and two top vertices
    /// (`[ab0, bb0, ab1, bb1, at0, bt0, at1, bt1]`): the branch-free form of
    /// [`Planar::piece_band`]; NaN for the pieces with a vertex on `F_B`.
    pub lines: Vec<[f64; 8]>,
    /// Indices of the pieces with a vertex on `F_B`, answered by `piece_band`.
    pub on_fb: Vec<u32>,
    /// Coverage tolerance in `u` (metres): coverage must overlap by this much.
    pub eps: f64,
    /// The shaft in scene-local coordinates: faces at `xa < xb`, centre line `yc`,
    /// ceiling `T`, and the part `[ga, gb]` of `[xa, xb]` whose occluders were gathered.
    pub xa: f64,
    pub xb: f64,
    pub yc: f64,
    pub ceiling: Ceiling,
    pub ga: f64,
    pub gb: f64,
    /// A part `[e0, e1]` at the other end of `[xa, xb]` gathered too (empty: `e1 ≤ e0`).
    pub ends: (f64, f64),
    /// How many of `pieces` (the first ones) are hidden boxes.
    pub hidden_pieces: usize,
}

/// A band of the refinement of `discrete::hidden`: rows `[w0, w1]` at level `n`, the pieces
/// that can still matter (`lists[first..first + len]`, or all when `len == ALL`) and the
/// `full` row of the parent band.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Band {
    pub w0: f64,
    pub w1: f64,
    pub n: u32,
    pub first: u32,
    pub len: u32,
    pub seed: u128,
}

/// Per-query scratch memory, reused across tests of one cell.
#[derive(Default)]
pub(crate) struct Scratch {
    pub planar: Planar,
    /// Per slab, the last walk that cut it (shared by both axes' decompositions).
    pub slab_stamps: Stamps,
    pub cuts: Vec<f64>,
    pub kept: Vec<(f64, f64)>,
    pub intervals: Vec<(f64, f64)>,
    pub bands: Vec<(f64, f64, u32)>,
    /// Refinement of `discrete::hidden`: bands and their piece lists.
    pub refine: Vec<Band>,
    pub lists: Vec<u32>,
    /// Bands `[w0, w1]` of `RS` that `discrete::hidden` found covered on the shaft being
    /// built (ascending, disjoint): pieces are only added to a shaft, so they stay
    /// covered when it is extended. Cleared by [`Planar::build`].
    pub covered: Vec<(f64, f64)>,
    pub covered_next: Vec<(f64, f64)>,
    /// Pieces of the ungathered part of a shaft, met by a candidate ray.
    pub far: Vec<Piece>,
    /// Candidate rays `(gap width, u, w)`.
    pub candidates: Vec<(f64, f64, f64)>,
    /// Per hidden box, the last test that took it as a piece.
    pub hidden_stamps: Stamps,
    /// The pieces of the hidden boxes of the shaft being built.
    pub hidden_pieces: Vec<Piece>,
    /// A ray `(u, w)` in a gap of the finest band the last `discrete::hidden` left
    /// uncovered (a candidate witness, to be verified).
    pub gap_ray: Option<(f64, f64)>,
}

/// The boxes proven hidden from the cell ([`HiddenSet`]), occluders of a test along
/// `axis`.
#[derive(Clone, Copy)]
pub(crate) struct Hidden<'a> {
    pub set: Option<&'a HiddenSet>,
    pub axis: Axis,
}

impl Hidden<'_> {
    pub(crate) const NONE: Hidden<'static> = Hidden {
        set: None,
        axis: Axis::X,
    };

    fn cover(&self) -> Option<&Cover> {
        self.set.map(|s| s.cover(self.axis))
    }
}

/// A cell box `a` and a node box `b` in `axis`-local coordinates, the lower one along
/// the axis first: `lo.x1 < hi.x0`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Oriented {
    pub lo: Rect,
    pub lo_top: f64,
    pub hi: Rect,
    pub hi_top: f64,
    /// The cell is the lower box.
    pub cell_low: bool,
}

impl Oriented {
    /// Length of the shaft between the two faces.
    pub(crate) fn len(&self) -> f64 {
        self.hi.x0 - self.lo.x1
    }

    /// Whether `lo` is the narrower box across the axis.
    pub(crate) fn narrow_lo(&self) -> bool {
        self.lo.y1 - self.lo.y0 < self.hi.y1 - self.hi.y0
    }
}

/// The line of the rays from `u` on `F_A` (at `xa`) to `w` on `F_B` (at `xb`): its `y` at
/// `x`, in scene-local coordinates (`yc` the shaft's centre line), held at its ends
/// beyond `[xa, xb]`. With `u`, `w` the bounds of a hull of `RS`, the lower or upper
/// edge of the region its rays sweep.
fn shaft_line((xa, xb): (f64, f64), yc: f64, u: f64, w: f64) -> impl Fn(f64) -> f64 {
    let inv = 1.0 / (xb - xa);
    move |x| yc + u + (w - u) * ((x - xa) * inv).clamp(0.0, 1.0)
}

/// `a` and `b` ordered along `axis`, or `None` when they are not separated along it.
pub(crate) fn orient(a: &Aabb3, b: &Aabb3, axis: Axis) -> Option<Oriented> {
    let (ra, rb) = (local_rect(a, axis), local_rect(b, axis));
    let cell_low = ra.x1 < rb.x0;
    if !cell_low && rb.x1 >= ra.x0 {
        return None;
    }
    let (lo, lo_top, hi, hi_top) = if cell_low {
        (ra, a.max.z, rb, b.max.z)
    } else {
        (rb, b.max.z, ra, a.max.z)
    };
    Some(Oriented {
        lo,
        lo_top,
        hi,
        hi_top,
        cell_low,
    })
}

impl Planar {
    /// Set up the shaft between `lo` (tops at `lo_top`) and `hi` (`lo.x1 < hi.x0`) and
    /// gather the occluder pieces cut by the ceiling from `decomp`, ordered from the
    /// cell's side (`lo` when `cell_low`) outwards.
    pub(crate) fn build(
        scratch: &mut Scratch,
        decomp: &Decomposition,
        pair: &Oriented,
        near: Option<f64>,
        hidden: Hidden<'_>,
    ) {
        let Oriented {
            lo,
            lo_top,
            hi,
            hi_top,
            cell_low,
        } = *pair;
        let ceiling = Ceiling::new(&lo, lo_top, &hi, hi_top);
        let xa = lo.x1;
        let xb = hi.x0;
        // Occluders gathered only within `near.abs()` of one face (of `lo` when
        // positive, of `hi` when negative): a subset of the pieces, whose coverage
        // implies the full one's.
        let (ga, gb) = match near {
            Some(d) if d >= 0.0 => (xa, (xa + d).min(xb)),
            Some(d) => ((xb + d).max(xa), xb),
            None => (xa, xb),
        };
        let yc = 0.5 * (lo.y0.min(hi.y0) + lo.y1.max(hi.y1));
        let to_local = |r: &Rect| Rect {
            x0: r.x0 - xa,
            x1: r.x1 - xa,
            y0: r.y0 - yc,
            y1: r.y1 - yc,
        };
        scratch.covered.clear();
        let p = &mut scratch.planar;
        p.len = xb - xa;
        p.lo = to_local(&lo);
        p.hi = to_local(&hi);
        let (u_lo, u_hi, w_lo, w_hi) = hull_sections(&p.lo, &p.hi);
        p.u_lo = u_lo;
        p.u_hi = u_hi;
        p.w_lo = w_lo;
        p.w_hi = w_hi;
        p.eps = 1e-9 * (1.0 + (u_hi - u_lo).max(w_hi - w_lo).max(p.len));
        p.pieces.clear();
        p.duals.clear();
        p.lines.clear();
        p.on_fb.clear();
        p.xa = xa;
        p.xb = xb;
        p.yc = yc;
        p.ceiling = ceiling;
        p.ga = ga;
        p.gb = gb;
        p.ends = (0.0, 0.0);
        p.hidden_pieces = 0;

        let rays = [u_lo, u_hi, w_lo, w_hi];
        Planar::gather(scratch, decomp, (ga, gb), rays, hidden.cover());
        let p = &mut scratch.planar;
        let lower = shaft_line((xa, xb), yc, u_lo, w_lo);
        let upper = shaft_line((xa, xb), yc, u_hi, w_hi);
        // Nearest the cell first: the coverage rows of `discrete` fill up early.
        if !cell_low {
            p.pieces.reverse();
        }
        // The hidden boxes over the whole shaft come first: few and large, they fill the
        // coverage rows fastest.
        if let Some(set) = hidden.set {
            let cache = &mut scratch.hidden_pieces;
            cache.clear();
            let hgen = scratch.hidden_stamps.next(set.boxes.len());
            let stamps = &mut scratch.hidden_stamps.marks;
            set.cover(hidden.axis).visit(
                (xa, xb),
                |cx0, cx1| (lower(cx0).min(lower(cx1)), upper(cx0).max(upper(cx1))),
                |cx0, cx1| ceiling.at(cx0).min(ceiling.at(cx1)),
                |id| {
                    let st = &mut stamps[id as usize];
                    if *st == hgen {
                        return;
                    }
                    *st = hgen;
                    let h = &set.boxes[id as usize];
                    let r = local_rect(h, hidden.axis);
                    let (cx0, cx1) = (r.x0.max(xa), r.x1.min(xb));
                    if cx1 <= cx0 {
                        return;
                    }
                    let Some((k0, k1)) = ceiling.below(h.max.z, cx0, cx1) else {
                        return;
                    };
                    cache.push(Piece {
                        x0: k0 - xa,
                        x1: k1 - xa,
                        yb0: r.y0 - yc,
                        yb1: r.y0 - yc,
                        yt0: r.y1 - yc,
                        yt1: r.y1 - yc,
                    });
                },
            );
            let extra = cache.len();
            p.pieces.extend_from_slice(cache);
            p.pieces.rotate_right(extra);
            p.hidden_pieces = extra;
        }
        p.prepare_from(0);
    }

    /// Extend the last [`Planar::build`], a partial gathering of this shaft, to the
    /// part `to` of the shaft (as `near` of [`Planar::build`]; `None`: the whole shaft):
    /// only the slabs of the part not gathered yet are walked and cut (a slab reaching
    /// into both parts yields a piece in each, the same union), and the pieces already
    /// prepared are kept.
    ///
    /// With `rays`, a hull `[u0, u1] × [w0, w1]` of `RS` holding every ray the pieces
    /// gathered so far may leave free ([`super::discrete::free_hull`]), only the slabs
    /// meeting those rays are: the others block no ray that is not blocked already, so
    /// every row of `RS` is covered exactly when it is with all of them.
    pub(crate) fn extend(
        scratch: &mut Scratch,
        decomp: &Decomposition,
        hidden: Hidden<'_>,
        to: Option<f64>,
        rays: Option<[f64; 4]>,
    ) {
        let p = &scratch.planar;
        let (xa, xb) = (p.xa, p.xb);
        let (na, nb) = match to {
            Some(d) if d >= 0.0 => (xa, (xa + d).min(xb)),
            Some(d) => ((xb + d).max(xa), xb),
            None => (xa, xb),
        };
        let (ga, gb) = (p.ga, p.gb);
        let mut ranges = [(na, ga), (gb, nb)];
        // Less the other end's part, if gathered: it lies at `xa` or at `xb`.
        let (e0, e1) = p.ends;
        if e1 > e0 {
            for r in &mut ranges {
                if e0 <= r.0 {
                    r.0 = r.0.max(e1);
                }
                if e1 >= r.1 {
                    r.1 = r.1.min(e0);
                }
            }
        }
        Planar::gather_parts(scratch, decomp, hidden, &ranges, rays);
        let p = &mut scratch.planar;
        p.ga = ga.min(na);
        p.gb = gb.max(nb);
        if p.ga <= e0 && e1 <= p.gb {
            p.ends = (0.0, 0.0);
        }
    }

    /// Gather the part of length `len` at the other end of the shaft from `[ga, gb]`
    /// (`[ga, gb]` must hold one end), over `rays` as [`Planar::extend`].
    pub(crate) fn extend_other_end(
        scratch: &mut Scratch,
        decomp: &Decomposition,
        hidden: Hidden<'_>,
        len: f64,
        rays: Option<[f64; 4]>,
    ) {
        let p = &scratch.planar;
        let end = if p.ga > p.xa {
            (p.xa, (p.xa + len).min(p.ga))
        } else {
            ((p.xb - len).max(p.gb), p.xb)
        };
        Planar::gather_parts(scratch, decomp, hidden, &[end], rays);
        scratch.planar.ends = end;
    }

    /// Gather `ranges` (parts of the shaft not gathered yet, empty ones skipped) over
    /// `rays` (`None`: every ray of the shaft) and prepare their pieces.
    fn gather_parts(
        scratch: &mut Scratch,
        decomp: &Decomposition,
        hidden: Hidden<'_>,
        ranges: &[(f64, f64)],
        rays: Option<[f64; 4]>,
    ) {
        let p = &scratch.planar;
        let first = p.pieces.len();
        let rays = rays.unwrap_or([p.u_lo, p.u_hi, p.w_lo, p.w_hi]);
        for &range in ranges {
            if range.1 > range.0 {
                Planar::gather(scratch, decomp, range, rays, hidden.cover());
            }
        }
        scratch.planar.prepare_from(first);
    }

    /// Walk the grid columns over `[f0, f1]` (rows within the hull of the rays
    /// `[u0, u1] × [w0, w1]` of `RS`), cut the slabs met by the ceiling and clip them to
    /// `[f0, f1]`, dropping the pieces that miss those rays: the pieces are appended.
    fn gather(
        scratch: &mut Scratch,
        decomp: &Decomposition,
        (f0, f1): (f64, f64),
        [u_lo, u_hi, w_lo, w_hi]: [f64; 4],
        cover: Option<&Cover>,
    ) {
        let gen = scratch.slab_stamps.next(decomp.slabs.len());
        let p = &mut scratch.planar;
        let (xa, xb, yc, ceiling) = (p.xa, p.xb, p.yc, p.ceiling);
        let lower = shaft_line((xa, xb), yc, u_lo, w_lo);
        let upper = shaft_line((xa, xb), yc, u_hi, w_hi);
        walk_slabs(
            decomp,
            (&mut scratch.slab_stamps.marks, gen),
            (f0, f1),
            &ceiling,
            cover,
            |cx0, cx1| (lower(cx0).min(lower(cx1)), upper(cx0).max(upper(cx1))),
            |slab, traps| {
                cut_slab(
                    slab,
                    traps,
                    &ceiling,
                    (xa, f0, f1),
                    yc,
                    &lower,
                    &upper,
                    &mut scratch.cuts,
                    &mut scratch.kept,
                    &mut p.pieces,
                );
                true
            },
        );
    }

    /// The dual forms of the pieces from `first` on.
    fn prepare_from(&mut self, first: usize) {
        let len = self.len;
        self.duals
            .extend(self.pieces[first..].iter().map(|q| DualPiece {
                b: [Dual::new(q.x0, q.yb0, len), Dual::new(q.x1, q.yb1, len)],
                t: [Dual::new(q.x0, q.yt0, len), Dual::new(q.x1, q.yt1, len)],
            }));
        for (i, d) in self.duals.iter().enumerate().skip(first) {
            let [b0, b1] = d.b;
            let [t0, t1] = d.t;
            if b0.on_fb || b1.on_fb || t0.on_fb || t1.on_fb {
                self.on_fb.push(i as u32);
                self.lines.push([f64::NAN; 8]);
            } else {
                self.lines.push([
                    b0.alpha, b0.beta, b1.alpha, b1.beta, t0.alpha, t0.beta, t1.alpha, t1.beta,
                ]);
            }
        }
    }

    /// Whether the ray `(u, w)` misses every occluder piece of the part of the shaft
    /// outside `[ga, gb]` (the pieces `build` did not gather), decided exactly: the
    /// grid buckets along the ray's line are cut by the same ceiling and each piece met
    /// is tested with `orient2d`. Stops at the first piece that blocks the ray.
    pub(crate) fn far_ray_clear(
        scratch: &mut Scratch,
        decomp: &Decomposition,
        hidden: Hidden<'_>,
        u: f64,
        w: f64,
    ) -> bool {
        let gen = scratch.slab_stamps.next(decomp.slabs.len());
        let p = &scratch.planar;
        let (xa, xb, yc, len) = (p.xa, p.xb, p.yc, p.len);
        let (u_lo, u_hi, w_lo, w_hi) = (p.u_lo, p.u_hi, p.w_lo, p.w_hi);
        let lower = shaft_line((xa, xb), yc, u_lo, w_lo);
        let upper = shaft_line((xa, xb), yc, u_hi, w_hi);
        let ray_y = shaft_line((xa, xb), yc, u, w);
        let (a, b) = (DVec2::new(0.0, u), DVec2::new(len, w));
        // Rounding of the ray's height must not skip a bucket row.
        let margin = 1e-6 * (1.0 + yc.abs() + u.abs() + w.abs());
        for (f0, f1) in [(xa, p.ga), (p.gb, xb)] {
            if f1 <= f0 {
                continue;
            }
            let clear = walk_slabs(
                decomp,
                (&mut scratch.slab_stamps.marks, gen),
                (f0, f1),
                &p.ceiling,
                hidden.cover(),
                |cx0, cx1| {
                    let (y0, y1) = (ray_y(cx0), ray_y(cx1));
                    (y0.min(y1) - margin, y0.max(y1) + margin)
                },
                |slab, traps| {
                    scratch.far.clear();
                    cut_slab(
                        slab,
                        traps,
                        &p.ceiling,
                        (xa, f0, f1),
                        yc,
                        &lower,
                        &upper,
                        &mut scratch.cuts,
                        &mut scratch.kept,
                        &mut scratch.far,
                    );
                    scratch.far.iter().all(|q| ray_misses_piece(a, b, q))
                },
            );
            if !clear {
                return false;
            }
        }
        true
    }

    /// [`Planar::piece_band`] through the branch-free lines where they exist.
    #[inline]
    pub(crate) fn piece_band_fast(&self, i: usize, w0: f64, w1: f64) -> (f64, f64) {
        let l = &self.lines[i];
        if l[0].is_nan() {
            return self.piece_band(i, w0, w1);
        }
        let lo = (l[0] - l[1] * w0).min(l[2] - l[3] * w0);
        let hi = (l[4] - l[5] * w1).max(l[6] - l[7] * w1);
        (lo, hi)
    }

    /// The rays `u` blocked by piece `i` for every `w` of the band `[w0, w1]`:
    /// `[H(w0), G(w1)]` (possibly empty: `lo > hi`).
    #[inline]
    pub(crate) fn piece_band(&self, i: usize, w0: f64, w1: f64) -> (f64, f64) {
        let d = &self.duals[i];
        let lo = d.b[0].h_at(w0).min(d.b[1].h_at(w0));
        let hi = d.t[0].g_at(w1).max(d.t[1].g_at(w1));
        (lo, hi)
    }

    /// Push the rays that miss `lo` or `hi` for every `w` of the band (they are not
    /// rays between the boxes: §4's shaft contains only rays through both).
    pub(crate) fn mask_band(&self, w0: f64, w1: f64, out: &mut Vec<(f64, f64)>) {
        let inf = f64::INFINITY;
        // lo box: the ray at x = lo.x0 is u - (w - u) * ka.
        let ka = (0.0 - self.lo.x0) / self.len;
        let below = (self.lo.y0 + ka * w0) / (1.0 + ka);
        out.push((-inf, self.lo.y0.min(below)));
        let above = (self.lo.y1 + ka * w1) / (1.0 + ka);
        out.push((self.lo.y1.max(above), inf));
        // hi box: the ray at x = hi.x1 is w + (w - u) * kb.
        let kb = (self.hi.x1 - self.len) / self.len;
        if w0 > self.hi.y1 {
            if kb > 0.0 {
                out.push((-inf, (w0 * (1.0 + kb) - self.hi.y1) / kb));
            } else {
                out.push((-inf, inf));
            }
        }
        if w1 < self.hi.y0 {
            if kb > 0.0 {
                out.push(((w1 * (1.0 + kb) - self.hi.y0) / kb, inf));
            } else {
                out.push((-inf, inf));
            }
        }
    }
}

/// Whether the line `a b` leaves every vertex of the convex piece `q` strictly on one
/// side (exact predicates).
#[inline]
pub(crate) fn ray_misses_piece(a: DVec2, b: DVec2, q: &Piece) -> bool {
    let s = [
        orient2d(a, b, DVec2::new(q.x0, q.yb0)),
        orient2d(a, b, DVec2::new(q.x1, q.yb1)),
        orient2d(a, b, DVec2::new(q.x0, q.yt0)),
        orient2d(a, b, DVec2::new(q.x1, q.yt1)),
    ];
    s.iter().all(|o| *o == Orientation::Left) || s.iter().all(|o| *o == Orientation::Right)
}

/// The shaft's cross-sections at `x = 0` (`u`) and `x = len` (`w`): the convex hull of
/// the two rectangles, bounded by the supporting planes `L` and `R`.
fn hull_sections(lo: &Rect, hi: &Rect) -> (f64, f64, f64, f64) {
    let len = hi.x0 - lo.x1;
    // Upper boundary.
    let (u_hi, w_hi) = if lo.y1 >= hi.y1 {
        // From lo's near top corner to hi's far top corner.
        let s = (hi.y1 - lo.y1) / (hi.x1 - lo.x1);
        (lo.y1, lo.y1 + s * len)
    } else {
        let s = (hi.y1 - lo.y1) / (hi.x0 - lo.x0);
        (lo.y1 + s * (lo.x1 - lo.x0), hi.y1)
    };
    let (u_lo, w_lo) = if lo.y0 <= hi.y0 {
        let s = (hi.y0 - lo.y0) / (hi.x1 - lo.x1);
        (lo.y0, lo.y0 + s * len)
    } else {
        let s = (hi.y0 - lo.y0) / (hi.x0 - lo.x0);
        (lo.y0 + s * (lo.x1 - lo.x0), hi.y0)
    };
    (u_lo, u_hi, w_lo, w_hi)
}

/// Cut one slab by the ceiling, clip it to the shaft and fuse its touching trapezoids
/// into convex pieces.
/// Visit once (per `gen` of `stamp`) each slab of `decomp` listed in the buckets of the
/// grid columns over `[f0, f1]` whose rows meet `rows(cx0, cx1)` (a `y` range over the
/// column's part `[cx0, cx1]`), until `visit` returns `false` (then `false`). A bucket
/// whose tallest slab stays under `ceiling` over the column is skipped: a slab of it
/// yields no piece there, and one reaching into other columns is visited there. So is a
/// bucket under the top of a hidden box of `cover` containing it: the box's own piece
/// blocks every ray its slabs would (`super::hidden`).
fn walk_slabs(
    decomp: &Decomposition,
    (stamp, gen): (&mut [u32], u32),
    (f0, f1): (f64, f64),
    ceiling: &Ceiling,
    cover: Option<&Cover>,
    rows: impl Fn(f64, f64) -> (f64, f64),
    mut visit: impl FnMut(&Slab, &[Trap]) -> bool,
) -> bool {
    let g = &decomp.grid;
    for c in g.col(f0)..=g.col(f1) {
        let cx0 = (g.origin.x + c as f64 * g.cell_m).max(f0);
        let cx1 = (g.origin.x + (c + 1) as f64 * g.cell_m).min(f1);
        let (ylo, yhi) = rows(cx0, cx1);
        let floor = ceiling.at(cx0).min(ceiling.at(cx1));
        for r in g.row(ylo)..=g.row(yhi) {
            let top = decomp.bucket_top[r * g.nx + c];
            if top <= floor || cover.is_some_and(|cv| top <= cv.top_of_bucket(c, r)) {
                continue;
            }
            for &id in g.bucket(c, r) {
                let st = &mut stamp[id as usize];
                if *st == gen {
                    continue;
                }
                *st = gen;
                let slab = &decomp.slabs[id as usize];
                let traps = &decomp.traps[slab.first as usize..(slab.first + slab.len) as usize];
                if !visit(slab, traps) {
                    return false;
                }
            }
        }
    }
    true
}

#[allow(clippy::too_many_arguments)]
fn cut_slab(
    slab: &Slab,
    traps: &[Trap],
    ceiling: &Ceiling,
    (xa, ga, gb): (f64, f64, f64),
    yc: f64,
    lower: &impl Fn(f64) -> f64,
    upper: &impl Fn(f64) -> f64,
    cuts: &mut Vec<f64>,
    kept: &mut Vec<(f64, f64)>,
    out: &mut Vec<Piece>,
) {
    let cx0 = slab.x0.max(ga);
    let cx1 = slab.x1.min(gb);
    if cx1 <= cx0 {
        return;
    }
    if slab.h_max <= ceiling.at(cx0).min(ceiling.at(cx1)) {
        return;
    }
    let lo_line = lower(cx0).min(lower(cx1));
    let hi_line = upper(cx0).max(upper(cx1));
    if slab.y_max < lo_line || slab.y_min > hi_line {
        return;
    }
    cuts.clear();
    kept.clear();
    cuts.push(cx0);
    cuts.push(cx1);
    for t in traps {
        match ceiling.below(t.h, cx0, cx1) {
            Some((k0, k1)) => {
                kept.push((k0, k1));
                if k0 > cx0 {
                    cuts.push(k0);
                }
                if k1 < cx1 {
                    cuts.push(k1);
                }
            }
            None => kept.push((f64::INFINITY, f64::NEG_INFINITY)),
        }
    }
    if cuts.len() > 2 {
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
    }
    // Both pieces on either side of a cut interpolate the same line at the same `x`:
    // bit-identical ends, whatever the rounding.
    let inv_span = 1.0 / (slab.x1 - slab.x0);
    let at = |line: &[f64; 2], x: f64| -> f64 {
        if x <= slab.x0 {
            line[0]
        } else if x >= slab.x1 {
            line[1]
        } else {
            line[0] + (line[1] - line[0]) * ((x - slab.x0) * inv_span)
        }
    };
    for w in cuts.windows(2) {
        let (c, d) = (w[0], w[1]);
        if d <= c {
            continue;
        }
        let mut i = 0;
        while i < traps.len() {
            let (k0, k1) = kept[i];
            if !(k0 <= c && k1 >= d) {
                i += 1;
                continue;
            }
            let first = i;
            let mut last = i;
            while last + 1 < traps.len()
                && traps[last + 1].touches_prev
                && kept[last + 1].0 <= c
                && kept[last + 1].1 >= d
            {
                last += 1;
            }
            i = last + 1;
            let (b, t) = (&traps[first].bot, &traps[last].top);
            let piece = Piece {
                x0: c - xa,
                x1: d - xa,
                yb0: at(b, c) - yc,
                yb1: at(b, d) - yc,
                yt0: at(t, c) - yc,
                yt1: at(t, d) - yc,
            };
            // Entirely outside the shaft: no ray of RS meets it.
            if piece.yb0 + yc > upper(c) && piece.yb1 + yc > upper(d) {
                continue;
            }
            if piece.yt0 + yc < lower(c) && piece.yt1 + yc < lower(d) {
                continue;
            }
            out.push(piece);
        }
    }
}

/// The `n` equal bands of `[w_lo, w_hi]`, last band first (the refinement stacks pop the
/// first band first); the last one ends exactly at `w_hi`.
pub(crate) fn bands_rev(w_lo: f64, w_hi: f64, n: usize) -> impl Iterator<Item = (f64, f64)> {
    let dw = (w_hi - w_lo) / n as f64;
    (0..n).rev().map(move |k| {
        let w0 = w_lo + dw * k as f64;
        let w1 = if k + 1 == n {
            w_hi
        } else {
            w_lo + dw * (k + 1) as f64
        };
        (w0, w1)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceiling_supports_both_boxes() {
        let lo = Rect {
            x0: 0.0,
            x1: 10.0,
            y0: 0.0,
            y1: 10.0,
        };
        let hi = Rect {
            x0: 30.0,
            x1: 40.0,
            y0: 0.0,
            y1: 10.0,
        };
        for (zl, zh) in [(2.0, 20.0), (20.0, 2.0), (5.0, 5.0), (2.0, 0.0)] {
            let c = Ceiling::new(&lo, zl, &hi, zh);
            for x in [0.0, 5.0, 10.0] {
                assert!(c.at(x) >= zl - 1e-12, "{zl} {zh} at {x}");
            }
            for x in [30.0, 35.0, 40.0] {
                assert!(c.at(x) >= zh - 1e-12, "{zl} {zh} at {x}");
            }
        }
        // Rising: through lo's far edge and hi's near edge.
        let c = Ceiling::new(&lo, 2.0, &hi, 20.0);
        assert!((c.at(0.0) - 2.0).abs() < 1e-12 && (c.at(30.0) - 20.0).abs() < 1e-12);
    }

    #[test]
    fn hull_sections_contain_both_faces() {
        let lo = Rect {
            x0: -10.0,
            x1: 0.0,
            y0: 0.0,
            y1: 10.0,
        };
        let hi = Rect {
            x0: 20.0,
            x1: 30.0,
            y0: 50.0,
            y1: 60.0,
        };
        let (u_lo, u_hi, w_lo, w_hi) = hull_sections(&lo, &hi);
        assert_eq!(u_lo, 0.0);
        assert!(u_hi > 10.0); // the hull bulges above lo's face towards hi
        assert!(w_lo < 50.0);
        assert_eq!(w_hi, 60.0);
    }
}
