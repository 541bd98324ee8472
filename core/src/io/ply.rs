//! PLY: a reader for ascii and binary (both endiannesses) files, and writers for
//! meshes and point sets.
//!
//! Any element/property layout is accepted: `vertex` and `face` are decoded and
//! everything else (ball.ply's `segment_index`, `edge` elements, ...) is skipped
//! in every encoding. Header counts are checked against the bytes that remain
//! before anything is reserved, so a lying header is an error, not an OOM.
//!
//! The line and token helpers here are shared with the other text readers.

use std::io::{BufRead as _, Read as _, Write as _};

use glam::Vec3;

use super::text::{Lines, PROGRESS_EVERY, Tokens, parse_f32, parse_f64, parse_int, shown, tick};
use super::volume::ScalarType;
use super::{Location, Model, ParseError, ParseResult};
use crate::geom::{PointSet, TriMesh};
use crate::progress::Progress;

/// Body encoding of a PLY file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

impl Encoding {
    fn header_name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLittleEndian => "binary_little_endian",
            Encoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

// ---------------------------------------------------------------------------
// Header
// ---------------------------------------------------------------------------

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Scalar(ScalarType),
    List { count: ScalarType, item: ScalarType },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
    /// Header line that declared it, for errors about its layout.
    line: usize,
}

struct Header<'a> {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Positioned at the first line (byte) of the body.
    body: Lines<'a>,
}

fn scalar_type(name: &str, line: usize) -> ParseResult<ScalarType> {
    ScalarType::parse(name).ok_or_else(|| {
        ParseError::line(
            line,
            format!("expected a property type (char, uchar, short, ushort, int, uint, float, double, int8 .. float64), found `{name}`"),
        )
    })
}

fn parse_header(data: &[u8]) -> ParseResult<Header<'_>> {
    let mut lines = Lines::new(data);
    match lines.next() {
        Some((_, l)) if l.trim_ascii_end() == b"ply" => {}
        _ => return Err(ParseError::line(1, "expected `ply` on the first line")),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some((n, raw)) = lines.next() else {
            return Err(ParseError::line(
                lines.line(),
                "expected `end_header`, found the end of the file",
            ));
        };
        let text = std::str::from_utf8(raw)
            .map_err(|_| ParseError::line(n, "expected a text header line"))?;
        let mut words = text.split_ascii_whitespace();
        match words.next() {
            None | Some("comment" | "obj_info") => {}
            Some("format") => {
                let enc = match words.next() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::BinaryLittleEndian,
                    Some("binary_big_endian") => Encoding::BinaryBigEndian,
                    _ => {
                        return Err(ParseError::line(
                            n,
                            "expected `format ascii|binary_little_endian|binary_big_endian 1.0`",
                        ));
                    }
                };
                if encoding.replace(enc).is_some() {
                    return Err(ParseError::line(n, "expected a single format line"));
                }
            }
            Some("element") => {
                let (Some(name), Some(count), None) = (words.next(), words.next(), words.next())
                else {
                    return Err(ParseError::line(n, "expected `element NAME COUNT`"));
                };
                let count = count.parse().map_err(|_| {
                    ParseError::line(
                        n,
                        format!("expected a non-negative element count, found `{count}`"),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                    line: n,
                });
            }
            Some("property") => {
                let Some(elem) = elements.last_mut() else {
                    return Err(ParseError::line(
                        n,
                        "expected an element line before the first property",
                    ));
                };
                let (kind, name) = match words.next() {
                    Some("list") => {
                        let (Some(c), Some(i), Some(name)) =
                            (words.next(), words.next(), words.next())
                        else {
                            return Err(ParseError::line(
                                n,
                                "expected `property list COUNT_TYPE ITEM_TYPE NAME`",
                            ));
                        };
                        let count = scalar_type(c, n)?;
                        let item = scalar_type(i, n)?;
                        (Kind::List { count, item }, name)
                    }
                    Some(t) => {
                        let Some(name) = words.next() else {
                            return Err(ParseError::line(n, "expected `property TYPE NAME`"));
                        };
                        (Kind::Scalar(scalar_type(t, n)?), name)
                    }
                    None => return Err(ParseError::line(n, "expected `property TYPE NAME`")),
                };
                if words.next().is_some() {
                    return Err(ParseError::line(
                        n,
                        "expected the property line to end after its name",
                    ));
                }
                elem.props.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            Some("end_header") => break,
            Some(other) => {
                return Err(ParseError::line(
                    n,
                    format!(
                        "expected comment, obj_info, format, element, property or end_header, found `{other}`"
                    ),
                ));
            }
        }
    }
    let encoding = encoding.ok_or_else(|| {
        ParseError::line(lines.line(), "expected a format line before end_header")
    })?;
    Ok(Header {
        encoding,
        elements,
        body: lines,
    })
}

// ---------------------------------------------------------------------------
// Element plans
// ---------------------------------------------------------------------------

const X: usize = 0;
const NX: usize = 3;
const RED: usize = 6;
const RADIUS: usize = 9;
/// Vertex fields decoded: x y z, nx ny nz, red green blue, radius.
const FIELDS: usize = 10;

fn field(name: &str) -> Option<usize> {
    Some(match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        "nx" => 3,
        "ny" => 4,
        "nz" => 5,
        "red" | "diffuse_red" => 6,
        "green" | "diffuse_green" => 7,
        "blue" | "diffuse_blue" => 8,
        "radius" => 9,
        _ => return None,
    })
}

/// What the reader does with one property.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Use {
    Field(usize),
    Indices,
    Skip,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    Vertex,
    Face,
    Other,
}

/// How the vertex element maps to fields, and the divisor that brings each
/// colour channel to 0..1 (integer channels are 0..type max, floats 0..1).
struct VertexPlan {
    present: [bool; FIELDS],
    divisor: [f64; FIELDS],
}

impl VertexPlan {
    fn has(&self, first: usize, n: usize) -> bool {
        self.present[first..first + n].iter().all(|p| *p)
    }
}

fn colour_max(t: ScalarType) -> f64 {
    match t {
        ScalarType::U16 | ScalarType::I16 => 65535.0,
        ScalarType::F32 | ScalarType::F64 => 1.0,
        _ => 255.0,
    }
}

