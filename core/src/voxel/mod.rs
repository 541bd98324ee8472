//! Voxel-based object simplification (voxel-based-object-simplification.txt).
//!
//! Paper: T. He, L. Hong, A. Kaufman, A. Varshney, S. Wang, "Voxel Based
//! Object Simplification", Proc. IEEE Visualization '95 (the "voxel paper" in
//! this tree's docs; the copy in ../shared/papers starts at its abstract).
//!
//! §2: the object is sampled into a volume buffer S (eq. 2, [`sampling`]), low-pass
//! filtered into a density f = h ∗ S (eq. 1, [`filter`]: the Gaussian or the
//! hyper-cone of eq. 3), and the iso-density surface f = 0.5 is extracted by
//! marching cubes ([`marching_cubes`]). A wider filter removes higher frequencies,
//! and with them small holes, tunnels and cavities: the genus falls with the radius
//! (Tables 1–3 pair coarser grids with wider filters).

pub mod caps;
pub mod filter;
pub mod layers;
pub mod marching_cubes;
pub mod params;
pub mod post_simplify;
pub mod pyramid;
pub mod sampling;
pub mod scanline;

pub use filter::Filter;
pub use marching_cubes::{DENSITY_ISO, marching_cubes};
pub use params::VoxelParams;
pub use post_simplify::{PostSimplify, post_simplify};
pub use pyramid::{Pyramid, Source};

use crate::geom::{Topology, TriMesh, Volume};
use crate::implicit::Implicit;
use crate::progress::{Cancelled, Progress};

/// Voxels along the longest side a build may ask for, everywhere (CLI,
/// export, studio): below 8 the filter leaves nothing of §2's levels; 512³
/// floats are 0.5 GiB, what a desktop holds beside the pyramid.
pub const RESOLUTION_RANGE: std::ops::RangeInclusive<usize> = 8..=512;
/// Refuses a resolution whose grids would not fit the memory budget: a
/// pyramid holds a few float grids of the finest size at once (sampled,
/// filtered, and the coarser levels: about four).
pub fn check_resolution_budget(resolution: usize) -> Result<(), String> {
    let voxels = (resolution as u64).saturating_pow(3);
    crate::io::limits::check_budget(
        &format!("a voxel pyramid of resolution {resolution}"),
        voxels.saturating_mul(4 * 4),
    )
    .map_err(|e| e.expected)
}

/// Filter support radius R, in voxels of the sampling grid.
pub const RADIUS_RANGE: std::ops::RangeInclusive<f32> = 0.0..=64.0;

/// Sub-samples per voxel edge when sampling S (k³ per voxel).
const SUPERSAMPLE: usize = 3;

/// One level of detail: the iso-surface of the filtered volume and its topology.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelLevel {
    pub mesh: TriMesh,
    /// Voxels along the longest side of the object's bounds.
    pub resolution: usize,
    /// Filter support radius in voxels of the sampling grid.
    pub radius: f32,
    pub components: usize,
    pub genus: i64,
}

/// The filtered density f = h ∗ S (eq. 1–2) of one level: a solid sampled with
/// `resolution` voxels along its longest side (k³-supersampled), or a volume's
/// S pooled over blocks of `factor`³ samples; filtered with support `radius` in
/// the level's own voxels and padded so the surface closes.
pub fn density(
    source: Source,
    resolution: usize,
    factor: usize,
    radius: f32,
    filter: Filter,
    progress: &Progress,
) -> Result<Volume, Cancelled> {
    let radius = radius.max(0.0);
    match source {
        Source::Solid(solid) => {
            let h = solid.bounds().extent().max_element() / resolution.max(1) as f32;
            // A mesh's solid by rows (the same S, much faster, where its
            // surface allows; else point by point); any other solid point by point.
            let s = match solid.surface() {
                Some(mesh) => scanline::sample_by_rows(
                    solid,
                    mesh,
                    resolution,
                    radius * h,
                    SUPERSAMPLE,
                    progress,
                )?,
                None => {
                    sampling::sample_implicit(solid, resolution, radius * h, SUPERSAMPLE, progress)?
                }
            };
            filter::apply(filter, &s, radius * h, progress)
        }
        Source::Volume(volume, iso) => {
            let s = sampling::pool(volume, iso, factor.max(1));
            let h = s.spacing.min_element();
            let pad = radius.ceil() as usize + 1;
            filter::apply(filter, &sampling::pad(&s, pad), radius * h, progress)
        }
    }
}

