//! Cells beyond boxes in `.pvs` files: convex polyhedra (BSP leaves) and voxel cells
//! round-trip with their shapes, point location decides by the shape and not by the
//! bounding box, box-only files keep the version-1 bytes, and damaged shape sections
//! give an error, never a panic.

use roaring::RoaringBitmap;
use sightline_core::{Cell, ConvexCell, HalfSpace, VoxelCell};
use sightline_geom::{DVec3, ViewCell};
use sightline_pvs::format::{encode_cells, encode_with, EncodeOptions, Header};
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
