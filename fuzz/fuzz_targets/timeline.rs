//! The timeline parser and its checks on arbitrary text: a timeline or an
//! error, never a panic, hang or unbounded allocation. Paths in the
//! timeline resolve under a folder that does not exist, so no real file is
//! read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("/nonexistent-groombake-fuzz/timeline.toml");
    if let Ok(timeline) = groombake::timeline::Timeline::parse(path, text.to_string()) {
        let _ = timeline.duration();
    }
});
