//! Skinned LODs measured where they are seen: in motion (issue 49, item 4).
//! A LOD is certified in the bind pose, where the methods built it; posed,
//! each vertex moves by its own blend of joint matrices (linear blend
//! skinning, glTF 2.0 §3.7.3: v' = Σ wᵢ·Jᵢ·v with Jᵢ = world(jointᵢ)·IBMᵢ),
//! so the distance between the skinned original and the skinned LOD is
//! measured at poses sampled evenly in time from each animation (the rest
//! pose when there is none): a two-sided sampled Hausdorff distance per pose.

use glam::{Mat4, Quat, Vec3};

use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};
use crate::geom::TriMesh;
use crate::io::rig::{Animation, Path, Rig};
use crate::io::scene::Skinning;

/// Area samples per surface for each pose (vertices and edge midpoints
/// come on top): poses are many, and the meshes measured are whole LODs.
const POSE_SAMPLES: usize = 20_000;

/// The measured distance between a skinned original and its skinned LOD.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PoseError {
    pub max: f32,
    pub mean: f32,
    /// Poses measured.
    pub poses: usize,
    /// Each pose's distance, in the order [`sample_poses`] gives.
    pub per_pose: Vec<f32>,
}

/// The world matrix of every node at time `t` of `animation` (`None`:
/// the rest pose).
pub fn node_worlds(rig: &Rig, animation: Option<&Animation>, t: f32) -> Vec<Mat4> {
    let mut local = rig.rest.clone();
    for c in animation.map_or(&[][..], |a| &a.channels) {
        let Some(trs) = local.get_mut(c.node) else {
            continue;
        };
        let v = sample(c.times.as_slice(), &c.values, c.step, c.path, t);
        match c.path {
            Path::Translation => trs.translation = Vec3::from_slice(&v[..3]),
            Path::Scale => trs.scale = Vec3::from_slice(&v[..3]),
            Path::Rotation => trs.rotation = Quat::from_array(v).normalize(),
        }
    }
    let n = local.len();
    let mut world: Vec<Option<Mat4>> = vec![None; n];
    for start in 0..n {
        // Up to the first node whose world is known (a chain no longer
        // than the node count: the reader refused cycles in the scene).
        let mut chain = vec![start];
        while let Some(Some(p)) = chain.last().map(|&i| rig.parent[i]) {
            if world[p].is_some() || chain.len() > n {
                break;
            }
            chain.push(p);
        }
        for &i in chain.iter().rev() {
            if world[i].is_none() {
                let above = rig.parent[i]
                    .and_then(|p| world[p])
                    .unwrap_or(Mat4::IDENTITY);
                world[i] = Some(above * local[i].matrix());
            }
        }
    }
    world
        .into_iter()
        .map(|w| w.unwrap_or(Mat4::IDENTITY))
        .collect()
}

/// A channel's value at `t`: held before the first key and after the
/// last, stepped or blended between (quaternions by slerp).
fn sample(times: &[f32], values: &[[f32; 4]], step: bool, path: Path, t: f32) -> [f32; 4] {
    let after = times.partition_point(|&k| k <= t);
    if after == 0 {
        return values[0];
    }
    if after >= times.len() || step {
        return values[after - 1];
    }
    let (t0, t1) = (times[after - 1], times[after]);
    let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    let (a, b) = (values[after - 1], values[after]);
    match path {
        Path::Rotation => Quat::from_array(a)
            .normalize()
            .slerp(Quat::from_array(b).normalize(), f)
            .to_array(),
        _ => std::array::from_fn(|i| a[i] + (b[i] - a[i]) * f),
    }
}

/// `per_animation` poses from each animation, evenly in time over its
/// keyframes (both ends included); the rest pose when there are none.
pub fn sample_poses(rig: &Rig, per_animation: usize) -> Vec<Vec<Mat4>> {
    if rig.animations.is_empty() || per_animation == 0 {
        return vec![node_worlds(rig, None, 0.0)];
    }
    let mut out = Vec::new();
    for a in &rig.animations {
        let (start, end) = a.span();
        for i in 0..per_animation {
            let f = match per_animation {
                1 => 0.0,
                n => i as f32 / (n - 1) as f32,
            };
            out.push(node_worlds(rig, Some(a), start + (end - start) * f));
        }
    }
    out
}

