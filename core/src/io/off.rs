//! OFF (Geomview Object File Format), ascii: OFF, COFF, NOFF, CNOFF and the ST
//! texture-coordinate prefix.
//!
//! Lines are the unit: a vertex or face is one line, `#` starts a comment
//! anywhere, blank lines are skipped, and a face's trailing tokens (its colour)
//! are ignored.

use glam::{Vec2, Vec3};

use super::text::{Lines, PROGRESS_EVERY, Tokens, parse_f32, parse_int, shown, tick};
use super::{Model, ParseError, ParseResult};
use crate::geom::{PointSet, TriMesh};
use crate::progress::Progress;

/// Per-vertex fields the header keyword's prefixes announce, in file order:
/// x y z, [nx ny nz], [r g b [a]], [s t].
#[derive(Debug, Clone, Copy, Default)]
struct Layout {
    normals: bool,
    colors: bool,
    texcoords: bool,
}

fn layout(keyword: &[u8]) -> Option<Layout> {
    let mut rest = keyword.strip_suffix(b"OFF")?;
    let texcoords = match rest.strip_prefix(b"ST") {
        Some(r) => {
            rest = r;
            true
        }
        None => false,
    };
    let (mut colors, mut normals) = (false, false);
    for &c in rest {
        match c {
            b'C' if !colors => colors = true,
            b'N' if !normals => normals = true,
            _ => return None,
        }
    }
    Some(Layout {
        normals,
        colors,
        texcoords,
    })
}

/// The next line with content, comments removed.
fn content<'a>(lines: &mut Lines<'a>) -> Option<(usize, Tokens<'a>)> {
    for (n, line) in lines.by_ref() {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(i) => &line[..i],
            None => line,
        };
        if line.iter().any(|b| !b.is_ascii_whitespace()) {
            return Some((n, Tokens(line)));
        }
    }
    None
}

fn count(tok: Option<&[u8]>, n: usize, what: &str) -> ParseResult<usize> {
    let tok = tok.ok_or_else(|| ParseError::line(n, format!("expected the {what} count")))?;
    parse_int(tok)
        .and_then(|v| usize::try_from(v).ok())
        .ok_or_else(|| {
            ParseError::line(
                n,
                format!(
                    "expected a non-negative {what} count, found `{}`",
                    shown(tok)
                ),
            )
        })
}

/// Most tokens of a vertex line that can matter: 3 + 3 + 4 + 2.
const VERTEX_TOKENS: usize = 12;

