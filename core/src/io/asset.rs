//! What a file holds besides the triangles lodstudio reads, so that nothing
//! is dropped silently (issue 49): a glTF's scene graph, skins, animations,
//! morph targets, cameras, extensions and material textures are counted,
//! and what the outputs do not carry is listed as [`Dropped`] (the CLI's
//! JSON `dropped`, the studio's log). An extension a file *requires* and
//! lodstudio cannot honour refuses the file, naming it: reading it anyway
//! would give wrong geometry or looks without a word.
//!
//! Read from the file's own JSON: the gltf crate, as configured, forgets
//! the extensions it does not know.

use serde::Serialize;
use serde_json::Value;

use super::error::{ParseError, ParseResult};

/// One thing of the input the outputs leave out, and where it was.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Dropped {
    pub what: String,
    #[serde(rename = "where")]
    pub place: String,
}

/// The asset around the mesh: its counts and what is not carried.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct AssetReport {
    pub nodes: usize,
    pub meshes: usize,
    /// Node instances that draw a mesh, in the scene read.
    pub instances: usize,
    pub skins: usize,
    pub animations: usize,
    /// Morph targets over all meshes (a mesh's targets counted once).
    pub morph_targets: usize,
    /// `extensionsUsed`.
    pub extensions: Vec<String>,
    pub dropped: Vec<Dropped>,
}

impl AssetReport {
    /// A file of one mesh and nothing else (OBJ, PLY, OFF, a volume).
    pub fn single() -> AssetReport {
        AssetReport {
            nodes: 1,
            meshes: 1,
            instances: 1,
            skins: 0,
            animations: 0,
            morph_targets: 0,
            extensions: Vec::new(),
            dropped: Vec::new(),
        }
    }
}

/// Why a required extension cannot be read, in the user's words.
fn required_why(name: &str) -> &'static str {
    match name {
        "KHR_draco_mesh_compression" => {
            "Draco-compressed geometry, which lodstudio cannot decode (no maintained Rust decoder): decompress it first, e.g. `gltf-transform copy IN OUT`"
        }
        _ => "an extension lodstudio cannot carry",
    }
}

/// Refuses a file that requires an extension, naming each and why it
/// cannot be read (before any other check, so the message says it).
pub fn check_required(root: &Value) -> ParseResult<()> {
    let required: Vec<String> = (root.get("extensionsRequired").and_then(Value::as_array))
        .map_or(&[][..], |a| a)
        .iter()
        .filter(|r| !r.as_str().is_some_and(|r| READ.contains(&r)))
        .map(|r| match r.as_str() {
            Some(name) => format!("{name} ({})", required_why(name)),
            None => format!("{r} (not an extension name)"),
        })
        .collect();
    match required.is_empty() {
        true => Ok(()),
        false => Err(ParseError::file(format!(
            "expected no required extension lodstudio cannot read, found {}",
            required.join("; ")
        ))),
    }
}

/// Extensions whose content the reader takes in whole: quantized
/// attributes are dequantized on load (`gltf::dequantized`), so the outputs
/// carry the same geometry in floats; compressed views are decoded
/// (`meshopt_compression`), so the outputs carry them plain.
pub const READ: [&str; 3] = [
    "KHR_mesh_quantization",
    super::meshopt_compression::NAMES[0],
    super::meshopt_compression::NAMES[1],
];

/// Material textures: whether the outputs carry each (on `TEXCOORD_0`, the
/// only UV set read), and its name in the list of what is left out.
const TEXTURES: [(&str, &str, bool); 5] = [
    ("baseColorTexture", "base-colour texture", true),
    ("normalTexture", "normal texture", true),
    ("occlusionTexture", "occlusion texture", false),
    ("emissiveTexture", "emissive texture", false),
    (
        "metallicRoughnessTexture",
        "metallic-roughness texture",
        false,
    ),
];

/// The attributes a primitive's triangles are read with.
const READ_ATTRIBUTES: [&str; 4] = ["POSITION", "NORMAL", "TEXCOORD_0", "COLOR_0"];

/// How much of a glTF the outputs carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Carried {
    /// One mesh: every instance flattened into world space (`gltf::read`).
    Flat,
    /// The document as read, with LOD meshes put in (`scene::read`): only
    /// what a primitive holds beyond the attributes read can be lost.
    Scene,
}

