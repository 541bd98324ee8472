//! The CPU side of the viewport: a [`Scene`] is a model, a cut or a build's
//! preview turned into GPU-ready parts (lit triangles with crease-split
//! normals, point discs, lines, translucent layers, textured splats and their
//! atlas), built once, on a worker if wanted, and uploaded when it changes.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};
use lodstudio_core::geom::{Aabb, AlphaMode, PointSet, TriMesh, Volume};
use lodstudio_core::io::Model;
use lodstudio_core::lod::{DrawSet, Layer};

use super::camera::Sphere;
use super::texture::{decoded, white};

/// Surface colour of meshes without vertex colours (linear RGB).
const CLAY: Vec3 = Vec3::new(0.62, 0.56, 0.50);

/// Colour of points without colours and of volume bounding boxes (linear RGB).
const POINT_COLOR: Vec3 = Vec3::new(0.45, 0.62, 0.80);

const BOX_COLOR: Vec3 = Vec3::new(0.80, 0.80, 0.80);

/// Colour of splat outlines (linear RGB).
const OUTLINE_COLOR: Vec3 = Vec3::new(0.05, 0.05, 0.05);

/// Colour of the wireframe overlay's edges (linear RGB).
const WIRE_COLOR: Vec3 = Vec3::new(0.06, 0.06, 0.07);

/// Colour of translucent voxel layers (linear RGB; alpha from eq. 4).
const LAYER_COLOR: Vec3 = Vec3::new(0.70, 0.62, 0.52);

/// Cosine of the crease angle (30°): sharper edges get split normals.
const CREASE_COS: f32 = 0.866;

/// One vertex of a lit or unlit triangle or line, opaque (alpha 1) or
/// translucent (voxel layers, §3, alpha from eq. 4), as the GPU reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(super) struct MeshVertex {
    position: [f32; 3],
    normal: [f32; 3],
    color: [f32; 4],
}

/// A vertex of a mesh whose material has a base-colour texture: the colour
/// (vertex colour × the material's base colour) multiplies the texture at `uv`.
/// With a normal map, `tangent` is its MikkTSpace frame (`geom::tangents`);
/// all zero without one. Fragments whose alpha is under `alpha_cutoff` are
/// not drawn (glTF's MASK; 0 for opaque materials).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(super) struct TexturedVertex {
    position: [f32; 3],
    normal: [f32; 3],
    color: [f32; 4],
    uv: [f32; 2],
    tangent: [f32; 4],
    alpha_cutoff: f32,
}

/// One point, drawn as a screen-facing disc (an instance of a 6-vertex quad).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct PointInstance {
    position: [f32; 3],
    /// Object-space radius; 0 draws the point at the default on-screen radius.
    radius: f32,
    /// Zero when the point has no normal: it is then shaded as a small sphere.
    normal: [f32; 3],
    color: [f32; 3],
}

/// A corner of a textured splat quad (AMG domain primitive); `uv` points into
/// the scene's texture atlas, whose alpha holds the partition-of-unity weight Ψ.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct SplatVertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
}

/// An RGBA8 image (sRGB): all splat textures packed into one (shelf
/// packing), or a material's base-colour texture.
#[derive(Debug, Clone, Default)]
pub(super) struct Atlas {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) rgba: Vec<[u8; 4]>,
}

/// Geometry ready for upload, built once per model (on a worker thread if wanted).
#[derive(Debug, Clone)]
pub struct Scene {
    /// Drawn in order: opaque parts first, then translucent ones.
    pub(super) parts: Vec<Geometry>,
    bounds: Aabb,
}

#[derive(Debug, Clone)]
pub(super) enum Geometry {
    Triangles {
        vertices: Vec<MeshVertex>,
        indices: Vec<u32>,
    },
    Points(Vec<PointInstance>),
    Lines(Vec<MeshVertex>),
    /// Alpha-blended triangles, drawn in index order (back to front).
    Translucent {
        vertices: Vec<MeshVertex>,
        indices: Vec<u32>,
    },
    /// Lit triangles sampling a material's base-colour texture and normal
    /// map (shared by every scene of the model: decoded and uploaded once).
    Textured {
        vertices: Vec<TexturedVertex>,
        indices: Vec<u32>,
        texture: Arc<Atlas>,
        normal_map: Option<Arc<Atlas>>,
    },
    /// Textured quads blended by their Ψ (AMG paper §4).
    Splats {
        vertices: Vec<SplatVertex>,
        indices: Vec<u32>,
        atlas: Atlas,
    },
}

