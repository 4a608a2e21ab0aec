//! The `.pvs` reader on arbitrary bytes: it must return an error or a file whose every
//! cell decodes, never panic, hang or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sightline_geom::DVec3;
use sightline_pvs::PvsFile;

fuzz_target!(|data: &[u8]| {
    if let Ok(file) = PvsFile::from_bytes(data.to_vec()) {
        let _ = file.verify();
        for (i, c) in file.cells().iter().enumerate().take(64) {
            let _ = file.query(c.center());
            let _ = file.pvs(i);
            let _ = file.visible_leaves(i);
        }
        let _ = file.query(DVec3::new(0.0, 0.0, 0.0));
    }
});