struct Plan {
    roles: Vec<Role>,
    uses: Vec<Vec<Use>>,
    vertex: VertexPlan,
    vertex_count: usize,
    face_count: Option<usize>,
}

fn plan(elements: &[Element]) -> ParseResult<Plan> {
    let mut vertex = VertexPlan {
        present: [false; FIELDS],
        divisor: [1.0; FIELDS],
    };
    let mut vertex_count = None;
    let mut face_count = None;
    let mut roles = Vec::with_capacity(elements.len());
    let mut uses = Vec::with_capacity(elements.len());
    for e in elements {
        let once = |seen: Option<usize>| match seen {
            Some(_) => Err(ParseError::line(
                e.line,
                format!("expected a single {} element", e.name),
            )),
            None => Ok(Some(e.count)),
        };
        let (role, u) = match e.name.as_str() {
            "vertex" => {
                vertex_count = once(vertex_count)?;
                let u: Vec<Use> = e
                    .props
                    .iter()
                    .map(|p| match (p.kind, field(&p.name)) {
                        (Kind::Scalar(t), Some(f)) => {
                            vertex.present[f] = true;
                            if (RED..RED + 3).contains(&f) {
                                vertex.divisor[f] = colour_max(t);
                            }
                            Use::Field(f)
                        }
                        _ => Use::Skip,
                    })
                    .collect();
                if !vertex.has(X, 3) {
                    return Err(ParseError::line(
                        e.line,
                        "expected scalar properties x, y and z in element vertex",
                    ));
                }
                (Role::Vertex, u)
            }
            "face" => {
                face_count = once(face_count)?;
                let mut found = false;
                let u: Vec<Use> = e
                    .props
                    .iter()
                    .map(|p| match (p.kind, p.name.as_str()) {
                        (Kind::List { .. }, "vertex_indices" | "vertex_index") if !found => {
                            found = true;
                            Use::Indices
                        }
                        _ => Use::Skip,
                    })
                    .collect();
                if !found {
                    return Err(ParseError::line(
                        e.line,
                        "expected a list property vertex_indices in element face",
                    ));
                }
                (Role::Face, u)
            }
            _ => (Role::Other, vec![Use::Skip; e.props.len()]),
        };
        roles.push(role);
        uses.push(u);
    }
    Ok(Plan {
        roles,
        uses,
        vertex,
        vertex_count: vertex_count.unwrap_or(0),
        face_count,
    })
}

// ---------------------------------------------------------------------------
// Body sources
// ---------------------------------------------------------------------------

/// Most corners of one face.
const MAX_FACE_CORNERS: usize = 1 << 24;

/// Why a value could not be read.
enum Miss {
    End,
    Bad(&'static str, String),
    Extra(String),
}

/// One body encoding: values are read one at a time as f64 (exact for every
/// PLY scalar type), so the element logic is written once.
trait Source {
    /// What the data runs out at, for messages.
    const END: &'static str;
    /// Moves to the next element instance; false at the end of the data.
    fn begin(&mut self) -> bool;
    fn value(&mut self, t: ScalarType) -> Result<f64, Miss>;
    fn skip(&mut self, t: ScalarType) -> Result<(), Miss>;
    /// Ends an instance (ascii: nothing may remain on its line).
    fn finish(&mut self) -> Result<(), Miss>;
    /// Fewest bytes one property can take; `face_list` lists hold at least 3 items.
    fn min_bytes(&self, kind: Kind, face_list: bool) -> usize;
    fn pos(&self) -> usize;
    fn total(&self) -> usize;
    /// Where an instance that started at byte `start` is, for messages.
    fn location(&self, start: usize) -> Location;
}

struct Text<'a> {
    lines: Lines<'a>,
    toks: Tokens<'a>,
}

impl Source for Text<'_> {
    const END: &'static str = "the end of the line";

    fn begin(&mut self) -> bool {
        for (_, line) in self.lines.by_ref() {
            if line.iter().any(|b| !b.is_ascii_whitespace()) {
                self.toks = Tokens(line);
                return true;
            }
        }
        false
    }

    fn value(&mut self, t: ScalarType) -> Result<f64, Miss> {
        let tok = self.toks.next().ok_or(Miss::End)?;
        let v = match t {
            ScalarType::F32 => parse_f32(tok).map(f64::from),
            ScalarType::F64 => parse_f64(tok),
            _ => parse_int(tok).map(|v| v as f64),
        };
        v.ok_or_else(|| {
            let what = if t.is_float() {
                "a number"
            } else {
                "an integer"
            };
            Miss::Bad(what, shown(tok))
        })
    }

    fn skip(&mut self, _: ScalarType) -> Result<(), Miss> {
        self.toks.next().map(|_| ()).ok_or(Miss::End)
    }

    fn finish(&mut self) -> Result<(), Miss> {
        match self.toks.next() {
            Some(tok) => Err(Miss::Extra(shown(tok))),
            None => Ok(()),
        }
    }

    fn min_bytes(&self, kind: Kind, face_list: bool) -> usize {
        // A token and its separator; a face list holds a count and 3 indices.
        match kind {
            Kind::List { .. } if face_list => 8,
            _ => 2,
        }
    }

    fn pos(&self) -> usize {
        self.lines.pos()
    }

    fn total(&self) -> usize {
        self.lines.len()
    }

    fn location(&self, _: usize) -> Location {
        Location::Line(self.lines.line())
    }
}

struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl Binary<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], Miss> {
        let b = self.data.get(self.pos..self.pos + n).ok_or(Miss::End)?;
        self.pos += n;
        Ok(b)
    }
}

