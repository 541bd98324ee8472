//! The OBJ reader on arbitrary bytes: an error or a mesh, never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let _ = lodstudio_core::io::obj::read(data, &lodstudio_core::Progress::new());
});
