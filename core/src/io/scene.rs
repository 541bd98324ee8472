//! A glTF read as a scene (issue 49): the document as the file has it
//! (nodes, names, transforms, skins, animations, cameras, materials and
//! their extensions), and each mesh the default scene draws read once, in
//! its own space, with the nodes that use it and what its vertices carry
//! besides the surface (skin joints and weights, morph target deltas).
//!
//! The methods work on [`SceneMesh::mesh`]; `scene_writer` puts their LODs
//! back into [`Scene::doc`]. The document's buffers are joined into one
//! binary ([`Scene::bin`], buffer 0) and images stored as files are
//! embedded, so every output is one self-contained GLB whatever the input
//! referenced (through `confine`, as any read).

use std::path::Path;

use glam::{Mat4, Vec3};
use serde_json::{Value, json};

use super::asset::{AssetReport, Carried, audit_gltf};
use super::error::{ParseError, ParseResult};
use super::gltf::{ImageCache, MeshReader, check_accessor, load_buffers, parse, read_uri};
use crate::geom::{Material, TriMesh};

/// A glTF scene: its document, one binary, and the meshes its default
/// scene draws.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file's JSON, its buffers joined into buffer 0 and file images
    /// embedded as buffer views; everything else as read.
    pub doc: Value,
    pub bin: Vec<u8>,
    /// The default scene's index (else the first scene's).
    pub scene: Option<usize>,
    /// The meshes the scene draws, by glTF index.
    pub meshes: Vec<SceneMesh>,
    /// What poses them: nodes' rest transforms, skins, animations.
    pub rig: super::rig::Rig,
    pub report: AssetReport,
}

/// One mesh of the scene, read once in its own space.
#[derive(Debug, Clone)]
pub struct SceneMesh {
    /// Its index in the document's `meshes`.
    pub index: usize,
    /// Its name, else `mesh{index}`.
    pub name: String,
    /// Its triangle primitives, one part per material, in mesh space.
    pub mesh: TriMesh,
    /// The glTF material of each part (`None`: the default material).
    pub materials: Vec<Option<usize>>,
    /// The nodes of the scene that draw it.
    pub instances: Vec<Instance>,
    /// `JOINTS_0`/`WEIGHTS_0` per vertex of `mesh`, where it has them.
    pub skin: Option<Skinning>,
    /// `TANGENT` per vertex of `mesh` (xyz, w the bitangent's sign), where
    /// it has them: materials with normal maps need them.
    pub tangents: Option<Vec<[f32; 4]>>,
    /// Morph targets: per target, its deltas per vertex of `mesh`.
    pub targets: Vec<MorphTarget>,
}

/// A node that draws a mesh, and where.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Instance {
    pub node: usize,
    /// The node's world matrix (its ancestors' transforms applied).
    pub world: Mat4,
    /// The node's skin (its joints then place the mesh, not `world`).
    pub skin: Option<usize>,
}

impl Instance {
    /// How far a mesh-space length can grow in world space: the largest
    /// singular value σ_max of the world matrix's linear part. A point
    /// moved by ε in mesh space moves by |M·d| ≤ σ_max·|d| in world space,
    /// so a certified mesh-space bound ε is a world-space bound σ_max·ε.
    pub fn scale(&self) -> f32 {
        largest_singular_value(glam::Mat3::from_mat4(self.world))
    }
}

/// σ_max of `m`: the square root of the largest eigenvalue of MᵀM
/// (symmetric 3×3, by the trigonometric method, rounded up by 1e-6
/// relative so that a bound scaled by it stays a bound).
pub fn largest_singular_value(m: glam::Mat3) -> f32 {
    let a = (m.transpose() * m)
        .to_cols_array_2d()
        .map(|c| c.map(f64::from));
    let p1 = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let largest = if p1 <= 1e-30 * q.abs().max(1e-30) {
        a[0][0].max(a[1][1]).max(a[2][2])
    } else {
        let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let b = |i: usize, j: usize| (a[i][j] - if i == j { q } else { 0.0 }) / p;
        let det = b(0, 0) * (b(1, 1) * b(2, 2) - b(1, 2) * b(2, 1))
            - b(0, 1) * (b(1, 0) * b(2, 2) - b(1, 2) * b(2, 0))
            + b(0, 2) * (b(1, 0) * b(2, 1) - b(1, 1) * b(2, 0));
        let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
        q + 2.0 * p * phi.cos()
    };
    (largest.max(0.0).sqrt() * (1.0 + 1e-6)) as f32
}

/// Joints and weights per vertex (the four a vertex has in `_0`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Skinning {
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[f32; 4]>,
    /// Per vertex, the four more in `JOINTS_1`/`WEIGHTS_1` where the file
    /// has them (empty otherwise): an input's influences, up to eight. A
    /// LOD's blend keeps the four largest (`scene::carry`).
    pub more: Vec<([u16; 4], [f32; 4])>,
}

