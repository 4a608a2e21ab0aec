//! Depth and object-id buffers, and the draw calls.

use crate::coverage::{self, Depth, Prepared, UnionScratch};
use crate::pyramid::{occluded_test, DepthPyramid};
use crate::view::{fan, ScreenVertex, View};
use crate::{Coverage, MAX_INPUT_VERTS};
use glam::DVec3;

/// The id of a pixel nothing was drawn on.
pub const NO_ID: u32 = u32::MAX;

/// A depth buffer (view depth in metres, `+∞` where empty) and an object-id buffer
/// ([`NO_ID`] where empty), row-major, row 0 at the view window's lower edge.
///
/// The depth test keeps the strictly nearer value: with [`Coverage::Inner`] a pixel
/// receives an upper bound of the occluder's depth in it, with [`Coverage::Outer`] a
/// lower bound, with [`Coverage::Standard`] the depth at the pixel centre.
#[derive(Clone, Debug)]
pub struct Framebuffer {
    pub width: u32,
    pub height: u32,
    pub depth: Vec<f32>,
    pub ids: Vec<u32>,
    scratch: Vec<ScreenVertex>,
    pieces: Vec<Prepared>,
    union: UnionScratch,
    /// Depths of one span (a row at most).
    zrow: Vec<f32>,
}

