//! Wavefront OBJ through tobj. Each `o`/`g` model becomes a part.
//!
//! tobj reports errors without a position, so a linear pre-pass checks every
//! `v` and `f` line first (numbers parse, face indices in range) and names the
//! line of the first problem; tobj then does the real parse.

use glam::{Vec2, Vec3};

use super::error::{ParseError, ParseResult};
use crate::geom::TriMesh;
use crate::progress::Progress;

/// True when the text starts like an OBJ file (used when the extension is absent).
pub fn looks_like_obj(head: &[u8]) -> bool {
    let text = String::from_utf8_lossy(head);
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .take(8)
        .any(|l| {
            let kw = l.split_ascii_whitespace().next().unwrap_or("");
            matches!(
                kw,
                "v" | "vn" | "vt" | "f" | "o" | "g" | "mtllib" | "usemtl" | "s"
            )
        })
}

pub fn read(data: &[u8], progress: &Progress) -> ParseResult<TriMesh> {
    let unreferenced = validate(data, progress)?;
    let opts = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ..Default::default()
    };
    let mut reader = std::io::BufReader::new(data);
    let (models, _) = tobj::load_obj_buf(&mut reader, &opts, |_| Ok(Default::default()))
        .map_err(|e| ParseError::file(format!("expected valid OBJ ({e})")))?;
    let mut mesh = TriMesh::default();
    // tobj may emit empty models (e.g. before the first `o`); they are no part.
    let models = models.iter().filter(|m| !m.mesh.indices.is_empty());
    for model in models {
        let m = &model.mesh;
        let n = m.positions.len() / 3;
        let triangles: Vec<[u32; 3]> = m
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        if triangles.iter().flatten().any(|i| *i as usize >= n) {
            return Err(ParseError::item(
                format!("object {:?}", model.name),
                "expected face indices within the vertex count",
            ));
        }
        let mut piece = TriMesh::new(
            m.positions.chunks_exact(3).map(Vec3::from_slice).collect(),
            triangles,
        );
        if m.normals.len() == m.positions.len() {
            piece.normals = Some(m.normals.chunks_exact(3).map(Vec3::from_slice).collect());
        }
        if m.vertex_color.len() == m.positions.len() {
            piece.colors = Some(
                m.vertex_color
                    .chunks_exact(3)
                    .map(Vec3::from_slice)
                    .collect(),
            );
        }
        if m.texcoords.len() / 2 == n && !m.texcoords.is_empty() {
            piece.uvs = Some(m.texcoords.chunks_exact(2).map(Vec2::from_slice).collect());
        }
        // `append` numbers each appended piece as the next part.
        mesh.append(&piece);
    }
    // tobj drops vertex records no face uses; keep them so repair reports them.
    let n = mesh.positions.len();
    mesh.positions.extend_from_slice(&unreferenced);
    for a in [&mut mesh.normals, &mut mesh.colors].into_iter().flatten() {
        a.resize(n + unreferenced.len(), Vec3::ZERO);
    }
    if let Some(uv) = &mut mesh.uvs {
        uv.resize(n + unreferenced.len(), Vec2::ZERO);
    }
    Ok(mesh)
}

/// Checks numbers and face references line by line (see the module doc) and
/// returns the vertex records that no face refers to.
fn validate(data: &[u8], progress: &Progress) -> ParseResult<Vec<Vec3>> {
    let text = std::str::from_utf8(data)
        .map_err(|e| ParseError::byte(e.valid_up_to() as u64, "expected UTF-8 text"))?;
    let (mut nv, mut nvt, mut nvn) = (0i64, 0i64, 0i64);
    // Positive indices may refer to vertices defined later: check them at the end.
    let mut max_ref = [(0i64, 0usize); 3];
    let mut positions: Vec<Vec3> = Vec::new();
    let mut referenced: Vec<bool> = Vec::new();
    let mut forward_refs: Vec<usize> = Vec::new();
    let total = text.len().max(1);
    let mut offset = 0usize;
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        offset += line.len() + 1;
        if ln % 65_536 == 0 {
            progress.set_fraction(offset as f32 / total as f32);
            progress
                .check()
                .map_err(|_| ParseError::line(ln, "cancelled"))?;
        }
        let mut tok = line.split_ascii_whitespace();
        match tok.next() {
            Some("v") => {
                let mut c = [0f32; 3];
                for x in &mut c {
                    *x = tok.next().and_then(|t| t.parse().ok()).ok_or_else(|| {
                        ParseError::line(ln, "expected a vertex with 3 numeric coordinates")
                    })?;
                }
                positions.push(Vec3::from_array(c));
                referenced.push(false);
                nv += 1;
            }
            Some("vt") => nvt += 1,
            Some("vn") => nvn += 1,
            Some("f") => {
                let mut corners = 0;
                for corner in tok {
                    corners += 1;
                    let counts = [nv, nvt, nvn];
                    for (k, idx) in corner.split('/').enumerate().take(3) {
                        if idx.is_empty() && k > 0 {
                            continue;
                        }
                        let v: i64 = idx.parse().map_err(|_| {
                            ParseError::line(ln, format!("expected a face index, found {corner:?}"))
                        })?;
                        let ok = match v {
                            0 => false,
                            v if v < 0 => -v <= counts[k],
                            v => {
                                if v > max_ref[k].0 {
                                    max_ref[k] = (v, ln);
                                }
                                true
                            }
                        };
                        if ok && k == 0 {
                            let abs = if v < 0 { nv + v } else { v - 1 } as usize;
                            match referenced.get_mut(abs) {
                                Some(r) => *r = true,
                                None => forward_refs.push(abs),
                            }
                        }
                        if !ok {
                            return Err(ParseError::line(
                                ln,
                                format!(
                                    "expected a face index referring to an existing element, found {v}"
                                ),
                            ));
                        }
                    }
                }
                if corners < 3 {
                    return Err(ParseError::line(
                        ln,
                        "expected a face with at least 3 vertices",
                    ));
                }
            }
            _ => {}
        }
    }
    for (k, count) in [nv, nvt, nvn].into_iter().enumerate() {
        let (v, ln) = max_ref[k];
        if v > count {
            return Err(ParseError::line(
                ln,
                format!("expected a face index of at most {count}, found {v}"),
            ));
        }
    }
    for abs in forward_refs {
        referenced[abs] = true;
    }
    Ok(positions
        .into_iter()
        .zip(referenced)
        .filter(|(_, r)| !r)
        .map(|(p, _)| p)
        .collect())
}

