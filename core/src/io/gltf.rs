//! glTF 2.0 (`.gltf` + `.bin`, `.glb`) through the gltf crate. Every material
//! of every mesh instance of the scene graph becomes a part, with its node
//! transform applied. Materials are kept (factors and the base-colour texture,
//! its image bytes as stored) for the exports; for display, the vertex colour is
//! the base-colour factor times `COLOR_0`.
//!
//! Accessor ranges are checked against the buffers before any read (the crate's
//! readers assume valid data), so hostile files give an error instead of a panic.

use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::error::{ParseError, ParseResult};
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
fn parse(data: &[u8]) -> ParseResult<gltf::Gltf> {
    check_glb_length(data)?;
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
    let document = gltf::Document::from_json(document.into_json()).map_err(invalid)?;
    Ok(gltf::Gltf { document, blob })
}

/// Every mesh instance of the default scene (else the first scene, else of
/// every node) as one mesh.
pub fn read(data: &[u8], base: Option<&Path>) -> ParseResult<TriMesh> {
    let g = parse(data)?;
    let roots = scene_roots(&g.document);
    read_nodes(&g, base, roots)
}

/// Level `lod` of the `MSFT_lod` chain that `export` writes: LOD 0 is the
/// scene's first root (node 0), whose `extensions.MSFT_lod.ids` name the
/// nodes of LOD 1, 2, … (which no scene lists, so [`read`] never sees them).
/// Only that node and its children are read.
///
/// # Errors
/// As [`read`], and when the chain has no LOD `lod`.
pub fn read_lod(data: &[u8], base: Option<&Path>, lod: usize) -> ParseResult<TriMesh> {
    let g = parse(data)?;
    let Some(head) = scene_roots(&g.document).into_iter().next() else {
        return Err(ParseError::file("expected a node to hold LOD 0"));
    };
    let ids = lod_ids(data, head.index())?;
    let index = match lod {
        0 => head.index(),
        k => *ids.get(k - 1).ok_or_else(|| {
            ParseError::file(format!(
                "expected an LOD {k}, but the MSFT_lod chain has LODs 0 to {}",
                ids.len()
            ))
        })?,
    };
    let node = g.document.nodes().nth(index).ok_or_else(|| {
        ParseError::item(
            format!("node {}", head.index()),
            format!("expected MSFT_lod ids among the nodes, found {index}"),
        )
    })?;
    read_nodes(&g, base, vec![node])
}

