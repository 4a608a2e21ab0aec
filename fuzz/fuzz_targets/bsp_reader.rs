//! The Quake BSP reader on arbitrary bytes: it must return an error or a level whose
//! tree walks terminate and whose visibility rows decode, never panic, hang or
//! allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sightline_scene::import::bsp::read_bsp;

fuzz_target!(|data: &[u8]| {
    if let Ok(level) = read_bsp(data) {
        let _ = level.point_leaf([0.0, 0.0, 0.0]);
        let _ = level.point_leaf([1e5, -1e5, 3.0]);
        for leaf in 0..=level.visleafs.min(64) {
            let _ = level.reference_row(leaf);
        }
        let _ = level.to_scene();
    }
});
