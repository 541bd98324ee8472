//! The NIfTI-1 reader (single-file .nii, both byte orders).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let _ = lodstudio_core::io::volume::read_nifti(data);
});
