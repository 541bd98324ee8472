//! Saved hierarchies: a built MRG, merge tree, voxel pyramid or AMG multiscale
//! with its parameters, in a versioned, checksummed file, so the studio reopens
//! it without rebuilding and cuts it exactly as before.
//!
//! Layout (little endian): magic `LODSTHRY`, format version (u32), method name
//! (u16 length + UTF-8), parameters (u32 length + JSON), body (u64 length +
//! gzip-compressed JSON of the hierarchy), then the CRC-32 of everything
//! before it. Every length is checked against what is left before reading, so
//! a truncated or hostile file is an error, never a panic or a huge allocation.

use std::io::{Read, Write};

use serde::Serialize;
use serde::de::DeserializeOwned;

const MAGIC: &[u8; 8] = b"LODSTHRY";
/// Bumped whenever a saved structure changes shape.
pub const VERSION: u32 = 1;
/// A body inflating beyond this many times its compressed size is refused.
const MAX_INFLATION: u64 = 64;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HierarchyFileError {
    #[error("not a saved lodstudio hierarchy (no LODSTHRY header)")]
    NotAHierarchy,
    #[error("saved by a different format version ({found}; this lodstudio reads {VERSION})")]
    Version { found: u32 },
    #[error("truncated: the {what} needs {needed} bytes but only {left} are left")]
    Truncated {
        what: &'static str,
        needed: u64,
        left: u64,
    },
    #[error(
        "checksum mismatch (stored {stored:08x}, computed {computed:08x}): the file is corrupted"
    )]
    Checksum { stored: u32, computed: u32 },
    #[error("holds a {found} hierarchy, not a {expected} one")]
    WrongMethod { found: String, expected: String },
    #[error("corrupted {what}: {why}")]
    Corrupt { what: &'static str, why: String },
}

/// What a file says about itself before its body is read.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    pub version: u32,
    pub method: String,
    pub params: serde_json::Value,
}

/// Encodes `body` (the built hierarchy) with its method name and parameters.
pub fn save<T: Serialize>(method: &str, params: &serde_json::Value, body: &T) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    let name = method.as_bytes();
    out.extend_from_slice(&(name.len().min(u16::MAX as usize) as u16).to_le_bytes());
    out.extend_from_slice(&name[..name.len().min(u16::MAX as usize)]);
    let params = params.to_string().into_bytes();
    out.extend_from_slice(&(params.len() as u32).to_le_bytes());
    out.extend_from_slice(&params);
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    // Serialising plain data into memory cannot fail.
    let json = serde_json::to_vec(body).expect("hierarchies serialise");
    gz.write_all(&json).expect("in-memory gzip");
    let compressed = gz.finish().expect("in-memory gzip");
    out.extend_from_slice(&(compressed.len() as u64).to_le_bytes());
    out.extend_from_slice(&compressed);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// A cursor that refuses to read past the end.
struct Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: u64, what: &'static str) -> Result<&'a [u8], HierarchyFileError> {
        let left = (self.data.len() - self.at) as u64;
        if n > left {
            return Err(HierarchyFileError::Truncated {
                what,
                needed: n,
                left,
            });
        }
        let s = &self.data[self.at..self.at + n as usize];
        self.at += n as usize;
        Ok(s)
    }
    fn word<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], HierarchyFileError> {
        Ok(self.take(N as u64, what)?.try_into().expect("N bytes"))
    }
}

/// Reads the header and returns it with the compressed body, after checking
/// the magic, the version, every length and the checksum.
fn open(bytes: &[u8]) -> Result<(Header, &[u8]), HierarchyFileError> {
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(HierarchyFileError::NotAHierarchy);
    }
    let mut r = Reader {
        data: bytes,
        at: MAGIC.len(),
    };
    let version = u32::from_le_bytes(r.word("version")?);
    if version != VERSION {
        return Err(HierarchyFileError::Version { found: version });
    }
    let name_len = u16::from_le_bytes(r.word("method name length")?);
    let name = r.take(name_len as u64, "method name")?;
    let params_len = u32::from_le_bytes(r.word("parameters length")?);
    let params = r.take(params_len as u64, "parameters")?;
    let body_len = u64::from_le_bytes(r.word("body length")?);
    let body = r.take(body_len, "body")?;
    let end = r.at;
    let stored = u32::from_le_bytes(r.word("checksum")?);
    let computed = crc32fast::hash(&bytes[..end]);
    if stored != computed {
        return Err(HierarchyFileError::Checksum { stored, computed });
    }
    let corrupt = |what, why: String| HierarchyFileError::Corrupt { what, why };
    let method =
        String::from_utf8(name.to_vec()).map_err(|e| corrupt("method name", e.to_string()))?;
    let params =
        serde_json::from_slice(params).map_err(|e| corrupt("parameters", e.to_string()))?;
    Ok((
        Header {
            version,
            method,
            params,
        },
        body,
    ))
}

