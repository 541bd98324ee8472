//! §2.2: local finite elements on the point set. Each point's neighbours are
//! projected to its tangent plane and Delaunay-triangulated; the triangle fan
//! around the point, taken back to 3D, gives row i of Ã (eq. 5), which is then
//! symmetrised (eq. 6) and given zero row sums (eq. 7).
//!
//! Only the fan around x_i is used, so it is found without triangulating the
//! rest: inverting the projected neighbours about x_i (q ↦ q/|q|²) maps every
//! circle through x_i to a line, its inside to the side away from x_i. A
//! triangle (x_i, a, b) is Delaunay (its circumcircle holds no neighbour)
//! exactly when a'b' is an edge of the inverted points' convex hull with x_i
//! on the hull's side of it. A hull of k points per row replaces a Delaunay
//! triangulation per row (spade's took 2 of the mug's 3 s).

use glam::{DVec2, Vec3};
use rayon::prelude::*;
use sprs::{CsMat, TriMat};

use super::classifier::Classification;
use super::neighbourhood::Neighbourhoods;
use crate::progress::{Cancelled, Progress};

/// One worker's buffers, reused for every row.
#[derive(Default)]
pub struct FanScratch {
    /// Inverted projections, with the neighbour's place in the list and its index.
    inverted: Vec<(DVec2, u32, u32)>,
    hull: Vec<(DVec2, u32, u32)>,
}

/// One chain of Andrew's monotone hull over points sorted by x (lower chain
/// left to right, then upper chain right to left), counter-clockwise and
/// without collinear points; its last point starts the other chain.
fn half_hull<'a>(
    hull: &mut Vec<(DVec2, u32, u32)>,
    sorted: impl Iterator<Item = &'a (DVec2, u32, u32)>,
) {
    let floor = hull.len();
    for p in sorted {
        while hull.len() >= floor + 2 {
            let (a, b) = (hull[hull.len() - 2].0, hull[hull.len() - 1].0);
            if (b - a).perp_dot(p.0 - a) > 0.0 {
                break;
            }
            hull.pop();
        }
        hull.push(*p);
    }
    hull.pop();
}

/// The fan around x_i of the Delaunay triangulation of its projected
/// neighbourhood, as neighbour pairs (a, b) with (x_i, a, b) counter-clockwise
/// in the tangent frame. Neighbours projecting onto x_i or onto an earlier
/// neighbour are left out, as one triangulation vertex per position would.
fn delaunay_fan(
    i: usize,
    points: &[Vec3],
    nb: &Neighbourhoods,
    c: &Classification,
    scratch: &mut FanScratch,
) -> impl Iterator<Item = (u32, u32)> {
    let f = c.frames[i];
    let (e0, e1) = (f.e0.as_dvec3(), f.e1.as_dvec3());
    let x = points[i].as_dvec3();
    let FanScratch { inverted, hull } = scratch;
    inverted.clear();
    for (k, &j) in nb.lists[i].iter().enumerate() {
        let d = points[j as usize].as_dvec3() - x;
        let q = DVec2::new(d.dot(e0), d.dot(e1));
        let r2 = q.length_squared();
        if r2 > 0.0 && r2.is_finite() {
            inverted.push((q / r2, k as u32, j));
        }
    }
    // Sorted for the monotone chain; equal positions keep the earliest neighbour.
    inverted.sort_unstable_by(|a, b| {
        (a.0.x.total_cmp(&b.0.x))
            .then(a.0.y.total_cmp(&b.0.y))
            .then(a.1.cmp(&b.1))
    });
    inverted.dedup_by(|later, first| later.0 == first.0);
    hull.clear();
    if inverted.len() >= 2 {
        half_hull(hull, inverted.iter());
        half_hull(hull, inverted.iter().rev());
    }
    let n = hull.len();
    let hull = &*hull;
    (0..n).filter_map(move |e| {
        let (a, b) = (hull[e], hull[(e + 1) % n]);
        // x_i (the origin) on the hull's side of a'b': (b' − a') × (−a') = a' × b'.
        (a.0.perp_dot(b.0) > 0.0).then_some((a.2, b.2))
    })
}