impl Scene {
    /// Lit triangles with the mesh's own normals, or else normals that are
    /// smooth across edges flatter than [`CREASE_COS`] and sharp at creases (so
    /// CAD parts keep crisp edges). Triangles that index outside the vertex
    /// array are left out.
    pub fn from_mesh(mesh: &TriMesh) -> Scene {
        Scene::mesh(mesh, None)
    }

    /// Like [`Scene::from_mesh`], but each triangle in one colour (linear RGB,
    /// indexed like `mesh.triangles`) to show a per-triangle value such as a
    /// certified error bound; triangles without an entry keep the mesh's colour.
    pub fn from_mesh_with_triangle_colors(mesh: &TriMesh, colors: &[Vec3]) -> Scene {
        Scene::mesh(mesh, Some(colors))
    }

    fn mesh(mesh: &TriMesh, triangle_colors: Option<&[Vec3]>) -> Scene {
        // Every corner takes its own side of a UV, normal or colour seam.
        let unwelded;
        let mesh = match &mesh.wedges {
            Some(_) => {
                unwelded = mesh.unwelded();
                &unwelded
            }
            None => mesh,
        };
        // A normal map shades in the frame of the vertices' tangents.
        let normal_mapped = triangle_colors.is_none()
            && mesh
                .materials
                .as_ref()
                .is_some_and(|m| m.table.iter().any(|m| m.normal_texture.is_some()));
        let framed = normal_mapped.then(|| mesh.with_tangents()).flatten();
        let (mesh, tangents) = match &framed {
            Some((split, tangents)) => (split, Some(tangents)),
            None => (mesh, None),
        };
        let n = mesh.positions.len();
        // Valid triangles and, for the colours, their index in the input.
        let (triangles, faces): (Vec<[u32; 3]>, Vec<usize>) = mesh
            .triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| t.iter().all(|&v| (v as usize) < n))
            .map(|(f, t)| (*t, f))
            .unzip();
        let colors = mesh.colors.as_ref().filter(|c| c.len() == n);
        let normals = mesh.normals.as_ref().filter(|v| v.len() == n);
        let uvs = mesh.uvs.as_ref().filter(|v| v.len() == n);
        let material = |f: usize| {
            let m = mesh.materials.as_ref()?;
            m.table.get(m.of(mesh.part(faces[f])) as usize)
        };
        // glTF's colour: vertex colour (where the material's vertices had
        // one) × base colour; clay for meshes without materials.
        let color = |v: usize, f: usize| -> Vec4 {
            if let Some(c) = triangle_colors.and_then(|c| c.get(faces[f])) {
                return c.extend(1.0);
            }
            match material(f) {
                None => colors.map_or(CLAY, |c| c[v]).extend(1.0),
                Some(m) => {
                    let vertex = colors
                        .filter(|_| m.vertex_attributes.colors)
                        .map_or(Vec3::ONE, |c| c[v]);
                    Vec4::from_array(m.base_color) * vertex.extend(1.0)
                }
            }
        };
        // The textures each triangle samples (none while coloured by value):
        // base colour, and the normal map where it has one.
        type Textures = (Arc<Atlas>, Option<Arc<Atlas>>);
        let texture = |f: usize| -> Option<Textures> {
            let m = material(f).filter(|m| m.vertex_attributes.uvs)?;
            uvs.filter(|_| triangle_colors.is_none())?;
            let normal_map = m.normal_texture.as_ref().filter(|_| tangents.is_some());
            let normal_map = normal_map.and_then(|(image, _)| decoded(image));
            // A normal map on a plain colour still bends the light.
            let base = match &m.base_color_texture {
                Some(image) => decoded(image)?,
                None => normal_map.as_ref().map(|_| white())?,
            };
            Some((base, normal_map))
        };
        let same_image = |a: &Option<Arc<Atlas>>, b: &Option<Arc<Atlas>>| match (a, b) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            (None, None) => true,
            _ => false,
        };
        let mut groups: Vec<(Option<Textures>, Vec<usize>)> = Vec::new();
        for f in 0..triangles.len() {
            let tex = texture(f);
            let same = |g: &Option<Textures>| match (g, &tex) {
                (Some(a), Some(b)) => Arc::ptr_eq(&a.0, &b.0) && same_image(&a.1, &b.1),
                (None, None) => true,
                _ => false,
            };
            match groups.iter_mut().find(|(g, _)| same(g)) {
                Some((_, members)) => members.push(f),
                None => groups.push((tex, vec![f])),
            }
        }
        let normal = |v: usize, computed: Vec3| {
            normals
                .map_or(computed, |given| given[v])
                .normalize_or_zero()
                .to_array()
        };
        let parts = groups
            .into_iter()
            .map(|(tex, members)| {
                let tris: Vec<[u32; 3]> = members.iter().map(|&f| triangles[f]).collect();
                let split = normals.is_none();
                match tex {
                    None => {
                        let (vertices, indices) =
                            crease_split(&mesh.positions, &tris, split, |v, k, computed| {
                                MeshVertex {
                                    position: mesh.positions[v].to_array(),
                                    normal: normal(v, computed),
                                    color: color(v, members[k]).to_array(),
                                }
                            });
                        Geometry::Triangles { vertices, indices }
                    }
                    Some((texture, normal_map)) => {
                        let uvs = uvs.expect("textured triangles have UVs");
                        let tangent = |v: usize| match (&normal_map, tangents) {
                            (Some(_), Some(t)) => t[v].to_array(),
                            _ => [0.0; 4],
                        };
                        let (vertices, indices) =
                            crease_split(&mesh.positions, &tris, split, |v, k, computed| {
                                TexturedVertex {
                                    position: mesh.positions[v].to_array(),
                                    normal: normal(v, computed),
                                    color: color(v, members[k]).to_array(),
                                    uv: uvs[v].to_array(),
                                    tangent: tangent(v),
                                    alpha_cutoff: match material(members[k]).map(|m| m.alpha_mode) {
                                        Some(AlphaMode::Mask(cutoff)) => cutoff,
                                        _ => 0.0,
                                    },
                                }
                            });
                        Geometry::Textured {
                            vertices,
                            indices,
                            texture,
                            normal_map,
                        }
                    }
                }
            })
            .collect();
        Scene {
            parts,
            bounds: mesh.bounds(),
        }
    }

    /// Screen-facing discs, sized by the points' radii where they have them.
    pub fn from_points(points: &PointSet) -> Scene {
        let n = points.positions.len();
        let normals = points.normals.as_ref().filter(|v| v.len() == n);
        let colors = points.colors.as_ref().filter(|v| v.len() == n);
        let radii = points.radii.as_ref().filter(|v| v.len() == n);
        let instances = (0..n)
            .map(|i| PointInstance {
                position: points.positions[i].to_array(),
                radius: radii.map_or(0.0, |r| r[i].max(0.0)),
                normal: normals
                    .map_or(Vec3::ZERO, |v| v[i].normalize_or_zero())
                    .to_array(),
                color: colors.map_or(POINT_COLOR, |c| c[i]).to_array(),
            })
            .collect();
        Scene {
            parts: vec![Geometry::Points(instances)],
            bounds: points.bounds(),
        }
    }

    /// A volume shows its bounding box as lines.
    pub fn from_volume(volume: &Volume) -> Scene {
        let b = volume.bounds();
        let corner = |i: usize| {
            Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            )
        };
        // The 12 edges join corners that differ in exactly one axis bit.
        let lines = (0..8usize)
            .flat_map(|i| [1, 2, 4].map(|bit| (i, i | bit)))
            .filter(|(i, j)| i != j)
            .flat_map(|(i, j)| [corner(i), corner(j)])
            .map(|p| MeshVertex {
                position: p.to_array(),
                normal: [0.0; 3],
                color: BOX_COLOR.extend(1.0).to_array(),
            })
            .collect();
        Scene {
            parts: vec![Geometry::Lines(lines)],
            bounds: b,
        }
    }

    /// The scene for any loaded model (meshes, points, or a volume's box).
    pub fn from_model(model: &Model) -> Scene {
        match model {
            Model::Mesh(m) => Scene::from_mesh(m),
            Model::Points(p) => Scene::from_points(p),
            Model::Volume(v) => Scene::from_volume(v),
        }
    }

    /// The scene with every edge of `mesh`'s triangles drawn over it (each
    /// edge once; triangles that index outside the vertices are left out).
    pub fn with_wireframe(mut self, mesh: &TriMesh) -> Scene {
        let n = mesh.positions.len() as u32;
        let mut edges: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .filter(|t| t.iter().all(|&v| v < n))
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let vertex = |v: u32| MeshVertex {
            position: mesh.positions[v as usize].to_array(),
            normal: [0.0; 3],
            color: WIRE_COLOR.extend(1.0).to_array(),
        };
        let lines = edges
            .iter()
            .flat_map(|&(a, b)| [vertex(a), vertex(b)])
            .collect();
        self.parts.push(Geometry::Lines(lines));
        self
    }

    /// Bounds of the model the scene was built from (what framing fits).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The bounds' sphere, which the camera frames and clips to (the unit
    /// sphere for empty or non-finite bounds).
    pub fn sphere(&self) -> Sphere {
        let b = self.bounds;
        if b.is_empty() || !b.diagonal().is_finite() {
            return Sphere::UNIT;
        }
        Sphere {
            center: b.center(),
            radius: (b.diagonal() * 0.5).max(1e-6),
        }
    }

    /// How many triangles the scene draws (opaque and translucent).
    pub fn triangle_count(&self) -> usize {
        self.parts
            .iter()
            .map(|g| match g {
                Geometry::Triangles { indices, .. }
                | Geometry::Translucent { indices, .. }
                | Geometry::Textured { indices, .. } => indices.len() / 3,
                Geometry::Points(_) | Geometry::Lines(_) | Geometry::Splats { .. } => 0,
            })
            .sum()
    }

    /// How many line segments the scene draws (wireframe, outlines, boxes).
    pub fn line_count(&self) -> usize {
        self.parts
            .iter()
            .map(|g| match g {
                Geometry::Lines(lines) => lines.len() / 2,
                _ => 0,
            })
            .sum()
    }

    /// How many points and splats the scene draws.
    pub fn point_and_splat_counts(&self) -> (usize, usize) {
        self.parts.iter().fold((0, 0), |(p, q), g| match g {
            Geometry::Points(points) => (p + points.len(), q),
            Geometry::Splats { indices, .. } => (p, q + indices.len() / 6),
            _ => (p, q),
        })
    }

    /// Everything on a cut: its triangles (coloured per triangle when
    /// `triangle_colors` is given), its points as discs of their radius, its
    /// splats as textured quads, and its translucent layers in `layer_order`
    /// ((layer, triangle), back to front; all layers in order when empty).
    pub fn from_draw_set(set: &DrawSet, style: &SceneStyle) -> Scene {
        let mut parts = Vec::new();
        let mut bounds = Aabb::EMPTY;
        if !set.mesh.triangles.is_empty() {
            let scene = Scene::mesh(&set.mesh, style.triangle_colors);
            bounds = bounds.union(scene.bounds);
            parts.extend(scene.parts);
        }
        if !set.points.is_empty() {
            let instances = set
                .points
                .iter()
                .map(|p| {
                    bounds = bounds.union(Aabb {
                        min: p.center - Vec3::splat(p.radius),
                        max: p.center + Vec3::splat(p.radius),
                    });
                    PointInstance {
                        position: p.center.to_array(),
                        radius: p.radius.max(0.0),
                        normal: p.normal.normalize_or_zero().to_array(),
                        color: p.color.to_array(),
                    }
                })
                .collect();
            parts.push(Geometry::Points(instances));
        }
        if !set.layers.is_empty() {
            let (vertices, indices) =
                translucent_layers(&set.layers, &set.layer_order, style.layer_colors);
            for v in &vertices {
                bounds = bounds.grow(Vec3::from_array(v.position));
            }
            parts.push(Geometry::Translucent { vertices, indices });
        }
        if !set.splats.is_empty() {
            let splats = splat_quads(set);
            for v in &splats.0 {
                bounds = bounds.grow(Vec3::from_array(v.position));
            }
            parts.push(Geometry::Splats {
                vertices: splats.0,
                indices: splats.1,
                atlas: splats.2,
            });
            if style.splat_outlines {
                // Each quad's border (AMG paper Fig. 12).
                let lines = set
                    .splats
                    .iter()
                    .flat_map(|s| {
                        let c = s.corners();
                        (0..4).flat_map(move |i| [c[i], c[(i + 1) % 4]])
                    })
                    .map(|p| MeshVertex {
                        position: p.to_array(),
                        normal: [0.0; 3],
                        color: OUTLINE_COLOR.extend(1.0).to_array(),
                    })
                    .collect();
                parts.push(Geometry::Lines(lines));
            }
        }
        let scene = Scene { parts, bounds };
        match style.wireframe {
            true => scene.with_wireframe(&set.mesh),
            false => scene,
        }
    }
}

