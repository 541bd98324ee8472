//! The glTF reader on arbitrary bytes: GLB containers and .gltf JSON, read
//! once from memory (no folder: data: URIs only) and once as if it lay in
//! the seeds' folder, so the asset-folder policy (`io::confine`) resolves
//! every URI the input names: relative ones, escapes, schemes, devices.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let _ = lodstudio_core::io::gltf::read(data, None);
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds/gltf");
    let _ = lodstudio_core::io::gltf::read(data, Some(&folder));
});
