//! §2.2: local finite elements on the point set. Each point's neighbours are
//! projected to its tangent plane and Delaunay-triangulated; the triangle fan
//! around the point, taken back to 3D, gives row i of Ã (eq. 5), which is then
//! symmetrised (eq. 6) and given zero row sums (eq. 7).

use glam::Vec3;
use rayon::prelude::*;
use spade::{DelaunayTriangulation, Point2, Triangulation};
use sprs::{CsMat, TriMat};

use super::classifier::Classification;
use super::neighbourhood::Neighbourhoods;
use crate::progress::{Cancelled, Progress};

/// The fan neighbours j of point i and the preliminary entries Ã_ij (eq. 5),
/// integrated over the fan's 3D triangles with C(T) the mean nodal classifier
/// raised to `contrast` (1 is the paper's literal eq. 5; see [`super::AmgOptions::contrast`]).
pub fn fan_row(
    i: usize,
    points: &[Vec3],
    nb: &Neighbourhoods,
    c: &Classification,
    contrast: f64,
) -> Vec<(u32, f64)> {
    let f = c.frames[i];
    let (e0, e1) = (f.e0.as_dvec3(), f.e1.as_dvec3());
    let x = points[i].as_dvec3();
    let mut tri: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    // Local index of each triangulation vertex: 0 is x_i, k+1 is lists[i][k].
    let mut local: Vec<usize> = Vec::with_capacity(nb.lists[i].len() + 1);
    let members = std::iter::once(i as u32).chain(nb.lists[i].iter().copied());
    for (k, j) in members.enumerate() {
        let d = points[j as usize].as_dvec3() - x;
        let Ok(h) = tri.insert(Point2::new(d.dot(e0), d.dot(e1))) else {
            continue;
        };
        // Coincident projections share one vertex: the first point keeps it.
        if h.index() == local.len() {
            local.push(k);
        }
    }
    let Some(v0) = tri
        .vertices()
        .next()
        .filter(|_| !local.is_empty() && local[0] == 0)
    else {
        return Vec::new();
    };
    let global = |h: spade::handles::FixedVertexHandle| -> u32 {
        let k = local[h.index()];
        if k == 0 { i as u32 } else { nb.lists[i][k - 1] }
    };
    let mut row: Vec<(u32, f64)> = Vec::new();
    for e in v0.out_edges() {
        if e.face().as_inner().is_none() {
            continue;
        }
        let (a, b) = (global(e.to().fix()), global(e.next().to().fix()));
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
        .map(|i| {
            if progress.is_cancelled() {
                Vec::new()
            } else {
                fan_row(i, points, nb, c, contrast)
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
