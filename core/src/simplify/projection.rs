//! The planar-projection bound of a simplified triangle P against the
//! original surface O (the measure of Cohen et al. 1997 that the hybrid
//! paper's §2.1 error is based on), used before branch and bound because it
//! certifies a whole triangle at once.
//!
//! Project a patch U of O orthogonally onto P's plane. If every triangle of U
//! projects with positive orientation, the projection is open on U's interior
//! (across an interior edge the two images lie on opposite sides; around an
//! interior vertex the fan winds at least once), so the boundary of the image
//! lies in the image of U's boundary edges. If no boundary edge's image meets
//! P's interior, that interior (connected) is inside the image or outside it;
//! one point inside decides, and the image is closed, so it holds all of P.
//! Then every y ∈ P has a point of U straight above or below it, at distance
//! |h| where h is U's height over the plane, linear on each triangle, so
//! max_{y∈P} d(y, O) ≤ max over the triangles of U of |h| on the part of them
//! over P (their clip by P, a convex polygon: its corners). Against f64
//! round-off the tests use P inset by a margin, and the bound adds how far P
//! reaches past the inset (d(·, O) is 1-Lipschitz).
//!
//! U grows from seed triangles across shared edges while a triangle's image
//! box meets P's: an excluded neighbour's box misses P's, so the edge it
//! shares misses P too. Folded triangles (not positive) and triangles wholly
//! far from the plane (another layer of O) are left out, and the edges U
//! shares with them, like border, non-manifold and inconsistently oriented
//! edges, are tested against P. Each seed's patch is checked on its own and
//! the smallest valid bound wins.

use std::cell::RefCell;

use glam::{DVec2, DVec3, Vec3};

use crate::geom::TriMesh;
use crate::geom::adjacency::{Adjacency, NONE, next};

/// O with its corner table, for [`Projection::bound`].
pub struct Projection<'a> {
    mesh: &'a TriMesh,
    opposite: Vec<u32>,
}

/// Per-thread marks of the triangles a search has reached.
#[derive(Default)]
struct Marks {
    /// `now` once reached by the search...
    stamp: Vec<u32>,
    /// ... and once in the patch.
    inside: Vec<u32>,
    now: u32,
    queue: Vec<u32>,
    /// Edges (triangle, corner facing it) of the patch to an unknown side.
    pending: Vec<(u32, u32)>,
}

thread_local! {
    static MARKS: RefCell<Marks> = RefCell::default();
}

/// P in its own plane: corners in 2-D (counter-clockwise), the origin and
/// frame, and its image box grown by a rounding margin.
struct Frame {
    origin: DVec3,
    e1: DVec3,
    e2: DVec3,
    n: DVec3,
    corners: [DVec2; 3],
    /// Inward unit normal and offset of each edge of P inset by a margin δ:
    /// inside(k, x) = n·x − c.
    edges: [(DVec2, f64); 3],
    lo: DVec2,
    hi: DVec2,
    /// Rounding margin in plane units.
    eps: f64,
    /// How far P's points can be from the inset P (at a corner of angle θ,
    /// δ / sin(θ/2)).
    slack: f64,
}

