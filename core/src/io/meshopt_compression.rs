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

use serde_json::{Value, json};

use super::error::{ParseError, ParseResult};

/// How exported GLBs store their buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Compression {
    /// Plain buffer views.
    #[default]
    None,
    /// EXT_meshopt_compression ([`compress`]).
    Meshopt,
}

impl Compression {
    pub fn name(self) -> &'static str {
        match self {
            Compression::None => "none",
            Compression::Meshopt => "meshopt",
        }
    }

    /// `glb` stored this way.
    pub fn apply(self, glb: Vec<u8>) -> Vec<u8> {
        match self {
            Compression::None => glb,
            Compression::Meshopt => compress_glb(&glb).unwrap_or(glb),
        }
    }
}

impl std::str::FromStr for Compression {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        [Compression::None, Compression::Meshopt]
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| format!("{s:?} is not one of none, meshopt"))
    }
}

/// A GLB with its buffer compressed ([`compress`]); `None` for bytes that
/// are no GLB (which the writers never make).
fn compress_glb(glb: &[u8]) -> Option<Vec<u8>> {
    let g = gltf::binary::Glb::from_slice(glb).ok()?;
    let mut doc: Value = serde_json::from_slice(&g.json).ok()?;
    let bin = g.bin.map(|b| b.into_owned()).unwrap_or_default();
    let out = compress(&mut doc, &bin);
    Some(super::gltf_writer::glb(&doc, out))
}

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

/// How a view is compressed: its mode, stride and filter.
struct Plan {
    mode: &'static str,
    stride: usize,
    count: usize,
    /// Read as a vertex attribute (its view then states its stride, which
    /// glTF forbids on views of other accessors).
    vertex: bool,
    /// Normals: octahedral, 8 bits per component (KHR_mesh_quantization).
    octahedral: bool,
}

/// The plan for each buffer view of `doc`: `None` leaves it plain (shared
/// by accessors, read by an image or a sparse accessor, interleaved, or of
/// a stride the codecs do not take).
fn plans(doc: &Value) -> Vec<Option<Plan>> {
    let views = doc["bufferViews"].as_array().map_or(0, Vec::len);
    let accessors = doc["accessors"].as_array().map_or(&[][..], |a| a);
    let mut users = vec![0usize; views];
    let mut plain = vec![false; views];
    let at = |v: &Value| v.as_u64().map(|i| i as usize);
    for a in accessors {
        if let Some(v) = at(&a["bufferView"]).filter(|&v| v < views) {
            users[v] += 1;
        }
        for part in ["indices", "values"] {
            if let Some(v) = at(&a["sparse"][part]["bufferView"]).filter(|&v| v < views) {
                plain[v] = true;
            }
        }
    }
    for image in doc["images"].as_array().into_iter().flatten() {
        if let Some(v) = at(&image["bufferView"]).filter(|&v| v < views) {
            plain[v] = true;
        }
    }
    // Accessors read as triangle indices, other indices, and unit normals.
    let (mut triangles, mut indices, mut normals, mut vertex) = (vec![], vec![], vec![], vec![]);
    for mesh in doc["meshes"].as_array().into_iter().flatten() {
        for p in mesh["primitives"].as_array().into_iter().flatten() {
            if let Some(i) = at(&p["indices"]) {
                match p["mode"].as_u64().unwrap_or(4) {
                    4 => triangles.push(i),
                    _ => indices.push(i),
                }
            }
            normals.extend(at(&p["attributes"]["NORMAL"]));
            let targets = p["targets"].as_array().into_iter().flatten();
            for set in std::iter::once(&p["attributes"]).chain(targets) {
                vertex.extend(
                    set.as_object()
                        .into_iter()
                        .flatten()
                        .filter_map(|(_, a)| at(a)),
                );
            }
        }
    }
    let mut out: Vec<Option<Plan>> = (0..views).map(|_| None).collect();
    for (i, a) in accessors.iter().enumerate() {
        let Some(v) = at(&a["bufferView"]).filter(|&v| v < views && users[v] == 1 && !plain[v])
        else {
            continue;
        };
        let view = &doc["bufferViews"][v];
        let component = match a["componentType"].as_u64() {
            Some(5120 | 5121) => 1,
            Some(5122 | 5123) => 2,
            Some(5125 | 5126) => 4,
            _ => continue,
        };
        let width = match a["type"].as_str() {
            Some("SCALAR") => 1,
            Some("VEC2") => 2,
            Some("VEC3") => 3,
            Some("VEC4" | "MAT2") => 4,
            Some("MAT3") => 9,
            Some("MAT4") => 16,
            _ => continue,
        };
        let size = component * width;
        let count = a["count"].as_u64().unwrap_or(0) as usize;
        let tight = a["byteOffset"].as_u64().unwrap_or(0) == 0
            && view["byteStride"]
                .as_u64()
                .is_none_or(|s| s as usize == size)
            && view["byteLength"].as_u64() == Some((size * count) as u64);
        let triangle = triangles.contains(&i);
        let plan = match () {
            _ if !tight || count == 0 => None,
            _ if triangle || indices.contains(&i) => (component >= 2).then(|| Plan {
                mode: match triangle && count.is_multiple_of(3) {
                    true => "TRIANGLES",
                    false => "INDICES",
                },
                stride: component,
                count,
                vertex: false,
                octahedral: false,
            }),
            _ if normals.contains(&i) && a["componentType"] == 5126 && width == 3 => Some(Plan {
                mode: "ATTRIBUTES",
                stride: 4,
                count,
                vertex: true,
                octahedral: true,
            }),
            _ => (size.is_multiple_of(4) && size <= 256).then_some(Plan {
                mode: "ATTRIBUTES",
                stride: size,
                count,
                vertex: vertex.contains(&i),
                octahedral: false,
            }),
        };
        out[v] = plan;
    }
    out
}

