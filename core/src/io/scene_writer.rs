//! A scene's LODs written back into the scene (issue 49, DESIGN "Assets,
//! not meshes"): the input's document carried unchanged, each mesh's
//! primitives replaced by its LOD0, and the lower LODs added in the layout
//! an engine reads:
//!
//! - `msft_lod`: each node that draws a mesh names nodes of the lower LODs
//!   in `extensions.MSFT_lod.ids` (copies of it, out of any scene), with
//!   its switch coverages in `extras.MSFT_screencoverage` (Babylon.js); a
//!   node with children first hands its mesh to a child `NAME_LOD0`, as a
//!   lower LOD replaces its head's children too;
//! - `nodes`: under each such node, children `NAME_LOD0…NAME_LODn` (the
//!   suffix Unity's LOD Group import, Unreal's and Godot's importers
//!   recognise), the node's mesh, skin and weights moved onto them;
//! - `files`: one whole scene per level (`OUT.glb` level 0, `OUT_LOD1.glb`…).
//!
//! Animations that drive a node's morph weights get a channel per LOD node
//! (the same sampler), so every LOD morphs as the original did.

use serde_json::{Value, json};

use super::gltf_writer::{GltfWriter, PointsAs, ScenePrimitives, glb};
use super::scene::{Scene, SceneMesh, VertexExtras};
use crate::geom::TriMesh;
use crate::lod::DrawSet;

/// How a scene's LOD chains are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// `MSFT_lod` on each node (Babylon.js).
    #[default]
    MsftLod,
    /// Children `NAME_LOD0…NAME_LODn` (Unity, Unreal, Godot importers).
    Nodes,
    /// One file per level.
    Files,
}

impl Layout {
    pub const ALL: [Layout; 3] = [Layout::MsftLod, Layout::Nodes, Layout::Files];

    /// The files this layout writes at `output`: it, and for `files` one
    /// per level after the first (`OUT_LOD1.glb`…).
    pub fn outputs(self, output: &std::path::Path, levels: usize) -> Vec<std::path::PathBuf> {
        let mut out = vec![output.to_path_buf()];
        if self == Layout::Files {
            let stem = output.file_stem().unwrap_or_default().to_string_lossy();
            let ext = output.extension().unwrap_or_default().to_string_lossy();
            for k in 1..levels {
                out.push(output.with_file_name(format!("{stem}_LOD{k}.{ext}")));
            }
        }
        out
    }

    pub fn name(self) -> &'static str {
        match self {
            Layout::MsftLod => "msft_lod",
            Layout::Nodes => "nodes",
            Layout::Files => "files",
        }
    }
}

impl std::str::FromStr for Layout {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Layout::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| format!("{s:?} is not one of msft_lod, nodes, files"))
    }
}

/// What `MSFT_screencoverage` measures, written into the file beside it.
pub const COVERAGE_NOTE: &str = "MSFT_screencoverage[i]: the smallest screen coverage at which LOD i \
     is shown, coverage being the projected diameter of the node's bounding sphere (the mesh's \
     bounding sphere, its radius times the largest singular value of the node's world matrix) over \
     the viewport height; LOD i's certified error then projects to at most the recipe's pixel \
     tolerance. It is a height share, not an area share: Babylon's addLODLevel with \
     useLODScreenCoverage compares the sphere's projected disc against the screen's area, \
     pi*c*c/(4*aspect) for this c; a camera distance d = r*sigma/(c*tan(fovY/2)) is exact for every \
     client. The nodes layout keeps the same values in the parent's extras.lod_screencoverage.";

/// One mesh's LOD chain, as the writer needs it.
pub struct MeshLods<'a> {
    pub mesh: &'a SceneMesh,
    /// The glTF material of each part of the LODs' meshes.
    pub materials: &'a [Option<usize>],
    /// LOD0 first.
    pub sets: Vec<&'a DrawSet>,
    /// `MSFT_screencoverage`: one per LOD (`lod::chain::lod_screen_coverages`).
    pub coverages: Vec<f32>,
    /// What each written vertex carries besides its surface.
    pub extras: &'a (dyn Fn(&TriMesh) -> VertexExtras + Sync),
}

impl MeshLods<'_> {
    /// LOD `k`, or the coarsest where the chain is shorter.
    fn set(&self, k: usize) -> &DrawSet {
        self.sets[k.min(self.sets.len() - 1)]
    }
}

