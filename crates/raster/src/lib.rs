//! Hand-written CPU rasterizer of sightline: perspective views (cube faces or any
//! frustum), near-plane clipping, depth and object-id buffers, three coverage rules
//! (standard, inner/under-estimating, outer/over-estimating), conservative depth and a
//! hierarchical max-depth pyramid.
//!
//! The guarantee for occlusion culling (as in Masked Occlusion Culling): occluders drawn
//! with [`Coverage::Inner`] (or [`Framebuffer::draw_union`]) write only pixels they cover
//! entirely, at an upper bound of their depth there; an occludee tested with
//! [`DepthPyramid::polygon_occluded`] is drawn with the outer rule at a lower bound of its
//! depth. So a query may report an occluded polygon as visible, never a visible one as
//! occluded (ties count as visible). Shrinking occluders by whole pixels this way is the
//! discrete counterpart of the one-pixel shrinking of extended projections (Durand et al.
//! 2000, §3.2) and of the √2·a inward shift of the dual ray space (Koltun et al. 2001,
//! §5.2).
//!
//! ```
//! use sightline_raster::{Coverage, Face, Framebuffer, View};
//! use glam::DVec3;
//! // A wall 10 m ahead (+y), 20 m wide, 0..10 m high, seen from eye height 1.7 m.
//! let eye = DVec3::new(0.0, 0.0, 1.7);
//! let view = View::cube_face(eye, Face::PosY, 256, 0.01);
//! let wall = [
//!     DVec3::new(-10.0, 10.0, 0.0), DVec3::new(10.0, 10.0, 0.0),
//!     DVec3::new(10.0, 10.0, 10.0), DVec3::new(-10.0, 10.0, 10.0),
//! ];
//! let mut fb = Framebuffer::for_view(&view);
//! fb.draw_union(&view, [&wall[..]], 7);
//! assert_eq!(fb.ids_seen(), vec![7]);
//! let pyramid = fb.pyramid();
//! // A low box face 20 m away, behind the wall: occluded.
//! let behind = [
//!     DVec3::new(-2.0, 20.0, 0.0), DVec3::new(2.0, 20.0, 0.0),
//!     DVec3::new(2.0, 20.0, 3.0), DVec3::new(-2.0, 20.0, 3.0),
//! ];
//! assert!(pyramid.polygon_occluded(&view, &behind));
//! // A tower face rising above the wall: visible.
//! let tower = [
//!     DVec3::new(-2.0, 20.0, 0.0), DVec3::new(2.0, 20.0, 0.0),
//!     DVec3::new(2.0, 20.0, 40.0), DVec3::new(-2.0, 20.0, 40.0),
//! ];
//! assert!(!pyramid.polygon_occluded(&view, &tower));
//! ```

pub mod coverage;
pub mod framebuffer;
pub mod pyramid;
pub mod view;

pub use coverage::EPS_PX;
pub use framebuffer::{Framebuffer, NO_ID};
use glam::DVec3;
pub use pyramid::{DepthPyramid, Keep, Level, Max, Mean, Min, Pyramid, Sum};
use rayon::prelude::*;
use sightline_geom::Polygon;
pub use view::{Face, ScreenVertex, View};

/// Most vertices of a prepared screen polygon.
pub(crate) const MAX_VERTS: usize = 16;
/// Most vertices of an input polygon drawn in one piece (near clipping adds one).
pub(crate) const MAX_INPUT_VERTS: usize = 12;

/// Which pixels a draw writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Coverage {
    /// Pixels whose centre lies in the polygon; depth at the centre. Ground truth.
    Standard,
    /// Only pixels the polygon covers entirely (under-estimating); depth = the farthest
    /// point of the polygon in the pixel. For occluders.
    Inner,
    /// Every pixel the polygon touches (over-estimating); depth = its nearest point in
    /// the pixel. For occludees.
    Outer,
}

/// The faces of the prism `footprint × [base, top]` as planar convex polygons: one quad
/// per wall (so walls fuse exactly under [`Framebuffer::draw_union`]) and the
/// triangulated caps (the bottom cap only when `base > 0`).
pub fn prism_faces(footprint: &Polygon, base: f64, top: f64) -> Vec<Vec<DVec3>> {
    let caps = footprint.triangulate();
    let mut out = Vec::with_capacity(footprint.vertex_count() + 2 * caps.len());
    if top > base {
        for ring in footprint.rings() {
            let n = ring.len();
            for k in 0..n {
                let (a, b) = (ring[k], ring[(k + 1) % n]);
                if a == b {
                    continue;
                }
                out.push(vec![
                    a.extend(base),
                    b.extend(base),
                    b.extend(top),
                    a.extend(top),
                ]);
            }
        }
    }
    out.extend(caps.iter().map(|t| t.map(|p| p.extend(top)).to_vec()));
    if base > 0.0 && top > base {
        out.extend(
            caps.iter()
                .map(|t| vec![t[0].extend(base), t[2].extend(base), t[1].extend(base)]),
        );
    }
    out
}

/// Render the six cube faces around `eye` in parallel (rayon): `draw` is called once per
/// face with the face's view and an empty buffer. Returns the buffers in [`Face::ALL`]
/// order.
pub fn render_cube<F>(
    eye: DVec3,
    resolution_px: u32,
    near: f64,
    draw: F,
) -> Vec<(View, Framebuffer)>
where
    F: Fn(&View, &mut Framebuffer) + Sync,
{
    Face::ALL
        .par_iter()
        .map(|&face| {
            let view = View::cube_face(eye, face, resolution_px, near);
            let mut fb = Framebuffer::for_view(&view);
            draw(&view, &mut fb);
            (view, fb)
        })
        .collect()
}
