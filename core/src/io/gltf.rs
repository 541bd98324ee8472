//! glTF 2.0 (`.gltf` + `.bin`, `.glb`) through the gltf crate. Every material
//! of every mesh instance of the scene graph becomes a part, with its node
//! transform applied. Materials are kept (factors and the base-colour texture,
//! its image bytes as stored) for the exports; for display, the vertex colour is
//! the base-colour factor times `COLOR_0`.
//!
//! Accessor ranges are checked against the buffers before any read (the crate's
//! readers assume valid data), so hostile files give an error instead of a panic.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::asset::{self, AssetReport, audit_gltf, check_required};
use super::confine;
use super::error::{ParseError, ParseResult};
use super::meshopt_compression;
use crate::geom::{AlphaMode, Image, Material, Materials, TriMesh, VertexAttributes};

/// The gltf crate subtracts the 12-byte header from a GLB's declared length
/// unchecked (an overflow panic under debug assertions, found by fuzzing), so
/// a declared length shorter than the header is refused here first.
fn check_glb_length(data: &[u8]) -> ParseResult<()> {
    if let Some(length) = data
        .strip_prefix(b"glTF")
        .and_then(|rest| rest.get(4..8))
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        && length < 12
    {
        return Err(ParseError::file(format!(
            "expected a GLB length of at least its 12-byte header, found {length}"
        )));
    }
    Ok(())
}

/// Parses and validates `data`. The crate's validation reads each primitive's
/// `POSITION` accessor before it checks that index (a panic on a hostile
/// file, found by fuzzing), so those indices are checked here first.
pub(super) fn parse(data: &[u8]) -> ParseResult<(gltf::Gltf, serde_json::Value)> {
    check_glb_length(data)?;
    // A required extension is named before the crate's own checks (which
    // refuse it as "unsupported" without saying what it is).
    let raw = raw_json(data);
    if let Ok(root) = &raw {
        check_required(root)?;
    }
    let invalid = |e: gltf::Error| ParseError::file(format!("expected valid glTF 2.0 ({e})"));
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(data).map_err(invalid)?;
    let root = document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = prim.attributes.get(&position)
                && index.value() >= root.accessors.len()
            {
                return Err(ParseError::item(
                    format!("mesh {m} primitive {p}"),
                    format!(
                        "expected a POSITION accessor among the {} accessors, found index {}",
                        root.accessors.len(),
                        index.value()
                    ),
                ));
            }
        }
    }
    // The crate unwraps the percent-decoding of relative buffer URIs.
    for (b, buffer) in root.buffers.iter().enumerate() {
        if let Some(uri) = buffer.uri.as_deref()
            && !uri.contains(':')
            && urlencoding::decode(uri).is_err()
        {
            return Err(ParseError::item(
                format!("buffer {b}"),
                "expected a URI that percent-decodes to UTF-8",
            ));
        }
    }
    // The crate unwraps the URI of an image that has no buffer view.
    for (i, image) in root.images.iter().enumerate() {
        if image.uri.is_none() && image.buffer_view.is_none() {
            return Err(ParseError::item(
                format!("image {i}"),
                "expected a uri or a bufferView",
            ));
        }
    }
    // What the reader takes in whole is no longer a requirement the crate
    // must know (it refuses KHR_mesh_quantization as unsupported).
    let mut json = document.into_json();
    json.extensions_required
        .retain(|e| !asset::READ.contains(&e.as_str()));
    let document = gltf::Document::from_json(json).map_err(invalid)?;
    Ok((gltf::Gltf { document, blob }, raw?))
}

/// Every mesh instance of the default scene (else the first scene, else of
/// every node) as one mesh, with what the file holds besides
/// ([`AssetReport`]: counted, and listed where the outputs leave it out).
///
/// # Errors
/// A malformed file, or one that requires an extension lodstudio cannot read.
pub fn read(data: &[u8], base: Option<&Path>) -> ParseResult<(TriMesh, AssetReport)> {
    let (g, raw) = parse(data)?;
    let scene = g
        .document
        .default_scene()
        .or_else(|| g.document.scenes().next())
        .map(|s| s.index());
    let report = audit_gltf(&raw, scene, asset::Carried::Flat)?;
    let roots = scene_roots(&g.document);
    Ok((read_nodes(&g, &raw, base, roots, 0)?, report))
}

