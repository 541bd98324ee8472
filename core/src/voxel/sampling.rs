//! Volume sampling (§2, eq. 2): the binary function S of a solid on a regular grid,
//! the input of the low-pass filter.
//!
//! S is supersampled: a voxel holds the fraction of k×k×k sub-samples of its cell
//! that lie inside, which makes the filtered density f = h ∗ S more accurate than
//! point samples of S would (the cell is the box of one voxel size centred on the
//! grid point).

use glam::Vec3;
use rayon::prelude::*;

use crate::geom::Volume;
use crate::implicit::Implicit;
use crate::progress::{Cancelled, Progress};

/// Samples the negated value of `solid` at the nodes of a grid of spacing `cell`
/// covering its bounds plus one cell, so the surface is the level 0 of a field that
/// is positive inside (what [`super::marching_cubes`] extracts) and the border
/// samples are outside. The grid is shifted by a fraction of a cell so that planar
/// faces at round coordinates do not pass exactly through grid nodes.
pub fn sample_field(
    solid: &dyn Implicit,
    cell: f32,
    progress: &Progress,
) -> Result<Volume, Cancelled> {
    progress.stage("sampling the solid");
    let bounds = solid.bounds();
    let origin = bounds.min - Vec3::splat(cell * (1.0 - 0.123));
    let dims = [0, 1, 2].map(|a| ((bounds.max[a] - origin[a]) / cell).ceil() as usize + 2);
    let (nx, ny) = (dims[0], dims[1]);
    let mut data = vec![0f32; nx * ny * dims[2]];
    for (z, slab) in data.chunks_mut(nx * ny).enumerate() {
        progress.check()?;
        progress.set_fraction(z as f32 / dims[2] as f32);
        slab.par_iter_mut().enumerate().for_each(|(i, v)| {
            let p = origin + Vec3::new((i % nx) as f32, (i / nx) as f32, z as f32) * cell;
            *v = -solid.value(p);
        });
    }
    Ok(Volume {
        dims,
        spacing: Vec3::splat(cell),
        origin,
        data,
    })
}

/// Samples `solid` (value < 0 inside) into an occupancy volume in 0..=1.
///
/// The grid has `resolution` cubic voxels along the longest side of the solid's
/// bounds, and extends `margin` (world units, typically the filter radius) plus one
/// voxel beyond them on every side, so the border samples are empty and the filtered
/// surface closes. `supersample` is k (1 = point samples).
///
/// Relies on the [`Implicit`] contract that |value| never exceeds the distance to the
/// surface: a cell whose centre is farther than its half diagonal is classified by
/// its centre alone, so only cells near the surface pay for the k³ sub-samples.
pub fn sample_implicit(
    solid: &dyn Implicit,
    resolution: usize,
    margin: f32,
    supersample: usize,
    progress: &Progress,
) -> Result<Volume, Cancelled> {
    progress.stage("sampling");
    let grid = Grid::around(solid.bounds(), resolution, margin);
    let Grid { dims, origin, h } = grid;
    let k = supersample.max(1);
    let offsets: Vec<Vec3> = (0..k * k * k)
        .map(|i| {
            let s = |j: usize| sub_offset(j, k, h);
            Vec3::new(s(i % k), s(i / k % k), s(i / (k * k)))
        })
        .collect();
    let half_diagonal = 0.5 * 3f32.sqrt() * h;
    let [nx, ny, nz] = dims;
    let mut data = vec![0.0f32; nx * ny * nz];
    let done = std::sync::atomic::AtomicUsize::new(0);
    let slabs = nz.div_ceil(BLOCK);
    // Slabs of BLOCK slices in parallel; within a slab, BLOCK³ blocks that the
    // solid classifies whole are filled at once, the rest voxel by voxel.
    data.par_chunks_mut(nx * ny * BLOCK)
        .enumerate()
        .try_for_each(|(slab, chunk)| {
            progress.check()?;
            let z0 = slab * BLOCK;
            let depth = chunk.len() / (nx * ny);
            for by in (0..ny).step_by(BLOCK) {
                for bx in (0..nx).step_by(BLOCK) {
                    let (ex, ey) = ((bx + BLOCK).min(nx), (by + BLOCK).min(ny));
                    let lo = origin + h * Vec3::new(bx as f32, by as f32, z0 as f32);
                    let hi = origin
                        + h * Vec3::new((ex - 1) as f32, (ey - 1) as f32, (z0 + depth - 1) as f32);
                    let whole = solid.classify_block((lo + hi) * 0.5, (hi - lo) * 0.5 + h * 0.5);
                    for z in 0..depth {
                        for y in by..ey {
                            for x in bx..ex {
                                let p = origin + h * Vec3::new(x as f32, y as f32, (z0 + z) as f32);
                                chunk[x + nx * (y + ny * z)] = match whole {
                                    Some(inside) => inside as u8 as f32,
                                    None => occupancy(solid, p, half_diagonal, &offsets),
                                };
                            }
                        }
                    }
                }
            }
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress.set_fraction(d as f32 / slabs as f32);
            Ok(())
        })?;
    Ok(grid.volume(data))
}

