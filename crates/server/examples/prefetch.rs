//! Does prefetch keep the next cell's PVS in hand? (dual ray space paper, §6, Fig. 5)
//!
//! A walker follows a random path through the scene at a given speed; the server's prefetch
//! policy ([`sightline_server::walk`]) feeds a pool of `--workers` workers:
//! * `--policy fig5`: the paper's — the cell and its 8 neighbours at start, then on each cell
//!   change the neighbours not yet sent, ahead first, and two cells ahead at speed, first
//!   come first served after demands;
//! * `--policy ahead` (the server's, default): the same, plus on every step the cell the
//!   motion leads into ([`CellGrid::next_cell`]) goes before every other prefetch, and on a
//!   cell change the queued jobs for cells no longer adjacent are withdrawn.
//!
//! Compute times are **real**: every cell the policy asks for is computed by the method on
//! this machine and timed; the clock the walker and the workers live on is simulated, so
//! that an hour of walking at 1.5 m/s takes only as long as computing the cells it needs.
//! The cells are computed one after the other (the simulated workers overlap in simulated
//! time only), so on a machine whose cores are all busy the real pool is slower than this
//! by up to the number of workers; `examples/load.rs` with one walker against a real
//! `sightline serve` measures the same figure in real time. A cell change is a hit when the
//! new cell's PVS was finished before the walker entered it (loopback transmission is
//! neglected: milliseconds against the seconds a 100 m cell takes to cross).
//!
//! ```text
//! cargo run --release -p sightline-server --example prefetch -- SCENE \
//!     [--method erosion] [--cell-size 100] [--speed 1.5] [--changes 100] [--workers 2] [--seed 1]
//!     [--policy ahead|fig5]
//! ```

use sightline_geom::{DVec2, DVec3};
use sightline_scene::import::{load, ImportOptions};
use sightline_server::grid::{CellGrid, CellId};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;
use std::time::Instant;

struct Args {
    scene: String,
    method: String,
    cell_size: f64,
    speed: f64,
    changes: usize,
    workers: usize,
    seed: u64,
    ahead: bool,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        scene: String::new(),
        method: "erosion".into(),
        cell_size: 100.0,
        speed: 1.5,
        changes: 100,
        workers: 2,
        seed: 1,
        ahead: true,
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or(format!("{k} needs a value"));
        match k.as_str() {
            "--method" => a.method = v()?,
            "--cell-size" => a.cell_size = v()?.parse().map_err(|e| format!("{e}"))?,
            "--speed" => a.speed = v()?.parse().map_err(|e| format!("{e}"))?,
            "--changes" => a.changes = v()?.parse().map_err(|e| format!("{e}"))?,
            "--workers" => a.workers = v()?.parse().map_err(|e| format!("{e}"))?,
            "--seed" => a.seed = v()?.parse().map_err(|e| format!("{e}"))?,
            "--policy" => {
                a.ahead = match v()?.as_str() {
                    "ahead" => true,
                    "fig5" => false,
                    p => return Err(format!("unknown policy {p} (ahead, fig5)")),
                }
            }
            s if !s.starts_with("--") && a.scene.is_empty() => a.scene = s.to_string(),
            s => return Err(format!("unknown argument {s}")),
        }
    }
    if a.scene.is_empty() {
        return Err("usage: prefetch SCENE [--method M] [--cell-size S] [--speed V] [--changes N] [--workers W] [--seed S] [--policy ahead|fig5]".into());
    }
    Ok(a)
}

/// Job priorities, as [`sightline_server::cache::Priority`].
const DEMAND: u8 = 0;
const AHEAD: u8 = 1;
const PREFETCH: u8 = 2;

/// Simulated server: jobs by priority (demand first, then request order) on `workers`.
struct Sim<'a> {
    method: &'a dyn sightline_methods::VisibilityMethod,
    grid: &'a CellGrid,
    workers: Vec<f64>,
    /// cell → simulated time its PVS is in the client's hands.
    ready: HashMap<CellId, f64>,
    queued: BTreeMap<(u8, u64), (CellId, f64)>,
    seq: u64,
    sent: HashSet<CellId>,
    compute_s: Vec<f64>,
    sizes: Vec<usize>,
    cancelled: usize,
}

