//! qbsp's portal file, read → written → read again: whatever the reader accepts, the
//! writer writes as text that reads back to exactly the same file (leaves, portals,
//! every coordinate), and writing that again gives the same text.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sightline_portals::prt::parse_prt;

fuzz_target!(|data: &[u8]| {
    let Ok(prt) = parse_prt(data) else { return };
    let text = prt.to_text();
    let back = parse_prt(text.as_bytes()).expect("the writer's text reads back");
    assert_eq!(back, prt);
    assert_eq!(back.to_text(), text);
});