/// The sampling grid of a solid: `resolution` cubic voxels of size `h` along
/// the longest side of `bounds`, extended by `margin` plus one voxel on every
/// side and centred on the bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    pub dims: [usize; 3],
    pub origin: Vec3,
    pub h: f32,
}

impl Grid {
    pub fn around(bounds: crate::geom::Aabb, resolution: usize, margin: f32) -> Grid {
        let extent = bounds.extent();
        let h = extent.max_element().max(f32::MIN_POSITIVE) / resolution.max(1) as f32;
        let pad = (margin.max(0.0) / h).ceil() as usize + 1;
        let dims = [0, 1, 2].map(|a| (extent[a] / h).ceil() as usize + 1 + 2 * pad);
        let span = Vec3::new(
            (dims[0] - 1) as f32,
            (dims[1] - 1) as f32,
            (dims[2] - 1) as f32,
        ) * h;
        Grid {
            dims,
            origin: bounds.center() - span * 0.5,
            h,
        }
    }
}

impl Grid {
    /// `data` (one value per node, x fastest) on this grid.
    pub fn volume(&self, data: Vec<f32>) -> Volume {
        Volume {
            dims: self.dims,
            spacing: Vec3::splat(self.h),
            origin: self.origin,
            data,
        }
    }
}

/// Offset of sub-sample `j` of `k` from its voxel's centre, along one axis.
pub fn sub_offset(j: usize, k: usize, h: f32) -> f32 {
    ((j as f32 + 0.5) / k as f32 - 0.5) * h
}

/// Edge of the blocks the sampler tries to classify whole.
const BLOCK: usize = 4;

/// The fraction of a voxel's cell inside `solid`: its centre decides alone when
/// the surface is farther than the cell's half diagonal, else the k³ sub-samples.
fn occupancy(solid: &dyn Implicit, p: Vec3, half_diagonal: f32, offsets: &[Vec3]) -> f32 {
    let v = solid.value(p);
    if v.abs() > half_diagonal {
        (v < 0.0) as u8 as f32
    } else {
        let inside = offsets
            .iter()
            .filter(|&&o| solid.value(p + o) < 0.0)
            .count();
        inside as f32 / offsets.len() as f32
    }
}

/// S of a volume at `factor` times its voxel size: the fraction of each block of
/// factor³ samples at or above `iso` (the supersampled S of eq. 2).
pub fn pool(volume: &Volume, iso: f32, factor: usize) -> Volume {
    let dims = volume.dims.map(|d| d.div_ceil(factor));
    let [nx, ny, _] = dims;
    let mut data = vec![0.0f32; dims[0] * dims[1] * dims[2]];
    data.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(z, slab)| {
            for (j, out) in slab.iter_mut().enumerate() {
                let (x, y) = (j % nx, j / nx);
                let (mut inside, mut count) = (0usize, 0usize);
                for sz in z * factor..((z + 1) * factor).min(volume.dims[2]) {
                    for sy in y * factor..((y + 1) * factor).min(volume.dims[1]) {
                        for sx in x * factor..((x + 1) * factor).min(volume.dims[0]) {
                            inside += (volume.value(sx, sy, sz) >= iso) as usize;
                            count += 1;
                        }
                    }
                }
                *out = inside as f32 / count.max(1) as f32;
            }
        });
    let spacing = volume.spacing * factor as f32;
    Volume {
        dims,
        spacing,
        // Block centres.
        origin: volume.origin + volume.spacing * 0.5 * (factor as f32 - 1.0),
        data,
    }
}

