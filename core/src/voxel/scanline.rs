//! Sampling a mesh's solid at the speed of a voxelizer (§2's volume buffer
//! S, eq. 2): the k³ sub-samples of every voxel lie on rows along x, and one
//! pass per row finds where the row pierces the surface (exact crossings,
//! each signed by its triangle's orientation). The winding number of a
//! sub-sample is the signed count of the crossings beyond it, which for a
//! closed mesh is exactly the generalised winding number the general sampler
//! evaluates point by point, so S is the same. An open mesh is closed first,
//! each boundary loop capped by a fan to its centroid: its generalised
//! winding number is the capped mesh's integer one minus the caps' solid
//! angle over 4π, which matters (can move a sub-sample across ½) only near a
//! cap, where it is computed exactly at a few sub-samples per row and carried
//! along it between them by a bound on its gradient (Biot–Savart over the
//! loop). A row passing within round-off of an edge or a vertex of the
//! projected surface would count a crossing twice or not at all: its
//! sub-samples are classified point by point instead, by the solid itself.

use std::borrow::Cow;
use std::collections::HashMap;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::sampling::{Grid, sub_offset};
use crate::geom::{TriMesh, Volume};
use crate::implicit::Implicit;
use crate::progress::{Cancelled, Progress};

/// Whether rows can sample `mesh`'s solid: a manifold, consistently
/// oriented surface whose boundary edges (if any) form simple loops to cap.
pub fn applies(mesh: &TriMesh) -> bool {
    capped(mesh).is_some()
}

/// One boundary loop's cap, a fan from the loop's centroid, and the ball
/// outside which the cap's solid angle stays below 2π (so the capped mesh's
/// winding number classifies a sub-sample as the open mesh's does).
struct Cap {
    /// The boundary loop, closed (last point = first), in the surface's direction.
    ring: Vec<DVec3>,
    center: DVec3,
    reach: f64,
}

/// The signed solid angle of a triangle over 4π (Van Oosterom and Strackee),
/// its corners given from the viewpoint with their lengths.
fn solid_angle([(a, la), (b, lb), (c, lc)]: [(DVec3, f64); 3]) -> f64 {
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    num.atan2(den) / (2.0 * std::f64::consts::PI)
}

impl Cap {
    /// The cap's signed solid angle at `p` over 4π, the open mesh's winding
    /// number short of the capped one's: its fan runs against the loop.
    fn winding(&self, p: DVec3) -> f64 {
        let from = |v: DVec3| {
            let d = v - p;
            (d, d.length())
        };
        let c = from(self.center);
        let mut prev = from(self.ring[0]);
        let mut sum = 0.0;
        for &v in &self.ring[1..] {
            let next = from(v);
            sum += solid_angle([next, prev, c]);
            prev = next;
        }
        sum
    }