/// Writes a mesh as OBJ: `v` (with `r g b` when coloured), `vt`, `vn`, and one
/// `o part_N` group per part.
pub fn write(mesh: &TriMesh) -> Vec<u8> {
    use std::fmt::Write;
    let mut s = String::with_capacity(mesh.positions.len() * 40 + mesh.triangles.len() * 30);
    s.push_str("# written by lodstudio\n");
    for (i, p) in mesh.positions.iter().enumerate() {
        match &mesh.colors {
            Some(c) => {
                let c = c[i];
                let _ = writeln!(s, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z);
            }
            None => {
                let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
            }
        }
    }
    for uv in mesh.uvs.iter().flatten() {
        let _ = writeln!(s, "vt {} {}", uv.x, uv.y);
    }
    for n in mesh.normals.iter().flatten() {
        let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
    }
    let corner = |v: u32| {
        let v = v + 1;
        match (mesh.uvs.is_some(), mesh.normals.is_some()) {
            (true, true) => format!("{v}/{v}/{v}"),
            (true, false) => format!("{v}/{v}"),
            (false, true) => format!("{v}//{v}"),
            (false, false) => v.to_string(),
        }
    };
    let mut part = u32::MAX;
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if mesh.parts.is_some() && mesh.part(t) != part {
            part = mesh.part(t);
            let _ = writeln!(s, "o part_{part}");
        }
        let _ = writeln!(
            s,
            "f {} {} {}",
            corner(tri[0]),
            corner(tri[1]),
            corner(tri[2])
        );
    }
    s.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::Location;

    fn parse(s: &str) -> ParseResult<TriMesh> {
        read(s.as_bytes(), &Progress::new())
    }

    #[test]
    fn objects_become_parts_and_polygons_are_triangulated() {
        let m = parse(
            "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n",
        )
        .unwrap();
        assert_eq!(m.triangles.len(), 3);
        assert_eq!(m.part_count(), 2);
        assert_eq!(m.parts.as_ref().unwrap(), &vec![0, 0, 1]);
    }

    #[test]
    fn write_then_read_round_trips() {
        let mut m = crate::builtins::torus(1.0, 0.3, 12, 8);
        m.colors = Some(m.positions.iter().map(|p| p.abs() / 1.3).collect());
        let back = read(&write(&m), &Progress::new()).unwrap();
        // Every corner keeps its attributes bit for bit (shortest round-trip
        // decimals), however the reader numbers the vertices.
        assert_eq!(back.triangles.len(), m.triangles.len());
        let bits3 = |v: glam::Vec3| v.to_array().map(f32::to_bits);
        for (a, b) in m.triangles.iter().zip(&back.triangles) {
            for (&va, &vb) in a.iter().zip(b) {
                let (va, vb) = (va as usize, vb as usize);
                assert_eq!(bits3(m.positions[va]), bits3(back.positions[vb]));
                let (na, nb) = (m.normals.as_ref().unwrap(), back.normals.as_ref().unwrap());
                assert_eq!(bits3(na[va]), bits3(nb[vb]));
                let (ua, ub) = (m.uvs.as_ref().unwrap(), back.uvs.as_ref().unwrap());
                assert_eq!(
                    ua[va].to_array().map(f32::to_bits),
                    ub[vb].to_array().map(f32::to_bits)
                );
                let (ca, cb) = (m.colors.as_ref().unwrap(), back.colors.as_ref().unwrap());
                assert_eq!(bits3(ca[va]), bits3(cb[vb]));
            }
        }
        let (back, _) = crate::geom::repair::repair_mesh(back, &Default::default());
        assert_eq!(back.positions.len(), m.positions.len(), "welded as before");
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap_err();
        assert_eq!(e.at, Location::Line(4));
        let e = parse("v 0 0 0\nv 1 zero 0\n").unwrap_err();
        assert_eq!(e.at, Location::Line(2));
        let e = parse("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err();
        assert_eq!(e.at, Location::Line(3));
        assert!(parse("v 0 0 0\nf 1 -5 1\n").is_err());
    }
}
