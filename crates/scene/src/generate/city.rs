//! `city`: a Vienna-like old town.
//!
//! Layout, in the spirit of a medieval core grown over a Roman grid:
//! * a perturbed grid of street crossings (jittered and gently bent, so blocks are
//!   irregular convex quads and streets are not straight lines);
//! * every grid line is a street with its own width (lanes of 6 m to boulevards of
//!   16 m), and the outer lines form a wide "Ring" (28 m);
//! * a street block is its quad inset by half the width of each street around it;
//!   large blocks are a ring of buildings around a courtyard (perimeter block), small
//!   ones are cut into rows of narrow houses. Neighbouring buildings **touch along party
//!   walls**: they share the very same vertices, so their footprints share edges exactly
//!   (the case of erosion paper §4 that real cities are full of: erosion must act on their union);
//! * the central block and a few others are squares (flat objects), often with a
//!   church: a nave and a tall tower that touch;
//! * a few blocks get a tower (40–80 m) among their 10–25 m houses;
//! * each street line is a flat object (the ground people stand on).
//!
//! Objects: the requested number of buildings first (nearest to the centre first), then
//! the flat squares and streets.

use super::{snap_cm, snap_ring, Rng};
use crate::{Object, Scene};
use sightline_geom::{DVec2, Polygon};

/// Parameters of [`city_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct CityParams {
    /// Number of buildings (exactly this many block objects are produced).
    pub buildings: usize,
    /// Mean distance between street axes, in metres.
    pub block_pitch_m: f64,
    /// Jitter of the street crossings, as a fraction of the pitch.
    pub jitter: f64,
    /// Probability that a built block has one tower.
    pub tower_probability: f64,
    /// Probability that a block (other than the central one) is a square.
    pub square_probability: f64,
    /// Emit the streets and squares as flat objects.
    pub flats: bool,
}

impl Default for CityParams {
    fn default() -> Self {
        CityParams {
            buildings: 500,
            block_pitch_m: 85.0,
            jitter: 0.14,
            tower_probability: 0.08,
            square_probability: 0.08,
            flats: true,
        }
    }
}

/// A Vienna-like old town with `n_buildings` buildings (default parameters otherwise).
pub fn city(seed: u64, n_buildings: usize) -> Scene {
    city_with(
        seed,
        &CityParams {
            buildings: n_buildings,
            ..CityParams::default()
        },
    )
}

/// A Vienna-like old town with explicit parameters.
pub fn city_with(seed: u64, p: &CityParams) -> Scene {
    if p.buildings == 0 {
        return Scene::from_objects(vec![]);
    }
    // About 16 buildings per perimeter block; grow the grid until the requested number fits.
    let mut g = ((p.buildings as f64 / 14.0).sqrt().ceil() as usize).max(1) + 1;
    loop {
        if let Some(scene) = try_city(seed, p, g) {
            return scene;
        }
        g += 1 + g / 4;
    }
}

/// One building before it becomes an object.
struct Lot {
    footprint: Vec<DVec2>,
    height: f64,
    name: String,
}

