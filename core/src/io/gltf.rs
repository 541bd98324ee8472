//! glTF 2.0 (`.gltf` + `.bin`, `.glb`) through the gltf crate. Every material
//! of every mesh instance of the scene graph becomes a part, with its node
//! transform applied. Materials are kept (factors and the base-colour texture,
//! its image bytes as stored) for the exports; for display, the vertex colour is
//! the base-colour factor times `COLOR_0`.
//!
//! Accessor ranges are checked against the buffers before any read (the crate's
//! readers assume valid data), so hostile files give an error instead of a panic.

use std::path::Path;

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

pub fn read(data: &[u8], base: Option<&Path>) -> ParseResult<TriMesh> {
    let g = parse(data)?;
    check_buffer_files(&g.document, base)?;
    let buffers = gltf::import_buffers(&g.document, base, g.blob.clone())
        .map_err(|e| ParseError::file(format!("expected readable glTF buffers ({e})")))?;
    let mut mesh = TriMesh::default();
    let roots: Vec<gltf::Node> = match g
        .document
        .default_scene()
        .or_else(|| g.document.scenes().next())
    {
        Some(scene) => scene.nodes().collect(),
        None => g.document.nodes().collect(),
    };
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

/// Writes one mesh as a binary glTF (GLB): positions, normals (area-weighted
/// vertex normals when the mesh has none), vertex colours and UVs when it has
/// them, and 32-bit indices in one buffer, one node, one scene.
pub fn write_glb(mesh: &TriMesh) -> Vec<u8> {
    super::gltf_writer::write_draw_set_glb(&crate::lod::DrawSet {
        mesh: mesh.clone(),
        ..Default::default()
    })
}

/// The `MSFT_screencoverage` thresholds of an LOD chain.
///
/// `error_bounds[i]` is LOD i's guaranteed (object-space) error bound, in
/// increasing order; `radius` is the object's bounding-sphere radius; the
/// tolerance is `pixels` on a viewport `viewport_height` pixels high.
///
/// The screen coverage `c` is the object's projected height (its bounding
/// sphere's diameter) as a fraction of the viewport height. With a vertical
/// field of view θ at distance d, a length `l` covers `l·H / (2 d tan(θ/2))`
/// pixels, so `c = 2r / (2 d tan(θ/2))` and an error bound `e` covers
/// `e·H·c / (2r)` pixels: it stays within `p` pixels exactly while
///
/// ```text
/// c <= c(e) = 2 r p / (e H)        (independent of θ and d)
/// ```
///
/// A loader shows LOD i while the coverage is at least `coverages[i]` (and
/// below `coverages[i-1]`), so LOD i+1 may take over once LOD i+1's bound
/// projects within the tolerance: `coverages[i] = c(e[i+1])`. The last value is
/// `p / H`, where the whole object spans `p` pixels (below it, leaving the
/// object out stays within the tolerance). Values are clamped to (0, 1] and
/// made strictly decreasing by lowering, never raising, a value, which only
/// keeps a finer LOD longer; so every shown LOD's bound projects to at most
/// `p` pixels (LOD0 excepted above `c(e[0])`, as nothing finer exists).
pub fn lod_screen_coverages(
    error_bounds: &[f32],
    radius: f32,
    pixels: f32,
    viewport_height: f32,
) -> Vec<f32> {
    let (r, p, h) = (radius as f64, pixels as f64, viewport_height as f64);
    let coverage = |e: f64| {
        let c = 2.0 * r * p / (e * h);
        if c.is_nan() { 1.0 } else { c }
    };
    let n = error_bounds.len();
    let mut out: Vec<f32> = Vec::with_capacity(n);
    for i in 0..n {
        let raw = match error_bounds.get(i + 1) {
            Some(&e) => coverage(e as f64),
            None => p / h,
        };
        let mut c = raw.clamp(0.0, 1.0) as f32;
        if let Some(&prev) = out.last() {
            c = c.min(prev * (1.0 - 1e-4));
        }
        if c.is_nan() || c <= 0.0 {
            // Degenerate input (zero radius or pixels): keep the order positive.
            c = out.last().map_or(1.0, |prev| prev * 0.5);
        }
        out.push(c);
    }
    out
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

/// Packs a JSON chunk (space-padded) and a binary chunk (zero-padded; left out
/// when empty) into GLB.
pub(crate) fn glb_container(mut json: Vec<u8>, bin: Vec<u8>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + json.len() + bin_chunk;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::gltf_writer::{write_draw_set_glb, write_lod_chain};

    #[test]
    fn glb_round_trips_through_the_reader() {
        let mut m = crate::builtins::torus(1.0, 0.3, 16, 8);
        m.colors = Some(vec![Vec3::new(0.2, 0.5, 0.9); m.positions.len()]);
        let glb = write_glb(&m);
        let back = read(&glb, None).unwrap();
        assert_eq!(back.triangles, m.triangles);
        assert_eq!(back.positions, m.positions);
        assert!(back.normals.is_some() && back.uvs.is_some());
        assert_eq!(back.colors.as_ref().unwrap()[3], Vec3::new(0.2, 0.5, 0.9));
    }

    #[test]
    fn materials_round_trip_one_primitive_per_material_with_their_images() {
        use crate::geom::{AlphaMode, Image, Material, Materials};
        let png = super::super::gltf_writer::encode_png(&crate::lod::Texture {
            width: 2,
            height: 1,
            rgba: vec![[255, 0, 0, 255], [0, 0, 255, 128]],
        });
        let textured = Material {
            name: Some("paint".into()),
            base_color: [1.0, 1.0, 1.0, 1.0],
            metallic: 0.25,
            roughness: 0.5,
            emissive: [0.0, 0.1, 0.0],
            alpha_mode: AlphaMode::Mask(0.3),
            double_sided: true,
            base_color_texture: Some(Image {
                mime_type: "image/png".into(),
                bytes: png.into(),
                mag_filter: Some(9729),
                min_filter: None,
                wrap_s: 10497,
                wrap_t: 33648,
            }),
            vertex_attributes: Default::default(),
        };
        let glass = Material {
            name: Some("glass".into()),
            base_color: [0.5, 0.25, 0.0, 0.4],
            alpha_mode: AlphaMode::Blend,
            ..Material::default()
        };
        let mut a = crate::builtins::torus(1.0, 0.3, 16, 8);
        a.materials = Some(Materials::single(textured));
        let mut b = crate::builtins::torus(2.0, 0.2, 12, 6);
        // Display colours are base colour × COLOR_0.
        b.colors = Some(
            (0..b.positions.len())
                .map(|i| Vec3::new(0.5, 0.25, 0.0) * (i % 3) as f32 / 2.0)
                .collect(),
        );
        b.materials = Some(Materials::single(glass));
        let mut m = a.clone();
        m.append(&b);
        assert_eq!(m.part_count(), 2);
        let glb = write_glb(&m);
        let doc = glb_json(&glb);
        assert_eq!(doc["meshes"][0]["primitives"].as_array().unwrap().len(), 2);
        assert_eq!(doc["materials"].as_array().unwrap().len(), 2);
        assert_eq!(
            doc["samplers"][0],
            serde_json::json!({"magFilter": 9729, "wrapS": 10497, "wrapT": 33648})
        );
        let back = read(&glb, None).unwrap();
        // Read back, each material says which attributes its primitive has:
        // the textured part's white COLOR_0 was left out.
        let mut expected = m.materials.clone().unwrap();
        expected.table[0].vertex_attributes = VertexAttributes {
            colors: false,
            uvs: true,
        };
        assert_eq!(back.materials, Some(expected));
        assert_eq!(back.triangles.len(), m.triangles.len());
        assert_eq!(back.part_count(), 2);
        // The textured part's vertex colour is white: no COLOR_0 was written for it.
        let first = &doc["meshes"][0]["primitives"][0]["attributes"];
        assert!(first.get("COLOR_0").is_none() && first.get("TEXCOORD_0").is_some());
        let (want, got) = (m.colors.clone().unwrap(), back.colors.clone().unwrap());
        for t in 0..m.triangles.len() {
            let p = m.part(t);
            assert_eq!(back.part(t), p);
            for (&v, &w) in m.triangles[t].iter().zip(&back.triangles[t]) {
                let (c, d) = (want[v as usize], got[w as usize]);
                assert!(c.abs_diff_eq(d, 1e-3), "part {p}: {c} vs {d}");
            }
        }
    }

    /// Image URIs name data or regular files beside the glTF, never devices,
    /// folders or other schemes.
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

    #[test]
    fn glb_with_points_holds_a_points_primitive_with_radius() {
        let mesh = crate::builtins::torus(1.0, 0.3, 8, 4);
        let points = crate::geom::PointSet {
            positions: vec![Vec3::ZERO, Vec3::X],
            normals: None,
            colors: Some(vec![Vec3::new(1.0, 0.0, 0.0); 2]),
            radii: Some(vec![0.1, 0.2]),
        };
        let set = |mesh: &TriMesh| crate::lod::DrawSet {
            mesh: mesh.clone(),
            points: (0..2)
                .map(|i| crate::lod::CutPoint {
                    center: points.positions[i],
                    radius: points.radii.as_ref().unwrap()[i],
                    color: Vec3::new(1.0, 0.0, 0.0),
                    normal: Vec3::Z,
                    error: 0.0,
                })
                .collect(),
            ..Default::default()
        };
        let glb = write_draw_set_glb(&set(&mesh));
        let doc = glb_json(&glb);
        assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0]));
        let prim = &doc["meshes"][0]["primitives"][1];
        assert_eq!(prim["mode"], 0);
        let radius = prim["attributes"]["_RADIUS"].as_u64().unwrap() as usize;
        assert_eq!(doc["accessors"][radius]["count"], 2);
        assert_eq!(read(&glb, None).unwrap().triangles, mesh.triangles);
        // Points alone still make a valid file.
        let only = glb_json(&write_draw_set_glb(&set(&TriMesh::default())));
        assert_eq!(only["meshes"][0]["primitives"][0]["mode"], 0);
    }

    fn sets(meshes: &[TriMesh]) -> Vec<crate::lod::DrawSet> {
        meshes
            .iter()
            .map(|m| crate::lod::DrawSet {
                mesh: m.clone(),
                ..Default::default()
            })
            .collect()
    }

    /// The JSON chunk of a GLB.
    fn glb_json(glb: &[u8]) -> serde_json::Value {
        let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        assert_eq!(&glb[16..20], b"JSON");
        serde_json::from_slice(&glb[20..20 + len]).unwrap()
    }

    #[test]
    fn lod_chain_carries_msft_lod_and_readers_without_it_see_lod0() {
        let lods = [
            crate::builtins::torus(1.0, 0.3, 32, 16),
            crate::builtins::torus(1.0, 0.3, 16, 8),
            crate::builtins::torus(1.0, 0.3, 8, 4),
        ];
        let coverages = lod_screen_coverages(&[0.001, 0.01, 0.1], 1.3, 2.0, 1080.0);
        let glb = write_lod_chain(&sets(&lods), &coverages, Default::default());
        let doc = glb_json(&glb);
        assert_eq!(doc["extensionsUsed"], serde_json::json!(["MSFT_lod"]));
        assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0]));
        assert_eq!(
            doc["nodes"][0]["extensions"]["MSFT_lod"]["ids"],
            serde_json::json!([1, 2])
        );
        let stated: Vec<f32> = doc["nodes"][0]["extras"]["MSFT_screencoverage"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        assert_eq!(stated, coverages);
        // Each LOD node's index accessor holds its triangles.
        for (i, lod) in lods.iter().enumerate() {
            let mesh = doc["nodes"][i]["mesh"].as_u64().unwrap() as usize;
            let prim = &doc["meshes"][mesh]["primitives"][0];
            let acc = prim["indices"].as_u64().unwrap() as usize;
            assert_eq!(
                doc["accessors"][acc]["count"].as_u64().unwrap() as usize,
                lod.triangles.len() * 3
            );
            for attr in ["POSITION", "NORMAL", "TEXCOORD_0"] {
                assert!(prim["attributes"][attr].is_u64(), "lod{i} {attr}");
            }
        }
        let back = read(&glb, None).unwrap();
        assert_eq!(back.triangles, lods[0].triangles);
        assert_eq!(back.positions, lods[0].positions);
        // One LOD: the plain file, no extension.
        let single = write_lod_chain(&sets(&lods[..1]), &coverages[..1], Default::default());
        assert_eq!(single, write_glb(&lods[0]));
    }

    #[test]
    fn lod_chain_without_triangles_in_a_lod_stays_readable() {
        let lods = [crate::builtins::torus(1.0, 0.3, 8, 4), TriMesh::default()];
        let glb = write_lod_chain(&sets(&lods), &[0.5, 0.1], Default::default());
        let doc = glb_json(&glb);
        assert!(doc["nodes"][1].get("mesh").is_none());
        assert_eq!(read(&glb, None).unwrap().triangles, lods[0].triangles);
        // Nothing at all: a valid GLB without a binary chunk.
        let empty = write_glb(&TriMesh::default());
        assert_eq!(
            empty.len(),
            20 + glb_json(&empty).to_string().len().next_multiple_of(4)
        );
        assert!(read(&empty, None).unwrap().triangles.is_empty());
        // A mesh without normals is written with computed ones.
        let mut bare = crate::builtins::torus(1.0, 0.3, 8, 4);
        bare.normals = None;
        let back = read(&write_glb(&bare), None).unwrap();
        let expected = bare.vertex_normals();
        for (a, b) in back.normals.unwrap().iter().zip(&expected) {
            assert!(a.distance(*b) < 1e-5);
        }
    }

    #[test]
    fn screen_coverage_is_where_the_next_bound_projects_to_the_tolerance() {
        // r = 1, p = 2 px, H = 1000: c(e) = 2·1·2 / (e·1000) = 0.004 / e.
        let c = lod_screen_coverages(&[0.001, 0.01, 0.1], 1.0, 2.0, 1000.0);
        assert_eq!(c.len(), 3);
        assert!((c[0] - 0.4).abs() < 1e-6, "{c:?}");
        assert!((c[1] - 0.04).abs() < 1e-6, "{c:?}");
        assert!((c[2] - 0.002).abs() < 1e-6, "{c:?}");
        // At coverage c[0], LOD1's bound projects to exactly p pixels:
        // pixels = e·H·c / (2r).
        assert!((0.01 * 1000.0 * c[0] / 2.0 - 2.0).abs() < 1e-4);
        // Zero bounds, equal bounds and huge bounds: clamped, strictly decreasing, positive.
        let c = lod_screen_coverages(&[0.0, 0.0, 0.5, 0.5, 1e9], 1.0, 1.0, 1080.0);
        assert!(c.iter().all(|v| *v > 0.0 && *v <= 1.0), "{c:?}");
        assert!(c.windows(2).all(|w| w[1] < w[0]), "{c:?}");
        let c = lod_screen_coverages(&[0.1, 0.2], 0.0, 1.0, 1080.0);
        assert!(
            c.iter().all(|v| *v > 0.0 && *v <= 1.0) && c[1] < c[0],
            "{c:?}"
        );
    }
}
