//! The saved-hierarchy container: any method's built structure with its
//! method tag and parameters, in a versioned, checksummed file, so the studio
//! reopens it without rebuilding and cuts it exactly as before. The container
//! knows no method: `lod::saved` decodes each through its [`crate::lod::Method`].
//!
//! Layout (little endian): magic `LODSTHRY`, format version (u32), method name
//! (u16 length + UTF-8), parameters (u32 length + JSON), body (u64 length +
//! the hierarchy in bincode, which keeps every float bit-exact, infinities
//! included), then the CRC-32 of everything before it. Every length is checked
//! against what is left before reading, and the body decoder is limited to the
//! body's size, so a truncated or hostile file is an error, never a panic or a
//! huge allocation.

use bincode::Options;
use serde::Serialize;
use serde::de::DeserializeOwned;

const MAGIC: &[u8; 8] = b"LODSTHRY";
/// Bumped whenever a saved structure changes shape.
pub const VERSION: u32 = 9;

/// The body codec: fixed-width little-endian integers, no trailing bytes, and
/// never reading (or allocating for) more than `limit` bytes.
fn codec(limit: u64) -> impl Options {
    bincode::DefaultOptions::new()
        .with_fixint_encoding()
        .with_little_endian()
        .reject_trailing_bytes()
        .with_limit(limit)
}

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
    #[error("{0}")]
    OverBudget(String),
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
    // Serialising plain data into memory cannot fail.
    let encoded = codec(u64::MAX)
        .serialize(body)
        .expect("hierarchies serialise");
    out.extend_from_slice(&(encoded.len() as u64).to_le_bytes());
    out.extend_from_slice(&encoded);
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
    // The decoded structures are about the size of their encoding.
    super::limits::check_budget("the saved hierarchy's body", body.len() as u64)
        .map_err(|e| HierarchyFileError::OverBudget(e.expected))?;
    let value =
        codec(body.len() as u64)
            .deserialize(body)
            .map_err(|e| HierarchyFileError::Corrupt {
                what: "body",
                why: e.to_string(),
            })?;
    Ok((header, value))
}

/// Whether `bytes` start like a saved hierarchy.
pub fn is_hierarchy(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
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
            // Bit-exact, infinities included (the drain's error is one).
            errors: (0..200)
                .map(|i| i as f32 * 0.125)
                .chain([f32::INFINITY])
                .collect(),
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
        future[8] = VERSION as u8 + 1;
        assert_eq!(
            load::<Toy>(&future, "mergetree").unwrap_err(),
            HierarchyFileError::Version { found: VERSION + 1 }
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

    /// Saved and reopened MRGs and merge trees cut exactly as the originals,
    /// for views near and far, in pixels and in object space.
    #[test]
    fn reopened_hierarchies_give_identical_cuts() {
        use crate::lod::Hierarchy;
        use crate::view::{Tolerance, View};
        use std::sync::Arc;
        let mesh = crate::builtins::torus(1.0, 0.35, 48, 24);
        let p = crate::progress::Progress::new();
        let views: Vec<(View, Tolerance)> = (0..6)
            .map(|i| {
                let view = View::orbit(glam::Vec3::ZERO, 1.5 + i as f32, 0.7 * i as f32, 0.2);
                let tol = if i % 2 == 0 {
                    Tolerance::Pixels(1.0 + i as f32)
                } else {
                    Tolerance::Relative(0.01 * i as f32)
                };
                (view, tol)
            })
            .collect();
        let mrg = crate::hybrid::build(&mesh, &Default::default(), &p).unwrap();
        let bytes = save("hybrid", &serde_json::json!({}), &mrg);
        let (_, back): (_, crate::hybrid::Mrg) = load(&bytes, "hybrid").unwrap();
        let (mut a, mut b) = (
            crate::hybrid::HybridCut::new(Arc::new(mrg)),
            crate::hybrid::HybridCut::new(Arc::new(back)),
        );
        for (view, tol) in &views {
            assert_eq!(a.select(view, *tol), b.select(view, *tol));
        }
        let tree = crate::mergetree::build(&mesh, &Default::default(), &p).unwrap();
        let bytes = save("mergetree", &serde_json::json!({}), &tree);
        let (_, back): (_, crate::mergetree::MergeTree) = load(&bytes, "mergetree").unwrap();
        let criteria = crate::mergetree::Criteria::default();
        let mut a = crate::mergetree::MergeTreeView::new(Arc::new(tree), criteria);
        let mut b = crate::mergetree::MergeTreeView::new(Arc::new(back), criteria);
        for (view, tol) in &views {
            assert_eq!(a.select(view, *tol), b.select(view, *tol));
        }
    }
}
