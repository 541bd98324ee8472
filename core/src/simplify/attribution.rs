//! The original surface's side of a collapse's bound (O → new triangles):
//! every point of the original surface O belongs to one piece, and every
//! piece to one triangle of the current mesh, which carries a bound on the
//! distance of its pieces to it. A collapse hands the pieces of the triangles
//! it removes to its new triangles.
//!
//! A piece is a convex polygon inside one original triangle, so the largest
//! distance of its points to a triangle is the largest of its corners'
//! (distance to a convex set is convex). A piece goes whole to the new
//! triangle that covers it best unless that is loose: where it straddles two
//! new triangles, a corner beside its triangle counts its in-plane distance
//! (whole original triangles bounded the finest collapses at 10–14× the
//! measured distance). Such a piece is cut by the wall between the two (the
//! plane through their common edge that halves their dihedral angle), each
//! part going to its own triangle, until it is within the tolerance of the
//! exact distances of its corners to the new star, or of a floor the bound
//! is known to reach anyway. When all the pieces of an original triangle
//! come back together they are cut afresh from the whole triangle, so old
//! cuts do not pile up.
//!
//! Following one point's pieces from the original up to any cut of the
//! collapses gives a triangle on the cut within its bound: so the two-sided
//! Hausdorff distance of any cut is within its triangles' bounds (with the
//! other direction, `step_bounds`).

use glam::Vec3;
use rayon::prelude::*;

use crate::distance::facets::Facets;
use crate::geom::TriMesh;

/// Corners a piece may have: a cut that would need more is not made (the
/// piece goes whole, which is still a true bound).
const CORNERS: usize = 8;

/// Cuts of one piece per collapse at most: a guard only, since each cut on
/// the way to a part is by another wall of the star.
const MAX_CUTS: u32 = 32;

/// Part of an original triangle: all of it until a cut, then a convex
/// polygon.
#[derive(Clone, Copy)]
struct Piece {
    original: u32,
    polygon: Polygon,
}

/// A convex polygon of at most [`CORNERS`] corners.
#[derive(Clone, Copy)]
struct Polygon {
    len: u8,
    corners: [Vec3; CORNERS],
}

impl Polygon {
    fn triangle(t: [Vec3; 3]) -> Polygon {
        let mut corners = [Vec3::ZERO; CORNERS];
        corners[..3].copy_from_slice(&t);
        Polygon { len: 3, corners }
    }

    fn corners(&self) -> &[Vec3] {
        &self.corners[..self.len as usize]
    }

    /// Appends a corner; `None` when the polygon is full.
    fn push(&mut self, v: Vec3) -> Option<()> {
        *self.corners.get_mut(self.len as usize)? = v;
        self.len += 1;
        Some(())
    }
}

/// A plane between two new triangles of a collapse: a point and its normal.
type Wall = (Vec3, Vec3);

/// Who stands for which part of the original, and how far it is.
pub(crate) struct Attribution<'a> {
    mesh: &'a TriMesh,
    /// Per triangle of the simplification: its pieces, until it is removed,
    owned: Vec<Vec<Piece>>,
    /// and the largest distance of its pieces to it.
    forward: Vec<f32>,
    /// Per original triangle, how many pieces it is in now.
    pieces_of: Vec<u32>,
}

impl<'a> Attribution<'a> {
    /// Every original triangle stands for itself.
    pub fn new(mesh: &'a TriMesh) -> Self {
        Attribution {
            mesh,
            owned: Vec::new(),
            forward: Vec::new(),
            pieces_of: vec![1; mesh.triangles.len()],
        }
    }

    /// Makes room for triangles up to id `total` (the original ones own themselves).
    pub fn grow(&mut self, total: usize) {
        let originals = self.mesh.triangles.len();
        let from = self.owned.len();
        self.owned.extend((from..total).map(|t| {
            if t < originals {
                vec![Piece {
                    original: t as u32,
                    polygon: Polygon::triangle(self.mesh.triangle(t)),
                }]
            } else {
                Vec::new()
            }
        }));
        self.forward.resize(total, 0.0);
    }

    /// The bound of triangle `t`'s pieces (0 for an original one).
    pub fn forward(&self, t: u32) -> f32 {
        self.forward[t as usize]
    }