impl Skinning {
    /// Vertex `v`'s joints and weights, both sets.
    pub fn influences(&self, v: usize) -> impl Iterator<Item = (u16, f32)> + '_ {
        let more = self.more.get(v).into_iter();
        (self.joints[v].iter().copied().zip(self.weights[v]))
            .chain(more.flat_map(|(j, w)| j.iter().copied().zip(*w)))
    }
}

/// One morph target of a mesh: its name and its deltas per vertex.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MorphTarget {
    pub name: Option<String>,
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
}

impl MorphTarget {
    /// `base` at this target's full weight (base + deltas, vertex by vertex).
    pub fn applied(&self, base: &TriMesh) -> TriMesh {
        let mut shape = base.clone();
        for (p, d) in shape.positions.iter_mut().zip(&self.positions) {
            *p += *d;
        }
        shape.normals = None;
        shape
    }

    /// The largest delta: how far any point of a shape moves at full weight
    /// (a point of a triangle moves by a barycentric blend of its corners').
    pub fn largest_delta(&self) -> f32 {
        self.positions
            .iter()
            .map(|d| d.length())
            .fold(0.0, f32::max)
    }
}

impl SceneMesh {
    /// The mesh at morph target `t`'s full weight (base + deltas).
    pub fn target_shape(&self, t: usize) -> TriMesh {
        self.targets[t].applied(&self.mesh)
    }
}

/// Whether `file` is read as a scene: a glTF or GLB named as itself
/// (`FILE.glb#lodN` is one level of a chain, read as a mesh).
pub fn is_scene(file: &Path) -> bool {
    let name = file.to_string_lossy();
    !name.contains("#lod") && matches!(super::extension(file).as_str(), "gltf" | "glb")
}

/// Reads `data` (a .gltf or .glb whose files lie in `base`) as a scene.
///
/// # Errors
/// As [`super::gltf::read`]: a malformed file, a required extension
/// lodstudio cannot read, a reference outside the asset folder.
pub fn read(data: &[u8], base: Option<&Path>) -> ParseResult<Scene> {
    let (g, mut doc) = parse(data)?;
    let document = &g.document;
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .map(|s| s.index());
    let report = audit_gltf(&doc, scene, Carried::Scene)?;
    let buffers = load_buffers(document, &doc, base, g.blob.clone())?;
    // Decoded: the scene carries the views' bytes as plain ones.
    super::meshopt_compression::strip(&mut doc);
    let mut images = ImageCache::new(document, base);
    let mut materials: Vec<Option<Material>> = vec![None; document.materials().len() + 1];
    let mut meshes: Vec<SceneMesh> = Vec::new();
    for (index, instances) in instances(document)?.into_iter().enumerate() {
        if instances.is_empty() {
            continue;
        }
        let Some(m) = document.meshes().nth(index) else {
            continue;
        };
        let mut skin = Skinning::default();
        let mut skinned = false;
        let mut tangents: Vec<[f32; 4]> = Vec::new();
        let mut tangent = false;
        let mut targets: Vec<MorphTarget> = target_names(&m);
        let mut reader = MeshReader {
            buffers: &buffers,
            images: &mut images,
            materials: &mut materials,
        };
        let (mesh, materials) = reader.read(&m, Mat4::IDENTITY, &mut |prim, n| {
            skinned |= read_skin(prim, &buffers, n, &mut skin)?;
            tangent |= read_tangents(prim, &buffers, n, &mut tangents)?;
            read_targets(prim, &buffers, n, &mut targets)
        })?;
        if mesh.triangles.is_empty() {
            continue;
        }
        meshes.push(SceneMesh {
            index,
            name: m.name().map_or(format!("mesh{index}"), str::to_string),
            mesh,
            materials,
            instances,
            skin: skinned.then_some(skin),
            tangents: tangent.then_some(tangents),
            targets,
        });
    }
    let rig = super::rig::read(document, &buffers)?;
    let bin = joined(&mut doc, &buffers, base)?;
    Ok(Scene {
        doc,
        bin,
        scene,
        meshes,
        rig,
        report,
    })
}