impl Sim<'_> {
    /// Request `cell` at `prio`, or move its queued job up to `prio`.
    fn promote(&mut self, cell: CellId, prio: u8, t: f64) {
        if !self.sent.contains(&cell) {
            return self.request(cell, prio, t);
        }
        let Some(k) = self
            .queued
            .iter()
            .find(|(k, v)| v.0 == cell && k.0 > prio)
            .map(|(k, _)| *k)
        else {
            return;
        };
        if let Some(v) = self.queued.remove(&k) {
            self.seq += 1;
            self.queued.insert((prio, self.seq), v);
        }
    }

    /// Withdraw the queued jobs of cells not in `keep`.
    fn withdraw_except(&mut self, keep: &[CellId]) {
        let before = self.queued.len();
        let mut gone = vec![];
        self.queued.retain(|_, v| {
            let k = keep.contains(&v.0);
            if !k {
                gone.push(v.0);
            }
            k
        });
        for c in gone {
            self.sent.remove(&c);
        }
        self.cancelled += before - self.queued.len();
    }

    fn request(&mut self, cell: CellId, prio: u8, t: f64) {
        if self.sent.insert(cell) {
            self.seq += 1;
            self.queued.insert((prio, self.seq), (cell, t));
        }
    }

    /// Run queued jobs that start before `until` (a worker is free and the job was
    /// requested).
    fn run_until(&mut self, until: f64) {
        loop {
            let (wi, free) = self
                .workers
                .iter()
                .copied()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, f64::INFINITY));
            // The best job already requested when this worker frees up.
            let pick = self
                .queued
                .iter()
                .filter(|(_, (_, at))| *at <= free.max(0.0) || *at <= until)
                .map(|(k, v)| (*k, *v))
                .next();
            let Some((key, (cell, at))) = pick else {
                return;
            };
            let start = free.max(at);
            if start > until {
                return;
            }
            self.queued.remove(&key);
            let Some(bx) = self.grid.cell(cell) else {
                continue;
            };
            let t0 = Instant::now();
            let n = self.method.pvs(&bx).map(|v| v.len()).unwrap_or(0);
            let dt = t0.elapsed().as_secs_f64();
            self.compute_s.push(dt);
            self.sizes.push(n);
            self.workers[wi] = start + dt;
            self.ready.insert(cell, start + dt);
        }
    }
}

