//! Caps: the fans that close a mesh's boundary so that rows can count its
//! winding number (voxel paper §2, eq. 2's S for open meshes), and a
//! hierarchy that evaluates their solid angle with a certified error.
//!
//! The boundary of the triangles, read as a 2-chain, is the 1-chain ∂M:
//! each undirected edge with its net multiplicity (uses a → b less uses
//! b → a). It is a cycle whatever the surface (every triangle adds as much
//! into each corner as out of it), so it splits into closed walks, and the
//! mesh plus a fan on each walk has no boundary: its signed crossing count
//! is an integer winding number w even where edges are non-manifold, faces
//! disagree on orientation or loops touch themselves (CT scans, CAD
//! assemblies). The open mesh's generalised winding number is w less the
//! caps' solid angle over 4π.
//!
//! A CAD assembly has a thousand loops and fifteen thousand cap triangles,
//! so the caps' solid angle is summed over a bounding hierarchy (Barill et
//! al. 2018's far field) with a bound on what the far field leaves out: a
//! cluster of area A within ρ of its centre c, seen from p at D = |c − p|,
//! subtends N·(c − p)/D³ (N its area vector) within 2Aρ/(D − ρ)³, since
//! the kernel (x − p)/|x − p|³ has a derivative of norm 2/|x − p|³. Its
//! loop edges (length L) bound the gradient of its solid angle by
//! L/(D − ρ)² (Biot–Savart over the boundary).

use std::borrow::Cow;

use glam::DVec3;
use rayon::prelude::*;

use crate::geom::TriMesh;

/// What the caps may add to a row's winding number at most for the row to
/// take the closed mesh's answer (w ≠ 0): under ½, with room for round-off,
/// for the sum of every loop (an assembly has hundreds).
const FAR: f64 = 0.45;

/// A cluster is taken whole when its centre is this many radii away.
const OPENING: f64 = 3.0;

/// The opening of a second try where the first's far-field error could tip
/// the answer, before every triangle is summed (the error falls as the
/// cube of the opening).
pub const FINER: f64 = 12.0;

/// Leaves hold at most this many cap triangles.
const LEAF: usize = 4;

const FOUR_PI: f64 = 4.0 * std::f64::consts::PI;

/// The signed solid angle of a triangle over 4π (Van Oosterom and Strackee),
/// its corners given from the viewpoint with their lengths: what the tests
/// sum triangle by triangle.
#[cfg(test)]
pub(super) fn solid_angle(corners: [(DVec3, f64); 3]) -> f64 {
    let (num, den) = half_angle(corners);
    num.atan2(den) / (2.0 * std::f64::consts::PI)
}

/// Half a triangle's solid angle as the argument of den + i·num.
fn half_angle([(a, la), (b, lb), (c, lc)]: [(DVec3, f64); 3]) -> (f64, f64) {
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    (num, den)
}

/// A sum of arguments, each as atan2 takes it (in (−π, π]), kept as one
/// product and the turns its running argument has made past ±π: one atan2
/// for a whole evaluation instead of one per triangle.
struct Angles {
    re: f64,
    im: f64,
    turns: f64,
}

impl Angles {
    fn new() -> Angles {
        Angles {
            re: 1.0,
            im: 0.0,
            turns: 0.0,
        }
    }

    /// Adds atan2(num, den).
    fn add(&mut self, num: f64, den: f64) {
        if num == 0.0 && den == 0.0 {
            return;
        }
        let (re, im) = (self.re * den - self.im * num, self.re * num + self.im * den);
        // The argument of a point in (0, π] (above, or on the negative real
        // axis), or in (−π, 0]. A left turn (in (0, π]; a half turn is left
        // for +0 and right for −0, as atan2 has it) from [0, π] that ends
        // out of (0, π] passed +π; a right one (in [−π, 0]) from (−π, 0]
        // that ends in (0, π] passed −π.
        let upper = |re: f64, im: f64| im > 0.0 || (im == 0.0 && re < 0.0);
        let lower = |re: f64, im: f64| im < 0.0 || (im == 0.0 && re > 0.0);
        let left = num > 0.0 || (num == 0.0 && num.is_sign_positive() && den < 0.0);
        if left && self.im >= 0.0 && !upper(re, im) {
            self.turns += 1.0;
        } else if !left && lower(self.re, self.im) && upper(re, im) {
            self.turns -= 1.0;
        }
        // Scaled, never normalised: only the direction matters.
        let scale = re.abs().max(im.abs());
        (self.re, self.im) = (re / scale, im / scale);
    }

