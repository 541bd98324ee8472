//! EXT_meshopt_compression (and the ratified KHR_meshopt_compression):
//! buffer views stored by meshoptimizer's codecs, gltfpack's `-c` output
//! and the web's common geometry compression. They are decoded on load with
//! the `meshopt` crate into each view's own place, so every reader after
//! this sees plain bytes, and the written scene carries them uncompressed.
//!
//! A compressed view names its compressed bytes in the extension (`buffer`,
//! `byteOffset`, `byteLength`) and keeps its own `buffer`, `byteOffset` and
//! `byteLength` for the decoded `count · byteStride` bytes; that buffer is
//! usually a fallback with no data (`fallback: true`), given zeros here and
//! filled. meshoptimizer's decoders are safe on hostile bytes (they may
//! return garbage, which the accessor checks bound as for any file), but
//! they assert the strides and counts the format allows: those are checked
//! here first, so a hostile file gets an error, not an abort.

use serde_json::Value;

use super::error::{ParseError, ParseResult};

/// The extension's names: the vendor one and its ratified successor (the
/// same bitstreams, plus the COLOR filter).
pub const NAMES: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// The extension object of a buffer or a buffer view, with its name.
fn extension(v: &Value) -> Option<(&'static str, &Value)> {
    NAMES
        .iter()
        .find_map(|&n| v.get("extensions")?.get(n).map(|e| (n, e)))
}

/// Whether buffer `b` is a fallback: bytes that only decoded views fill
/// (it may have no URI and, in a GLB, is not the binary chunk).
pub fn is_fallback(root: &Value, b: usize) -> bool {
    extension(&root["buffers"][b])
        .is_some_and(|(_, e)| e.get("fallback").and_then(Value::as_bool) == Some(true))
}

/// One compressed view, as its extension describes it.
struct Compressed<'a> {
    source: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: &'a str,
    filter: &'a str,
}

impl<'a> Compressed<'a> {
    fn read(e: &'a Value, what: &dyn Fn() -> String) -> ParseResult<Self> {
        let field = |key: &str| -> ParseResult<usize> {
            e.get(key)
                .and_then(Value::as_u64)
                .and_then(|v| usize::try_from(v).ok())
                .ok_or_else(|| ParseError::item(what(), format!("expected a `{key}` count")))
        };
        let c = Compressed {
            source: field("buffer")?,
            offset: e.get("byteOffset").map_or(Ok(0), |_| field("byteOffset"))?,
            length: field("byteLength")?,
            stride: field("byteStride")?,
            count: field("count")?,
            mode: e.get("mode").and_then(Value::as_str).unwrap_or(""),
            filter: e.get("filter").and_then(Value::as_str).unwrap_or("NONE"),
        };
        // What the format allows (and the decoders assert).
        let allowed = match (c.mode, c.filter) {
            ("ATTRIBUTES", "NONE") | ("ATTRIBUTES", "EXPONENTIAL") => {
                c.stride > 0 && c.stride <= 256 && c.stride.is_multiple_of(4)
            }
            ("ATTRIBUTES", "OCTAHEDRAL") | ("ATTRIBUTES", "COLOR") => {
                c.stride == 4 || c.stride == 8
            }
            ("ATTRIBUTES", "QUATERNION") => c.stride == 8,
            ("TRIANGLES", "NONE") => (c.stride == 2 || c.stride == 4) && c.count.is_multiple_of(3),
            ("INDICES", "NONE") => c.stride == 2 || c.stride == 4,
            _ => false,
        };
        if !allowed {
            return Err(ParseError::item(
                what(),
                format!(
                    "expected a mode, filter, byteStride and count the format allows, found {} / {} / {} / {}",
                    super::confine::excerpt(c.mode),
                    super::confine::excerpt(c.filter),
                    c.stride,
                    c.count
                ),
            ));
        }
        Ok(c)
    }

