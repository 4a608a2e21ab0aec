//! The `.pvs` reader on arbitrary bytes, through both faces: `sightline-runtime`'s `Pvs`
//! and `sightline-pvs`'s `PvsFile` (built on it, adding the pipeline's types and shapes)
//! must both return an error or both open the file and give the same answers (cells,
//! point location, rows or the same failure, leaves), and neither may panic, hang or
//! allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sightline_geom::DVec3;
use sightline_pvs::PvsFile;
use sightline_runtime::{Pvs, Query};

fuzz_target!(|data: &[u8]| {
    let file = PvsFile::from_bytes(data.to_vec());
    let runtime = Pvs::from_bytes(data);
    let (file, runtime) = match (file, runtime) {
        (Err(_), Err(_)) => return,
        (Ok(f), Ok(r)) => (f, r),
        (f, r) => panic!(
            "the readers disagree on opening: pvs {:?}, runtime {:?}",
            f.err().map(|e| e.to_string()),
            r.err().map(|e| e.to_string())
        ),
    };
    let _ = file.verify();
    assert_eq!(file.cells().len(), runtime.cell_count() as usize);
    let mut q = Query::new();
    let mut around = Vec::new();
    for (i, c) in file.cells().iter().enumerate().take(64) {
        let at = c.center();
        let _ = file.query(at);
        assert_eq!(
            file.locate(at).map(|i| i as u32),
            runtime.locate(at.to_array())
        );
        match (file.pvs(i), runtime.visible(&mut q, i as u32)) {
            (Ok(a), Ok(b)) => assert_eq!(a, b),
            (Err(_), Err(_)) => {}
            (a, b) => panic!("cell {i}: pvs {:?}, runtime {:?}", a.err(), b.err()),
        }
        assert_eq!(file.visible_leaves(i), runtime.visible_leaves(i as u32));
        runtime.neighbours_into(i as u32, &mut around);
        let _ = runtime.can_see(&mut q, i as u32, 0);
    }
    let origin = DVec3::new(0.0, 0.0, 0.0);
    assert_eq!(
        file.locate(origin).map(|i| i as u32),
        runtime.locate(origin.to_array())
    );
});
