//! The USD text reader on arbitrary bytes (after its `#usda ` magic): it
//! must return a groom or an error, never panic, hang or allocate without
//! bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let mut bytes = b"#usda ".to_vec();
    bytes.extend_from_slice(data.strip_prefix(b"#usda ").unwrap_or(data));
    let _ = importers::usd::read_bytes(Path::new("fuzz.usda"), &bytes);
    // The sequence reader (inspect, convert) evaluates changing topologies.
    let _ = importers::usd::read_sequence_bytes(Path::new("fuzz.usda"), &bytes);
});
