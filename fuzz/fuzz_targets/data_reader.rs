//! The .data reader on arbitrary bytes: it must return a groom or an error,
//! never panic, hang or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = importers::data::parse(Path::new("fuzz.data"), data);
});
