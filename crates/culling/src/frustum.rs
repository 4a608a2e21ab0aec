//! The view of one frame: an eye, a viewing direction, a vertical field of view and a
//! pixel grid (z up), validated once so that no culler meets a NaN or an empty buffer.

use crate::CullError;
use glam::DVec3;
use sightline_raster::{ScreenVertex, View};

/// Near clipping depth of every frame (metres). A box reaching in front of it is
/// visible (it may contain the eye).
pub const NEAR_M: f64 = 0.05;
/// Largest accepted buffer side (pixels).
pub const MAX_SIDE_PX: u32 = 16_384;

/// A perspective view frustum: `eye`, unit `dir`, vertical field of view `fov_deg`,
/// `width × height` pixels (square pixels), z up.
///
/// ```
/// use sightline_culling::Frustum;
/// use glam::DVec3;
/// let f = Frustum::new(DVec3::new(0.0, 0.0, 1.7), DVec3::Y, 60.0, 640, 360).unwrap();
/// assert_eq!(f.view().width_px, 640);
/// assert!(Frustum::new(DVec3::new(f64::NAN, 0.0, 0.0), DVec3::Y, 60.0, 640, 360).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    pub eye: DVec3,
    pub dir: DVec3,
    pub fov_deg: f64,
    pub width_px: u32,
    pub height_px: u32,
    view: View,
}

impl Frustum {
    /// Validate and build. Errors: non-finite eye or direction, a zero direction, a field
    /// of view outside `(0, 179]` degrees, a zero or absurd buffer size.
    pub fn new(
        eye: DVec3,
        dir: DVec3,
        fov_deg: f64,
        width_px: u32,
        height_px: u32,
    ) -> Result<Frustum, CullError> {
        if !eye.is_finite() {
            return Err(CullError::BadFrustum(format!("eye {eye} is not finite")));
        }
        if !dir.is_finite() || dir.length() < 1e-9 {
            return Err(CullError::BadFrustum(format!(
                "direction {dir} is not a finite non-zero vector"
            )));
        }
        if !(fov_deg > 0.0 && fov_deg <= 179.0) {
            return Err(CullError::BadFrustum(format!(
                "vertical field of view {fov_deg}° is not in (0, 179]"
            )));
        }
        if width_px == 0 || height_px == 0 || width_px > MAX_SIDE_PX || height_px > MAX_SIDE_PX {
            return Err(CullError::BadFrustum(format!(
                "buffer {width_px}x{height_px} is empty or larger than {MAX_SIDE_PX} px a side"
            )));
        }
        let dir = dir.normalize();
        // z is up; looking straight up or down, the screen's up is +y.
        let up_hint = if dir.cross(DVec3::Z).length() < 1e-6 {
            DVec3::Y
        } else {
            DVec3::Z
        };
        let ty = (fov_deg.to_radians() / 2.0).tan();
        let tx = ty * width_px as f64 / height_px as f64;
        let view = View::frustum(
            eye,
            dir,
            up_hint,
            [-tx, -ty, tx, ty],
            width_px,
            height_px,
            NEAR_M,
        );
        Ok(Frustum {
            eye,
            dir,
            fov_deg,
            width_px,
            height_px,
            view,
        })
    }

    /// The raster view of this frustum at its own size.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// The same frustum on a `width × height` grid (same window: a point projects to the
    /// same place scaled).
    pub fn view_at(&self, width_px: u32, height_px: u32) -> View {
        View {
            width_px: width_px.max(1),
            height_px: height_px.max(1),
            ..self.view
        }
    }
}

/// Where a box lies with respect to a view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoxInView {
    /// Entirely outside one side plane or behind the near plane: hidden.
    Outside,
    /// Reaching in front of the near plane (inside the side planes): visible.
    CrossesNear,
    /// In front of the near plane: its outer screen rectangle (pixels, inclusive, clamped
    /// to the screen) and a lower bound of its depth (metres, rounded down to `f32`).
    Rect {
        i0: u32,
        j0: u32,
        i1: u32,
        j1: u32,
        z_near: f32,
    },
}

