//! Sampling a closed mesh's solid at the speed of a voxelizer (§2's volume
//! buffer S, eq. 2): the k³ sub-samples of every voxel lie on rows along x,
//! and one pass per row finds where the row pierces the surface (exact
//! crossings, each signed by its triangle's orientation). The winding number
//! of a sub-sample is the signed count of the crossings beyond it, which for
//! a closed mesh is exactly the generalised winding number the general
//! sampler evaluates point by point, so S is the same. A row passing within
//! round-off of an edge or a vertex of the projected surface would count a
//! crossing twice or not at all: its sub-samples are classified point by
//! point instead, by the solid itself.

use glam::Vec3;
use rayon::prelude::*;

use super::sampling::{Grid, sub_offset};
use crate::geom::{Topology, TriMesh, Volume};
use crate::implicit::Implicit;
use crate::progress::{Cancelled, Progress};

/// Whether `mesh` bounds a solid that rows can sample: closed (no border
/// edge), so every row's signed crossings add up to its winding number.
pub fn applies(mesh: &TriMesh) -> bool {
    !mesh.triangles.is_empty() && Topology::of(mesh).is_closed()
}

/// Samples the solid of the closed `mesh` (which `solid` is, for rows that
/// need a point-by-point answer) like [`super::sampling::sample_implicit`]:
/// the same grid, the same sub-samples, the same occupancy.
pub fn sample_closed(
    solid: &dyn Implicit,
    mesh: &TriMesh,
    resolution: usize,
    margin: f32,
    supersample: usize,
    progress: &Progress,
) -> Result<Volume, Cancelled> {
    progress.stage("sampling (scanlines)");
    let Grid { dims, origin, h } = Grid::around(solid.bounds(), resolution, margin);
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
            let mut rows: Vec<Vec<(f64, i32)>> = vec![Vec::new(); ys.len()];
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
                            Crossing::At(x, sign) => rows[iy].push((x, sign)),
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
                    // Winding beyond the sample = total − crossings up to it.
                    let total: i32 = row.iter().map(|c| c.1).sum();
                    let (mut next, mut before) = (0, 0);
                    for (ix, &sx) in xs.iter().enumerate() {
                        while next < row.len() && row[next].0 <= sx as f64 {
                            before += row[next].1;
                            next += 1;
                        }
                        line[ix / k] += u16::from(total - before != 0);
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
    Ok(Volume {
        dims,
        spacing: Vec3::splat(h),
        origin,
        data,
    })
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
    /// sample, whichever way the mesh faces.
    #[test]
    fn rows_equal_the_winding_number_on_closed_meshes() {
        let torus = crate::builtins::torus(1.0, 0.4, 40, 20);
        let mut inward = torus.clone();
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        let p = Progress::new();
        for mesh in [&torus, &inward] {
            assert!(applies(mesh));
            let solid = MeshSolid::new(mesh);
            let rows = sample_closed(&solid, mesh, 24, 0.2, 3, &p).unwrap();
            let points = sample_implicit(&solid, 24, 0.2, 3, &p).unwrap();
            assert_eq!(
                (rows.dims, rows.origin, rows.spacing),
                (points.dims, points.origin, points.spacing)
            );
            let differ = rows
                .data
                .iter()
                .zip(&points.data)
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differ, 0, "of {} voxels", rows.data.len());
            assert!(rows.data.iter().any(|&v| v > 0.0 && v < 1.0));
        }
        // An open mesh is left to the winding number.
        let mut open = torus.clone();
        open.triangles.pop();
        assert!(!applies(&open));
    }
}
