//! The one glTF writer: any cut of any method ([`DrawSet`]: triangles,
//! points, splats, translucent layers) becomes a node whose mesh holds one
//! primitive per kind, and LOD chains stack such nodes under `MSFT_lod`.
//!
//! - triangles: one vertex per wedge (`geom::wedges`), positions, normals
//!   (area-weighted when the mesh has none; every one facing its faces' front),
//!   `COLOR_0` and `TEXCOORD_0` when present, 32-bit indices; a mesh with the
//!   input's materials gets one primitive per material, wearing it (factors and
//!   the embedded base-colour image), `COLOR_0` divided back by the base colour;
//! - points (hybrid paper §5.3): mode POINTS with `COLOR_0` and the custom
//!   attribute `_RADIUS` (object space; said in the primitive's `extras`),
//!   or, for clients that draw POINTS as one-pixel dots ([`PointsAs`]), a
//!   small mesh per point facing its normal and covering its disc;
//! - splats (AMG paper §3): textured quads, their textures packed into
//!   atlases (`io::atlas`), one primitive with one alpha-blended unlit
//!   material per atlas, the atlas embedded as PNG (colour, Ψ in alpha);
//! - layers (voxel paper §3): one primitive per layer with a material whose
//!   base-colour alpha is the layer's opacity, blended unless opaque.

use std::collections::{BTreeSet, HashMap};
use std::hash::{DefaultHasher, Hash, Hasher};

use glam::Vec3;
use serde_json::{Value, json};

use super::scene::VertexExtras;
use crate::geom::{Aabb, AlphaMode, Material, TriMesh};
use crate::lod::{DrawSet, Texture};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const UNSIGNED_SHORT: u32 = 5123;

/// How a cut's points are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PointsAs {
    /// A POINTS primitive with `_RADIUS`: compact, for renderers that splat.
    #[default]
    Points,
    /// The square around each disc (a fan of four triangles).
    Quads,
    /// The octagon around each disc (a fan of eight triangles).
    Discs,
}

impl PointsAs {
    /// What a client draws per point: the polygon's triangles, or one
    /// point primitive (counted as one).
    pub fn primitives_per_point(self) -> usize {
        match self {
            PointsAs::Points => 1,
            PointsAs::Quads => 4,
            PointsAs::Discs => 8,
        }
    }
}

impl std::str::FromStr for PointsAs {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "points" => Ok(PointsAs::Points),
            "quads" => Ok(PointsAs::Quads),
            "discs" => Ok(PointsAs::Discs),
            _ => Err(format!("{s:?} is not one of points, quads, discs")),
        }
    }
}

/// What `_RADIUS` means, written beside it in the file.
const RADIUS_NOTE: &str = "_RADIUS: object-space radius of each point; draw each point as a disc of \
     that radius facing its normal (lodstudio hybrid LOD, hybrid paper 5.3). Clients that draw POINTS \
     as pixels see a sparse cloud: export with --points-as quads|discs for a covering surface.";

/// How a scene's mesh is written ([`GltfWriter::scene_mesh`]): the glTF
/// material of each part, and what each written vertex carries besides
/// its surface (skin, morph target deltas), given the vertices.
pub struct ScenePrimitives<'a> {
    pub materials: &'a [Option<usize>],
    /// The materials of the scene mesh's parts, which `materials` writes: a
    /// LOD wearing others (a baked texture) writes its own.
    pub source: Option<&'a crate::geom::Materials>,
    pub extras: &'a dyn Fn(&TriMesh) -> VertexExtras,
}

/// Accumulates buffers, accessors, materials and nodes, then packs a GLB.
#[derive(Default)]
pub struct GltfWriter {
    /// The document written into (a scene's, [`GltfWriter::extending`]),
    /// less the arrays this writer holds.
    base: Option<Value>,
    points_as: PointsAs,
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    materials: Vec<Value>,
    images: Vec<Value>,
    textures: Vec<Value>,
    samplers: Vec<Value>,
    extensions: BTreeSet<&'static str>,
    /// The shared opaque surface material, once made.
    surface: Option<usize>,
    /// The input's materials written so far, with their glTF indices.
    originals: Vec<(Material, usize)>,
    /// Images by a hash of their bytes, and textures by (image, sampler):
    /// an AMG level has thousands of splat textures, and searching the lists
    /// made writing the dragon's level 3 take 29 s.
    image_by_hash: HashMap<u64, Vec<usize>>,
    texture_by_parts: HashMap<(usize, usize), usize>,
}

