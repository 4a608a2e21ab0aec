//! The runtime reads back what `sightline-pvs` wrote, on real files of every cell kind:
//! every cell's row against the row it was written with, its box, kind, source id and
//! visible leaves as `sightline_pvs::PvsFile` sees them (the pipeline's reader, built on
//! this one), the cell located at many points (centres, corners, shared faces, random
//! points, outside) against brute force over the cells' own shapes
//! (`sightline_core::Cell::contains`, no spatial index), the source mapping; and its
//! neighbours and gameplay queries against brute force over the written rows.

mod common;

use common::Written;
use sightline_geom::DVec3;
use sightline_pvs::PvsFile;
use sightline_runtime::{CellKind, CellRelation, Pvs, Query};
use std::collections::BTreeSet;

fn same_answers(name: &str, written: &Written) -> (Pvs, PvsFile) {
    let bytes = &written.bytes;
    let file = PvsFile::from_bytes(bytes.to_vec()).unwrap();
    let pvs = Pvs::from_bytes(bytes).unwrap();
    assert_eq!(pvs.header().method, file.header().method, "{name}");
    assert_eq!(pvs.header().params, file.header().params, "{name}");
    assert_eq!(pvs.header().fingerprint, file.header().fingerprint);
    assert_eq!(pvs.object_count(), file.header().object_count);
    assert_eq!(pvs.cell_count() as usize, file.cells().len());
    let mut q = Query::new();
    let stored: BTreeSet<u32> = file.stored().into_iter().collect();
    let written_stored: BTreeSet<u32> = (0..written.rows.len() as u32)
        .filter(|&i| written.rows[i as usize].is_some())
        .collect();
    assert_eq!(stored, written_stored, "{name}");
    for (i, c) in file.cells().iter().enumerate() {
        let i32 = i as u32;
        assert_eq!(pvs.cell_box(i32), Some(c.to_array()), "{name} cell {i}");
        let shaped = file.cell(i).unwrap();
        assert_eq!(pvs.cell_source_id(i32), shaped.id(), "{name} cell {i}");
        let kind = match shaped.kind() {
            sightline_core::CellKind::Box => CellKind::Box,
            sightline_core::CellKind::Convex => CellKind::Convex,
            sightline_core::CellKind::Voxels => CellKind::Voxels,
        };
        assert_eq!(pvs.cell_kind(i32), Some(kind));
        assert_eq!(pvs.is_stored(i32), stored.contains(&i32));
        if stored.contains(&i32) {
            let row = written.rows[i].as_deref().unwrap();
            assert_eq!(pvs.visible(&mut q, i32).unwrap(), row, "{name} cell {i}");
            assert_eq!(file.pvs(i).unwrap(), row, "{name} cell {i}");
            assert_eq!(pvs.row_len(i32), file.set_len(i));
        } else {
            assert!(pvs.visible(&mut q, i32).is_err());
        }
        assert_eq!(
            pvs.visible_leaves(i32),
            file.visible_leaves(i),
            "{name} cell {i}"
        );
    }
    assert!(pvs.visible(&mut q, pvs.cell_count()).is_err());
    assert_eq!(pvs.cell_box(pvs.cell_count()), None);
    let boxes: Vec<[f64; 6]> = file.cells().iter().map(|c| c.to_array()).collect();
    let mut located = 0;
    let shapes = file.shaped_cells();
    for p in common::probe_points(&boxes, 20_000) {
        let v = DVec3::from_array(p);
        let expected = (0..shapes.len())
            .find(|&i| file.cells()[i].contains(v) && shapes[i].contains(v))
            .map(|i| i as u32);
        assert_eq!(pvs.locate(p), expected, "{name} at {p:?}");
        located += expected.is_some() as usize;
    }
    assert!(located > 1000, "{name}: only {located} points in a cell");
    // Neighbours: the cells whose closed boxes touch.
    let mut around = Vec::new();
    for (i, b) in boxes.iter().enumerate() {
        let tol = 1e-6;
        let brute: Vec<u32> = (0..boxes.len())
            .filter(|&j| {
                j != i
                    && (0..3)
                        .all(|k| b[k] <= boxes[j][k + 3] + tol && boxes[j][k] <= b[k + 3] + tol)
            })
            .map(|j| j as u32)
            .collect();
        pvs.neighbours_into(i as u32, &mut around);
        assert_eq!(around, brute, "{name} cell {i}");
    }
    (pvs, file)
}