    /// The sum.
    fn total(&self) -> f64 {
        let principal = match self.im == 0.0 && self.re < 0.0 {
            true => std::f64::consts::PI,
            false => self.im.atan2(self.re),
        };
        principal + std::f64::consts::TAU * self.turns
    }
}

/// One cap triangle (b, a, centre): the loop runs a → b, its cap against
/// it. A fan's only boundary edge is a → b (its spokes cancel with its
/// neighbours'); a sliver (see [`close`]) has all three.
#[derive(Clone, Copy)]
struct Piece {
    a: DVec3,
    b: DVec3,
    center: DVec3,
    sliver: bool,
}

impl Piece {
    fn area_vector(&self) -> DVec3 {
        0.5 * (self.a - self.b).cross(self.center - self.b)
    }
    fn centroid(&self) -> DVec3 {
        (self.a + self.b + self.center) / 3.0
    }
    /// The boundary edges this piece answers for in the gradient bound.
    fn edges(&self) -> impl Iterator<Item = (DVec3, DVec3)> {
        let spokes = [(self.b, self.center), (self.center, self.a)];
        std::iter::once((self.a, self.b)).chain(spokes.into_iter().filter(move |_| self.sliver))
    }
}

/// A cluster of cap triangles: its far field and what bounds it.
struct Node {
    center: DVec3,
    radius: f64,
    /// Σ area vectors (the dipole), Σ areas, Σ loop-edge lengths.
    normal: DVec3,
    area: f64,
    length: f64,
    /// A leaf (`count` > 0) holds `pieces[first..first + count]`; an inner
    /// node has the children `first` and `right`.
    first: u32,
    count: u32,
    right: u32,
}

/// The caps' solid angle at a point over 4π, with what the far field may
/// have left out, a bound S on its gradient there and a distance d within
/// which each term of S grows at most as (d/(d − t))³ at t from the point.
/// `clearance` is at most the distance to the caps themselves (0 unless
/// asked for): within it no path crosses a cap, so the value moves by its
/// drift whichever way one goes, not only along a row.
#[derive(Debug, Clone, Copy, Default)]
pub struct Eval {
    pub value: f64,
    pub error: f64,
    pub slope: f64,
    pub distance: f64,
    pub clearance: f64,
}

impl Eval {
    /// How far the value can move within `dx` of the point (off the caps):
    /// ∫₀^dx S (d/(d − t))³ dt = S·dx·(2 − u)/(2(1 − u)²), u = dx/d.
    pub fn drift(&self, dx: f64) -> f64 {
        let u = dx / self.distance;
        if u >= 1.0 {
            return f64::INFINITY;
        }
        self.slope * dx * (2.0 - u) / (2.0 * (1.0 - u) * (1.0 - u))
    }
}

/// Every cap of a mesh, in one hierarchy.
pub struct Caps {
    pieces: Vec<Piece>,
    nodes: Vec<Node>,
    /// How many loops the boundary split into.
    pub loops: usize,
}

impl Caps {
    /// The number of cap triangles (they follow the mesh's own in the
    /// closed mesh [`close`] returns).
    pub fn triangles(&self) -> usize {
        self.pieces.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }

