//! Bone boundaries (issue 49, item 4; as Unreal's skeletal-mesh reduction
//! keeps them): a skinned mesh's triangles are grouped by the joint that
//! moves them most, and each group becomes a part of the mesh the methods
//! build on. Edge collapse never joins parts: an edge between two groups
//! is constrained, its vertices move only along it, so no collapse merges
//! vertices that different bones move apart and the LOD keeps a row of
//! vertices wherever the skin bends.

use crate::geom::{Materials, TriMesh};
use crate::io::scene::Skinning;

/// `mesh` with its parts split by each triangle's dominant joint (the one
/// whose weights over the three corners sum largest; ties to the lower
/// index), and the glTF material of each new part (from `materials`, the
/// old parts').
pub fn split_by_bone(
    mesh: &TriMesh,
    skin: &Skinning,
    materials: &[Option<usize>],
) -> (TriMesh, Vec<Option<usize>>) {
    let mut keys: Vec<(u32, u16)> = Vec::new();
    let mut parts = Vec::with_capacity(mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut sums: Vec<(u16, f32)> = Vec::with_capacity(12);
        for &v in tri {
            let v = v as usize;
            for (j, w) in skin.influences(v) {
                match sums.iter_mut().find(|(have, _)| *have == j) {
                    Some(s) => s.1 += w,
                    None => sums.push((j, w)),
                }
            }
        }
        let joint = sums
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            .map_or(0, |s| s.0);
        let key = (mesh.part(t), joint);
        let part = match keys.iter().position(|k| *k == key) {
            Some(p) => p,
            None => {
                keys.push(key);
                keys.len() - 1
            }
        };
        parts.push(part as u32);
    }
    let mut out = mesh.clone();
    out.parts = (keys.len() > 1).then_some(parts);
    if let Some(m) = &mesh.materials {
        out.materials = Some(Materials {
            table: m.table.clone(),
            of_part: keys.iter().map(|(p, _)| m.of(*p)).collect(),
        });
    }
    let of_new = keys
        .iter()
        .map(|(p, _)| materials.get(*p as usize).copied().flatten())
        .collect();
    (out, of_new)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn triangles_group_by_their_dominant_joint_within_their_part() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
        let mut mesh = TriMesh::new(positions, vec![[0, 1, 2], [1, 3, 2]]);
        mesh.materials = Some(Materials::single(Default::default()));
        let skin = Skinning {
            joints: vec![[0, 1, 0, 0], [0, 1, 0, 0], [1, 0, 0, 0], [1, 0, 0, 0]],
            weights: vec![
                [1.0, 0.0, 0.0, 0.0],
                [0.6, 0.4, 0.0, 0.0],
                [1.0, 0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0, 0.0],
            ],
            ..Skinning::default()
        };
        let (split, materials) = split_by_bone(&mesh, &skin, &[Some(3)]);
        // Triangle 0: joint 0 has 1.6, joint 1 1.4; triangle 1: joint 1 2.4.
        assert_eq!(split.parts, Some(vec![0, 1]));
        assert_eq!(materials, vec![Some(3), Some(3)]);
        assert_eq!(split.materials.unwrap().of_part, vec![0, 0]);
    }
}
