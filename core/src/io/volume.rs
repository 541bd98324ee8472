//! Scalar volumes: headerless raw, NRRD (attached data), NIfTI-1 (single file)
//! and INRIMAGE-4. Samples become f32, x fastest.
//!
//! Dimensions come from headers, so their product is computed with checked
//! arithmetic and compared with the bytes present before anything is allocated.

use glam::Vec3;

use super::text::Lines;
use super::{Location, ParseError, ParseResult};
use crate::geom::Volume;

/// Sample type of a volume (also the PLY property types).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScalarType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
    F64,
}

impl ScalarType {
    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            ScalarType::U8 | ScalarType::I8 => 1,
            ScalarType::U16 | ScalarType::I16 => 2,
            ScalarType::U32 | ScalarType::I32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    /// Accepts the spellings of NRRD, PLY, C and command lines, case-insensitively:
    /// `u8`, `uint8`, `uint8_t`, `uchar`, `unsigned char`, `i8`, `int8`, `char`,
    /// `signed char`, ... `float`, `float32`, `f32`, `double`, `float64`, `f64`.
    pub fn parse(name: &str) -> Option<ScalarType> {
        let words: Vec<String> = name
            .split_ascii_whitespace()
            .map(str::to_ascii_lowercase)
            .collect();
        Some(match words.join(" ").as_str() {
            "u8" | "uint8" | "uint8_t" | "uchar" | "unsigned char" => ScalarType::U8,
            "i8" | "int8" | "int8_t" | "char" | "signed char" => ScalarType::I8,
            "u16" | "uint16" | "uint16_t" | "ushort" | "unsigned short" | "unsigned short int" => {
                ScalarType::U16
            }
            "i16" | "int16" | "int16_t" | "short" | "short int" | "signed short"
            | "signed short int" => ScalarType::I16,
            "u32" | "uint32" | "uint32_t" | "uint" | "unsigned int" => ScalarType::U32,
            "i32" | "int32" | "int32_t" | "int" | "signed int" => ScalarType::I32,
            "f32" | "float32" | "float" => ScalarType::F32,
            "f64" | "float64" | "double" => ScalarType::F64,
            _ => return None,
        })
    }

    pub(super) fn is_float(self) -> bool {
        matches!(self, ScalarType::F32 | ScalarType::F64)
    }

    /// Decodes one sample from the first [`size`](Self::size) bytes of `b`; the
    /// caller has checked that they are there. f64 holds every type exactly.
    pub(super) fn decode(self, b: &[u8], big_endian: bool) -> f64 {
        fn bytes<const N: usize>(b: &[u8], big_endian: bool) -> [u8; N] {
            let mut a = [0; N];
            a.copy_from_slice(&b[..N]);
            if big_endian {
                a.reverse();
            }
            a
        }
        let be = big_endian;
        match self {
            ScalarType::U8 => f64::from(b[0]),
            ScalarType::I8 => f64::from(b[0] as i8),
            ScalarType::U16 => f64::from(u16::from_le_bytes(bytes(b, be))),
            ScalarType::I16 => f64::from(i16::from_le_bytes(bytes(b, be))),
            ScalarType::U32 => f64::from(u32::from_le_bytes(bytes(b, be))),
            ScalarType::I32 => f64::from(i32::from_le_bytes(bytes(b, be))),
            ScalarType::F32 => f64::from(f32::from_le_bytes(bytes(b, be))),
            ScalarType::F64 => f64::from_le_bytes(bytes(b, be)),
        }
    }
}

/// Layout of a headerless volume, given by the user.
#[derive(Debug, Clone, PartialEq)]
pub struct RawSpec {
    pub dims: [usize; 3],
    pub scalar: ScalarType,
    pub big_endian: bool,
    pub spacing: Vec3,
    /// Bytes to skip before the samples.
    pub header_bytes: usize,
}

/// Voxel count of `dims`; zero or overflowing dimensions are errors.
fn voxel_count(dims: [usize; 3], at: Location) -> ParseResult<usize> {
    let [x, y, z] = dims;
    if dims.contains(&0) {
        return Err(ParseError::new(
            at,
            format!("expected non-zero dimensions, found {x} x {y} x {z}"),
        ));
    }
    let count = x
        .checked_mul(y)
        .and_then(|n| n.checked_mul(z))
        .ok_or_else(|| {
            ParseError::new(
                at.clone(),
                format!("expected dimensions whose product fits in memory, found {x} x {y} x {z}"),
            )
        })?;
    // Samples are held as f32 whatever their type on disk.
    super::limits::check_items(&format!("voxels ({x} x {y} x {z})"), count, 4)
        .map_err(|e| ParseError::new(at, e.expected))?;
    Ok(count)
}

/// Decodes `count` samples starting at `data[offset..]`; `exact` also refuses
/// trailing bytes (a raw file of the wrong size means wrong dimensions).
fn samples(
    data: &[u8],
    offset: usize,
    count: usize,
    scalar: ScalarType,
    big_endian: bool,
    exact: bool,
) -> ParseResult<Vec<f32>> {
    let size = scalar.size();
    let have = data.len().saturating_sub(offset);
    match count.checked_mul(size) {
        Some(need) if need <= have && (!exact || need == have) => Ok(data[offset..offset + need]
            .chunks_exact(size)
            .map(|c| scalar.decode(c, big_endian) as f32)
            .collect()),
        _ => Err(ParseError::byte(
            offset as u64,
            format!(
                "expected {}{count} samples of {size} bytes, found {have} bytes",
                if exact { "exactly " } else { "" }
            ),
        )),
    }
}