    /// Whether the caps together add less than [`FAR`] in magnitude to the
    /// winding number anywhere on the row along x through (y, z): then the
    /// closed mesh's w ≠ 0 is the open mesh's |w − Ω/4π| ≥ ½. A cluster of
    /// area A within ρ of its centre subtends at most A/(d − ρ)² from d away,
    /// and every point of the row is at least the yz distance from it.
    pub fn far_from_row(&self, y: f64, z: f64) -> bool {
        if self.nodes.is_empty() {
            return true;
        }
        let mut sum = 0.0;
        let mut stack = [0u32; 128];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let d = (node.center.y - y).hypot(node.center.z - z);
            if d > OPENING * node.radius {
                sum += node.area / (FOUR_PI * (d - node.radius).powi(2));
                if sum >= FAR {
                    return false;
                }
            } else if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for piece in &self.pieces[range] {
                    // A sliver of a junction exactly on its edge has no area
                    // and no solid angle.
                    let area = piece.area_vector().length();
                    if area == 0.0 {
                        continue;
                    }
                    let c = piece.centroid();
                    let r = [piece.a, piece.b, piece.center]
                        .map(|v| v.distance(c))
                        .into_iter()
                        .fold(0.0, f64::max);
                    let d = (c.y - y).hypot(c.z - z);
                    if d <= r {
                        return false;
                    }
                    sum += area / (FOUR_PI * (d - r).powi(2));
                }
                if sum >= FAR {
                    return false;
                }
            } else {
                stack[top] = node.first;
                stack[top + 1] = node.right;
                top += 2;
            }
        }
        true
    }

    /// The caps' solid angle at `p` over 4π; `exact` sums every triangle.
    pub fn eval(&self, p: DVec3, exact: bool) -> Eval {
        self.eval_opened(p, if exact { f64::INFINITY } else { OPENING })
    }

    /// [`Caps::eval`] with clusters taken whole from `opening` radii away
    /// (infinite: every triangle).
    pub fn eval_opened(&self, p: DVec3, opening: f64) -> Eval {
        self.eval_with(p, opening, false)
    }

    /// [`Caps::eval`] (the far field allowed) with its clearance: what a
    /// ball about `p` needs to be known whole.
    pub fn eval_cleared(&self, p: DVec3) -> Eval {
        self.eval_with(p, OPENING, true)
    }

    fn eval_with(&self, p: DVec3, opening: f64, clear: bool) -> Eval {
        if self.nodes.is_empty() {
            return Eval {
                distance: f64::INFINITY,
                clearance: f64::INFINITY,
                ..Eval::default()
            };
        }
        let mut clearance = f64::INFINITY;
        // Sums in steradians and length/distance², over 4π at the end.
        let (mut value, mut error, mut slope) = (0.0, 0.0, 0.0);
        // The exact triangles' 4π·Ω/4π = 2·atan2 each, summed as one product.
        let mut angles = Angles::new();
        let mut nearest = f64::INFINITY;
        // An edge's Biot–Savart term length/d² and its distance d.
        let edge = |a: DVec3, b: DVec3| {
            let d = segment_distance(a, b, p);
            (a.distance(b) / (d * d), d)
        };
        let mut far = f64::INFINITY;
        let mut stack = [0u32; 128];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let r = node.center - p;
            let d = r.length();
            if d > opening * node.radius {
                let gap = d - node.radius;
                value += node.normal.dot(r) / (d * d * d);
                error += 2.0 * node.area * node.radius / (gap * gap * gap);
                // Biot–Savart over its edges, or the kernel's derivative over
                // its area (far better for slivers): both bound the gradient.
                slope += (node.length / (gap * gap)).min(2.0 * node.area / (gap * gap * gap));
                far = far.min(gap);
                clearance = clearance.min(gap);
            } else if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for piece in &self.pieces[range] {
                    let from = |v: DVec3| {
                        let d = v - p;
                        (d, d.length())
                    };
                    let (num, den) = half_angle([from(piece.b), from(piece.a), from(piece.center)]);
                    angles.add(num, den);
                    if clear {
                        clearance =
                            clearance.min(triangle_distance(p, [piece.a, piece.b, piece.center]));
                    }
                    let (ab, d_ab) = edge(piece.a, piece.b);
                    if !piece.sliver {
                        slope += ab;
                        nearest = nearest.min(d_ab);
                        continue;
                    }
                    // A sliver: its perimeter's Biot–Savart bound, or 2a/d³
                    // with d ≥ the distance to a → b less the apex's to it
                    // (the triangle's farthest point from that edge).
                    let (bm, d_bm) = edge(piece.b, piece.center);
                    let (ma, d_ma) = edge(piece.center, piece.a);
                    let low = d_ab - segment_distance(piece.a, piece.b, piece.center);
                    let dipole = 2.0 * piece.area_vector().length() / (low * low * low);
                    if low > 0.0 && dipole < ab + bm + ma {
                        slope += dipole;
                        nearest = nearest.min(low);
                    } else {
                        slope += ab + bm + ma;
                        nearest = nearest.min(d_ab.min(d_bm).min(d_ma));
                    }
                }
            } else {
                stack[top] = node.first;
                stack[top + 1] = node.right;
                top += 2;
            }
        }
        Eval {
            value: (value + 2.0 * angles.total()) / FOUR_PI,
            error: error / FOUR_PI,
            slope: slope / FOUR_PI,
            distance: nearest.min(far),
            clearance: if clear { clearance } else { 0.0 },
        }
    }

    /// Builds the hierarchy over `pieces` (reordered), median splits along
    /// the longest side of the centroids' box.
    fn new(mut pieces: Vec<Piece>, loops: usize) -> Caps {
        let mut nodes = Vec::new();
        if !pieces.is_empty() {
            build(&mut pieces, 0, &mut nodes);
        }
        Caps {
            pieces,
            nodes,
            loops,
        }
    }
}