/// How a cut's scene is coloured beyond its own attributes.
#[derive(Debug, Clone, Copy, Default)]
pub struct SceneStyle<'a> {
    /// One colour per triangle of the cut's mesh.
    pub triangle_colors: Option<&'a [Vec3]>,
    /// One tint per translucent layer.
    pub layer_colors: Option<&'a [Vec3]>,
    /// Each splat's border (AMG paper Fig. 12).
    pub splat_outlines: bool,
    /// Every triangle edge of the cut's mesh drawn over it.
    pub wireframe: bool,
}

/// The layers' triangles as one alpha-blended list in `order` (each layer's
/// mesh keeps its vertices; normals are area-weighted), tinted `colors[layer]`
/// when given.
fn translucent_layers(
    layers: &[Layer],
    order: &[[u32; 2]],
    colors: Option<&[Vec3]>,
) -> (Vec<MeshVertex>, Vec<u32>) {
    let mut vertices = Vec::new();
    let mut base = Vec::with_capacity(layers.len());
    for (l, layer) in layers.iter().enumerate() {
        base.push(vertices.len() as u32);
        let normals = layer.mesh.vertex_normals();
        let color = colors
            .and_then(|c| c.get(l))
            .copied()
            .unwrap_or(LAYER_COLOR);
        let tint = color.extend(layer.alpha.clamp(0.0, 1.0));
        vertices.extend(
            layer
                .mesh
                .positions
                .iter()
                .zip(&normals)
                .map(|(p, n)| MeshVertex {
                    position: p.to_array(),
                    normal: n.normalize_or_zero().to_array(),
                    color: tint.to_array(),
                }),
        );
    }
    let all: Vec<[u32; 2]>;
    let order = if order.is_empty() {
        all = layers
            .iter()
            .enumerate()
            .flat_map(|(l, m)| (0..m.mesh.triangles.len() as u32).map(move |t| [l as u32, t]))
            .collect();
        &all
    } else {
        order
    };
    let indices = order
        .iter()
        .filter_map(|&[l, t]| {
            let layer = layers.get(l as usize)?;
            let tri = layer.mesh.triangles.get(t as usize)?;
            Some(tri.map(|v| base[l as usize] + v))
        })
        .flatten()
        .collect();
    (vertices, indices)
}

