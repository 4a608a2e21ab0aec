//! A ray oracle independent of the portal code: segments between random points of two
//! leaves, traced through the BSP tree (Quake's recursive hull check, point hull). A
//! segment that crosses only open leaves (empty, water, slime, lava) is a clear sight
//! line: the pair is visible, and a conservative PVS must hold it.

use sightline_scene::import::bsp::{BspLevel, Child};

/// A small deterministic generator (xorshift64*), so the oracle's samples are the
/// same on every run.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }

    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Whether the segment `a`–`b` crosses only open leaves.
pub fn segment_clear(level: &BspLevel, a: [f64; 3], b: [f64; 3]) -> bool {
    clear(level, level.headnode, a, b)
}

fn clear(level: &BspLevel, c: Child, a: [f64; 3], b: [f64; 3]) -> bool {
    match c {
        Child::Leaf(l) => level.leaves.get(l as usize).is_some_and(|l| l.is_open()),
        Child::Node(n) => {
            let node = &level.nodes[n as usize];
            let plane = &level.planes[node.plane as usize];
            let (da, db) = (plane.distance(a), plane.distance(b));
            if da >= 0.0 && db >= 0.0 {
                return clear(level, node.children[0], a, b);
            }
            if da < 0.0 && db < 0.0 {
                return clear(level, node.children[1], a, b);
            }
            let t = da / (da - db);
            let mid = [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]));
            let (near, far) = if da < 0.0 { (1, 0) } else { (0, 1) };
            clear(level, node.children[near], a, mid) && clear(level, node.children[far], mid, b)
        }
    }
}

/// Up to `n` random points inside `leaf`, by rejection in the leaf's box (fewer when
/// the leaf fills little of its box).
pub fn sample_leaf(level: &BspLevel, leaf: u32, n: usize, rng: &mut Rng) -> Vec<[f64; 3]> {
    let Some(l) = level.leaves.get(leaf as usize) else {
        return Vec::new();
    };
    let mut out = Vec::with_capacity(n);
    for _ in 0..n * 64 {
        if out.len() == n {
            break;
        }
        let p = [0, 1, 2].map(|k| l.mins[k] + rng.unit() * (l.maxs[k] - l.mins[k]));
        if level.point_leaf(p) == leaf {
            out.push(p);
        }
    }
    out
}

/// Whether some of `segments` random segments between points of `a` and points of
/// `b` is clear. `pool` points per leaf are drawn once and paired at random.
pub fn pair_visible(
    level: &BspLevel,
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    segments: usize,
    rng: &mut Rng,
) -> bool {
    if a.is_empty() || b.is_empty() {
        return false;
    }
    (0..segments).any(|_| {
        let p = a[(rng.next_u64() % a.len() as u64) as usize];
        let q = b[(rng.next_u64() % b.len() as u64) as usize];
        segment_clear(level, p, q)
    })
}