    /// Takes the pieces of the `removed` triangles, for [`Attribution::hand_over`].
    pub fn take(&mut self, removed: &[u32]) -> Handover {
        let mut region = Vec::new();
        for t in removed {
            region.extend(std::mem::take(&mut self.owned[*t as usize]));
        }
        Handover {
            region,
            parts: Vec::new(),
        }
    }

    /// Moves triangle `from`'s pieces to triangle `to`, whose bound of them
    /// is `forward` (at least theirs to `from` plus how far `from`'s points
    /// move onto `to`: module `limit`).
    pub fn carry(&mut self, from: u32, to: u32, forward: f32) {
        let pieces = std::mem::take(&mut self.owned[from as usize]);
        self.owned[to as usize].extend(pieces);
        self.forward[to as usize] = self.forward[to as usize].max(forward);
    }

    /// The pieces of the `removed` triangles, copied: for a collapse that
    /// may not happen (module `limit`); [`Attribution::give`] after
    /// [`Attribution::take`] applies it if it does.
    pub fn peek(&self, removed: &[u32]) -> Handover {
        Handover {
            region: removed
                .iter()
                .flat_map(|t| self.owned[*t as usize].iter().copied())
                .collect(),
            parts: Vec::new(),
        }
    }

    /// Decides who gets the pieces of `handover` among new triangles with
    /// corners `made`, cutting loose ones (module doc) no finer than the
    /// tolerance of the corners' exact distances (relative `rel_tol`,
    /// absolute `abs_tol`) or `floor`. It changes nothing: collapses that
    /// take no triangle of each other's can hand over at the same time, and
    /// [`Attribution::give`] applies each.
    pub fn hand_over(
        &self,
        handover: &mut Handover,
        made: &[[Vec3; 3]],
        (rel_tol, abs_tol, floor): (f32, f32, f32),
    ) {
        let mut facets = Facets::default();
        for p in made {
            facets.push(p);
        }
        let mut walls = Vec::new();
        for k1 in 0..made.len() {
            for k2 in k1 + 1..made.len() {
                walls.extend(wall(made[k1], made[k2]));
            }
        }
        let star = Star {
            facets: &facets,
            walls: &walls,
            rel_tol,
            abs_tol,
            floor,
        };
        // The pieces of one original together: when they are all here, the
        // original is cut afresh. (Another collapse handing over at the same
        // time cannot make a group look whole: it holds a piece of it.)
        let region = &mut handover.region;
        region.sort_unstable_by_key(|p| p.original);
        let groups: Vec<&[Piece]> = region.chunk_by(|x, y| x.original == y.original).collect();
        let (mesh, pieces_of) = (self.mesh, &self.pieces_of);
        let attribute = |out: &mut Vec<(usize, f32, Piece)>, group: &&[Piece]| {
            let original = group[0].original;
            if group.len() as u32 == pieces_of[original as usize] {
                let whole = Polygon::triangle(mesh.triangle(original as usize));
                star.attribute(original, whole, 0, out);
            } else {
                for piece in group.iter() {
                    star.attribute(original, piece.polygon, 0, out);
                }
            }
        };
        // Most collapses hand over a few dozen pieces: one thread.
        handover.parts = if groups.len() < 64 {
            let mut out = Vec::with_capacity(region.len() + 8);
            groups.iter().for_each(|g| attribute(&mut out, g));
            out
        } else {
            let parts: Vec<Vec<(usize, f32, Piece)>> = groups
                .par_iter()
                .with_min_len(32)
                .fold(Vec::new, |mut out, g| {
                    attribute(&mut out, g);
                    out
                })
                .collect();
            parts.into_iter().flatten().collect()
        };
    }

    /// Gives the `added` triangles (in the order of `made`) their pieces.
    pub fn give(&mut self, handover: Handover, added: &[u32]) {
        for p in &handover.region {
            self.pieces_of[p.original as usize] -= 1;
        }
        for (k, d, piece) in handover.parts {
            let t = added[k] as usize;
            self.pieces_of[piece.original as usize] += 1;
            self.owned[t].push(piece);
            self.forward[t] = self.forward[t].max(d);
        }
    }
}