/// Splat quads and the atlas holding their textures (shelf packing, one texel
/// of gutter so bilinear filtering never reads a neighbour).
fn splat_quads(set: &DrawSet) -> (Vec<SplatVertex>, Vec<u32>, Atlas) {
    const WIDTH: u32 = 2048;
    let mut places = Vec::with_capacity(set.textures.len());
    let (mut x, mut y, mut shelf) = (0u32, 0u32, 0u32);
    for t in &set.textures {
        let (w, h) = (t.width.clamp(1, WIDTH - 2) + 2, t.height.max(1) + 2);
        if x + w > WIDTH {
            x = 0;
            y += shelf;
            shelf = 0;
        }
        places.push((x + 1, y + 1));
        x += w;
        shelf = shelf.max(h);
    }
    let height = (y + shelf).max(1);
    let mut atlas = Atlas {
        width: WIDTH,
        height,
        rgba: vec![[0; 4]; (WIDTH * height) as usize],
    };
    for (t, &(px, py)) in set.textures.iter().zip(&places) {
        let w = t.width.min(WIDTH - 2);
        for row in 0..t.height {
            for col in 0..w {
                if let Some(texel) = t.rgba.get((row * t.width + col) as usize) {
                    atlas.rgba[((py + row) * WIDTH + px + col) as usize] = *texel;
                }
            }
        }
    }
    let mut vertices = Vec::with_capacity(set.splats.len() * 4);
    let mut indices = Vec::with_capacity(set.splats.len() * 6);
    for splat in &set.splats {
        let Some((t, &(px, py))) = set
            .textures
            .get(splat.texture)
            .zip(places.get(splat.texture))
        else {
            continue;
        };
        let (u0, v0) = (px as f32 / WIDTH as f32, py as f32 / height as f32);
        let (u1, v1) = (
            (px + t.width.min(WIDTH - 2)) as f32 / WIDTH as f32,
            (py + t.height) as f32 / height as f32,
        );
        let base = vertices.len() as u32;
        let c = splat.corners();
        for (corner, uv) in [
            (c[0], [u0, v0]),
            (c[1], [u1, v0]),
            (c[2], [u1, v1]),
            (c[3], [u0, v1]),
        ] {
            vertices.push(SplatVertex {
                position: corner.to_array(),
                normal: splat.normal.to_array(),
                uv,
            });
        }
        indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    (vertices, indices, atlas)
}

/// Per-corner normals (with `compute_normals`; else `vertex` brings its
/// own): each corner averages (area-weighted) the normals of the
/// faces around its vertex that lie within the crease angle of its own face.
/// `vertex(v, face, normal)` makes the output vertex; corners of one vertex
/// that come out equal (normal and colour) share it, so smooth meshes keep one
/// vertex per input vertex; unused vertices are dropped.
fn crease_split<V: Copy + PartialEq>(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    compute_normals: bool,
    vertex: impl Fn(usize, usize, Vec3) -> V,
) -> (Vec<V>, Vec<u32>) {
    let n = positions.len();
    let face_normals: Vec<Vec3> = match compute_normals {
        true => triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| positions[v as usize]);
                (b - a).cross(c - a)
            })
            .collect(),
        false => Vec::new(),
    };
    let unit: Vec<Vec3> = face_normals.iter().map(|f| f.normalize_or_zero()).collect();
    // Faces around each vertex, in compressed rows.
    let mut start = vec![0usize; n + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut faces = vec![0u32; start[n]];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            faces[fill[v as usize]] = f as u32;
            fill[v as usize] += 1;
        }
    }
    let mut vertices = Vec::with_capacity(n);
    let mut indices = vec![0u32; triangles.len() * 3];
    for v in 0..n {
        let around = &faces[start[v]..start[v + 1]];
        let first = vertices.len();
        for &f in around {
            let f = f as usize;
            let normal: Vec3 = match compute_normals {
                true => around
                    .iter()
                    .map(|&g| g as usize)
                    .filter(|&g| unit[f].dot(unit[g]) >= CREASE_COS)
                    .map(|g| face_normals[g])
                    .sum(),
                false => Vec3::ZERO,
            };
            let out = vertex(v, f, normal);
            let index = match vertices[first..].iter().position(|o| *o == out) {
                Some(i) => first + i,
                None => {
                    vertices.push(out);
                    vertices.len() - 1
                }
            };
            for (k, &corner) in triangles[f].iter().enumerate() {
                if corner as usize == v {
                    indices[3 * f + k] = index as u32;
                }
            }
        }
    }
    (vertices, indices)
}

