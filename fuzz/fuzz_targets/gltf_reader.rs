//! The glTF reader (strands and collider triangles) on arbitrary bytes: it
//! must return a result or an error, never panic, hang or allocate without
//! bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = importers::gltf::parse(Path::new("fuzz.gltf"), data);
    let _ = importers::gltf::parse_triangles(Path::new("fuzz.gltf"), data);
});