/// Level `lod` of the `MSFT_lod` chains that `export` writes, as a client
/// of the extension draws it: the scene walked from its roots, each node
/// whose `extensions.MSFT_lod.ids` name lower LODs replaced whole (children
/// included) by its `lod`-th (its coarsest where its chain is shorter).
/// LOD nodes are in no scene, so [`read`] never sees them.
///
/// # Errors
/// As [`read`], and when no chain has an LOD `lod`.
pub fn read_lod(data: &[u8], base: Option<&Path>, lod: usize) -> ParseResult<TriMesh> {
    let (g, raw) = parse(data)?;
    let mut levels = 0;
    for n in g.document.nodes() {
        levels = levels.max(lod_ids(&raw, n.index())?.len());
    }
    if lod > levels {
        return Err(ParseError::file(format!(
            "expected an LOD {lod}, but the MSFT_lod chains have LODs 0 to {levels}"
        )));
    }
    read_nodes(&g, &raw, base, scene_roots(&g.document), lod)
}

pub(super) fn scene_roots(document: &gltf::Document) -> Vec<gltf::Node<'_>> {
    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().collect(),
        None => document.nodes().collect(),
    }
}

/// The `MSFT_lod` ids of node `node` (none without the extension), read from
/// the JSON itself: the gltf crate, as configured, drops unknown extensions.
pub(super) fn lod_ids(root: &serde_json::Value, node: usize) -> ParseResult<Vec<usize>> {
    let Some(ids) = root["nodes"][node]["extensions"]["MSFT_lod"].get("ids") else {
        return Ok(Vec::new());
    };
    serde_json::from_value(ids.clone()).map_err(|_| {
        ParseError::item(
            format!("node {node}"),
            "expected MSFT_lod ids to be node indices",
        )
    })
}

/// The file's JSON as written (a GLB's JSON chunk).
fn raw_json(data: &[u8]) -> ParseResult<serde_json::Value> {
    let json = match gltf::binary::Glb::from_slice(data) {
        Ok(glb) => glb.json.into_owned(),
        Err(_) => data.to_vec(),
    };
    serde_json::from_slice(&json).map_err(|e| ParseError::file(format!("expected glTF JSON ({e})")))
}

/// Most node instances a scene graph may expand to: a graph of nodes that
/// list each other as children more than once (a DAG) multiplies its
/// instances with every level (28 levels of two: 2^28 from 1.3 KB), so the
/// expansion is counted and refused past this, whatever the triangles.
pub const MAX_INSTANCES: usize = 1 << 20;