fn try_city(seed: u64, p: &CityParams, g: usize) -> Option<Scene> {
    let mut rng = Rng::derive(seed, 0xC17);
    let s = p.block_pitch_m;
    let n1 = g + 1;
    let node_id = |i: usize, j: usize| j * n1 + i;

    // Street crossings: regular grid, bent by two slow waves and jittered.
    let (ph1, ph2) = (rng.range(0.0, 6.3), rng.range(0.0, 6.3));
    let mut nodes = Vec::with_capacity(n1 * n1);
    for j in 0..n1 {
        for i in 0..n1 {
            let bend = DVec2::new(
                0.22 * s * (j as f64 * 0.7 + ph1).sin(),
                0.22 * s * (i as f64 * 0.6 + ph2).sin(),
            );
            let jit = DVec2::new(
                rng.range(-p.jitter, p.jitter),
                rng.range(-p.jitter, p.jitter),
            ) * s;
            nodes.push(DVec2::new(i as f64 * s, j as f64 * s) + bend + jit);
        }
    }

    // Street widths: one per grid line, varied a little per edge; the outer lines are the Ring.
    let line_width = |rng: &mut Rng, k: usize| -> f64 {
        if k == 0 || k == g {
            28.0
        } else {
            [6.0, 7.0, 8.0, 9.0, 10.0, 12.0, 16.0][rng.below(7)]
        }
    };
    let row_w: Vec<f64> = (0..n1).map(|j| line_width(&mut rng, j)).collect();
    let col_w: Vec<f64> = (0..n1).map(|i| line_width(&mut rng, i)).collect();
    // Horizontal edge (i,j)-(i+1,j) and vertical edge (i,j)-(i,j+1) widths.
    let h_w: Vec<f64> = (0..n1 * g)
        .map(|k| row_w[k / g] * rng.range(0.85, 1.15))
        .collect();
    let v_w: Vec<f64> = (0..n1 * g)
        .map(|k| col_w[k / g] * rng.range(0.85, 1.15))
        .collect();
    let hw = |i: usize, j: usize| h_w[j * g + i];
    let vw = |i: usize, j: usize| v_w[i * g + j];

    // Blocks, nearest to the centre first.
    let centre = nodes.iter().copied().sum::<DVec2>() / nodes.len() as f64;
    let mut blocks: Vec<(f64, usize, usize)> = Vec::with_capacity(g * g);
    for j in 0..g {
        for i in 0..g {
            let c = (nodes[node_id(i, j)]
                + nodes[node_id(i + 1, j)]
                + nodes[node_id(i + 1, j + 1)]
                + nodes[node_id(i, j + 1)])
                * 0.25;
            blocks.push((c.distance_squared(centre), i, j));
        }
    }
    blocks.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)).then(a.1.cmp(&b.1)));

    let mut buildings: Vec<Lot> = Vec::with_capacity(p.buildings);
    let mut squares: Vec<(String, Polygon)> = Vec::new();
    let mut used = vec![false; g * g];
    for (rank, &(_, i, j)) in blocks.iter().enumerate() {
        if buildings.len() >= p.buildings {
            break;
        }
        let quad = [
            nodes[node_id(i, j)],
            nodes[node_id(i + 1, j)],
            nodes[node_id(i + 1, j + 1)],
            nodes[node_id(i, j + 1)],
        ];
        let insets = [
            hw(i, j) / 2.0,
            vw(i + 1, j) / 2.0,
            hw(i, j + 1) / 2.0,
            vw(i, j) / 2.0,
        ];
        let Some(plot) = inset(&quad, insets) else {
            continue;
        };
        let mut brng = Rng::derive(seed, (j * g + i) as u64 + 1);
        let tag = format!("{i}-{j}");
        let is_square = rank == 0 || brng.chance(p.square_probability);
        let lots = if is_square {
            squares.push((format!("square-{tag}"), Polygon::new(plot.to_vec(), vec![])));
            church(&mut brng, &plot, rank == 0, &tag)
        } else {
            perimeter_block(&mut brng, &plot, p, &tag)
        };
        used[j * g + i] = true;
        let room = p.buildings - buildings.len();
        buildings.extend(lots.into_iter().take(room));
    }
    if buildings.len() < p.buildings {
        return None;
    }

    let mut objects: Vec<Object> = buildings
        .into_iter()
        .map(|l| {
            let footprint = Polygon::new(snap_ring(l.footprint), vec![]);
            Object::block(Some(l.name), footprint, 0.0, snap_cm(l.height))
        })
        .collect();
    if p.flats {
        for (name, poly) in squares {
            let poly = Polygon::new(snap_ring(poly.exterior), vec![]);
            objects.push(Object::flat(Some(name), vec![poly]));
        }
        // Streets: one flat object per grid line, a strip per edge between crossings.
        let strip = |a: DVec2, b: DVec2, w: f64| -> Polygon {
            let n = (b - a).normalize().perp() * (w / 2.0);
            Polygon::new(snap_ring(vec![a - n, b - n, b + n, a + n]), vec![])
        };
        // Only the streets along blocks in use, so the scene ends where the town does.
        let block_used = |i: usize, j: usize| i < g && j < g && used[j * g + i];
        let h_used = |i: usize, j: usize| block_used(i, j) || (j > 0 && block_used(i, j - 1));
        let v_used = |i: usize, j: usize| block_used(i, j) || (i > 0 && block_used(i - 1, j));
        for j in 0..n1 {
            let polys: Vec<Polygon> = (0..g)
                .filter(|&i| h_used(i, j))
                .map(|i| strip(nodes[node_id(i, j)], nodes[node_id(i + 1, j)], hw(i, j)))
                .collect();
            if !polys.is_empty() {
                objects.push(Object::flat(Some(format!("street-row-{j}")), polys));
            }
        }
        for i in 0..n1 {
            let polys: Vec<Polygon> = (0..g)
                .filter(|&j| v_used(i, j))
                .map(|j| strip(nodes[node_id(i, j)], nodes[node_id(i, j + 1)], vw(i, j)))
                .collect();
            if !polys.is_empty() {
                objects.push(Object::flat(Some(format!("street-col-{i}")), polys));
            }
        }
    }
    Some(Scene::from_objects(objects))
}

