//! What an original mesh's vertices carry besides the surface (skin joints
//! and weights, morph target deltas, tangents), onto any LOD of it: the
//! payload the build carried through each collapse ([`super::carry`]) where
//! the method kept it, else transferred. A transferred LOD vertex takes the
//! values at its closest point on the original, blended by that point's
//! barycentric coordinates in its triangle: every method's LOD lies within
//! its certified bound ε of the original, so that point is at most ε away
//! (the voxel and AMG methods make new surfaces, whose vertices carried
//! nothing). Weights blend joint by joint and keep the four largest,
//! renormalised to sum to 1 (glTF 2.0 §3.7.3.3).

use std::sync::OnceLock;

use glam::Vec3;

use super::carry::Columns;
use crate::distance::{MeshDistance, barycentric};
use crate::geom::TriMesh;
use crate::io::scene::{MorphTarget, SceneMesh, Skinning, VertexExtras};

/// Brings `source`'s vertex extras onto LODs of it.
pub struct Transfer<'a> {
    source: &'a SceneMesh,
    columns: Columns,
    /// Built the first time a LOD carried no payload.
    distance: OnceLock<MeshDistance<'a>>,
}

impl<'a> Transfer<'a> {
    pub fn new(source: &'a SceneMesh) -> Self {
        Transfer {
            source,
            columns: Columns::of(source),
            distance: OnceLock::new(),
        }
    }

    /// Whether `lod` brought its extras through its build (else they are
    /// transferred by closest point).
    pub fn carried(&self, lod: &TriMesh) -> bool {
        self.columns.extras(lod).is_some()
    }

    /// The extras of `lod`'s vertices: carried, else transferred.
    pub fn extras(&self, lod: &TriMesh) -> VertexExtras {
        if self.columns.is_empty() {
            return VertexExtras::default();
        }
        if let Some(carried) = self.columns.extras(lod) {
            return carried;
        }
        let src = &self.source;
        let distance = self.distance.get_or_init(|| MeshDistance::new(&src.mesh));
        let corners: Vec<([usize; 3], [f32; 3])> = lod
            .positions
            .iter()
            .map(|&p| match distance.closest(p) {
                Some((q, t)) => {
                    let tri = src.mesh.triangles[t as usize].map(|i| i as usize);
                    let [a, b, c] = tri.map(|i| src.mesh.positions[i]);
                    (tri, barycentric(q, a, b, c))
                }
                None => ([0; 3], [1.0, 0.0, 0.0]),
            })
            .collect();
        let skin = src.skin.as_ref().map(|_| Skinning {
            joints: Vec::with_capacity(corners.len()),
            weights: Vec::with_capacity(corners.len()),
            ..Skinning::default()
        });
        // Tangents blend like normals: renormalised, the handedness of the
        // corner that weighs most.
        let tangents = src.tangents.as_ref().map(|from| {
            corners
                .iter()
                .map(|(tri, b)| {
                    let xyz: Vec3 = (0..3)
                        .map(|k| b[k] * Vec3::from_slice(&from[tri[k]][..3]))
                        .sum();
                    let most = (0..3).max_by(|&i, &j| b[i].total_cmp(&b[j])).unwrap_or(0);
                    let xyz = xyz
                        .try_normalize()
                        .or_else(|| Vec3::from_slice(&from[tri[most]][..3]).try_normalize())
                        .unwrap_or(Vec3::X);
                    let w = if from[tri[most]][3] < 0.0 { -1.0 } else { 1.0 };
                    [xyz.x, xyz.y, xyz.z, w]
                })
                .collect()
        });
        let mut out = VertexExtras {
            skin,
            tangents,
            targets: Vec::with_capacity(src.targets.len()),
        };
        if let (Some(from), Some(to)) = (&src.skin, &mut out.skin) {
            for (tri, bary) in &corners {
                let (j, w) = blend_weights(from, tri, bary);
                to.joints.push(j);
                to.weights.push(w);
            }
        }
        for target in &src.targets {
            let lerp = |values: &[Vec3]| -> Vec<Vec3> {
                corners
                    .iter()
                    .map(|(tri, b)| (0..3).map(|k| b[k] * values[tri[k]]).sum())
                    .collect()
            };
            out.targets.push(MorphTarget {
                name: target.name.clone(),
                positions: lerp(&target.positions),
                normals: target.normals.as_deref().map(lerp),
            });
        }
        out
    }
}

/// The joints and weights at a point: the corners' weights blended joint
/// by joint, the four largest kept and renormalised (a point without any:
/// joint 0 at full weight).
fn blend_weights(skin: &Skinning, tri: &[usize; 3], bary: &[f32; 3]) -> ([u16; 4], [f32; 4]) {
    let mut sum: Vec<(u16, f32)> = Vec::with_capacity(12);
    for k in 0..3 {
        for (j, w) in skin.influences(tri[k]) {
            let w = w * bary[k];
            if w <= 0.0 {
                continue;
            }
            match sum.iter_mut().find(|(have, _)| *have == j) {
                Some(slot) => slot.1 += w,
                None => sum.push((j, w)),
            }
        }
    }
    four_largest(&mut sum)
}

/// The four largest of `sum`'s joint weights, renormalised to sum to 1
/// (none above 0: joint 0 at full weight).
pub(super) fn four_largest(sum: &mut Vec<(u16, f32)>) -> ([u16; 4], [f32; 4]) {
    sum.retain(|(_, w)| *w > 0.0);
    // Largest first; equal weights by joint, so the result is deterministic.
    sum.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    sum.truncate(4);
    let total: f32 = sum.iter().map(|(_, w)| w).sum();
    if total <= 0.0 || !total.is_finite() {
        return ([0; 4], [1.0, 0.0, 0.0, 0.0]);
    }
    let (mut joints, mut weights) = ([0u16; 4], [0f32; 4]);
    for (i, (j, w)) in sum.iter().enumerate() {
        joints[i] = *j;
        weights[i] = w / total;
    }
    // The largest absorbs the rounding, so the four sum to 1 in f32.
    let rest: f32 = weights[1..].iter().sum();
    weights[0] = 1.0 - rest;
    (joints, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blended_weights_keep_the_four_largest_and_sum_to_one() {
        let skin = Skinning {
            joints: vec![[0, 1, 2, 3], [4, 5, 0, 1], [6, 0, 0, 0]],
            weights: vec![
                [0.4, 0.3, 0.2, 0.1],
                [0.5, 0.5, 0.0, 0.0],
                [1.0, 0.0, 0.0, 0.0],
            ],
            ..Skinning::default()
        };
        let (j, w) = blend_weights(&skin, &[0, 1, 2], &[0.5, 0.25, 0.25]);
        // Joint 0: 0.2; 1: 0.15; 2: 0.1; 3: 0.05; 4: 0.125; 5: 0.125; 6: 0.25.
        assert_eq!(j, [6, 0, 1, 4]);
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{w:?}");
        assert!(w.windows(2).all(|p| p[0] >= p[1]), "{w:?}");
        let none = Skinning {
            joints: vec![[0; 4]; 3],
            weights: vec![[0.0; 4]; 3],
            ..Skinning::default()
        };
        assert_eq!(
            blend_weights(&none, &[0, 1, 2], &[1.0, 0.0, 0.0]).1,
            [1.0, 0.0, 0.0, 0.0]
        );
    }
}