    /// The decoded bytes of `encoded`.
    fn decode(&self, encoded: &[u8], what: &dyn Fn() -> String) -> ParseResult<Vec<u8>> {
        let failed = |e: meshopt::Error| {
            ParseError::item(
                what(),
                format!("expected bytes meshoptimizer decodes ({e:?})"),
            )
        };
        let indices = |v: Vec<u32>| -> Vec<u8> {
            match self.stride {
                2 => v.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
                _ => v.iter().flat_map(|&i| i.to_le_bytes()).collect(),
            }
        };
        match self.mode {
            "TRIANGLES" => meshopt::decode_index_buffer::<u32>(encoded, self.count)
                .map(indices)
                .map_err(failed),
            "INDICES" => meshopt::decode_index_sequence::<u32>(encoded, self.count)
                .map(indices)
                .map_err(failed),
            _ => {
                // Words, so the filters read aligned 16-bit components.
                let mut words = vec![0u32; self.count * self.stride / 4];
                // SAFETY: `words` holds count·stride bytes, all the decoder
                // writes; it reads `encoded` within its length; the stride
                // is one the decoder accepts (checked in `read`).
                let rc = unsafe {
                    meshopt::ffi::meshopt_decodeVertexBuffer(
                        words.as_mut_ptr().cast(),
                        self.count,
                        self.stride,
                        encoded.as_ptr(),
                        encoded.len(),
                    )
                };
                if rc != 0 {
                    return Err(ParseError::item(
                        what(),
                        format!("expected vertex bytes meshoptimizer decodes (code {rc})"),
                    ));
                }
                let filter = match self.filter {
                    "OCTAHEDRAL" => Some(meshopt::ffi::meshopt_decodeFilterOct as Filter),
                    "QUATERNION" => Some(meshopt::ffi::meshopt_decodeFilterQuat as Filter),
                    "EXPONENTIAL" => Some(meshopt::ffi::meshopt_decodeFilterExp as Filter),
                    "COLOR" => Some(meshopt::ffi::meshopt_decodeFilterColor as Filter),
                    _ => None,
                };
                if let Some(filter) = filter {
                    // SAFETY: as above: count elements of `stride` bytes in
                    // place, a stride this filter accepts.
                    unsafe { filter(words.as_mut_ptr().cast(), self.count, self.stride) };
                }
                Ok(words.iter().flat_map(|w| w.to_ne_bytes()).collect())
            }
        }
    }
}

/// meshoptimizer's in-place filters, all of one signature.
type Filter = unsafe extern "C" fn(*mut std::ffi::c_void, usize, usize);

/// Decodes every compressed view of `root` into its place in `buffers`
/// (loaded as the document says, fallbacks as zeros).
///
/// # Errors
/// A compressed view whose description, bytes or place do not fit.
pub fn decode(root: &Value, buffers: &mut [gltf::buffer::Data]) -> ParseResult<()> {
    let views = root["bufferViews"].as_array().map_or(&[][..], |v| v);
    for (i, view) in views.iter().enumerate() {
        let Some((name, e)) = extension(view) else {
            continue;
        };
        let what = || format!("buffer view {i} ({name})");
        let c = Compressed::read(e, &what)?;
        let encoded = buffers
            .get(c.source)
            .and_then(|b| b.0.get(c.offset..c.offset.checked_add(c.length)?))
            .ok_or_else(|| {
                ParseError::item(what(), "expected its compressed bytes inside their buffer")
            })?
            .to_vec();
        let size = c.count.checked_mul(c.stride).filter(|&s| {
            s <= super::limits::current().memory_budget as usize
                && view["byteLength"].as_u64().is_some_and(|l| s as u64 <= l)
        });
        let Some(size) = size else {
            return Err(ParseError::item(
                what(),
                "expected count · byteStride decoded bytes to fit the view's byteLength",
            ));
        };
        let target = view["buffer"].as_u64().unwrap_or(u64::MAX) as usize;
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let place = buffers
            .get_mut(target)
            .and_then(|b| b.0.get_mut(start..start.checked_add(size)?))
            .ok_or_else(|| ParseError::item(what(), "expected the view inside its buffer"))?;
        place.copy_from_slice(&c.decode(&encoded, &what)?);
    }
    Ok(())
}

/// The document without the extension: views and buffers lose it (their
/// bytes are decoded) and it leaves `extensionsUsed`/`extensionsRequired`.
pub fn strip(doc: &mut Value) {
    for key in ["bufferViews", "buffers"] {
        for v in doc
            .get_mut(key)
            .and_then(Value::as_array_mut)
            .into_iter()
            .flatten()
        {
            if let Some(ext) = v.get_mut("extensions").and_then(Value::as_object_mut) {
                for n in NAMES {
                    ext.remove(n);
                }
                if ext.is_empty()
                    && let Some(o) = v.as_object_mut()
                {
                    o.remove("extensions");
                }
            }
        }
    }
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = doc.get_mut(key).and_then(Value::as_array_mut) {
            list.retain(|e| !e.as_str().is_some_and(|e| NAMES.contains(&e)));
            if list.is_empty()
                && let Some(o) = doc.as_object_mut()
            {
                o.remove(key);
            }
        }
    }
}
