//! Frames to cull: the path file of `sightline frames` and a generated street-level walk.

use glam::DVec3;
use serde::{Deserialize, Serialize};
use sightline_scene::Scene;
use sightline_stats::Rng;

/// One frame of a path: eye, viewing direction, vertical field of view (degrees).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathFrame {
    pub eye: [f64; 3],
    pub dir: [f64; 3],
    #[serde(default = "default_fov")]
    pub fov_deg: f64,
}

fn default_fov() -> f64 {
    60.0
}

/// Whether `p` is at least `margin` (horizontally) away from every block of `scene`
/// that spans its height (tested at `p` and eight points around it).
pub fn is_free(scene: &Scene, p: DVec3, margin: f64) -> bool {
    let probes = [
        (0.0, 0.0),
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 1.0),
        (0.0, -1.0),
        (0.7, 0.7),
        (-0.7, 0.7),
        (0.7, -0.7),
        (-0.7, -0.7),
    ];
    for o in &scene.objects {
        let b = &o.bounds;
        if p.x < b.min.x - margin
            || p.x > b.max.x + margin
            || p.y < b.min.y - margin
            || p.y > b.max.y + margin
            || p.z < b.min.z
            || p.z > b.max.z
        {
            continue;
        }
        for pr in o.outer.iter().chain(o.inner.iter()) {
            if p.z < pr.base || p.z > pr.top {
                continue;
            }
            for (dx, dy) in probes {
                let q = p.truncate() + glam::DVec2::new(dx, dy) * margin;
                if pr.footprint.contains(q) {
                    return false;
                }
            }
        }
    }
    true
}

/// Whether some block's bounding box lies within `dist_m` (horizontally) of `p`: a
/// street, not the middle of a river or a park.
pub fn near_building(scene: &Scene, p: DVec3, dist_m: f64) -> bool {
    scene.objects.iter().any(|o| {
        let b = o.bounds.xy();
        let q = p.truncate().clamp(b.min, b.max);
        q.distance(p.truncate()) <= dist_m && o.bounds.max.z > p.z
    })
}

/// Streets: a walk stays within this distance of a building (metres).
pub const STREET_M: f64 = 15.0;

/// A deterministic street-level walk of `n` frames through `scene`: eye 1.5–2 m above
/// the ground, 1 m or more from any building and within [`STREET_M`] of one, stepping 3 m per frame and turning when a
/// building or the scene's edge is ahead, looking roughly horizontally.
pub fn street_walk(scene: &Scene, n: usize, seed: u64, fov_deg: f64) -> Vec<PathFrame> {
    let mut rng = Rng::new(seed);
    let b = scene.bounds;
    let mut out = Vec::with_capacity(n);
    if scene.is_empty() || n == 0 {
        return out;
    }
    let random_free = |rng: &mut Rng| -> Option<DVec3> {
        for _ in 0..10_000 {
            let p = DVec3::new(
                rng.range(b.min.x, b.max.x),
                rng.range(b.min.y, b.max.y),
                rng.range(1.5, 2.0),
            );
            if is_free(scene, p, 1.0) && near_building(scene, p, STREET_M) {
                return Some(p);
            }
        }
        None
    };
    let Some(mut eye) = random_free(&mut rng) else {
        return out;
    };
    let mut azimuth = rng.range(0.0, std::f64::consts::TAU);
    while out.len() < n {
        let pitch = rng.range(-5.0f64, 10.0).to_radians();
        let dir = DVec3::new(
            azimuth.cos() * pitch.cos(),
            azimuth.sin() * pitch.cos(),
            pitch.sin(),
        );
        out.push(PathFrame {
            eye: eye.to_array(),
            dir: dir.to_array(),
            fov_deg,
        });
        let mut moved = false;
        for attempt in 0..24 {
            if attempt > 0 {
                azimuth = rng.range(0.0, std::f64::consts::TAU);
            }
            let next = eye + DVec3::new(azimuth.cos(), azimuth.sin(), 0.0) * 3.0;
            let inside =
                next.x > b.min.x && next.x < b.max.x && next.y > b.min.y && next.y < b.max.y;
            if inside && is_free(scene, next, 1.0) && near_building(scene, next, STREET_M) {
                eye = next;
                moved = true;
                break;
            }
        }
        if !moved {
            match random_free(&mut rng) {
                Some(p) => eye = p,
                None => break,
            }
        }
        azimuth += rng.range(-0.3, 0.3);
    }
    out
}

/// Deterministic indoor frames for a scene of meshes (a BSP level's faces, a mesh level):
/// each eye is `eye_height` above a random point of a random floor triangle (one facing
/// up within 25°, picked with probability proportional to its area), looking in a random
/// horizontal direction (pitch −10°…10°). Empty when the scene has no floor.
pub fn floor_frames(
    scene: &Scene,
    n: usize,
    seed: u64,
    eye_height: f64,
    fov_deg: f64,
) -> Vec<PathFrame> {
    let mut floors: Vec<([DVec3; 3], f64)> = Vec::new();
    for o in &scene.objects {
        let sightline_scene::Geometry::Mesh(m) = &o.geometry else {
            continue;
        };
        for t in &m.triangles {
            if t.iter().any(|&i| i as usize >= m.vertices.len()) {
                continue;
            }
            let tri = m.triangle(t);
            let nrm = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            let area2 = nrm.length();
            if area2 > 0.0 && nrm.z / area2 > 25f64.to_radians().cos() {
                floors.push((tri, area2));
            }
        }
    }
    let total: f64 = floors.iter().map(|f| f.1).sum();
    let mut out = Vec::with_capacity(n);
    if floors.is_empty() || !(total > 0.0) {
        return out;
    }
    let mut rng = Rng::new(seed);
    while out.len() < n {
        let mut pick = rng.range(0.0, total);
        let tri = floors
            .iter()
            .find(|f| {
                pick -= f.1;
                pick <= 0.0
            })
            .map_or(floors[floors.len() - 1].0, |f| f.0);
        let (mut a, mut b) = (rng.range(0.0, 1.0), rng.range(0.0, 1.0));
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let p = tri[0] + (tri[1] - tri[0]) * a + (tri[2] - tri[0]) * b;
        let az = rng.range(0.0, std::f64::consts::TAU);
        let pitch = rng.range(-10.0f64, 10.0).to_radians();
        out.push(PathFrame {
            eye: (p + DVec3::Z * eye_height).to_array(),
            dir: [az.cos() * pitch.cos(), az.sin() * pitch.cos(), pitch.sin()],
            fov_deg,
        });
    }
    out
}