impl Source for Binary<'_> {
    const END: &'static str = "the end of the data";

    fn begin(&mut self) -> bool {
        true
    }

    fn value(&mut self, t: ScalarType) -> Result<f64, Miss> {
        let big_endian = self.big_endian;
        self.take(t.size()).map(|b| t.decode(b, big_endian))
    }

    fn skip(&mut self, t: ScalarType) -> Result<(), Miss> {
        self.take(t.size()).map(|_| ())
    }

    fn finish(&mut self) -> Result<(), Miss> {
        Ok(())
    }

    fn min_bytes(&self, kind: Kind, face_list: bool) -> usize {
        match kind {
            Kind::Scalar(t) => t.size(),
            Kind::List { count, item } if face_list => count.size() + 3 * item.size(),
            Kind::List { count, .. } => count.size(),
        }
    }

    fn pos(&self) -> usize {
        self.pos
    }

    fn total(&self) -> usize {
        self.data.len()
    }

    fn location(&self, start: usize) -> Location {
        Location::Byte(start as u64)
    }
}

/// A binary body read from a stream.
struct StreamBinary<R> {
    reader: R,
    pos: usize,
    total: usize,
    big_endian: bool,
    /// A read that failed other than at the end (corrupt gzip, a disk).
    failed: Option<std::io::Error>,
}

impl<R: std::io::Read> Source for StreamBinary<R> {
    const END: &'static str = "the end of the data";

    fn begin(&mut self) -> bool {
        true
    }

    fn value(&mut self, t: ScalarType) -> Result<f64, Miss> {
        let mut b = [0u8; 8];
        let b = &mut b[..t.size()];
        self.reader.read_exact(b).map_err(|e| {
            if e.kind() != std::io::ErrorKind::UnexpectedEof {
                self.failed.get_or_insert(e);
            }
            Miss::End
        })?;
        self.pos += b.len();
        Ok(t.decode(b, self.big_endian))
    }

    fn skip(&mut self, t: ScalarType) -> Result<(), Miss> {
        self.value(t).map(|_| ())
    }

    fn finish(&mut self) -> Result<(), Miss> {
        Ok(())
    }

    fn min_bytes(&self, _: Kind, _: bool) -> usize {
        // The stream's length is not known up front: a count it cannot hold
        // runs into its end, one element at a time.
        0
    }

    fn pos(&self) -> usize {
        self.pos
    }

    fn total(&self) -> usize {
        self.total
    }

    fn location(&self, start: usize) -> Location {
        Location::Byte(start as u64)
    }
}

/// An ascii body read from a stream, a line at a time.
struct StreamText<R> {
    reader: R,
    line: Vec<u8>,
    /// Where the next token of `line` starts.
    at: usize,
    number: usize,
    pos: usize,
    total: usize,
    failed: Option<std::io::Error>,
}

impl<R: std::io::BufRead> StreamText<R> {
    fn token<T>(&mut self, parse: impl Fn(&[u8]) -> T) -> Option<T> {
        let mut toks = Tokens(&self.line[self.at..]);
        let value = parse(toks.next()?);
        self.at = self.line.len() - toks.0.len();
        Some(value)
    }
}

impl<R: std::io::BufRead> Source for StreamText<R> {
    const END: &'static str = "the end of the line";

    fn begin(&mut self) -> bool {
        loop {
            self.line.clear();
            match self.reader.read_until(b'\n', &mut self.line) {
                Ok(0) => return false,
                Err(e) => {
                    self.failed.get_or_insert(e);
                    return false;
                }
                Ok(n) => {
                    self.pos += n;
                    self.number += 1;
                    self.at = 0;
                    if self.line.iter().any(|b| !b.is_ascii_whitespace()) {
                        return true;
                    }
                }
            }
        }
    }

    fn value(&mut self, t: ScalarType) -> Result<f64, Miss> {
        let parsed = self
            .token(|tok| {
                let v = match t {
                    ScalarType::F32 => parse_f32(tok).map(f64::from),
                    ScalarType::F64 => parse_f64(tok),
                    _ => parse_int(tok).map(|v| v as f64),
                };
                v.ok_or_else(|| shown(tok))
            })
            .ok_or(Miss::End)?;
        parsed.map_err(|tok| {
            let what = if t.is_float() {
                "a number"
            } else {
                "an integer"
            };
            Miss::Bad(what, tok)
        })
    }

    fn skip(&mut self, _: ScalarType) -> Result<(), Miss> {
        self.token(|_| ()).ok_or(Miss::End)
    }

    fn finish(&mut self) -> Result<(), Miss> {
        match self.token(shown) {
            Some(tok) => Err(Miss::Extra(tok)),
            None => Ok(()),
        }
    }

    fn min_bytes(&self, _: Kind, _: bool) -> usize {
        0
    }

    fn pos(&self) -> usize {
        self.pos
    }

    fn total(&self) -> usize {
        self.total
    }

    fn location(&self, _: usize) -> Location {
        Location::Line(self.number)
    }
}

/// A PLY mesh read as a stream of `total` bytes (for progress; any when not
/// known), out of core: its vertices are returned (positions, and normals
/// or colours where it has them), its faces handed to `sink` one polygon's
/// triangles at a time, in file order, each index checked against the
/// vertex count. The vertex element must come before the faces.
pub fn stream_mesh(
    mut reader: impl std::io::BufRead,
    total: usize,
    progress: &Progress,
    sink: FaceSink<'_>,
) -> ParseResult<TriMesh> {
    // The header: lines up to `end_header`, at most 64 KiB of them.
    let mut head = Vec::new();
    loop {
        let before = head.len();
        let n = (&mut reader)
            .take(65_536 - head.len() as u64)
            .read_until(b'\n', &mut head)
            .map_err(|e| ParseError::line(0, format!("cannot read: {e}")))?;
        let line = head[before..].trim_ascii();
        if line.split(|b| b.is_ascii_whitespace()).next() == Some(b"end_header") {
            break;
        }
        if n == 0 || head.len() >= 65_536 {
            return Err(ParseError::line(
                0,
                "expected `end_header` within the first 64 KiB",
            ));
        }
    }
    let header = parse_header(&head)?;
    let plan = plan(&header.elements)?;
    let first = |role: Role| plan.roles.iter().position(|r| *r == role);
    if first(Role::Face).is_none() {
        return Err(ParseError::line(0, "expected a face element (a mesh)"));
    }
    if first(Role::Face) < first(Role::Vertex) {
        return Err(ParseError::line(
            0,
            "faces come before the vertices: this PLY cannot be read as a stream",
        ));
    }
    // A read that failed is said as such, not as the data ending there.
    let failed =
        |e: Option<std::io::Error>| e.map(|e| ParseError::line(0, format!("cannot read: {e}")));
    let model = match header.encoding {
        Encoding::Ascii => {
            let mut src = StreamText {
                reader,
                line: Vec::new(),
                at: 0,
                number: header.body.line(),
                pos: head.len(),
                total,
                failed: None,
            };
            let read = read_body(&mut src, &header.elements, &plan, progress, Some(sink));
            read.map_err(|e| failed(src.failed.take()).unwrap_or(e))
        }
        enc => {
            let mut src = StreamBinary {
                reader,
                pos: head.len(),
                total,
                big_endian: enc == Encoding::BinaryBigEndian,
                failed: None,
            };
            let read = read_body(&mut src, &header.elements, &plan, progress, Some(sink));
            read.map_err(|e| failed(src.failed.take()).unwrap_or(e))
        }
    }?;
    match model {
        Model::Mesh(m) => Ok(m),
        _ => Err(ParseError::line(0, "expected a mesh")),
    }
}

