//! The low-pass filters h of §2 (eq. 1): the discrete convolution f = h ∗ S of a
//! sampled density with a radially symmetric kernel of support radius R.
//!
//! Both kernels are normalised to total weight one (the paper's w in eq. 3), so a
//! constant density stays constant; samples outside the volume count as zero. The
//! radius is in world units and becomes a per-axis voxel radius, so anisotropic
//! spacing filters the same physical neighbourhood along every axis.

use glam::Vec3;
use rayon::prelude::*;

use crate::geom::Volume;
use crate::progress::{Cancelled, Progress};

/// Which low-pass filter of §2 to apply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Filter {
    /// The "higher-order" Gaussian of §2, σ = R/3, truncated at R; separable, so
    /// it costs about 3·(2R+1) multiply-adds per voxel.
    #[default]
    Gaussian,
    /// The hyper-cone of eq. 3, h(r) ∝ (R − r) for r < R. Not separable: a direct
    /// convolution with about (4/3)πR³ taps per voxel (R in voxels).
    Cone,
}

impl Filter {
    pub fn name(self) -> &'static str {
        match self {
            Filter::Gaussian => "Gaussian",
            Filter::Cone => "Cone",
        }
    }
}

/// Applies `filter` with support radius `radius` (world units) to `volume`.
pub fn apply(
    filter: Filter,
    volume: &Volume,
    radius: f32,
    progress: &Progress,
) -> Result<Volume, Cancelled> {
    match filter {
        Filter::Gaussian => gaussian(volume, radius, progress),
        Filter::Cone => cone(volume, radius, progress),
    }
}

/// Voxel radius along each axis for a world radius.
fn voxel_radius(radius: f32, spacing: Vec3) -> [usize; 3] {
    [0, 1, 2].map(|a| (radius / spacing[a]).floor().max(0.0) as usize)
}

/// Separable Gaussian (§2): three passes of a normalised 1D kernel.
pub fn gaussian(volume: &Volume, radius: f32, progress: &Progress) -> Result<Volume, Cancelled> {
    progress.stage("gaussian filter");
    let sigma = radius / 3.0;
    let reach = voxel_radius(radius, volume.spacing);
    let mut data = volume.data.clone();
    for (axis, &reach) in reach.iter().enumerate() {
        let r = reach as isize;
        let weights: Vec<f32> = (-r..=r)
            .map(|i| {
                let d = i as f32 * volume.spacing[axis];
                (-d * d / (2.0 * sigma * sigma)).exp()
            })
            .collect();
        let sum: f32 = weights.iter().sum();
        let weights: Vec<f32> = weights.iter().map(|w| w / sum).collect();
        data = convolve_axis(&data, volume.dims, axis, &weights, progress)?;
        progress.set_fraction((axis + 1) as f32 / 3.0);
    }
    Ok(Volume {
        data,
        ..volume.clone()
    })
}

/// One 1D pass along `axis` with a centred kernel, parallel over z slices.
fn convolve_axis(
    src: &[f32],
    dims: [usize; 3],
    axis: usize,
    weights: &[f32],
    progress: &Progress,
) -> Result<Vec<f32>, Cancelled> {
    if weights.len() == 1 {
        return Ok(src.to_vec());
    }
    let [nx, ny, nz] = dims;
    let slice = nx * ny;
    let r = (weights.len() / 2) as isize;
    let mut out = vec![0.0f32; src.len()];
    out.par_chunks_mut(slice)
        .enumerate()
        .try_for_each(|(z, dst)| {
            progress.check()?;
            for (k, &w) in weights.iter().enumerate() {
                let d = k as isize - r;
                match axis {
                    0 => {
                        let lo = (-d).max(0) as usize;
                        let hi = (nx as isize - d).min(nx as isize).max(0) as usize;
                        for y in 0..ny {
                            let row = z * slice + y * nx;
                            for x in lo..hi {
                                dst[y * nx + x] += w * src[row + (x as isize + d) as usize];
                            }
                        }
                    }
                    1 => {
                        for y in 0..ny {
                            let ys = y as isize + d;
                            if ys < 0 || ys >= ny as isize {
                                continue;
                            }
                            let s = &src[z * slice + ys as usize * nx..][..nx];
                            for (o, v) in dst[y * nx..][..nx].iter_mut().zip(s) {
                                *o += w * v;
                            }
                        }
                    }
                    _ => {
                        let zs = z as isize + d;
                        if zs < 0 || zs >= nz as isize {
                            continue;
                        }
                        let s = &src[zs as usize * slice..][..slice];
                        for (o, v) in dst.iter_mut().zip(s) {
                            *o += w * v;
                        }
                    }
                }
            }
            Ok(())
        })?;
    Ok(out)
}

/// The taps `(dx, weight)` of one kernel row at offset (dy, dz).
struct KernelRow {
    dy: isize,
    dz: isize,
    taps: Vec<(isize, f32)>,
}