/// `v` with `pad` empty voxels on every side, so the filter and marching cubes
/// see the object whole and the surface closes.
pub fn pad(v: &Volume, pad: usize) -> Volume {
    let [nx, ny, nz] = v.dims;
    let dims = [nx + 2 * pad, ny + 2 * pad, nz + 2 * pad];
    let mut data = vec![0.0f32; dims[0] * dims[1] * dims[2]];
    for z in 0..nz {
        for y in 0..ny {
            let src = &v.data[nx * (y + ny * z)..][..nx];
            data[pad + dims[0] * (y + pad + dims[1] * (z + pad))..][..nx].copy_from_slice(src);
        }
    }
    Volume {
        dims,
        spacing: v.spacing,
        origin: v.origin - v.spacing * pad as f32,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::Sphere;

    #[test]
    fn supersampled_occupancy_integrates_to_the_solid_volume() {
        let sphere = Sphere {
            center: Vec3::new(0.3, -0.2, 1.0),
            radius: 1.0,
        };
        let p = Progress::new();
        let vol = sample_implicit(&sphere, 32, 0.25, 4, &p).unwrap();
        let h = vol.spacing.x;
        assert!((h - 2.0 / 32.0).abs() < 1e-6);
        // Bounds plus margin plus one voxel on each side, centred on the solid.
        assert_eq!(vol.dims, [33 + 2 * 5; 3]);
        let b = vol.bounds();
        assert!((b.center() - sphere.center).length() < 1e-5);
        let volume: f32 = vol.data.iter().sum::<f32>() * h * h * h;
        let exact = 4.0 / 3.0 * std::f32::consts::PI;
        assert!(
            (volume - exact).abs() < 0.005 * exact,
            "{volume} vs {exact}"
        );
        assert!(
            vol.data.iter().any(|&v| v > 0.0 && v < 1.0),
            "fractional on the surface"
        );
        // The border is empty.
        let [nx, ny, nz] = vol.dims;
        for (x, y, z) in [(0, 0, 0), (nx - 1, ny / 2, nz / 2), (nx / 2, ny / 2, 0)] {
            assert_eq!(vol.value(x, y, z), 0.0);
        }
        // k = 1 is plain point sampling: binary values.
        let point = sample_implicit(&sphere, 16, 0.0, 1, &p).unwrap();
        assert!(point.data.iter().all(|&v| v == 0.0 || v == 1.0));
    }

    #[test]
    fn pooling_by_one_thresholds_and_pads() {
        let vol = Volume {
            dims: [3, 2, 1],
            spacing: Vec3::new(1.0, 2.0, 3.0),
            origin: Vec3::ZERO,
            data: vec![0.1, 0.5, 0.9, 0.49, 2.0, -1.0],
        };
        let b = pad(&pool(&vol, 0.5, 1), 2);
        assert_eq!(b.dims, [7, 6, 5]);
        assert_eq!(b.origin, Vec3::new(-2.0, -4.0, -6.0));
        assert_eq!(b.data.iter().sum::<f32>(), 3.0);
        assert_eq!(b.value(3, 2, 2), 1.0);
        assert_eq!(b.value(2, 2, 2), 0.0);
        assert_eq!(b.value(3, 3, 2), 1.0);
        // Pooling by 2: block fractions, at block centres.
        let p = pool(&vol, 0.5, 2);
        assert_eq!(p.dims, [2, 1, 1]);
        assert_eq!(p.data, [0.5, 1.0 / 2.0]);
        assert_eq!(p.origin, Vec3::new(0.5, 1.0, 1.5));
    }
}
