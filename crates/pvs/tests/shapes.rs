//! Cells beyond boxes in `.pvs` files: convex polyhedra (BSP leaves) and voxel cells
//! round-trip with their shapes, point location decides by the shape and not by the
//! bounding box, box-only files keep the version-1 bytes, and damaged shape sections
//! give an error, never a panic. The optional LEAF section (each cell's visible leaves)
//! round-trips, survives a merge, and every bit flip or cut of it is an error.

use roaring::RoaringBitmap;
use sightline_core::{Cell, ConvexCell, HalfSpace, VoxelCell};
use sightline_geom::{DVec3, ViewCell};
use sightline_pvs::format::{
    encode_cells, encode_cells_with_leaves, encode_with, EncodeOptions, Header,
};
use sightline_pvs::{PvsFile, FORMAT_VERSION, FORMAT_VERSION_BOXES};

fn bx(a: [f64; 6]) -> ViewCell {
    ViewCell::from_array(a).unwrap()
}

/// Two wedges splitting the unit cube along x + y = 1 (same bounding box), an L of two
/// voxel boxes, and a plain box far away (coordinates far from the origin).
fn cells() -> Vec<Cell> {
    let cube = bx([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    let n = DVec3::new(1.0, 1.0, 0.0);
    vec![
        Cell::Convex(ConvexCell::new(
            7,
            cube,
            vec![HalfSpace {
                normal: n,
                offset: 1.0,
            }],
        )),
        Cell::Convex(ConvexCell::new(
            9,
            cube,
            vec![HalfSpace {
                normal: -n,
                offset: -1.0,
            }],
        )),
        Cell::Voxels(
            VoxelCell::new(
                3,
                vec![
                    bx([2.0, 0.0, 0.0, 4.0, 1.0, 1.0]),
                    bx([2.0, 1.0, 0.0, 3.0, 3.0, 1.0]),
                ],
            )
            .unwrap(),
        ),
        Cell::Box(bx([1e6, 1e6, 0.0, 1e6 + 5.0, 1e6 + 5.0, 2.0])),
    ]
}

fn sets(n: usize) -> Vec<RoaringBitmap> {
    (0..n as u32)
        .map(|i| [i, i + 10].into_iter().collect())
        .collect()
}

fn encode(cells: &[Cell]) -> Vec<u8> {
    let header = Header::new(42, "test", vec![], 100, cells.len());
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    encode_cells(
        &header,
        cells,
        &present,
        &sets(cells.len()),
        &EncodeOptions::default(),
    )
    .unwrap()
}

#[test]
fn shapes_round_trip_and_decide_point_location() {
    let cells = cells();
    let bytes = encode(&cells);
    assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), FORMAT_VERSION);
    let f = PvsFile::from_bytes(bytes).unwrap();
    assert_eq!(f.shaped_cells(), cells);
    let at = |x, y, z| f.locate(DVec3::new(x, y, z));
    // Same bounding box, the shape decides.
    assert_eq!(at(0.2, 0.2, 0.5), Some(0));
    assert_eq!(at(0.9, 0.9, 0.5), Some(1));
    // On the shared face: the lowest index.
    assert_eq!(at(0.5, 0.5, 0.5), Some(0));
    // Inside the L's bounding box but outside both of its boxes.
    assert_eq!(at(3.5, 2.5, 0.5), None);
    assert_eq!(at(3.5, 0.5, 0.5), Some(2));
    assert_eq!(at(2.5, 2.5, 0.5), Some(2));
    assert_eq!(at(1e6 + 1.0, 1e6 + 1.0, 1.0), Some(3));
    let (c, v) = f.query(DVec3::new(0.9, 0.9, 0.5)).unwrap().unwrap();
    assert_eq!((c, v), (cells[1].bounds(), vec![1, 11]));
}

#[test]
fn box_only_files_keep_version_one_bytes() {
    let boxes: Vec<ViewCell> = (0..6)
        .map(|i| bx([i as f64, 0.0, 0.0, i as f64 + 1.0, 1.0, 2.0]))
        .collect();
    let header = Header::new(42, "test", vec![], 100, boxes.len());
    let present: Vec<u32> = (0..boxes.len() as u32).collect();
    let old = encode_with(
        &header,
        &boxes,
        &present,
        &sets(boxes.len()),
        &EncodeOptions::default(),
    )
    .unwrap();
    let cells: Vec<Cell> = boxes.iter().copied().map(Cell::Box).collect();
    assert_eq!(encode(&cells), old);
    assert_eq!(u16::from_le_bytes([old[8], old[9]]), FORMAT_VERSION_BOXES);
}

