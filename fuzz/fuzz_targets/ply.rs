//! The PLY reader (ASCII and both binary encodings) on arbitrary bytes.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let _ = lodstudio_core::io::ply::read(data, &lodstudio_core::Progress::new());
});