/// Reads an OFF file: a mesh when it has faces, else a point set.
pub fn read(data: &[u8], progress: &Progress) -> ParseResult<Model> {
    let mut lines = Lines::new(data);
    let (n, mut toks) = content(&mut lines)
        .ok_or_else(|| ParseError::file("expected an OFF header, found an empty file"))?;
    let keyword = toks.next().unwrap_or_default();
    // The keyword is optional (the extension said OFF); counts may follow it on its line.
    let (lay, mut head) = match layout(keyword) {
        Some(lay) => (lay, toks.next()),
        None if parse_int(keyword).is_some() => (Layout::default(), Some(keyword)),
        None => {
            return Err(ParseError::line(
                n,
                format!(
                    "expected the keyword OFF, COFF, NOFF, CNOFF or STOFF, found `{}` (4D and nOFF are not supported)",
                    shown(keyword)
                ),
            ));
        }
    };
    if head == Some(b"BINARY") {
        return Err(ParseError::line(
            n,
            "expected an ascii OFF file: binary OFF is not supported",
        ));
    }
    let mut counts_line = n;
    if head.is_none() {
        let (m, t) = content(&mut lines).ok_or_else(|| {
            ParseError::line(
                n,
                "expected the vertex and face counts, found the end of the file",
            )
        })?;
        counts_line = m;
        toks = t;
        head = toks.next();
    }
    let nv = count(head, counts_line, "vertex")?;
    let nf = count(toks.next(), counts_line, "face")?;

    // A vertex line holds at least its values and separators; a face "3 a b c".
    let per_vertex = 3
        + 3 * usize::from(lay.normals)
        + 3 * usize::from(lay.colors)
        + 2 * usize::from(lay.texcoords);
    let remaining = data.len() - lines.pos();
    let need = nv
        .checked_mul(2 * per_vertex)
        .and_then(|v| nf.checked_mul(8).and_then(|f| v.checked_add(f)));
    // +1: the last line may lack its newline.
    if need.is_none_or(|need| need > remaining + 1) {
        return Err(ParseError::line(
            counts_line,
            format!("expected {nv} vertices and {nf} faces, but only {remaining} bytes remain"),
        ));
    }
    if nf > 0 && nv > u32::MAX as usize {
        return Err(ParseError::line(
            counts_line,
            format!("expected at most {} vertices in a mesh", u32::MAX),
        ));
    }

    super::limits::check_items("vertices", nv, 12 * (1 + 2) + 8)
        .and_then(|()| super::limits::check_items("faces", nf, 12))
        .map_err(|e| ParseError::line(counts_line, e.expected))?;
    let mut positions = Vec::with_capacity(nv);
    let mut normals = lay.normals.then(|| Vec::with_capacity(nv));
    let mut colors = lay.colors.then(|| Vec::with_capacity(nv));
    let mut uvs = lay.texcoords.then(|| Vec::with_capacity(nv));
    // Colours are 0..255 integers or 0..1 floats; the whole file decides.
    let (mut fractional, mut above_one) = (false, false);
    for i in 0..nv {
        if i % PROGRESS_EVERY == 0 {
            tick(progress, lines.pos(), data.len())?;
        }
        let (n, toks) = content(&mut lines).ok_or_else(|| {
            ParseError::line(
                lines.line(),
                format!("expected vertex {i} of {nv}, found the end of the file"),
            )
        })?;
        let mut t: [&[u8]; VERTEX_TOKENS] = [&[]; VERTEX_TOKENS];
        let mut k = 0;
        for tok in toks {
            if k < VERTEX_TOKENS {
                t[k] = tok;
            }
            k += 1;
        }
        if k < 3 {
            return Err(ParseError::line(
                n,
                format!("expected 3 coordinates of vertex {i}, found {k} values"),
            ));
        }
        let fixed = per_vertex - 3 * usize::from(lay.colors);
        let ncol = if lay.colors {
            k.saturating_sub(fixed)
        } else {
            0
        };
        if k < fixed || (lay.colors && !(ncol == 3 || ncol == 4)) {
            return Err(ParseError::line(
                n,
                format!(
                    "expected {per_vertex} values (x y z [nx ny nz] [r g b [a]] [s t]) for vertex {i}, found {k}"
                ),
            ));
        }
        let num = |j: usize, what: &str| {
            parse_f32(t[j]).ok_or_else(|| {
                ParseError::line(
                    n,
                    format!(
                        "expected a number for the {what} of vertex {i}, found `{}`",
                        shown(t[j])
                    ),
                )
            })
        };
        let v3 = |j: usize, what: &str| {
            Ok::<_, ParseError>(Vec3::new(
                num(j, what)?,
                num(j + 1, what)?,
                num(j + 2, what)?,
            ))
        };
        positions.push(v3(0, "coordinates")?);
        let mut j = 3;
        if let Some(nr) = normals.as_mut() {
            nr.push(v3(j, "normal")?);
            j += 3;
        }
        if let Some(c) = colors.as_mut() {
            let rgb = v3(j, "colour")?;
            fractional |= t[j..j + 3]
                .iter()
                .any(|tok| tok.iter().any(|b| matches!(b, b'.' | b'e' | b'E')));
            above_one |= rgb.max_element() > 1.0;
            c.push(rgb);
            j += ncol;
        }
        if let Some(uv) = uvs.as_mut() {
            uv.push(Vec2::new(
                num(j, "texture coordinates")?,
                num(j + 1, "texture coordinates")?,
            ));
        }
    }
    if let Some(c) = colors.as_mut().filter(|_| above_one && !fractional) {
        c.iter_mut().for_each(|c| *c /= 255.0);
    }

    let mut triangles = Vec::with_capacity(nf);
    for i in 0..nf {
        if i % PROGRESS_EVERY == 0 {
            tick(progress, lines.pos(), data.len())?;
        }
        let (n, mut toks) = content(&mut lines).ok_or_else(|| {
            ParseError::line(
                lines.line(),
                format!("expected face {i} of {nf}, found the end of the file"),
            )
        })?;
        let first_tok = toks.next().unwrap_or_default();
        let len = parse_int(first_tok).unwrap_or(-1);
        if len < 3 {
            return Err(ParseError::line(
                n,
                format!(
                    "expected a vertex count of 3 or more to start face {i}, found `{}`",
                    shown(first_tok)
                ),
            ));
        }
        let mut index = |j: i64| {
            let tok = toks.next().ok_or_else(|| {
                ParseError::line(
                    n,
                    format!("expected {len} vertex indices in face {i}, found {j}"),
                )
            })?;
            match parse_int(tok) {
                Some(v) if v >= 0 && (v as u64) < nv as u64 => Ok(v as u32),
                _ => Err(ParseError::line(
                    n,
                    format!(
                        "expected vertex indices in 0..{nv} in face {i}, found `{}`",
                        shown(tok)
                    ),
                )),
            }
        };
        let first = index(0)?;
        let mut prev = index(1)?;
        for j in 2..len {
            let cur = index(j)?;
            triangles.push([first, prev, cur]);
            prev = cur;
        }
    }
    progress.set_fraction(1.0);
    Ok(if nf == 0 {
        Model::Points(PointSet {
            positions,
            normals,
            colors,
            radii: None,
        })
    } else {
        Model::Mesh(TriMesh {
            positions,
            triangles,
            normals,
            colors,
            uvs,
            parts: None,
            materials: None,
            wedges: None,
            payload: None,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::Location;

    fn model(src: &str) -> ParseResult<Model> {
        read(src.as_bytes(), &Progress::new())
    }

    fn mesh(src: &str) -> TriMesh {
        match model(src) {
            Ok(Model::Mesh(m)) => m,
            other => panic!("expected a mesh, got {other:?}"),
        }
    }

    fn err(src: &str) -> ParseError {
        match model(src) {
            Err(e) => e,
            Ok(m) => panic!("expected an error, got {m:?}"),
        }
    }

    #[test]
    fn reads_off_with_comments_blank_lines_and_polygons() {
        let m = mesh(
            "# a comment first\n\nOFF # keyword\n# counts next\n5 2 0\n0 0 0\n1 0 0 # trailing\n\n1 1 0\n0 1 0\r\n2 2 2\n4 0 1 2 3 255 0 0\n3 2 3 4\n",
        );
        assert_eq!(m.positions.len(), 5);
        assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [2, 3, 4]]);
        assert!(m.normals.is_none() && m.colors.is_none() && m.uvs.is_none());
        // Counts on the keyword line; no keyword at all; edge count omitted.
        for src in [
            "OFF 3 1 3\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2",
            "3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        ] {
            assert_eq!(mesh(src).triangles, vec![[0, 1, 2]]);
        }
    }

    #[test]
    fn reads_colours_normals_and_texture_coordinates() {
        // Integer colours (0..255), RGB and RGBA mixed.
        let m = mesh("COFF\n3 1 0\n0 0 0 255 0 0\n1 0 0 0 255 0 255\n0 1 0 0 0 51 128\n3 0 1 2\n");
        assert_eq!(
            m.colors.unwrap(),
            vec![Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, 0.2)]
        );
        // Float colours (0..1), even when some are written as integers.
        let m = mesh("COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0.5 0.25 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
        assert_eq!(
            m.colors.unwrap(),
            vec![Vec3::X, Vec3::new(0.5, 0.25, 0.0), Vec3::Z]
        );
        let m = mesh("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 1 0\n3 0 1 2\n");
        assert_eq!(m.normals.unwrap()[2], Vec3::Y);
        for kw in ["CNOFF", "NCOFF"] {
            let src = format!(
                "{kw}\n3 1 0\n0 0 0 0 0 1 255 255 255\n1 0 0 0 0 1 0 0 0\n0 1 0 0 1 0 0 255 0 0\n3 0 1 2\n"
            );
            let m = mesh(&src);
            assert_eq!(m.normals.unwrap()[2], Vec3::Y);
            assert_eq!(m.colors.unwrap(), vec![Vec3::ONE, Vec3::ZERO, Vec3::Y]);
        }
        let m = mesh(
            "STCOFF\n3 1 0\n0 0 0 1 0 0 0.5 0.25\n1 0 0 0 1 0 1 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n",
        );
        assert_eq!(m.uvs.unwrap(), vec![Vec2::new(0.5, 0.25), Vec2::X, Vec2::Y]);
    }

    #[test]
    fn no_faces_gives_points() {
        match model("NOFF\n2 0 0\n0 0 0 0 0 1\n1 2 3 1 0 0\n").unwrap() {
            Model::Points(p) => {
                assert_eq!(p.positions[1], Vec3::new(1.0, 2.0, 3.0));
                assert_eq!(p.normals.unwrap()[1], Vec3::X);
            }
            m => panic!("expected points, got {m:?}"),
        }
    }

    #[test]
    fn malformed_files_are_errors_at_their_line() {
        let cases: &[(&str, usize, &str)] = &[
            ("OFF\n", 1, "counts"),
            ("4OFF\n1 0 0\n0 0 0 0\n", 1, "keyword"),
            ("OFF BINARY\n", 1, "binary"),
            ("OFF\n-1 0 0\n", 2, "non-negative vertex"),
            ("OFF\n3 x 0\n", 2, "face count"),
            (
                "OFF\n1000000000000 1000000000000 0\n0 0 0\n",
                2,
                "1000000000000 vertices",
            ),
            ("OFF\n9223372036854775807 1 0\n0 0 0\n", 2, "remain"),
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n", 5, "vertex 2 of 3"),
            (
                "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n",
                4,
                "expected 3 coordinates of vertex 1",
            ),
            ("OFF\n3 1 0\n0 0 0\n1 y 0\n0 1 0\n3 0 1 2\n", 4, "found `y`"),
            (
                "NOFF\n3 1 0\n0 0 0 0 0\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n",
                3,
                "vertex 0",
            ),
            (
                "COFF\n3 1 0\n0 0 0 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n",
                3,
                "vertex 0",
            ),
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n", 6, "face 0 of 1"),
            (
                "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
                6,
                "in 0..3 in face 0, found `3`",
            ),
            (
                "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
                6,
                "found `-1`",
            ),
            (
                "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n",
                6,
                "3 vertex indices",
            ),
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", 6, "3 or more"),
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\nq 0 1 2\n", 6, "found `q`"),
        ];
        for (src, line, what) in cases {
            // Padding, so that only the huge counts fail the up-front size check.
            let e = err(&format!("{src}# padding comment\n"));
            assert_eq!(e.at, Location::Line(*line), "{src:?}: {e:?}");
            assert!(e.expected.contains(what), "{src:?}: {}", e.expected);
        }
        assert_eq!(err("").at, Location::File);
        assert_eq!(err("# only a comment\n\n").at, Location::File);
    }

    #[test]
    fn no_prefix_or_corruption_panics() {
        let data = b"CNOFF 4 2 0\n0 0 0 0 0 1 1 0 0\n1 0 0 0 0 1 0 1 0 1\n1 1 0 0 0 1 0 0 1\n0 1 0 0 0 1 1 1 1\n4 0 1 2 3\n3 0 2 3 1 1 1\n";
        for n in 0..data.len() {
            let _ = read(&data[..n], &Progress::new());
        }
        for i in 0..data.len() {
            let mut d = data.to_vec();
            d[i] ^= 0x21;
            let _ = read(&d, &Progress::new());
        }
    }

    fn shared(name: &str) -> TriMesh {
        let path = format!("{}/../../shared/models/{name}", env!("CARGO_MANIFEST_DIR"));
        let data = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        match read(&data, &Progress::new()).unwrap() {
            Model::Mesh(m) => m,
            _ => panic!("{name}: expected a mesh"),
        }
    }

    #[test]
    fn reads_the_cgal_off_files() {
        for (name, v, f) in [
            ("couplingdown.off", 1_841, 3_714),
            ("knot2.off", 5_760, 11_520),
            ("bones.off", 2_154, 4_204),
        ] {
            let m = shared(name);
            assert_eq!((m.positions.len(), m.triangles.len()), (v, f), "{name}");
        }
    }
}
