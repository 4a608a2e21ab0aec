//! Golden facts of the Quake levels in `data/quake/`: counts from the shared data's
//! README, and the reference PVS rows decoded from the visibility lump.

use sightline_scene::import::bsp::{load_bsp, read_bsp, Child};
use std::path::PathBuf;

fn level(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/quake")
        .join(name)
}

#[test]
fn e1m1_golden_facts() {
    let l = load_bsp(&level("e1m1.bsp")).unwrap();
    assert_eq!(l.leaves.len(), 1593);
    assert_eq!(l.visleafs, 1206);
    assert_eq!(l.faces.len(), 5267);
    let mut total = 0usize;
    for leaf in 1..=l.visleafs {
        let row = l.reference_row(leaf);
        assert!(row.contains(&leaf), "leaf {leaf} does not see itself");
        assert!(row.windows(2).all(|w| w[0] < w[1]));
        assert!(row.iter().all(|&j| j >= 1 && j <= l.visleafs));
        total += row.len();
    }
    let mean = total as f64 / l.visleafs as f64;
    assert!((mean - 142.0).abs() < 0.05, "mean row {mean}");
    assert!(l.reference_row(0).is_empty());
}

#[test]
fn dm1_golden_facts_and_point_location() {
    let l = load_bsp(&level("dm1.bsp")).unwrap();
    assert_eq!(
        (l.leaves.len(), l.visleafs, l.faces.len()),
        (483, 434, 2174)
    );
    let total: usize = (1..=l.visleafs).map(|j| l.reference_row(j).len()).sum();
    assert!((total as f64 / 434.0 - 90.6).abs() < 0.05);
    // Every open leaf's box centre that lands in the leaf itself is located there.
    let mut located = 0;
    for (i, leaf) in l
        .leaves
        .iter()
        .enumerate()
        .skip(1)
        .take(l.visleafs as usize)
    {
        let c = [0, 1, 2].map(|k| 0.5 * (leaf.mins[k] + leaf.maxs[k]));
        let found = l.point_leaf(c);
        assert!((found as usize) < l.leaves.len());
        located += usize::from(found as usize == i);
    }
    assert!(located > 100, "{located}");
    assert!(matches!(l.headnode, Child::Node(0)));
    // The scene: one object per world face, ids = face indices.
    let scene = l.to_scene();
    assert_eq!(scene.objects.len(), 2174);
    let loaded = sightline_scene::import::load(
        &level("dm1.bsp"),
        &sightline_scene::import::ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(loaded.objects.len(), 2174);
}

#[test]
fn damaged_files_are_errors_not_panics() {
    let bytes = std::fs::read(level("dm1.bsp")).unwrap();
    // Every truncation is an error with a one-line message.
    for cut in [0, 3, 4, 60, 123, 1000, bytes.len() / 2, bytes.len() - 1] {
        let e = read_bsp(&bytes[..cut]).unwrap_err().to_string();
        assert!(!e.contains('\n') && e.starts_with("BSP"), "{e}");
    }
    // Bytes flipped all over the file: an error or a level, never a panic.
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..300 {
        let mut b = bytes.clone();
        for _ in 0..8 {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            let i = (rng % b.len() as u64) as usize;
            b[i] = (rng >> 32) as u8;
        }
        if let Ok(l) = read_bsp(&b) {
            let _ = l.point_leaf([0.0, 0.0, 0.0]);
            for j in 0..=l.visleafs.min(20) {
                let _ = l.reference_row(j);
            }
        }
    }
}
