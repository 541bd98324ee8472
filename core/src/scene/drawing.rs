//! A scene drawn as one mesh (what the studio's viewport shows of an
//! asset): every instance of every mesh at one level of its chain, posed at
//! one time of one animation. Nodes move by their animated world matrices;
//! a skinned mesh is placed by its joints instead (glTF 2.0 §3.7.3.3: the
//! node's own transform does not apply) through linear blend skinning of
//! the LOD's carried joints and weights ([`super::transfer`]), the same
//! skinning that `--poses` measures ([`super::pose`]).

use std::ops::Range;

use glam::Mat4;

use super::SceneChains;
use super::pose::{node_worlds, skinned};
use super::transfer::Transfer;
use crate::geom::TriMesh;
use crate::io::scene::{Scene, Skinning};

/// One mesh at one level, in mesh space, with its skin.
struct Level {
    mesh: TriMesh,
    skin: Option<Skinning>,
}

/// The meshes of a scene at every level of their chains, ready to pose.
pub struct Drawing {
    /// Per scene mesh, per level (LOD0 first; a mesh without a chain has
    /// only its source).
    levels: Vec<Vec<Level>>,
}

/// Where one instance lies in a drawn mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Drawn {
    pub node: usize,
    /// Its triangles in the drawn mesh.
    pub triangles: Range<usize>,
}

impl Drawing {
    /// The scene's meshes, and with `chains` their LODs (their triangle
    /// part; points and splats are not posed).
    pub fn new(scene: &Scene, chains: Option<&SceneChains>) -> Drawing {
        let levels = scene
            .meshes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let source = Level {
                    mesh: m.mesh.clone(),
                    skin: m.skin.clone(),
                };
                let Some(chain) = chains.and_then(|c| c.chains.get(i)) else {
                    return vec![source];
                };
                let transfer = Transfer::new(m);
                chain
                    .lods
                    .iter()
                    .map(|l| Level {
                        skin: transfer.extras(&l.set.mesh).skin,
                        mesh: l.set.mesh.clone(),
                    })
                    .collect()
            })
            .collect();
        Drawing { levels }
    }

    /// The most levels a mesh has.
    pub fn levels(&self) -> usize {
        self.levels.iter().map(Vec::len).max().unwrap_or(0)
    }

    /// Triangles at `level` (a mesh with fewer levels at its coarsest), each
    /// mesh counted once and once per instance.
    pub fn triangles(&self, scene: &Scene, level: usize) -> (usize, usize) {
        let mut once = 0;
        let mut drawn = 0;
        for (m, levels) in scene.meshes.iter().zip(&self.levels) {
            let t = levels[level.min(levels.len() - 1)].mesh.triangles.len();
            once += t;
            drawn += t * m.instances.len();
        }
        (once, drawn)
    }

    /// Draws `scene` at `level` and time `t` of animation `animation`
    /// (`None`: the rest pose) into `out`, and where each instance lies
    /// into `drawn`; both are cleared first (the studio reuses them).
    pub fn draw(
        &self,
        scene: &Scene,
        level: usize,
        animation: Option<usize>,
        t: f32,
        out: &mut TriMesh,
        drawn: &mut Vec<Drawn>,
    ) {
        out.positions.clear();
        out.triangles.clear();
        out.normals = None;
        out.uvs = None;
        out.colors = None;
        out.parts = None;
        out.materials = None;
        drawn.clear();
        let worlds = node_worlds(
            &scene.rig,
            animation.and_then(|a| scene.rig.animations.get(a)),
            t,
        );
        for (m, levels) in scene.meshes.iter().zip(&self.levels) {
            let l = &levels[level.min(levels.len() - 1)];
            for instance in &m.instances {
                let base = out.positions.len() as u32;
                let first = out.triangles.len();
                match (instance.skin, &l.skin) {
                    (Some(s), Some(skin)) => {
                        let posed = skinned(&l.mesh, skin, &scene.rig, s, &worlds);
                        out.positions.extend(posed.positions);
                    }
                    _ => {
                        let world = worlds.get(instance.node).copied().unwrap_or(Mat4::IDENTITY);
                        out.positions
                            .extend(l.mesh.positions.iter().map(|&p| world.transform_point3(p)));
                    }
                }
                out.triangles
                    .extend(l.mesh.triangles.iter().map(|t| t.map(|i| i + base)));
                drawn.push(Drawn {
                    node: instance.node,
                    triangles: first..out.triangles.len(),
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Khronos' simple skin, drawn at its rest pose and through its animation: the
    /// triangles stay, the vertices that the animated joint weighs move,
    /// and the instance's range covers every triangle.
    #[test]
    fn a_skinned_mesh_moves_with_its_animation() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/models/production/simple_skin/simple_skin.gltf");
        let Ok(bytes) = std::fs::read(&path) else {
            panic!("{} is a shared model", path.display());
        };
        let scene = crate::io::scene::read(&bytes, path.parent()).unwrap();
        let drawing = Drawing::new(&scene, None);
        assert_eq!(drawing.levels(), 1);
        let (mut rest, mut posed) = (TriMesh::default(), TriMesh::default());
        let mut drawn = Vec::new();
        drawing.draw(&scene, 0, None, 0.0, &mut rest, &mut drawn);
        assert_eq!(drawn.len(), 1);
        assert_eq!(drawn[0].triangles, 0..rest.triangles.len());
        let (start, end) = scene.rig.animations[0].span();
        let mut moved = 0;
        for k in 1..8 {
            let t = start + (end - start) * k as f32 / 8.0;
            drawing.draw(&scene, 0, Some(0), t, &mut posed, &mut drawn);
            assert_eq!(rest.triangles, posed.triangles);
            let here = (rest.positions.iter().zip(&posed.positions))
                .filter(|(a, b)| a.distance(**b) > 1e-3)
                .count();
            moved = moved.max(here);
        }
        assert!(moved > 0 && moved < rest.positions.len(), "{moved} moved");
    }
}