/// The attributes a scene's primitives are read and written with
/// (`JOINTS_1`/`WEIGHTS_1` are read, and written folded into `_0`).
const SCENE_ATTRIBUTES: [&str; 9] = [
    "POSITION",
    "NORMAL",
    "TANGENT",
    "TEXCOORD_0",
    "COLOR_0",
    "JOINTS_0",
    "WEIGHTS_0",
    "JOINTS_1",
    "WEIGHTS_1",
];

/// The report of a glTF's JSON `root`, whose scene `scene` (its index) is
/// the one read, for outputs that carry `carried`; refuses a required
/// extension.
pub fn audit_gltf(
    root: &Value,
    scene: Option<usize>,
    carried: Carried,
) -> ParseResult<AssetReport> {
    let flat = carried == Carried::Flat;
    check_required(root)?;
    let list = |key: &str| {
        root.get(key)
            .and_then(Value::as_array)
            .map_or(&[][..], |a| a)
    };
    let names = |key: &str| -> Vec<String> {
        list(key)
            .iter()
            .filter_map(|v| v.as_str().map(str::to_string))
            .collect()
    };
    let label = |kind: &str, i: usize, v: &Value| match v.get("name").and_then(Value::as_str) {
        Some(n) => format!("{kind} {i} \"{n}\""),
        None => format!("{kind} {i}"),
    };
    let mut dropped = Vec::new();
    let mut drop = |what: &str, place: String| {
        dropped.push(Dropped {
            what: what.to_string(),
            place,
        })
    };
    let (nodes, meshes) = (list("nodes"), list("meshes"));
    // Instances per mesh in the scene read (the reader's own walk).
    let mut uses = vec![0usize; meshes.len()];
    let roots: Vec<usize> = match scene.and_then(|s| list("scenes").get(s)) {
        Some(s) => indices(s.get("nodes")),
        None => (0..nodes.len()).collect(),
    };
    let mut stack: Vec<(usize, usize)> = roots.into_iter().map(|n| (n, 0)).collect();
    let mut visits = 0usize;
    while let Some((n, depth)) = stack.pop() {
        visits += 1;
        // The reader refuses cycles and explosive DAGs; counting stops too.
        if depth > nodes.len() || visits > super::gltf::MAX_INSTANCES {
            break;
        }
        let Some(node) = nodes.get(n) else { continue };
        if let Some(m) = node.get("mesh").and_then(Value::as_u64)
            && let Some(u) = uses.get_mut(m as usize)
        {
            *u += 1;
        }
        stack.extend(
            indices(node.get("children"))
                .into_iter()
                .map(|c| (c, depth + 1)),
        );
    }
    let instances = uses.iter().sum();
    let mut morph_targets = 0;
    for mesh in meshes {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        morph_targets += prims
            .map_or(&[][..], |a| a)
            .iter()
            .map(|p| array_len(p, "targets"))
            .max()
            .unwrap_or(0);
    }
    let report = |dropped| AssetReport {
        nodes: nodes.len(),
        meshes: meshes.len(),
        instances,
        skins: list("skins").len(),
        animations: list("animations").len(),
        morph_targets,
        extensions: names("extensionsUsed"),
        dropped,
    };
    if !flat {
        for (m, mesh) in meshes.iter().enumerate() {
            let prims = mesh.get("primitives").and_then(Value::as_array);
            for (p, prim) in prims.map_or(&[][..], |a| a).iter().enumerate() {
                let at = || format!("{} primitive {p}", label("mesh", m, mesh));
                // Points and lines are carried as they are.
                if prim.get("mode").and_then(Value::as_u64).unwrap_or(4) < 4 {
                    continue;
                }
                if let Some(attributes) = prim.get("attributes").and_then(Value::as_object) {
                    for name in attributes.keys() {
                        if !SCENE_ATTRIBUTES.contains(&name.as_str()) {
                            drop(&format!("attribute {name}"), at());
                        }
                    }
                    if attributes.contains_key("JOINTS_1") {
                        drop(
                            "influences past four (JOINTS_1/WEIGHTS_1)",
                            format!(
                                "{}: all eight are read and carried; each written vertex keeps \
                                 its four largest, renormalised, in JOINTS_0/WEIGHTS_0",
                                at()
                            ),
                        );
                    }
                }
                let targets = prim.get("targets").and_then(Value::as_array);
                for target in targets.map_or(&[][..], |a| a) {
                    for name in target.as_object().into_iter().flat_map(|t| t.keys()) {
                        if name != "POSITION" && name != "NORMAL" {
                            drop(&format!("morph target {name}"), at());
                        }
                    }
                }
                for name in extension_names(prim) {
                    drop(&name, at());
                }
            }
        }
        dropped.dedup();
        return Ok(report(dropped));
    }
    if nodes.len() > 1 || nodes.iter().any(|n| n.get("name").is_some()) {
        drop(
            "scene graph",
            format!(
                "{} nodes: names and hierarchy flattened into one mesh, transforms applied",
                nodes.len()
            ),
        );
    }
    for (m, (mesh, &k)) in meshes.iter().zip(&uses).enumerate() {
        if k > 1 {
            drop(
                "instancing",
                format!(
                    "{}: used by {k} nodes, written {k} times",
                    label("mesh", m, mesh)
                ),
            );
        }
    }
    if let Some(s) = scene {
        for (i, other) in list("scenes").iter().enumerate().filter(|(i, _)| *i != s) {
            drop(
                "scene",
                format!("{}: only scene {s} is read", label("scene", i, other)),
            );
        }
    }
    for (m, mesh) in meshes.iter().enumerate() {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        let mut targets = 0;
        for (p, prim) in prims.map_or(&[][..], |a| a).iter().enumerate() {
            let at = || format!("{} primitive {p}", label("mesh", m, mesh));
            let mode = prim.get("mode").and_then(Value::as_u64).unwrap_or(4);
            if mode < 4 {
                drop("points or lines primitive", at());
            }
            if let Some(attributes) = prim.get("attributes").and_then(Value::as_object) {
                for name in attributes.keys() {
                    if !READ_ATTRIBUTES.contains(&name.as_str()) {
                        drop(&format!("attribute {name}"), at());
                    }
                }
            }
            targets = targets.max(array_len(prim, "targets"));
        }
        if targets > 0 {
            drop(
                "morph targets",
                format!("{}: {targets} targets", label("mesh", m, mesh)),
            );
        }
    }
    for (i, skin) in list("skins").iter().enumerate() {
        let joints = array_len(skin, "joints");
        let at = label("skin", i, skin);
        drop(
            "skin",
            format!("{at} ({joints} joints): read in its bind pose"),
        );
    }
    for (i, animation) in list("animations").iter().enumerate() {
        let channels = array_len(animation, "channels");
        let at = label("animation", i, animation);
        drop("animation", format!("{at} ({channels} channels)"));
    }
    for (i, camera) in list("cameras").iter().enumerate() {
        drop("camera", label("camera", i, camera));
    }
    for (i, material) in list("materials").iter().enumerate() {
        let pbr = material.get("pbrMetallicRoughness");
        for (key, what, carried) in TEXTURES {
            let Some(info) = material.get(key).or_else(|| pbr.and_then(|p| p.get(key))) else {
                continue;
            };
            let set = info.get("texCoord").and_then(Value::as_u64).unwrap_or(0);
            match (carried, set) {
                (true, 0) => {}
                (true, n) => drop(
                    &format!("{what} on TEXCOORD_{n}"),
                    label("material", i, material),
                ),
                (false, _) => drop(what, label("material", i, material)),
            }
        }
    }
    // Where each extension appears: the outputs carry none of them.
    for (key, kind) in [
        ("materials", "material"),
        ("textures", "texture"),
        ("images", "image"),
        ("nodes", "node"),
        ("meshes", "mesh"),
        ("scenes", "scene"),
    ] {
        for (i, item) in list(key).iter().enumerate() {
            for name in extension_names(item) {
                drop(&name, label(kind, i, item));
            }
        }
    }
    for name in extension_names(root) {
        drop(&name, "the asset".into());
    }
    Ok(report(dropped))
}

