//! The INRIMAGE-4 reader.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let _ = lodstudio_core::io::volume::read_inr(data);
});
