//! Sampling a mesh's solid at the speed of a voxelizer (§2's volume buffer
//! S, eq. 2): the k³ sub-samples of every voxel lie on rows along x, and one
//! pass per row finds where the row pierces the surface (exact crossings,
//! each signed by its triangle's orientation). The winding number of a
//! sub-sample is the signed count of the crossings beyond it, which for a
//! closed mesh is exactly the generalised winding number the general sampler
//! evaluates point by point, so S is the same. Any other mesh (open,
//! non-manifold, faces that disagree) is closed first by [`super::caps`]:
//! its generalised winding number is the capped mesh's integer one minus
//! the caps' solid angle over 4π, which matters (can move a sub-sample
//! across ½) only on rows near a cap, where it is computed at a few
//! sub-samples per row (within a stated error) and carried along it between
//! them by a bound on its gradient (Biot–Savart over the loops). A row passing within round-off of an edge or a vertex of the
//! projected surface would count a crossing twice or not at all: its
//! sub-samples are classified point by point instead, by the solid itself.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::caps::{Caps, Eval, FINER, close};
use super::sampling::{Grid, sub_offset};
use crate::geom::{TriMesh, Volume};
use crate::implicit::Implicit;
use crate::progress::{Cancelled, Progress};

/// Whether rows can sample `mesh`'s solid: any mesh with a triangle, since
/// its boundary is capped whatever its connectivity (see [`super::caps`]).
pub fn applies(mesh: &TriMesh) -> bool {
    close(mesh).is_some()
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
    let Some((mesh, caps)) = close(mesh) else {
        return super::sampling::sample_implicit(solid, resolution, margin, supersample, progress);
    };
    let mesh = &mesh;
    // The caps' fans close the mesh after its own triangles.
    let first_cap = mesh.triangles.len() - caps.triangles();
    let grid = Grid::around(solid.bounds(), resolution, margin);
    let Grid { dims, h, .. } = grid;
    let k = supersample.max(1);
    let [nx, ny, nz] = dims;
    let [xs, ys, zs] = sub_samples(&grid, k);
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
            // The rows near a cap, and what cap-free balls know of them.
            let layer = &zs[z * k..(z + 1) * k];
            let near: Vec<bool> = (0..k * ys.len())
                .map(|i| !caps.far_from_row(ys[i % ys.len()] as f64, layer[i / ys.len()] as f64))
                .collect();
            let known = match near.contains(&true) {
                true => known_by_balls(&caps, &xs, &ys, layer, &near),
                false => Vec::new(),
            };
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
                    let (y, z) = (ys[iy] as f64, sz);
                    // Winding beyond the sample = total − crossings up to it.
                    let total: i32 = row.iter().map(|c| c.1).sum();
                    let (mut next, mut before) = (0, 0);
                    let row_at = (jz * ys.len() + iy) * xs.len();
                    if !near[jz * ys.len() + iy] {
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
                    // the caps there (g's error, gradient bound, distance).
                    let mut anchor: Option<(f64, f64, i32, Eval)> = None;
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
                        if let Some(&round) = known.get(row_at + ix).filter(|&&r| r != UNKNOWN) {
                            line[ix / k] += u16::from(w != i32::from(round));
                            continue;
                        }
                        // Within dx of the anchor the caps' winding moves by at
                        // most its drift (`Eval::drift`): the side of ½ is
                        // kept while that stays under the anchor's margin
                        // (less the far field's error).
                        let known = anchor.and_then(|(ax, ag, asurf, e)| {
                            let margin = (ag + (surface - asurf) as f64).abs() - 0.5;
                            let m = margin.abs() - 1e-9 - e.error;
                            (m > 0.0 && e.drift(x - ax) < m).then_some(margin > 0.0)
                        });
                        let inside = known.unwrap_or_else(|| {
                            let q = DVec3::new(x, y, z);
                            // Where the far field could tip it, a finer one,
                            // then every cap exactly.
                            let tips =
                                |e: &Eval| ((w as f64 - e.value).abs() - 0.5).abs() <= e.error;
                            let mut e = caps.eval(q, false);
                            if tips(&e) {
                                e = caps.eval_opened(q, FINER);
                            }
                            if tips(&e) {
                                e = caps.eval(q, true);
                            }
                            let g = w as f64 - e.value;
                            anchor = Some((x, g, surface, e));
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

/// The sub-sample coordinates along each axis of `grid` (k per voxel),
/// computed as the general sampler computes its sample points (voxel node,
/// then offset).
fn sub_samples(grid: &Grid, k: usize) -> [Vec<f32>; 3] {
    let Grid { dims, origin, h } = *grid;
    [0, 1, 2].map(|axis| {
        (0..dims[axis] * k)
            .map(|i| (origin[axis] + h * (i / k) as f32) + sub_offset(i % k, k, h))
            .collect()
    })
}

/// No ball decided this sub-sample.
const UNKNOWN: i8 = i8::MIN;

/// Blocks of sub-samples are tried from this many along x and y down to 2.
const TOP_BLOCK: usize = 32;

/// For each sub-sample of one layer's near rows (`near`, by sub-slice then
/// row; `layer` the sub-slices' z), the integer n that the caps' Ω/4π is
/// certified to be within ½ of, or [`UNKNOWN`]: then the open mesh is
/// inside there exactly where the closed mesh's w ≠ n (|w − Ω/4π| ≥ ½).
/// A block is known whole from one evaluation at its centre when the ball
/// that holds it crosses no cap (within the evaluation's clearance, Ω/4π
/// moves by at most its drift in any direction) and that drift keeps the
/// value between the same half-integers; else its quarters are tried. Rows
/// meet a ball along its diameter only, so where the margin allows a ball
/// several sub-samples wide this costs one evaluation where a row's anchors
/// (one per row) would cost one per row crossing it.
fn known_by_balls(caps: &Caps, xs: &[f32], ys: &[f32], layer: &[f32], near: &[bool]) -> Vec<i8> {
    let (sx, sy) = (xs.len(), ys.len());
    let mut known = vec![UNKNOWN; layer.len() * sy * sx];
    let (z_lo, z_hi) = (layer[0] as f64, layer[layer.len() - 1] as f64);
    let any_near = |y0: usize, y1: usize| {
        (0..layer.len()).any(|jz| near[jz * sy + y0..jz * sy + y1].contains(&true))
    };
    let mut stack: Vec<[usize; 4]> = Vec::new();
    for y0 in (0..sy).step_by(TOP_BLOCK) {
        for x0 in (0..sx).step_by(TOP_BLOCK) {
            stack.push([x0, (x0 + TOP_BLOCK).min(sx), y0, (y0 + TOP_BLOCK).min(sy)]);
        }
    }
    while let Some([x0, x1, y0, y1]) = stack.pop() {
        if !any_near(y0, y1) {
            continue;
        }
        let (xa, xb) = (xs[x0] as f64, xs[x1 - 1] as f64);
        let (ya, yb) = (ys[y0] as f64, ys[y1 - 1] as f64);
        let center = DVec3::new(xa + xb, ya + yb, z_lo + z_hi) * 0.5;
        let radius = 0.5 * DVec3::new(xb - xa, yb - ya, z_hi - z_lo).length();
        let e = caps.eval_cleared(center);
        let round = e.value.round();
        let moved = e.drift(radius) + e.error;
        if radius < e.clearance
            && (e.value - round).abs() + moved < 0.5 - 1e-9
            && round.abs() < 100.0
        {
            for jz in 0..layer.len() {
                for iy in y0..y1 {
                    if near[jz * sy + iy] {
                        let row = (jz * sy + iy) * sx;
                        known[row + x0..row + x1].fill(round as i8);
                    }
                }
            }
        } else if x1 - x0 > 2 || y1 - y0 > 2 {
            let xm = if x1 - x0 > 2 { (x0 + x1) / 2 } else { x1 };
            let ym = if y1 - y0 > 2 { (y0 + y1) / 2 } else { y1 };
            for (a, b) in [(x0, xm), (xm, x1)] {
                for (c, d) in [(y0, ym), (ym, y1)] {
                    if a < b && c < d {
                        stack.push([a, b, c, d]);
                    }
                }
            }
        }
    }
    known
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
    use crate::voxel::caps::solid_angle;
    use crate::voxel::sampling::sample_implicit;

    /// Every sub-sample a ball decides has the caps' exact Ω/4π within ½ of
    /// the integer the ball gave it, on the open torus's layers; most of
    /// the near rows' sub-samples are decided so.
    #[test]
    fn balls_certify_what_they_decide() {
        let open = crate::voxel::caps::tests::holed_torus(300);
        let (_, caps) = close(&open).unwrap();
        let grid = Grid::around(open.bounds(), 20, 0.2);
        let k = 3;
        let [xs, ys, zs] = sub_samples(&grid, k);
        let (mut decided, mut near_samples) = (0, 0);
        for z in 0..grid.dims[2] {
            let layer = &zs[z * k..(z + 1) * k];
            let near: Vec<bool> = (0..k * ys.len())
                .map(|i| !caps.far_from_row(ys[i % ys.len()] as f64, layer[i / ys.len()] as f64))
                .collect();
            let known = known_by_balls(&caps, &xs, &ys, layer, &near);
            for (i, &n) in known.iter().enumerate() {
                let (ix, row) = (i % xs.len(), i / xs.len());
                let (iy, jz) = (row % ys.len(), row / ys.len());
                near_samples += usize::from(near[row]);
                if n == UNKNOWN {
                    continue;
                }
                assert!(near[row], "only near rows are decided");
                decided += 1;
                let q = DVec3::new(xs[ix] as f64, ys[iy] as f64, layer[jz] as f64);
                let exact = caps.eval(q, true).value;
                assert!((exact - f64::from(n)).abs() < 0.5, "{q}: {exact} vs {n}");
            }
        }
        assert!(
            decided * 10 > near_samples * 9,
            "{decided} of {near_samples}"
        );
    }

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
        // Open: a band of the torus's faces taken away leaves two loops,
        // and a face that disagrees with its neighbours: its edges are a
        // boundary loop of multiplicity two, capped like a hole.
        let open = crate::voxel::caps::tests::holed_torus(300);
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
    }
}