impl BoxInView {
    /// The outer screen rectangle `[i0, j0, i1, j1]` and depth lower bound of a box on
    /// screen; `None` when it is outside or crosses the near plane.
    pub fn rect(self) -> Option<([u32; 4], f32)> {
        match self {
            BoxInView::Rect {
                i0,
                j0,
                i1,
                j1,
                z_near,
            } => Some(([i0, j0, i1, j1], z_near)),
            _ => None,
        }
    }
}

/// Classify the box `[lo, hi]` in `view`: the side planes pass through the eye, so a
/// box is outside when all eight corners are on the outer side of one of them.
pub fn box_in_view(view: &View, lo: DVec3, hi: DVec3) -> BoxInView {
    let [x0, y0, x1, y1] = view.window;
    let mut cam = [DVec3::ZERO; 8];
    for (k, c) in cam.iter_mut().enumerate() {
        let p = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        *c = view.to_camera(p);
    }
    let all = |f: &dyn Fn(&DVec3) -> bool| cam.iter().all(f);
    if all(&|c| c.z < view.near)
        || all(&|c| c.x < x0 * c.z)
        || all(&|c| c.x > x1 * c.z)
        || all(&|c| c.y < y0 * c.z)
        || all(&|c| c.y > y1 * c.z)
    {
        return BoxInView::Outside;
    }
    if cam.iter().any(|c| c.z < view.near) {
        return BoxInView::CrossesNear;
    }
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    let mut zmin = f64::MAX;
    for c in &cam {
        let s = view.camera_to_screen(*c);
        xmin = xmin.min(s.x);
        xmax = xmax.max(s.x);
        ymin = ymin.min(s.y);
        ymax = ymax.max(s.y);
        zmin = zmin.min(c.z);
    }
    let (w, h) = (view.width_px as f64, view.height_px as f64);
    const EPS: f64 = 1e-6;
    if xmax < -EPS || ymax < -EPS || xmin > w + EPS || ymin > h + EPS {
        return BoxInView::Outside;
    }
    let clamp = |v: f64, n: f64| v.floor().clamp(0.0, n - 1.0) as u32;
    BoxInView::Rect {
        i0: clamp(xmin - EPS, w),
        i1: clamp(xmax + EPS, w),
        j0: clamp(ymin - EPS, h),
        j1: clamp(ymax + EPS, h),
        z_near: f32_down(zmin * (1.0 - 1e-12)),
    }
}

/// Clip a planar convex world polygon against the near plane and project it
/// (Sutherland–Hodgman). Returns false if nothing is left.
pub fn clip_project(view: &View, poly: &[DVec3], out: &mut Vec<ScreenVertex>) -> bool {
    out.clear();
    let n = poly.len();
    if n < 3 {
        return false;
    }
    // Each vertex to camera space once (a polygon of a prism has at most a handful).
    const STACK: usize = 16;
    let mut stack = [DVec3::ZERO; STACK];
    let heap: Vec<DVec3>;
    let cam: &[DVec3] = if n <= STACK {
        for (c, p) in stack.iter_mut().zip(poly) {
            *c = view.to_camera(*p);
        }
        &stack[..n]
    } else {
        heap = poly.iter().map(|p| view.to_camera(*p)).collect();
        &heap
    };
    for k in 0..n {
        let (a, b) = (cam[k], cam[(k + 1) % n]);
        let (ain, bin) = (a.z >= view.near, b.z >= view.near);
        if ain {
            out.push(view.camera_to_screen(a));
        }
        if ain != bin {
            let t = (view.near - a.z) / (b.z - a.z);
            let mut c = a + (b - a) * t;
            c.z = view.near;
            out.push(view.camera_to_screen(c));
        }
    }
    if out.len() < 3 {
        out.clear();
        return false;
    }
    true
}

/// `v` rounded up to an `f32` (`v > 0`).
#[inline]
pub(crate) fn f32_up(v: f64) -> f32 {
    let f = v as f32;
    if (f as f64) < v {
        f.next_up()
    } else {
        f
    }
}

/// `v` rounded down to an `f32`.
#[inline]
pub(crate) fn f32_down(v: f64) -> f32 {
    let f = v as f32;
    if (f as f64) > v {
        f.next_down()
    } else {
        f
    }
}