/// The encoded bytes of a view's `data` as `plan` says.
fn encode(plan: &Plan, data: &[u8]) -> Vec<u8> {
    let count = plan.count;
    let words = |d: &[u8]| -> Vec<u32> {
        d.chunks_exact(4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
            .collect()
    };
    match plan.mode {
        "TRIANGLES" | "INDICES" => {
            let ix: Vec<u32> = match plan.stride {
                2 => data
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]) as u32)
                    .collect(),
                _ => words(data),
            };
            let vertices = ix.iter().max().map_or(0, |&m| m as usize + 1);
            let encoded = match plan.mode {
                "TRIANGLES" => meshopt::encode_index_buffer(&ix, vertices),
                _ => meshopt::encode_index_sequence(&ix, vertices),
            };
            encoded.unwrap_or_default()
        }
        _ => {
            let stream: Vec<u32> = match plan.octahedral {
                true => {
                    let unit: Vec<[f32; 4]> = words(data)
                        .chunks_exact(3)
                        .map(|c| {
                            let n = glam::Vec3::new(
                                f32::from_bits(c[0]),
                                f32::from_bits(c[1]),
                                f32::from_bits(c[2]),
                            );
                            let n = n.try_normalize().unwrap_or(glam::Vec3::Z);
                            [n.x, n.y, n.z, 0.0]
                        })
                        .collect();
                    meshopt::encode_filter_oct::<i8>(&unit, 8)
                        .iter()
                        .map(|c| u32::from_ne_bytes(c.map(|b| b as u8)))
                        .collect()
                }
                false => data
                    .chunks_exact(4)
                    .map(|w| u32::from_ne_bytes([w[0], w[1], w[2], w[3]]))
                    .collect(),
            };
            // SAFETY: `stream` holds count·stride bytes (a stride the codec
            // takes: a multiple of 4 up to 256), `out` the bound the encoder
            // asks for.
            let bound =
                unsafe { meshopt::ffi::meshopt_encodeVertexBufferBound(count, plan.stride) };
            let mut out = vec![0u8; bound];
            // Version 0: the one EXT_meshopt_compression allows.
            let size = unsafe {
                meshopt::ffi::meshopt_encodeVertexBufferLevel(
                    out.as_mut_ptr(),
                    out.len(),
                    stream.as_ptr().cast(),
                    count,
                    plan.stride,
                    2,
                    0,
                )
            };
            out.truncate(size);
            out
        }
    }
}

