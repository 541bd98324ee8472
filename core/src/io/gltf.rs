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