/// The scene with its LODs, as GLBs: one for `msft_lod` and `nodes`, one
/// per level for `files` (level 0 first).
pub fn write(
    scene: &Scene,
    lods: &[MeshLods],
    layout: Layout,
    points_as: PointsAs,
) -> Vec<Vec<u8>> {
    match layout {
        Layout::Files => {
            let levels = lods.iter().map(|l| l.sets.len()).max().unwrap_or(1);
            (0..levels)
                .map(|k| level_file(scene, lods, k, points_as))
                .collect()
        }
        _ => vec![chain_file(scene, lods, layout, points_as)],
    }
}

/// The node's label for its LOD nodes: its name, else its mesh's.
fn node_name(node: &Value, mesh: &SceneMesh, index: usize) -> String {
    match node.get("name").and_then(Value::as_str) {
        Some(n) => n.to_string(),
        None => format!("{}_{index}", mesh.name),
    }
}

/// The mesh `k` of a chain: the original mesh's object (its name,
/// weights, extras) with `primitives` (the written ones, then the points
/// and lines primitives it had, carried as they are).
fn lod_mesh(original: &Value, primitives: Vec<Value>, name: Option<String>) -> Value {
    let mut mesh = original.clone();
    let mut all = primitives;
    let kept = original["primitives"].as_array().into_iter().flatten();
    all.extend(
        kept.filter(|p| p["mode"].as_u64().is_some_and(|m| m < 4))
            .cloned(),
    );
    mesh["primitives"] = Value::Array(all);
    if let Some(name) = name {
        mesh["name"] = json!(name);
    }
    mesh
}

/// Writes each chain's meshes: LOD `k` of mesh m in place of mesh m when
/// `in_place == Some(k)`, else LOD0 in place and the others appended.
/// Returns each chain's mesh index per LOD.
fn write_meshes(w: &mut GltfWriter, lods: &[MeshLods], in_place: Option<usize>) -> Vec<Vec<usize>> {
    let mut out = Vec::with_capacity(lods.len());
    for l in lods {
        let index = l.mesh.index;
        let original = w.meshes_mut()[index].clone();
        let scene = ScenePrimitives {
            materials: l.materials,
            source: l.mesh.mesh.materials.as_ref(),
            extras: l.extras,
        };
        let mut ids = Vec::new();
        let levels: Vec<usize> = match in_place {
            Some(k) => vec![k],
            None => (0..l.sets.len()).collect(),
        };
        for (i, k) in levels.into_iter().enumerate() {
            let primitives = w.scene_primitives(l.set(k), &scene);
            if i == 0 {
                w.meshes_mut()[index] = lod_mesh(&original, primitives, None);
                ids.push(index);
            } else {
                let name = format!("{}_LOD{k}", l.mesh.name);
                w.meshes_mut()
                    .push(lod_mesh(&original, primitives, Some(name)));
                ids.push(w.meshes_mut().len() - 1);
            }
        }
        out.push(ids);
    }
    out
}

/// Sets `extras[key]` (an `extras` that is not an object is left alone).
fn set_extra(item: &mut Value, key: &str, value: Value) {
    if item.get("extras").is_none() {
        item["extras"] = json!({});
    }
    if let Some(extras) = item["extras"].as_object_mut() {
        extras.insert(key.into(), value);
    }
}

/// The properties of a node that place and deform its mesh.
const PLACEMENT: [&str; 4] = ["translation", "rotation", "scale", "matrix"];