impl Framebuffer {
    /// An empty buffer of `width × height` pixels.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Framebuffer {
            width,
            height,
            depth: vec![f32::INFINITY; n],
            ids: vec![NO_ID; n],
            scratch: Vec::with_capacity(2 * MAX_INPUT_VERTS),
            pieces: Vec::new(),
            union: UnionScratch::default(),
            zrow: vec![0.0; width as usize],
        }
    }

    /// An empty buffer matching `view`'s pixel grid.
    pub fn for_view(view: &View) -> Self {
        Self::new(view.width_px, view.height_px)
    }

    /// Empty every pixel.
    pub fn clear(&mut self) {
        self.depth.fill(f32::INFINITY);
        self.ids.fill(NO_ID);
    }

    #[inline]
    fn index(&self, i: u32, j: u32) -> usize {
        j as usize * self.width as usize + i as usize
    }

    /// Depth at pixel `(i, j)`.
    pub fn depth_at(&self, i: u32, j: u32) -> f32 {
        self.depth[self.index(i, j)]
    }

    /// Object id at pixel `(i, j)`.
    pub fn id_at(&self, i: u32, j: u32) -> u32 {
        self.ids[self.index(i, j)]
    }

    /// The distinct ids drawn, sorted.
    pub fn ids_seen(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.ids.iter().copied().filter(|&i| i != NO_ID).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Draw a planar convex world polygon (a triangle, a wall quad, …) seen in `view`,
    /// clipped at the near plane. Polygons with many vertices are split into fans.
    pub fn draw_polygon(&mut self, view: &View, poly: &[DVec3], id: u32, coverage: Coverage) {
        if poly.len() > MAX_INPUT_VERTS {
            for chunk in fan(poly) {
                self.draw_polygon(view, &chunk, id, coverage);
            }
            return;
        }
        let mut scratch = std::mem::take(&mut self.scratch);
        if view.clip_project(poly, &mut scratch) >= 3 {
            self.draw_screen_polygon(&scratch, id, coverage);
        }
        self.scratch = scratch;
    }

    /// Draw a world triangle.
    pub fn draw_triangle(&mut self, view: &View, tri: &[DVec3; 3], id: u32, coverage: Coverage) {
        self.draw_polygon(view, tri, id, coverage)
    }

    /// Draw a convex screen polygon (the rasterizer's 2D entry point, for callers that
    /// project by themselves, e.g. extended projections).
    pub fn draw_screen_polygon(&mut self, poly: &[ScreenVertex], id: u32, coverage: Coverage) {
        let Some(p) = Prepared::new(poly) else { return };
        if p.off_screen(self.width, self.height) {
            return;
        }
        let (w, h) = (self.width, self.height);
        let width = self.width as usize;
        if self.zrow.len() < width {
            self.zrow.resize(width, 0.0);
        }
        let (depth, ids, zrow) = (&mut self.depth, &mut self.ids, &mut self.zrow);
        // One span of row `j`: depths of the span, then depth test and write over row
        // slices (branch-free, no bounds checks per pixel).
        let mut span = |kind: Depth, j: u32, i0: u32, i1: u32| {
            let k0 = j as usize * width + i0 as usize;
            let k1 = j as usize * width + i1 as usize;
            let zs = &mut zrow[..=(i1 - i0) as usize];
            p.row_depths(kind, j, i0, zs);
            depth_test(zs, &mut depth[k0..=k1], &mut ids[k0..=k1], id);
        };
        match coverage {
            Coverage::Standard => {
                coverage::standard(&p, w, h, |j, a, b| span(Depth::Centre, j, a, b))
            }
            Coverage::Inner => coverage::inner(&p, w, h, |j, a, b| span(Depth::Far, j, a, b)),
            Coverage::Outer => {
                coverage::outer(&p, w, h, |j, a, b| {
                    span(Depth::Near, j, a, b);
                    false
                });
            }
        }
    }

    /// Draw the **union** of planar convex world polygons (e.g. every face of one fused
    /// occluder) with the inner rule: a pixel is written when the union covers it
    /// entirely, even if no single piece does, with an upper bound of the
    /// union's depth in it.
    pub fn draw_union<'a>(
        &mut self,
        view: &View,
        pieces: impl IntoIterator<Item = &'a [DVec3]>,
        id: u32,
    ) {
        let mut prepared = std::mem::take(&mut self.pieces);
        prepared.clear();
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut push = |poly: &[DVec3], prepared: &mut Vec<Prepared>| {
            if view.clip_project(poly, &mut scratch) >= 3 {
                if let Some(p) = Prepared::new(&scratch) {
                    prepared.push(p);
                }
            }
        };
        for poly in pieces {
            if poly.len() > MAX_INPUT_VERTS {
                for chunk in fan(poly) {
                    push(&chunk, &mut prepared);
                }
            } else {
                push(poly, &mut prepared);
            }
        }
        self.scratch = scratch;
        self.union_prepared(&prepared, id);
        self.pieces = prepared;
    }

    /// Screen-space version of [`Framebuffer::draw_union`].
    pub fn draw_screen_union(&mut self, pieces: &[&[ScreenVertex]], id: u32) {
        let mut prepared = std::mem::take(&mut self.pieces);
        prepared.clear();
        prepared.extend(pieces.iter().filter_map(|p| Prepared::new(p)));
        self.union_prepared(&prepared, id);
        self.pieces = prepared;
    }

    fn union_prepared(&mut self, prepared: &[Prepared], id: u32) {
        let width = self.width as usize;
        let (w, h) = (self.width, self.height);
        let (depth, ids) = (&mut self.depth, &mut self.ids);
        coverage::inner_union(prepared, w, h, &mut self.union, |j, i0, zs| {
            let k0 = j as usize * width + i0 as usize;
            let (d, ids) = (&mut depth[k0..k0 + zs.len()], &mut ids[k0..k0 + zs.len()]);
            depth_test(zs, d, ids, id);
        });
    }

    /// Whether a convex world polygon, drawn with the outer rule at its nearest depth,
    /// is hidden behind what the buffer holds in `view` (ties count as visible). Only
    /// the part inside the view's window is judged; a polygon reaching in front of the
    /// near plane is never occluded.
    pub fn polygon_occluded(&self, view: &View, poly: &[DVec3]) -> bool {
        occluded_test(view, poly, self.width, self.height, &self.depth, None)
    }

    /// The hierarchical max-depth pyramid of the current depth buffer.
    pub fn pyramid(&self) -> DepthPyramid {
        DepthPyramid::from_depth(self.width, self.height, &self.depth)
    }
}

/// Keep the strictly nearer of `zs` and `d` per pixel, with its id (branch-free).
#[inline]
fn depth_test(zs: &[f32], d: &mut [f32], ids: &mut [u32], id: u32) {
    for ((&z, d), i) in zs.iter().zip(d.iter_mut()).zip(ids.iter_mut()) {
        let nearer = z < *d;
        *d = if nearer { z } else { *d };
        *i = if nearer { id } else { *i };
    }
}
