//! glTF 2.0 (`.gltf` + `.bin`, `.glb`) through the gltf crate. Every mesh
//! instance of the scene graph becomes a part with its node transform applied;
//! a material's base colour becomes a vertex colour when the primitive has none.
//!
//! Accessor ranges are checked against the buffers before any read (the crate's
//! readers assume valid data), so hostile files give an error instead of a panic.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::error::{ParseError, ParseResult};
use crate::geom::TriMesh;

pub fn read(data: &[u8], base: Option<&Path>) -> ParseResult<TriMesh> {
    let g = gltf::Gltf::from_slice(data)
        .map_err(|e| ParseError::file(format!("expected valid glTF 2.0 ({e})")))?;
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
            for prim in m.primitives() {
                if let Some(piece) = read_primitive(&prim, &buffers, world)? {
                    instance.append(&piece);
                }
            }
            // One part per mesh instance, whatever its primitive count.
            instance.parts = None;
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
    if count == 0 {
        return Ok(());
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
    mesh.colors = match colors {
        Some(c) if c.len() == n => Some(c),
        _ => {
            let [r, g, b, _] = prim.material().pbr_metallic_roughness().base_color_factor();
            Some(vec![Vec3::new(r, g, b); n])
        }
    };
    // A mirroring transform flips the winding; flip it back to keep normals outward.
    if world.determinant() < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    Ok(Some(mesh))
}

/// Writes one mesh as a binary glTF (GLB): positions, normals, vertex colours,
/// UVs and 32-bit indices in one buffer, one node, one scene.
pub fn write_glb(mesh: &TriMesh) -> Vec<u8> {
    use serde_json::json;
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut attributes = serde_json::Map::new();
    let n = mesh.positions.len();
    let bounds = mesh.bounds();
    let mut add = |bin: &mut Vec<u8>,
                   data: &[f32],
                   kind: &str,
                   target: u32,
                   extra: serde_json::Value| {
        let offset = bin.len();
        bin.extend(data.iter().flat_map(|x| x.to_le_bytes()));
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len() * 4, "target": target}));
        let mut acc =
            json!({"bufferView": views.len() - 1, "componentType": 5126, "count": n, "type": kind});
        if let (Some(a), Some(e)) = (acc.as_object_mut(), extra.as_object()) {
            a.extend(e.clone());
        }
        accessors.push(acc);
        accessors.len() - 1
    };
    let flat3 = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
    let pos = add(
        &mut bin,
        &flat3(&mesh.positions),
        "VEC3",
        34962,
        json!({"min": bounds.min.to_array(), "max": bounds.max.to_array()}),
    );
    attributes.insert("POSITION".into(), pos.into());
    if let Some(nr) = &mesh.normals {
        let unit: Vec<Vec3> = nr
            .iter()
            .map(|v| v.try_normalize().unwrap_or(Vec3::Z))
            .collect();
        let a = add(&mut bin, &flat3(&unit), "VEC3", 34962, json!({}));
        attributes.insert("NORMAL".into(), a.into());
    }
    if let Some(c) = &mesh.colors {
        let clamped: Vec<Vec3> = c.iter().map(|v| v.clamp(Vec3::ZERO, Vec3::ONE)).collect();
        let a = add(&mut bin, &flat3(&clamped), "VEC3", 34962, json!({}));
        attributes.insert("COLOR_0".into(), a.into());
    }
    if let Some(uv) = &mesh.uvs {
        let flat: Vec<f32> = uv.iter().flat_map(|v| v.to_array()).collect();
        let a = add(&mut bin, &flat, "VEC2", 34962, json!({}));
        attributes.insert("TEXCOORD_0".into(), a.into());
    }
    let offset = bin.len();
    bin.extend(
        mesh.triangles
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes()),
    );
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": mesh.triangles.len() * 12, "target": 34963}));
    accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5125, "count": mesh.triangles.len() * 3, "type": "SCALAR"}));
    let indices = accessors.len() - 1;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "lodstudio"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "lod0"}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": indices, "mode": 4, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}, "doubleSided": false}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    glb_container(doc.to_string().into_bytes(), bin)
}

/// Packs a JSON chunk (space-padded) and a binary chunk (zero-padded) into GLB.
fn glb_container(mut json: Vec<u8>, bin: Vec<u8>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