/// The length of `item`'s array `key` (0 without one).
fn array_len(item: &Value, key: &str) -> usize {
    item.get(key).and_then(Value::as_array).map_or(0, Vec::len)
}

/// Node indices in a JSON array (others skipped: the reader refuses them).
fn indices(v: Option<&Value>) -> Vec<usize> {
    v.and_then(Value::as_array)
        .map_or(&[][..], |a| a)
        .iter()
        .filter_map(|i| i.as_u64().map(|i| i as usize))
        .collect()
}

/// The extensions an object of the JSON names, and those of the texture
/// references inside a material (`KHR_texture_transform` lives there).
fn extension_names(item: &Value) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut add = |v: &Value| {
        if let Some(e) = v.get("extensions").and_then(Value::as_object) {
            out.extend(e.keys().cloned());
        }
    };
    add(item);
    let pbr = item.get("pbrMetallicRoughness");
    for key in [
        "baseColorTexture",
        "normalTexture",
        "occlusionTexture",
        "emissiveTexture",
        "metallicRoughnessTexture",
    ] {
        if let Some(t) = item.get(key).or_else(|| pbr.and_then(|p| p.get(key))) {
            add(t);
        }
    }
    out.sort();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn whats(r: &AssetReport) -> Vec<&str> {
        r.dropped.iter().map(|d| d.what.as_str()).collect()
    }

    /// A skinned, morphing, animated scene with a camera, a mesh used
    /// twice and an optional extension: every piece is counted and listed.
    #[test]
    fn what_is_not_carried_is_listed() {
        let root = json!({
            "scenes": [{"nodes": [0]}, {"nodes": [1]}],
            "nodes": [
                {"name": "root", "children": [1, 2]},
                {"mesh": 0, "skin": 0},
                {"mesh": 0, "camera": 0}
            ],
            "meshes": [{"name": "body", "primitives": [
                {"attributes": {"POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2},
                 "targets": [{"POSITION": 3}, {"POSITION": 4}]},
                {"attributes": {"POSITION": 0}, "mode": 1}
            ]}],
            "skins": [{"joints": [0, 1]}],
            "animations": [{"name": "walk", "channels": [{}, {}]}],
            "cameras": [{}],
            "materials": [{"normalTexture": {"index": 0, "texCoord": 1},
                           "occlusionTexture": {"index": 0},
                           "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                               "extensions": {"KHR_texture_transform": {}}}},
                           "extensions": {"KHR_materials_clearcoat": {}}}],
            "extensionsUsed": ["KHR_texture_transform", "KHR_materials_clearcoat"]
        });
        let r = audit_gltf(&root, Some(0), Carried::Flat).unwrap();
        assert_eq!(
            (
                r.nodes,
                r.meshes,
                r.instances,
                r.skins,
                r.animations,
                r.morph_targets
            ),
            (3, 1, 2, 1, 1, 2)
        );
        assert_eq!(
            r.extensions,
            ["KHR_texture_transform", "KHR_materials_clearcoat"]
        );
        for what in [
            "scene graph",
            "instancing",
            "scene",
            "points or lines primitive",
            "attribute JOINTS_0",
            "attribute WEIGHTS_0",
            "morph targets",
            "skin",
            "animation",
            "camera",
            "normal texture on TEXCOORD_1",
            "occlusion texture",
            "KHR_texture_transform",
            "KHR_materials_clearcoat",
        ] {
            assert!(
                whats(&r).contains(&what),
                "{what} not listed: {:?}",
                r.dropped
            );
        }
        let anim = r.dropped.iter().find(|d| d.what == "animation").unwrap();
        assert_eq!(anim.place, "animation 0 \"walk\" (2 channels)");
    }

    /// A required extension refuses the file, naming it and why.
    #[test]
    fn a_required_extension_refuses_the_file_by_name() {
        let root = json!({"extensionsRequired": ["KHR_draco_mesh_compression"]});
        let e = audit_gltf(&root, None, Carried::Flat).unwrap_err().expected;
        assert!(
            e.contains("KHR_draco_mesh_compression") && e.contains("Draco"),
            "{e}"
        );
    }

    /// One plain mesh in one unnamed node: nothing to list.
    #[test]
    fn a_plain_mesh_drops_nothing() {
        let root = json!({
            "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}]
        });
        let r = audit_gltf(&root, Some(0), Carried::Flat).unwrap();
        assert!(r.dropped.is_empty(), "{:?}", r.dropped);
        assert_eq!((r.nodes, r.meshes, r.instances), (1, 1, 1));
    }
}
