//! Saved hierarchies past their checksum: the first byte picks the method, the
//! rest is the body, framed here with a valid header and CRC (the layout of
//! io::hierarchy_file) so the fuzzer reaches the body decoder and the checks
//! each method makes before a cut. The reopened hierarchy is then cut at a few
//! tolerances.
#![no_main]
use lodstudio_core::io::hierarchy_file::VERSION;
use lodstudio_core::lod::Method;
use lodstudio_core::view::{Tolerance, View};

fn frame(method: &str, params: &[u8], body: &[u8]) -> Vec<u8> {
    let mut out = b"LODSTHRY".to_vec();
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(method.len() as u16).to_le_bytes());
    out.extend_from_slice(method.as_bytes());
    out.extend_from_slice(&(params.len() as u32).to_le_bytes());
    out.extend_from_slice(params);
    out.extend_from_slice(&(body.len() as u64).to_le_bytes());
    out.extend_from_slice(body);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let method = Method::ALL[pick as usize % Method::ALL.len()].tag();
    let file = frame(method, b"{}", body);
    // The raw bytes too: the header's own checks.
    let _ = lodstudio_core::open::reopen(data);
    let Ok((_, mut h)) = lodstudio_core::open::reopen(&file) else {
        return;
    };
    let view = View::orbit(glam::Vec3::ZERO, 2.0, 0.3, 0.2);
    for tol in [0.0, 0.01, 0.5] {
        let _ = h.select(&view, Tolerance::Relative(tol));
    }
    let _ = h.select_triangles(10);
});
