//! The OFF reader (OFF, COFF, NOFF, STOFF and their combinations) on arbitrary bytes.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let _ = lodstudio_core::io::off::read(data, &lodstudio_core::Progress::new());
});