/// Samples `solid` with `resolution` voxels along its longest side (the finest grid
/// of this level, k³-supersampled), filters it with support `radius` voxels of that
/// grid, and extracts the surface at density `iso` (§2; 0.5 in §4).
pub fn simplify_implicit(
    solid: &dyn Implicit,
    resolution: usize,
    radius: f32,
    filter: Filter,
    iso: f32,
    progress: &Progress,
) -> Result<VoxelLevel, Cancelled> {
    let f = density(
        Source::Solid(solid),
        resolution,
        1,
        radius,
        filter,
        progress,
    )?;
    let mesh = marching_cubes(&f, iso, progress)?;
    Ok(level(mesh, resolution, radius))
}

/// The same for a scalar volume (CT, MRI): S is the set of samples at or above
/// `iso`, filtered with support `radius` voxels (of the smallest spacing), and the
/// density surface 0.5 is extracted on the volume's own grid.
pub fn simplify_volume(
    volume: &Volume,
    iso: f32,
    radius: f32,
    filter: Filter,
    progress: &Progress,
) -> Result<VoxelLevel, Cancelled> {
    let f = density(Source::Volume(volume, iso), 0, 1, radius, filter, progress)?;
    let mesh = marching_cubes(&f, DENSITY_ISO, progress)?;
    Ok(level(
        mesh,
        volume.dims.into_iter().max().unwrap_or(0),
        radius,
    ))
}

/// A level from its extracted mesh: topology (components, genus) measured.
pub fn level(mesh: TriMesh, resolution: usize, radius: f32) -> VoxelLevel {
    let topo = Topology::of(&mesh);
    VoxelLevel {
        resolution,
        radius,
        components: topo.components.len(),
        genus: topo.genus,
        mesh,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::{Sphereflake, csg_part};

    /// A sampled sphere volume (values = distance from the centre, inside below
    /// the iso level is outside here: S is `value >= iso`) gives one closed surface.
    #[test]
    fn volumes_are_simplified_on_their_own_grid() {
        let n = 40;
        let mut data = Vec::with_capacity(n * n * n);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let d = glam::Vec3::new(x as f32, y as f32, z as f32) - glam::Vec3::splat(19.5);
                    data.push(15.0 - d.length());
                }
            }
        }
        let v = Volume {
            dims: [n; 3],
            spacing: glam::Vec3::new(1.0, 1.0, 2.0),
            origin: glam::Vec3::ZERO,
            data,
        };
        let l = simplify_volume(&v, 0.0, 2.0, Filter::Gaussian, &Progress::new()).unwrap();
        assert_eq!((l.components, l.genus, l.resolution), (1, 0, n));
        assert!(Topology::of(&l.mesh).is_closed());
    }

    #[test]
    fn csg_part_loses_genus_as_the_filter_widens() {
        let part = csg_part();
        let p = Progress::new();
        for filter in [Filter::Gaussian, Filter::Cone] {
            let levels: Vec<VoxelLevel> = [1.0, 4.0, 8.0, 12.0]
                .into_iter()
                .map(|r| simplify_implicit(&part, 64, r, filter, DENSITY_ISO, &p).unwrap())
                .collect();
            let fine = &levels[0];
            assert_eq!((fine.components, fine.genus), (1, 5), "{filter:?}");
            let topo = Topology::of(&fine.mesh);
            assert!(topo.is_closed() && topo.is_manifold());
            for pair in levels.windows(2) {
                assert!(pair[1].genus <= pair[0].genus, "{filter:?}");
                assert_eq!(pair[1].components, 1);
            }
            let coarse = levels.last().unwrap();
            assert!(coarse.genus <= 1, "{filter:?}: genus {}", coarse.genus);
            assert!(coarse.mesh.triangles.len() < fine.mesh.triangles.len());
        }
    }

    #[test]
    fn sphereflake_merges_into_one_component_once_filtered() {
        // The 820 spheres only touch at points: at 64 voxels the smallest (radius
        // 1/27) are under a voxel, and a one-voxel filter leaves some apart; a
        // two-voxel filter fills the tangencies and joins them all.
        let flake = Sphereflake::new(3);
        let p = Progress::new();
        let thin = simplify_implicit(&flake, 64, 1.0, Filter::Gaussian, DENSITY_ISO, &p).unwrap();
        assert!(thin.components > 1);
        let merged = simplify_implicit(&flake, 64, 2.0, Filter::Gaussian, DENSITY_ISO, &p).unwrap();
        assert_eq!((merged.components, merged.genus), (1, 0));
        assert!(Topology::of(&merged.mesh).is_closed());
    }
}
