//! A level's PVS against its own reference (the `vis` lump Quake's tools computed) and
//! against the ray oracle: the figures of `check LEVEL.bsp --reference vis` and of the
//! `portals_levels` example.

use crate::oracle::{pair_visible, sample_leaf, Rng};
use crate::{LeafPvs, Mode, Portals};
use serde::Serialize;
use sightline_scene::import::bsp::BspLevel;

/// The comparison of one level's leaf and face PVS with its reference and the oracle.
#[derive(Clone, Debug, Default, Serialize)]
pub struct VisReport {
    pub visleafs: u32,
    pub portals: usize,
    pub mode: &'static str,
    /// Σ|PVS| over the view leaves (leaves), and the reference's Σ.
    pub leaves_ours: usize,
    pub leaves_reference: usize,
    /// Σ faces over the view leaves, and Σ faces of the reference's visible leaves.
    pub faces_ours: usize,
    pub faces_reference: usize,
    /// Leaf pairs the reference has and we lack.
    pub reference_only_pairs: usize,
    /// Of those, pairs the oracle found a clear segment for (each a miss).
    pub reference_only_clear: usize,
    /// Source leaves checked against the oracle, and pairs we call hidden that the
    /// oracle found a clear segment for (misses: must be 0).
    pub sources: usize,
    pub missed_pairs: usize,
    pub seconds: f64,
}

impl VisReport {
    pub fn leaves_ratio(&self) -> f64 {
        self.leaves_ours as f64 / self.leaves_reference.max(1) as f64
    }
    pub fn faces_ratio(&self) -> f64 {
        self.faces_ours as f64 / self.faces_reference.max(1) as f64
    }
}

/// One view leaf's PVS sizes next to the reference's (the points of `bench`'s plot).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LeafSizes {
    pub leaf: u32,
    /// |PVS| in leaves, and the reference row's size.
    pub leaves_ours: usize,
    pub leaves_reference: usize,
    /// Faces kept, and the faces of the reference's visible leaves.
    pub faces_ours: usize,
    pub faces_reference: usize,
}

/// The sizes of every view leaf's PVS (`all`, indexed by leaf as
/// [`Portals::solve_all`] gives them) against the level's reference rows, ascending by
/// leaf. Leaves `all` does not cover are skipped.
pub fn leaf_sizes(level: &BspLevel, all: &[LeafPvs]) -> Vec<LeafSizes> {
    view_leaves(level)
        .into_iter()
        .filter_map(|leaf| {
            let ours = all.get(leaf as usize)?;
            let row = level.reference_row(leaf);
            let mut ref_faces: Vec<u32> = row
                .iter()
                .filter_map(|&l| level.leaves.get(l as usize))
                .flat_map(|l| l.faces.iter().copied())
                .collect();
            ref_faces.sort_unstable();
            ref_faces.dedup();
            Some(LeafSizes {
                leaf,
                leaves_ours: ours.leaves.len(),
                leaves_reference: row.len(),
                faces_ours: ours.faces.len(),
                faces_reference: ref_faces.len(),
            })
        })
        .collect()
}

fn view_leaves(level: &BspLevel) -> Vec<u32> {
    (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .collect()
}

/// Compare the PVS of every view leaf (`mode`) with the reference, and `sources` source
/// leaves (spread evenly) with the oracle: `segments` random segments per pair we call
/// hidden (256 at least for the pairs the reference has).
pub fn compare_with_reference(
    portals: &Portals,
    mode: Mode,
    sources: usize,
    segments: usize,
) -> VisReport {
    let t = std::time::Instant::now();
    let all: Vec<LeafPvs> = portals.solve_all(mode);
    let mut r = compare_sets(portals, &all, mode, sources, segments);
    r.seconds = t.elapsed().as_secs_f64();
    r
}

/// [`compare_with_reference`] on sets already solved (`all`, indexed by leaf, as
/// [`Portals::solve_all`]`(mode)` gives them): for callers that time the solve
/// themselves. `seconds` is the comparison's own time.
pub fn compare_sets(
    portals: &Portals,
    all: &[LeafPvs],
    mode: Mode,
    sources: usize,
    segments: usize,
) -> VisReport {
    let t = std::time::Instant::now();
    let level = portals.level();
    let mut r = VisReport {
        visleafs: level.visleafs,
        portals: portals.portals().len(),
        mode: match mode {
            Mode::Full => "portals",
            Mode::Fast => "portals-fast",
        },
        ..VisReport::default()
    };
    for s in leaf_sizes(level, all) {
        r.leaves_ours += s.leaves_ours;
        r.leaves_reference += s.leaves_reference;
        r.faces_ours += s.faces_ours;
        r.faces_reference += s.faces_reference;
    }
    let open = view_leaves(level);
    let mut rng = Rng::new(7);
    let points: Vec<Vec<[f64; 3]>> = (0..=level.visleafs)
        .map(|l| {
            if level.is_view_leaf(l) {
                sample_leaf(level, l, 16, &mut rng)
            } else {
                Vec::new()
            }
        })
        .collect();
    let k = sources.min(open.len());
    r.sources = k;
    for i in 0..k {
        let s = open[i * open.len() / k];
        let row = level.reference_row(s);
        let Some(pvs) = all.get(s as usize) else {
            continue;
        };
        for &other in &open {
            if pvs.leaves.binary_search(&other).is_ok() {
                continue;
            }
            let in_ref = row.binary_search(&other).is_ok();
            let segs = if in_ref { segments.max(256) } else { segments };
            let clear = pair_visible(
                level,
                &points[s as usize],
                &points[other as usize],
                segs,
                &mut rng,
            );
            if in_ref {
                r.reference_only_pairs += 1;
                r.reference_only_clear += usize::from(clear);
            }
            r.missed_pairs += usize::from(clear);
        }
    }
    r.seconds = t.elapsed().as_secs_f64();
    r
}