/// The pieces a collapse hands over, and who gets them.
pub(crate) struct Handover {
    region: Vec<Piece>,
    parts: Vec<(usize, f32, Piece)>,
}

impl Handover {
    /// The largest distance of a piece to the new triangle it goes to (0
    /// before [`Attribution::hand_over`]).
    pub fn forward(&self) -> f32 {
        self.parts.iter().map(|p| p.1).fold(0.0, f32::max)
    }
}

/// The wall between new triangles `p` and `q` if they share an edge: the
/// plane through it that halves their dihedral angle.
fn wall(p: [Vec3; 3], q: [Vec3; 3]) -> Option<Wall> {
    let mut common = p.iter().filter(|v| q.contains(v));
    let (Some(a), Some(b), None) = (common.next(), common.next(), common.next()) else {
        return None;
    };
    let normal = |t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
    let m = (*b - *a).cross(normal(&p) + normal(&q)).normalize_or_zero();
    (m != Vec3::ZERO).then_some((*a, m))
}

/// A collapse's new triangles, to attribute pieces of the original to.
struct Star<'a> {
    facets: &'a Facets,
    walls: &'a [Wall],
    rel_tol: f32,
    abs_tol: f32,
    floor: f32,
}

impl Star<'_> {
    /// Appends `(new triangle, bound, part)` for the parts of `piece`, a
    /// polygon of triangle `original`.
    fn attribute(
        &self,
        original: u32,
        piece: Polygon,
        cuts: u32,
        out: &mut Vec<(usize, f32, Piece)>,
    ) {
        // With the exact distances of the corners to the star: no part can
        // do better than the largest.
        let mut scratch = [0f32; CORNERS];
        let (best, cover, lower) = self.facets.cover_and_nearest(piece.corners(), &mut scratch);
        let (cover, lower) = (cover.sqrt(), lower.sqrt());
        let good_enough = self.floor.max(lower * (1.0 + self.rel_tol) + self.abs_tol);
        let parts = (cover > good_enough && cuts < MAX_CUTS)
            .then(|| self.cut(&piece))
            .flatten();
        match parts {
            Some([a, b]) => {
                self.attribute(original, a, cuts + 1, out);
                self.attribute(original, b, cuts + 1, out);
            }
            None => out.push((
                best,
                cover,
                Piece {
                    original,
                    polygon: piece,
                },
            )),
        }
    }

    /// `piece` on either side of the first wall with corners strictly on
    /// both; `None` when there is none (the piece then lies past the star's
    /// rim, and no cut brings its overhang nearer) or a part would have too
    /// many corners.
    fn cut(&self, piece: &Polygon) -> Option<[Polygon; 2]> {
        let corners = piece.corners();
        // A corner within round-off of a wall (the new vertex, on all of
        // them) is on it: a cut there would leave a sliver.
        let scale = corners
            .iter()
            .map(|v| v.abs().max_element())
            .fold(0.0, f32::max);
        let round_off = 8.0 * f32::EPSILON * scale;
        let mut side = [0f32; CORNERS];
        let wall = self.walls.iter().find(|(o, m)| {
            for (s, v) in side.iter_mut().zip(corners) {
                let f = (*v - *o).dot(*m);
                *s = if f.abs() <= round_off { 0.0 } else { f };
            }
            let side = &side[..corners.len()];
            side.iter().any(|f| *f > 0.0) && side.iter().any(|f| *f < 0.0)
        });
        wall?;
        let mut parts = [Polygon {
            len: 0,
            corners: [Vec3::ZERO; CORNERS],
        }; 2];
        let n = corners.len();
        for i in 0..n {
            let (v, f) = (corners[i], side[i]);
            let (w, g) = (corners[(i + 1) % n], side[(i + 1) % n]);
            for (part, keep) in parts.iter_mut().zip([f >= 0.0, f <= 0.0]) {
                if keep {
                    part.push(v)?;
                }
            }
            if f * g < 0.0 {
                let x = v + (w - v) * (f / (f - g));
                for part in parts.iter_mut() {
                    part.push(x)?;
                }
            }
        }
        Some(parts)
    }
}
