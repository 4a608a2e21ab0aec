//! The portal solver on real Quake levels (`data/quake/`), checked against the ray
//! oracle (no clear segment may join a pair the PVS lacks, no clear segment may reach
//! the front of a face the PVS drops) and against the level's own `vis`.

use sightline_portals::oracle::{pair_visible, sample_leaf, segment_clear, Rng};
use sightline_portals::{LeafPvs, Mode, Portals};
use sightline_scene::import::bsp::{load_bsp, BspLevel};
use std::path::PathBuf;

fn level(name: &str) -> BspLevel {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/quake")
        .join(name);
    load_bsp(&path).unwrap()
}

/// `k` view leaves spread over the level.
fn sources(level: &BspLevel, k: usize) -> Vec<u32> {
    let open: Vec<u32> = (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .collect();
    (0..k).map(|i| open[i * open.len() / k]).collect()
}

/// Misses of `pvs` against the oracle: clear segments to leaves it lacks, and clear
/// segments to the front of faces it drops. Also checks that reference pairs we lack
/// have no clear segment.
fn oracle_misses(
    level: &BspLevel,
    pvs: &LeafPvs,
    points: &[Vec<[f64; 3]>],
    rng: &mut Rng,
) -> usize {
    let src = &points[pvs.leaf as usize];
    let reference = level.reference_row(pvs.leaf);
    let mut misses = 0;
    for other in 1..=level.visleafs {
        if pvs.leaves.binary_search(&other).is_ok() {
            continue;
        }
        let segs = if reference.binary_search(&other).is_ok() {
            256
        } else {
            16
        };
        if pair_visible(level, src, &points[other as usize], segs, rng) {
            eprintln!("miss: leaf {} sees leaf {other}", pvs.leaf);
            misses += 1;
        }
    }
    // Dropped faces of visible leaves: segments to points just in front of them.
    for &l in &pvs.leaves {
        for &f in &level.leaves[l as usize].faces {
            if pvs.faces.binary_search(&f).is_ok() {
                continue;
            }
            let face = &level.faces[f as usize];
            let plane = level.planes[face.plane as usize];
            let sign = if face.back { -1.0 } else { 1.0 };
            let n = plane.normal.map(|v| v * sign);
            let poly = &face.polygon;
            if poly.len() < 3 {
                continue;
            }
            for _ in 0..32 {
                let k = 1 + (rng.next_u64() as usize % (poly.len() - 2));
                let (mut a, mut b) = (rng.unit(), rng.unit());
                if a + b > 1.0 {
                    (a, b) = (1.0 - a, 1.0 - b);
                }
                let target: [f64; 3] = std::array::from_fn(|i| {
                    poly[0][i]
                        + a * (poly[k][i] - poly[0][i])
                        + b * (poly[k + 1][i] - poly[0][i])
                        + 0.05 * n[i]
                });
                let Some(&eye) = src.get(rng.next_u64() as usize % src.len().max(1)) else {
                    break;
                };
                let front = (0..3).map(|i| (eye[i] - target[i]) * n[i]).sum::<f64>() > 0.0;
                let two_sided = sightline_scene::import::bsp::is_liquid(&face.texture);
                if (front || two_sided) && segment_clear(level, eye, target) {
                    eprintln!("miss: leaf {} sees face {f} of leaf {l}", pvs.leaf);
                    misses += 1;
                    break;
                }
            }
        }
    }
    misses
}

fn leaf_points(level: &BspLevel, per_leaf: usize, rng: &mut Rng) -> Vec<Vec<[f64; 3]>> {
    (0..=level.visleafs)
        .map(|l| {
            if level.is_view_leaf(l) {
                sample_leaf(level, l, per_leaf, rng)
            } else {
                Vec::new()
            }
        })
        .collect()
}

fn contains(big: &[u32], small: &[u32]) -> bool {
    small.iter().all(|x| big.binary_search(x).is_ok())
}

#[test]
fn dm1_every_leaf_conservative_fast_contains_full_close_to_vis() {
    let level = level("dm1.bsp");
    let portals = Portals::build(&level).unwrap();
    let full = portals.solve_all(Mode::Full);
    let fast = portals.solve_all(Mode::Fast);
    let (mut sum_full, mut sum_fast, mut sum_ref) = (0, 0, 0);
    for leaf in 1..=level.visleafs {
        let (a, b) = (&full[leaf as usize], &fast[leaf as usize]);
        assert!(
            contains(&b.leaves, &a.leaves) && contains(&b.faces, &a.faces),
            "leaf {leaf}"
        );
        assert!(a.leaves.contains(&leaf));
        assert!(contains(&a.faces, &level.leaves[leaf as usize].faces));
        sum_full += a.leaves.len();
        sum_fast += b.leaves.len();
        sum_ref += level.reference_row(leaf).len();
    }
    let ratio = sum_full as f64 / sum_ref as f64;
    eprintln!(
        "dm1: {} portals, Σ full {sum_full}, fast {sum_fast}, ref {sum_ref} (×{ratio:.3})",
        portals.portals().len()
    );
    // Our portals are qbsp's (see the test below): as tight as the flow on the .prt.
    assert!(ratio < 1.005, "{ratio}");
    let mut rng = Rng::new(1);
    let points = leaf_points(&level, 8, &mut rng);
    // Solving one leaf gives the same answer as solving them all; the local solve
    // (its own portals' flows only, bounded by floods) lies within fast and is
    // conservative on its own (flows pruned by vis's rule are not nested: it need not
    // contain the level-wide answer).
    for leaf in sources(&level, 5) {
        assert_eq!(portals.solve(leaf, Mode::Full), full[leaf as usize]);
        let local = portals.solve_local(leaf);
        assert!(contains(&fast[leaf as usize].leaves, &local.leaves));
        assert!(contains(&fast[leaf as usize].faces, &local.faces));
        assert_eq!(oracle_misses(&level, &local, &points, &mut rng), 0);
    }
    let misses: usize = sources(&level, 20)
        .into_iter()
        .map(|s| oracle_misses(&level, &full[s as usize], &points, &mut rng))
        .sum();
    assert_eq!(misses, 0);
}

#[test]
fn e1m1_sampled_leaves_conservative() {
    // The level-wide flow of e1m1 takes minutes in the test profile on a shared
    // machine (see the example): here each source leaf is solved by the flows of its
    // own portals alone, which contain the full answer.
    let level = level("e1m1.bsp");
    let portals = Portals::build(&level).unwrap();
    let mut rng = Rng::new(2);
    let points = leaf_points(&level, 8, &mut rng);
    let mut misses = 0;
    let (mut sum_local, mut sum_ref) = (0, 0);
    for s in sources(&level, 20) {
        let local = portals.solve_local(s);
        let fast = portals.solve(s, Mode::Fast);
        assert!(contains(&fast.leaves, &local.leaves) && contains(&fast.faces, &local.faces));
        assert!(contains(&local.leaves, &[s]));
        sum_local += local.leaves.len();
        sum_ref += level.reference_row(s).len();
        misses += oracle_misses(&level, &local, &points, &mut rng);
    }
    eprintln!(
        "e1m1: {} portals; 20 leaves Σ local {sum_local}, ref {sum_ref}",
        portals.portals().len()
    );
    assert_eq!(misses, 0);
    assert!((sum_local as f64) < 1.5 * sum_ref as f64);
}

/// The tree's portalization gives exactly the portals qbsp wrote for dm1: the same
/// leaf pairs (one portal each) and the same area to float noise.
#[test]
fn dm1_portals_are_qbsps() {
    let level = level("dm1.bsp");
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.prt");
    let file = sightline_portals::prt::parse_prt(&std::fs::read(path).unwrap()).unwrap();
    let theirs = sightline_portals::prt::portals_for_level(&file, &level).unwrap();
    let ours = Portals::build(&level).unwrap();
    let pairs = |v: &mut dyn Iterator<Item = [u32; 2]>| {
        let mut s: Vec<[u32; 2]> = v
            .map(|mut l| {
                l.sort();
                l
            })
            .collect();
        s.sort();
        s
    };
    let a = pairs(&mut ours.portals().iter().map(|p| p.leaves));
    let b = pairs(&mut theirs.iter().map(|p| p.leaves));
    assert_eq!(a.len(), 1108);
    assert_eq!(a, b);
    let area = |w: &mut dyn Iterator<Item = f64>| w.sum::<f64>();
    let (x, y) = (
        area(&mut ours.portals().iter().map(|p| p.winding.area())),
        area(&mut theirs.iter().map(|p| p.winding.area())),
    );
    assert!((x - y).abs() < 1e-5 * y, "{x} {y}");
}