// ---------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------

/// Reads a PLY file: a mesh when it has faces, else a point set.
pub fn read(data: &[u8], progress: &Progress) -> ParseResult<Model> {
    let header = parse_header(data)?;
    let plan = plan(&header.elements)?;
    match header.encoding {
        Encoding::Ascii => {
            let mut src = Text {
                lines: header.body,
                toks: Tokens::default(),
            };
            read_body(&mut src, &header.elements, &plan, progress, None)
        }
        enc => {
            let mut src = Binary {
                data,
                pos: header.body.pos(),
                big_endian: enc == Encoding::BinaryBigEndian,
            };
            read_body(&mut src, &header.elements, &plan, progress, None)
        }
    }
}

/// Where a streamed body's triangles go, one face's at a time.
type FaceSink<'s> = &'s mut dyn FnMut(&[[u32; 3]]) -> Result<(), String>;

/// Reads a body; with `sink`, faces go there instead of into the mesh
/// (which then holds the vertices alone).
fn read_body<S: Source>(
    src: &mut S,
    elements: &[Element],
    plan: &Plan,
    progress: &Progress,
    mut sink: Option<FaceSink<'_>>,
) -> ParseResult<Model> {
    let vp = &plan.vertex;
    let mut positions = Vec::new();
    let mut normals = None;
    let mut colors = None;
    let mut radii = None;
    let mut triangles = Vec::new();
    for ((elem, role), uses) in elements.iter().zip(&plan.roles).zip(&plan.uses) {
        check_room(src, elem, uses)?;
        match role {
            Role::Vertex => {
                let n = elem.count;
                // Position, normal, colour (12 bytes each) and radius.
                super::limits::check_items("vertices", n, 40)
                    .map_err(|e| ParseError::line(elem.line, e.expected))?;
                positions.reserve_exact(n);
                normals = vp.has(NX, 3).then(|| Vec::with_capacity(n));
                colors = vp.has(RED, 3).then(|| Vec::with_capacity(n));
                radii = vp.present[RADIUS].then(|| Vec::with_capacity(n));
                let d = vp.divisor;
                read_element(src, elem, uses, progress, |_, f, _| {
                    let v3 = |i: usize| Vec3::new(f[i] as f32, f[i + 1] as f32, f[i + 2] as f32);
                    positions.push(v3(X));
                    if let Some(n) = normals.as_mut() {
                        n.push(v3(NX));
                    }
                    if let Some(c) = colors.as_mut() {
                        c.push(Vec3::new(
                            (f[RED] / d[RED]) as f32,
                            (f[RED + 1] / d[RED + 1]) as f32,
                            (f[RED + 2] / d[RED + 2]) as f32,
                        ));
                    }
                    if let Some(r) = radii.as_mut() {
                        r.push(f[RADIUS] as f32);
                    }
                    Ok(())
                })?;
            }
            Role::Face => {
                if elem.count > 0 && plan.vertex_count > u32::MAX as usize {
                    return Err(ParseError::line(
                        elem.line,
                        format!("expected at most {} vertices in a mesh", u32::MAX),
                    ));
                }
                if let Some(sink) = sink.as_mut() {
                    let mut one = Vec::with_capacity(8);
                    read_element(src, elem, uses, progress, |i, _, list| {
                        one.clear();
                        triangulate(i, list, plan.vertex_count, &mut one)?;
                        sink(&one)
                    })?;
                    continue;
                }
                super::limits::check_items("faces", elem.count, 12)
                    .map_err(|e| ParseError::line(elem.line, e.expected))?;
                triangles.reserve(elem.count);
                read_element(src, elem, uses, progress, |i, _, list| {
                    triangulate(i, list, plan.vertex_count, &mut triangles)
                })?;
            }
            Role::Other => read_element(src, elem, uses, progress, |_, _, _| Ok(()))?,
        }
    }
    progress.set_fraction(1.0);
    if plan.face_count.unwrap_or(0) == 0 && sink.is_none() {
        Ok(Model::Points(PointSet {
            positions,
            normals,
            colors,
            radii,
        }))
    } else {
        Ok(Model::Mesh(TriMesh {
            positions,
            triangles,
            normals,
            colors,
            ..TriMesh::default()
        }))
    }
}

/// Refuses a count the remaining bytes cannot hold, before anything is reserved.
fn check_room<S: Source>(src: &S, elem: &Element, uses: &[Use]) -> ParseResult<()> {
    let min: usize = elem
        .props
        .iter()
        .zip(uses)
        .map(|(p, u)| src.min_bytes(p.kind, *u == Use::Indices))
        .sum();
    let remaining = src.total() - src.pos();
    // +1: the last ascii line may lack its newline.
    if elem
        .count
        .checked_mul(min)
        .is_none_or(|need| need > remaining + 1)
    {
        return Err(ParseError::new(
            src.location(src.pos()),
            format!(
                "expected {} {} elements of at least {min} bytes each, but only {remaining} bytes remain",
                elem.count, elem.name
            ),
        ));
    }
    Ok(())
}