/// The header of a saved hierarchy (checked whole, body included).
pub fn peek(bytes: &[u8]) -> Result<Header, HierarchyFileError> {
    open(bytes).map(|(h, _)| h)
}

/// Decodes a saved hierarchy of `method`, with its parameters.
pub fn load<T: DeserializeOwned>(
    bytes: &[u8],
    method: &str,
) -> Result<(Header, T), HierarchyFileError> {
    let (header, body) = open(bytes)?;
    if header.method != method {
        return Err(HierarchyFileError::WrongMethod {
            found: header.method,
            expected: method.to_string(),
        });
    }
    let corrupt = |why: String| HierarchyFileError::Corrupt { what: "body", why };
    let limit = (body.len() as u64)
        .saturating_mul(MAX_INFLATION)
        .max(1 << 20);
    let mut json = Vec::new();
    flate2::read::GzDecoder::new(body)
        .take(limit + 1)
        .read_to_end(&mut json)
        .map_err(|e| corrupt(e.to_string()))?;
    if json.len() as u64 > limit {
        return Err(corrupt("inflates beyond any hierarchy this size".into()));
    }
    let value = serde_json::from_slice(&json).map_err(|e| corrupt(e.to_string()))?;
    Ok((header, value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    struct Toy {
        levels: Vec<Vec<u32>>,
        errors: Vec<f32>,
    }

    fn toy() -> Toy {
        Toy {
            levels: (0..50).map(|i| (0..i).collect()).collect(),
            errors: (0..200).map(|i| i as f32 * 0.125).collect(),
        }
    }

    #[test]
    fn round_trips_with_method_and_parameters() {
        let params = serde_json::json!({"kappa": 3.0, "tau": 5.0});
        let bytes = save("hybrid", &params, &toy());
        let (header, back): (Header, Toy) = load(&bytes, "hybrid").unwrap();
        assert_eq!(back, toy());
        assert_eq!(
            header,
            Header {
                version: VERSION,
                method: "hybrid".into(),
                params
            }
        );
        assert!(matches!(
            load::<Toy>(&bytes, "amg"),
            Err(HierarchyFileError::WrongMethod { .. })
        ));
    }

    #[test]
    fn truncation_and_corruption_are_clear_errors() {
        let bytes = save("mergetree", &serde_json::json!({}), &toy());
        // Every truncation fails, and never panics.
        for len in 0..bytes.len() {
            let e = load::<Toy>(&bytes[..len], "mergetree").unwrap_err();
            assert!(
                matches!(
                    e,
                    HierarchyFileError::NotAHierarchy | HierarchyFileError::Truncated { .. }
                ),
                "{len}: {e}"
            );
        }
        // Every single-byte flip after the magic is caught.
        for at in (8..bytes.len()).step_by(7) {
            let mut bad = bytes.clone();
            bad[at] ^= 0x5a;
            assert!(load::<Toy>(&bad, "mergetree").is_err(), "flip at {at}");
        }
        let mut future = bytes.clone();
        future[8] = 9;
        assert_eq!(
            load::<Toy>(&future, "mergetree").unwrap_err(),
            HierarchyFileError::Version { found: 9 }
        );
        // A hostile length does not allocate: it is checked against what is left.
        let mut huge = bytes[..8 + 4 + 2 + 9].to_vec();
        huge.extend_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            load::<Toy>(&huge, "mergetree"),
            Err(HierarchyFileError::Truncated {
                what: "parameters",
                ..
            })
        ));
    }
}