/// The fan neighbours j of point i and the preliminary entries Ã_ij (eq. 5),
/// integrated over the fan's 3D triangles with C(T) the mean nodal classifier
/// raised to `contrast` (1 is the paper's literal eq. 5; see [`super::AmgOptions::contrast`]).
pub fn fan_row(
    i: usize,
    points: &[Vec3],
    nb: &Neighbourhoods,
    c: &Classification,
    contrast: f64,
    scratch: &mut FanScratch,
) -> Vec<(u32, f64)> {
    let x = points[i].as_dvec3();
    let mut row: Vec<(u32, f64)> = Vec::new();
    for (a, b) in delaunay_fan(i, points, nb, c, scratch) {
        let p = [
            x,
            points[a as usize].as_dvec3(),
            points[b as usize].as_dvec3(),
        ];
        // ∇Φ_j·∇Φ_k |T| = (E_j·E_k)/(4|T|), E_j the edge opposite vertex j.
        let edges = [p[2] - p[1], p[0] - p[2], p[1] - p[0]];
        let area = 0.5 * edges[2].cross(-edges[1]).length();
        if area.is_nan() || area <= 1e-300 {
            continue;
        }
        let mean = (c.value[i] + c.value[a as usize] + c.value[b as usize]) as f64 / 3.0;
        let ct = mean.powf(contrast);
        for (k, j) in [(1, a), (2, b)] {
            let v = ct * edges[0].dot(edges[k]) / (4.0 * area);
            match row.iter_mut().find(|(jj, _)| *jj == j) {
                Some(entry) => entry.1 += v,
                None => row.push((j, v)),
            }
        }
    }
    row
}

/// The symmetric stiffness matrix A of eq. 5–7 in CSR form.
pub fn stiffness(
    points: &[Vec3],
    nb: &Neighbourhoods,
    c: &Classification,
    contrast: f64,
    progress: &Progress,
) -> Result<CsMat<f64>, Cancelled> {
    let n = points.len();
    let rows: Vec<Vec<(u32, f64)>> = (0..n)
        .into_par_iter()
        .map_init(FanScratch::default, |scratch, i| {
            if progress.is_cancelled() {
                Vec::new()
            } else {
                fan_row(i, points, nb, c, contrast, scratch)
            }
        })
        .collect();
    progress.check()?;
    let nnz: usize = rows.iter().map(Vec::len).sum();
    let mut t = TriMat::with_capacity((n, n), 4 * nnz + n);
    for (i, row) in rows.iter().enumerate() {
        t.add_triplet(i, i, 0.0);
        for &(j, v) in row {
            let (j, h) = (j as usize, 0.5 * v);
            // Eq. 6: A_ij = ½(Ã_ij + Ã_ji); eq. 7: A_ii = −Σ_j A_ij.
            t.add_triplet(i, j, h);
            t.add_triplet(j, i, h);
            t.add_triplet(i, i, -h);
            t.add_triplet(j, j, -h);
        }
    }
    Ok(t.to_csr())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::amg::classifier::Frame;
    use crate::rng::Rng;
    use spade::{DelaunayTriangulation, Point2, Triangulation};

    /// The fan of point 0 in a full Delaunay triangulation (spade's, exact
    /// predicates) of the projected neighbourhood, as in the paper (§2.2).
    fn spade_fan(points: &[Vec3], list: &[u32]) -> Vec<(u32, u32)> {
        let mut tri: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
        let mut global = Vec::new();
        for j in std::iter::once(0).chain(list.iter().copied()) {
            let p = points[j as usize].as_dvec3();
            let h = tri.insert(Point2::new(p.x, p.y)).unwrap();
            if h.index() == global.len() {
                global.push(j);
            }
        }
        let v0 = tri.vertices().next().unwrap();
        let mut fan: Vec<(u32, u32)> = v0
            .out_edges()
            .filter(|e| e.face().as_inner().is_some())
            .map(|e| {
                (
                    global[e.to().fix().index()],
                    global[e.next().to().fix().index()],
                )
            })
            .collect();
        fan.sort_unstable();
        fan
    }

    #[test]
    fn the_hull_fan_is_the_delaunay_fan_inside_and_on_the_border() {
        let mut rng = Rng::new(7);
        for case in 0..300 {
            let k = 3 + case % 60;
            // Point 0 at the origin: inside its neighbours, or (every third
            // case) on their border, all neighbours to one side.
            let side = case % 3 == 0;
            let mut points = vec![Vec3::ZERO];
            for _ in 0..k {
                let x = rng.f32() * 2.0 - 1.0;
                let x = if side { x.abs() + 0.01 } else { x };
                points.push(Vec3::new(x, rng.f32() * 2.0 - 1.0, rng.f32() * 0.1));
            }
            // Duplicates of a neighbour and of point 0 (one vertex each).
            points.push(points[1]);
            points.push(Vec3::new(0.0, 0.0, 0.05));
            let list: Vec<u32> = (1..points.len() as u32).collect();
            let nb = Neighbourhoods {
                lists: vec![list.clone()],
                radii: vec![1.0],
            };
            let c = Classification {
                value: vec![1.0; points.len()],
                frames: vec![Frame {
                    e0: Vec3::X,
                    e1: Vec3::Y,
                    e2: Vec3::Z,
                }],
            };
            let mut fan: Vec<(u32, u32)> =
                delaunay_fan(0, &points, &nb, &c, &mut FanScratch::default()).collect();
            fan.sort_unstable();
            assert_eq!(fan, spade_fan(&points, &list), "case {case}, k = {k}");
            assert!(!fan.is_empty());
        }
    }
}