/// Appends the node for `pieces` (starting at `offset` in the whole list)
/// and its subtree; returns its id.
fn build(pieces: &mut [Piece], offset: usize, nodes: &mut Vec<Node>) -> u32 {
    let area: f64 = pieces.iter().map(|p| p.area_vector().length()).sum();
    let normal: DVec3 = pieces.iter().map(Piece::area_vector).sum();
    let length: f64 = pieces
        .iter()
        .flat_map(Piece::edges)
        .map(|(a, b)| a.distance(b))
        .sum();
    let center = if area > 0.0 {
        pieces
            .iter()
            .map(|p| p.area_vector().length() * p.centroid())
            .sum::<DVec3>()
            / area
    } else {
        pieces.iter().map(Piece::centroid).sum::<DVec3>() / pieces.len() as f64
    };
    let radius = pieces
        .iter()
        .flat_map(|p| [p.a, p.b, p.center])
        .map(|v| v.distance(center))
        .fold(0.0, f64::max);
    let id = nodes.len() as u32;
    nodes.push(Node {
        center,
        radius,
        normal,
        area,
        length,
        first: offset as u32,
        count: pieces.len() as u32,
        right: 0,
    });
    if pieces.len() > LEAF {
        let (lo, hi) = pieces.iter().map(Piece::centroid).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), c| (lo.min(c), hi.max(c)),
        );
        let axis = (hi - lo).max_position();
        let mid = pieces.len() / 2;
        pieces.select_nth_unstable_by(mid, |p, q| {
            p.centroid()[axis].total_cmp(&q.centroid()[axis])
        });
        let (left, right) = pieces.split_at_mut(mid);
        let l = build(left, offset, nodes);
        let r = build(right, offset + mid, nodes);
        let node = &mut nodes[id as usize];
        (node.first, node.count, node.right) = (l, 0, r);
    }
    id
}

