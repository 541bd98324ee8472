//! A scene drawn as one mesh (what the studio's viewport shows of an
//! asset): every instance of every mesh at one level of its chain, posed at
//! one time of one animation. Nodes move by their animated world matrices;
//! a skinned mesh is placed by its joints instead (glTF 2.0 §3.7.3.3: the
//! node's own transform does not apply) through linear blend skinning of
//! the LOD's carried joints and weights ([`super::transfer`]), the same
//! skinning that `--poses` measures ([`super::pose`]). A morphing mesh is
//! first moved by its targets' carried deltas at the weights its node has
//! then (animated, or at rest), as glTF 2.0 §3.7.2.2 orders it: morph, then
//! skin.

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
    /// Each morph target's position deltas.
    targets: Vec<Vec<glam::Vec3>>,
}

impl Level {
    fn new(mesh: &TriMesh, transfer: &Transfer) -> Level {
        let mut mesh = mesh.unwelded();
        mesh.normals = None;
        let extras = transfer.extras(&mesh);
        Level {
            skin: extras.skin,
            targets: extras.targets.into_iter().map(|t| t.positions).collect(),
            mesh,
        }
    }
}

/// `level`'s positions moved by its targets at the weights node `node`
/// has at time `t` of `animation` (at rest without a channel), into `out`.
fn morph_into(
    level: &Level,
    rig: &crate::io::rig::Rig,
    (animation, node, t): (Option<&crate::io::rig::Animation>, usize, f32),
    weights: &mut Vec<f32>,
    out: &mut Vec<glam::Vec3>,
) {
    let n = level.targets.len();
    weights.clear();
    weights.resize(n, 0.0);
    let rest = rig.rest_weights.get(node).map_or(&[][..], Vec::as_slice);
    for (w, r) in weights.iter_mut().zip(rest) {
        *w = *r;
    }
    let channel = animation.and_then(|a| a.morphs.iter().find(|c| c.node == node));
    if let Some(c) = channel {
        c.weights_at(t, &mut weights[..c.targets.min(n)]);
    }
    out.clear();
    out.extend_from_slice(&level.mesh.positions);
    for (deltas, &w) in level.targets.iter().zip(weights.iter()) {
        if w != 0.0 {
            for (p, d) in out.iter_mut().zip(deltas) {
                *p += w * *d;
            }
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
    /// The morphed positions and target weights of the instance being
    /// posed (kept between frames: no allocation per frame).
    morphed: Vec<glam::Vec3>,
    weights: Vec<f32>,
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
            morphed: Vec::new(),
            weights: Vec::new(),
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
        let animation = animation.and_then(|a| scene.rig.animations.get(a));
        let worlds = node_worlds(&scene.rig, animation, t);
        let Some(shown) = self.shown.as_mut() else {
            unreachable!("made above")
        };
        for d in &shown.drawn {
            let levels = &self.levels[d.mesh];
            let l = &levels[level.min(levels.len() - 1)];
            let instance = &scene.meshes[d.mesh].instances[d.instance];
            let base = match l.targets.is_empty() {
                true => &l.mesh.positions,
                false => {
                    let at = (animation, instance.node, t);
                    morph_into(l, &scene.rig, at, &mut self.weights, &mut self.morphed);
                    &self.morphed
                }
            };
            let out = &mut shown.mesh.positions[d.vertices.clone()];
            match (instance.skin, &l.skin) {
                (Some(s), Some(skin)) => skin_into(base, skin, &scene.rig, s, &worlds, out),
                _ => {
                    let world = worlds.get(instance.node).copied().unwrap_or(Mat4::IDENTITY);
                    for (o, p) in out.iter_mut().zip(base) {
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

    /// Khronos' animated morph cube: its animation weighs its two targets,
    /// so the drawn cube moves with it, and at every time each vertex is
    /// the base plus the weighted deltas (read back from the channel).
    #[test]
    fn a_morphing_mesh_moves_with_its_weights() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/models/production/AnimatedMorphCube/AnimatedMorphCube.gltf");
        let Ok(bytes) = std::fs::read(&path) else {
            panic!("{} is a shared model", path.display());
        };
        let scene = crate::io::scene::read(&bytes, path.parent()).unwrap();
        let animation = &scene.rig.animations[0];
        assert_eq!(animation.morphs.len(), 1);
        let channel = &animation.morphs[0];
        assert_eq!(channel.targets, 2);
        let mut drawing = Drawing::new(&scene, None);
        let (rest, _) = drawing.draw(&scene, 0, None, 0.0);
        let rest = rest.clone();
        let level = &drawing.levels[0][0];
        let (base, targets) = (level.mesh.positions.clone(), level.targets.clone());
        let node = scene.meshes[0].instances[0].node;
        let world = node_worlds(&scene.rig, Some(animation), 0.0)[node];
        let (start, end) = animation.span();
        let mut moved = 0.0f32;
        for k in 0..=8 {
            let t = start + (end - start) * k as f32 / 8.0;
            let mut w = [0.0; 2];
            channel.weights_at(t, &mut w);
            let (posed, _) = drawing.draw(&scene, 0, Some(0), t);
            for (v, p) in posed.positions.iter().enumerate() {
                let want = base[v] + w[0] * targets[0][v] + w[1] * targets[1][v];
                assert!(
                    p.distance(world.transform_point3(want)) < 1e-6,
                    "t {t} vertex {v}"
                );
                moved = moved.max(p.distance(rest.positions[v]));
            }
        }
        assert!(moved > 1e-3, "the cube moved {moved}");
    }

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