#[cfg(test)]
mod tests {
    use glam::Vec2;
    use lodstudio_core::lod::{CutPoint, Splat, Texture};

    use super::*;

    /// A unit cube: 8 shared corners, 12 outward triangles.
    fn cube() -> TriMesh {
        let positions = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        TriMesh::new(positions, triangles)
    }

    fn triangles(scene: &Scene) -> (&[MeshVertex], &[u32]) {
        match &scene.parts[..] {
            [Geometry::Triangles { vertices, indices }] => (vertices, indices),
            _ => panic!("one triangle part expected"),
        }
    }

    #[test]
    fn creases_split_normals_and_smooth_surfaces_share_vertices() {
        let scene = Scene::from_mesh(&cube());
        let (vertices, indices) = triangles(&scene);
        // Every corner of the cube meets three faces at 90°: one vertex per face.
        assert_eq!((vertices.len(), indices.len()), (24, 36));
        assert_eq!(scene.triangle_count(), 12);
        for v in vertices {
            let n = Vec3::from_array(v.normal);
            assert!((n.length() - 1.0).abs() < 1e-5);
            assert_eq!(n.abs().max_element(), 1.0, "axis-aligned: {n}");
            assert_eq!(v.color, CLAY.extend(1.0).to_array());
        }
        // A fine sphere has no crease: one vertex per input vertex.
        let sphere = lodstudio_core::builtins::icosphere(Vec3::ZERO, 1.0, 3);
        let smooth = Scene::from_mesh(&sphere);
        assert_eq!(triangles(&smooth).0.len(), sphere.positions.len());
    }