/// `mesh` closed by a fan on each walk of its boundary, and the caps (see
/// the module doc); `None` only for an empty mesh or one with 2³¹ vertices
/// or more. Triangles with a repeated corner are left out: no solid angle,
/// no net boundary.
pub fn close(mesh: &TriMesh) -> Option<(Cow<'_, TriMesh>, Caps)> {
    if mesh.triangles.is_empty() || mesh.positions.len() > (u32::MAX >> 1) as usize {
        return None;
    }
    let proper = |t: &[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[2] != t[0];
    let edges: Vec<(u32, u32)> = mesh
        .triangles
        .par_iter()
        .filter(|t| proper(t))
        .flat_map_iter(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    let degenerate = mesh.triangles.len() * 3 != edges.len();
    let chain = net(edges);
    let (chain, slivers) = split_at_junctions(&mesh.positions, chain);
    if chain.is_empty() && !degenerate && slivers.is_empty() {
        return Some((Cow::Borrowed(mesh), Caps::new(Vec::new(), 0)));
    }
    let mut closed = TriMesh::new(
        mesh.positions.clone(),
        mesh.triangles.iter().copied().filter(proper).collect(),
    );
    let pos = |v: u32| mesh.positions[v as usize].as_dvec3();
    let mut pieces = Vec::new();
    for [a, b, m] in slivers {
        closed.triangles.push([b, a, m]);
        pieces.push(Piece {
            a: pos(a),
            b: pos(b),
            center: pos(m),
            sliver: true,
        });
    }
    // Closed walks: from the first unused edge, follow unused edges out of
    // each vertex until the walk is back where it started (in = out at
    // every vertex, so it can stop nowhere else).
    let mut used = vec![false; chain.len()];
    let mut cursor: std::collections::HashMap<u32, usize> = Default::default();
    let mut next_out = |v: u32, used: &mut [bool]| -> Option<u32> {
        let at = cursor
            .entry(v)
            .or_insert_with(|| chain.partition_point(|e| e.0 < v));
        while *at < chain.len() && chain[*at].0 == v && used[*at] {
            *at += 1;
        }
        (*at < chain.len() && chain[*at].0 == v).then(|| {
            used[*at] = true;
            chain[*at].1
        })
    };
    let mut loops = 0;
    for first in 0..chain.len() {
        if used[first] {
            continue;
        }
        let start = chain[first].0;
        let mut ring = vec![start];
        let mut v = next_out(start, &mut used)?;
        while v != start {
            ring.push(v);
            v = next_out(v, &mut used)?;
        }
        let center = ring.iter().map(|&v| pos(v)).sum::<DVec3>() / ring.len() as f64;
        let c = closed.positions.len() as u32;
        closed.positions.push(center.as_vec3());
        // The fan's own corner as the closed mesh stores it (f32), so the
        // rows' crossings and the solid angles see one surface.
        let center = closed.positions[c as usize].as_dvec3();
        for (i, &a) in ring.iter().enumerate() {
            let b = ring[(i + 1) % ring.len()];
            // The surface runs a → b; its cap runs b → a.
            closed.triangles.push([b, a, c]);
            let piece = Piece {
                a: pos(a),
                b: pos(b),
                center,
                sliver: false,
            };
            pieces.push(piece);
        }
        loops += 1;
    }
    Some((Cow::Owned(closed), Caps::new(pieces, loops)))
}

/// The distance from `p` to the triangle `t`: to its plane where `p`
/// projects inside it, else to its nearest edge.
fn triangle_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let n = (b - a).cross(c - a);
    let n2 = n.length_squared();
    if n2 > 0.0 {
        let q = p - (p - a).dot(n) / n2 * n;
        let side = |u: DVec3, v: DVec3| (v - u).cross(q - u).dot(n) >= 0.0;
        if side(a, b) && side(b, c) && side(c, a) {
            return p.distance(q);
        }
    }
    segment_distance(a, b, p)
        .min(segment_distance(b, c, p))
        .min(segment_distance(c, a, p))
}

/// The distance from `p` to the segment a–b.
fn segment_distance(a: DVec3, b: DVec3, p: DVec3) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    (a + t * ab).distance(p)
}