#[test]
fn damaged_shape_files_error_without_panicking() {
    let bytes = encode(&cells());
    for i in 0..bytes.len() {
        for bit in [0x01u8, 0x80] {
            let mut b = bytes.clone();
            b[i] ^= bit;
            if let Ok(f) = PvsFile::from_bytes(b) {
                // A flip the checksums cannot see (none expected) must still answer.
                let _ = f.locate(DVec3::new(0.5, 0.5, 0.5));
            }
        }
    }
    for len in 0..bytes.len() {
        assert!(PvsFile::from_bytes(bytes[..len].to_vec()).is_err());
    }
}

fn leaf_sets(n: usize) -> Vec<Vec<u32>> {
    (0..n as u32)
        .map(|i| (0..=i).map(|k| 3 * k + i).collect())
        .collect()
}

fn encode_with_leaves(cells: &[Cell]) -> Vec<u8> {
    let header = Header::new(42, "test", vec![], 100, cells.len());
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    encode_cells_with_leaves(
        &header,
        cells,
        &present,
        &sets(cells.len()),
        Some(&leaf_sets(cells.len())),
        &EncodeOptions::default(),
    )
    .unwrap()
}

#[test]
fn visible_leaves_round_trip_and_are_optional() {
    let cells = cells();
    let f = PvsFile::from_bytes(encode_with_leaves(&cells)).unwrap();
    assert!(f.has_visible_leaves());
    for (i, want) in leaf_sets(cells.len()).iter().enumerate() {
        assert_eq!(f.visible_leaves(i), Some(want.as_slice()));
    }
    assert_eq!(f.visible_leaves(cells.len()), None);
    f.verify().unwrap();
    // Without leaves: the bytes of encode_cells, no LEAF section.
    let plain = PvsFile::from_bytes(encode(&cells)).unwrap();
    assert!(!plain.has_visible_leaves() && plain.visible_leaves(0).is_none());
    // Boxes with leaves: version 2 (the LEAF section), still answering by box.
    let boxes: Vec<Cell> = (0..3)
        .map(|i| Cell::Box(bx([i as f64, 0.0, 0.0, i as f64 + 1.0, 1.0, 2.0])))
        .collect();
    let bytes = encode_with_leaves(&boxes);
    assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), FORMAT_VERSION);
    let f = PvsFile::from_bytes(bytes).unwrap();
    assert_eq!(f.locate(DVec3::new(1.5, 0.5, 1.0)), Some(1));
    assert_eq!(f.visible_leaves(2), Some(&[2u32, 5, 8][..]));
    // A merge keeps them.
    let merged = sightline_pvs::merge(&[("a".into(), f)]).unwrap();
    assert_eq!(merged, encode_with_leaves(&boxes));
    // Unsorted sets and a wrong count are refused by the writer.
    let header = Header::new(42, "test", vec![], 100, 3);
    let bad = encode_cells_with_leaves(
        &header,
        &boxes,
        &[0, 1, 2],
        &sets(3),
        Some(&[vec![1], vec![3, 2], vec![]]),
        &EncodeOptions::default(),
    );
    assert!(bad.is_err());
    let short = encode_cells_with_leaves(
        &header,
        &boxes,
        &[0, 1, 2],
        &sets(3),
        Some(&[vec![1]]),
        &EncodeOptions::default(),
    );
    assert!(short.is_err());
}

#[test]
fn every_flip_or_cut_of_a_file_with_leaves_is_an_error() {
    let bytes = encode_with_leaves(&cells());
    for pos in 0..bytes.len() {
        let mut b = bytes.clone();
        b[pos] ^= 1 << (pos % 8);
        let detected = match PvsFile::from_bytes(b) {
            Err(_) => true,
            Ok(f) => f.verify().is_err(),
        };
        assert!(
            detected,
            "flip at byte {pos} of {} not detected",
            bytes.len()
        );
    }
    for len in 0..bytes.len() {
        assert!(PvsFile::from_bytes(bytes[..len].to_vec()).is_err());
    }
}
