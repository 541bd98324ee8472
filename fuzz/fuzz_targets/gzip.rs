//! The gzip layer in front of every reader: arbitrary bytes behind a gzip
//! magic, through format detection, the head check and the cap.
#![no_main]
use std::path::Path;

use lodstudio_core::io::{self, LoadOptions};

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    if !io::is_gzip(data) {
        return;
    }
    let _ = io::gunzip(data, 1 << 20);
    let _ = io::load_bytes(
        Path::new("fuzz.ply.gz"),
        data,
        &LoadOptions::default(),
        &lodstudio_core::Progress::new(),
    );
});