/// The net 1-chain of directed `edges`: each undirected edge once per unit
/// of its net multiplicity, in its net direction, sorted by (from, to).
/// Packed in 64 bits (indices below 2³¹), one parallel sort.
fn net(edges: Vec<(u32, u32)>) -> Vec<(u32, u32)> {
    let key =
        |(a, b): (u32, u32)| (a.min(b) as u64) << 32 | (a.max(b) as u64) << 1 | u64::from(a > b);
    let mut keys: Vec<u64> = edges
        .into_par_iter()
        .filter(|e| e.0 != e.1)
        .map(key)
        .collect();
    keys.par_sort_unstable();
    let mut chain: Vec<(u32, u32)> = Vec::new();
    for same in keys.chunk_by(|x, y| x >> 1 == y >> 1) {
        let net: i64 = same.iter().map(|e| 1 - 2 * (e & 1) as i64).sum();
        let (lo, hi) = ((same[0] >> 32) as u32, (same[0] as u32) >> 1);
        let edge = if net > 0 { (lo, hi) } else { (hi, lo) };
        chain.extend(std::iter::repeat_n(edge, net.unsigned_abs() as usize));
    }
    chain.sort_unstable();
    chain
}

/// A vertex splits a boundary edge when it lies this close to it, as a
/// fraction of the edge's length.
const JUNCTION: f64 = 0.05;

