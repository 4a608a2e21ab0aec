//! The screen-space-error (SSE) refinement of a plain 3D Tiles client, as a model to
//! count what it downloads (the benchmark; not used to render).
//!
//! A perspective camera (vertical field of view `fov_y_rad`, `screen_height_px`) walks
//! the tree from the root as 3DTilesRendererJS and CesiumJS do:
//!
//! * a tile whose bounding box lies wholly outside the view frustum is skipped with its
//!   subtree;
//! * a visited tile with content is requested;
//! * its children are visited if its SSE, `geometricError · screen_height_px /
//!   (2 d tan(fov_y / 2))` with `d` the distance from the eye to its box, exceeds
//!   `max_sse_px` (both clients' default is 16 px).
//!
//! The PVS-driven client walks the same way and requests a content tile only if the
//! tile-level PVS of the eye's cell lists it: with a conservative PVS it requests every
//! tile of the plain client that holds a visible feature.

use crate::layout::Layout;
use sightline_geom::{Aabb3, DVec3};

/// The camera of [`requested`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    /// Unit view direction.
    pub forward: DVec3,
    pub fov_y_rad: f64,
    /// Width / height.
    pub aspect: f64,
    pub screen_height_px: f64,
    pub near_m: f64,
    pub far_m: f64,
    pub max_sse_px: f64,
}

impl Camera {
    /// A 1920 × 1080 camera with a 60° vertical field of view, looking horizontally
    /// along `azimuth_rad` (0 = +x, counter-clockwise), far plane 5 km, 16 px SSE.
    pub fn street(eye: DVec3, azimuth_rad: f64) -> Camera {
        Camera {
            eye,
            forward: DVec3::new(azimuth_rad.cos(), azimuth_rad.sin(), 0.0),
            fov_y_rad: 60f64.to_radians(),
            aspect: 16.0 / 9.0,
            screen_height_px: 1080.0,
            near_m: 0.1,
            far_m: 5000.0,
            max_sse_px: 16.0,
        }
    }

    /// The inward normals and offsets of the six frustum planes (`n · p + d >= 0`
    /// inside).
    fn planes(&self) -> [(DVec3, f64); 6] {
        let f = self.forward.normalize();
        let up0 = if f.z.abs() > 0.99 { DVec3::X } else { DVec3::Z };
        let right = f.cross(up0).normalize();
        let up = right.cross(f);
        let ty = (self.fov_y_rad / 2.0).tan();
        let tx = ty * self.aspect;
        // A side plane holds the eye, a frustum edge direction and the axis across it;
        // its inward normal points to the forward side.
        let side = |edge: DVec3, across: DVec3| {
            let n = edge.cross(across).normalize();
            let n = if n.dot(f) < 0.0 { -n } else { n };
            (n, -n.dot(self.eye))
        };
        [
            (f, -f.dot(self.eye) - self.near_m),
            (-f, f.dot(self.eye) + self.far_m),
            side(f + right * tx, up),
            side(f - right * tx, up),
            side(f + up * ty, right),
            side(f - up * ty, right),
        ]
    }

    /// Conservative: `false` only if the box is wholly outside one plane.
    pub fn sees_box(&self, b: &Aabb3) -> bool {
        let corners = b.corners();
        self.planes()
            .iter()
            .all(|(n, d)| corners.iter().any(|c| n.dot(*c) + d >= 0.0))
    }

    /// The screen-space error of `geometric_error` at the distance of `b`.
    pub fn sse_px(&self, geometric_error: f64, b: &Aabb3) -> f64 {
        let d = (b.min - self.eye)
            .max(self.eye - b.max)
            .max(DVec3::ZERO)
            .length();
        if d <= 0.0 {
            return f64::INFINITY;
        }
        geometric_error * self.screen_height_px / (2.0 * d * (self.fov_y_rad / 2.0).tan())
    }
}

/// Indices of the content tiles the client requests from `camera`, in traversal order;
/// `allowed` filters content tiles (the PVS-driven client), `None` is the plain client.
pub fn requested(
    layout: &Layout,
    camera: &Camera,
    allowed: Option<&dyn Fn(usize) -> bool>,
) -> Vec<usize> {
    let mut out = Vec::new();
    let mut stack = vec![0usize];
    while let Some(t) = stack.pop() {
        let tile = &layout.tiles[t];
        if !camera.sees_box(&tile.bounds) {
            continue;
        }
        if !tile.objects.is_empty() && allowed.is_none_or(|f| f(t)) {
            out.push(t);
        }
        if camera.sse_px(tile.geometric_error, &tile.bounds) > camera.max_sse_px {
            stack.extend(tile.children.iter().rev());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frustum_sees_ahead_not_behind() {
        let cam = Camera::street(DVec3::new(0.0, 0.0, 1.7), 0.0);
        let ahead = Aabb3::new(DVec3::new(50.0, -5.0, 0.0), DVec3::new(60.0, 5.0, 10.0));
        let behind = Aabb3::new(DVec3::new(-60.0, -5.0, 0.0), DVec3::new(-50.0, 5.0, 10.0));
        let left_out = Aabb3::new(DVec3::new(1.0, 50.0, 0.0), DVec3::new(5.0, 60.0, 10.0));
        assert!(cam.sees_box(&ahead));
        assert!(!cam.sees_box(&behind));
        assert!(
            !cam.sees_box(&left_out),
            "90° off axis is outside a 53° half-width"
        );
        let far = Aabb3::new(DVec3::new(6000.0, -5.0, 0.0), DVec3::new(6010.0, 5.0, 10.0));
        assert!(!cam.sees_box(&far));
    }

    #[test]
    fn sse_falls_with_distance() {
        let cam = Camera::street(DVec3::ZERO, 0.0);
        let near = Aabb3::new(DVec3::new(10.0, 0.0, 0.0), DVec3::new(11.0, 1.0, 1.0));
        let far = Aabb3::new(DVec3::new(1000.0, 0.0, 0.0), DVec3::new(1001.0, 1.0, 1.0));
        assert!(cam.sse_px(10.0, &near) > cam.sse_px(10.0, &far));
        let inside = Aabb3::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        assert_eq!(cam.sse_px(1.0, &inside), f64::INFINITY);
    }
}
