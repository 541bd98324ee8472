//! A scene mesh's skin, morph target deltas and tangents as the payload its
//! vertices carry through a build (issue 49, items 4 and 5;
//! [`crate::geom::payload`]): each collapse interpolates them with the
//! parameter it interpolates UVs with, so target shapes follow the
//! collapse's rule (the new vertex's delta is its ends' blended as its
//! position is), and a merge or a cut keeps the values of the vertices it
//! keeps.
//!
//! Columns, per vertex: the skin's weights, one per joint the mesh uses
//! (dense, so a blend is joint by joint; the four largest are kept and
//! renormalised once, when written, glTF 2.0 §3.7.3.3), then each target's
//! position delta (these two shape the surface: hard), then each target's
//! normal delta and the tangent (soft, as normals are).

use glam::Vec3;

use crate::geom::{Payload, TriMesh};
use crate::io::scene::{MorphTarget, SceneMesh, Skinning, VertexExtras};

/// Which column holds what, for one scene mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Columns {
    /// The joints a weight column stands for, in column order.
    joints: Vec<u16>,
    skinned: bool,
    /// Per target: its name and whether it has normal deltas.
    targets: Vec<(Option<String>, bool)>,
    tangents: bool,
}

impl Columns {
    /// The layout of `m`'s payload.
    pub fn of(m: &SceneMesh) -> Columns {
        let mut joints: Vec<u16> = m
            .skin
            .iter()
            .flat_map(|s| (0..s.joints.len()).flat_map(|v| s.influences(v)))
            .filter(|(_, w)| *w > 0.0)
            .map(|(j, _)| j)
            .collect();
        joints.sort_unstable();
        joints.dedup();
        Columns {
            joints,
            skinned: m.skin.is_some(),
            targets: m
                .targets
                .iter()
                .map(|t| (t.name.clone(), t.normals.is_some()))
                .collect(),
            tangents: m.tangents.is_some(),
        }
    }

    /// Whether `m` carries anything.
    pub fn is_empty(&self) -> bool {
        !self.skinned && self.targets.is_empty() && !self.tangents
    }

    fn normal_targets(&self) -> usize {
        self.targets.iter().filter(|t| t.1).count()
    }

    fn width(&self) -> usize {
        self.hard() + 3 * self.normal_targets() + if self.tangents { 4 } else { 0 }
    }

    fn hard(&self) -> usize {
        self.joints.len() + 3 * self.targets.len()
    }

    /// The payload of `m.mesh`'s vertices; `None` when it carries nothing.
    pub fn payload(&self, m: &SceneMesh) -> Option<Payload> {
        if self.is_empty() {
            return None;
        }
        let n = m.mesh.positions.len();
        let mut p = Payload::new(self.width(), self.hard(), self.joints.len());
        p.values.reserve(n * p.width);
        for v in 0..n {
            let start = p.values.len();
            p.values.resize(start + self.joints.len(), 0.0);
            if let Some(s) = &m.skin {
                for (j, w) in s.influences(v) {
                    if let (true, Ok(k)) = (w > 0.0, self.joints.binary_search(&j)) {
                        p.values[start + k] += w;
                    }
                }
            }
            for t in &m.targets {
                p.values.extend_from_slice(&t.positions[v].to_array());
            }
            for t in &m.targets {
                if let Some(n) = &t.normals {
                    p.values.extend_from_slice(&n[v].to_array());
                }
            }
            if let Some(t) = &m.tangents {
                p.values.extend_from_slice(&t[v]);
            }
        }
        Some(p)
    }

    /// The extras of `lod`'s vertices from the payload it carried; `None`
    /// where it carries none of this layout (a method that made a new
    /// surface: voxels, AMG, splats).
    pub fn extras(&self, lod: &TriMesh) -> Option<VertexExtras> {
        let p = lod.payload.as_ref()?;
        let n = lod.positions.len();
        if self.is_empty() || p.width != self.width() || p.check("payload", n).is_err() {
            return None;
        }
        let mut out = VertexExtras {
            skin: self.skinned.then(|| Skinning {
                joints: Vec::with_capacity(n),
                weights: Vec::with_capacity(n),
                ..Skinning::default()
            }),
            tangents: self.tangents.then(|| Vec::with_capacity(n)),
            targets: self
                .targets
                .iter()
                .map(|(name, normals)| MorphTarget {
                    name: name.clone(),
                    positions: Vec::with_capacity(n),
                    normals: normals.then(|| Vec::with_capacity(n)),
                })
                .collect(),
        };
        let nj = self.joints.len();
        let mut sum: Vec<(u16, f32)> = Vec::with_capacity(nj);
        for v in 0..n {
            let x = p.get(v);
            if let Some(skin) = &mut out.skin {
                sum.clear();
                sum.extend(self.joints.iter().zip(&x[..nj]).map(|(j, w)| (*j, *w)));
                let (j, w) = super::transfer::four_largest(&mut sum);
                skin.joints.push(j);
                skin.weights.push(w);
            }
            let mut at = nj;
            let mut next3 = || {
                at += 3;
                Vec3::from_slice(&x[at - 3..at])
            };
            for t in &mut out.targets {
                t.positions.push(next3());
            }
            for t in &mut out.targets {
                if let Some(normals) = &mut t.normals {
                    normals.push(next3());
                }
            }
            if let Some(tangents) = &mut out.tangents {
                let t = &x[at..at + 4];
                let xyz = Vec3::from_slice(t).try_normalize().unwrap_or(Vec3::X);
                let w = if t[3] < 0.0 { -1.0 } else { 1.0 };
                tangents.push([xyz.x, xyz.y, xyz.z, w]);
            }
        }
        Some(out)
    }
}