    /// At `p`: a bound on the gradient of [`Cap::winding`] off the cap, and
    /// the distance to the loop. The gradient of a solid angle is the
    /// Biot–Savart integral over the boundary, |∇Ω| ≤ ∮ |dr| / |r − p|², at
    /// most Σ over the loop's edges of length / distance².
    fn gradient_bound(&self, p: DVec3) -> (f64, f64) {
        let (mut sum, mut nearest) = (0.0, f64::INFINITY);
        for e in self.ring.windows(2) {
            let (a, ab) = (e[0], e[1] - e[0]);
            let len2 = ab.length_squared();
            let t = ((p - a).dot(ab) / len2.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            let d2 = (a + t * ab).distance_squared(p);
            sum += len2.sqrt() / d2;
            nearest = nearest.min(d2);
        }
        (sum / (4.0 * std::f64::consts::PI), nearest.sqrt())
    }
}

/// `mesh` with each boundary loop capped by a fan to the loop's centroid,
/// oriented with the surface, and the caps; `None` when the surface is not
/// manifold and consistently oriented or its boundary is not simple loops.
fn capped(mesh: &TriMesh) -> Option<(Cow<'_, TriMesh>, Vec<Cap>)> {
    if mesh.triangles.is_empty()
        || mesh
            .triangles
            .iter()
            .any(|t| t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
    {
        return None;
    }
    // Edges sorted by their two ends, then direction (packed in 64 bits,
    // so indices below 2³¹: any mesh that fits in memory): a directed edge
    // used twice is an edge of three or more triangles or of two that
    // disagree on orientation (then the signed crossings are no winding
    // number); an edge used once is border. One sort of 3n keys.
    if mesh.positions.len() > (u32::MAX >> 1) as usize {
        return None;
    }
    let key = |a: u32, b: u32| (a.min(b) as u64) << 32 | (a.max(b) as u64) << 1 | u64::from(a > b);
    let mut edges: Vec<u64> = mesh
        .triangles
        .par_iter()
        .flat_map_iter(|t| [key(t[0], t[1]), key(t[1], t[2]), key(t[2], t[0])])
        .collect();
    edges.par_sort_unstable();
    if edges.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    let border: Vec<(u32, u32)> = edges
        .chunk_by(|x, y| x >> 1 == y >> 1)
        .filter(|same| same.len() == 1)
        .map(|e| {
            let (lo, hi) = ((e[0] >> 32) as u32, (e[0] as u32) >> 1);
            if e[0] & 1 == 1 { (hi, lo) } else { (lo, hi) }
        })
        .collect();
    if border.is_empty() {
        return Some((Cow::Borrowed(mesh), Vec::new()));
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in &border {
        if next.insert(a, b).is_some() {
            return None;
        }
    }
    let mut closed = TriMesh::new(mesh.positions.clone(), mesh.triangles.clone());
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut caps = Vec::new();
    for start in starts {
        if seen.contains(&start) {
            continue;
        }
        let mut ring = vec![start];
        seen.insert(start);
        let mut v = *next.get(&start)?;
        while v != start {
            if !seen.insert(v) {
                return None;
            }
            ring.push(v);
            v = *next.get(&v)?;
        }
        let pos = |v: u32| mesh.positions[v as usize].as_dvec3();
        let center = ring.iter().map(|&v| pos(v)).sum::<DVec3>() / ring.len() as f64;
        let c = closed.positions.len() as u32;
        closed.positions.push(center.as_vec3());
        for (i, &a) in ring.iter().enumerate() {
            let b = ring[(i + 1) % ring.len()];
            // The surface runs a → b; its cap runs b → a.
            closed.triangles.push([b, a, c]);
        }
        let mut loop_points: Vec<DVec3> = ring.iter().map(|&v| pos(v)).collect();
        loop_points.push(pos(ring[0]));
        let radius = loop_points
            .iter()
            .map(|v| v.distance(center))
            .fold(0.0, f64::max);
        let area: f64 = loop_points
            .windows(2)
            .map(|e| 0.5 * (e[0] - center).cross(e[1] - center).length())
            .sum();
        // A triangle's |solid angle| is at most its area over the square of
        // its distance, so beyond `reach` the caps' sum stays under 2π.
        let reach = 1.01 * (radius + (area / (2.0 * std::f64::consts::PI)).sqrt()) + 1e-9;
        caps.push(Cap {
            ring: loop_points,
            center,
            reach,
        });
    }
    Some((Cow::Owned(closed), caps))
}

/// Samples the solid of `mesh` (which `solid` is, for rows that need a
/// point-by-point answer) like [`super::sampling::sample_implicit`]: the
/// same grid, the same sub-samples, the same occupancy. `mesh` must be one
/// that [`applies`] accepts; others are sampled point by point.
pub fn sample_by_rows(
    solid: &dyn Implicit,
    mesh: &TriMesh,
    resolution: usize,
    margin: f32,
    supersample: usize,
    progress: &Progress,
) -> Result<Volume, Cancelled> {
    progress.stage("sampling");
    let Some((mesh, caps)) = capped(mesh) else {
        return super::sampling::sample_implicit(solid, resolution, margin, supersample, progress);
    };
    let mesh = &mesh;
    // The caps' fans close the mesh after its own triangles.
    let first_cap = mesh.triangles.len() - caps.iter().map(|c| c.ring.len() - 1).sum::<usize>();
    let grid = Grid::around(solid.bounds(), resolution, margin);
    let Grid { dims, origin, h } = grid;
    let k = supersample.max(1);
    let [nx, ny, nz] = dims;
    // The sub-sample coordinates along each axis, computed as the general
    // sampler computes its sample points (voxel node, then offset).
    let coords = |axis: usize, n: usize| -> Vec<f32> {
        (0..n * k)
            .map(|i| (origin[axis] + h * (i / k) as f32) + sub_offset(i % k, k, h))
            .collect()
    };
    let (xs, ys, zs) = (coords(0, nx), coords(1, ny), coords(2, nz));
    let rows_spanned = |lo: f32, hi: f32, at: &[f32]| {
        let first = at.partition_point(|&c| c < lo);
        let end = at.partition_point(|&c| c <= hi);
        first..end
    };
    // Triangles by the z rows their extent spans.
    let mut by_z: Vec<Vec<u32>> = vec![Vec::new(); zs.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let p = tri.map(|v| mesh.positions[v as usize]);
        let (lo, hi) = (
            p[0].z.min(p[1].z).min(p[2].z),
            p[0].z.max(p[1].z).max(p[2].z),
        );
        for iz in rows_spanned(lo, hi, &zs) {
            by_z[iz].push(t as u32);
        }
    }
    let per_voxel = (k * k * k) as f32;
    let mut data = vec![0.0f32; nx * ny * nz];
    let done = std::sync::atomic::AtomicUsize::new(0);
    data.par_chunks_mut(nx * ny)
        .enumerate()
        .try_for_each(|(z, slice)| {
            progress.check()?;
            let mut counts = vec![0u16; nx * ny];
            // Crossings: x, sign, and whether a cap's (not the mesh's own).
            let mut rows: Vec<Vec<(f64, i32, bool)>> = vec![Vec::new(); ys.len()];
            let mut degenerate = vec![false; ys.len()];
            for jz in 0..k {
                let iz = z * k + jz;
                let sz = zs[iz] as f64;
                rows.iter_mut().for_each(Vec::clear);
                degenerate.iter_mut().for_each(|d| *d = false);
                for &t in &by_z[iz] {
                    let p = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
                    let (lo, hi) = (
                        p[0].y.min(p[1].y).min(p[2].y),
                        p[0].y.max(p[1].y).max(p[2].y),
                    );
                    for iy in rows_spanned(lo, hi, &ys) {
                        match crossing(&p, ys[iy] as f64, sz, h as f64) {
                            Crossing::None => {}
                            Crossing::At(x, sign) => {
                                rows[iy].push((x, sign, t as usize >= first_cap))
                            }
                            Crossing::Degenerate => degenerate[iy] = true,
                        }
                    }
                }
                for (iy, row) in rows.iter_mut().enumerate() {
                    let y = iy / k;
                    let line = &mut counts[y * nx..(y + 1) * nx];
                    if degenerate[iy] {
                        for (ix, &sx) in xs.iter().enumerate() {
                            let q = Vec3::new(sx, ys[iy], zs[iz]);
                            line[ix / k] += u16::from(solid.value(q) < 0.0);
                        }
                        continue;
                    }
                    row.sort_by(|a, b| a.0.total_cmp(&b.0));
                    // The caps near enough this row to matter.
                    let (y, z) = (ys[iy] as f64, sz);
                    let near: Vec<&Cap> = caps
                        .iter()
                        .filter(|c| (c.center.y - y).hypot(c.center.z - z) < c.reach)
                        .collect();
                    // Winding beyond the sample = total − crossings up to it.
                    let total: i32 = row.iter().map(|c| c.1).sum();
                    let (mut next, mut before) = (0, 0);
                    if near.is_empty() {
                        // Between two crossings the winding is constant: the
                        // sub-samples from the first at or past one crossing
                        // to the first at or past the next fill their voxels.
                        let mut start = 0;
                        for c in row.iter() {
                            let end = xs.partition_point(|&sx| (sx as f64) < c.0);
                            if total != before {
                                fill(line, start, end, k);
                            }
                            before += c.1;
                            start = end;
                        }
                        if total != before {
                            fill(line, start, xs.len(), k);
                        }
                        continue;
                    }
                    // Near a cap the open mesh's winding number g = w − the
                    // caps' solid angle over 4π. It is continuous across a cap
                    // (both jump by the crossing) and jumps by the crossing at
                    // the mesh's own, so from a sub-sample where it was
                    // computed (the anchor) it is known up to the caps'
                    // drift: only sub-samples where that leaves the side of
                    // ½ open are computed.
                    let surface_total: i32 = row.iter().filter(|c| !c.2).map(|c| c.1).sum();
                    let mut surface_before = 0;
                    // Anchor: x, g there, the surface's winding there, and
                    // the caps' gradient bound and least distance there.
                    let mut anchor: Option<(f64, f64, i32, f64, f64)> = None;
                    for (ix, &sx) in xs.iter().enumerate() {
                        let x = sx as f64;
                        while next < row.len() && row[next].0 <= x {
                            before += row[next].1;
                            if !row[next].2 {
                                surface_before += row[next].1;
                            }
                            next += 1;
                        }
                        let (w, surface) = (total - before, surface_total - surface_before);
                        // Within dx of the anchor the caps' winding moves by at
                        // most S·dx / (1 − dx/d) (S the gradient bound, d the
                        // least distance to a loop there): the side of ½ is
                        // kept while that stays under the anchor's margin m,
                        // for dx < m / (S + m/d).
                        let known = anchor.and_then(|(ax, ag, asurf, slope, d)| {
                            let margin = (ag + (surface - asurf) as f64).abs() - 0.5;
                            let m = margin.abs() - 1e-9;
                            (m > 0.0 && x - ax < m / (slope + m / d)).then_some(margin > 0.0)
                        });
                        let inside = known.unwrap_or_else(|| {
                            let q = DVec3::new(x, y, z);
                            let (mut open, mut slope, mut d) = (0.0, 0.0, f64::INFINITY);
                            for c in &near {
                                open += c.winding(q);
                                let (s, dc) = c.gradient_bound(q);
                                slope += s;
                                d = d.min(dc);
                            }
                            let g = w as f64 - open;
                            anchor = Some((x, g, surface, slope, d));
                            g.abs() >= 0.5
                        });
                        line[ix / k] += u16::from(inside);
                    }
                }
            }
            for (v, &c) in slice.iter_mut().zip(&counts) {
                *v = c as f32 / per_voxel;
            }
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress.set_fraction(d as f32 / nz as f32);
            Ok(())
        })?;
    Ok(grid.volume(data))
}

/// Counts the sub-samples `start..end` of a row (k per voxel) in their voxels.
fn fill(line: &mut [u16], start: usize, end: usize, k: usize) {
    if start >= end {
        return;
    }
    let (first, last) = (start / k, (end - 1) / k);
    if first == last {
        line[first] += (end - start) as u16;
        return;
    }
    line[first] += (k * (first + 1) - start) as u16;
    for v in &mut line[first + 1..last] {
        *v += k as u16;
    }
    line[last] += (end - last * k) as u16;
}

/// Where the row along x through (y, z) meets a triangle.
enum Crossing {
    None,
    /// At this x, with the sign of the triangle's orientation seen along x.
    At(f64, i32),
    /// Within round-off of an edge or a vertex (or of an edge-on triangle).
    Degenerate,
}

fn crossing(p: &[Vec3; 3], y: f64, z: f64, h: f64) -> Crossing {
    let q = p.map(|v| [v.x as f64, v.y as f64, v.z as f64]);
    // Twice the signed area of (u, v, (y, z)) in the yz plane.
    let orient = |u: [f64; 3], v: [f64; 3]| (v[1] - u[1]) * (z - u[2]) - (v[2] - u[2]) * (y - u[1]);
    let w = [orient(q[1], q[2]), orient(q[2], q[0]), orient(q[0], q[1])];
    // An edge function is |edge| times the distance to the edge's line.
    let near = [(1, 2), (2, 0), (0, 1)].map(|(a, b)| {
        let len = ((q[b][1] - q[a][1]).powi(2) + (q[b][2] - q[a][2]).powi(2)).sqrt();
        1e-6 * h * len.max(f64::MIN_POSITIVE)
    });
    let positive = (0..3).any(|i| w[i] > near[i]);
    let negative = (0..3).any(|i| w[i] < -near[i]);
    if positive && negative {
        return Crossing::None;
    }
    if (0..3).any(|i| w[i].abs() <= near[i]) {
        return Crossing::Degenerate;
    }
    let area = w[0] + w[1] + w[2];
    let x = (w[0] * q[0][0] + w[1] * q[1][0] + w[2] * q[2][0]) / area;
    Crossing::At(x, if area > 0.0 { 1 } else { -1 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::MeshSolid;
    use crate::voxel::sampling::sample_implicit;

    /// The rows give the very occupancy the winding number gives, sample for
    /// sample, whichever way the mesh faces and with holes in it.
    #[test]
    fn rows_equal_the_winding_number_closed_or_open() {
        let torus = crate::builtins::torus(1.0, 0.4, 40, 20);
        let mut inward = torus.clone();
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        let p = Progress::new();
        // Open: a band of the torus's faces taken away leaves two loops.
        let mut open = torus.clone();
        open.triangles.drain(0..80);
        for mesh in [&torus, &inward, &open] {
            assert!(applies(mesh));
            let solid = MeshSolid::new(mesh);
            let rows = sample_by_rows(&solid, mesh, 24, 0.2, 3, &p).unwrap();
            let points = sample_implicit(&solid, 24, 0.2, 3, &p).unwrap();
            assert_eq!(
                (rows.dims, rows.origin, rows.spacing),
                (points.dims, points.origin, points.spacing)
            );
            let differ: Vec<f32> = rows
                .data
                .iter()
                .zip(&points.data)
                .filter(|(a, b)| a != b)
                .map(|(a, b)| (a - b).abs())
                .collect();
            if std::ptr::eq(mesh, &open) {
                // Across the holes the point sampler's winding number is a
                // fast approximation (within about 0.01), and in the gap the
                // exact one stays near ½ over a wide region: where the two
                // disagree, the rows agree with the exact sum of every
                // triangle's solid angle.
                assert!(
                    differ.len() * 100 < rows.data.len(),
                    "{} differ",
                    differ.len()
                );
                let exact = |q: Vec3| -> f32 {
                    let w: f64 = mesh
                        .triangles
                        .iter()
                        .map(|t| {
                            solid_angle(t.map(|v| {
                                let d = (mesh.positions[v as usize] - q).as_dvec3();
                                (d, d.length())
                            }))
                        })
                        .sum();
                    (w.abs() >= 0.5) as u8 as f32
                };
                let [nx, ny, _] = rows.dims;
                let h = rows.spacing.x;
                for (i, (a, b)) in rows.data.iter().zip(&points.data).enumerate() {
                    if a == b {
                        continue;
                    }
                    let node = rows.origin
                        + h * Vec3::new(
                            (i % nx) as f32,
                            (i / nx % ny) as f32,
                            (i / (nx * ny)) as f32,
                        );
                    let subs = (0..27).map(|s| {
                        let o = |j: usize| crate::voxel::sampling::sub_offset(j, 3, h);
                        node + Vec3::new(o(s % 3), o(s / 3 % 3), o(s / 9))
                    });
                    let want = subs.map(exact).sum::<f32>() / 27.0;
                    assert!(
                        (want - a).abs() < 1.5 / 27.0,
                        "voxel {i}: rows {a}, exact {want}, points {b}"
                    );
                }
            } else {
                assert!(
                    differ.is_empty(),
                    "{} of {} voxels",
                    differ.len(),
                    rows.data.len()
                );
            }
            assert!(rows.data.iter().any(|&v| v > 0.0 && v < 1.0));
        }
        // A mesh with a flipped face is left to the winding number.
        let mut flipped = torus.clone();
        flipped.triangles[0].swap(1, 2);
        assert!(!applies(&flipped));
    }
}