/// A perimeter block: buildings around a courtyard when the plot is deep enough,
/// otherwise a row of houses across the plot. Neighbours share their cut vertices.
fn perimeter_block(rng: &mut Rng, plot: &[DVec2; 4], p: &CityParams, tag: &str) -> Vec<Lot> {
    let block_h = rng.range(14.0, 22.0);
    let mut footprints: Vec<Vec<DVec2>> = Vec::new();
    let depths = [
        rng.range(10.0, 16.0),
        rng.range(10.0, 16.0),
        rng.range(10.0, 16.0),
        rng.range(10.0, 16.0),
    ];
    let court = inset(plot, depths)
        .filter(|c| ring_area(c) >= 120.0 && (0..4).all(|k| c[k].distance(c[(k + 1) % 4]) >= 8.0));
    let mut courtyard_building = None;
    match court {
        Some(inner) => {
            // Four trapezoids between the plot edge k and the courtyard edge k, each cut
            // into houses; cut points are computed once and shared by both neighbours.
            for k in 0..4 {
                let (o0, o1) = (plot[k], plot[(k + 1) % 4]);
                let (i0, i1) = (inner[k], inner[(k + 1) % 4]);
                let cuts = cut_params(rng, o0.distance(o1), 12.0, 22.0);
                let po = points_along(o0, o1, &cuts);
                let pi = points_along(i0, i1, &cuts);
                for m in 0..cuts.len() - 1 {
                    footprints.push(vec![po[m], po[m + 1], pi[m + 1], pi[m]]);
                }
            }
            // Sometimes a low workshop stands free in the courtyard.
            if rng.chance(0.3) {
                courtyard_building = inset(&inner, [4.0; 4]).filter(|c| ring_area(c) >= 30.0);
            }
        }
        None => {
            // A row of houses across the longer direction.
            let k = if plot[0].distance(plot[1]) + plot[3].distance(plot[2])
                >= plot[1].distance(plot[2]) + plot[0].distance(plot[3])
            {
                0
            } else {
                1
            };
            let (a0, a1) = (plot[k], plot[k + 1]);
            let (b0, b1) = (plot[(k + 3) % 4], plot[k + 2]);
            let cuts = cut_params(rng, a0.distance(a1), 10.0, 18.0);
            let pa = points_along(a0, a1, &cuts);
            let pb = points_along(b0, b1, &cuts);
            for m in 0..cuts.len() - 1 {
                footprints.push(vec![pa[m], pa[m + 1], pb[m + 1], pb[m]]);
            }
        }
    }
    let tower = if rng.chance(p.tower_probability) && !footprints.is_empty() {
        Some(rng.below(footprints.len()))
    } else {
        None
    };
    let mut lots: Vec<Lot> = footprints
        .into_iter()
        .enumerate()
        .map(|(m, footprint)| {
            let (height, kind) = if tower == Some(m) {
                (rng.range(40.0, 80.0), "tower")
            } else {
                ((block_h + rng.range(-4.0, 4.0)).clamp(10.0, 25.0), "house")
            };
            Lot {
                footprint,
                height,
                name: format!("{kind}-{tag}-{m}"),
            }
        })
        .collect();
    if let Some(c) = courtyard_building {
        lots.push(Lot {
            footprint: c.to_vec(),
            height: rng.range(4.0, 7.0),
            name: format!("workshop-{tag}"),
        });
    }
    lots
}