impl Frame {
    fn new(p: [Vec3; 3]) -> Option<Frame> {
        let p = p.map(|v| v.as_dvec3());
        let (u, w) = (p[1] - p[0], p[2] - p[0]);
        let n = u.cross(w);
        let size = u.length().max(w.length());
        if !n.is_finite() || n.length() <= 1e-12 * size * size {
            return None;
        }
        let n = n.normalize();
        let e1 = u.normalize();
        let e2 = n.cross(e1);
        let corners = [
            DVec2::ZERO,
            DVec2::new(u.dot(e1), 0.0),
            DVec2::new(w.dot(e1), w.dot(e2)),
        ];
        let eps = 1e-9 * size;
        // A surface meeting P's plane along P's edge (a crease under an edge
        // of original vertices) touches P's border only, which is fine in
        // exact arithmetic (covering P's interior covers P); against
        // round-off the patch covers P inset by a margin, and the rest is
        // within `slack` of that (d(·, O) is 1-Lipschitz).
        let reach = p.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max);
        let inset = 2.0 * eps + 1e-10 * reach;
        let edges = [0, 1, 2].map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            let inward = (b - a).perp().normalize();
            (inward, inward.dot(a) + inset)
        });
        let slack = (0..3)
            .map(|k| {
                let (a, b) = (
                    corners[(k + 1) % 3] - corners[k],
                    corners[(k + 2) % 3] - corners[k],
                );
                let half = 0.5 * a.angle_to(b).abs();
                inset / half.sin()
            })
            .fold(0.0, f64::max);
        if !slack.is_finite() || slack >= 0.01 * size {
            return None;
        }
        let lo = corners[0].min(corners[1]).min(corners[2]) - eps;
        let hi = corners[0].max(corners[1]).max(corners[2]) + eps;
        Some(Frame {
            origin: p[0],
            e1,
            e2,
            n,
            corners,
            edges,
            lo,
            hi,
            eps,
            slack,
        })
    }

    /// Image in the plane and height over it.
    fn project(&self, v: Vec3) -> (DVec2, f64) {
        let d = v.as_dvec3() - self.origin;
        (DVec2::new(d.dot(self.e1), d.dot(self.e2)), d.dot(self.n))
    }

    /// Signed distance of `x` inside edge k of the inset P (positive inside).
    #[inline]
    fn inside(&self, k: usize, x: DVec2) -> f64 {
        let (n, c) = self.edges[k];
        n.dot(x) - c
    }

    /// Whether segment (a, b) meets the inset P grown by the margin.
    fn segment_meets(&self, a: DVec2, b: DVec2) -> bool {
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..3 {
            let (sa, sb) = (self.inside(k, a) + self.eps, self.inside(k, b) + self.eps);
            if sa < 0.0 && sb < 0.0 {
                return false;
            }
            if sa < 0.0 {
                t0 = t0.max(sa / (sa - sb));
            } else if sb < 0.0 {
                t1 = t1.min(sa / (sa - sb));
            }
        }
        t0 <= t1
    }

    /// Largest |h| over the part of the image triangle `q` (with heights)
    /// over the inset P, or `None` when they do not overlap.
    fn clipped_height(&self, q: [(DVec2, f64); 3]) -> Option<f64> {
        // Most triangles lie inside P or outside one of its edges: no clip.
        let side = [0, 1, 2].map(|k| q.map(|v| self.inside(k, v.0)));
        if side.iter().any(|s| s.iter().all(|x| *x < 0.0)) {
            return None;
        }
        if side.iter().all(|s| s.iter().all(|x| *x >= 0.0)) {
            return Some(q[0].1.abs().max(q[1].1.abs()).max(q[2].1.abs()));
        }
        let mut poly = [(DVec2::ZERO, 0.0); 9];
        poly[..3].copy_from_slice(&q);
        let mut len = 3;
        let mut out = [(DVec2::ZERO, 0.0); 9];
        for k in 0..3 {
            let mut m = 0;
            for i in 0..len {
                let (x, y) = (poly[i], poly[(i + 1) % len]);
                let (sx, sy) = (self.inside(k, x.0), self.inside(k, y.0));
                if sx >= 0.0 {
                    out[m] = x;
                    m += 1;
                }
                if (sx >= 0.0) != (sy >= 0.0) {
                    let t = sx / (sx - sy);
                    out[m] = (x.0 + (y.0 - x.0) * t, x.1 + (y.1 - x.1) * t);
                    m += 1;
                }
            }
            poly[..m].copy_from_slice(&out[..m]);
            len = m;
            if len == 0 {
                return None;
            }
        }
        Some(poly[..len].iter().map(|v| v.1.abs()).fold(0.0, f64::max))
    }
}

