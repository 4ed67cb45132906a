//! The USD crate (binary) reader on arbitrary bytes (after its `PXR-USDC`
//! magic): it must return a groom or an error, never panic, hang or
//! allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let mut bytes = b"PXR-USDC".to_vec();
    bytes.extend_from_slice(data.strip_prefix(b"PXR-USDC").unwrap_or(data));
    let _ = importers::usd::read_bytes(Path::new("fuzz.usdc"), &bytes);
    // The sequence reader (inspect, convert) evaluates changing topologies.
    let _ = importers::usd::read_sequence_bytes(Path::new("fuzz.usdc"), &bytes);
});