/// Reads every instance of `elem`, handing each one's fields and kept list to `sink`.
fn read_element<S: Source>(
    src: &mut S,
    elem: &Element,
    uses: &[Use],
    progress: &Progress,
    mut sink: impl FnMut(usize, &[f64; FIELDS], &[f64]) -> Result<(), String>,
) -> ParseResult<()> {
    if elem.props.is_empty() {
        return Ok(());
    }
    let mut fields = [0.0; FIELDS];
    let mut list = Vec::new();
    for i in 0..elem.count {
        if i % PROGRESS_EVERY == 0 {
            tick(progress, src.pos(), src.total())?;
        }
        let start = src.pos();
        if !src.begin() {
            return Err(ParseError::new(
                src.location(start),
                format!(
                    "expected {} {i} of {}, found the end of the file",
                    elem.name, elem.count
                ),
            ));
        }
        for (p, u) in elem.props.iter().zip(uses) {
            let got = match (p.kind, *u) {
                (Kind::Scalar(t), Use::Field(f)) => src.value(t).map(|v| fields[f] = v),
                (Kind::Scalar(t), _) => src.skip(t),
                (Kind::List { count, item }, u) => {
                    read_list(src, count, item, u == Use::Indices, &mut list)
                }
            };
            got.map_err(|m| miss(src, m, &p.name, elem, i))?;
        }
        src.finish().map_err(|m| miss(src, m, "", elem, i))?;
        sink(i, &fields, &list).map_err(|msg| ParseError::new(src.location(start), msg))?;
    }
    Ok(())
}

fn read_list<S: Source>(
    src: &mut S,
    count: ScalarType,
    item: ScalarType,
    keep: bool,
    out: &mut Vec<f64>,
) -> Result<(), Miss> {
    let n = src.value(count)?;
    if !(n >= 0.0 && n.fract() == 0.0) {
        return Err(Miss::Bad("a list length", n.to_string()));
    }
    // A kept list is held whole (8 bytes an item, its fan 12 a triangle):
    // no real polygon comes near this many corners.
    if keep && n > MAX_FACE_CORNERS as f64 {
        return Err(Miss::Bad("a face of at most 2^24 corners", n.to_string()));
    }
    if keep {
        out.clear();
    }
    // Each item consumes input or fails, so a huge length cannot spin for long.
    for _ in 0..n as u64 {
        if keep {
            out.push(src.value(item)?);
        } else {
            src.skip(item)?;
        }
    }
    Ok(())
}

fn miss<S: Source>(src: &S, m: Miss, prop: &str, elem: &Element, i: usize) -> ParseError {
    let e = &elem.name;
    let msg = match m {
        Miss::End => format!("expected property `{prop}` of {e} {i}, found {}", S::END),
        Miss::Bad(what, tok) => {
            format!("expected {what} for property `{prop}` of {e} {i}, found `{tok}`")
        }
        Miss::Extra(tok) => format!("expected the line of {e} {i} to end, found `{tok}`"),
    };
    ParseError::new(src.location(src.pos()), msg)
}