/// Hyper-cone of eq. 3 by direct convolution with the precomputed kernel.
pub fn cone(volume: &Volume, radius: f32, progress: &Progress) -> Result<Volume, Cancelled> {
    progress.stage("hyper-cone filter");
    let [nx, ny, nz] = volume.dims;
    let [rx, ry, rz] = voxel_radius(radius, volume.spacing).map(|r| r as isize);
    let s = volume.spacing;
    // Kernel rows (dy, dz) with their taps (dx, weight): h(r) = (R − r) inside R.
    let mut rows: Vec<KernelRow> = Vec::new();
    let mut total = 0.0f32;
    for dz in -rz..=rz {
        for dy in -ry..=ry {
            let taps: Vec<(isize, f32)> = (-rx..=rx)
                .filter_map(|dx| {
                    let r = (Vec3::new(dx as f32, dy as f32, dz as f32) * s).length();
                    (r < radius).then_some((dx, radius - r))
                })
                .collect();
            total += taps.iter().map(|t| t.1).sum::<f32>();
            if !taps.is_empty() {
                rows.push(KernelRow { dy, dz, taps });
            }
        }
    }
    if rows.is_empty() {
        // R = 0: the identity.
        return Ok(volume.clone());
    }
    for row in &mut rows {
        for t in &mut row.taps {
            t.1 /= total;
        }
    }
    let src = &volume.data;
    let slice = nx * ny;
    let mut out = vec![0.0f32; src.len()];
    out.par_chunks_mut(slice)
        .enumerate()
        .try_for_each(|(z, dst)| {
            progress.check()?;
            for KernelRow { dy, dz, taps } in &rows {
                let zs = z as isize + dz;
                if zs < 0 || zs >= nz as isize {
                    continue;
                }
                for y in 0..ny {
                    let ys = y as isize + dy;
                    if ys < 0 || ys >= ny as isize {
                        continue;
                    }
                    let s = &src[zs as usize * slice + ys as usize * nx..][..nx];
                    let o = &mut dst[y * nx..][..nx];
                    for &(dx, w) in taps {
                        let lo = (-dx).max(0) as usize;
                        let hi = (nx as isize - dx).min(nx as isize).max(0) as usize;
                        if lo >= hi {
                            continue;
                        }
                        let shifted = &s[(lo as isize + dx) as usize..(hi as isize + dx) as usize];
                        for (o, v) in o[lo..hi].iter_mut().zip(shifted) {
                            *o += w * v;
                        }
                    }
                }
            }
            Ok(())
        })?;
    Ok(Volume {
        data: out,
        ..volume.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn filled(dims: [usize; 3], spacing: Vec3, f: impl Fn(usize, usize, usize) -> f32) -> Volume {
        let mut data = Vec::new();
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    data.push(f(x, y, z));
                }
            }
        }
        Volume {
            dims,
            spacing,
            origin: Vec3::ZERO,
            data,
        }
    }

    const FILTERS: [Filter; 2] = [Filter::Gaussian, Filter::Cone];

    #[test]
    fn a_full_volume_stays_one_inside_and_drops_at_the_zero_padded_border() {
        let spacing = Vec3::new(1.0, 0.5, 2.0);
        let vol = filled([24, 40, 14], spacing, |_, _, _| 1.0);
        let p = Progress::new();
        for f in FILTERS {
            let out = apply(f, &vol, 4.0, &p).unwrap();
            // Voxel radius (4, 8, 2): the interior beyond it is untouched.
            for z in 2..12 {
                for y in 8..32 {
                    for x in 4..20 {
                        assert!((out.value(x, y, z) - 1.0).abs() < 1e-5, "{f:?}");
                    }
                }
            }
            assert!(out.value(0, 0, 0) < 0.3, "{f:?} corner sees zero padding");
        }
    }

    #[test]
    fn a_half_space_filters_to_one_half_on_its_boundary_plane() {
        let p = Progress::new();
        // Occupancy 1 below the plane z = 10, 1/2 in the voxel it cuts, 0 above.
        let vol = filled([12, 12, 21], Vec3::splat(0.5), |_, _, z| match z {
            0..10 => 1.0,
            10 => 0.5,
            _ => 0.0,
        });
        for f in FILTERS {
            let out = apply(f, &vol, 2.0, &p).unwrap();
            let v = out.value(6, 6, 10);
            assert!((v - 0.5).abs() < 1e-5, "{f:?}: {v}");
            assert!(out.value(6, 6, 8) > 0.5 && out.value(6, 6, 12) < 0.5);
            // Monotone across the plane.
            for z in 4..16 {
                assert!(out.value(6, 6, z) >= out.value(6, 6, z + 1) - 1e-6);
            }
        }
    }

    #[test]
    fn kernels_are_normalised_symmetric_and_end_at_their_support() {
        let n = 17;
        let vol = filled([n; 3], Vec3::ONE, |x, y, z| {
            (x == 8 && y == 8 && z == 8) as u8 as f32
        });
        let p = Progress::new();
        for f in FILTERS {
            let out = apply(f, &vol, 5.0, &p).unwrap();
            let at = |d: [isize; 3]| {
                out.value(
                    (8 + d[0]) as usize,
                    (8 + d[1]) as usize,
                    (8 + d[2]) as usize,
                )
            };
            assert!((out.data.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            assert!(at([0, 0, 0]) > at([1, 0, 0]));
            assert!((at([3, 0, 0]) - at([0, 0, 3])).abs() < 1e-7);
            assert!((at([0, 4, 0]) - at([0, 0, -4])).abs() < 1e-7);
            assert!(
                at([0, 0, 6]) == 0.0 && at([0, -6, 0]) == 0.0,
                "support ends at R"
            );
        }
    }

    #[test]
    fn a_zero_radius_is_the_identity() {
        let vol = filled([5, 6, 7], Vec3::ONE, |x, y, z| (x * y + z) as f32);
        let p = Progress::new();
        for f in FILTERS {
            assert_eq!(apply(f, &vol, 0.5, &p).unwrap(), vol);
        }
    }
}