/// A church on a square: a nave and a tower of the nave's width touching its west end
/// (they share one full edge). `main` makes it the cathedral of the central square.
fn church(rng: &mut Rng, plot: &[DVec2; 4], main: bool, tag: &str) -> Vec<Lot> {
    if !main && !rng.chance(0.5) {
        return vec![];
    }
    let k = (0..4)
        .max_by(|&a, &b| {
            let la = plot[a].distance(plot[(a + 1) % 4]);
            let lb = plot[b].distance(plot[(b + 1) % 4]);
            la.total_cmp(&lb)
        })
        .unwrap_or(0);
    let u = (plot[(k + 1) % 4] - plot[k]).normalize();
    let v = u.perp();
    let c = plot.iter().copied().sum::<DVec2>() / 4.0;
    let (mut len, mut w) = if main {
        (rng.range(45.0, 60.0), rng.range(18.0, 22.0))
    } else {
        (rng.range(28.0, 40.0), rng.range(12.0, 16.0))
    };
    let nave_h = rng.range(18.0, 26.0);
    let tower_h = if main {
        rng.range(65.0, 80.0)
    } else {
        rng.range(40.0, 60.0)
    };
    for _ in 0..6 {
        let x0 = -(len + w) / 2.0; // tower west face
        let x1 = x0 + w; // tower/nave shared wall
        let x2 = x1 + len; // nave east end
        let at = |x: f64, y: f64| c + u * x + v * y;
        let (s0, s1) = (at(x1, -w / 2.0), at(x1, w / 2.0));
        let nave = vec![s0, at(x2, -w / 2.0), at(x2, w / 2.0), s1];
        let tower = vec![at(x0, -w / 2.0), s0, s1, at(x0, w / 2.0)];
        let margin = 3.0;
        let fits = nave
            .iter()
            .chain(&tower)
            .all(|q| inside_convex(plot, *q, margin));
        if fits {
            return vec![
                Lot {
                    footprint: nave,
                    height: nave_h,
                    name: format!("church-{tag}"),
                },
                Lot {
                    footprint: tower,
                    height: tower_h,
                    name: format!("church-tower-{tag}"),
                },
            ];
        }
        len *= 0.8;
        w *= 0.85;
    }
    vec![]
}

/// Cut parameters 0 = t0 < t1 < … < tm = 1 for a frontage of `len` metres cut into
/// houses of `lo..hi` metres.
fn cut_params(rng: &mut Rng, len: f64, lo: f64, hi: f64) -> Vec<f64> {
    let m = ((len / rng.range(lo, hi)).round() as usize).max(1);
    let mut t: Vec<f64> = (0..=m)
        .map(|i| {
            if i == 0 || i == m {
                i as f64 / m as f64
            } else {
                (i as f64 + rng.range(-0.25, 0.25)) / m as f64
            }
        })
        .collect();
    t[m] = 1.0;
    t
}

/// Points at parameters `t` along `a → b`, with the end points exactly `a` and `b`.
fn points_along(a: DVec2, b: DVec2, t: &[f64]) -> Vec<DVec2> {
    let last = t.len() - 1;
    t.iter()
        .enumerate()
        .map(|(i, &t)| match i {
            0 => a,
            i if i == last => b,
            _ => a + (b - a) * t,
        })
        .collect()
}

/// The convex quad `q` (counter-clockwise) with edge `k` moved inwards by `d[k]`, or
/// None when the result degenerates (an edge flips or vanishes).
pub(crate) fn inset(q: &[DVec2; 4], d: [f64; 4]) -> Option<[DVec2; 4]> {
    let line = |k: usize| {
        let a = q[k];
        let dir = (q[(k + 1) % 4] - a).normalize();
        (a + dir.perp() * d[k], dir)
    };
    let mut out = [DVec2::ZERO; 4];
    for (k, corner) in out.iter_mut().enumerate() {
        let (p1, d1) = line((k + 3) % 4);
        let (p2, d2) = line(k);
        let den = d1.perp_dot(d2);
        if den.abs() < 1e-9 {
            return None;
        }
        let t = (p2 - p1).perp_dot(d2) / den;
        *corner = p1 + d1 * t;
    }
    let same_direction =
        (0..4).all(|k| (out[(k + 1) % 4] - out[k]).dot(q[(k + 1) % 4] - q[k]) > 0.0);
    (same_direction && ring_area(&out) > 1.0 && out.iter().all(|p| p.is_finite())).then_some(out)
}

fn ring_area(r: &[DVec2]) -> f64 {
    sightline_geom::polygon::ring_signed_area(r)
}

/// Whether `p` is inside the convex counter-clockwise quad at least `margin` from its edges.
fn inside_convex(q: &[DVec2; 4], p: DVec2, margin: f64) -> bool {
    (0..4).all(|k| {
        let (a, b) = (q[k], q[(k + 1) % 4]);
        let dir = (b - a).normalize();
        dir.perp_dot(p - a) >= margin
    })
}
