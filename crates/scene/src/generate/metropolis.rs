//! `metropolis`: a grid city for scale tests (≥ 150,000 buildings, ≥ 2 M triangles).
//!
//! Square street blocks on a 110 m pitch (streets of 18 m, avenues of 30 m every fifth
//! line); each block is cut into 2–4 × 2–4 lots that touch exactly. Heights follow a
//! realistic distribution: a low-rise background (median 12 m) and a few high-rise
//! centres (radius 4–10 % of the city's side) where the median rises to 60–150 m; each building's height is log-normal
//! around the local median (σ = 0.4 in log space), clamped to 4–450 m. Low-rise lots are
//! rectangles, L or U shapes (party walls); towers stand back from the lot edge as
//! rectangles or chamfered octagons.
//!
//! Blocks are generated in parallel, each from its own random stream, so the result
//! does not depend on the thread count.

use super::{snap_cm, snap_ring, Rng};
use crate::{Object, Scene};
use rayon::prelude::*;
use sightline_geom::{DVec2, Polygon};

/// Parameters of [`metropolis_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct MetropolisParams {
    /// Number of buildings (exactly).
    pub buildings: usize,
    /// Distance between street axes, in metres.
    pub block_pitch_m: f64,
    /// Number of high-rise centres (default: 1 + buildings / 25,000).
    pub centres: Option<usize>,
}

impl Default for MetropolisParams {
    fn default() -> Self {
        MetropolisParams {
            buildings: 150_000,
            block_pitch_m: 110.0,
            centres: None,
        }
    }
}

/// A grid metropolis of `n_buildings` buildings (default parameters otherwise).
pub fn metropolis(seed: u64, n_buildings: usize) -> Scene {
    metropolis_with(
        seed,
        &MetropolisParams {
            buildings: n_buildings,
            ..MetropolisParams::default()
        },
    )
}

/// A grid metropolis with explicit parameters.
pub fn metropolis_with(seed: u64, p: &MetropolisParams) -> Scene {
    let n = p.buildings;
    if n == 0 {
        return Scene::from_objects(vec![]);
    }
    let pitch = p.block_pitch_m;
    // Columns fixed so the city is roughly square (about 9 lots per block).
    let cols = ((n as f64 / 9.0).sqrt().ceil() as usize).max(1);
    // Lots per block, in row-major order, until there are enough buildings.
    let mut blocks: Vec<(usize, usize, usize, usize)> = Vec::new(); // (col, row, nx, ny)
    let mut total = 0usize;
    while total < n {
        let k = blocks.len();
        let mut r = Rng::derive(seed ^ 0x4D45_5452_4F50, k as u64);
        let (nx, ny) = (2 + r.below(3), 2 + r.below(3));
        blocks.push((k % cols, k / cols, nx, ny));
        total += nx * ny;
    }
    let rows = blocks.last().map_or(1, |b| b.1 + 1);
    let extent = DVec2::new(cols as f64, rows as f64) * pitch;

    // High-rise centres: (position, radius, peak median height).
    let mut crng = Rng::derive(seed, 0xCE47);
    let n_centres = p.centres.unwrap_or(1 + n / 25_000);
    let centres: Vec<(DVec2, f64, f64)> = (0..n_centres)
        .map(|_| {
            (
                DVec2::new(crng.range(0.1, 0.9), crng.range(0.1, 0.9)) * extent,
                crng.range(0.04, 0.1) * extent.max_element(),
                crng.range(60.0, 150.0),
            )
        })
        .collect();
    let street = |line: usize| if line.is_multiple_of(5) { 30.0 } else { 18.0 };

    let per_block: Vec<Vec<Object>> = blocks
        .par_iter()
        .enumerate()
        .map(|(k, &(col, row, nx, ny))| {
            let mut r = Rng::derive(seed, k as u64 + 1);
            let x0 = col as f64 * pitch + street(col) / 2.0;
            let x1 = (col + 1) as f64 * pitch - street(col + 1) / 2.0;
            let y0 = row as f64 * pitch + street(row) / 2.0;
            let y1 = (row + 1) as f64 * pitch - street(row + 1) / 2.0;
            let xs = cuts(&mut r, x0, x1, nx);
            let ys = cuts(&mut r, y0, y1, ny);
            let mut out = Vec::with_capacity(nx * ny);
            for b in 0..ny {
                for a in 0..nx {
                    let (lo, hi) = (DVec2::new(xs[a], ys[b]), DVec2::new(xs[a + 1], ys[b + 1]));
                    let c = (lo + hi) * 0.5;
                    let median = 12.0
                        + centres
                            .iter()
                            .map(|(q, rad, peak)| {
                                peak * (-(c.distance_squared(*q)) / (2.0 * rad * rad)).exp()
                            })
                            .sum::<f64>();
                    let h = r.lognormal(median, 0.4).clamp(4.0, 450.0);
                    let ring = if h >= 45.0 {
                        tower_footprint(&mut r, lo, hi)
                    } else {
                        low_rise_footprint(&mut r, lo, hi)
                    };
                    out.push(Object::block(
                        Some(format!("m{row}-{col}-{}", b * nx + a)),
                        Polygon::new(snap_ring(ring), vec![]),
                        0.0,
                        snap_cm(h),
                    ));
                }
            }
            out
        })
        .collect();
    let mut objects: Vec<Object> = per_block.into_iter().flatten().collect();
    objects.truncate(n);
    Scene::from_objects(objects)
}