/// Cancels boundary that is no boundary: a CAD assembly's faces meet along
/// curves that each side tessellates with its own vertices (T-junctions and
/// chords of one arc), so the index-level chain has a loop per face though
/// the two sides run along one curve. An edge a → b with a boundary vertex
/// m close to it is a → m + m → b + ∂[a, b, m]: the chain becomes the split
/// one (where the two sides now cancel) and the sliver [b, a, m] joins the
/// caps, so the closed surface and the caps' solid angle are as exact as
/// before. Vertices at one position are one vertex here. Returns the net
/// chain and the slivers as (a, b, m).
fn split_at_junctions(
    positions: &[glam::Vec3],
    chain: Vec<(u32, u32)>,
) -> (Vec<(u32, u32)>, Vec<[u32; 3]>) {
    if chain.is_empty() {
        return (chain, Vec::new());
    }
    let mut first_at: std::collections::HashMap<[u32; 3], u32> = Default::default();
    let mut canon = |v: u32| {
        *first_at
            .entry(positions[v as usize].to_array().map(f32::to_bits))
            .or_insert(v)
    };
    let chain: Vec<(u32, u32)> = chain
        .into_iter()
        .map(|(a, b)| (canon(a), canon(b)))
        .collect();
    let pos = |v: u32| positions[v as usize].as_dvec3();
    let mut vertices: Vec<u32> = chain.iter().flat_map(|&(a, b)| [a, b]).collect();
    vertices.sort_unstable();
    vertices.dedup();
    // Vertices hashed in cells of the mean edge length.
    let cell = chain
        .iter()
        .map(|&(a, b)| pos(a).distance(pos(b)))
        .sum::<f64>()
        / chain.len() as f64;
    if !(cell > 0.0 && cell.is_finite()) {
        return (net(chain), Vec::new());
    }
    let at = |p: DVec3| (p / cell).floor().as_i64vec3().to_array();
    let mut grid: std::collections::HashMap<[i64; 3], Vec<u32>> = Default::default();
    for &v in &vertices {
        grid.entry(at(pos(v))).or_default().push(v);
    }
    let mut edges = Vec::with_capacity(chain.len());
    let mut slivers = Vec::new();
    let mut on: Vec<(f64, u32)> = Vec::new();
    for &(a, b) in &chain {
        let (pa, pb) = (pos(a), pos(b));
        let ab = pb - pa;
        let len2 = ab.length_squared();
        let tol = JUNCTION * len2.sqrt();
        let (lo, hi) = (at(pa.min(pb) - tol), at(pa.max(pb) + tol));
        on.clear();
        // Splitting is optional (the chain is exact either way): an edge
        // that would look at too many cells or vertices (a hostile file's
        // crowd in one cell) stays whole, so this stays linear.
        let cells = (0..3).map(|i| (hi[i] - lo[i] + 1) as u64).product::<u64>();
        let crowd = |x, y, z| grid.get(&[x, y, z]).map_or(0, Vec::len);
        let looked = (cells <= 4096).then(|| {
            (lo[0]..=hi[0])
                .flat_map(|x| {
                    (lo[1]..=hi[1]).flat_map(move |y| (lo[2]..=hi[2]).map(move |z| (x, y, z)))
                })
                .map(|(x, y, z)| crowd(x, y, z))
                .sum::<usize>()
        });
        if looked.is_some_and(|n| n <= 4096) {
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        for &m in grid.get(&[x, y, z]).into_iter().flatten() {
                            let t = (pos(m) - pa).dot(ab) / len2;
                            if m != a
                                && m != b
                                && t > 1e-9
                                && t < 1.0 - 1e-9
                                && (pa + t * ab).distance(pos(m)) <= tol
                            {
                                on.push((t, m));
                            }
                        }
                    }
                }
            }
        }
        on.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        on.dedup_by_key(|x| x.1);
        let mut from = a;
        for &(_, m) in on.iter() {
            edges.push((from, m));
            slivers.push([from, b, m]);
            from = m;
        }
        edges.push((from, b));
    }
    (net(edges), slivers)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use glam::Vec3;

    /// Along x within a tenth of the distance `eval` gives, the caps' value
    /// moves by at most its drift, across a cap by a whole turn more; in
    /// any direction within the clearance (which no cap comes closer than,
    /// by an independent closest point), by at most its drift alone.
    fn drift_holds(caps: &Caps, p: DVec3) {
        let cleared = caps.eval_cleared(p);
        let nearest = caps
            .pieces
            .iter()
            .map(|t| {
                let [a, b, c] = [t.a, t.b, t.center].map(|v| v.as_vec3());
                let q = crate::distance::closest_point_on_triangle(p.as_vec3(), a, b, c);
                q.as_dvec3().distance(p)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            cleared.clearance <= nearest * (1.0 + 1e-5) + 1e-6,
            "{p}: clearance {} past the caps at {nearest}",
            cleared.clearance
        );
        let u = DVec3::new(p.y + 0.31, p.z - 0.77, p.x + 0.19).normalize();
        let t = (0.5 * cleared.distance).min(0.999 * cleared.clearance);
        let moved = caps.eval(p + t * u, true).value - caps.eval(p, true).value;
        let bound = cleared.drift(t);
        assert!(
            moved.abs() <= bound + 1e-12,
            "{p} along {u}: moved {moved}, bound {bound}"
        );
        // The slope and distance of the far field's answer and of the exact.
        for exact in [false, true] {
            let here = caps.eval(p, exact);
            let dx = 0.1 * here.distance;
            let q = p + DVec3::new(dx, 0.0, 0.0);
            let moved = caps.eval(q, true).value - caps.eval(p, true).value;
            let bound = here.drift(dx);
            if bound < 0.4 {
                let smooth = moved - moved.round();
                assert!(
                    smooth.abs() <= bound + 1e-12,
                    "{p}: moved {moved}, bound {bound}"
                );
            }
        }
    }

    /// One product and its turns sum arguments as atan2 does one by one,
    /// over long runs of random turns, half turns (±0 against a negative)
    /// and none.
    #[test]
    fn angles_sum_as_atan2_does() {
        let mut rng = crate::rng::Rng::new(11);
        for run in 0..200 {
            let (mut angles, mut sum) = (Angles::new(), 0.0);
            for _ in 0..(run % 50) * 7 {
                let (num, den) = match rng.below(8) {
                    0 => (0.0, -1.0),
                    1 => (-0.0, -2.0),
                    2 => (0.0, 3.0),
                    _ => (rng.f32() as f64 - 0.5, rng.f32() as f64 - 0.3),
                };
                angles.add(num, den);
                sum += f64::atan2(num, den);
            }
            assert!(
                (angles.total() - sum).abs() < 1e-9,
                "{} vs {sum}",
                angles.total()
            );
        }
    }

    /// A torus with a band of faces taken away (two loops) and the face
    /// `flipped` turned against its neighbours (a loop run twice).
    pub(in crate::voxel) fn holed_torus(flipped: usize) -> TriMesh {
        let mut mesh = crate::builtins::torus(1.0, 0.4, 40, 20);
        mesh.triangles.drain(0..80);
        mesh.triangles[flipped].swap(1, 2);
        mesh
    }

    /// The winding number of every triangle of `mesh` at `p`, summed.
    fn brute(mesh: &TriMesh, p: DVec3) -> f64 {
        mesh.triangles
            .iter()
            .map(|t| {
                solid_angle(t.map(|v| {
                    let d = mesh.positions[v as usize].as_dvec3() - p;
                    (d, d.length())
                }))
            })
            .sum()
    }

    /// Meshes whose boundary is no set of simple loops: a quad whose two
    /// halves meet at a T-junction (on the diagonal, and a little off it,
    /// as the chord of an arc), two triangles pinched at a vertex, a fin on
    /// a non-manifold edge, a face that disagrees with its neighbours.
    /// Closed by their caps, each has an integer winding number everywhere.
    #[test]
    fn caps_close_any_boundary() {
        let quad = |off: f32| {
            let m = Vec3::new(0.5 + off, 0.5 - off, 0.0);
            let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y, m];
            TriMesh::new(positions, vec![[0, 1, 2], [0, 4, 3], [4, 2, 3]])
        };
        let pinched = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, -Vec3::X, -Vec3::Y + Vec3::Z],
            vec![[0, 1, 2], [0, 3, 4]],
        );
        let mut fin = crate::builtins::icosphere(Vec3::ZERO, 1.0, 1);
        let [a, b, _] = fin.triangles[0];
        fin.positions.push(Vec3::splat(2.0));
        fin.triangles.push([a, b, fin.positions.len() as u32 - 1]);
        let mut flipped = crate::builtins::torus(1.0, 0.4, 16, 8);
        flipped.triangles[3].swap(1, 2);
        for (name, mesh, loops, slivers) in [
            ("T-junction", quad(0.0), 1, 1),
            ("chord", quad(0.02), 1, 1),
            // A walk closes when it is back at its start: the pinch splits it.
            ("pinched", pinched, 2, 0),
            ("fin", fin, 1, 0),
            // Each edge twice: the walk goes round twice.
            ("flipped", flipped, 2, 0),
        ] {
            let (closed, caps) = close(&mesh).unwrap();
            assert_eq!(caps.loops, loops, "{name}");
            assert_eq!(
                caps.pieces.iter().filter(|p| p.sliver).count(),
                slivers,
                "{name}"
            );
            let mut rng = crate::rng::Rng::new(3);
            for _ in 0..200 {
                let p =
                    (DVec3::new(rng.f32() as f64, rng.f32() as f64, rng.f32() as f64) - 0.3) * 3.0;
                let w = brute(&closed, p);
                assert!((w - w.round()).abs() < 1e-6, "{name} at {p}: {w}");
                // The open mesh's winding number is the closed one's less the caps'.
                let open = brute(&mesh, p);
                assert!((w - caps.eval(p, true).value - open).abs() < 1e-9, "{name}");
                drift_holds(&caps, p);
            }
        }
    }

    /// The far field's value lies within its stated error of the exact sum,
    /// and the gradient bound holds against finite differences, around the
    /// caps of a torus with a band of faces taken away and a flipped face.
    #[test]
    fn the_far_field_is_within_its_error_and_slope() {
        let (_, caps) = close(&holed_torus(500)).unwrap();
        assert_eq!(caps.loops, 4, "two band loops and the flipped face's twice");
        let mut rng = crate::rng::Rng::new(5);
        let mut far_taken = 0;
        for _ in 0..2000 {
            let p = (DVec3::new(rng.f32() as f64, rng.f32() as f64, rng.f32() as f64) - 0.5) * 4.0;
            let (fast, exact) = (caps.eval(p, false), caps.eval(p, true));
            assert!(
                (fast.value - exact.value).abs() <= fast.error + 1e-12,
                "{p}: {} vs {} ± {}",
                fast.value,
                exact.value,
                fast.error
            );
            far_taken += usize::from(fast.error > 0.0);
            drift_holds(&caps, p);
        }
        assert!(far_taken > 1000, "the far field is used: {far_taken}");
    }
}