fn main() {
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let t_load = Instant::now();
    let scene = match load(std::path::Path::new(&a.scene), &ImportOptions::default()) {
        Ok(s) => Arc::new(s),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    eprintln!(
        "loaded {} objects in {:.1} s",
        scene.len(),
        t_load.elapsed().as_secs_f64()
    );
    let t_prep = Instant::now();
    let method = match sightline_methods::create(&a.method, scene.clone(), &Default::default()) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    eprintln!(
        "prepared {} in {:.1} s",
        a.method,
        t_prep.elapsed().as_secs_f64()
    );
    let grid = match CellGrid::cover(&scene.bounds, a.cell_size) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let mut rng = sightline_stats::Rng::new(a.seed);
    let lo = DVec2::from_array(grid.origin);
    let hi = grid.max();
    let mut p = lo + (hi - lo) * DVec2::new(0.3 + 0.4 * rng.f64(), 0.3 + 0.4 * rng.f64());
    let mut heading = rng.f64() * std::f64::consts::TAU;
    let mut sim = Sim {
        method: method.as_ref(),
        grid: &grid,
        workers: vec![0.0; a.workers.max(1)],
        ready: HashMap::new(),
        queued: BTreeMap::new(),
        seq: 0,
        sent: HashSet::new(),
        compute_s: vec![],
        sizes: vec![],
        cancelled: 0,
    };
    let cell_of = |p: DVec2| grid.locate(DVec3::new(p.x, p.y, 1.7)).ok();
    let Some(mut cell) = cell_of(p) else { return };
    let mut t = 0.0;
    sim.request(cell, DEMAND, t);
    for n in grid.neighbours(cell, DVec2::ZERO) {
        sim.request(n, PREFETCH, t);
    }
    let dt = 1.0; // s per walking step
    let (mut changes, mut hits, mut waits) = (0usize, 0usize, vec![]);
    let wall = Instant::now();
    while changes < a.changes {
        if rng.f64() < 0.02 {
            heading += (rng.f64() - 0.5) * std::f64::consts::PI;
        }
        let dir = DVec2::new(heading.cos(), heading.sin());
        let mut q = p + dir * a.speed * dt;
        if q.x < lo.x || q.y < lo.y || q.x > hi.x || q.y > hi.y {
            heading += std::f64::consts::PI * (0.5 + rng.f64());
            q = p;
        }
        t += dt;
        sim.run_until(t);
        p = q;
        if a.ahead {
            if let Some(n) = grid.next_cell(p, dir) {
                if !sim.ready.contains_key(&n) {
                    sim.promote(n, AHEAD, t);
                }
            }
        }
        let Some(c) = cell_of(p) else { continue };
        if c != cell {
            changes += 1;
            let ready_at = sim.ready.get(&c).copied();
            if sim.sent.contains(&c) && ready_at.is_some_and(|r| r <= t) {
                hits += 1;
            } else {
                // Not in hand: demand it now (promoted if queued) and measure the wait.
                sim.promote(c, DEMAND, t);
                while !sim.ready.contains_key(&c) {
                    let before = sim.queued.len();
                    sim.run_until(f64::INFINITY.min(t + 1e6));
                    if sim.queued.len() == before && !sim.ready.contains_key(&c) {
                        break;
                    }
                }
                waits.push(sim.ready.get(&c).copied().unwrap_or(t) - t);
            }
            cell = c;
            let fast = a.speed > 0.05 * grid.cell_size_m;
            let mut next = grid.neighbours(cell, dir);
            if fast {
                if let Some(x) = grid.ahead(cell, dir, 2) {
                    next.insert(1.min(next.len()), x);
                }
            }
            if a.ahead {
                let mut keep = next.clone();
                keep.push(cell);
                sim.withdraw_except(&keep);
            }
            for n in next {
                sim.request(n, PREFETCH, t);
            }
        }
    }
    let mut cs = sim.compute_s.clone();
    cs.sort_by(f64::total_cmp);
    let med = |v: &[f64]| v.get(v.len() / 2).copied().unwrap_or(0.0);
    let p90 = |v: &[f64]| v.get(v.len() * 9 / 10).copied().unwrap_or(0.0);
    let mut sz = sim.sizes.clone();
    sz.sort_unstable();
    waits.sort_by(f64::total_cmp);
    println!(
        "prefetch: scene {} ({} objects), method {}, {} m cells, speed {} m/s ({:.0} s per cell), {} workers\n  \
         cell changes {changes}, PVS in hand on entry {hits} ({:.1} %), waits when not: median {:.1} s, max {:.1} s\n  \
         policy {}, cells computed {} (withdrawn before start {}), compute per cell median {:.2} s, p90 {:.2} s, max {:.2} s; PVS size median {}, p90 {}\n  \
         simulated walk {:.0} s, wall time {:.0} s",
        a.scene,
        scene.len(),
        a.method,
        a.cell_size,
        a.speed,
        a.cell_size / a.speed,
        sim.workers.len(),
        100.0 * hits as f64 / changes.max(1) as f64,
        med(&waits),
        waits.last().copied().unwrap_or(0.0),
        if a.ahead { "ahead" } else { "fig5" },
        cs.len(),
        sim.cancelled,
        med(&cs),
        p90(&cs),
        cs.last().copied().unwrap_or(0.0),
        sz.get(sz.len() / 2).copied().unwrap_or(0),
        sz.get(sz.len() * 9 / 10).copied().unwrap_or(0),
        t,
        wall.elapsed().as_secs_f64(),
    );
}
