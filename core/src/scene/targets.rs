//! Certified bounds of a morphing mesh's LODs, per morph target (issue 49,
//! item 5).
//!
//! A LOD's target shape is its vertices moved by the deltas carried onto
//! them ([`super::transfer`]); the original's is the mesh at that target's
//! full weight. For a triangle LOD the two shapes are certified against each
//! other directly ([`crate::simplify::bound`]: a two-sided Hausdorff bound by
//! branch and bound), so the bound holds whatever rule carried the deltas.
//! A LOD of points or splats does not morph: with ε its base bound and δ the
//! target's largest delta, every point of the base shape moves by at most δ
//! (a barycentric blend of its corners' deltas), so by the triangle
//! inequality the LOD is within ε + δ of the target shape.
//!
//! A LOD's bound is then the largest over its base and every target (what
//! the switch coverages are derived from). Weights strictly between 0 and 1
//! are not certified: the Hausdorff distance is not convex in the weight.

use crate::geom::TriMesh;
use crate::io::scene::SceneMesh;
use crate::lod::chain::lod_screen_coverages;
use crate::progress::{Cancelled, Progress};
use crate::recipe::Chain;
use crate::simplify::{BoundOptions, Original, certify_against};

use super::transfer::Transfer;

/// One morph target's certified bound on one LOD, in mesh space.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TargetBound {
    pub target: usize,
    pub name: Option<String>,
    pub bound: f32,
}

/// Certifies every LOD of `chain` (built from `mesh`) against each of the
/// mesh's target shapes, raises each LOD's bound to the largest over its base
/// and targets, and derives the chain's coverages again. Per LOD, its
/// targets' bounds (none for a mesh without targets).
///
/// # Errors
/// Cancellation.
pub fn certify(
    mesh: &SceneMesh,
    chain: &mut Chain,
    progress: &Progress,
) -> Result<Vec<Vec<TargetBound>>, Cancelled> {
    let mut out = vec![Vec::with_capacity(mesh.targets.len()); chain.lods.len()];
    if mesh.targets.is_empty() {
        return Ok(out);
    }
    let transfer = Transfer::new(mesh);
    let opts = BoundOptions::for_diagonal(chain.diagonal);
    // Each LOD's carried deltas, once: `None` for a LOD that does not morph.
    let carried: Vec<Option<Vec<TriMesh>>> = chain
        .lods
        .iter()
        .map(|l| {
            let s = &l.set;
            let morphs = s.points.is_empty()
                && s.splats.is_empty()
                && s.layers.is_empty()
                && !s.mesh.triangles.is_empty();
            morphs.then(|| {
                let extras = transfer.extras(&s.mesh);
                extras.targets.iter().map(|t| t.applied(&s.mesh)).collect()
            })
        })
        .collect();
    for (t, target) in mesh.targets.iter().enumerate() {
        let shape = mesh.target_shape(t);
        let original = Original::new(&shape);
        for ((l, shapes), bounds) in chain.lods.iter().zip(&carried).zip(&mut out) {
            let bound = match shapes {
                Some(shapes) => {
                    certify_against(&original, &shapes[t], &opts, progress)?.error_bound()
                }
                None => l.bound() + target.largest_delta(),
            };
            bounds.push(TargetBound {
                target: t,
                name: target.name.clone(),
                bound,
            });
        }
    }
    for (l, bounds) in chain.lods.iter_mut().zip(&out) {
        let largest = bounds.iter().map(|b| b.bound).fold(l.bound(), f32::max);
        l.set.error_bound = largest;
    }
    let bounds: Vec<f32> = chain.lods.iter().map(|l| l.bound()).collect();
    chain.coverages = lod_screen_coverages(
        &bounds,
        chain.radius(),
        chain.recipe.pixels,
        chain.recipe.viewport_height,
    );
    Ok(out)
}