/// The meshes of `roots` and their descendants, node transforms applied.
/// Each mesh's material and each image is read once however many nodes and
/// primitives use it; the instances are concatenated once at the end, so
/// the cost is linear in the instances (appending one by one recounted the
/// parts each time).
fn read_nodes(
    g: &gltf::Gltf,
    root: &serde_json::Value,
    base: Option<&Path>,
    roots: Vec<gltf::Node>,
    lod: usize,
) -> ParseResult<TriMesh> {
    let buffers = load_buffers(&g.document, root, base, g.blob.clone())?;
    let mut images = ImageCache::new(&g.document, base);
    let mut materials_read: Vec<Option<Material>> = vec![None; g.document.materials().len() + 1];
    let mut pieces: Vec<TriMesh> = Vec::new();
    let (mut instances, mut triangles) = (0usize, 0u64);
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        // At LOD `lod` a node with MSFT_lod ids is its LOD node.
        let ids = match lod {
            0 => Vec::new(),
            _ => lod_ids(root, node.index())?,
        };
        let node = match ids.get(lod.wrapping_sub(1)).or(ids.last()) {
            None => node,
            Some(&i) => g.document.nodes().nth(i).ok_or_else(|| {
                ParseError::item(
                    format!("node {}", node.index()),
                    format!("expected MSFT_lod ids among the nodes, found {i}"),
                )
            })?,
        };
        // A node graph deeper than the node count has a cycle.
        if depth > g.document.nodes().len() {
            return Err(ParseError::item(
                format!("node {}", node.index()),
                "expected an acyclic node hierarchy",
            ));
        }
        instances += 1;
        if instances > MAX_INSTANCES {
            return Err(ParseError::item(
                format!("node {}", node.index()),
                format!(
                    "expected at most {MAX_INSTANCES} node instances, but the node graph \
                     expands to more (nodes listed as children of several parents)"
                ),
            ));
        }
        let world = world_of(&node, parent)?;
        if let Some(m) = node.mesh() {
            // What the instances would hold, before they are made.
            triangles = triangles.saturating_add(mesh_triangles(&m));
            super::limits::check_budget(
                &format!("{triangles} triangles of instanced meshes"),
                triangles.saturating_mul(INSTANCE_BYTES_PER_TRIANGLE),
            )?;
            let mut reader = MeshReader {
                buffers: &buffers,
                images: &mut images,
                materials: &mut materials_read,
            };
            let (instance, _) = reader.read(&m, world, &mut |_, _| Ok(()))?;
            if !instance.triangles.is_empty() {
                pieces.push(instance);
            }
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    Ok(TriMesh::concat(&pieces))
}

/// Reads meshes, each material and image once however many meshes use it.
pub(super) struct MeshReader<'r, 'a> {
    pub buffers: &'r [gltf::buffer::Data],
    pub images: &'r mut ImageCache<'a>,
    /// The materials read so far, by glTF index (the last: the default).
    pub materials: &'r mut Vec<Option<Material>>,
}

impl MeshReader<'_, '_> {
    /// The triangles of `mesh` under `world`, one part per material, and
    /// each part's glTF material index (`None`: the default material).
    /// `each` sees every primitive read and the vertex count it added, in
    /// the order of the mesh's vertices (for attributes read beside them).
    pub fn read(
        &mut self,
        mesh: &gltf::Mesh,
        world: Mat4,
        each: &mut dyn FnMut(&gltf::Primitive, usize) -> ParseResult<()>,
    ) -> ParseResult<(TriMesh, Vec<Option<usize>>)> {
        let mut out = TriMesh::default();
        // Primitives of one material make one part, whatever their count.
        let mut keys: Vec<Option<usize>> = Vec::new();
        let mut materials = Materials::default();
        let mut parts = Vec::new();
        for prim in mesh.primitives() {
            let Some(piece) = read_primitive(&prim, self.buffers, world)? else {
                continue;
            };
            let key = prim.material().index();
            let part = match keys.iter().position(|k| *k == key) {
                Some(p) => p,
                None => {
                    let slot = key.unwrap_or(self.materials.len() - 1);
                    let mut material = match &self.materials[slot] {
                        Some(m) => m.clone(),
                        None => {
                            let m = read_material(&prim.material(), self.buffers, self.images)?;
                            self.materials[slot] = Some(m.clone());
                            m
                        }
                    };
                    material.vertex_attributes = VertexAttributes {
                        colors: prim.get(&gltf::Semantic::Colors(0)).is_some(),
                        uvs: prim.get(&gltf::Semantic::TexCoords(0)).is_some(),
                    };
                    let i = materials.intern(&material);
                    materials.of_part.push(i);
                    keys.push(key);
                    keys.len() - 1
                }
            };
            parts.extend(std::iter::repeat_n(part as u32, piece.triangles.len()));
            each(&prim, piece.positions.len())?;
            out.append(&piece);
        }
        out.parts = (keys.len() > 1).then_some(parts);
        out.materials = Some(materials);
        Ok((out, keys))
    }
}

/// The world matrix of `node` under `parent`; a transform that overflows is refused.
pub(super) fn world_of(node: &gltf::Node, parent: Mat4) -> ParseResult<Mat4> {
    let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
    if !world.is_finite() {
        return Err(ParseError::item(
            format!("node {}", node.index()),
            "expected a finite transform",
        ));
    }
    Ok(world)
}

/// What one triangle of an instance costs once read: three vertices
/// (position, normal, colour, UV: 44 bytes each), its indices and part.
const INSTANCE_BYTES_PER_TRIANGLE: u64 = 3 * 44 + 16;

/// Triangles a mesh's primitives declare (indices, else vertices, over 3).
fn mesh_triangles(mesh: &gltf::Mesh) -> u64 {
    mesh.primitives()
        .map(|p| {
            let count = p
                .indices()
                .or_else(|| p.get(&gltf::Semantic::Positions))
                .map_or(0, |a| a.count());
            count as u64 / 3 + 1
        })
        .sum()
}

/// The buffers' bytes: the GLB's binary chunk, `data:` URIs, and files
/// inside the asset folder (`confine`), each within the memory budget and
/// padded to 4 bytes as the gltf crate's readers expect.
pub(super) fn load_buffers(
    document: &gltf::Document,
    root: &serde_json::Value,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
) -> ParseResult<Vec<gltf::buffer::Data>> {
    let mut out = Vec::with_capacity(document.buffers().len());
    for buffer in document.buffers() {
        let what = format!("buffer {}", buffer.index());
        let fallback = meshopt_compression::is_fallback(root, buffer.index());
        let mut data = match buffer.source() {
            // Filled by the views decoded into it.
            _ if fallback && buffer.length() <= super::limits::current().memory_budget as usize => {
                vec![0; buffer.length()]
            }
            _ if fallback => {
                return Err(ParseError::item(
                    &what,
                    format!(
                        "expected a fallback buffer within the memory budget, found {} bytes",
                        buffer.length()
                    ),
                ));
            }
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| ParseError::item(&what, "expected the GLB's binary chunk"))?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, base, &what)?,
        };
        while data.len() % 4 != 0 {
            data.push(0);
        }
        if data.len() < buffer.length() {
            return Err(ParseError::item(
                what,
                format!("expected {} bytes, found {}", buffer.length(), data.len()),
            ));
        }
        out.push(gltf::buffer::Data(data));
    }
    meshopt_compression::decode(root, &mut out)?;
    Ok(out)
}