/// A usable voxel size: non-finite or zero (common in headers) means 1.
fn voxel_size(v: f64) -> f32 {
    if v.is_finite() && v != 0.0 {
        v.abs() as f32
    } else {
        1.0
    }
}

/// Reads a headerless volume laid out as `spec` says; the size must match exactly.
pub fn read_raw(data: &[u8], spec: &RawSpec) -> ParseResult<Volume> {
    let count = voxel_count(spec.dims, Location::File)?;
    if !(spec.spacing.is_finite() && spec.spacing.min_element() > 0.0) {
        return Err(ParseError::file(format!(
            "expected a positive voxel size, found {}",
            spec.spacing
        )));
    }
    let data = samples(
        data,
        spec.header_bytes,
        count,
        spec.scalar,
        spec.big_endian,
        true,
    )?;
    Ok(Volume {
        dims: spec.dims,
        spacing: spec.spacing,
        origin: Vec3::ZERO,
        data,
    })
}

// ---------------------------------------------------------------------------
// NRRD
// ---------------------------------------------------------------------------

/// Parses NRRD vectors such as `(1,0,0) none (0, 2.5,0)`; `none` is `None`.
fn nrrd_vectors(value: &str) -> Option<Vec<Option<Vec<f64>>>> {
    let mut out = Vec::new();
    let mut rest = value.trim();
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("none") {
            out.push(None);
            rest = r.trim_start();
        } else {
            let (inner, r) = rest.strip_prefix('(')?.split_once(')')?;
            let v = inner
                .split(',')
                .map(|s| s.trim().parse().ok())
                .collect::<Option<Vec<f64>>>()?;
            out.push(Some(v));
            rest = r.trim_start();
        }
    }
    Some(out)
}

fn nrrd_numbers<T: std::str::FromStr>(value: &str) -> Option<Vec<T>> {
    value
        .split_ascii_whitespace()
        .map(|s| s.parse().ok())
        .collect()
}

/// Reads a NRRD file (NRRD0001..NRRD0005) with attached raw or gzip data.
pub fn read_nrrd(data: &[u8]) -> ParseResult<Volume> {
    let mut lines = Lines::new(data);
    match lines.next() {
        Some((_, l))
            if l.len() == 8 && l.starts_with(b"NRRD000") && (b'1'..=b'5').contains(&l[7]) => {}
        _ => {
            return Err(ParseError::line(
                1,
                "expected a NRRD0001 .. NRRD0005 magic line",
            ));
        }
    }
    let mut scalar = None;
    let mut dimension = None;
    let mut sizes: Option<(usize, Vec<usize>)> = None;
    let mut big_endian = None;
    let mut gzip = None;
    let mut spacings: Option<(usize, Vec<f64>)> = None;
    let mut directions: Option<(usize, Vec<Option<Vec<f64>>>)> = None;
    let mut origin = Vec3::ZERO;
    let mut byte_skip: i64 = 0;
    let mut line_skip: u64 = 0;
    loop {
        let Some((n, raw)) = lines.next() else {
            return Err(ParseError::line(
                lines.line(),
                "expected a blank line ending the header and the data after it, found the end of the file",
            ));
        };
        if raw.trim_ascii().is_empty() {
            break;
        }
        if raw.starts_with(b"#") {
            continue;
        }
        let text = std::str::from_utf8(raw)
            .map_err(|_| ParseError::line(n, "expected a text header line"))?;
        let Some((field, value)) = text.split_once(':') else {
            return Err(ParseError::line(
                n,
                "expected `field: value` or `key:=value`",
            ));
        };
        if value.starts_with('=') {
            continue; // key/value pairs carry no layout
        }
        let value = value.trim();
        let bad = |what: &str| ParseError::line(n, format!("expected {what}, found `{value}`"));
        match field {
            "type" => {
                scalar =
                    Some(ScalarType::parse(value).ok_or_else(|| {
                        bad("a type of 8, 16 or 32-bit integers, float or double")
                    })?);
            }
            "dimension" => {
                dimension = Some((n, value.parse::<usize>().map_err(|_| bad("a dimension"))?));
            }
            "sizes" => sizes = Some((n, nrrd_numbers(value).ok_or_else(|| bad("sizes"))?)),
            "endian" => {
                big_endian = Some(match value {
                    "little" => false,
                    "big" => true,
                    _ => return Err(bad("little or big")),
                });
            }
            "encoding" => {
                gzip = Some(match value {
                    "raw" => false,
                    "gzip" | "gz" => true,
                    _ => {
                        return Err(bad(
                            "encoding raw or gzip (ascii, hex and bzip2 are not supported)",
                        ));
                    }
                });
            }
            "spacings" => spacings = Some((n, nrrd_numbers(value).ok_or_else(|| bad("spacings"))?)),
            "space directions" => {
                directions = Some((
                    n,
                    nrrd_vectors(value).ok_or_else(|| bad("vectors like (1,0,0)"))?,
                ));
            }
            "space origin" => match nrrd_vectors(value).as_deref() {
                Some([Some(v)]) if v.len() == 3 => {
                    origin = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
                }
                _ => return Err(bad("an origin like (0,0,0)")),
            },
            "byte skip" | "byteskip" => {
                byte_skip = value
                    .parse()
                    .ok()
                    .filter(|v| *v >= -1)
                    .ok_or_else(|| bad("a byte skip of -1 or more"))?;
            }
            "line skip" | "lineskip" => {
                line_skip = value.parse().map_err(|_| bad("a line skip of 0 or more"))?;
            }
            "data file" | "datafile" => {
                return Err(ParseError::line(
                    n,
                    "expected the data attached after the header: detached data files are not supported",
                ));
            }
            _ => {}
        }
    }
    let header_end = lines.line();
    let missing =
        |f: &str| ParseError::line(header_end, format!("expected a `{f}` field in the header"));
    let scalar = scalar.ok_or_else(|| missing("type"))?;
    let (dim_line, dimension) = dimension.ok_or_else(|| missing("dimension"))?;
    let gzip = gzip.ok_or_else(|| missing("encoding"))?;
    let (size_line, sizes) = sizes.ok_or_else(|| missing("sizes"))?;
    if !(dimension == 3 || dimension == 4) {
        return Err(ParseError::line(
            dim_line,
            format!("expected dimension 3 (or 4 with a first size of 1), found {dimension}"),
        ));
    }
    // A 4-D file with one sample per voxel is a scalar volume with a leading axis.
    let lead = dimension - 3;
    if sizes.len() != dimension || sizes[..lead].iter().any(|s| *s != 1) {
        return Err(ParseError::line(
            size_line,
            format!(
                "expected {dimension} sizes (a first size of 1 when there are 4), found {sizes:?}"
            ),
        ));
    }
    let dims = [sizes[lead], sizes[lead + 1], sizes[lead + 2]];
    let count = voxel_count(dims, Location::Line(size_line))?;
    let big_endian = match big_endian {
        Some(b) => b,
        None if scalar.size() == 1 => false,
        None => return Err(missing("endian")),
    };
    let mut spacing = Vec3::ONE;
    if let Some((line, d)) = directions {
        if d.len() != dimension {
            return Err(ParseError::line(
                line,
                format!("expected {dimension} space directions"),
            ));
        }
        for (k, v) in d[lead..].iter().enumerate() {
            let Some(v) = v else {
                return Err(ParseError::line(
                    line,
                    "expected a vector, not `none`, for each spatial axis",
                ));
            };
            spacing[k] = voxel_size(v.iter().map(|c| c * c).sum::<f64>().sqrt());
        }
    } else if let Some((line, s)) = spacings {
        if s.len() != dimension {
            return Err(ParseError::line(
                line,
                format!("expected {dimension} spacings"),
            ));
        }
        for (k, v) in s[lead..].iter().enumerate() {
            spacing[k] = voxel_size(*v);
        }
    }

    let mut body = &data[lines.pos()..];
    let at = |body: &[u8]| (data.len() - body.len()) as u64;
    for _ in 0..line_skip {
        let Some(nl) = body.iter().position(|&b| b == b'\n') else {
            return Err(ParseError::byte(
                at(body),
                format!("expected {line_skip} lines to skip"),
            ));
        };
        body = &body[nl + 1..];
    }
    let offset = at(body);
    let unzipped;
    if gzip {
        unzipped =
            super::gunzip(body, u64::MAX).map_err(|e| ParseError::byte(offset, e.expected))?;
        body = &unzipped;
    }
    let need = count.saturating_mul(scalar.size());
    let skip = match usize::try_from(byte_skip) {
        Ok(s) => s,
        // -1: the samples are the last bytes of the (raw) data.
        Err(_) if !gzip => body.len().saturating_sub(need),
        Err(_) => {
            return Err(ParseError::byte(
                offset,
                "expected a byte skip of 0 or more with gzip data",
            ));
        }
    };
    let data = samples(body, skip, count, scalar, big_endian, false)
        .map_err(|e| ParseError::byte(offset, e.expected))?;
    Ok(Volume {
        dims,
        spacing,
        origin,
        data,
    })
}