impl<'a> Projection<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        Projection {
            mesh,
            opposite: Adjacency::new(&mesh.triangles).opposite,
        }
    }

    /// An upper bound of max_{y∈P} d(y, O) for triangle `p`, from patches
    /// grown from the triangles `seeds` of O with at most `cap` triangles
    /// each; `None` where no patch covers P without folding (module doc).
    /// Triangles wholly farther than `limit` from P's plane are left out (the
    /// bound would be useless through them).
    pub fn bound(&self, p: [Vec3; 3], seeds: [u32; 3], cap: usize, limit: f32) -> Option<f32> {
        let frame = Frame::new(p)?;
        let centroid = (frame.corners[0] + frame.corners[1] + frame.corners[2]) / 3.0;
        if (0..3).any(|k| frame.inside(k, centroid) <= 0.0) {
            return None;
        }
        let nt = self.mesh.triangles.len();
        MARKS.with_borrow_mut(|marks| {
            if marks.stamp.len() < nt {
                marks.stamp.resize(nt, 0);
                marks.inside.resize(nt, 0);
            }
            if marks.now > u32::MAX - 4 {
                marks.stamp.fill(0);
                marks.inside.fill(0);
                marks.now = 0;
            }
            // A seed an earlier search reached has the same patch, or none.
            let first = marks.now + 1;
            let mut best: Option<f64> = None;
            for seed in seeds {
                if seed as usize >= nt || marks.stamp[seed as usize] >= first {
                    continue;
                }
                marks.now += 1;
                if let Some(b) =
                    self.patch_bound(&frame, centroid, seed, (cap, limit as f64), marks)
                {
                    best = Some(best.map_or(b, |x| x.min(b)));
                }
            }
            // The inset's slack, f64 round-off, then up to the next f32.
            best.map(|b| {
                ((b + frame.slack) * (1.0 + 1e-9) + frame.eps) as f32 * (1.0 + f32::EPSILON)
            })
        })
    }

    /// The patch of `seed`'s component over P: its bound, or `None` when its
    /// border (folded and far triangles are left out) meets P, it outgrows
    /// `cap` or it misses P.
    fn patch_bound(
        &self,
        frame: &Frame,
        centroid: DVec2,
        seed: u32,
        (cap, limit): (usize, f64),
        marks: &mut Marks,
    ) -> Option<f64> {
        let now = marks.now;
        marks.queue.clear();
        marks.pending.clear();
        marks.queue.push(seed);
        marks.stamp[seed as usize] = now;
        let (mut height, mut covered, mut size) = (0.0f64, false, 0usize);
        let mut i = 0;
        while i < marks.queue.len() {
            let t = marks.queue[i];
            i += 1;
            let tri = self.mesh.triangles[t as usize];
            let q = tri.map(|v| frame.project(self.mesh.positions[v as usize]));
            let lo = q[0].0.min(q[1].0).min(q[2].0);
            let hi = q[0].0.max(q[1].0).max(q[2].0);
            if lo.x > frame.hi.x || lo.y > frame.hi.y || hi.x < frame.lo.x || hi.y < frame.lo.y {
                continue;
            }
            size += 1;
            if size > cap {
                return None;
            }
            let (a, b, c) = (q[0].0, q[1].0, q[2].0);
            // In the frame (x, y, h): the triangle's normal, whose h part is
            // the image's orientation; nearly edge-on counts as folded.
            let [u, w] =
                [1, 2].map(|i| DVec3::new(q[i].0.x - a.x, q[i].0.y - a.y, q[i].1 - q[0].1));
            let normal = u.cross(w);
            let det = normal.z;
            let reach = (hi - lo).max_element().max(frame.hi.x - frame.lo.x);
            let far = q.iter().all(|v| v.1 > limit) || q.iter().all(|v| v.1 < -limit);
            if far
                || !(det > 0.0
                    && det * det > 1e-12 * normal.length_squared()
                    && det > 1e-13 * reach * reach)
            {
                // Folded, or another layer of O: left out of the patch, so
                // the edges it shares with it are border.
                continue;
            }
            marks.inside[t as usize] = now;
            if let Some(h) = frame.clipped_height(q) {
                height = height.max(h);
            }
            if !covered {
                let w = [
                    (b - a).perp_dot(centroid - a),
                    (c - b).perp_dot(centroid - b),
                    (a - c).perp_dot(centroid - c),
                ];
                covered = w.iter().all(|x| *x >= 0.0);
            }
            for k in 0..3u32 {
                let corner = 3 * t + k;
                let o = self.opposite[corner as usize];
                let vert = |c: u32| self.mesh.triangles[(c / 3) as usize][(c % 3) as usize];
                if o == NONE || vert(next(corner)) == vert(next(o)) {
                    let (e0, e1) = (q[(k as usize + 1) % 3].0, q[(k as usize + 2) % 3].0);
                    if frame.segment_meets(e0, e1) {
                        return None;
                    }
                    continue;
                }
                let nb = o / 3;
                marks.pending.push((t, k));
                if marks.stamp[nb as usize] != now {
                    marks.stamp[nb as usize] = now;
                    marks.queue.push(nb);
                }
            }
        }
        // Edges to a triangle left out are border too.
        for &(t, k) in &marks.pending {
            let nb = self.opposite[(3 * t + k) as usize] / 3;
            if marks.inside[nb as usize] != now {
                let tri = self.mesh.triangles[t as usize];
                let [e0, e1] = [1, 2].map(|j| {
                    let v = tri[(k as usize + j) % 3];
                    frame.project(self.mesh.positions[v as usize]).0
                });
                if frame.segment_meets(e0, e1) {
                    return None;
                }
            }
        }
        covered.then_some(height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::MeshDistance;

    /// A height field z = f(x, y) over [-1, 1]², `n` cells a side, as
    /// counter-clockwise triangles seen from +z.
    fn height_field(n: usize, f: impl Fn(f32, f32) -> f32) -> TriMesh {
        let at = |i: usize| -1.0 + 2.0 * i as f32 / n as f32;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                positions.push(Vec3::new(at(i), at(j), f(at(i), at(j))));
            }
        }
        let v = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        TriMesh::new(positions, triangles)
    }

    fn bumps(x: f32, y: f32) -> f32 {
        0.05 * (3.0 * x).sin() * (2.0 * y).cos()
    }

    fn seeds(target: &MeshDistance, p: [Vec3; 3]) -> [u32; 3] {
        p.map(|v| target.nearest(v).1)
    }

    /// max d(y, O) over a dense sampling of triangle p.
    fn sampled(target: &MeshDistance, p: [Vec3; 3]) -> f32 {
        let n = 120;
        let mut worst = 0.0f32;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                worst = worst.max(target.distance(p[0] + (p[1] - p[0]) * u + (p[2] - p[0]) * v));
            }
        }
        worst
    }

    /// Over a smooth patch the bound holds against dense sampling and is
    /// close to it (the surface is nearly parallel to the triangle).
    #[test]
    fn bound_holds_and_is_tight_over_a_smooth_patch() {
        let o = height_field(40, bumps);
        let (target, projection) = (MeshDistance::new(&o), Projection::new(&o));
        for (k, p) in [
            [
                Vec3::new(-0.5, -0.4, 0.02),
                Vec3::new(0.3, -0.5, 0.0),
                Vec3::new(0.0, 0.45, 0.03),
            ],
            [
                Vec3::new(0.1, 0.1, -0.01),
                Vec3::new(0.14, 0.1, -0.01),
                Vec3::new(0.1, 0.15, 0.0),
            ],
        ]
        .into_iter()
        .enumerate()
        {
            let b = projection
                .bound(p, seeds(&target, p), 4096, f32::INFINITY)
                .expect("covered");
            let s = sampled(&target, p);
            assert!(b >= s, "case {k}: bound {b} < sampled {s}");
            assert!(b <= 1.1 * s, "case {k}: bound {b} vs sampled {s}");
        }
    }

    /// Two parallel sheets: the bound comes from the nearer one.
    #[test]
    fn the_nearest_valid_patch_decides() {
        let mut o = height_field(10, |_, _| 0.0);
        let far = height_field(10, |_, _| 0.5);
        let base = o.positions.len() as u32;
        o.positions.extend(&far.positions);
        o.triangles
            .extend(far.triangles.iter().map(|t| t.map(|v| v + base)));
        let o = TriMesh::new(o.positions, o.triangles);
        let projection = Projection::new(&o);
        let p = [
            Vec3::new(-0.5, -0.5, 0.1),
            Vec3::new(0.5, -0.5, 0.1),
            Vec3::new(0.0, 0.5, 0.12),
        ];
        // One seed on each sheet, under the triangle (cell (5, 5)).
        let b = projection
            .bound(p, [310, 110, 310], 4096, f32::INFINITY)
            .expect("covered");
        assert!((0.12..0.1201).contains(&b), "{b}");
    }

    /// No bound where the patch folds under the triangle, where the
    /// triangle reaches past the surface's border, or past the size cap.
    #[test]
    fn folds_borders_and_the_cap_refuse() {
        let p = [
            Vec3::new(-0.5, -0.4, 0.02),
            Vec3::new(0.3, -0.5, 0.0),
            Vec3::new(0.0, 0.45, 0.03),
        ];
        let mut folded = height_field(10, bumps);
        // The centre vertex pushed past its neighbours: its fan overlaps itself.
        folded.positions[5 * 11 + 5].x += 0.35;
        let target = MeshDistance::new(&folded);
        let s = seeds(&target, p);
        assert_eq!(
            Projection::new(&folded).bound(p, s, 4096, f32::INFINITY),
            None
        );

        let o = height_field(10, bumps);
        let (target, projection) = (MeshDistance::new(&o), Projection::new(&o));
        let past = [p[0], Vec3::new(1.2, -0.5, 0.0), p[2]];
        assert_eq!(
            projection.bound(past, seeds(&target, past), 4096, f32::INFINITY),
            None
        );
        assert!(
            projection
                .bound(p, seeds(&target, p), 4096, f32::INFINITY)
                .is_some()
        );
        assert_eq!(
            projection.bound(p, seeds(&target, p), 20, f32::INFINITY),
            None
        );
    }
}