/// The bytes a URI names, through the asset-folder policy (`confine`): a
/// `data:` URI decoded, or a regular file inside the folder within the
/// memory budget. A GLB read from memory has no folder, so files are refused.
pub(super) fn read_uri(uri: &str, base: Option<&Path>, what: &str) -> ParseResult<Vec<u8>> {
    let refused = |e: confine::Refused| ParseError::file(e.message().to_string());
    let target = match base {
        Some(folder) => confine::resolve_uri(folder, uri, what).map_err(refused)?,
        None if uri.starts_with("data:") => confine::Target::Data,
        None => {
            return Err(ParseError::file(format!(
                "{what}: uri {} names a file, but this glTF was read from memory",
                confine::excerpt(uri)
            )));
        }
    };
    match target {
        confine::Target::Data => {
            gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
                .map(|d| d.0)
                .map_err(|e| {
                    ParseError::file(format!("{what}: expected a readable data URI ({e})"))
                })
        }
        confine::Target::File(path) => {
            confine::read_regular(&path, super::limits::current().memory_budget).map_err(refused)
        }
    }
}

/// A three-component attribute: floats through the crate's `read`, integers
/// (KHR_mesh_quantization) through [`dequantized`]; `None` without one.
fn vec3s(
    prim: &gltf::Primitive,
    semantic: &gltf::Semantic,
    buffers: &[gltf::buffer::Data],
    read: impl FnOnce() -> Option<Vec<[f32; 3]>>,
) -> Option<Vec<[f32; 3]>> {
    match prim.get(semantic) {
        Some(acc) if acc.data_type() != gltf::accessor::DataType::F32 => {
            Some(dequantized::<3>(&acc, buffers))
        }
        _ => read(),
    }
}

/// The elements of an integer accessor as floats, as KHR_mesh_quantization
/// reads them: normalized components map to [0, 1] or [-1, 1] (glTF 2.0
/// §3.11: `max(c / 127, -1)`, `c / 255`, `max(c / 32767, -1)`,
/// `c / 65535`), the others keep their values (a node's scale and offset
/// then dequantize them). The accessor was checked against its buffer
/// ([`check_accessor`]).
pub(super) fn dequantized<const N: usize>(
    acc: &gltf::Accessor,
    buffers: &[gltf::buffer::Data],
) -> Vec<[f32; N]> {
    use gltf::accessor::DataType as D;
    let (Some(view), size) = (acc.view(), acc.data_type().size()) else {
        return Vec::new();
    };
    let Some(data) = buffers.get(view.buffer().index()) else {
        return Vec::new();
    };
    let stride = view.stride().unwrap_or(acc.size());
    let start = view.offset() + acc.offset();
    let normalized = acc.normalized();
    let component = |at: usize| -> f32 {
        let b = &data.0[at..at + size];
        let (value, max) = match acc.data_type() {
            D::I8 => (b[0] as i8 as f32, 127.0),
            D::U8 => (b[0] as f32, 255.0),
            D::I16 => (i16::from_le_bytes([b[0], b[1]]) as f32, 32767.0),
            D::U16 => (u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0),
            D::U32 => (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32, 1.0),
            D::F32 => (f32::from_le_bytes([b[0], b[1], b[2], b[3]]), 1.0),
        };
        match normalized {
            true => (value / max).max(-1.0),
            false => value,
        }
    };
    (0..acc.count())
        .map(|i| std::array::from_fn(|c| component(start + i * stride + c * size)))
        .collect()
}

/// Checks that every element of the accessor lies inside its buffer view and buffer.
pub(super) fn check_accessor(
    acc: &gltf::Accessor,
    buffers: &[gltf::buffer::Data],
) -> ParseResult<()> {
    let what = || format!("accessor {}", acc.index());
    if acc.sparse().is_some() {
        return Err(ParseError::item(
            what(),
            "expected a dense accessor (sparse accessors are not supported)",
        ));
    }
    let Some(view) = acc.view() else {
        return Err(ParseError::item(what(), "expected a buffer view"));
    };
    let buf_len = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|e| e > buf_len) {
        return Err(ParseError::item(
            what(),
            "expected a buffer view inside its buffer",
        ));
    }
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    let count = acc.count();
    // glTF 2.0 requires count ≥ 1, and the gltf crate's reader subtracts 1 from it.
    if count == 0 {
        return Err(ParseError::item(what(), "expected at least one element"));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(acc.offset()))
        .and_then(|x| x.checked_add(elem));
    if stride < elem || end.is_none_or(|e| e > view.length()) {
        return Err(ParseError::item(
            what(),
            format!("expected {count} elements inside its buffer view"),
        ));
    }
    Ok(())
}