/// Fans a polygon into triangles after checking its indices.
fn triangulate(
    face: usize,
    list: &[f64],
    nv: usize,
    out: &mut Vec<[u32; 3]>,
) -> Result<(), String> {
    if list.len() < 3 {
        return Err(format!(
            "expected at least 3 vertex indices in face {face}, found {}",
            list.len()
        ));
    }
    let index = |v: f64| {
        if v >= 0.0 && v.fract() == 0.0 && (v as usize) < nv {
            Ok(v as u32)
        } else {
            Err(format!(
                "expected vertex indices in 0..{nv} in face {face}, found {v}"
            ))
        }
    };
    let first = index(list[0])?;
    let mut prev = index(list[1])?;
    for &v in &list[2..] {
        let cur = index(v)?;
        out.push([first, prev, cur]);
        prev = cur;
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------

/// Values in the chosen encoding; ascii rows are space-separated lines.
struct Writer {
    out: Vec<u8>,
    enc: Encoding,
    row_start: bool,
}

impl Writer {
    fn new(enc: Encoding, header: String) -> Self {
        Self {
            out: header.into_bytes(),
            enc,
            row_start: true,
        }
    }

    fn sep(&mut self) {
        if !self.row_start {
            self.out.push(b' ');
        }
        self.row_start = false;
    }

    /// One scalar: its Display text in ascii (the shortest text that reads back to
    /// the same value), else its bytes in the file's byte order.
    fn scalar<const N: usize>(&mut self, v: impl std::fmt::Display, le: [u8; N], be: [u8; N]) {
        match self.enc {
            Encoding::Ascii => {
                self.sep();
                let _ = write!(self.out, "{v}");
            }
            Encoding::BinaryLittleEndian => self.out.extend_from_slice(&le),
            Encoding::BinaryBigEndian => self.out.extend_from_slice(&be),
        }
    }

    fn f32(&mut self, v: f32) {
        self.scalar(v, v.to_le_bytes(), v.to_be_bytes());
    }

    fn vec3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }

    fn u8(&mut self, v: u8) {
        self.scalar(v, [v], [v]);
    }

    fn color(&mut self, c: Vec3) {
        for v in c.to_array() {
            self.u8((v.clamp(0.0, 1.0) * 255.0).round() as u8);
        }
    }

    fn u32(&mut self, v: u32) {
        self.scalar(v, v.to_le_bytes(), v.to_be_bytes());
    }

    fn end_row(&mut self) {
        if self.enc == Encoding::Ascii {
            self.out.push(b'\n');
        }
        self.row_start = true;
    }
}

fn header(enc: Encoding, vertices: usize, props: &[&str], faces: Option<(usize, &str)>) -> String {
    use std::fmt::Write as _;
    let mut h = format!(
        "ply\nformat {} 1.0\ncomment written by lodstudio\nelement vertex {vertices}\n",
        enc.header_name()
    );
    for p in props {
        let _ = writeln!(h, "property {p}");
    }
    if let Some((n, index)) = faces {
        let _ = writeln!(
            h,
            "element face {n}\nproperty list uchar {index} vertex_indices"
        );
    }
    h.push_str("end_header\n");
    h
}

/// An attribute array only when it matches the vertex count.
fn attr<T>(a: &Option<Vec<T>>, n: usize) -> Option<&[T]> {
    a.as_deref().filter(|a| a.len() == n)
}

/// Writes x y z as float, nx ny nz and red green blue (uchar) when present, and
/// faces as `list uchar int vertex_indices`.
pub fn write_mesh(mesh: &TriMesh, enc: Encoding) -> Vec<u8> {
    let n = mesh.positions.len();
    let normals = attr(&mesh.normals, n);
    let colors = attr(&mesh.colors, n);
    let mut props = vec!["float x", "float y", "float z"];
    if normals.is_some() {
        props.extend(["float nx", "float ny", "float nz"]);
    }
    if colors.is_some() {
        props.extend(["uchar red", "uchar green", "uchar blue"]);
    }
    // `int` is what every reader expects; only indices past i32 need `uint`.
    let index = if n > i32::MAX as usize { "uint" } else { "int" };
    let head = header(enc, n, &props, Some((mesh.triangles.len(), index)));
    let mut w = Writer::new(enc, head);
    for (i, p) in mesh.positions.iter().enumerate() {
        w.vec3(*p);
        if let Some(nr) = normals {
            w.vec3(nr[i]);
        }
        if let Some(c) = colors {
            w.color(c[i]);
        }
        w.end_row();
    }
    for t in &mesh.triangles {
        w.u8(3);
        for v in t {
            w.u32(*v);
        }
        w.end_row();
    }
    w.out
}

/// Writes the `.points.ply` contract: `x y z radius` (radius 0 when absent),
/// `nx ny nz` when present, and `red green blue` as uchar (white when absent).
pub fn write_points(points: &PointSet, enc: Encoding) -> Vec<u8> {
    let n = points.positions.len();
    let normals = attr(&points.normals, n);
    let colors = attr(&points.colors, n);
    let radii = attr(&points.radii, n);
    let mut props = vec!["float x", "float y", "float z", "float radius"];
    if normals.is_some() {
        props.extend(["float nx", "float ny", "float nz"]);
    }
    props.extend(["uchar red", "uchar green", "uchar blue"]);
    let mut w = Writer::new(enc, header(enc, n, &props, None));
    for (i, p) in points.positions.iter().enumerate() {
        w.vec3(*p);
        w.f32(radii.map_or(0.0, |r| r[i]));
        if let Some(nr) = normals {
            w.vec3(nr[i]);
        }
        w.color(colors.map_or(Vec3::ONE, |c| c[i]));
        w.end_row();
    }
    w.out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(data: &[u8]) -> ParseResult<Model> {
        read(data, &Progress::new())
    }

    fn mesh(data: &[u8]) -> TriMesh {
        match model(data) {
            Ok(Model::Mesh(m)) => m,
            other => panic!("expected a mesh, got {other:?}"),
        }
    }

    fn points(data: &[u8]) -> PointSet {
        match model(data) {
            Ok(Model::Points(p)) => p,
            other => panic!("expected points, got {other:?}"),
        }
    }

    fn encode_value(out: &mut Vec<u8>, t: ScalarType, tok: &[u8], big_endian: bool) {
        let v = parse_f64(tok).unwrap();
        macro_rules! put {
            ($ty:ty) => {{
                let x = v as $ty;
                out.extend_from_slice(&if big_endian {
                    x.to_be_bytes()
                } else {
                    x.to_le_bytes()
                });
            }};
        }
        match t {
            ScalarType::U8 => put!(u8),
            ScalarType::I8 => put!(i8),
            ScalarType::U16 => put!(u16),
            ScalarType::I16 => put!(i16),
            ScalarType::U32 => put!(u32),
            ScalarType::I32 => put!(i32),
            ScalarType::F32 => put!(f32),
            ScalarType::F64 => put!(f64),
        }
    }

    /// Re-encodes an ascii PLY (one element per line) in `enc`, using the
    /// header's types, so one hand-written file tests all three encodings.
    fn encode(ascii: &str, enc: Encoding) -> Vec<u8> {
        let data = ascii.as_bytes();
        if enc == Encoding::Ascii {
            return data.to_vec();
        }
        let header = parse_header(data).unwrap();
        let head = String::from_utf8(data[..header.body.pos()].to_vec())
            .unwrap()
            .replace("format ascii", &format!("format {}", enc.header_name()));
        let big = enc == Encoding::BinaryBigEndian;
        let mut out = head.into_bytes();
        let mut lines = header
            .body
            .clone()
            .filter(|(_, l)| !l.trim_ascii().is_empty());
        for e in &header.elements {
            for _ in 0..e.count {
                let (_, line) = lines.next().unwrap();
                let mut toks = Tokens(line);
                for p in &e.props {
                    match p.kind {
                        Kind::Scalar(t) => encode_value(&mut out, t, toks.next().unwrap(), big),
                        Kind::List { count, item } => {
                            let n = toks.next().unwrap();
                            encode_value(&mut out, count, n, big);
                            for _ in 0..parse_int(n).unwrap() {
                                encode_value(&mut out, item, toks.next().unwrap(), big);
                            }
                        }
                    }
                }
                assert!(toks.next().is_none());
            }
        }
        out
    }

    const ALL: [Encoding; 3] = [
        Encoding::Ascii,
        Encoding::BinaryLittleEndian,
        Encoding::BinaryBigEndian,
    ];

    /// Every type, unknown properties and elements (with lists) around the
    /// ones we read, colours, a quad and a pentagon.
    const RICH: &str = "ply\r
format ascii 1.0\r
comment hand written\r
obj_info test\r
element material 2\r
property list uint8 int16 ids\r
property double shininess\r
element vertex 5\r
property double x\r
property float32 y\r
property short z\r
property list uchar float junk\r
property float nx\r
property float ny\r
property float nz\r
property uchar red\r
property uchar green\r
property uchar blue\r
property int segment_index\r
property float radius\r
element edge 1\r
property int vertex1\r
property int vertex2\r
element face 2\r
property uchar flags\r
property list uint8 uint32 vertex_indices\r
property list char char extra\r
end_header\r
3 1 2 3 0.5\r
0 0.5\r
0.25 -1.5 7 2 1.5 2.5 0 0 1 255 0 51 -4 0.125\r
1 0 -3 0 0 0 1 0 0 255 9 1\r
\r
1 1 0 1 9.5 0 1 0 255 102 0 0 0\r
0 1 32767 0 1 0 0 3 4 5 6 0\r
2 2 2 0 0 0 1 1 1 1 1 1e-3\r
0 4\r
7 4 0 1 2 3 2 -1 -2\r
0 3 2 3 4 0\r
";

    #[test]
    fn reads_the_same_model_from_all_three_encodings() {
        for enc in ALL {
            let m = mesh(&encode(RICH, enc));
            assert_eq!(m.positions.len(), 5, "{enc:?}");
            assert_eq!(m.positions[0], Vec3::new(0.25, -1.5, 7.0));
            assert_eq!(m.positions[3], Vec3::new(0.0, 1.0, 32767.0));
            assert_eq!(
                m.triangles,
                vec![[0, 1, 2], [0, 2, 3], [2, 3, 4]],
                "{enc:?}"
            );
            let n = m.normals.as_ref().unwrap();
            assert_eq!(n[1], Vec3::new(0.0, 0.0, 1.0));
            let c = m.colors.as_ref().unwrap();
            assert_eq!(c[0], Vec3::new(1.0, 0.0, 0.2));
            assert_eq!(c[2], Vec3::new(1.0, 0.4, 0.0));
            assert!(m.uvs.is_none() && m.parts.is_none());
        }
    }

    #[test]
    fn points_keep_normals_colours_and_radii() {
        let src = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty ushort diffuse_red\nproperty ushort diffuse_green\nproperty ushort diffuse_blue\nproperty double radius\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n1 2 3 0 1 0 65535 0 0 0.5\n4 5 6 1 0 0 0 65535 0 0.25";
        for enc in ALL {
            let p = points(&encode(src, enc));
            assert_eq!(
                p.positions,
                vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)]
            );
            assert_eq!(p.normals.unwrap()[0], Vec3::Y);
            assert_eq!(p.colors.unwrap()[1], Vec3::Y);
            assert_eq!(p.radii.unwrap(), vec![0.5, 0.25]);
        }
        // Float colours are taken as 0..1; no face element at all gives points too.
        let src = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float red\nproperty float green\nproperty float blue\nend_header\n0 0 0 0.5 0.25 1\n";
        let p = points(src.as_bytes());
        assert_eq!(p.colors.unwrap()[0], Vec3::new(0.5, 0.25, 1.0));
        assert!(p.normals.is_none() && p.radii.is_none());
    }

    #[test]
    fn non_finite_coordinates_are_read_not_rejected() {
        let src = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\nnan 0 0\ninf -inf 1\n+1.5 2e3 -0\n";
        let p = points(src.as_bytes());
        assert!(p.positions[0].x.is_nan());
        assert_eq!(p.positions[1].y, f32::NEG_INFINITY);
        assert_eq!(p.positions[2], Vec3::new(1.5, 2000.0, 0.0));
    }

    fn sample_mesh() -> TriMesh {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.5, -2.25, 1e-7),
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(-123456.78, 3.4e30, f32::MIN_POSITIVE),
        ];
        TriMesh {
            triangles: vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]],
            normals: Some(vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.6, 0.8, 0.0)]),
            colors: Some(
                (0..4)
                    .map(|i| Vec3::new(i as f32 / 255.0, 1.0, 0.0))
                    .collect(),
            ),
            ..TriMesh::new(positions, Vec::new())
        }
    }

    #[test]
    fn mesh_round_trips_in_all_encodings() {
        let full = sample_mesh();
        let bare = TriMesh::new(full.positions.clone(), full.triangles.clone());
        for enc in ALL {
            for m in [&full, &bare] {
                assert_eq!(&mesh(&write_mesh(m, enc)), m, "{enc:?}");
            }
        }
        // Binary is the exact fixed size: header + 3 floats + 3 floats + 3 bytes per vertex.
        let bytes = write_mesh(&full, Encoding::BinaryLittleEndian);
        let head = parse_header(&bytes).unwrap().body.pos();
        assert_eq!(bytes.len() - head, 4 * 27 + 3 * 13);
    }

    #[test]
    fn points_round_trip_in_all_encodings() {
        let m = sample_mesh();
        let full = PointSet {
            positions: m.positions.clone(),
            normals: m.normals.clone(),
            colors: m.colors.clone(),
            radii: Some(vec![0.5, 0.0, 1e-3, 7.0]),
        };
        let bare = PointSet {
            positions: m.positions.clone(),
            ..PointSet::default()
        };
        for enc in ALL {
            assert_eq!(points(&write_points(&full, enc)), full, "{enc:?}");
            let back = points(&write_points(&bare, enc));
            assert_eq!(back.positions, bare.positions);
            assert_eq!(back.radii, Some(vec![0.0; 4]));
            assert_eq!(back.colors, Some(vec![Vec3::ONE; 4]));
            assert!(back.normals.is_none());
        }
        let text = String::from_utf8(write_points(&bare, Encoding::Ascii)).unwrap();
        assert!(text.contains(
            "property float x\nproperty float y\nproperty float z\nproperty float radius\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
        ));
    }

    fn err(data: &[u8]) -> ParseError {
        match model(data) {
            Err(e) => e,
            Ok(m) => panic!("expected an error, got {m:?}"),
        }
    }

    const TRI_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

    #[test]
    fn malformed_headers_are_errors_at_their_line() {
        let cases: &[(&str, usize)] = &[
            ("", 1),
            ("plyx\n", 1),
            ("ply\nformat ascii 1.0\n", 2),
            ("ply\nformat text 1.0\nend_header\n", 2),
            ("ply\nformat ascii 1.0\nformat ascii 1.0\n", 3),
            ("ply\nproperty float x\n", 2),
            ("ply\nformat ascii 1.0\nelement vertex -1\n", 3),
            (
                "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\n",
                3,
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\n",
                4,
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar x\n",
                4,
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x y\n",
                4,
            ),
            ("ply\nformat ascii 1.0\nbogus\n", 3),
            ("ply\nelement vertex 0\nend_header\n", 3),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
                3,
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty int vertex_indices\nend_header\n",
                7,
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement vertex 0\nend_header\n",
                7,
            ),
        ];
        for (src, line) in cases {
            assert_eq!(err(src.as_bytes()).at, Location::Line(*line), "{src:?}");
        }
        assert!(
            err(b"ply\nformat ascii 1.0\n\xff\xfe\n")
                .expected
                .contains("text")
        );
    }

    #[test]
    fn huge_counts_are_errors_not_allocations() {
        let huge = TRI_HEAD.replace("vertex 3", "vertex 1000000000000");
        let e = err(format!("{huge}0 0 0\n").as_bytes());
        assert_eq!(e.at, Location::Line(9));
        assert!(
            e.expected.contains("1000000000000 vertex"),
            "{}",
            e.expected
        );
        for enc in [Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
            let data = encode(&format!("{TRI_HEAD}0 0 0\n1 1 1\n2 2 2\n3 0 1 2\n"), enc);
            assert_eq!(mesh(&data).triangles.len(), 1);
            let body = parse_header(&data).unwrap().body.pos();
            let head = String::from_utf8(data[..body].to_vec()).unwrap();
            // The second count overflows usize when multiplied by the face size.
            for count in ["1000000000000".to_string(), usize::MAX.to_string()] {
                let mut bad = head
                    .replace("face 1", &format!("face {count}"))
                    .into_bytes();
                let vertices_end = bad.len() as u64 + 36;
                bad.extend_from_slice(&data[body..]);
                let e = err(&bad);
                assert_eq!(e.at, Location::Byte(vertices_end), "{}", e.expected);
            }
        }
    }

    #[test]
    fn truncated_and_garbled_bodies_are_errors() {
        let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let cases: &[(&str, usize, &str)] = &[
            ("0 0 0\n1 0 0\n", 9, "3 vertex elements of at least 6 bytes"),
            ("0 0 0\n1 0 0\n      \n", 12, "vertex 2 of 3"),
            ("0 0 0\n1 0\n0 1 0\n3 0 1 2\n", 11, "`z` of vertex 1"),
            ("0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", 11, "found `x`"),
            ("0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n", 11, "to end"),
            (
                "0 0 0\n1 0 0\n0 1 0\n3 0 1   \n",
                13,
                "`vertex_indices` of face 0",
            ),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n", 13, "an integer"),
            ("0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n", 13, "a list length"),
            (
                "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
                13,
                "in 0..3 in face 0, found 3",
            ),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", 13, "found -1"),
            ("0 0 0\n1 0 0\n0 1 0\n2 0 1   \n", 13, "at least 3"),
        ];
        assert_eq!(
            mesh(format!("{TRI_HEAD}{body}").as_bytes()).triangles.len(),
            1
        );
        for (b, line, what) in cases {
            let e = err(format!("{TRI_HEAD}{b}").as_bytes());
            assert_eq!(e.at, Location::Line(*line), "{b:?}: {e:?}");
            assert!(e.expected.contains(what), "{b:?}: {}", e.expected);
        }
        for enc in [Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
            let bad = encode(&format!("{TRI_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), enc);
            let e = err(&bad);
            assert_eq!(e.at, Location::Byte(bad.len() as u64 - 13));
            assert!(e.expected.contains("face 0"));
            let good = encode(&format!("{TRI_HEAD}{body}"), enc);
            let e = err(&good[..good.len() - 1]);
            assert_eq!(e.at, Location::Byte(good.len() as u64 - 4));
            assert!(e.expected.contains("end of the data"), "{}", e.expected);
        }
    }

    #[test]
    fn no_prefix_or_corruption_panics() {
        for enc in ALL {
            let data = encode(RICH, enc);
            for n in 0..data.len() {
                let _ = model(&data[..n]);
            }
            for i in 0..data.len() {
                let mut d = data.clone();
                d[i] ^= 0xa5;
                let _ = model(&d);
            }
        }
    }

    #[test]
    fn cancel_stops_reading() {
        let p = Progress::new();
        p.cancel();
        let e = read(
            format!("{TRI_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").as_bytes(),
            &p,
        );
        assert_eq!(e.unwrap_err().expected, "cancelled");
    }

    fn shared(name: &str) -> Vec<u8> {
        let path = format!("{}/../../shared/models/{name}", env!("CARGO_MANIFEST_DIR"));
        std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    #[test]
    fn reads_ball_ascii_points_with_normals() {
        let p = points(&shared("ball.ply"));
        assert_eq!(p.positions.len(), 31_374);
        assert_eq!(p.normals.as_ref().map(Vec::len), Some(31_374));
        assert!(p.colors.is_none() && p.radii.is_none());
    }

    #[test]
    fn reads_table_scene_binary_points_with_colours() {
        let p = points(&shared("table_scene_mug_stereo_textured.ply"));
        assert_eq!(p.positions.len(), 209_280);
        let c = p.colors.unwrap();
        assert_eq!(c.len(), 209_280);
        assert!(
            c.iter()
                .all(|c| c.min_element() >= 0.0 && c.max_element() <= 1.0)
        );
        assert!(p.positions.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn reads_horse_binary_mesh() {
        let m = mesh(&shared("horse.ply"));
        assert_eq!(m.positions.len(), 48_485);
        assert_eq!(m.triangles.len(), 96_966);
        assert_eq!(m.normals.as_ref().map(Vec::len), Some(48_485));
        assert!(m.colors.is_none());
    }

    #[test]
    fn reads_dragon_ascii_mesh() {
        let data = super::super::gunzip(&shared("dragon_vrip.ply.gz"), u64::MAX).unwrap();
        let p = Progress::new();
        let m = match read(&data, &p).unwrap() {
            Model::Mesh(m) => m,
            _ => panic!("expected a mesh"),
        };
        assert_eq!(m.positions.len(), 437_645);
        assert_eq!(m.triangles.len(), 871_414);
        assert_eq!(p.fraction(), 1.0);
    }
}
