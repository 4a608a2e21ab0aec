//! The `.prt` writer (`prt::prt_from_portals`, `Prt::to_text`): our portals written as
//! qbsp's PRT1 read back as the same portals, match the level's shipped `.prt`, and the
//! reader never panics on mutated writer output (one-line errors only).

use proptest::prelude::*;
use sightline_portals::portalize::{portalize, Portal};
use sightline_portals::prt::{parse_prt, portals_for_level, prt_from_portals};
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::{load_bsp, BspLevel};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::OnceLock;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/quake")
        .join(name)
}

fn dm1() -> &'static BspLevel {
    static L: OnceLock<BspLevel> = OnceLock::new();
    L.get_or_init(|| load_bsp(&data("dm1.bsp")).unwrap())
}

/// dm1's own portals written as PRT1 text.
fn dm1_text() -> &'static str {
    static T: OnceLock<String> = OnceLock::new();
    T.get_or_init(|| {
        let level = dm1();
        prt_from_portals(&portalize(level), level.visleafs)
            .unwrap()
            .to_text()
    })
}

/// Two portals are the same: leaves, points (in the same order or reversed), planes
/// pointing the same way.
fn same_portal(a: &Portal, b: &Portal) -> Result<(), String> {
    if a.leaves != b.leaves {
        return Err(format!("leaves {:?} / {:?}", a.leaves, b.leaves));
    }
    let (pa, pb) = (&a.winding.points, &b.winding.points);
    let reversed: Vec<_> = pb.iter().rev().copied().collect();
    if pa != pb && *pa != reversed {
        return Err(format!("points {pa:?} / {pb:?}"));
    }
    let (na, nb) = (a.plane.normal.normalize(), b.plane.normal.normalize());
    if na.dot(nb) < 1.0 - 1e-9 {
        return Err(format!("normals {na:?} / {nb:?}"));
    }
    let (da, db) = (
        a.plane.dist / a.plane.normal.length(),
        b.plane.dist / b.plane.normal.length(),
    );
    if (da - db).abs() > 1e-6 {
        return Err(format!("distances {da} / {db}"));
    }
    Ok(())
}

#[test]
fn dm1_portals_round_trip_through_the_writer() {
    let level = dm1();
    let ours = portalize(level);
    let text = dm1_text();
    let prt = parse_prt(text.as_bytes()).unwrap();
    assert_eq!(prt.leaves, level.visleafs);
    let back = portals_for_level(&prt, level).unwrap();
    assert_eq!(back.len(), ours.len());
    for (i, (a, b)) in ours.iter().zip(&back).enumerate() {
        same_portal(a, b).unwrap_or_else(|e| panic!("portal {i}: {e}"));
    }
    // Written again from what was read: the same text, and exactly the same portals.
    let again = prt_from_portals(&back, level.visleafs).unwrap().to_text();
    assert_eq!(again, text);
    let back2 = portals_for_level(&parse_prt(again.as_bytes()).unwrap(), level).unwrap();
    assert_eq!(back2, back);
}

/// The written file has the shipped `.prt`'s portals: the same leaf pairs, the same
/// area per pair; and the fast bound from it equals the one from the tree.
#[test]
fn dm1_written_prt_matches_the_shipped_one() {
    let level = dm1();
    let ours = parse_prt(dm1_text().as_bytes()).unwrap();
    let shipped = parse_prt(&std::fs::read(data("dm1.prt")).unwrap()).unwrap();
    assert_eq!(ours.leaves, shipped.leaves);
    assert_eq!(ours.portals.len(), shipped.portals.len());
    let pairs = |p: &sightline_portals::prt::Prt| {
        let mut m: BTreeMap<[u32; 2], f64> = BTreeMap::new();
        for q in &p.portals {
            let [a, b] = q.leaves;
            let pts: Vec<sightline_geom::DVec3> = q.points.iter().map(|v| (*v).into()).collect();
            let area = sightline_portals::winding::Winding::new(pts).area();
            *m.entry([a.min(b), a.max(b)]).or_default() += area;
        }
        m
    };
    let (a, b) = (pairs(&ours), pairs(&shipped));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, area) in &a {
        assert!(
            (area - b[k]).abs() < 0.01 * area.max(1.0),
            "{k:?}: {area} / {}",
            b[k]
        );
    }
    let from_prt = Portals::from_prt(level, &ours).unwrap();
    let from_tree = Portals::build(level).unwrap();
    assert_eq!(
        from_prt.solve_all(Mode::Fast),
        from_tree.solve_all(Mode::Fast)
    );
}