fn scene_roots(document: &gltf::Document) -> Vec<gltf::Node<'_>> {
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
fn lod_ids(data: &[u8], node: usize) -> ParseResult<Vec<usize>> {
    let json = match gltf::binary::Glb::from_slice(data) {
        Ok(glb) => glb.json.into_owned(),
        Err(_) => data.to_vec(),
    };
    let root: serde_json::Value = serde_json::from_slice(&json)
        .map_err(|e| ParseError::file(format!("expected glTF JSON ({e})")))?;
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

/// The meshes of `roots` and their descendants, node transforms applied.
fn read_nodes(g: &gltf::Gltf, base: Option<&Path>, roots: Vec<gltf::Node>) -> ParseResult<TriMesh> {
    check_buffer_files(&g.document, base)?;
    let buffers = gltf::import_buffers(&g.document, base, g.blob.clone())
        .map_err(|e| ParseError::file(format!("expected readable glTF buffers ({e})")))?;
    let mut mesh = TriMesh::default();
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        // A node graph deeper than the node count has a cycle.
        if depth > g.document.nodes().len() {
            return Err(ParseError::item(
                format!("node {}", node.index()),
                "expected an acyclic node hierarchy",
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(ParseError::item(
                format!("node {}", node.index()),
                "expected a finite transform",
            ));
        }
        if let Some(m) = node.mesh() {
            let mut instance = TriMesh::default();
            // Primitives of one material make one part, whatever their count.
            let mut keys: Vec<Option<usize>> = Vec::new();
            let mut materials = Materials::default();
            let mut parts = Vec::new();
            for prim in m.primitives() {
                if let Some(piece) = read_primitive(&prim, &buffers, world)? {
                    let key = prim.material().index();
                    let part = match keys.iter().position(|k| *k == key) {
                        Some(p) => p,
                        None => {
                            let mut material = read_material(&prim.material(), &buffers, base)?;
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
                    instance.append(&piece);
                }
            }
            instance.parts = (keys.len() > 1).then_some(parts);
            instance.materials = Some(materials);
            if !instance.triangles.is_empty() {
                mesh.append(&instance);
            }
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    Ok(mesh)
}

/// Buffers in files must be regular files within the memory budget: the
/// crate reads them whole (a buffer at `/dev/zero` would never end).
fn check_buffer_files(document: &gltf::Document, base: Option<&Path>) -> ParseResult<()> {
    let Some(base) = base else {
        return Ok(()); // the crate refuses external buffers without a base
    };
    for buffer in document.buffers() {
        let gltf::buffer::Source::Uri(uri) = buffer.source() else {
            continue;
        };
        let what = || format!("buffer {}", buffer.index());
        let path = match uri
            .strip_prefix("file://")
            .or_else(|| uri.strip_prefix("file:"))
        {
            Some(rest) => base.join(rest),
            None if uri.contains(':') => continue,
            None => match urlencoding::decode(uri) {
                Ok(relative) => base.join(&*relative),
                Err(_) => continue, // refused by `parse`
            },
        };
        match std::fs::metadata(&path) {
            Ok(m) if m.is_file() => super::limits::check_budget(&what(), m.len())?,
            _ => {
                return Err(ParseError::item(
                    what(),
                    format!("expected {uri:?} to be a regular file"),
                ));
            }
        }
    }
    Ok(())
}

/// Checks that every element of the accessor lies inside its buffer view and buffer.
fn check_accessor(acc: &gltf::Accessor, buffers: &[gltf::buffer::Data]) -> ParseResult<()> {
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
            Semantic::Positions | Semantic::Normals => {
                acc.dimensions() == N::Vec3 && acc.data_type() == D::F32
            }
            Semantic::TexCoords(0) => {
                acc.dimensions() == N::Vec2 && matches!(acc.data_type(), D::F32 | D::U8 | D::U16)
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
    let Some(positions) = reader.read_positions() else {
        return Ok(None);
    };
    let positions: Vec<Vec3> = positions
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
    if let Some(nr) = reader.read_normals() {
        let normals: Vec<Vec3> = nr
            .map(|v| (normal_matrix * Vec3::from_array(v)).normalize_or_zero())
            .collect();
        if normals.len() == n {
            mesh.normals = Some(normals);
        }
    }
    if let Some(uv) = reader.read_tex_coords(0) {
        let uvs: Vec<Vec2> = uv.into_f32().map(Vec2::from_array).collect();
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
/// as stored: a buffer view, a data URI or a file next to the glTF).
fn read_material(
    m: &gltf::Material,
    buffers: &[gltf::buffer::Data],
    base: Option<&Path>,
) -> ParseResult<Material> {
    let pbr = m.pbr_metallic_roughness();
    let what = || {
        format!(
            "material {}",
            m.index().map_or("default".into(), |i| i.to_string())
        )
    };
    let texture = match pbr.base_color_texture() {
        // Only TEXCOORD_0 is carried, so textures on other sets are left out.
        Some(info) if info.tex_coord() == 0 => {
            let tex = info.texture();
            let (bytes, mime_type) = match tex.source().source() {
                gltf::image::Source::View { view, mime_type } => {
                    let data = buffers
                        .get(view.buffer().index())
                        .map_or(&[][..], |d| &d.0[..]);
                    let bytes = view
                        .offset()
                        .checked_add(view.length())
                        .and_then(|end| data.get(view.offset()..end))
                        .ok_or_else(|| {
                            ParseError::item(what(), "expected its image inside its buffer")
                        })?;
                    (bytes.to_vec(), mime_type.to_string())
                }
                gltf::image::Source::Uri { uri, mime_type } => {
                    let bytes =
                        read_image_uri(uri, base).map_err(|e| ParseError::item(what(), e))?;
                    let png = bytes.starts_with(b"\x89PNG");
                    let mime = mime_type.map_or(
                        if png { "image/png" } else { "image/jpeg" }.to_string(),
                        str::to_string,
                    );
                    (bytes, mime)
                }
            };
            let sampler = tex.sampler();
            Some(Image {
                mime_type,
                bytes: bytes.into(),
                mag_filter: sampler.mag_filter().map(|f| f.as_gl_enum()),
                min_filter: sampler.min_filter().map(|f| f.as_gl_enum()),
                wrap_s: sampler.wrap_s().as_gl_enum(),
                wrap_t: sampler.wrap_t().as_gl_enum(),
            })
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
        vertex_attributes: VertexAttributes::default(),
    })
}

/// The largest image file a glTF may reference (a hostile file could name a
/// device or a huge file).
const MAX_IMAGE_BYTES: u64 = 256 << 20;

/// The bytes of an image URI: a data URI, or a regular file beside the glTF.
fn read_image_uri(uri: &str, base: Option<&Path>) -> Result<Vec<u8>, String> {
    if uri.starts_with("data:") {
        // The decoder pads buffers to 4 bytes; an image keeps its exact length.
        let payload = uri.rsplit(',').next().unwrap_or("").trim_end_matches('=');
        let exact = payload.len() * 3 / 4;
        return gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
            .map(|d| d.0[..exact.min(d.0.len())].to_vec())
            .map_err(|e| format!("expected a readable data URI ({e})"));
    }
    let Some(base) = base.filter(|_| !uri.contains(':')) else {
        return Err(format!(
            "expected a data URI or a file beside the glTF, found {uri:?}"
        ));
    };
    let path = base.join(uri);
    match std::fs::metadata(&path) {
        Ok(m) if m.is_file() && m.len() <= MAX_IMAGE_BYTES => {
            std::fs::read(&path).map_err(|e| format!("expected a readable image {uri:?} ({e})"))
        }
        Ok(_) => Err(format!(
            "expected {uri:?} to be an image file of at most 256 MiB"
        )),
        Err(e) => Err(format!("expected the image file {uri:?} ({e})")),
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

/// The files beside a glTF that it names (external buffers and images, in
/// document order, each once): what a glTF's content is made of besides its
/// own bytes (batch caches hash them). Unreadable documents name none.
pub fn referenced_files(path: &Path, bytes: &[u8]) -> Vec<PathBuf> {
    let Ok(gltf) = gltf::Gltf::from_slice_without_validation(bytes) else {
        return Vec::new();
    };
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf.document.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(uri) => Some(uri),
        gltf::buffer::Source::Bin => None,
    });
    let images = gltf.document.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } => Some(uri),
        gltf::image::Source::View { .. } => None,
    });
    let mut out: Vec<PathBuf> = Vec::new();
    for uri in buffers.chain(images) {
        let relative = uri
            .strip_prefix("file://")
            .or_else(|| uri.strip_prefix("file:"))
            .map(str::to_owned)
            .or_else(|| {
                (!uri.contains(':'))
                    .then(|| urlencoding::decode(uri).ok().map(|d| d.into_owned()))
                    .flatten()
            });
        if let Some(r) = relative {
            let p = base.join(r);
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
    out
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
        assert_eq!(read(&chain, None).unwrap().triangles.len(), 3, "LOD0 alone");
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

    #[test]
    fn image_uris_are_data_or_files_beside_the_gltf() {
        let here = Path::new(env!("CARGO_MANIFEST_DIR"));
        assert_eq!(
            read_image_uri("data:image/png;base64,AAEC", None),
            Ok(vec![0, 1, 2])
        );
        assert_eq!(
            read_image_uri("Cargo.toml", Some(here)).ok(),
            std::fs::read(here.join("Cargo.toml")).ok()
        );
        for bad in [
            "/dev/zero",
            "src",
            "http://example.invalid/a.png",
            "missing.png",
        ] {
            assert!(read_image_uri(bad, Some(here)).is_err(), "{bad}");
        }
        assert!(
            read_image_uri("Cargo.toml", None).is_err(),
            "no folder for a GLB in memory"
        );
    }
}