// ---------------------------------------------------------------------------
// NIfTI-1
// ---------------------------------------------------------------------------

const NIFTI_HEADER: usize = 348;

/// Whether `data` starts with a NIfTI-1 header (either byte order).
pub fn is_nifti(data: &[u8]) -> bool {
    let Some(h) = data.get(..NIFTI_HEADER) else {
        return false;
    };
    let size = [h[0], h[1], h[2], h[3]];
    (i32::from_le_bytes(size) == 348 || i32::from_be_bytes(size) == 348)
        && matches!(&h[344..348], b"n+1\0" | b"ni1\0")
}

/// Reads a single-file NIfTI-1 image (`.nii`, already gunzipped).
pub fn read_nifti(data: &[u8]) -> ParseResult<Volume> {
    let h = data.get(..NIFTI_HEADER).ok_or_else(|| {
        ParseError::file(format!(
            "expected a {NIFTI_HEADER}-byte NIfTI-1 header, found {} bytes",
            data.len()
        ))
    })?;
    let size = [h[0], h[1], h[2], h[3]];
    let be = if i32::from_le_bytes(size) == 348 {
        false
    } else if i32::from_be_bytes(size) == 348 {
        true
    } else {
        return Err(ParseError::byte(0, "expected sizeof_hdr 348"));
    };
    match &h[344..348] {
        b"n+1\0" => {}
        b"ni1\0" => {
            return Err(ParseError::byte(
                344,
                "expected a single-file .nii (magic n+1): .hdr/.img pairs are not supported",
            ));
        }
        _ => return Err(ParseError::byte(344, "expected the NIfTI-1 magic n+1")),
    }
    let i16_at = |o: usize| ScalarType::I16.decode(&h[o..], be) as i64;
    let f32_at = |o: usize| ScalarType::F32.decode(&h[o..], be);
    let ndim = i16_at(40);
    if !(1..=7).contains(&ndim) {
        return Err(ParseError::byte(
            40,
            format!("expected dim[0] in 1..7, found {ndim}"),
        ));
    }
    let mut dims = [1usize; 3];
    for k in 1..=ndim as usize {
        let d = i16_at(40 + 2 * k);
        if d < 1 || (k > 3 && d != 1) {
            return Err(ParseError::byte(
                (40 + 2 * k) as u64,
                format!(
                    "expected dim[{k}] to be {}, found {d}",
                    if k > 3 {
                        "1 (a scalar 3-D image)"
                    } else {
                        "1 or more"
                    }
                ),
            ));
        }
        if k <= 3 {
            dims[k - 1] = d as usize;
        }
    }
    let scalar = match i16_at(70) {
        2 => ScalarType::U8,
        4 => ScalarType::I16,
        8 => ScalarType::I32,
        16 => ScalarType::F32,
        64 => ScalarType::F64,
        256 => ScalarType::I8,
        512 => ScalarType::U16,
        768 => ScalarType::U32,
        other => {
            return Err(ParseError::byte(
                70,
                format!("expected datatype 2, 4, 8, 16, 64, 256, 512 or 768, found {other}"),
            ));
        }
    };
    let vox_offset = f32_at(108);
    if !(vox_offset >= NIFTI_HEADER as f64 && vox_offset.fract() == 0.0) {
        return Err(ParseError::byte(
            108,
            format!(
                "expected vox_offset of {NIFTI_HEADER} or more whole bytes, found {vox_offset}"
            ),
        ));
    }
    if vox_offset > data.len() as f64 {
        return Err(ParseError::byte(
            108,
            format!(
                "expected vox_offset within the {} bytes of the file, found {vox_offset}",
                data.len()
            ),
        ));
    }
    let count = voxel_count(dims, Location::Byte(42))?;
    let mut samples = samples(data, vox_offset as usize, count, scalar, be, false)?;
    let (slope, inter) = (f32_at(112), f32_at(116));
    if slope != 0.0 && slope.is_finite() && inter.is_finite() && (slope, inter) != (1.0, 0.0) {
        let (slope, inter) = (slope as f32, inter as f32);
        for v in &mut samples {
            *v = *v * slope + inter;
        }
    }
    let vec3 = |o: [usize; 3]| o.map(|o| f32_at(o) as f32).into();
    // The qform (else sform) translation places the first voxel.
    let origin = if i16_at(252) > 0 {
        vec3([268, 272, 276])
    } else if i16_at(254) > 0 {
        vec3([292, 308, 324])
    } else {
        Vec3::ZERO
    };
    Ok(Volume {
        dims,
        spacing: [80, 84, 88].map(|o| voxel_size(f32_at(o))).into(),
        origin,
        data: samples,
    })
}