    #[test]
    fn bad_triangles_are_left_out_and_face_colours_split_shared_corners() {
        let mut quad = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3], [0, 2, 99]],
        );
        assert_eq!(Scene::from_mesh(&quad).triangle_count(), 2);
        quad.triangles.pop();
        let scene = Scene::from_mesh_with_triangle_colors(&quad, &[Vec3::X, Vec3::Z]);
        let (vertices, indices) = triangles(&scene);
        // Corners 0 and 2 carry both colours: 4 + 2 vertices.
        assert_eq!(vertices.len(), 6);
        assert_eq!(vertices[indices[0] as usize].color, [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(vertices[indices[3] as usize].color, [0.0, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn textured_materials_sample_their_image_with_each_sides_uvs() {
        use lodstudio_core::geom::{Image, Material, Materials, VertexAttributes, Wedges};
        let png = lodstudio_core::io::image::encode_png(&Texture {
            width: 1,
            height: 1,
            rgba: vec![[200, 100, 50, 255]],
        });
        let image = |bytes: &[u8]| Image {
            mime_type: "image/png".into(),
            bytes: bytes.into(),
            mag_filter: None,
            min_filter: None,
            wrap_s: 10497,
            wrap_t: 10497,
        };
        let textured = Material {
            base_color: [0.5, 1.0, 1.0, 1.0],
            base_color_texture: Some(image(&png)),
            vertex_attributes: VertexAttributes {
                colors: false,
                uvs: true,
            },
            ..Default::default()
        };
        let plain = Material {
            base_color: [0.0, 0.5, 0.0, 1.0],
            ..Default::default()
        };
        // Two triangles sharing the edge 0–2, welded across a UV seam: the
        // wedges give corners 0 and 2 one UV on each side.
        let mut mesh = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        mesh.uvs = Some(vec![Vec2::ZERO; 4]);
        mesh.wedges = Some(Wedges {
            corners: vec![[0, 1, 2], [3, 4, 5]],
            vertex: vec![0, 1, 2, 0, 2, 3],
            normals: None,
            colors: None,
            uvs: Some((0..6).map(|w| Vec2::splat(w as f32 / 10.0)).collect()),
            payload: None,
        });
        mesh.parts = Some(vec![0, 0]);
        mesh.materials = Some(Materials::single(textured.clone()));
        let scene = Scene::from_mesh(&mesh);
        let [
            Geometry::Textured {
                vertices,
                indices,
                texture,
                normal_map,
            },
        ] = &scene.parts[..]
        else {
            panic!("one textured part");
        };
        assert_eq!(texture.rgba, vec![[200, 100, 50, 255]]);
        let uvs: Vec<[f32; 2]> = indices.iter().map(|&i| vertices[i as usize].uv).collect();
        let want: Vec<[f32; 2]> = (0..6).map(|w| [w as f32 / 10.0; 2]).collect();
        assert_eq!(uvs, want, "every corner its own side of the seam");
        assert_eq!(vertices[0].color, [0.5, 1.0, 1.0, 1.0], "the base colour");
        // The same image is decoded once for every scene of the model.
        let again = Scene::from_mesh(&mesh);
        let [Geometry::Textured { texture: other, .. }] = &again.parts[..] else {
            panic!("one textured part");
        };
        assert!(Arc::ptr_eq(texture, other));
        assert!(normal_map.is_none() && vertices.iter().all(|v| v.tangent == [0.0; 4]));
        // A normal map comes with every vertex's MikkTSpace frame.
        let mut mapped = mesh.clone();
        mapped.materials.as_mut().unwrap().table[0].normal_texture = Some((image(&png), 1.0));
        let [
            Geometry::Textured {
                vertices,
                normal_map,
                ..
            },
        ] = &Scene::from_mesh(&mapped).parts[..]
        else {
            panic!("one textured part");
        };
        assert!(normal_map.is_some());
        assert!(vertices.iter().all(|v| v.tangent[3].abs() == 1.0));
        // A normal map on a plain colour is drawn too, on one white texel.
        mapped.materials.as_mut().unwrap().table[0].base_color_texture = None;
        let [
            Geometry::Textured {
                texture,
                normal_map,
                ..
            },
        ] = &Scene::from_mesh(&mapped).parts[..]
        else {
            panic!("one normal-mapped part");
        };
        assert!(normal_map.is_some() && texture.rgba == [[255; 4]]);
        // A second, untextured part draws in its base colour; an image that
        // does not decode leaves its material's base colour alone.
        mesh.parts = Some(vec![0, 1]);
        mesh.materials = Some(Materials {
            table: vec![textured, plain],
            of_part: vec![0, 1],
        });
        let two = Scene::from_mesh(&mesh);
        assert_eq!(two.parts.len(), 2);
        let Geometry::Triangles { vertices, .. } = &two.parts[1] else {
            panic!("the plain part");
        };
        assert!(vertices.iter().all(|v| v.color == [0.0, 0.5, 0.0, 1.0]));
        let mut broken = mesh.clone();
        broken.materials.as_mut().unwrap().table[0].base_color_texture = Some(image(b"no png"));
        let shown = Scene::from_mesh(&broken);
        assert!(
            shown
                .parts
                .iter()
                .all(|p| matches!(p, Geometry::Triangles { .. }))
        );
        assert_eq!(shown.triangle_count(), 2);
    }

    #[test]
    fn a_cut_draws_its_points_splats_outlines_and_layers() {
        let texture = Texture {
            width: 2,
            height: 1,
            rgba: vec![[10, 20, 30, 255], [40, 50, 60, 128]],
        };
        let splat = Splat {
            center: Vec3::new(5.0, 0.0, 0.0),
            axes: [Vec3::X, Vec3::Y],
            normal: Vec3::Z,
            texture: 0,
            domain: 0,
            neighbours: Vec::new(),
        };
        let layer = |alpha| Layer {
            mesh: cube(),
            alpha,
            isodensity: 0.5,
        };
        let set = DrawSet {
            mesh: cube(),
            points: vec![CutPoint {
                center: Vec3::new(0.0, -3.0, 0.0),
                radius: 0.5,
                color: Vec3::ONE,
                normal: Vec3::Z,
                error: 0.1,
            }],
            splats: vec![
                splat.clone(),
                Splat {
                    texture: 7,
                    ..splat
                },
            ],
            textures: vec![texture],
            layers: vec![layer(0.3), layer(0.6)],
            layer_order: vec![[1, 0], [0, 11], [5, 0]],
            ..Default::default()
        };
        let style = SceneStyle {
            splat_outlines: true,
            ..Default::default()
        };
        let scene = Scene::from_draw_set(&set, &style);
        // A splat with no texture is skipped; the points count once.
        assert_eq!(scene.point_and_splat_counts(), (1, 1));
        // The cube's 12 triangles and the two layer triangles in order (a
        // bad layer index is skipped).
        assert_eq!(scene.triangle_count(), 12 + 2);
        let mut seen = 0;
        for part in &scene.parts {
            match part {
                Geometry::Lines(lines) => assert_eq!(lines.len(), 2 * 8, "4 edges per splat"),
                Geometry::Translucent { vertices, indices } => {
                    assert_eq!(vertices[indices[0] as usize].color[3], 0.6);
                    // Layer 1's first triangle (after layer 0's 8 vertices),
                    // then layer 0's last.
                    assert_eq!(indices, &[8, 10, 11, 1, 7, 5]);
                }
                Geometry::Splats {
                    atlas, vertices, ..
                } => {
                    // The texture sits one gutter texel in, where its uv points.
                    assert_eq!(atlas.rgba[(atlas.width + 1) as usize], [10, 20, 30, 255]);
                    assert_eq!(atlas.rgba[(atlas.width + 2) as usize], [40, 50, 60, 128]);
                    let uv = vertices[0].uv;
                    assert_eq!(uv[0] * atlas.width as f32, 1.0);
                }
                _ => {}
            }
            seen += 1;
        }
        assert_eq!(seen, 5, "triangles, points, layers, splats, outlines");
        // The bounds hold the point's disc and the splat's corners.
        let b = scene.bounds();
        assert_eq!((b.min.y, b.max.x), (-3.5, 6.0));
    }

    #[test]
    fn empty_and_volume_scenes_frame_sensibly() {
        assert_eq!(
            Scene::from_draw_set(&DrawSet::default(), &SceneStyle::default()).sphere(),
            Sphere::UNIT
        );
        let points = PointSet {
            positions: vec![Vec3::splat(2.0), Vec3::splat(4.0)],
            ..Default::default()
        };
        let s = Scene::from_points(&points).sphere();
        assert_eq!(s.center, Vec3::splat(3.0));
        assert!((s.radius - 3f32.sqrt()).abs() < 1e-5);
    }
}
