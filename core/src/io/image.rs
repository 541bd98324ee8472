//! Images as PNG: splat textures encoded for glTF, and a material's
//! base-colour image decoded to RGBA8 for viewers (exports keep the bytes as
//! the input stored them). PNG is decoded; other formats are reported, and a
//! viewer then shows the material's base colour alone.

use crate::geom::Image;
use crate::lod::Texture;

/// Images larger than this many texels per side are not decoded for display
/// (no GPU samples them, and a hostile header could ask for gigabytes).
pub const MAX_SIDE: u32 = 16_384;

/// Decoded texels, row by row from the top (glTF's UV origin), sRGB-encoded.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgba {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u8; 4]>,
}

/// Linear to sRGB-encoded 8 bits (glTF base-colour textures are sRGB).
pub fn encode_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// sRGB-encoded 8 bits to linear, from a table (texture lookups in bakes
/// and the measure of `bake::choice` spent a tenth of their time in `powf`).
pub fn decode_srgb(v: u8) -> f32 {
    static TABLE: std::sync::LazyLock<[f32; 256]> = std::sync::LazyLock::new(|| {
        std::array::from_fn(|v| {
            let s = v as f32 / 255.0;
            if s <= 0.040_45 {
                s / 12.92
            } else {
                ((s + 0.055) / 1.055).powf(2.4)
            }
        })
    });
    TABLE[v as usize]
}

/// glTF sampler wrap modes (glTF 2.0 §5.26).
pub const REPEAT: u32 = 10497;
pub const CLAMP_TO_EDGE: u32 = 33071;
pub const MIRRORED_REPEAT: u32 = 33648;

/// `texture` as a material's PNG image, default filters, `wrap` both ways.
pub fn png_image(texture: &Texture, wrap: u32) -> Image {
    Image {
        mime_type: "image/png".into(),
        bytes: encode_png(texture).into(),
        mag_filter: None,
        min_filter: None,
        wrap_s: wrap,
        wrap_t: wrap,
    }
}

/// An RGBA8 texture as PNG.
pub fn encode_png(tex: &Texture) -> Vec<u8> {
    let (w, h) = (tex.width.max(1), tex.height.max(1));
    let mut data: Vec<u8> = tex.rgba.concat();
    data.resize((w * h * 4) as usize, 0);
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    // Encoding into memory with a matching size cannot fail.
    let mut writer = enc.write_header().expect("writing to memory");
    writer
        .write_image_data(&data)
        .expect("size matches the header");
    drop(writer);
    out
}

/// Refuses an image whose declared size would not fit the memory budget
/// once decoded to RGBA8 (a 60000×60000 PNG is a few KB on disk and 13 GB
/// decoded): checked from the header, before any decoder runs.
pub fn check_declared_size(bytes: &[u8]) -> Result<(), String> {
    let Some((w, h)) = crate::geom::declared_size(bytes) else {
        return Ok(()); // not decoded by lodstudio; carried as stored
    };
    super::limits::check_budget(
        &format!("decoding its {w}×{h} texels"),
        u64::from(w) * u64::from(h) * 4,
    )
    .map_err(|e| e.expected)
}

/// Decodes `image` to RGBA8.
///
/// # Errors
/// A message naming the problem: an undecoded format, a damaged or
/// oversized PNG.
pub fn decode_rgba(image: &Image) -> Result<Rgba, String> {
    if image.mime_type != "image/png" {
        return Err(format!(
            "{} images are not decoded for display",
            image.mime_type
        ));
    }
    let mut decoder = png::Decoder::new(std::io::Cursor::new(&image.bytes[..]));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| format!("PNG: {e}"))?;
    let (width, height) = {
        let info = reader.info();
        (info.width, info.height)
    };
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!("PNG of {width}×{height} texels is not shown"));
    }
    check_declared_size(&image.bytes)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| "PNG: image too large".to_string())?;
    let mut buf = vec![0u8; size];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("PNG: {e}"))?;
    let bytes = &buf[..frame.buffer_size()];
    let texels: Vec<[u8; 4]> = match frame.color_type {
        png::ColorType::Rgba => bytes
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        png::ColorType::Rgb => bytes
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2], 255])
            .collect(),
        png::ColorType::GrayscaleAlpha => bytes
            .chunks_exact(2)
            .map(|c| [c[0], c[0], c[0], c[1]])
            .collect(),
        png::ColorType::Grayscale => bytes.iter().map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::Indexed => return Err("PNG: palette not expanded".into()),
    };
    if texels.len() != (width * height) as usize {
        return Err("PNG: short image data".into());
    }
    Ok(Rgba {
        width,
        height,
        texels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(bytes: Vec<u8>, mime: &str) -> Image {
        Image {
            mime_type: mime.into(),
            bytes: bytes.into(),
            mag_filter: None,
            min_filter: None,
            wrap_s: 10497,
            wrap_t: 10497,
        }
    }

    #[test]
    fn pngs_decode_to_rgba_and_bad_ones_say_why() {
        let mut png_bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut png_bytes, 2, 1);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().unwrap();
            w.write_image_data(&[255, 0, 0, 0, 0, 255]).unwrap();
        }
        let rgba = decode_rgba(&image(png_bytes.clone(), "image/png")).unwrap();
        assert_eq!((rgba.width, rgba.height), (2, 1));
        assert_eq!(rgba.texels, vec![[255, 0, 0, 255], [0, 0, 255, 255]]);
        // What the glTF writer encodes decodes to the same texels.
        let texture = Texture {
            width: 2,
            height: 2,
            rgba: vec![
                [1, 2, 3, 4],
                [5, 6, 7, 8],
                [9, 10, 11, 12],
                [13, 14, 15, 16],
            ],
        };
        let back = decode_rgba(&image(encode_png(&texture), "image/png")).unwrap();
        assert_eq!(back.texels, texture.rgba);
        assert!(decode_rgba(&image(png_bytes.clone(), "image/jpeg")).is_err());
        png_bytes.truncate(png_bytes.len() / 2);
        assert!(decode_rgba(&image(png_bytes, "image/png")).is_err());
        assert!(decode_rgba(&image(b"not a png".to_vec(), "image/png")).is_err());
    }

    #[test]
    fn a_declared_size_is_read_from_the_header_and_checked_against_the_budget() {
        use crate::geom::declared_size;
        // A PNG signature and IHDR declaring 60000×60000 texels: 13.4 GB decoded.
        let mut bomb = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
        bomb.extend(60_000u32.to_be_bytes());
        bomb.extend(60_000u32.to_be_bytes());
        bomb.extend([8, 6, 0, 0, 0]);
        assert_eq!(declared_size(&bomb), Some((60_000, 60_000)));
        let e = check_declared_size(&bomb).unwrap_err();
        assert!(
            e.contains("60000×60000") && e.contains("over the budget"),
            "{e}"
        );
        assert!(decode_rgba(&image(bomb, "image/png")).is_err());
        // A JPEG's start of frame (baseline, 640 wide, 480 high) after an APP0.
        let jpeg = [
            0xff, 0xd8, 0xff, 0xe0, 0, 4, 0, 0, 0xff, 0xc0, 0, 11, 8, 0x01, 0xe0, 0x02, 0x80,
        ];
        assert_eq!(declared_size(&jpeg), Some((640, 480)));
        assert_eq!(declared_size(b"GIF89a"), None);
        assert!(check_declared_size(&jpeg).is_ok());
    }
}