/// `doc` and its one buffer `bin` stored with EXT_meshopt_compression, as
/// gltfpack `-c` stores them: each view that one accessor reads tightly is
/// encoded by meshoptimizer's codecs (index codec for indices, vertex codec
/// for the rest) into buffer 0 after the plain views, and decodes into a
/// fallback buffer 1 that holds no bytes. Positions and every other float
/// keep their bits (the vertex codec is lossless), so every bound holds as
/// written; unit normals go to 8-bit octahedral (KHR_mesh_quantization),
/// at most 1/127 off per component. The new buffer.
pub fn compress(doc: &mut Value, bin: &[u8]) -> Vec<u8> {
    let plans = plans(doc);
    let mut out: Vec<u8> = Vec::with_capacity(bin.len() / 2);
    let mut fallback = 0usize;
    let mut encoded_any = false;
    let mut octahedral = Vec::new();
    for (v, view) in doc["bufferViews"]
        .as_array_mut()
        .into_iter()
        .flatten()
        .enumerate()
    {
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let length = view["byteLength"].as_u64().unwrap_or(0) as usize;
        let data = bin.get(start..start.saturating_add(length)).unwrap_or(&[]);
        while !out.len().is_multiple_of(4) {
            out.push(0);
        }
        let Some(plan) = plans[v].as_ref().filter(|_| data.len() == length) else {
            view["buffer"] = json!(0);
            view["byteOffset"] = json!(out.len());
            out.extend_from_slice(data);
            continue;
        };
        let count = plan.count;
        let encoded = encode(plan, data);
        let mut extension = json!({"buffer": 0, "byteOffset": out.len(),
            "byteLength": encoded.len(), "byteStride": plan.stride, "count": count,
            "mode": plan.mode});
        if plan.octahedral {
            extension["filter"] = json!("OCTAHEDRAL");
            octahedral.push(v);
        }
        out.extend_from_slice(&encoded);
        view["buffer"] = json!(1);
        view["byteOffset"] = json!(fallback);
        view["byteLength"] = json!(plan.stride * count);
        match plan.vertex {
            true => view["byteStride"] = json!(plan.stride),
            false => {
                view.as_object_mut().map(|o| o.remove("byteStride"));
            }
        }
        view["extensions"] = json!({NAMES[0]: extension});
        fallback += (plan.stride * count).next_multiple_of(4);
        encoded_any = true;
    }
    while !out.len().is_multiple_of(4) {
        out.push(0);
    }
    if !encoded_any {
        doc["buffers"] = json!([{"byteLength": out.len()}]);
        return out;
    }
    doc["buffers"] = json!([{"byteLength": out.len()},
        {"byteLength": fallback, "extensions": {NAMES[0]: {"fallback": true}}}]);
    for a in doc["accessors"].as_array_mut().into_iter().flatten() {
        if a["bufferView"]
            .as_u64()
            .is_some_and(|v| octahedral.contains(&(v as usize)))
        {
            a["componentType"] = json!(5120);
            a["normalized"] = json!(true);
        }
    }
    let mut required = vec![NAMES[0]];
    if !octahedral.is_empty() {
        required.push("KHR_mesh_quantization");
    }
    for key in ["extensionsUsed", "extensionsRequired"] {
        let mut list: Vec<Value> = doc[key].as_array().cloned().unwrap_or_default();
        for name in &required {
            if !list.iter().any(|e| e == name) {
                list.push(json!(name));
            }
        }
        doc[key] = json!(list);
    }
    out
}