/// `can_see`, `cells_seeing_into` and `secondary_into` against brute force over the
/// written rows; returns the number of (stored) pairs that see each other and of all
/// pairs.
fn same_gameplay(name: &str, pvs: &Pvs, file: &PvsFile, written: &Written) -> (usize, usize) {
    let mut q = Query::new();
    let stored = file.stored();
    let rows: Vec<Option<BTreeSet<u32>>> = written
        .rows
        .iter()
        .map(|r| r.as_ref().map(|r| r.iter().copied().collect()))
        .collect();
    let sees = |a: usize, b: usize| -> bool {
        if a == b {
            return true;
        }
        match pvs.cell_relation() {
            CellRelation::Leaves => {
                let num = |c: usize| file.cell(c).and_then(|c| c.id()).unwrap_or(c as u32);
                let (la, lb) = (
                    file.visible_leaves(a).unwrap(),
                    file.visible_leaves(b).unwrap(),
                );
                la.contains(&num(b)) && lb.contains(&num(a))
            }
            CellRelation::SharedObjects => {
                let (ra, rb) = (rows[a].as_ref().unwrap(), rows[b].as_ref().unwrap());
                ra.intersection(rb).next().is_some()
            }
        }
    };
    let (mut out, mut seen) = (Vec::new(), Vec::new());
    let mut pairs_seeing = 0;
    for &a in &stored {
        let a = a as usize;
        let expected: Vec<u32> = stored
            .iter()
            .copied()
            .filter(|&b| sees(a, b as usize))
            .collect();
        for &b in &stored {
            let s = pvs.can_see(&mut q, a as u32, b).unwrap();
            assert_eq!(s, sees(a, b as usize), "{name}: {a} sees {b}");
            pairs_seeing += s as usize;
        }
        pvs.cells_seeing_into(&mut q, a as u32, &mut seen).unwrap();
        assert_eq!(seen, expected, "{name}: cells seeing {a}");
        let union: BTreeSet<u32> = expected
            .iter()
            .flat_map(|&b| rows[b as usize].clone().unwrap())
            .collect();
        pvs.secondary_into(&mut q, a as u32, &mut out).unwrap();
        assert_eq!(
            out,
            union.into_iter().collect::<Vec<_>>(),
            "{name}: secondary of {a}"
        );
        assert!(rows[a]
            .as_ref()
            .unwrap()
            .iter()
            .all(|o| out.binary_search(o).is_ok()));
        // The cells seeing a point of `a` are those seeing `a`.
        let b = pvs.cell_box(a as u32).unwrap();
        let c = [
            0.5 * (b[0] + b[3]),
            0.5 * (b[1] + b[4]),
            0.5 * (b[2] + b[5]),
        ];
        if let Some(cell) = pvs.locate(c) {
            let got = pvs.cells_seeing_point_into(&mut q, c, &mut out).unwrap();
            assert_eq!(got, Some(cell));
            pvs.cells_seeing_into(&mut q, cell, &mut seen).unwrap();
            assert_eq!(out, seen);
        }
    }
    let n = stored.len();
    assert!(pairs_seeing >= n);
    assert_eq!(
        pvs.cells_seeing_point_into(&mut q, [f64::NAN, 0.0, 0.0], &mut out)
            .unwrap(),
        None
    );
    assert!(out.is_empty());
    (pairs_seeing, n * n)
}

#[test]
fn a_generated_city_reads_back() {
    let written = common::city();
    let (pvs, file) = same_answers("city", &written);
    assert_eq!(pvs.cell_relation(), CellRelation::SharedObjects);
    assert!(pvs.sources().is_none() && pvs.source_names().is_none());
    let (seeing, pairs) = same_gameplay("city", &pvs, &file, &written);
    assert!(seeing < pairs, "every pair of cells shares an object");
}

#[test]
fn quake_dm1_reads_back() {
    let written = common::dm1();
    let (pvs, file) = same_answers("dm1", &written);
    assert_eq!(pvs.cell_relation(), CellRelation::Leaves);
    assert!(pvs.has_visible_leaves());
    let (seeing, pairs) = same_gameplay("dm1", &pvs, &file, &written);
    assert!(
        seeing < pairs / 2,
        "{seeing} of {pairs} pairs of leaves see each other"
    );
}

#[test]
fn voxel_cells_and_sources_read_back() {
    let written = common::voxels();
    let (pvs, file) = same_answers("voxels", &written);
    same_gameplay("voxels", &pvs, &file, &written);
    let mut q = Query::new();
    let mut out = Vec::new();
    for i in 0..pvs.cell_count() {
        let row = pvs.visible(&mut q, i).unwrap().to_vec();
        assert!(pvs.visible_sources_into(&row, &mut out));
        // The CLI's mapping (`query`'s `visible_sources`).
        let map: Vec<u32> = file.header().params[0]
            .1
            .split(',')
            .map(|s| s.parse().unwrap())
            .collect();
        let expected: BTreeSet<u32> = row.iter().map(|&c| map[c as usize]).collect();
        assert_eq!(out, expected.into_iter().collect::<Vec<_>>());
    }
    let names = pvs.source_names().unwrap();
    assert_eq!(names[0], "obj \"0\"");
    assert_eq!(names.len(), 14);
}

#[test]
fn a_shard_reads_back() {
    let written = common::shard();
    let (pvs, file) = same_answers("shard", &written);
    same_gameplay("shard", &pvs, &file, &written);
    let mut q = Query::new();
    assert!(pvs.can_see(&mut q, 0, 1).is_err());
    assert!(pvs.secondary_into(&mut q, 0, &mut Vec::new()).is_err());
}

#[test]
fn one_query_scratch_serves_two_files() {
    let (a, b) = (common::shard().bytes, common::voxels().bytes);
    let (fa, fb) = (
        Pvs::from_vec(a.clone()).unwrap(),
        Pvs::from_vec(b.clone()).unwrap(),
    );
    let (ra, rb) = (
        PvsFile::from_bytes(a).unwrap(),
        PvsFile::from_bytes(b).unwrap(),
    );
    let mut q = Query::with_cache_bytes(1);
    for _ in 0..2 {
        assert_eq!(fa.visible(&mut q, 1).unwrap(), ra.pvs(1).unwrap());
        assert_eq!(fb.visible(&mut q, 1).unwrap(), rb.pvs(1).unwrap());
    }
}

#[test]
fn open_from_a_path() {
    let dir = std::env::temp_dir().join(format!("sightline-runtime-open-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("v.pvs");
    std::fs::write(&path, common::voxels().bytes).unwrap();
    let pvs = Pvs::open(&path).unwrap();
    assert_eq!(pvs.cell_count(), 32);
    let err = Pvs::open(dir.join("missing.pvs")).unwrap_err();
    assert!(err.to_string().contains("missing.pvs"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
