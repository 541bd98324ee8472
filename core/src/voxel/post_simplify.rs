//! The voxel paper calls its method "the first stage": a topology-preserving
//! geometric simplification "can then be applied to further reduce the number
//! of triangles" (§5). Marching cubes makes a few triangles per surface voxel
//! whatever the shape, so an extracted level can hold more triangles than the
//! input; every level is therefore collapsed with the certified edge collapse
//! (which keeps the level's genus and components), by default to half a voxel.
//! The level's own certified bound is then measured on the collapsed surface.

use serde::{Deserialize, Serialize};

use crate::geom::TriMesh;
use crate::progress::{Cancelled, Progress};
use crate::simplify::{self, SimplifyError, SimplifyOptions, Target};

/// How an extracted level is simplified further.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum PostSimplify {
    /// The raw extraction.
    Off,
    /// As few triangles as possible within this many voxel sizes (certified).
    Voxels(f32),
    /// At most this many triangles.
    Triangles(usize),
}

impl PostSimplify {
    /// What builds use unless told otherwise: half a voxel, about the
    /// extraction's own placement error.
    pub const HALF_VOXEL: PostSimplify = PostSimplify::Voxels(0.5);

    /// A problem with the values, in words (for the CLI's exit 2).
    pub fn check(self) -> Result<(), String> {
        match self {
            PostSimplify::Voxels(v) if !(v.is_finite() && v >= 0.0) => Err(format!(
                "the post-simplification error must be a number of voxels >= 0, got {v}"
            )),
            PostSimplify::Triangles(0) => {
                Err("the post-simplification triangle target must be at least 1".into())
            }
            _ => Ok(()),
        }
    }
}

/// `mesh`, extracted on a grid of voxels `voxel` wide, simplified as `post`
/// says (unchanged for [`PostSimplify::Off`] or an empty mesh).
pub fn post_simplify(
    mesh: TriMesh,
    voxel: f32,
    post: PostSimplify,
    progress: &Progress,
) -> Result<TriMesh, Cancelled> {
    let target = match post {
        PostSimplify::Off => return Ok(mesh),
        _ if mesh.triangles.is_empty() => return Ok(mesh),
        PostSimplify::Voxels(v) => Target::Error(v.max(0.0) * voxel.max(0.0)),
        PostSimplify::Triangles(n) => Target::Triangles(n.max(1)),
    };
    let opts = SimplifyOptions {
        target,
        collapse: Default::default(),
        per_triangle_bounds: false,
    };
    match simplify::simplify(&mesh, &opts, progress) {
        Ok(s) => Ok(s.mesh),
        Err(SimplifyError::Cancelled) => Err(Cancelled),
        // Targets are made valid above; a bad one keeps the extraction.
        Err(SimplifyError::BadTarget(_)) => Ok(mesh),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Topology;

    #[test]
    fn levels_get_fewer_triangles_and_keep_their_topology() {
        let torus = crate::builtins::torus(1.0, 0.4, 48, 24);
        let solid = crate::implicit::MeshSolid::new(&torus);
        let p = Progress::new();
        let source = super::super::Source::Solid(&solid);
        let f =
            super::super::density(source, 40, 1, 1.0, super::super::Filter::Gaussian, &p).unwrap();
        let raw = super::super::marching_cubes(&f, super::super::DENSITY_ISO, &p).unwrap();
        let voxel = f.spacing.max_element();
        let half = post_simplify(raw.clone(), voxel, PostSimplify::HALF_VOXEL, &p).unwrap();
        assert!(
            half.triangles.len() * 2 < raw.triangles.len(),
            "{} of {}",
            half.triangles.len(),
            raw.triangles.len()
        );
        let (a, b) = (Topology::of(&raw), Topology::of(&half));
        assert_eq!((a.genus, a.components.len()), (b.genus, b.components.len()));
        // Its distance to the raw level is within the half voxel asked for.
        let opts = crate::distance::SamplingOptions::default();
        let d = crate::distance::hausdorff_mesh_mesh(&raw, &half, &opts).two_sided();
        assert!(d <= 0.5 * voxel * 1.0001, "{d} > half of {voxel}");
        let few = post_simplify(raw.clone(), voxel, PostSimplify::Triangles(500), &p).unwrap();
        assert!(few.triangles.len() <= 500);
        assert_eq!(
            post_simplify(raw.clone(), voxel, PostSimplify::Off, &p).unwrap(),
            raw
        );
        assert!(PostSimplify::Voxels(f32::NAN).check().is_err());
        assert!(PostSimplify::Triangles(0).check().is_err());
    }
}
