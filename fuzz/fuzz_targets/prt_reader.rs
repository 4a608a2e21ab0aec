//! qbsp's portal file reader on arbitrary bytes: an error or a file whose leaves and
//! points are in range, never a panic, a hang or an allocation out of proportion to
//! the input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sightline_portals::prt::parse_prt;

fuzz_target!(|data: &[u8]| {
    if let Ok(prt) = parse_prt(data) {
        for p in &prt.portals {
            assert!(p.leaves.iter().all(|&l| l < prt.leaves));
            assert!(p.points.len() >= 3);
            assert!(p.points.iter().flatten().all(|v| v.is_finite()));
        }
    }
});