/// `n + 1` cut coordinates from `a` to `b`, interior ones jittered by ±20 % of a lot.
fn cuts(r: &mut Rng, a: f64, b: f64, n: usize) -> Vec<f64> {
    let w = (b - a) / n as f64;
    (0..=n)
        .map(|i| {
            if i == 0 {
                a
            } else if i == n {
                b
            } else {
                a + w * (i as f64 + r.range(-0.2, 0.2))
            }
        })
        .collect()
}

/// A low-rise building filling its lot: a rectangle, an L (a rear corner left as a
/// yard) or a U (a notch in one side).
fn low_rise_footprint(r: &mut Rng, lo: DVec2, hi: DVec2) -> Vec<DVec2> {
    let (x0, y0, x1, y1) = (lo.x, lo.y, hi.x, hi.y);
    let u = r.f64();
    let mut ring = if u < 0.4 {
        vec![lo, DVec2::new(x1, y0), hi, DVec2::new(x0, y1)]
    } else if u < 0.75 {
        let xc = x0 + (x1 - x0) * r.range(0.45, 0.7);
        let yc = y0 + (y1 - y0) * r.range(0.45, 0.7);
        vec![
            lo,
            DVec2::new(x1, y0),
            DVec2::new(x1, yc),
            DVec2::new(xc, yc),
            DVec2::new(xc, y1),
            DVec2::new(x0, y1),
        ]
    } else {
        let xa = x0 + (x1 - x0) * r.range(0.3, 0.4);
        let xb = x0 + (x1 - x0) * r.range(0.6, 0.7);
        let yn = y1 - (y1 - y0) * r.range(0.3, 0.5);
        vec![
            lo,
            DVec2::new(x1, y0),
            hi,
            DVec2::new(xb, y1),
            DVec2::new(xb, yn),
            DVec2::new(xa, yn),
            DVec2::new(xa, y1),
            DVec2::new(x0, y1),
        ]
    };
    // Mirror so yards and notches face every direction.
    if r.chance(0.5) {
        ring.iter_mut().for_each(|v| v.x = x0 + x1 - v.x);
    }
    if r.chance(0.5) {
        ring.iter_mut().for_each(|v| v.y = y0 + y1 - v.y);
    }
    ring
}

/// A tower set back 2–4 m from its lot: a rectangle or a chamfered octagon.
fn tower_footprint(r: &mut Rng, lo: DVec2, hi: DVec2) -> Vec<DVec2> {
    let s = r.range(2.0, 4.0).min(0.25 * (hi - lo).min_element());
    let (lo, hi) = (lo + DVec2::splat(s), hi - DVec2::splat(s));
    let (x0, y0, x1, y1) = (lo.x, lo.y, hi.x, hi.y);
    if r.chance(0.4) {
        return vec![lo, DVec2::new(x1, y0), hi, DVec2::new(x0, y1)];
    }
    let c = 0.25 * (hi - lo).min_element();
    vec![
        DVec2::new(x0 + c, y0),
        DVec2::new(x1 - c, y0),
        DVec2::new(x1, y0 + c),
        DVec2::new(x1, y1 - c),
        DVec2::new(x1 - c, y1),
        DVec2::new(x0 + c, y1),
        DVec2::new(x0, y1 - c),
        DVec2::new(x0, y0 + c),
    ]
}