// ---------------------------------------------------------------------------
// INRIMAGE-4
// ---------------------------------------------------------------------------

/// Reads an INRIMAGE-4 file: 256-byte header blocks ending with `##}\n`, then samples.
pub fn read_inr(data: &[u8]) -> ParseResult<Volume> {
    if !data.starts_with(b"#INRIMAGE-4#{") {
        return Err(ParseError::line(
            1,
            "expected `#INRIMAGE-4#{` on the first line",
        ));
    }
    let end = data
        .windows(4)
        .position(|w| w == b"##}\n")
        .ok_or_else(|| ParseError::file("expected the header to end with `##}`"))?;
    let mut lines = Lines::new(&data[..end]);
    lines.next();
    let mut dims = [None; 3];
    let (mut kind, mut bits, mut big_endian) = (None, None, None);
    let mut spacing = Vec3::ONE;
    for (n, raw) in lines.by_ref() {
        let text = std::str::from_utf8(raw)
            .map_err(|_| ParseError::line(n, "expected a text header line"))?;
        let Some((key, value)) = text.split_once('=') else {
            continue; // padding and comments
        };
        let value = value.trim();
        let bad = |what: &str| ParseError::line(n, format!("expected {what}, found `{value}`"));
        let dim = || {
            value
                .parse::<usize>()
                .ok()
                .filter(|d| *d > 0)
                .ok_or_else(|| bad("a dimension of 1 or more"))
        };
        match key.trim() {
            "XDIM" => dims[0] = Some(dim()?),
            "YDIM" => dims[1] = Some(dim()?),
            "ZDIM" => dims[2] = Some(dim()?),
            "VDIM" if dim()? != 1 => return Err(bad("VDIM=1 (a scalar image)")),
            "TYPE" => {
                kind = Some(match value {
                    "float" => 'f',
                    "unsigned fixed" => 'u',
                    "signed fixed" => 's',
                    _ => return Err(bad("TYPE float, unsigned fixed or signed fixed")),
                });
            }
            "PIXSIZE" => {
                let b = value
                    .split_ascii_whitespace()
                    .next()
                    .and_then(|b| b.parse::<u32>().ok());
                bits = Some((n, b.ok_or_else(|| bad("a pixel size like `32 bits`"))?));
            }
            "CPU" => {
                big_endian = Some(match value {
                    "decm" | "alpha" | "pc" => false,
                    "sun" | "sgi" => true,
                    _ => return Err(bad("CPU decm, alpha, pc, sun or sgi")),
                });
            }
            k @ ("VX" | "VY" | "VZ") => {
                let v: f64 = value.parse().map_err(|_| bad("a voxel size"))?;
                spacing[usize::from(k.as_bytes()[1] - b'X')] = voxel_size(v);
            }
            _ => {}
        }
    }
    let missing = |f: &str| ParseError::file(format!("expected {f} in the header"));
    let [Some(x), Some(y), Some(z)] = dims else {
        return Err(missing("XDIM, YDIM and ZDIM"));
    };
    let kind = kind.ok_or_else(|| missing("TYPE"))?;
    let (bits_line, bits) = bits.ok_or_else(|| missing("PIXSIZE"))?;
    let scalar = match (kind, bits) {
        ('f', 32) => ScalarType::F32,
        ('f', 64) => ScalarType::F64,
        ('u', 8) => ScalarType::U8,
        ('u', 16) => ScalarType::U16,
        ('u', 32) => ScalarType::U32,
        ('s', 8) => ScalarType::I8,
        ('s', 16) => ScalarType::I16,
        ('s', 32) => ScalarType::I32,
        _ => {
            return Err(ParseError::line(
                bits_line,
                format!("expected a pixel size of 8, 16, 32 (or 64 for float) bits, found {bits}"),
            ));
        }
    };
    let big_endian = match big_endian {
        Some(b) => b,
        None if scalar.size() == 1 => false,
        None => return Err(missing("CPU")),
    };
    let dims = [x, y, z];
    let count = voxel_count(dims, Location::File)?;
    let data = samples(data, end + 4, count, scalar, big_endian, false)?;
    Ok(Volume {
        dims,
        spacing,
        origin: Vec3::ZERO,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TYPES: [ScalarType; 8] = [
        ScalarType::U8,
        ScalarType::I8,
        ScalarType::U16,
        ScalarType::I16,
        ScalarType::U32,
        ScalarType::I32,
        ScalarType::F32,
        ScalarType::F64,
    ];

    fn encode(values: &[f64], t: ScalarType, be: bool) -> Vec<u8> {
        let mut out = Vec::new();
        for &v in values {
            macro_rules! put {
                ($ty:ty) => {{
                    let x = v as $ty;
                    out.extend_from_slice(&if be { x.to_be_bytes() } else { x.to_le_bytes() });
                }};
            }
            match t {
                ScalarType::U8 => put!(u8),
                ScalarType::I8 => put!(i8),
                ScalarType::U16 => put!(u16),
                ScalarType::I16 => put!(i16),
                ScalarType::U32 => put!(u32),
                ScalarType::I32 => put!(i32),
                ScalarType::F32 => put!(f32),
                ScalarType::F64 => put!(f64),
            }
        }
        out
    }

    fn gzip(data: &[u8]) -> Vec<u8> {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(data).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn scalar_type_names_and_sizes() {
        let names = [
            ("uchar", ScalarType::U8, 1),
            ("Unsigned  Char", ScalarType::U8, 1),
            ("int8", ScalarType::I8, 1),
            ("char", ScalarType::I8, 1),
            ("uint16_t", ScalarType::U16, 2),
            ("signed short int", ScalarType::I16, 2),
            ("uint", ScalarType::U32, 4),
            ("i32", ScalarType::I32, 4),
            ("float", ScalarType::F32, 4),
            ("float64", ScalarType::F64, 8),
            ("double", ScalarType::F64, 8),
        ];
        for (name, t, size) in names {
            assert_eq!(ScalarType::parse(name), Some(t), "{name}");
            assert_eq!(t.size(), size);
        }
        assert_eq!(ScalarType::parse("int64"), None);
        assert_eq!(ScalarType::parse(""), None);
    }

    fn spec(
        dims: [usize; 3],
        scalar: ScalarType,
        big_endian: bool,
        header_bytes: usize,
    ) -> RawSpec {
        RawSpec {
            dims,
            scalar,
            big_endian,
            spacing: Vec3::new(1.0, 2.0, 0.5),
            header_bytes,
        }
    }

    #[test]
    fn raw_reads_every_type_in_both_byte_orders() {
        for t in TYPES {
            for be in [false, true] {
                let signed = !matches!(t, ScalarType::U8 | ScalarType::U16 | ScalarType::U32);
                let values: Vec<f64> = (0..12)
                    .map(|i| {
                        if signed && i % 3 == 0 {
                            -f64::from(i)
                        } else {
                            f64::from(i)
                        }
                    })
                    .collect();
                let mut data = b"HEAD".to_vec();
                data.extend(encode(&values, t, be));
                let v = read_raw(&data, &spec([3, 2, 2], t, be, 4)).unwrap();
                assert_eq!(v.dims, [3, 2, 2]);
                assert_eq!(v.spacing, Vec3::new(1.0, 2.0, 0.5));
                let want: Vec<f32> = values.iter().map(|v| *v as f32).collect();
                assert_eq!(v.data, want, "{t:?} be={be}");
                assert_eq!(v.value(2, 1, 1), 11.0);
            }
        }
    }

    #[test]
    fn raw_rejects_bad_layouts() {
        let data = vec![0u8; 24];
        let ok = spec([2, 3, 4], ScalarType::U8, false, 0);
        assert_eq!(read_raw(&data, &ok).unwrap().data.len(), 24);
        let cases = [
            (spec([2, 0, 4], ScalarType::U8, false, 0), Location::File),
            (
                spec([usize::MAX, 2, 1], ScalarType::U8, false, 0),
                Location::File,
            ),
            (
                spec([1 << 40, 1 << 40, 1], ScalarType::U8, false, 0),
                Location::File,
            ),
            (
                spec([usize::MAX / 2, 1, 1], ScalarType::F64, false, 0),
                Location::File,
            ),
            (
                spec([2, 3, 4], ScalarType::U16, false, 0),
                Location::Byte(0),
            ),
            (spec([2, 3, 3], ScalarType::U8, false, 0), Location::Byte(0)),
            (spec([2, 3, 4], ScalarType::U8, false, 1), Location::Byte(1)),
            (
                spec([1, 1, 1], ScalarType::U8, false, 100),
                Location::Byte(100),
            ),
            (
                RawSpec {
                    spacing: Vec3::new(1.0, 0.0, 1.0),
                    ..ok.clone()
                },
                Location::File,
            ),
            (
                RawSpec {
                    spacing: Vec3::splat(f32::NAN),
                    ..ok.clone()
                },
                Location::File,
            ),
        ];
        for (s, at) in cases {
            assert_eq!(read_raw(&data, &s).unwrap_err().at, at, "{s:?}");
        }
    }

    #[test]
    fn nrrd_reads_raw_gzip_and_4d_files() {
        let mut f = b"NRRD0004\n# comment\ntype: short\ndimension: 3\nsizes: 2 2 1\nendian: big\nencoding: raw\nspace dimension: 3\nspace directions: (2,0,0) (0,0,3) (0, 4, 0)\nspace origin: (1, 2, 3)\nnote:=a: b\n\n".to_vec();
        f.extend(encode(&[1.0, -2.0, 3.0, 4.0], ScalarType::I16, true));
        let v = read_nrrd(&f).unwrap();
        assert_eq!(v.dims, [2, 2, 1]);
        assert_eq!(v.data, vec![1.0, -2.0, 3.0, 4.0]);
        assert_eq!(v.spacing, Vec3::new(2.0, 3.0, 4.0));
        assert_eq!(v.origin, Vec3::new(1.0, 2.0, 3.0));

        let samples = encode(&[0.5, 1.5, 2.5, 3.5], ScalarType::F32, false);
        let mut f = b"NRRD0005\r\ntype: float\r\ndimension: 4\r\nsizes: 1 2 1 2\r\nendian: little\r\nencoding: gzip\r\nspacings: nan 0.5 0.5 2\r\n\r\n".to_vec();
        f.extend(gzip(&samples));
        let v = read_nrrd(&f).unwrap();
        assert_eq!(v.dims, [2, 1, 2]);
        assert_eq!(v.data, vec![0.5, 1.5, 2.5, 3.5]);
        assert_eq!(v.spacing, Vec3::new(0.5, 0.5, 2.0));

        // Byte and line skips; one-byte samples need no endian field.
        let mut f = b"NRRD0001\ntype: uchar\ndimension: 3\nsizes: 1 1 2\nencoding: raw\nline skip: 1\nbyte skip: 2\n\nskipped line\nxx".to_vec();
        f.extend([7, 9]);
        assert_eq!(read_nrrd(&f).unwrap().data, vec![7.0, 9.0]);
        let mut f = b"NRRD0001\ntype: uchar\ndimension: 3\nsizes: 1 1 2\nencoding: raw\nbyte skip: -1\n\njunk".to_vec();
        f.extend([7, 9]);
        assert_eq!(read_nrrd(&f).unwrap().data, vec![7.0, 9.0]);
    }

    #[test]
    fn nrrd_errors_name_the_field() {
        let head = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 1\nencoding: raw\n";
        let line_cases: &[(&str, usize, &str)] = &[
            ("NRRD0009\n\n", 1, "magic"),
            ("NRRD0004\ndata file: vol.raw\n\n", 2, "detached"),
            ("NRRD0004\ntype: int64\n\n", 2, "type"),
            ("NRRD0004\nencoding: bzip2\n\n", 2, "raw or gzip"),
            ("NRRD0004\nendian: middle\n\n", 2, "little or big"),
            ("NRRD0004\nno colon\n\n", 2, "field: value"),
            (
                "NRRD0004\ndimension: 3\nsizes: 2 2 1\nencoding: raw\n\n",
                5,
                "`type`",
            ),
            (
                "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 2 2\nencoding: raw\n\n",
                3,
                "dimension 3",
            ),
            (
                "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 3 2 2 1\nencoding: raw\n\n",
                4,
                "first size of 1",
            ),
            (
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 0 1\nencoding: raw\n\n",
                4,
                "non-zero",
            ),
            (
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\nencoding: raw\n\n",
                4,
                "fits in memory",
            ),
            (
                "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 1\nencoding: raw\n\n",
                6,
                "`endian`",
            ),
            (
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 1\nencoding: raw\nspacings: 1 1\n\n",
                6,
                "3 spacings",
            ),
            (
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 1\nencoding: raw\nspace directions: (1,0,0) none (0,0,1)\n\n",
                6,
                "not `none`",
            ),
            ("NRRD0004\nspace origin: (1,2)\n\n", 2, "origin"),
            ("NRRD0004\ntype: uchar\n", 2, "blank line"),
        ];
        for (src, line, what) in line_cases {
            let e = read_nrrd(src.as_bytes()).unwrap_err();
            assert_eq!(e.at, Location::Line(*line), "{src:?}: {e:?}");
            assert!(e.expected.contains(what), "{src:?}: {}", e.expected);
        }
        let body = head.len() as u64 + 1;
        let e = read_nrrd(format!("{head}\n123").as_bytes()).unwrap_err();
        assert_eq!(e.at, Location::Byte(body));
        assert!(e.expected.contains("4 samples"), "{}", e.expected);
        let gz = format!("{head}\n").replace("raw", "gzip");
        let mut f = gz.clone().into_bytes();
        f.extend(b"not gzip");
        assert_eq!(
            read_nrrd(&f).unwrap_err().at,
            Location::Byte(gz.len() as u64)
        );
        let mut f = gz.into_bytes();
        f.extend(gzip(&[1, 2, 3]));
        assert!(matches!(read_nrrd(&f).unwrap_err().at, Location::Byte(_)));
    }

    struct Nifti {
        be: bool,
        datatype: i16,
        dims: Vec<i16>,
        slope: f32,
        inter: f32,
        magic: &'static [u8; 4],
        vox_offset: f32,
    }

    impl Nifti {
        fn new(be: bool, datatype: i16, dims: &[i16]) -> Self {
            Nifti {
                be,
                datatype,
                dims: dims.to_vec(),
                slope: 0.0,
                inter: 0.0,
                magic: b"n+1\0",
                vox_offset: 352.0,
            }
        }

        fn bytes(&self, body: &[u8]) -> Vec<u8> {
            let mut h = vec![0u8; 352];
            let be = self.be;
            let mut put = |o: usize, b: &[u8]| h[o..o + b.len()].copy_from_slice(b);
            let i16b = |v: i16| if be { v.to_be_bytes() } else { v.to_le_bytes() };
            let f32b = |v: f32| if be { v.to_be_bytes() } else { v.to_le_bytes() };
            put(
                0,
                &if be {
                    348i32.to_be_bytes()
                } else {
                    348i32.to_le_bytes()
                },
            );
            put(40, &i16b(self.dims.len() as i16));
            for (k, d) in self.dims.iter().enumerate() {
                put(42 + 2 * k, &i16b(*d));
            }
            put(70, &i16b(self.datatype));
            put(80, &f32b(1.5));
            put(84, &f32b(-2.0));
            put(88, &f32b(0.0));
            put(108, &f32b(self.vox_offset));
            put(112, &f32b(self.slope));
            put(116, &f32b(self.inter));
            put(252, &i16b(1));
            put(268, &f32b(-90.0));
            put(272, &f32b(-126.0));
            put(276, &f32b(-72.0));
            put(344, self.magic);
            h.extend_from_slice(body);
            h
        }
    }

    #[test]
    fn nifti_reads_both_byte_orders_and_applies_scaling() {
        let codes = [
            (2, ScalarType::U8),
            (4, ScalarType::I16),
            (8, ScalarType::I32),
            (16, ScalarType::F32),
            (64, ScalarType::F64),
            (256, ScalarType::I8),
            (512, ScalarType::U16),
            (768, ScalarType::U32),
        ];
        for be in [false, true] {
            for (code, t) in codes {
                let values = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
                let f = Nifti::new(be, code, &[3, 1, 2, 1]).bytes(&encode(&values, t, be));
                assert!(is_nifti(&f));
                let v = read_nifti(&f).unwrap();
                assert_eq!(v.dims, [3, 1, 2], "{t:?}");
                assert_eq!(v.data, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "{t:?} be={be}");
                assert_eq!(v.spacing, Vec3::new(1.5, 2.0, 1.0));
                assert_eq!(v.origin, Vec3::new(-90.0, -126.0, -72.0));
            }
            let mut n = Nifti::new(be, 4, &[2, 2]);
            n.slope = 0.5;
            n.inter = -1.0;
            let v =
                read_nifti(&n.bytes(&encode(&[2.0, 4.0, -6.0, 8.0], ScalarType::I16, be))).unwrap();
            assert_eq!(v.dims, [2, 2, 1]);
            assert_eq!(v.data, vec![0.0, 1.0, -4.0, 3.0]);
        }
    }

    #[test]
    fn nifti_errors_point_at_the_field() {
        let body = [0u8; 8];
        let base = || Nifti::new(false, 2, &[2, 2, 2]);
        assert!(read_nifti(&base().bytes(&body)).is_ok());
        let mut cases: Vec<(Nifti, u64)> = Vec::new();
        let mut n = base();
        n.magic = b"ni1\0";
        cases.push((n, 344));
        let mut n = base();
        n.magic = b"abc\0";
        cases.push((n, 344));
        cases.push((Nifti::new(false, 2, &[]), 40));
        cases.push((Nifti::new(false, 2, &[2, 2, 2, 2]), 48));
        cases.push((Nifti::new(false, 2, &[2, -2, 2]), 44));
        cases.push((Nifti::new(false, 128, &[2, 2, 2]), 70));
        cases.push((Nifti::new(false, 2, &[2, 2, 3]), 352));
        let mut n = base();
        n.vox_offset = 100.0;
        cases.push((n, 108));
        let mut n = base();
        n.vox_offset = f32::NAN;
        cases.push((n, 108));
        let mut n = base();
        n.vox_offset = 1e30;
        cases.push((n, 108));
        for (n, at) in cases {
            let e = read_nifti(&n.bytes(&body)).unwrap_err();
            assert_eq!(e.at, Location::Byte(at), "{}", e.expected);
        }
        let f = base().bytes(&body);
        assert_eq!(read_nifti(&f[..300]).unwrap_err().at, Location::File);
        let mut bad = f.clone();
        bad[0] = 0;
        assert!(!is_nifti(&bad));
        assert_eq!(read_nifti(&bad).unwrap_err().at, Location::Byte(0));
        assert!(!is_nifti(&f[..347]));
    }

    fn inr(fields: &str, body: &[u8]) -> Vec<u8> {
        let mut h = format!("#INRIMAGE-4#{{\n{fields}");
        while h.len() < 252 {
            h.push('\n');
        }
        h.push_str("##}\n");
        let mut out = h.into_bytes();
        out.extend_from_slice(body);
        out
    }

    #[test]
    fn inr_reads_types_and_byte_orders() {
        let f = inr(
            "XDIM=2\nYDIM=1\nZDIM=2\nVDIM=1\nTYPE=signed fixed\nPIXSIZE=16 bits\nSCALE=2**0\nCPU=sun\nVX=0.5\nVY=2\nVZ=3\n#comment\n",
            &encode(&[1.0, -2.0, 3.0, -4.0], ScalarType::I16, true),
        );
        let v = read_inr(&f).unwrap();
        assert_eq!(v.dims, [2, 1, 2]);
        assert_eq!(v.data, vec![1.0, -2.0, 3.0, -4.0]);
        assert_eq!(v.spacing, Vec3::new(0.5, 2.0, 3.0));
        let f = inr(
            "XDIM=1\nYDIM=1\nZDIM=1\nTYPE=float\nPIXSIZE=64 bits\nCPU=pc\n",
            &encode(&[2.5], ScalarType::F64, false),
        );
        assert_eq!(read_inr(&f).unwrap().data, vec![2.5]);
        let f = inr(
            "XDIM=2\nYDIM=1\nZDIM=1\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n",
            &[200, 3],
        );
        assert_eq!(read_inr(&f).unwrap().data, vec![200.0, 3.0]);
    }

    #[test]
    fn inr_errors() {
        let ok = "XDIM=2\nYDIM=1\nZDIM=1\nTYPE=float\nPIXSIZE=32 bits\nCPU=decm\n";
        assert!(read_inr(&inr(ok, &[0; 8])).is_ok());
        let cases: &[(&str, Location)] = &[
            (&ok.replace("XDIM=2", "XDIM=two"), Location::Line(2)),
            (&ok.replace("XDIM=2", "XDIM=0"), Location::Line(2)),
            (
                &ok.replace("XDIM=2", "XDIM=4294967296")
                    .replace("YDIM=1", "YDIM=4294967296"),
                Location::File,
            ),
            (&ok.replace("YDIM=1\n", "VDIM=3\n"), Location::Line(3)),
            (&ok.replace("ZDIM=1\n", ""), Location::File),
            (&ok.replace("TYPE=float", "TYPE=complex"), Location::Line(5)),
            (&ok.replace("32 bits", "12 bits"), Location::Line(6)),
            (&ok.replace("CPU=decm\n", ""), Location::File),
            (&ok.replace("CPU=decm", "CPU=vax"), Location::Line(7)),
            (&ok.replace("XDIM=2", "XDIM=4"), Location::Byte(256)),
        ];
        for (fields, at) in cases {
            let e = read_inr(&inr(fields, &[0; 8])).unwrap_err();
            assert_eq!(&e.at, at, "{fields:?}: {}", e.expected);
        }
        assert_eq!(
            read_inr(b"#INRIMAGE-4#{\nXDIM=1\n").unwrap_err().at,
            Location::File
        );
        assert_eq!(read_inr(b"INRIMAGE").unwrap_err().at, Location::Line(1));
    }

    #[test]
    fn no_prefix_or_corruption_panics() {
        let mut nrrd = b"NRRD0004\ntype: short\ndimension: 4\nsizes: 1 2 2 1\nendian: big\nencoding: raw\nspace directions: none (1,0,0) (0,1,0) (0,0,1)\nbyte skip: 0\n\n".to_vec();
        nrrd.extend([0, 1, 0, 2, 0, 3, 0, 4]);
        let nifti = Nifti::new(true, 4, &[2, 2, 1]).bytes(&[0, 1, 0, 2, 0, 3, 0, 4]);
        let inr = inr(
            "XDIM=2\nYDIM=2\nZDIM=1\nTYPE=signed fixed\nPIXSIZE=16 bits\nCPU=sun\n",
            &[0, 1, 0, 2, 0, 3, 0, 4],
        );
        type Reader = fn(&[u8]) -> ParseResult<Volume>;
        let readers: [(Reader, &[u8]); 3] =
            [(read_nrrd, &nrrd), (read_nifti, &nifti), (read_inr, &inr)];
        for (read, data) in readers {
            assert_eq!(read(data).unwrap().data, vec![1.0, 2.0, 3.0, 4.0]);
            for n in 0..data.len() {
                let _ = read(&data[..n]);
            }
            for i in 0..data.len() {
                for flip in [0x01, 0x80, 0xff] {
                    let mut d = data.to_vec();
                    d[i] ^= flip;
                    let _ = read(&d);
                }
            }
        }
    }

    fn shared(name: &str) -> Vec<u8> {
        let path = format!("{}/../../shared/models/{name}", env!("CARGO_MANIFEST_DIR"));
        std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    #[test]
    fn reads_the_skull_inr() {
        let v = read_inr(&shared("skull_2.9.inr")).unwrap();
        assert_eq!(v.dims, [64, 64, 64]);
        assert!(
            (v.spacing - Vec3::new(3.94305, 3.94305, 3.65079))
                .abs()
                .max_element()
                < 1e-6
        );
        let (lo, hi) = v.value_range();
        assert!((0.0..0.01).contains(&lo), "{lo}");
        assert!((hi - 5.43).abs() < 0.01, "{hi}");
    }

    #[test]
    fn reads_the_ch2_nifti() {
        let data = super::super::gunzip(&shared("ch2.nii.gz"), u64::MAX).unwrap();
        assert!(is_nifti(&data));
        let v = read_nifti(&data).unwrap();
        assert_eq!(v.dims, [181, 217, 181]);
        assert_eq!(v.spacing, Vec3::ONE);
        assert_eq!(v.value_range(), (0.0, 254.0));
    }
}