fn chain_file(scene: &Scene, lods: &[MeshLods], layout: Layout, points_as: PointsAs) -> Vec<u8> {
    let mut w = GltfWriter::extending(scene.doc.clone(), scene.bin.clone(), points_as);
    let meshes = write_meshes(&mut w, lods, None);
    // Morph weight channels to copy: (driven node, its LOD nodes).
    let mut driven: Vec<(usize, Vec<usize>, bool)> = Vec::new();
    for (l, ids) in lods.iter().zip(&meshes) {
        for instance in &l.mesh.instances {
            let n = instance.node;
            let node = w.nodes_mut()[n].clone();
            let name = node_name(&node, l.mesh, n);
            let lod_node = |k: usize, with_placement: bool| {
                let mut new = json!({"name": format!("{name}_LOD{k}"), "mesh": ids[k]});
                let mut keys: Vec<&str> = vec!["skin", "weights"];
                if with_placement {
                    keys.extend(PLACEMENT);
                }
                for key in keys {
                    if let Some(v) = node.get(key) {
                        new[key] = v.clone();
                    }
                }
                new
            };
            match layout {
                Layout::MsftLod if ids.len() > 1 => {
                    // A lower LOD node replaces its head whole, children
                    // included (Babylon.js swaps the nodes): a node with
                    // children keeps them and its placement, and its mesh
                    // moves onto a child `NAME_LOD0` that heads the LODs.
                    let parent = node["children"].as_array().is_some_and(|c| !c.is_empty());
                    let lower: Vec<Value> = (1..ids.len()).map(|k| lod_node(k, !parent)).collect();
                    let mut lower: Vec<usize> = lower.into_iter().map(|v| w.push_node(v)).collect();
                    let head = match parent {
                        false => n,
                        true => {
                            let head = w.push_node(lod_node(0, false));
                            hand_mesh_to(&mut w.nodes_mut()[n], &[head]);
                            head
                        }
                    };
                    let node = &mut w.nodes_mut()[head];
                    if node.get("extensions").is_none() {
                        node["extensions"] = json!({});
                    }
                    node["extensions"]["MSFT_lod"] = json!({"ids": lower});
                    set_extra(node, "MSFT_screencoverage", json!(l.coverages));
                    if parent {
                        lower.insert(0, head);
                    }
                    driven.push((n, lower, parent));
                }
                Layout::Nodes => {
                    let children: Vec<Value> = (0..ids.len()).map(|k| lod_node(k, false)).collect();
                    let children: Vec<usize> =
                        children.into_iter().map(|v| w.push_node(v)).collect();
                    let parent = &mut w.nodes_mut()[n];
                    hand_mesh_to(parent, &children);
                    set_extra(parent, "lod_screencoverage", json!(l.coverages));
                    driven.push((n, children, true));
                }
                _ => {}
            }
        }
    }
    if layout == Layout::MsftLod && meshes.iter().any(|ids| ids.len() > 1) {
        w.uses("MSFT_lod");
    }
    let (mut doc, bin) = w.document(&[]);
    let bin = super::compact::compact(&mut doc, bin);
    retarget_weights(&mut doc, &driven);
    set_extra(
        &mut doc["asset"],
        "MSFT_screencoverage",
        json!(COVERAGE_NOTE),
    );
    glb(&doc, bin)
}

/// `node` without its mesh, skin and weights, with `children` (the nodes
/// that now draw them) after its own.
fn hand_mesh_to(node: &mut Value, children: &[usize]) {
    if let Some(o) = node.as_object_mut() {
        for key in ["mesh", "skin", "weights"] {
            o.remove(key);
        }
    }
    let mut all: Vec<Value> = node["children"].as_array().cloned().unwrap_or_default();
    all.extend(children.iter().map(|c| json!(c)));
    node["children"] = Value::Array(all);
}

/// Copies each animation channel that drives a node's morph weights to
/// its LOD nodes; `moved`: the node lost its mesh, so its own channel goes.
fn retarget_weights(doc: &mut Value, driven: &[(usize, Vec<usize>, bool)]) {
    let Some(animations) = doc.get_mut("animations").and_then(Value::as_array_mut) else {
        return;
    };
    for animation in animations {
        let Some(channels) = animation.get_mut("channels").and_then(Value::as_array_mut) else {
            continue;
        };
        let mut out = Vec::with_capacity(channels.len());
        for channel in channels.drain(..) {
            let target = &channel["target"];
            let hit = (target["path"] == "weights")
                .then(|| target["node"].as_u64())
                .flatten()
                .and_then(|n| driven.iter().find(|(d, _, _)| *d as u64 == n));
            let Some((_, lods, moved)) = hit else {
                out.push(channel);
                continue;
            };
            if !moved {
                out.push(channel.clone());
            }
            for &lod in lods {
                let mut copy = channel.clone();
                copy["target"]["node"] = json!(lod);
                out.push(copy);
            }
        }
        *channels = out;
    }
}

fn level_file(scene: &Scene, lods: &[MeshLods], k: usize, points_as: PointsAs) -> Vec<u8> {
    let mut w = GltfWriter::extending(scene.doc.clone(), scene.bin.clone(), points_as);
    write_meshes(&mut w, lods, Some(k));
    let (mut doc, bin) = w.document(&[]);
    let bin = super::compact::compact(&mut doc, bin);
    set_extra(&mut doc["asset"], "lod_level", json!(k));
    glb(&doc, bin)
}
