//! The build journal parser on arbitrary bytes: an error or records, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = sightline_pvs::journal::parse(std::path::Path::new("fuzz.journal"), data);
});