fn le(data: &[f32]) -> Vec<u8> {
    data.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn flat3(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

impl GltfWriter {
    pub fn new() -> Self {
        Self::default()
    }

    /// A writer that writes points as `points_as`.
    pub fn with_points_as(points_as: PointsAs) -> Self {
        Self {
            points_as,
            ..Self::default()
        }
    }

    /// A writer that adds to `doc` (whose buffer 0 is `bin`, its only
    /// buffer): new objects take the indices after the document's own.
    pub fn extending(mut doc: Value, bin: Vec<u8>, points_as: PointsAs) -> Self {
        let mut take = |key: &str| match doc.as_object_mut().and_then(|o| o.remove(key)) {
            Some(Value::Array(a)) => a,
            _ => Vec::new(),
        };
        let mut w = Self {
            points_as,
            bin,
            views: take("bufferViews"),
            accessors: take("accessors"),
            meshes: take("meshes"),
            nodes: take("nodes"),
            materials: take("materials"),
            images: take("images"),
            textures: take("textures"),
            samplers: take("samplers"),
            ..Self::default()
        };
        w.base = Some(doc);
        w
    }

    /// The nodes, to edit in place (a scene's nodes, then those added).
    pub fn nodes_mut(&mut self) -> &mut Vec<Value> {
        &mut self.nodes
    }

    /// The meshes, to edit in place.
    pub fn meshes_mut(&mut self) -> &mut Vec<Value> {
        &mut self.meshes
    }

    /// Appends a node; its index.
    pub fn push_node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// The primitives of `set` as one of a scene's meshes: its surface one
    /// primitive per part wearing the scene's materials, with the vertex
    /// extras `scene` gives, then its points and splats.
    pub fn scene_primitives(&mut self, set: &DrawSet, scene: &ScenePrimitives) -> Vec<Value> {
        let mut primitives = Vec::new();
        if !set.mesh.triangles.is_empty() {
            primitives.extend(self.wearing(&set.mesh, Some(scene)));
        }
        primitives.extend(self.points(set));
        primitives.extend(self.splats(set));
        primitives
    }

    /// Marks an extension used.
    pub fn uses(&mut self, extension: &'static str) {
        self.extensions.insert(extension);
    }

    /// Appends `bytes` as a buffer view (4-byte aligned).
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// A float accessor of `kind` ("SCALAR", "VEC2", "VEC3") over `data`.
    fn floats(&mut self, data: &[f32], kind: &str, bounds: Option<Aabb>) -> usize {
        let width = match kind {
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 1,
        };
        let view = self.view(&le(data), Some(ARRAY_BUFFER));
        let mut acc = json!({"bufferView": view, "componentType": FLOAT, "count": data.len() / width, "type": kind});
        if let Some(b) = bounds {
            acc["min"] = json!(b.min.to_array());
            acc["max"] = json!(b.max.to_array());
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    fn indices(&mut self, indices: &[u32]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": indices.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    fn material(&mut self, m: Value) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    /// A texture of `img` with its own sampler.
    fn material_texture(&mut self, img: &crate::geom::Image) -> usize {
        let sampler = self.sampler(json!({
            "magFilter": img.mag_filter, "minFilter": img.min_filter,
            "wrapS": img.wrap_s, "wrapT": img.wrap_t,
        }));
        self.image(&img.bytes, &img.mime_type, sampler)
    }

    /// The glTF material of one of the input's materials (each written once).
    fn original_material(&mut self, m: &Material) -> usize {
        if let Some((_, i)) = self.originals.iter().find(|(o, _)| o == m) {
            return *i;
        }
        let mut pbr = json!({"baseColorFactor": m.base_color, "metallicFactor": m.metallic, "roughnessFactor": m.roughness});
        if let Some(img) = &m.base_color_texture {
            pbr["baseColorTexture"] = json!({"index": self.material_texture(img)});
        }
        let mut v = json!({"pbrMetallicRoughness": pbr, "emissiveFactor": m.emissive, "doubleSided": m.double_sided});
        if let Some((img, scale)) = &m.normal_texture {
            v["normalTexture"] = json!({"index": self.material_texture(img), "scale": scale});
        }
        match m.alpha_mode {
            AlphaMode::Opaque => {}
            AlphaMode::Mask(cutoff) => {
                v["alphaMode"] = json!("MASK");
                v["alphaCutoff"] = json!(cutoff);
            }
            AlphaMode::Blend => v["alphaMode"] = json!("BLEND"),
        }
        if let Some(name) = &m.name {
            v["name"] = json!(name);
        }
        let i = self.material(v);
        self.originals.push((m.clone(), i));
        i
    }

    /// The triangle primitives of a cut's surface: one with the shared surface
    /// material, or one per material of the input's that it wears.
    fn surface_primitives(&mut self, mesh: &TriMesh) -> Vec<Value> {
        self.wearing(mesh, None)
    }

    /// [`Self::surface_primitives`], or with `scene` one primitive per part
    /// wearing the scene's own material (`None`: glTF's default), with the
    /// vertex extras `scene` gives each.
    fn wearing(&mut self, mesh: &TriMesh, scene: Option<&ScenePrimitives>) -> Vec<Value> {
        // glTF stores attributes per vertex: one vertex per wedge.
        let mesh = &mesh.unwelded();
        let Some(materials) = &mesh.materials else {
            let m = self.surface_material();
            return self.triangles(mesh, Some(m), None).into_iter().collect();
        };
        // Groups: materials, or a scene's glTF materials (two parts may wear
        // equal materials that are distinct glTF materials, or one glTF
        // material: a skinned mesh's parts are its bones'). A LOD that wears
        // its own materials (baked) writes them, with the scene's extras.
        let extras = scene.map(|s| s.extras);
        let scene = scene.filter(|s| s.source == Some(materials));
        let scene_groups: Vec<Option<usize>> = match scene {
            Some(s) => {
                let mut g: Vec<Option<usize>> = s.materials.to_vec();
                g.sort();
                g.dedup();
                g
            }
            None => Vec::new(),
        };
        let groups_len = match scene {
            Some(_) => scene_groups.len().max(1),
            None => materials.table.len(),
        };
        let mut groups: Vec<Vec<u32>> = vec![Vec::new(); groups_len];
        for t in 0..mesh.triangles.len() {
            let g = match scene {
                Some(s) => {
                    let key = s.materials.get(mesh.part(t) as usize).copied().flatten();
                    scene_groups.binary_search(&key).unwrap_or(0)
                }
                None => materials.of(mesh.part(t)) as usize,
            };
            groups[g.min(groups_len - 1)].push(t as u32);
        }
        let mut out = Vec::new();
        for (g, tris) in groups.into_iter().enumerate() {
            if tris.is_empty() {
                continue;
            }
            let m = match scene {
                Some(_) => {
                    let part = mesh.part(tris[0] as usize);
                    &materials.table[(materials.of(part) as usize).min(materials.table.len() - 1)]
                }
                None => &materials.table[g],
            };
            let mut piece = mesh.subset(&tris);
            // Only the attributes the input gave this material's vertices.
            if !m.vertex_attributes.uvs {
                piece.uvs = None;
            }
            if !m.vertex_attributes.colors {
                piece.colors = None;
            }
            // Display colours are base colour × COLOR_0 (see io::gltf): divide
            // the factor back out, and leave out a COLOR_0 that is white.
            let factor = Vec3::from_slice(&m.base_color[..3]);
            if let Some(c) = &mut piece.colors {
                for v in c.iter_mut() {
                    *v = Vec3::select(factor.cmpgt(Vec3::splat(1e-6)), *v / factor, Vec3::ONE);
                }
                if c.iter().all(|v| v.abs_diff_eq(Vec3::ONE, 1.0 / 512.0)) {
                    piece.colors = None;
                }
            }
            let material = match scene {
                Some(_) => scene_groups.get(g).copied().flatten(),
                None => Some(self.original_material(m)),
            };
            // Normals are oriented before the extras are taken, so the
            // vertices it splits off have extras too (a second orientation in
            // `triangles` splits none).
            // A normal map needs the frame it was made in: MikkTSpace
            // tangents of the vertices as written (`geom::tangents`), which
            // may split some.
            let tangents = match &m.normal_texture {
                Some(_) => {
                    piece.orient_normals_to_winding();
                    piece.with_tangents().map(|(split, t)| {
                        piece = split;
                        t.iter().map(|t| t.to_array()).collect::<Vec<_>>()
                    })
                }
                None => None,
            };
            let mut extras = extras.map(|e| {
                piece.orient_normals_to_winding();
                e(&piece)
            });
            if let Some(t) = tangents {
                extras.get_or_insert_with(VertexExtras::default).tangents = Some(t);
            }
            out.extend(self.triangles(&piece, material, extras));
        }
        out
    }

    fn surface_material(&mut self) -> usize {
        if let Some(m) = self.surface {
            return m;
        }
        let m = self.material(json!({
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8},
            "doubleSided": false
        }));
        self.surface = Some(m);
        m
    }

    /// The triangle primitive of `mesh` (with its vertices' `extras`), or
    /// `None` when it has no triangles.
    fn triangles(
        &mut self,
        mesh: &TriMesh,
        material: Option<usize>,
        extras: Option<VertexExtras>,
    ) -> Option<Value> {
        if mesh.triangles.is_empty() || mesh.positions.is_empty() {
            return None;
        }
        // Every mesh shades (meshes without normals get area-weighted ones),
        // and from the front: no normal points away from a face it shades.
        let mut mesh = mesh.clone();
        mesh.orient_normals_to_winding();
        let mut attributes = serde_json::Map::new();
        let pos = self.floats(&flat3(&mesh.positions), "VEC3", Some(mesh.bounds()));
        attributes.insert("POSITION".into(), pos.into());
        let unit: Vec<Vec3> = mesh
            .normals
            .iter()
            .flatten()
            .map(|v| v.try_normalize().unwrap_or(Vec3::Z))
            .collect();
        let nrm = self.floats(&flat3(&unit), "VEC3", None);
        attributes.insert("NORMAL".into(), nrm.into());
        if let Some(c) = &mesh.colors {
            let clamped: Vec<Vec3> = c.iter().map(|v| v.clamp(Vec3::ZERO, Vec3::ONE)).collect();
            let a = self.floats(&flat3(&clamped), "VEC3", None);
            attributes.insert("COLOR_0".into(), a.into());
        }
        if let Some(uv) = &mesh.uvs {
            let flat: Vec<f32> = uv.iter().flat_map(|v| v.to_array()).collect();
            let a = self.floats(&flat, "VEC2", None);
            attributes.insert("TEXCOORD_0".into(), a.into());
        }
        let mut targets = Vec::new();
        if let Some(extras) = extras {
            if let Some(skin) = extras.skin {
                let joints: Vec<u8> = skin
                    .joints
                    .iter()
                    .flatten()
                    .flat_map(|j| j.to_le_bytes())
                    .collect();
                let view = self.view(&joints, Some(ARRAY_BUFFER));
                self.accessors.push(json!({"bufferView": view, "componentType": UNSIGNED_SHORT, "count": skin.joints.len(), "type": "VEC4"}));
                attributes.insert("JOINTS_0".into(), (self.accessors.len() - 1).into());
                let weights: Vec<f32> = skin.weights.iter().flatten().copied().collect();
                let a = self.floats(&weights, "VEC4", None);
                attributes.insert("WEIGHTS_0".into(), a.into());
            }
            if let Some(tangents) = &extras.tangents {
                let flat: Vec<f32> = tangents.iter().flatten().copied().collect();
                let a = self.floats(&flat, "VEC4", None);
                attributes.insert("TANGENT".into(), a.into());
            }
            for target in &extras.targets {
                let bounds = crate::geom::Aabb::from_points(&target.positions);
                let mut t = serde_json::Map::new();
                let p = self.floats(&flat3(&target.positions), "VEC3", Some(bounds));
                t.insert("POSITION".into(), p.into());
                if let Some(n) = &target.normals {
                    let a = self.floats(&flat3(n), "VEC3", None);
                    t.insert("NORMAL".into(), a.into());
                }
                targets.push(Value::Object(t));
            }
        }
        let flat: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let indices = self.indices(&flat);
        let mut primitive = json!({"attributes": attributes, "indices": indices, "mode": 4});
        if let Some(m) = material {
            primitive["material"] = json!(m);
        }
        if !targets.is_empty() {
            primitive["targets"] = json!(targets);
        }
        Some(primitive)
    }

    /// The points of a cut as a POINTS primitive with `_RADIUS`, or as
    /// meshes ([`PointsAs`]).
    fn points(&mut self, set: &DrawSet) -> Option<Value> {
        if set.points.is_empty() {
            return None;
        }
        if self.points_as != PointsAs::Points {
            return self.point_meshes(set);
        }
        let centers: Vec<Vec3> = set.points.iter().map(|p| p.center).collect();
        let bounds = Aabb::from_points(&centers);
        let pos = self.floats(&flat3(&centers), "VEC3", Some(bounds));
        let colors: Vec<Vec3> = set
            .points
            .iter()
            .map(|p| p.color.clamp(Vec3::ZERO, Vec3::ONE))
            .collect();
        let col = self.floats(&flat3(&colors), "VEC3", None);
        let radii: Vec<f32> = set.points.iter().map(|p| p.radius.max(0.0)).collect();
        let rad = self.floats(&radii, "SCALAR", None);
        Some(json!({
            "attributes": {"POSITION": pos, "COLOR_0": col, "_RADIUS": rad},
            "mode": 0,
            "extras": {"_RADIUS": RADIUS_NOTE},
        }))
    }

    /// Each point as a small mesh in the plane of its normal, covering its
    /// disc (a square, or an octagon whose inscribed circle is the disc),
    /// wearing its colour; double-sided, as a point has no back.
    fn point_meshes(&mut self, set: &DrawSet) -> Option<Value> {
        let sides = self.points_as.primitives_per_point();
        // The polygon's corners lie at r / cos(π / sides) so its edges touch the disc.
        let reach = 1.0 / (std::f32::consts::PI / sides as f32).cos();
        let mut mesh = TriMesh::default();
        let (mut normals, mut colors) = (Vec::new(), Vec::new());
        for p in &set.points {
            let n = p.normal.try_normalize().unwrap_or(Vec3::Z);
            let (u, v) = n.any_orthonormal_pair();
            // Counter-clockwise around the normal: the front faces along it.
            let (u, v) = if u.cross(v).dot(n) < 0.0 {
                (v, u)
            } else {
                (u, v)
            };
            let base = mesh.positions.len() as u32;
            mesh.positions.push(p.center);
            for k in 0..sides {
                let a = std::f32::consts::TAU * (k as f32 + 0.5) / sides as f32;
                let r = p.radius.max(0.0) * reach;
                mesh.positions
                    .push(p.center + r * (a.cos() * u + a.sin() * v));
            }
            for k in 0..sides as u32 {
                let next = (k + 1) % sides as u32;
                mesh.triangles.push([base, base + 1 + k, base + 1 + next]);
            }
            normals.extend(std::iter::repeat_n(n, sides + 1));
            colors.extend(std::iter::repeat_n(p.color, sides + 1));
        }
        mesh.normals = Some(normals);
        mesh.colors = Some(colors);
        let m = self.material(json!({
            "name": "points",
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8},
            "doubleSided": true
        }));
        self.triangles(&mesh, Some(m), None)
    }

    /// The splats of a cut: textured quads, their textures packed into
    /// atlases (`io::atlas`), one primitive and one material per atlas.
    fn splats(&mut self, set: &DrawSet) -> Vec<Value> {
        let mut used: Vec<usize> = set
            .splats
            .iter()
            .map(|s| s.texture)
            .filter(|&t| t < set.textures.len())
            .collect();
        used.sort_unstable();
        used.dedup();
        let textures: Vec<&Texture> = used.iter().map(|&t| &set.textures[t]).collect();
        let mut out = Vec::new();
        for atlas in super::atlas::pack(&textures) {
            // The UV rectangle of each texture of this atlas, by texture index.
            let mut rect = vec![None; set.textures.len()];
            for &(k, r) in &atlas.members {
                rect[used[k]] = Some(r);
            }
            let (mut positions, mut normals, mut uvs, mut indices) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for s in &set.splats {
                let Some([u0, v0, u1, v1]) = rect.get(s.texture).copied().flatten() else {
                    continue;
                };
                let base = positions.len() as u32;
                positions.extend(s.corners());
                let n = s.normal.try_normalize().unwrap_or(Vec3::Z);
                normals.extend([n; 4]);
                uvs.extend([u0, v0, u1, v0, u1, v1, u0, v1]);
                indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
            }
            let image = self.texture(&atlas.texture);
            let material = self.material(json!({
                "name": "splats",
                "pbrMetallicRoughness": {"baseColorTexture": {"index": image}, "metallicFactor": 0.0, "roughnessFactor": 1.0},
                "alphaMode": "BLEND",
                "doubleSided": true,
                "extensions": {"KHR_materials_unlit": {}}
            }));
            self.extensions.insert("KHR_materials_unlit");
            let pos = self.floats(
                &flat3(&positions),
                "VEC3",
                Some(Aabb::from_points(&positions)),
            );
            let nrm = self.floats(&flat3(&normals), "VEC3", None);
            let uv = self.floats(&uvs, "VEC2", None);
            let indices = self.indices(&indices);
            out.push(json!({"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "indices": indices, "mode": 4, "material": material}));
        }
        out
    }

    /// Embeds `tex` as a PNG image and returns its texture index.
    fn texture(&mut self, tex: &Texture) -> usize {
        // Atlases ring each texture with its own edge: clamp, never repeat.
        let sampler = self
            .sampler(json!({"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}));
        self.image(&super::image::encode_png(tex), "image/png", sampler)
    }

    /// The index of sampler `s`, added when new (`null` fields left out).
    fn sampler(&mut self, mut s: Value) -> usize {
        if let Some(o) = s.as_object_mut() {
            o.retain(|_, v| !v.is_null());
        }
        match self.samplers.iter().position(|t| *t == s) {
            Some(i) => i,
            None => {
                self.samplers.push(s);
                self.samplers.len() - 1
            }
        }
    }

    /// The index of a texture sampling encoded image `bytes` with `sampler`; an
    /// image already embedded (materials sharing one atlas) is not embedded again.
    fn image(&mut self, bytes: &[u8], mime_type: &str, sampler: usize) -> usize {
        let mut hasher = DefaultHasher::new();
        bytes.hash(&mut hasher);
        let key = hasher.finish();
        let embedded = |w: &Self, image: usize| {
            let view = &w.views[w.images[image]["bufferView"].as_u64().unwrap_or(0) as usize];
            let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
            w.bin
                .get(at..at + view["byteLength"].as_u64().unwrap_or(0) as usize)
                == Some(bytes)
        };
        let same = self
            .image_by_hash
            .get(&key)
            .and_then(|c| c.iter().copied().find(|&i| embedded(self, i)));
        let source = match same {
            Some(i) => i,
            None => {
                let view = self.view(bytes, None);
                self.images
                    .push(json!({"bufferView": view, "mimeType": mime_type}));
                let i = self.images.len() - 1;
                self.image_by_hash.entry(key).or_default().push(i);
                i
            }
        };
        *self
            .texture_by_parts
            .entry((source, sampler))
            .or_insert_with(|| {
                self.textures
                    .push(json!({"source": source, "sampler": sampler}));
                self.textures.len() - 1
            })
    }

    /// One child node per translucent layer (a separate mesh each, as
    /// translucent meshes are drawn one after another), innermost first.
    fn layers(&mut self, set: &DrawSet) -> Vec<usize> {
        let mut out = Vec::new();
        for (i, layer) in set.layers.iter().enumerate() {
            let alpha = layer.alpha.clamp(0.0, 1.0);
            let m = self.material(json!({
                "name": format!("isodensity {:.3}", layer.isodensity),
                "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, alpha], "metallicFactor": 0.0, "roughnessFactor": 0.8},
                "alphaMode": if alpha >= 1.0 { "OPAQUE" } else { "BLEND" },
            }));
            let mut node = json!({"name": format!("layer{i}")});
            if let Some(primitive) = self.triangles(&layer.mesh, Some(m), None) {
                self.meshes.push(json!({"primitives": [primitive]}));
                node["mesh"] = json!(self.meshes.len() - 1);
            }
            self.nodes.push(node);
            out.push(self.nodes.len() - 1);
        }
        out
    }

    /// A node named `name` showing `set` (a node without a mesh when empty).
    pub fn node(&mut self, name: &str, set: &DrawSet) -> usize {
        // The node's id first: its layers' child nodes come after it.
        let id = self.nodes.len();
        self.nodes.push(json!({"name": name}));
        let mut primitives: Vec<Value> = Vec::new();
        if !set.mesh.triangles.is_empty() {
            primitives.extend(self.surface_primitives(&set.mesh));
        }
        primitives.extend(self.points(set));
        primitives.extend(self.splats(set));
        let layers = self.layers(set);
        if !primitives.is_empty() {
            self.meshes.push(json!({"primitives": primitives}));
            self.nodes[id]["mesh"] = json!(self.meshes.len() - 1);
        }
        if !layers.is_empty() {
            self.nodes[id]["children"] = json!(layers);
        }
        id
    }

    /// The glTF document (scene = `scene_nodes`) and its binary buffer.
    pub fn document(mut self, scene_nodes: &[usize]) -> (Value, Vec<u8>) {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        if let Some(base) = self.base.take() {
            return self.scene_document(base);
        }
        let mut doc = json!({
            "asset": {"version": "2.0", "generator": "lodstudio"},
            "scene": 0,
            "scenes": [{"nodes": scene_nodes}],
            "nodes": self.nodes,
        });
        if !self.meshes.is_empty() {
            doc["meshes"] = json!(self.meshes);
            doc["materials"] = json!(self.materials);
            doc["buffers"] = json!([{"byteLength": self.bin.len()}]);
            doc["bufferViews"] = json!(self.views);
            doc["accessors"] = json!(self.accessors);
        }
        if !self.images.is_empty() {
            doc["images"] = json!(self.images);
            doc["textures"] = json!(self.textures);
            doc["samplers"] = json!(self.samplers);
        }
        if !self.extensions.is_empty() {
            doc["extensionsUsed"] = json!(self.extensions.iter().collect::<Vec<_>>());
        }
        (doc, self.bin)
    }
}

impl GltfWriter {
    /// The scene document `base` with this writer's arrays put back (each
    /// only where it has entries, as glTF wants no empty arrays).
    fn scene_document(self, mut base: Value) -> (Value, Vec<u8>) {
        for (key, list) in [
            ("bufferViews", self.views),
            ("accessors", self.accessors),
            ("meshes", self.meshes),
            ("nodes", self.nodes),
            ("materials", self.materials),
            ("images", self.images),
            ("textures", self.textures),
            ("samplers", self.samplers),
        ] {
            if !list.is_empty() {
                base[key] = Value::Array(list);
            }
        }
        base["buffers"] = json!([{"byteLength": self.bin.len()}]);
        let mut used: Vec<Value> = base["extensionsUsed"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        for e in self.extensions {
            if !used.iter().any(|u| u == e) {
                used.push(json!(e));
            }
        }
        if !used.is_empty() {
            base["extensionsUsed"] = json!(used);
        }
        (base, self.bin)
    }
}

/// A document and its binary as a GLB.
pub fn glb(doc: &Value, bin: Vec<u8>) -> Vec<u8> {
    glb_container(doc.to_string().into_bytes(), bin)
}

/// One cut as a GLB: a single node in the scene.
pub fn write_draw_set_glb(set: &DrawSet) -> Vec<u8> {
    let mut w = GltfWriter::new();
    let node = w.node("lod0", set);
    let (doc, bin) = w.document(&[node]);
    glb_container(doc.to_string().into_bytes(), bin)
}

/// An LOD chain as a GLB with the `MSFT_lod` node extension.
///
/// `lods` are in decreasing quality (LOD0 first), one node each (node `i`
/// unless earlier LODs have layer child nodes); the scene lists LOD0's node
/// only (node 0), whose `extensions.MSFT_lod.ids` are the lower LODs' nodes in
/// decreasing quality and whose
/// `extras.MSFT_screencoverage` is `coverages`: one value per LOD, LOD0's
/// included, each the smallest screen coverage at which that LOD is shown
/// (see [`crate::lod::chain::lod_screen_coverages`]). Loaders without the extension
/// see LOD0 alone.
///
/// # Panics
/// If `lods` is empty or `coverages.len() != lods.len()`.
pub fn write_lod_chain(lods: &[DrawSet], coverages: &[f32], points_as: PointsAs) -> Vec<u8> {
    assert!(!lods.is_empty(), "an LOD chain needs LOD0");
    assert_eq!(
        coverages.len(),
        lods.len(),
        "one screen coverage per LOD, LOD0's included"
    );
    let mut w = GltfWriter::with_points_as(points_as);
    let ids: Vec<usize> = lods
        .iter()
        .enumerate()
        .map(|(i, lod)| w.node(&format!("lod{i}"), lod))
        .collect();
    let (mut doc, bin) = w.document(&ids[..1]);
    if lods.len() > 1 {
        let root = ids[0];
        doc["nodes"][root]["extensions"] = json!({"MSFT_lod": {"ids": ids[1..]}});
        doc["nodes"][root]["extras"] = json!({"MSFT_screencoverage": coverages});
        let mut used = doc["extensionsUsed"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        used.push(json!("MSFT_lod"));
        doc["extensionsUsed"] = json!(used);
    }
    glb_container(doc.to_string().into_bytes(), bin)
}

/// Writes one mesh as a binary glTF (GLB): positions, normals (area-weighted
/// vertex normals when the mesh has none), vertex colours and UVs when it has
/// them, and 32-bit indices in one buffer, one node, one scene.
pub fn write_glb(mesh: &TriMesh) -> Vec<u8> {
    super::gltf_writer::write_draw_set_glb(&crate::lod::DrawSet {
        mesh: mesh.clone(),
        ..Default::default()
    })
}

/// Packs a JSON chunk (space-padded) and a binary chunk (zero-padded; left out
/// when empty) into GLB.
fn glb_container(mut json: Vec<u8>, bin: Vec<u8>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + json.len() + bin_chunk;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

/// Writes a GLB to `output` as is, or as `.gltf` + `.bin` beside it when
/// the name ends in `.gltf`, each atomically (the one file writer of LOD
/// chains: `lodstudio export` and the studio's chain export); returns the
/// bytes written.
pub fn write_file(output: &std::path::Path, glb: &[u8]) -> Result<usize, String> {
    let files = encode_file(output, glb)?;
    for (path, bytes) in &files {
        super::write_atomic(path, bytes)
            .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    }
    Ok(files.iter().map(|(_, b)| b.len()).sum())
}

/// The files a GLB becomes at `output`: itself, or for `.gltf` the JSON and
/// its `.bin` beside it (the `.bin` first, so the JSON never names a
/// buffer that is not there yet).
///
/// # Errors
/// `glb` is no GLB container (an internal error).
pub fn encode_file(
    output: &std::path::Path,
    glb: &[u8],
) -> Result<Vec<(std::path::PathBuf, Vec<u8>)>, String> {
    let gltf = output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
    if !gltf {
        return Ok(vec![(output.to_path_buf(), glb.to_vec())]);
    }
    let bin_path = output.with_extension("bin");
    let bin_name = bin_path
        .file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned();
    let (json, bin) = super::gltf::split_glb(glb, &bin_name)
        .ok_or_else(|| "internal: the GLB writer made no container".to_string())?;
    Ok(vec![(bin_path, bin), (output.to_path_buf(), json)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::{Layer, Splat};

    #[test]
    fn splats_and_layers_read_back_with_their_textures_and_alpha() {
        let tex = |w: u32, h: u32| Texture {
            width: w,
            height: h,
            rgba: (0..w * h).map(|i| [i as u8, 7, 9, (i * 3) as u8]).collect(),
        };
        let splat = |c: f32, t: usize| Splat {
            center: Vec3::new(c, 0.0, 0.0),
            axes: [Vec3::X * 0.5, Vec3::Y * 0.25],
            normal: Vec3::Z,
            texture: t,
            domain: t,
            neighbours: Vec::new(),
        };
        let torus = crate::builtins::torus(1.0, 0.3, 8, 4);
        let set = DrawSet {
            splats: vec![splat(0.0, 0), splat(2.0, 1), splat(4.0, 1)],
            textures: vec![tex(3, 2), tex(5, 4)],
            layers: vec![
                Layer {
                    mesh: torus.clone(),
                    alpha: 1.0,
                    isodensity: 0.8,
                },
                Layer {
                    mesh: torus.clone(),
                    alpha: 0.4,
                    isodensity: 0.3,
                },
            ],
            ..DrawSet::default()
        };
        let glb = write_draw_set_glb(&set);
        let (doc, buffers, images) = gltf::import_slice(&glb).expect("valid glTF");
        let prims: Vec<_> = doc.meshes().flat_map(|m| m.primitives()).collect();
        assert_eq!(prims.len(), 2 + 1, "two layers, one primitive of quads");
        let alpha: Vec<_> = prims[..2]
            .iter()
            .map(|p| p.material().alpha_mode())
            .collect();
        assert_eq!(
            alpha,
            [
                gltf::material::AlphaMode::Opaque,
                gltf::material::AlphaMode::Blend
            ]
        );
        assert_eq!(
            prims[1]
                .material()
                .pbr_metallic_roughness()
                .base_color_factor()[3],
            0.4
        );
        let quads = &prims[2];
        assert_eq!(
            quads.material().alpha_mode(),
            gltf::material::AlphaMode::Blend
        );
        let reader = quads.reader(|b| Some(&buffers[b.index()]));
        let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let uv: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
        let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!((pos.len(), indices.len()), (12, 18));
        let t = quads
            .material()
            .pbr_metallic_roughness()
            .base_color_texture()
            .unwrap();
        let atlas = &images[t.texture().source().index()];
        assert_eq!(images.len(), 1, "one atlas for every splat");
        for (k, s) in set.splats.iter().enumerate() {
            assert_eq!(pos[4 * k + 2], [2.0 * k as f32 + 0.5, 0.25, 0.0]);
            // The quad's UVs span its texture's texels in the atlas.
            let want = &set.textures[s.texture];
            let [u0, v0] = uv[4 * k];
            let [u1, v1] = uv[4 * k + 2];
            let (w, h) = (atlas.width as f32, atlas.height as f32);
            assert_eq!(
                ((u1 - u0) * w, (v1 - v0) * h),
                (want.width as f32, want.height as f32)
            );
            let (x0, y0) = ((u0 * w) as usize, (v0 * h) as usize);
            for y in 0..want.height as usize {
                for x in 0..want.width as usize {
                    let at = 4 * ((y0 + y) * atlas.width as usize + x0 + x);
                    let texel = want.rgba[y * want.width as usize + x];
                    assert_eq!(atlas.pixels[at..at + 4], texel, "splat {k} texel {x},{y}");
                }
            }
        }
    }
}

/// The writer's files read back by the reader.
#[cfg(test)]
mod round_trips {
    use super::*;
    use crate::geom::VertexAttributes;
    use crate::io::gltf::read;
    use crate::lod::chain::lod_screen_coverages;

    #[test]
    fn glb_round_trips_through_the_reader() {
        let mut m = crate::builtins::torus(1.0, 0.3, 16, 8);
        m.colors = Some(vec![Vec3::new(0.2, 0.5, 0.9); m.positions.len()]);
        let glb = write_glb(&m);
        let back = read(&glb, None).unwrap().0;
        assert_eq!(back.triangles, m.triangles);
        assert_eq!(back.positions, m.positions);
        assert!(back.normals.is_some() && back.uvs.is_some());
        assert_eq!(back.colors.as_ref().unwrap()[3], Vec3::new(0.2, 0.5, 0.9));
    }

    #[test]
    fn materials_round_trip_one_primitive_per_material_with_their_images() {
        use crate::geom::{AlphaMode, Image, Material, Materials};
        let png = crate::io::image::encode_png(&crate::lod::Texture {
            width: 2,
            height: 1,
            rgba: vec![[255, 0, 0, 255], [0, 0, 255, 128]],
        });
        let image = |png: &[u8]| Image {
            mime_type: "image/png".into(),
            bytes: png.into(),
            mag_filter: Some(9729),
            min_filter: None,
            wrap_s: 10497,
            wrap_t: 33648,
        };
        let textured = Material {
            name: Some("paint".into()),
            base_color: [1.0, 1.0, 1.0, 1.0],
            metallic: 0.25,
            roughness: 0.5,
            emissive: [0.0, 0.1, 0.0],
            alpha_mode: AlphaMode::Mask(0.3),
            double_sided: true,
            base_color_texture: Some(image(&png)),
            normal_texture: Some((image(&png[..]), 0.75)),
            vertex_attributes: Default::default(),
        };
        let glass = Material {
            name: Some("glass".into()),
            base_color: [0.5, 0.25, 0.0, 0.4],
            alpha_mode: AlphaMode::Blend,
            ..Material::default()
        };
        let mut a = crate::builtins::torus(1.0, 0.3, 16, 8);
        a.materials = Some(Materials::single(textured));
        let mut b = crate::builtins::torus(2.0, 0.2, 12, 6);
        // Display colours are base colour × COLOR_0.
        b.colors = Some(
            (0..b.positions.len())
                .map(|i| Vec3::new(0.5, 0.25, 0.0) * (i % 3) as f32 / 2.0)
                .collect(),
        );
        b.materials = Some(Materials::single(glass));
        let mut m = a.clone();
        m.append(&b);
        assert_eq!(m.part_count(), 2);
        let glb = write_glb(&m);
        let doc = glb_json(&glb);
        assert_eq!(doc["meshes"][0]["primitives"].as_array().unwrap().len(), 2);
        assert_eq!(doc["materials"].as_array().unwrap().len(), 2);
        assert_eq!(
            doc["samplers"][0],
            serde_json::json!({"magFilter": 9729, "wrapS": 10497, "wrapT": 33648})
        );
        let back = read(&glb, None).unwrap().0;
        // Read back, each material says which attributes its primitive has:
        // the textured part's white COLOR_0 was left out.
        let mut expected = m.materials.clone().unwrap();
        expected.table[0].vertex_attributes = VertexAttributes {
            colors: false,
            uvs: true,
        };
        assert_eq!(back.materials, Some(expected));
        assert_eq!(back.triangles.len(), m.triangles.len());
        assert_eq!(back.part_count(), 2);
        // The textured part's vertex colour is white: no COLOR_0 was written for it.
        let first = &doc["meshes"][0]["primitives"][0]["attributes"];
        assert!(first.get("COLOR_0").is_none() && first.get("TEXCOORD_0").is_some());
        // The normal map's frame is written: a MikkTSpace tangent per vertex.
        let count =
            |a: &serde_json::Value| doc["accessors"][a.as_u64().unwrap() as usize]["count"].clone();
        assert_eq!(count(&first["TANGENT"]), count(&first["POSITION"]));
        assert_eq!(doc["materials"][0]["normalTexture"]["scale"], 0.75);
        let (want, got) = (m.colors.clone().unwrap(), back.colors.clone().unwrap());
        for t in 0..m.triangles.len() {
            let p = m.part(t);
            assert_eq!(back.part(t), p);
            for (&v, &w) in m.triangles[t].iter().zip(&back.triangles[t]) {
                let (c, d) = (want[v as usize], got[w as usize]);
                assert!(c.abs_diff_eq(d, 1e-3), "part {p}: {c} vs {d}");
            }
        }
    }

    /// Image URIs name data or regular files beside the glTF, never devices,
    /// folders or other schemes.

    #[test]
    fn glb_with_points_holds_a_points_primitive_with_radius() {
        let mesh = crate::builtins::torus(1.0, 0.3, 8, 4);
        let points = crate::geom::PointSet {
            positions: vec![Vec3::ZERO, Vec3::X],
            normals: None,
            colors: Some(vec![Vec3::new(1.0, 0.0, 0.0); 2]),
            radii: Some(vec![0.1, 0.2]),
        };
        let set = |mesh: &TriMesh| crate::lod::DrawSet {
            mesh: mesh.clone(),
            points: (0..2)
                .map(|i| crate::lod::CutPoint {
                    center: points.positions[i],
                    radius: points.radii.as_ref().unwrap()[i],
                    color: Vec3::new(1.0, 0.0, 0.0),
                    normal: Vec3::Z,
                    error: 0.0,
                })
                .collect(),
            ..Default::default()
        };
        let glb = write_draw_set_glb(&set(&mesh));
        let doc = glb_json(&glb);
        assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0]));
        let prim = &doc["meshes"][0]["primitives"][1];
        assert_eq!(prim["mode"], 0);
        let radius = prim["attributes"]["_RADIUS"].as_u64().unwrap() as usize;
        assert_eq!(doc["accessors"][radius]["count"], 2);
        assert_eq!(read(&glb, None).unwrap().0.triangles, mesh.triangles);
        // Points alone still make a valid file.
        let only = glb_json(&write_draw_set_glb(&set(&TriMesh::default())));
        assert_eq!(only["meshes"][0]["primitives"][0]["mode"], 0);
    }

    fn sets(meshes: &[TriMesh]) -> Vec<crate::lod::DrawSet> {
        meshes
            .iter()
            .map(|m| crate::lod::DrawSet {
                mesh: m.clone(),
                ..Default::default()
            })
            .collect()
    }

    /// The JSON chunk of a GLB.
    fn glb_json(glb: &[u8]) -> serde_json::Value {
        let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        assert_eq!(&glb[16..20], b"JSON");
        serde_json::from_slice(&glb[20..20 + len]).unwrap()
    }

    #[test]
    fn lod_chain_carries_msft_lod_and_readers_without_it_see_lod0() {
        let lods = [
            crate::builtins::torus(1.0, 0.3, 32, 16),
            crate::builtins::torus(1.0, 0.3, 16, 8),
            crate::builtins::torus(1.0, 0.3, 8, 4),
        ];
        let coverages = lod_screen_coverages(&[0.001, 0.01, 0.1], 1.3, 2.0, 1080.0);
        let glb = write_lod_chain(&sets(&lods), &coverages, Default::default());
        let doc = glb_json(&glb);
        assert_eq!(doc["extensionsUsed"], serde_json::json!(["MSFT_lod"]));
        assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0]));
        assert_eq!(
            doc["nodes"][0]["extensions"]["MSFT_lod"]["ids"],
            serde_json::json!([1, 2])
        );
        let stated: Vec<f32> = doc["nodes"][0]["extras"]["MSFT_screencoverage"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        assert_eq!(stated, coverages);
        // Each LOD node's index accessor holds its triangles.
        for (i, lod) in lods.iter().enumerate() {
            let mesh = doc["nodes"][i]["mesh"].as_u64().unwrap() as usize;
            let prim = &doc["meshes"][mesh]["primitives"][0];
            let acc = prim["indices"].as_u64().unwrap() as usize;
            assert_eq!(
                doc["accessors"][acc]["count"].as_u64().unwrap() as usize,
                lod.triangles.len() * 3
            );
            for attr in ["POSITION", "NORMAL", "TEXCOORD_0"] {
                assert!(prim["attributes"][attr].is_u64(), "lod{i} {attr}");
            }
        }
        let back = read(&glb, None).unwrap().0;
        assert_eq!(back.triangles, lods[0].triangles);
        assert_eq!(back.positions, lods[0].positions);
        // One LOD: the plain file, no extension.
        let single = write_lod_chain(&sets(&lods[..1]), &coverages[..1], Default::default());
        assert_eq!(single, write_glb(&lods[0]));
    }

    #[test]
    fn lod_chain_without_triangles_in_a_lod_stays_readable() {
        let lods = [crate::builtins::torus(1.0, 0.3, 8, 4), TriMesh::default()];
        let glb = write_lod_chain(&sets(&lods), &[0.5, 0.1], Default::default());
        let doc = glb_json(&glb);
        assert!(doc["nodes"][1].get("mesh").is_none());
        assert_eq!(read(&glb, None).unwrap().0.triangles, lods[0].triangles);
        // Nothing at all: a valid GLB without a binary chunk.
        let empty = write_glb(&TriMesh::default());
        assert_eq!(
            empty.len(),
            20 + glb_json(&empty).to_string().len().next_multiple_of(4)
        );
        assert!(read(&empty, None).unwrap().0.triangles.is_empty());
        // A mesh without normals is written with computed ones.
        let mut bare = crate::builtins::torus(1.0, 0.3, 8, 4);
        bare.normals = None;
        let back = read(&write_glb(&bare), None).unwrap().0;
        let expected = bare.vertex_normals();
        for (a, b) in back.normals.unwrap().iter().zip(&expected) {
            assert!(a.distance(*b) < 1e-5);
        }
    }
}