/// The instances of each mesh (by index) in the default scene.
fn instances(document: &gltf::Document) -> ParseResult<Vec<Vec<Instance>>> {
    let mut out = vec![Vec::new(); document.meshes().len()];
    let roots = super::gltf::scene_roots(document);
    let mut stack: Vec<(gltf::Node, Mat4)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY)).collect();
    // glTF 2.0 §3.5.3: nodes form trees, a node under one parent at most.
    // A node met twice is a cycle or a node under several parents, whose
    // instances would multiply with every level: refused at once.
    let mut seen = vec![false; document.nodes().len()];
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(ParseError::item(
                format!("node {}", node.index()),
                "expected each node at most once in the scene's tree, found it under \
                 several parents or in a cycle (its instances would multiply)",
            ));
        }
        let world = super::gltf::world_of(&node, parent)?;
        if let Some(m) = node.mesh() {
            out[m.index()].push(Instance {
                node: node.index(),
                world,
                skin: node.skin().map(|s| s.index()),
            });
        }
        for child in node.children() {
            stack.push((child, world));
        }
    }
    for list in &mut out {
        list.sort_by_key(|i| i.node);
    }
    Ok(out)
}

/// The mesh's targets, named from `extras.targetNames` (the convention
/// three.js, Blender and Babylon share), with no deltas yet.
fn target_names(mesh: &gltf::Mesh) -> Vec<MorphTarget> {
    let count = mesh
        .primitives()
        .map(|p| p.morph_targets().len())
        .max()
        .unwrap_or(0);
    let names: Vec<Option<String>> = mesh
        .extras()
        .as_ref()
        .and_then(|e| serde_json::from_str::<Value>(e.get()).ok())
        .and_then(|e| e.get("targetNames").cloned())
        .and_then(|n| serde_json::from_value(n).ok())
        .unwrap_or_default();
    (0..count)
        .map(|t| MorphTarget {
            name: names.get(t).cloned().flatten(),
            ..MorphTarget::default()
        })
        .collect()
}

/// Appends the primitive's `JOINTS_0`/`WEIGHTS_0` (and `_1`) for its
/// `n` vertices (none: joint 0 at weight 0, which a skinned client
/// ignores); whether it had them.
fn read_skin(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    n: usize,
    skin: &mut Skinning,
) -> ParseResult<bool> {
    let before = skin.joints.len();
    type Set = (Vec<[u16; 4]>, Vec<[f32; 4]>);
    let set = |k: u32| -> ParseResult<Option<Set>> {
        let (Some(ja), Some(wa)) = (
            prim.get(&gltf::Semantic::Joints(k)),
            prim.get(&gltf::Semantic::Weights(k)),
        ) else {
            return Ok(None);
        };
        check_accessor(&ja, buffers)?;
        check_accessor(&wa, buffers)?;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let joints: Vec<[u16; 4]> = reader
            .read_joints(k)
            .map(|j| j.into_u16().collect())
            .unwrap_or_default();
        let weights: Vec<[f32; 4]> = reader
            .read_weights(k)
            .map(|w| w.into_f32().collect())
            .unwrap_or_default();
        if joints.len() != n || weights.len() != n {
            return Err(ParseError::item(
                format!("mesh primitive {}", prim.index()),
                format!("expected JOINTS_{k} and WEIGHTS_{k} for its {n} vertices"),
            ));
        }
        Ok(Some((joints, weights)))
    };
    let first = set(0)?;
    let had = first.is_some();
    let (joints, weights) = first.unwrap_or_else(|| (vec![[0; 4]; n], vec![[0.0; 4]; n]));
    skin.joints.extend(joints);
    skin.weights.extend(weights);
    if let Some((joints, weights)) = set(1)?.filter(|_| had) {
        skin.more.resize(before, ([0; 4], [0.0; 4]));
        skin.more.extend(joints.into_iter().zip(weights));
    } else if !skin.more.is_empty() {
        skin.more.resize(before + n, ([0; 4], [0.0; 4]));
    }
    Ok(had)
}

/// Appends the primitive's `TANGENT`s for its `n` vertices (none: +x with
/// a right-handed frame); whether it had them.
fn read_tangents(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    n: usize,
    out: &mut Vec<[f32; 4]>,
) -> ParseResult<bool> {
    let Some(acc) = prim.get(&gltf::Semantic::Tangents) else {
        out.extend(std::iter::repeat_n([1.0, 0.0, 0.0, 1.0], n));
        return Ok(false);
    };
    let read: Vec<[f32; 4]> = floats(&acc, buffers)?;
    if read.len() != n {
        return Err(ParseError::item(
            format!("mesh primitive {}", prim.index()),
            format!("expected TANGENT for its {n} vertices"),
        ));
    }
    out.extend(read);
    Ok(true)
}

/// The elements of a float or quantized (KHR_mesh_quantization: tangents
/// and target deltas as normalized or plain 8/16-bit integers) accessor of
/// `N` components, checked against its buffer.
fn floats<const N: usize>(
    acc: &gltf::Accessor,
    buffers: &[gltf::buffer::Data],
) -> ParseResult<Vec<[f32; N]>> {
    if acc.dimensions().multiplicity() != N || acc.data_type() == gltf::accessor::DataType::U32 {
        return Err(ParseError::item(
            format!("accessor {}", acc.index()),
            format!("expected {N} float or 8/16-bit components"),
        ));
    }
    check_accessor(acc, buffers)?;
    Ok(super::gltf::dequantized::<N>(acc, buffers))
}

