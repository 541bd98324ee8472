//! The raw-volume reader: the first 8 bytes choose the layout the user would
//! give on the command line (dimensions, scalar type, byte order, header
//! bytes), the rest are the file.
#![no_main]
use lodstudio_core::io::{RawSpec, ScalarType, volume};

const TYPES: [&str; 8] = ["u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64"];

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let Some((layout, file)) = data.split_first_chunk::<8>() else {
        return;
    };
    let spec = RawSpec {
        dims: [layout[0] as usize, layout[1] as usize, layout[2] as usize],
        scalar: ScalarType::parse(TYPES[layout[3] as usize % 8]).expect("known type"),
        big_endian: layout[4] & 1 == 1,
        spacing: glam::Vec3::new(1.0, f32::from(layout[5]) * 0.1, 1.0),
        header_bytes: u16::from_le_bytes([layout[6], layout[7]]) as usize,
    };
    let _ = volume::read_raw(file, &spec);
});
