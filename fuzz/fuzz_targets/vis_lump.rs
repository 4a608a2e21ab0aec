//! The visibility lump writer on arbitrary bytes taken as a BSP file: when the file's
//! header and leaves are usable, rows made from the input are written and must read
//! back exactly (read → write → re-read), writing them again must give the same bytes,
//! and the writer must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sightline_portals::vislump::{read_rows, row_bytes, write_vis, Lumps};

fuzz_target!(|data: &[u8]| {
    let _ = read_rows(data);
    let Ok(dir) = Lumps::read(data) else { return };
    let Ok((visleafs, _)) = dir.leaf_counts(data) else {
        return;
    };
    if visleafs > 4096 {
        return;
    }
    // Rows from the input's own bytes (its tail, cycled), padding bits cleared.
    let rb = row_bytes(visleafs);
    let mut src = data.iter().rev().cycle();
    let rows: Vec<Vec<u8>> = (0..visleafs)
        .map(|_| {
            let mut r: Vec<u8> = (0..rb).map(|_| *src.next().unwrap_or(&0)).collect();
            if visleafs % 8 != 0 {
                if let Some(last) = r.last_mut() {
                    *last &= (1u8 << (visleafs % 8)) - 1;
                }
            }
            r
        })
        .collect();
    let Ok(out) = write_vis(data, &rows) else { return };
    let back = read_rows(&out).expect("the written file reads back");
    assert_eq!(back.len(), rows.len());
    for (b, r) in back.iter().zip(&rows) {
        assert_eq!(b.as_ref(), Some(r));
    }
    assert_eq!(write_vis(&out, &rows).expect("rewrite"), out);
});