/// Appends the primitive's target deltas for its `n` vertices (zero where
/// it has fewer targets than the mesh).
fn read_targets(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    n: usize,
    targets: &mut [MorphTarget],
) -> ParseResult<()> {
    let what = || format!("mesh primitive {}", prim.index());
    let mut read = Vec::new();
    for t in prim.morph_targets() {
        let vec3s = |acc: Option<gltf::Accessor>| -> ParseResult<Option<Vec<Vec3>>> {
            acc.map(|a| {
                Ok(floats::<3>(&a, buffers)?
                    .into_iter()
                    .map(Vec3::from)
                    .collect())
            })
            .transpose()
        };
        read.push((vec3s(t.positions())?, vec3s(t.normals())?));
    }
    let mut read = read.into_iter();
    let before = targets.first().map_or(0, |t| t.positions.len());
    for target in targets.iter_mut() {
        let (positions, normals) = read.next().unwrap_or_default();
        let positions = positions.unwrap_or_else(|| vec![Vec3::ZERO; n]);
        if positions.len() != n || normals.as_ref().is_some_and(|v| v.len() != n) {
            return Err(ParseError::item(
                what(),
                format!("expected morph target deltas for its {n} vertices"),
            ));
        }
        target.positions.extend(positions);
        match (&mut target.normals, normals) {
            (Some(have), Some(new)) => have.extend(new),
            (Some(have), None) => have.extend(std::iter::repeat_n(Vec3::ZERO, n)),
            (None, Some(new)) => {
                let mut all = vec![Vec3::ZERO; before];
                all.extend(new);
                target.normals = Some(all);
            }
            (None, None) => {}
        }
    }
    Ok(())
}

/// Joins the document's buffers into one binary (buffer 0), rebasing the
/// buffer views, and embeds images stored as files (through `confine`) as
/// buffer views: the outputs are single GLBs.
fn joined(
    doc: &mut Value,
    buffers: &[gltf::buffer::Data],
    base: Option<&Path>,
) -> ParseResult<Vec<u8>> {
    let mut bin: Vec<u8> = Vec::new();
    let mut starts = Vec::with_capacity(buffers.len());
    for b in buffers {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        starts.push(bin.len());
        bin.extend_from_slice(&b.0);
    }
    if let Some(views) = doc.get_mut("bufferViews").and_then(Value::as_array_mut) {
        for view in views {
            let b = view["buffer"].as_u64().unwrap_or(0) as usize;
            let offset = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
            view["buffer"] = json!(0);
            view["byteOffset"] = json!(starts.get(b).copied().unwrap_or(0) + offset);
        }
    }
    // The embedded images' views go after the file's own.
    let mut views = doc["bufferViews"].as_array().cloned().unwrap_or_default();
    if let Some(images) = doc.get_mut("images").and_then(Value::as_array_mut) {
        for (i, image) in images.iter_mut().enumerate() {
            let Some(uri) = image.get("uri").and_then(Value::as_str).map(str::to_string) else {
                continue;
            };
            if uri.starts_with("data:") {
                continue;
            }
            let bytes = read_uri(&uri, base, &format!("image {i}"))?;
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
            bin.extend_from_slice(&bytes);
            let sniffed = match bytes.starts_with(b"\x89PNG") {
                true => "image/png",
                false => "image/jpeg",
            };
            if let Some(object) = image.as_object_mut() {
                object.remove("uri");
                object.insert(
                    "mimeType".into(),
                    json!(image_mime(&uri).unwrap_or(sniffed)),
                );
                object.insert("bufferView".into(), json!(views.len() - 1));
            }
        }
    }
    if !views.is_empty() {
        doc["bufferViews"] = json!(views);
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    Ok(bin)
}

/// The MIME type a file name's extension says, if it says one.
fn image_mime(uri: &str) -> Option<&'static str> {
    let lower = uri.to_ascii_lowercase();
    match lower.rsplit('.').next()? {
        "png" => Some("image/png"),
        "jpg" | "jpeg" => Some("image/jpeg"),
        "webp" => Some("image/webp"),
        "ktx2" => Some("image/ktx2"),
        _ => None,
    }
}

/// What the vertices of a written primitive carry besides the surface:
/// their skin and their morph target deltas (one per target of the mesh).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VertexExtras {
    pub skin: Option<Skinning>,
    pub tangents: Option<Vec<[f32; 4]>>,
    pub targets: Vec<MorphTarget>,
}