#[test]
fn the_writer_refuses_portals_outside_the_visleafs() {
    let level = dm1();
    let mut ours = portalize(level);
    ours[0].leaves[1] = level.visleafs + 1;
    let e = prt_from_portals(&ours, level.visleafs)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("not two of the visleafs") && !e.contains('\n'),
        "{e}"
    );
    ours[0].leaves[1] = 0;
    assert!(prt_from_portals(&ours, level.visleafs).is_err());
    let mut ours = portalize(level);
    ours[3].winding.points[1].x = f64::NAN;
    assert!(prt_from_portals(&ours, level.visleafs).is_err());
}

/// An edit of the writer's text: replace, insert or delete bytes at a place, or cut it.
#[derive(Clone, Debug)]
enum Edit {
    Replace(usize, u8),
    Insert(usize, u8),
    Delete(usize, usize),
    Truncate(usize),
    /// A line moved elsewhere (portal lines swapped with the header, say).
    MoveLine(usize, usize),
}

fn byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        3 => prop::sample::select(b"0123456789 ()-.+eEnaif\n\r\t".to_vec()),
        1 => any::<u8>(),
    ]
}

fn edit() -> impl Strategy<Value = Edit> {
    let at = 0..200_000usize;
    prop_oneof![
        4 => (at.clone(), byte()).prop_map(|(i, b)| Edit::Replace(i, b)),
        2 => (at.clone(), byte()).prop_map(|(i, b)| Edit::Insert(i, b)),
        2 => (at.clone(), 1..40usize).prop_map(|(i, n)| Edit::Delete(i, n)),
        1 => at.clone().prop_map(Edit::Truncate),
        1 => (0..2000usize, 0..2000usize).prop_map(|(a, b)| Edit::MoveLine(a, b)),
    ]
}

fn apply(text: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut t = text.to_vec();
    // Edits land near the head half of the time (the header and first portals).
    for e in edits {
        let n = t.len().max(1);
        match *e {
            Edit::Replace(i, b) => {
                if !t.is_empty() {
                    let i = if i % 2 == 0 { i % 64.min(n) } else { i % n };
                    t[i] = b;
                }
            }
            Edit::Insert(i, b) => t.insert(i % (n + 1), b),
            Edit::Delete(i, k) => {
                let i = i % n;
                let j = (i + k).min(t.len());
                t.drain(i.min(t.len())..j);
            }
            Edit::Truncate(i) => t.truncate(i % n),
            Edit::MoveLine(a, b) => {
                let mut lines: Vec<Vec<u8>> =
                    t.split(|&c| c == b'\n').map(<[u8]>::to_vec).collect();
                let m = lines.len();
                let l = lines.remove(a % m);
                lines.insert(b % m, l);
                t = lines.join(&b'\n');
            }
        }
    }
    t
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Mutated writer output: the reader and the level check give a result or a
    /// one-line error, never a panic; what reads is in range.
    #[test]
    fn the_reader_never_panics_on_mutated_writer_output(
        edits in prop::collection::vec(edit(), 1..6)
    ) {
        let text = apply(dm1_text().as_bytes(), &edits);
        match parse_prt(&text) {
            Err(e) => prop_assert!(!e.to_string().contains('\n'), "{}", e),
            Ok(prt) => {
                for p in &prt.portals {
                    prop_assert!(p.leaves.iter().all(|&l| l < prt.leaves));
                    prop_assert!(p.points.len() >= 3);
                    prop_assert!(p.points.iter().flatten().all(|v| v.is_finite()));
                }
                match portals_for_level(&prt, dm1()) {
                    Err(e) => prop_assert!(!e.to_string().contains('\n'), "{}", e),
                    Ok(portals) => {
                        // What reads back is written again and reads back the same.
                        let again = prt_from_portals(&portals, prt.leaves).unwrap().to_text();
                        let back = portals_for_level(&parse_prt(again.as_bytes()).unwrap(), dm1());
                        prop_assert_eq!(back.map(|b| b.len()).ok(), Some(portals.len()));
                    }
                }
            }
        }
    }
}
