//! The glTF reader on arbitrary bytes: GLB containers and .gltf JSON (data:
//! URIs only; no folder is given, so nothing outside the input is read).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let _ = lodstudio_core::io::gltf::read(data, None);
});
