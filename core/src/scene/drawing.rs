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
use super::pose::{node_worlds, skin_into};
use super::transfer::Transfer;
use crate::geom::TriMesh;
use crate::io::scene::{Scene, Skinning};

/// One mesh at one level, in mesh space: one vertex per wedge (each corner
/// its side of a UV seam, materials and parts kept), normals left to the
/// viewer to derive from the posed surface; with its skin.
struct Level {
    mesh: TriMesh,
    skin: Option<Skinning>,
}

impl Level {
    fn new(mesh: &TriMesh, transfer: &Transfer) -> Level {
        let mut mesh = mesh.unwelded();
        mesh.normals = None;
        Level {
            skin: transfer.extras(&mesh).skin,
            mesh,
        }
    }
}

/// The meshes of a scene at every level of their chains, ready to pose.
pub struct Drawing {
    /// Per scene mesh, per level (LOD0 first; a mesh without a chain has
    /// only its source).
    levels: Vec<Vec<Level>>,
    /// Every instance at the level drawn last, whose positions each pose
    /// rewrites in place (the rest is made once per level).
    shown: Option<Shown>,
}

struct Shown {
    level: usize,
    mesh: TriMesh,
    drawn: Vec<Drawn>,
}

/// Where one instance lies in a drawn mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Drawn {
    pub node: usize,
    /// Its triangles in the drawn mesh.
    pub triangles: Range<usize>,
    /// Its vertices, and the scene mesh (its place in `Scene::meshes`) and
    /// instance they come from.
    vertices: Range<usize>,
    mesh: usize,
    instance: usize,
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
                let transfer = Transfer::new(m);
                match chains.and_then(|c| c.chains.get(i)) {
                    None => vec![Level::new(&m.mesh, &transfer)],
                    Some(chain) => chain
                        .lods
                        .iter()
                        .map(|l| Level::new(&l.set.mesh, &transfer))
                        .collect(),
                }
            })
            .collect();
        Drawing {
            levels,
            shown: None,
        }
    }

    /// The most levels a mesh has.
    pub fn levels(&self) -> usize {
        self.levels.iter().map(Vec::len).max().unwrap_or(0)
    }

    /// Mesh `m`'s level `level` (its coarsest where it has fewer).
    fn level(&self, m: usize, level: usize) -> &Level {
        let levels = &self.levels[m];
        &levels[level.min(levels.len() - 1)]
    }

    /// Triangles at `level`, each mesh counted once and once per instance.
    pub fn triangles(&self, scene: &Scene, level: usize) -> (usize, usize) {
        let mut once = 0;
        let mut drawn = 0;
        for (i, m) in scene.meshes.iter().enumerate() {
            let t = self.level(i, level).mesh.triangles.len();
            once += t;
            drawn += t * m.instances.len();
        }
        (once, drawn)
    }

    /// `scene` at `level`, posed at time `t` of animation `animation`
    /// (`None`: the rest pose), and where each instance lies in it.
    pub fn draw(
        &mut self,
        scene: &Scene,
        level: usize,
        animation: Option<usize>,
        t: f32,
    ) -> (&TriMesh, &[Drawn]) {
        if self.shown.as_ref().is_none_or(|s| s.level != level) {
            self.shown = Some(self.instances(scene, level));
        }
        let worlds = node_worlds(
            &scene.rig,
            animation.and_then(|a| scene.rig.animations.get(a)),
            t,
        );
        let Some(shown) = self.shown.as_mut() else {
            unreachable!("made above")
        };
        for d in &shown.drawn {
            let levels = &self.levels[d.mesh];
            let l = &levels[level.min(levels.len() - 1)];
            let instance = &scene.meshes[d.mesh].instances[d.instance];
            let out = &mut shown.mesh.positions[d.vertices.clone()];
            match (instance.skin, &l.skin) {
                (Some(s), Some(skin)) => {
                    skin_into(&l.mesh.positions, skin, &scene.rig, s, &worlds, out)
                }
                _ => {
                    let world = worlds.get(instance.node).copied().unwrap_or(Mat4::IDENTITY);
                    for (o, p) in out.iter_mut().zip(&l.mesh.positions) {
                        *o = world.transform_point3(*p);
                    }
                }
            }
        }
        (&shown.mesh, &shown.drawn)
    }

    /// Every instance at `level`, in mesh space, one after the other.
    fn instances(&self, scene: &Scene, level: usize) -> Shown {
        let mut pieces = Vec::new();
        let mut drawn = Vec::new();
        let (mut vertices, mut triangles) = (0, 0);
        for (i, m) in scene.meshes.iter().enumerate() {
            let l = self.level(i, level);
            for (k, instance) in m.instances.iter().enumerate() {
                let (v, t) = (l.mesh.positions.len(), l.mesh.triangles.len());
                drawn.push(Drawn {
                    node: instance.node,
                    triangles: triangles..triangles + t,
                    vertices: vertices..vertices + v,
                    mesh: i,
                    instance: k,
                });
                (vertices, triangles) = (vertices + v, triangles + t);
                pieces.push(l.mesh.clone());
            }
        }
        Shown {
            level,
            mesh: TriMesh::concat(&pieces),
            drawn,
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
        let mut drawing = Drawing::new(&scene, None);
        assert_eq!(drawing.levels(), 1);
        let (rest, drawn) = drawing.draw(&scene, 0, None, 0.0);
        let rest = rest.clone();
        assert_eq!(drawn.len(), 1);
        assert_eq!(drawn[0].triangles, 0..rest.triangles.len());
        let (start, end) = scene.rig.animations[0].span();
        let mut moved = 0;
        for k in 1..8 {
            let t = start + (end - start) * k as f32 / 8.0;
            let (posed, _) = drawing.draw(&scene, 0, Some(0), t);
            assert_eq!(rest.triangles, posed.triangles);
            let here = (rest.positions.iter().zip(&posed.positions))
                .filter(|(a, b)| a.distance(**b) > 1e-3)
                .count();
            moved = moved.max(here);
        }
        assert!(moved > 0 && moved < rest.positions.len(), "{moved} moved");
    }
}