fn read_primitive(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    world: Mat4,
) -> ParseResult<Option<TriMesh>> {
    use gltf::mesh::Mode;
    let what = || format!("mesh primitive {}", prim.index());
    if !matches!(
        prim.mode(),
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(None);
    }
    use gltf::Semantic;
    use gltf::accessor::{DataType as D, Dimensions as N};
    for (semantic, acc) in prim.attributes() {
        // Only the attributes read below; the reader assumes their element types.
        let ok = match semantic {
            // Integers: KHR_mesh_quantization, read by [`dequantized`].
            Semantic::Positions => {
                acc.dimensions() == N::Vec3
                    && matches!(acc.data_type(), D::F32 | D::I8 | D::U8 | D::I16 | D::U16)
            }
            Semantic::Normals => {
                acc.dimensions() == N::Vec3 && matches!(acc.data_type(), D::F32 | D::I8 | D::I16)
            }
            Semantic::TexCoords(0) => {
                acc.dimensions() == N::Vec2
                    && matches!(acc.data_type(), D::F32 | D::I8 | D::U8 | D::I16 | D::U16)
            }
            Semantic::Colors(0) => {
                matches!(acc.dimensions(), N::Vec3 | N::Vec4)
                    && matches!(acc.data_type(), D::F32 | D::U8 | D::U16)
            }
            _ => continue,
        };
        if !ok {
            return Err(ParseError::item(
                format!("accessor {}", acc.index()),
                format!("expected the glTF element type of {semantic:?}"),
            ));
        }
        check_accessor(&acc, buffers)?;
    }
    if let Some(acc) = prim.indices() {
        if acc.dimensions() != N::Scalar || !matches!(acc.data_type(), D::U8 | D::U16 | D::U32) {
            return Err(ParseError::item(
                format!("accessor {}", acc.index()),
                "expected unsigned scalar indices",
            ));
        }
        check_accessor(&acc, buffers)?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(positions) = vec3s(prim, &Semantic::Positions, buffers, || {
        reader.read_positions().map(Iterator::collect)
    }) else {
        return Ok(None);
    };
    let positions: Vec<Vec3> = positions
        .into_iter()
        .map(|p| world.transform_point3(Vec3::from_array(p)))
        .collect();
    let n = positions.len();
    let indices: Vec<u32> = match reader.read_indices() {
        Some(ix) => ix.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    if let Some(bad) = indices.iter().find(|i| **i as usize >= n) {
        return Err(ParseError::item(
            what(),
            format!("expected indices below {n}, found {bad}"),
        ));
    }
    let triangles: Vec<[u32; 3]> = match prim.mode() {
        Mode::TriangleStrip => indices
            .windows(3)
            .enumerate()
            .map(|(i, w)| {
                if i % 2 == 0 {
                    [w[0], w[1], w[2]]
                } else {
                    [w[1], w[0], w[2]]
                }
            })
            .collect(),
        Mode::TriangleFan => indices
            .windows(2)
            .skip(1)
            .map(|w| [indices[0], w[0], w[1]])
            .collect(),
        _ => indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    };
    let mut mesh = TriMesh::new(positions, triangles);
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    if let Some(nr) = vec3s(prim, &Semantic::Normals, buffers, || {
        reader.read_normals().map(Iterator::collect)
    }) {
        let normals: Vec<Vec3> = nr
            .into_iter()
            .map(|v| (normal_matrix * Vec3::from_array(v)).normalize_or_zero())
            .collect();
        if normals.len() == n {
            mesh.normals = Some(normals);
        }
    }
    let uvs = match prim.get(&Semantic::TexCoords(0)) {
        Some(acc) if acc.data_type() != D::F32 => Some(dequantized::<2>(&acc, buffers)),
        _ => reader.read_tex_coords(0).map(|uv| uv.into_f32().collect()),
    };
    if let Some(uv) = uvs {
        let uvs: Vec<Vec2> = uv.into_iter().map(Vec2::from_array).collect();
        if uvs.len() == n {
            mesh.uvs = Some(uvs);
        }
    }
    let colors: Option<Vec<Vec3>> = reader
        .read_colors(0)
        .map(|c| c.into_rgb_f32().map(Vec3::from_array).collect());
    let [r, g, b, _] = prim.material().pbr_metallic_roughness().base_color_factor();
    let factor = Vec3::new(r, g, b);
    mesh.colors = match colors {
        Some(c) if c.len() == n => Some(c.into_iter().map(|c| c * factor).collect()),
        _ => Some(vec![factor; n]),
    };
    // A mirroring transform flips the winding; flip it back to keep normals outward.
    if world.determinant() < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    Ok(Some(mesh))
}

/// The material of a primitive, its base-colour texture's image included (bytes
/// as stored: a buffer view, a data URI or a file in the asset folder).
fn read_material(
    m: &gltf::Material,
    buffers: &[gltf::buffer::Data],
    images: &mut ImageCache,
) -> ParseResult<Material> {
    let pbr = m.pbr_metallic_roughness();
    let texture = match pbr.base_color_texture() {
        // Only TEXCOORD_0 is carried, so textures on other sets are left out.
        Some(info) if info.tex_coord() == 0 => {
            Some(texture_image(&info.texture(), buffers, images)?)
        }
        _ => None,
    };
    Ok(Material {
        name: m.name().map(str::to_string),
        base_color: pbr.base_color_factor(),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        emissive: m.emissive_factor(),
        alpha_mode: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        double_sided: m.double_sided(),
        base_color_texture: texture,
        normal_texture: match m.normal_texture() {
            Some(info) if info.tex_coord() == 0 => Some((
                texture_image(&info.texture(), buffers, images)?,
                info.scale(),
            )),
            _ => None,
        },
        vertex_attributes: VertexAttributes::default(),
    })
}

/// A texture's image with its sampler's settings.
fn texture_image(
    tex: &gltf::Texture,
    buffers: &[gltf::buffer::Data],
    images: &mut ImageCache,
) -> ParseResult<Image> {
    let (bytes, mime_type) = images.get(&tex.source(), buffers)?;
    let sampler = tex.sampler();
    Ok(Image {
        mime_type,
        bytes,
        mag_filter: sampler.mag_filter().map(|f| f.as_gl_enum()),
        min_filter: sampler.min_filter().map(|f| f.as_gl_enum()),
        wrap_s: sampler.wrap_s().as_gl_enum(),
        wrap_t: sampler.wrap_t().as_gl_enum(),
    })
}

/// Each image's bytes, read once however many materials name it (60
/// materials naming one 200 MB file held it 60 times), its declared size
/// checked against the memory budget before anything decodes it.
pub(super) struct ImageCache<'a> {
    base: Option<&'a Path>,
    read: Vec<Option<(Arc<[u8]>, String)>>,
}

impl<'a> ImageCache<'a> {
    pub(super) fn new(document: &gltf::Document, base: Option<&'a Path>) -> Self {
        ImageCache {
            base,
            read: vec![None; document.images().len()],
        }
    }

    /// The image's bytes as stored and its MIME type.
    fn get(
        &mut self,
        image: &gltf::Image,
        buffers: &[gltf::buffer::Data],
    ) -> ParseResult<(Arc<[u8]>, String)> {
        let what = format!("image {}", image.index());
        if let Some(Some(hit)) = self.read.get(image.index()) {
            return Ok(hit.clone());
        }
        let (bytes, mime) = match image.source() {
            gltf::image::Source::View { view, mime_type } => {
                let data = buffers
                    .get(view.buffer().index())
                    .map_or(&[][..], |d| &d.0[..]);
                let bytes = view
                    .offset()
                    .checked_add(view.length())
                    .and_then(|end| data.get(view.offset()..end))
                    .ok_or_else(|| ParseError::item(&what, "expected it inside its buffer"))?;
                (bytes.to_vec(), mime_type.to_string())
            }
            gltf::image::Source::Uri { uri, mime_type } => {
                let mut bytes = read_uri(uri, self.base, &what)?;
                if uri.starts_with("data:") {
                    // The decoder pads to 4 bytes; an image keeps its exact length.
                    let payload = uri.rsplit(',').next().unwrap_or("").trim_end_matches('=');
                    bytes.truncate(payload.len() * 3 / 4);
                }
                let png = bytes.starts_with(b"\x89PNG");
                let mime = mime_type.map_or(
                    if png { "image/png" } else { "image/jpeg" }.to_string(),
                    str::to_string,
                );
                (bytes, mime)
            }
        };
        super::image::check_declared_size(&bytes).map_err(|e| ParseError::item(&what, e))?;
        let entry = (Arc::<[u8]>::from(bytes), mime);
        if let Some(slot) = self.read.get_mut(image.index()) {
            *slot = Some(entry.clone());
        }
        Ok(entry)
    }
}

/// The .gltf JSON and the .bin buffer of a GLB made by this module's writers,
/// the buffer referenced as `bin_name`; `None` when `glb` is no GLB container.
pub fn split_glb(glb: &[u8], bin_name: &str) -> Option<(Vec<u8>, Vec<u8>)> {
    let word = |at: usize| Some(u32::from_le_bytes(glb.get(at..at + 4)?.try_into().ok()?) as usize);
    if glb.get(0..4)? != b"glTF" {
        return None;
    }
    let json_len = word(12)?;
    let json = glb.get(20..20 + json_len)?;
    let bin = match word(20 + json_len) {
        Some(len) => glb.get(28 + json_len..28 + json_len + len)?.to_vec(),
        None => Vec::new(),
    };
    let mut doc: serde_json::Value = serde_json::from_slice(json).ok()?;
    if let Some(buffer) = doc.get_mut("buffers").and_then(|b| b.get_mut(0)) {
        buffer["uri"] = serde_json::json!(bin_name);
    }
    Some((serde_json::to_vec_pretty(&doc).ok()?, bin))
}

/// The files a glTF names (external buffers and images, in document order,
/// each once, canonical): what its content is made of besides its own bytes
/// (batch caches hash them). Each goes through the asset-folder policy, so a
/// reference outside it is an error here as when the model loads, and is
/// never read. Unreadable documents name none (they fail when loaded).
///
/// # Errors
/// The first reference the policy refuses.
pub fn referenced_files(path: &Path, bytes: &[u8]) -> Result<Vec<PathBuf>, confine::Refused> {
    let Ok(gltf) = gltf::Gltf::from_slice_without_validation(bytes) else {
        return Ok(Vec::new());
    };
    let folder = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf.document.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(uri) => Some((format!("buffer {}", b.index()), uri)),
        gltf::buffer::Source::Bin => None,
    });
    let images = gltf.document.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } => Some((format!("image {}", i.index()), uri)),
        gltf::image::Source::View { .. } => None,
    });
    let mut out: Vec<PathBuf> = Vec::new();
    for (what, uri) in buffers.chain(images) {
        if let confine::Target::File(p) = confine::resolve_uri(folder, uri, &what)?
            && !out.contains(&p)
        {
            out.push(p);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_lod_chain_reads_level_by_level() {
        use crate::io::gltf_writer::{PointsAs, write_glb, write_lod_chain};
        use crate::lod::DrawSet;
        let triangle = |n: usize| {
            let mesh = TriMesh::new(
                vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
                [[0, 1, 2], [0, 1, 3], [0, 2, 3]][..n].to_vec(),
            );
            DrawSet {
                mesh,
                ..Default::default()
            }
        };
        let chain = write_lod_chain(
            &[triangle(3), triangle(2), triangle(1)],
            &[1.0, 0.5, 0.1],
            PointsAs::default(),
        );
        assert_eq!(
            read(&chain, None).unwrap().0.triangles.len(),
            3,
            "LOD0 alone"
        );
        for (lod, triangles) in [(0, 3), (1, 2), (2, 1)] {
            assert_eq!(
                read_lod(&chain, None, lod).unwrap().triangles.len(),
                triangles
            );
        }
        let missing = read_lod(&chain, None, 3).unwrap_err().expected;
        assert!(
            missing.contains("LOD 3") && missing.contains("0 to 2"),
            "{missing}"
        );
        // A plain file is a chain of one.
        let single = write_glb(&triangle(2).mesh);
        assert_eq!(read_lod(&single, None, 0).unwrap().triangles.len(), 2);
        assert!(read_lod(&single, None, 1).is_err());
    }

    /// A one-triangle glTF whose buffer and image are the URIs given.
    fn gltf_naming(buffer: &str, image: Option<&str>) -> Vec<u8> {
        let mut doc = serde_json::json!({
            "asset": {"version": "2.0"},
            "buffers": [{"uri": buffer, "byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
            "materials": [{}],
            "nodes": [{"mesh": 0}],
            "scenes": [{"nodes": [0]}],
        });
        if let Some(uri) = image {
            doc["images"] = serde_json::json!([{"uri": uri}]);
            doc["textures"] = serde_json::json!([{"source": 0}]);
            doc["materials"][0]["pbrMetallicRoughness"] =
                serde_json::json!({"baseColorTexture": {"index": 0}});
        }
        serde_json::to_vec(&doc).unwrap()
    }

    fn triangle_bytes() -> Vec<u8> {
        [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    /// KHR_mesh_quantization (gltfpack's default output) is read, not
    /// refused: normalized i16 positions under a node's scale, normalized i8
    /// normals and unnormalized u16 UVs give the floats they stand for.
    #[test]
    fn quantized_attributes_are_dequantized_on_load() {
        let dir = tempfile::tempdir().unwrap();
        let mut bin = Vec::new();
        for p in [[0i16, 0, 0], [32767, 0, 0], [0, 32767, 0]] {
            p.iter().for_each(|c| bin.extend(c.to_le_bytes()));
            bin.extend([0, 0]); // 4-byte aligned stride of 8
        }
        for _ in 0..3 {
            bin.extend([0u8, 0, 127, 0]); // (0, 0, 1), stride 4
        }
        for uv in [[0u16, 0], [1, 0], [0, 1]] {
            uv.iter().for_each(|c| bin.extend(c.to_le_bytes()));
        }
        std::fs::write(dir.path().join("q.bin"), &bin).unwrap();
        let doc = serde_json::json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": ["KHR_mesh_quantization"],
            "extensionsRequired": ["KHR_mesh_quantization"],
            "buffers": [{"uri": "q.bin", "byteLength": 48}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": 24, "byteStride": 8},
                {"buffer": 0, "byteOffset": 24, "byteLength": 12, "byteStride": 4},
                {"buffer": 0, "byteOffset": 36, "byteLength": 12}
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5122, "normalized": true, "count": 3,
                 "type": "VEC3", "min": [0, 0, 0], "max": [32767, 32767, 0]},
                {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"},
                {"bufferView": 2, "componentType": 5123, "count": 3, "type": "VEC2"}
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}]}],
            "nodes": [{"mesh": 0, "scale": [2.0, 2.0, 2.0]}],
            "scenes": [{"nodes": [0]}],
        });
        let (mesh, report) = read(&serde_json::to_vec(&doc).unwrap(), Some(dir.path())).unwrap();
        let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
        assert_eq!(
            positions,
            [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]
        );
        let normals = mesh.normals.expect("normals");
        assert!(
            normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6),
            "{normals:?}"
        );
        let uvs: Vec<[f32; 2]> = mesh
            .uvs
            .expect("uvs")
            .iter()
            .map(|u| u.to_array())
            .collect();
        assert_eq!(uvs, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        assert!(
            report
                .dropped
                .iter()
                .all(|d| !d.what.contains("quantization"))
        );
    }

    #[test]
    fn buffers_and_images_are_read_only_inside_the_asset_folder() {
        let dir = tempfile::tempdir().unwrap();
        let model = dir.path().join("model");
        std::fs::create_dir_all(model.join("sub")).unwrap();
        std::fs::write(model.join("sub/tri.bin"), triangle_bytes()).unwrap();
        std::fs::write(dir.path().join("secret.bin"), triangle_bytes()).unwrap();
        std::fs::write(model.join("img.png"), b"\x89PNG not decoded here").unwrap();
        let read_at = |json: &[u8]| read(json, Some(&model)).map(|(mesh, _)| mesh);
        let ok = read_at(&gltf_naming("sub/tri.bin", Some("img.png"))).unwrap();
        assert_eq!(ok.triangles.len(), 1);
        let image = ok.materials.unwrap().table[0]
            .base_color_texture
            .clone()
            .unwrap();
        assert_eq!(&image.bytes[..], b"\x89PNG not decoded here");
        let inline = format!(
            "data:application/octet-stream;base64,{}",
            "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"
        );
        assert_eq!(
            read_at(&gltf_naming(&inline, None))
                .unwrap()
                .triangles
                .len(),
            1
        );
        let secret = dir.path().join("secret.bin");
        let secret = secret.to_str().unwrap();
        for (buffer, image, item) in [
            ("../secret.bin", None, "buffer 0"),
            (secret, None, "buffer 0"),
            (&format!("file://{secret}"), None, "buffer 0"),
            ("sub/tri.bin", Some("/etc/passwd"), "image 0"),
            ("sub/tri.bin", Some("../secret.bin"), "image 0"),
        ] {
            let e = read_at(&gltf_naming(buffer, image)).unwrap_err().expected;
            assert!(
                e.starts_with(item) && e.contains("outside the asset folder"),
                "{e}"
            );
            let named = referenced_files(&model.join("m.gltf"), &gltf_naming(buffer, image));
            assert!(named.is_err(), "{buffer} {image:?}");
        }
        assert_eq!(
            referenced_files(
                &model.join("m.gltf"),
                &gltf_naming("sub/tri.bin", Some("img.png"))
            ),
            Ok(vec![
                model.join("sub/tri.bin").canonicalize().unwrap(),
                model.join("img.png").canonicalize().unwrap()
            ])
        );
        // A GLB read from memory has no folder: no file is read for it.
        let e = read(&gltf_naming("sub/tri.bin", None), None)
            .unwrap_err()
            .expected;
        assert!(e.contains("read from memory"), "{e}");
    }

    #[test]
    fn a_node_graph_that_multiplies_its_instances_is_refused() {
        // 28 levels of nodes, each listing the next twice: 2^28 instances.
        let mut doc: serde_json::Value =
            serde_json::from_slice(&gltf_naming("tri.bin", None)).unwrap();
        let mut nodes = vec![serde_json::json!({"mesh": 0})];
        for level in 1..28 {
            nodes.push(serde_json::json!({"children": [level - 1, level - 1]}));
        }
        doc["nodes"] = nodes.into();
        doc["scenes"] = serde_json::json!([{"nodes": [27]}]);
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("tri.bin"), triangle_bytes()).unwrap();
        let start = std::time::Instant::now();
        let e = read(&serde_json::to_vec(&doc).unwrap(), Some(dir.path())).unwrap_err();
        assert!(e.expected.contains("node instances"), "{}", e.expected);
        assert!(start.elapsed().as_secs() < 20);
    }
}
