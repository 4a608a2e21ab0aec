//! Views: an eye, an orthonormal camera frame, a window on the plane at depth 1 and a
//! pixel grid. Cube faces (90° fov, square) are the common case; any (asymmetric)
//! frustum works.

use crate::MAX_INPUT_VERTS;
use glam::DVec3;

/// One of the six faces of a cube map centred on the eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Face {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

impl Face {
    /// All six faces: together they cover the full sphere of directions.
    pub const ALL: [Face; 6] = [
        Face::PosX,
        Face::NegX,
        Face::PosY,
        Face::NegY,
        Face::PosZ,
        Face::NegZ,
    ];

    /// `(forward, up)` of the face's camera; `right = forward × up`.
    pub fn axes(self) -> (DVec3, DVec3) {
        match self {
            Face::PosX => (DVec3::X, DVec3::Z),
            Face::NegX => (DVec3::NEG_X, DVec3::Z),
            Face::PosY => (DVec3::Y, DVec3::Z),
            Face::NegY => (DVec3::NEG_Y, DVec3::Z),
            Face::PosZ => (DVec3::Z, DVec3::Y),
            Face::NegZ => (DVec3::NEG_Z, DVec3::Y),
        }
    }
}

/// A point in screen space: `x`, `y` in pixels (pixel `(i, j)` is the square
/// `[i, i+1] × [j, j+1]`, row 0 at the window's lower edge) and `w = 1 / depth`, which
/// is affine in screen space for planar polygons (so it can be interpolated exactly).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenVertex {
    pub x: f64,
    pub y: f64,
    /// Reciprocal of the depth along the view axis (`> 0`).
    pub w: f64,
}

/// A perspective view.
///
/// Camera coordinates of a world point `p`: `x = (p - eye)·right`, `y = (p - eye)·up`,
/// `depth = (p - eye)·forward`. The screen position is the point's image on the plane
/// at depth 1, mapped from `window = [x0, y0, x1, y1]` onto `[0, width_px] × [0, height_px]`.
/// Geometry closer than `near` (depth) is clipped away.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub eye: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// `[x0, y0, x1, y1]` on the plane at depth 1 (tangents of the half-angles for a
    /// symmetric frustum: a cube face is `[-1, -1, 1, 1]`).
    pub window: [f64; 4],
    pub width_px: u32,
    pub height_px: u32,
    /// Near clipping depth (metres, `> 0`).
    pub near: f64,
}

impl View {
    /// The cube-map face `face` seen from `eye`: square, 90° field of view.
    pub fn cube_face(eye: DVec3, face: Face, resolution_px: u32, near: f64) -> View {
        let (forward, up) = face.axes();
        View {
            eye,
            forward,
            right: forward.cross(up),
            up,
            window: [-1.0, -1.0, 1.0, 1.0],
            width_px: resolution_px.max(1),
            height_px: resolution_px.max(1),
            near,
        }
    }

    /// A general frustum looking along `forward` with `up` as the vertical hint
    /// (orthonormalized; must not be parallel to `forward`).
    pub fn frustum(
        eye: DVec3,
        forward: DVec3,
        up: DVec3,
        window: [f64; 4],
        width_px: u32,
        height_px: u32,
        near: f64,
    ) -> View {
        let forward = forward.normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        View {
            eye,
            forward,
            right,
            up,
            window,
            width_px: width_px.max(1),
            height_px: height_px.max(1),
            near,
        }
    }

    /// Camera coordinates `(x right, y up, depth)` of a world point.
    #[inline]
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        let d = p - self.eye;
        DVec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }

    /// Screen position of a camera-space point with positive depth.
    #[inline]
    pub fn camera_to_screen(&self, c: DVec3) -> ScreenVertex {
        let w = 1.0 / c.z;
        let [x0, y0, x1, y1] = self.window;
        ScreenVertex {
            x: (c.x * w - x0) / (x1 - x0) * self.width_px as f64,
            y: (c.y * w - y0) / (y1 - y0) * self.height_px as f64,
            w,
        }
    }

    /// Screen position of a world point, or `None` if it lies before the near plane.
    pub fn project(&self, p: DVec3) -> Option<ScreenVertex> {
        let c = self.to_camera(p);
        (c.z >= self.near).then(|| self.camera_to_screen(c))
    }

    /// Unit world direction from the eye through the screen point `(x, y)` (pixels).
    pub fn direction(&self, x: f64, y: f64) -> DVec3 {
        let [x0, y0, x1, y1] = self.window;
        let u = x0 + x / self.width_px as f64 * (x1 - x0);
        let v = y0 + y / self.height_px as f64 * (y1 - y0);
        (self.forward + self.right * u + self.up * v).normalize()
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width_px as usize * self.height_px as usize
    }

    /// Clip a planar convex world polygon against the near plane and project it.
    /// Returns the number of screen vertices written to `out` (0 if nothing is left).
    pub(crate) fn clip_project(&self, poly: &[DVec3], out: &mut Vec<ScreenVertex>) -> usize {
        out.clear();
        let n = poly.len();
        if n < 3 {
            return 0;
        }
        let mut cam = [DVec3::ZERO; crate::MAX_VERTS];
        let mut all_in = true;
        let mut all_out = true;
        for (k, p) in poly.iter().take(crate::MAX_VERTS).enumerate() {
            cam[k] = self.to_camera(*p);
            if cam[k].z >= self.near {
                all_out = false;
            } else {
                all_in = false;
            }
        }
        let n = n.min(crate::MAX_VERTS);
        if all_out {
            return 0;
        }
        if all_in {
            out.extend(cam[..n].iter().map(|c| self.camera_to_screen(*c)));
            return out.len();
        }
        // Sutherland–Hodgman against depth >= near.
        for k in 0..n {
            let a = cam[k];
            let b = cam[(k + 1) % n];
            let ain = a.z >= self.near;
            let bin = b.z >= self.near;
            if ain {
                out.push(self.camera_to_screen(a));
            }
            if ain != bin {
                let t = (self.near - a.z) / (b.z - a.z);
                let mut c = a + (b - a) * t;
                c.z = self.near;
                out.push(self.camera_to_screen(c));
            }
        }
        if out.len() < 3 {
            out.clear();
        }
        out.len()
    }
}

/// Split a polygon with many vertices into fan pieces of at most MAX_INPUT_VERTS.
pub(crate) fn fan(poly: &[DVec3]) -> Vec<Vec<DVec3>> {
    let mut out = Vec::new();
    let mut k = 1;
    while k + 1 < poly.len() {
        let end = (k + MAX_INPUT_VERTS - 1).min(poly.len());
        let mut c = Vec::with_capacity(end - k + 1);
        c.push(poly[0]);
        c.extend_from_slice(&poly[k..end]);
        if c.len() >= 3 {
            out.push(c);
        }
        k = end - 1;
    }
    out
}