/// `mesh` skinned by `skin` (skin `skin_index` of the rig) at a pose.
pub fn skinned(
    mesh: &TriMesh,
    skin: &Skinning,
    rig: &Rig,
    skin_index: usize,
    worlds: &[Mat4],
) -> TriMesh {
    let mut out = TriMesh::new(mesh.positions.clone(), mesh.triangles.clone());
    skin_into(
        &mesh.positions,
        skin,
        rig,
        skin_index,
        worlds,
        &mut out.positions,
    );
    out
}

/// [`skinned`] positions written into `out` (as long as `positions`): the
/// studio poses its vertex buffer in place every frame. Unchanged without
/// the skin.
pub fn skin_into(
    positions: &[Vec3],
    skin: &Skinning,
    rig: &Rig,
    skin_index: usize,
    worlds: &[Mat4],
    out: &mut [Vec3],
) {
    let Some(def) = rig.skins.get(skin_index) else {
        return;
    };
    let joint: Vec<Mat4> = def
        .joints
        .iter()
        .zip(&def.inverse_bind)
        .map(|(&j, ibm)| worlds.get(j).copied().unwrap_or(Mat4::IDENTITY) * *ibm)
        .collect();
    for (i, (&p, o)) in positions.iter().zip(out.iter_mut()).enumerate() {
        let mut m = Mat4::ZERO;
        for (j, w) in skin.influences(i) {
            if w != 0.0 {
                m += joint.get(j as usize).copied().unwrap_or(Mat4::IDENTITY) * w;
            }
        }
        *o = m.transform_point3(p);
    }
}

/// The distance between `original` and `lod` (each with its skin) at
/// every pose of `poses`.
pub fn pose_error(
    original: (&TriMesh, &Skinning),
    lod: (&TriMesh, &Skinning),
    rig: &Rig,
    skin_index: usize,
    poses: &[Vec<Mat4>],
) -> PoseError {
    let opts = SamplingOptions {
        samples: POSE_SAMPLES,
        ..SamplingOptions::default()
    };
    let per_pose: Vec<f32> = poses
        .iter()
        .map(|worlds| {
            let a = skinned(original.0, original.1, rig, skin_index, worlds);
            let b = skinned(lod.0, lod.1, rig, skin_index, worlds);
            hausdorff_mesh_mesh(&a, &b, &opts).two_sided()
        })
        .collect();
    PoseError {
        max: per_pose.iter().copied().fold(0.0, f32::max),
        mean: per_pose.iter().sum::<f32>() / per_pose.len().max(1) as f32,
        poses: per_pose.len(),
        per_pose,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::rig::{Channel, SkinDef, Trs};

    /// One joint turned a quarter turn about z halfway through a linear
    /// animation: sampled at the ends and halfway, a vertex bound to it
    /// follows the slerp.
    #[test]
    fn a_posed_vertex_follows_its_joint() {
        let rest = Trs {
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        };
        let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let rig = Rig {
            rest: vec![rest],
            parent: vec![None],
            skins: vec![SkinDef {
                joints: vec![0],
                inverse_bind: vec![Mat4::IDENTITY],
            }],
            animations: vec![Animation {
                name: None,
                channels: vec![Channel {
                    node: 0,
                    path: Path::Rotation,
                    times: vec![0.0, 2.0],
                    values: vec![Quat::IDENTITY.to_array(), quarter.to_array()],
                    step: false,
                }],
                morphs: Vec::new(),
            }],
            ..Rig::default()
        };
        let poses = sample_poses(&rig, 3);
        assert_eq!(poses.len(), 3);
        let mesh = TriMesh::new(vec![Vec3::X, Vec3::Y, Vec3::Z], vec![[0, 1, 2]]);
        let skin = Skinning {
            joints: vec![[0; 4]; 3],
            weights: vec![[1.0, 0.0, 0.0, 0.0]; 3],
            ..Skinning::default()
        };
        let end = skinned(&mesh, &skin, &rig, 0, &poses[2]);
        assert!(
            end.positions[0].abs_diff_eq(Vec3::Y, 1e-6),
            "{:?}",
            end.positions
        );
        let half = skinned(&mesh, &skin, &rig, 0, &poses[1]);
        let s = std::f32::consts::FRAC_1_SQRT_2;
        assert!(half.positions[0].abs_diff_eq(Vec3::new(s, s, 0.0), 1e-6));
        // The same mesh as its own LOD is at distance 0 in every pose.
        let e = pose_error((&mesh, &skin), (&mesh, &skin), &rig, 0, &poses);
        assert_eq!(e.poses, 3);
        assert!(e.max < 1e-6, "{e:?}");
    }
}
