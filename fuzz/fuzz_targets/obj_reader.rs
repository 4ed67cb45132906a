//! The .obj reader (polyline strands and collider triangles) on arbitrary
//! bytes: it must return a result or an error, never panic, hang or
//! allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = importers::obj::parse(Path::new("fuzz.obj"), data);
    let _ = importers::mesh::parse_obj(Path::new("fuzz.obj"), data);
});
