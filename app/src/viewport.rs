//! The studio's 3D viewport: an orbit camera and a wgpu renderer drawn through
//! egui's paint callback.
//!
//! egui's render pass has no depth buffer, so [`CallbackTrait::prepare`] renders
//! the scene into an offscreen colour + depth target of our own (sized to the
//! viewport in physical pixels, multisampled where the adapter allows), and
//! [`CallbackTrait::paint`] copies that image into egui's pass with a
//! full-screen triangle. GPU resources live in the renderer's
//! `callback_resources` (created once by [`init`]); geometry is uploaded only
//! when the scene's version changes, into buffers that grow but are reused.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use bytemuck::{Pod, Zeroable};
use egui_wgpu::{CallbackResources, CallbackTrait, ScreenDescriptor, wgpu};
use glam::{Mat4, Vec3};
use lodstudio_core::geom::{Aabb, PointSet, TriMesh, Volume};
use lodstudio_core::io::Model;
use lodstudio_core::lod::{DrawSet, Layer};

/// Vertical field of view of the camera.
const FOV_Y: f32 = std::f32::consts::FRAC_PI_4;
/// Surface colour of meshes without vertex colours (linear RGB).
const CLAY: Vec3 = Vec3::new(0.62, 0.56, 0.50);
/// Colour of points without colours and of volume bounding boxes (linear RGB).
const POINT_COLOR: Vec3 = Vec3::new(0.45, 0.62, 0.80);
const BOX_COLOR: Vec3 = Vec3::new(0.80, 0.80, 0.80);
/// Colour of splat outlines (linear RGB).
const OUTLINE_COLOR: Vec3 = Vec3::new(0.05, 0.05, 0.05);
/// Colour of translucent voxel layers (linear RGB; alpha from eq. 4).
const LAYER_COLOR: Vec3 = Vec3::new(0.70, 0.62, 0.52);
/// Background of the viewport (linear RGB).
const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.045,
    g: 0.050,
    b: 0.060,
    a: 1.0,
};
/// On-screen radius of points that carry no radius of their own.
const POINT_RADIUS_PX: f32 = 2.5;
const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Cosine of the crease angle (30°): sharper edges get split normals.
const CREASE_COS: f32 = 0.866;
/// Pitch stays short of the poles so the view's up vector is never parallel to it.
const MAX_PITCH: f32 = 1.55;

/// One mesh or line vertex as the GPU reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct MeshVertex {
    position: [f32; 3],
    normal: [f32; 3],
    color: [f32; 3],
}

/// One point, drawn as a screen-facing disc (an instance of a 6-vertex quad).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PointInstance {
    position: [f32; 3],
    /// Object-space radius; 0 draws the point at [`POINT_RADIUS_PX`].
    radius: f32,
    /// Zero when the point has no normal: it is then shaded as a small sphere.
    normal: [f32; 3],
    color: [f32; 3],
}

/// A vertex of a translucent surface (voxel layers, §3): colour with alpha.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct BlendVertex {
    position: [f32; 3],
    normal: [f32; 3],
    color: [f32; 4],
}

/// A corner of a textured splat quad (AMG domain primitive); `uv` points into
/// the scene's texture atlas, whose alpha holds the partition-of-unity weight Ψ.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SplatVertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
}

/// All splat textures packed into one RGBA8 image (shelf packing).
#[derive(Debug, Clone, Default)]
struct Atlas {
    width: u32,
    height: u32,
    rgba: Vec<[u8; 4]>,
}

/// Per-frame uniforms; the layout matches `Frame` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct FrameUniforms {
    view_proj: [[f32; 4]; 4],
    /// xyz: camera position.
    eye: [f32; 4],
    /// Viewport width and height in pixels, focal length in pixels, default point radius.
    viewport: [f32; 4],
}

/// Geometry ready for upload, built once per model (on a worker thread if wanted).
#[derive(Debug, Clone)]
pub struct Scene {
    /// Drawn in order: opaque parts first, then translucent ones.
    parts: Vec<Geometry>,
    bounds: Aabb,
}

#[derive(Debug, Clone)]
enum Geometry {
    Triangles {
        vertices: Vec<MeshVertex>,
        indices: Vec<u32>,
    },
    Points(Vec<PointInstance>),
    Lines(Vec<MeshVertex>),
    /// Alpha-blended triangles, drawn in index order (back to front).
    Translucent {
        vertices: Vec<BlendVertex>,
        indices: Vec<u32>,
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
        let vertex = |v: usize, face: Option<usize>, normal: Vec3| MeshVertex {
            position: mesh.positions[v].to_array(),
            normal: normals
                .map_or(normal, |given| given[v])
                .normalize_or_zero()
                .to_array(),
            color: face
                .and_then(|f| triangle_colors?.get(faces[f]).copied())
                .unwrap_or_else(|| colors.map_or(CLAY, |c| c[v]))
                .to_array(),
        };
        let geometry = match (normals, triangle_colors) {
            // Given normals and per-vertex colours: the mesh's own vertices serve.
            (Some(_), None) => Geometry::Triangles {
                vertices: (0..n).map(|v| vertex(v, None, Vec3::ZERO)).collect(),
                indices: triangles.into_iter().flatten().collect(),
            },
            _ => {
                let (vertices, indices) =
                    crease_split(&mesh.positions, &triangles, |v, f, normal| {
                        vertex(v, Some(f), normal)
                    });
                Geometry::Triangles { vertices, indices }
            }
        };
        Scene {
            parts: vec![geometry],
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
                color: BOX_COLOR.to_array(),
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

    /// Bounds of the model the scene was built from (what framing fits).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// How many triangles the scene draws (opaque and translucent).
    pub fn triangle_count(&self) -> usize {
        self.parts
            .iter()
            .map(|g| match g {
                Geometry::Triangles { indices, .. } | Geometry::Translucent { indices, .. } => {
                    indices.len() / 3
                }
                Geometry::Points(_) | Geometry::Lines(_) | Geometry::Splats { .. } => 0,
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
                        color: OUTLINE_COLOR.to_array(),
                    })
                    .collect();
                parts.push(Geometry::Lines(lines));
            }
        }
        Scene { parts, bounds }
    }
}

/// The layers' triangles as one alpha-blended list in `order` (each layer's
/// mesh keeps its vertices; normals are area-weighted), tinted `colors[layer]`
/// when given.
fn translucent_layers(
    layers: &[Layer],
    order: &[[u32; 2]],
    colors: Option<&[Vec3]>,
) -> (Vec<BlendVertex>, Vec<u32>) {
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
                .map(|(p, n)| BlendVertex {
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

/// Per-corner normals: each corner averages (area-weighted) the normals of the
/// faces around its vertex that lie within the crease angle of its own face.
/// `vertex(v, face, normal)` makes the output vertex; corners of one vertex
/// that come out equal (normal and colour) share it, so smooth meshes keep one
/// vertex per input vertex; unused vertices are dropped.
fn crease_split(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    vertex: impl Fn(usize, usize, Vec3) -> MeshVertex,
) -> (Vec<MeshVertex>, Vec<u32>) {
    let n = positions.len();
    let face_normals: Vec<Vec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            (b - a).cross(c - a)
        })
        .collect();
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
            let normal: Vec3 = around
                .iter()
                .map(|&g| g as usize)
                .filter(|&g| unit[f].dot(unit[g]) >= CREASE_COS)
                .map(|g| face_normals[g])
                .sum();
            let out = vertex(v, f, normal);
            let index = match vertices[first..]
                .iter()
                .position(|o: &MeshVertex| o.normal == out.normal && o.color == out.color)
            {
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

/// How a cut's scene is coloured beyond its own attributes.
#[derive(Debug, Clone, Copy, Default)]
pub struct SceneStyle<'a> {
    /// One colour per triangle of the cut's mesh.
    pub triangle_colors: Option<&'a [Vec3]>,
    /// One tint per translucent layer.
    pub layer_colors: Option<&'a [Vec3]>,
    /// Each splat's border (AMG paper Fig. 12).
    pub splat_outlines: bool,
}

/// The 3D view of one scene with an orbit camera.
pub struct Viewport {
    /// Point the camera orbits around and looks at.
    pub target: Vec3,
    /// Distance from the camera to `target`.
    pub distance: f32,
    /// Rotation about the vertical axis, radians.
    pub yaw: f32,
    /// Elevation above the horizontal plane, radians.
    pub pitch: f32,
    scene: Option<Arc<Scene>>,
    /// Bumped on every scene change; the GPU side re-uploads when it differs.
    version: u64,
    /// Width / height of the last shown rect, for framing.
    aspect: f32,
    has_wgpu: bool,
    /// Set by the GPU side when the scene does not fit in its buffers.
    too_large: Arc<AtomicBool>,
    /// Pixel size of the last shown rect (what cuts are taken for).
    size_px: [u32; 2],
    /// The ray (eye, direction) under the last click, until taken.
    click: Option<(Vec3, Vec3)>,
    /// Fly mode: W/A/S/D/Q/E walk the camera through the scene and dragging
    /// looks around the eye instead of orbiting the target.
    pub fly: bool,
    /// Which of the [`SLOTS`] GPU resource sets draws this viewport.
    slot: usize,
    /// Its accessibility label.
    label: &'static str,
}

/// Viewports that can be on screen at once (the side-by-side compare).
const SLOTS: usize = 2;

impl Viewport {
    /// A viewport drawing with `render_state` (after [`init`] on it), or a
    /// placeholder message when there is none.
    pub fn new(render_state: Option<&egui_wgpu::RenderState>) -> Self {
        if let Some(rs) = render_state {
            init(rs);
        }
        Viewport {
            target: Vec3::ZERO,
            distance: 3.0,
            yaw: 0.6,
            pitch: 0.4,
            scene: None,
            version: 0,
            aspect: 1.0,
            has_wgpu: render_state.is_some(),
            too_large: Arc::new(AtomicBool::new(false)),
            size_px: [1024, 768],
            click: None,
            fly: false,
            slot: 0,
            label: "3D viewport",
        }
    }

    /// A second viewport drawing beside the first (after [`Viewport::new`]
    /// made the GPU resources), with its own label and resources.
    pub fn second(render_state: Option<&egui_wgpu::RenderState>, label: &'static str) -> Self {
        let mut v = Viewport::new(None);
        v.has_wgpu = render_state.is_some();
        v.slot = 1;
        v.label = label;
        v
    }

    /// Takes `other`'s camera (target, distance, orbit angles and fly mode).
    pub fn follow(&mut self, other: &Viewport) {
        self.target = other.target;
        self.distance = other.distance;
        self.yaw = other.yaw;
        self.pitch = other.pitch;
        self.fly = other.fly;
    }

    /// Whether both viewports look from the same camera.
    pub fn same_camera(&self, other: &Viewport) -> bool {
        (self.target, self.distance, self.yaw, self.pitch)
            == (other.target, other.distance, other.yaw, other.pitch)
    }

    /// Shows `scene` from the default direction, framed to fit.
    pub fn set_scene(&mut self, scene: Scene) {
        self.frame_scene(Arc::new(scene));
    }

    /// Shows a shared `scene` (a newly opened model) from the default
    /// direction, framed to fit.
    pub fn frame_scene(&mut self, scene: Arc<Scene>) {
        self.replace_scene(scene);
        self.yaw = 0.6;
        self.pitch = 0.4;
        self.frame_all();
    }

    /// Shows `scene` through the current camera, so switching between versions
    /// of one model (original, simplified, colour-coded) keeps the view.
    /// Showing the scene already on screen uploads nothing.
    pub fn swap_scene(&mut self, scene: &Arc<Scene>) {
        if !self.scene.as_ref().is_some_and(|s| Arc::ptr_eq(s, scene)) {
            self.replace_scene(Arc::clone(scene));
        }
    }

    fn replace_scene(&mut self, scene: Arc<Scene>) {
        self.scene = Some(scene);
        self.version += 1;
        self.too_large.store(false, Ordering::Relaxed);
    }

    /// The scene on screen.
    pub fn scene(&self) -> Option<&Scene> {
        self.scene.as_deref()
    }

    /// Shows a mesh (builds its GPU geometry here, on the calling thread).
    pub fn set_mesh(&mut self, mesh: &TriMesh) {
        self.set_scene(Scene::from_mesh(mesh));
    }

    /// Shows a point set (builds its GPU geometry here, on the calling thread).
    pub fn set_points(&mut self, points: &PointSet) {
        self.set_scene(Scene::from_points(points));
    }

    /// Shows a volume's bounding box.
    pub fn set_volume(&mut self, volume: &Volume) {
        self.set_scene(Scene::from_volume(volume));
    }

    /// The camera as the core's cuts see it: eye, target, field of view and
    /// the viewport's size in pixels; the light comes from the eye.
    pub fn core_view(&self) -> lodstudio_core::view::View {
        let eye = self.eye();
        lodstudio_core::view::View {
            eye,
            target: self.target,
            up: Vec3::Y,
            fov_y: FOV_Y,
            width: self.size_px[0],
            height: self.size_px[1],
            light_dir: (eye - self.target).normalize_or(Vec3::Z),
        }
    }

    /// Centres the scene and moves the camera back until its bounding sphere fits.
    pub fn frame_all(&mut self) {
        let (center, radius) = self.scene_sphere();
        let half_fov_x = ((FOV_Y * 0.5).tan() * self.aspect).atan();
        let half_fov = half_fov_x.clamp(0.05, FOV_Y * 0.5);
        self.target = center;
        self.distance = radius / half_fov.sin() * 1.05;
    }

    /// Centre and radius of the scene's bounding sphere (unit sphere when there is none).
    fn scene_sphere(&self) -> (Vec3, f32) {
        match &self.scene {
            Some(s) if !s.bounds.is_empty() && s.bounds.diagonal().is_finite() => {
                (s.bounds.center(), (s.bounds.diagonal() * 0.5).max(1e-6))
            }
            _ => (Vec3::ZERO, 1.0),
        }
    }

    fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Camera right and up vectors in world space.
    fn basis(&self) -> (Vec3, Vec3) {
        let forward = (self.target - self.eye()).normalize_or(Vec3::NEG_Z);
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        (right, right.cross(forward))
    }

    /// View-projection matrix with near and far planes hugging the scene.
    fn view_proj(&self, aspect: f32) -> Mat4 {
        let eye = self.eye();
        let (center, radius) = self.scene_sphere();
        let d = eye.distance(center);
        let far = (d + radius * 1.05).max(1e-4);
        let near = (d - radius * 1.05).clamp(far * 1e-4, far * 0.5);
        let proj = glam::camera::rh::proj::directx::perspective(FOV_Y, aspect, near, far);
        let view = glam::camera::rh::view::look_at_mat4(eye, self.target, Vec3::Y);
        proj * view
    }

    /// Rotates about the target by a drag of `delta` points.
    fn orbit(&mut self, delta: egui::Vec2) {
        self.yaw -= delta.x * 0.01;
        self.pitch = (self.pitch + delta.y * 0.01).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target so the scene follows the pointer.
    fn pan(&mut self, delta: egui::Vec2, height_points: f32) {
        let world_per_point = 2.0 * self.distance * (FOV_Y * 0.5).tan() / height_points.max(1.0);
        let (right, up) = self.basis();
        self.target += (up * delta.y - right * delta.x) * world_per_point;
    }

    /// Moves towards (factor < 1) or away from the target, within sane bounds.
    fn zoom(&mut self, factor: f32) {
        let (_, radius) = self.scene_sphere();
        if factor.is_finite() && factor > 0.0 {
            self.distance = (self.distance * factor).clamp(radius * 1e-3, radius * 1e3);
        }
    }

    /// Draws the viewport into all remaining space and handles camera input:
    /// left-drag orbits, right/middle/shift+left-drag pans, scroll or pinch zooms,
    /// double-click frames the whole scene.
    pub fn show(&mut self, ui: &mut egui::Ui) -> egui::Response {
        let size = ui.available_size().max(egui::vec2(1.0, 1.0));
        let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
        let label = self.label;
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, label));
        self.aspect = rect.width() / rect.height().max(1.0);

        if !self.has_wgpu {
            ui.painter()
                .rect_filled(rect, 0.0, ui.visuals().extreme_bg_color);
            ui.put(rect, egui::Label::new("3D viewport needs wgpu"));
            return response;
        }

        self.handle_input(ui, &response, rect);

        let ppp = ui.ctx().pixels_per_point();
        let size_px = [
            (rect.width() * ppp).round().max(1.0) as u32,
            (rect.height() * ppp).round().max(1.0) as u32,
        ];
        self.size_px = size_px;
        let focal_px = size_px[1] as f32 * 0.5 / (FOV_Y * 0.5).tan();
        let uniforms = FrameUniforms {
            view_proj: self.view_proj(self.aspect).to_cols_array_2d(),
            eye: self.eye().extend(1.0).to_array(),
            viewport: [
                size_px[0] as f32,
                size_px[1] as f32,
                focal_px,
                POINT_RADIUS_PX * ppp,
            ],
        };
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(
            rect,
            ViewportCallback {
                slot: self.slot,
                uniforms,
                scene: self.scene.clone(),
                version: self.version,
                size_px,
                too_large: Arc::clone(&self.too_large),
            },
        ));
        if self.too_large.load(Ordering::Relaxed) {
            ui.put(
                rect,
                egui::Label::new(
                    egui::RichText::new("model too large for this GPU's buffers")
                        .color(ui.visuals().warn_fg_color),
                ),
            );
        }
        response
    }

    /// The ray under the last click in the viewport (taken once).
    pub fn take_click(&mut self) -> Option<(Vec3, Vec3)> {
        self.click.take()
    }

    /// The ray through the point `pos` of the viewport `rect`.
    fn ray(&self, pos: egui::Pos2, rect: egui::Rect) -> (Vec3, Vec3) {
        let ndc = glam::Vec2::new(
            (pos.x - rect.min.x) / rect.width().max(1.0) * 2.0 - 1.0,
            1.0 - (pos.y - rect.min.y) / rect.height().max(1.0) * 2.0,
        );
        let inverse = self.view_proj(self.aspect).inverse();
        let near = inverse.project_point3(ndc.extend(0.0));
        let far = inverse.project_point3(ndc.extend(1.0));
        (self.eye(), (far - near).normalize_or(Vec3::NEG_Z))
    }

    /// Turns the view about the eye (fly mode's look), keeping the eye still.
    fn look(&mut self, delta: egui::Vec2) {
        let eye = self.eye();
        self.orbit(-delta);
        self.target = eye - (self.eye() - self.target);
    }

    /// Fly mode's walk: `dir` in camera axes (right, up, forward), scaled to
    /// half the scene's radius per second (shift: four times faster).
    fn walk(&mut self, dir: Vec3, seconds: f32, fast: bool) {
        let (_, radius) = self.scene_sphere();
        let forward = (self.target - self.eye()).normalize_or(Vec3::NEG_Z);
        let (right, up) = self.basis();
        let speed = 0.5 * radius * if fast { 4.0 } else { 1.0 };
        self.target += (right * dir.x + up * dir.y + forward * dir.z) * speed * seconds;
    }

    fn handle_input(&mut self, ui: &egui::Ui, response: &egui::Response, rect: egui::Rect) {
        use egui::PointerButton::{Middle, Primary, Secondary};
        let delta = response.drag_delta();
        let shift = ui.input(|i| i.modifiers.shift);
        if response.dragged_by(Secondary)
            || response.dragged_by(Middle)
            || (response.dragged_by(Primary) && shift)
        {
            self.pan(delta, rect.height());
        } else if response.dragged_by(Primary) {
            if self.fly {
                self.look(delta);
            } else {
                self.orbit(delta);
            }
        }
        // Keys walk unless a text field has the keyboard.
        if self.fly && ui.memory(|m| m.focused().is_none()) {
            let (dir, dt) = ui.input(|i| {
                let key = |k: egui::Key| if i.key_down(k) { 1.0 } else { 0.0 };
                let dir = Vec3::new(
                    key(egui::Key::D) - key(egui::Key::A),
                    key(egui::Key::E) - key(egui::Key::Q),
                    key(egui::Key::W) - key(egui::Key::S),
                );
                (dir, i.stable_dt.min(0.1))
            });
            if dir != Vec3::ZERO {
                self.walk(dir, dt, shift);
                ui.ctx().request_repaint();
            }
        }
        if response.hovered() {
            let (scroll, pinch) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta()));
            if scroll != 0.0 {
                self.zoom((-scroll * 0.002).exp());
            }
            if pinch != 1.0 {
                self.zoom(1.0 / pinch);
            }
        }
        if response.double_clicked() {
            self.frame_all();
        } else if response.clicked()
            && let Some(pos) = response.interact_pointer_pos()
        {
            self.click = Some(self.ray(pos, rect));
        }
    }
}

/// The GPU resources of each viewport slot.
struct Slots(Vec<ViewportResources>);

/// Creates the viewports' pipelines in `render_state`; call once at start-up.
pub fn init(render_state: &egui_wgpu::RenderState) {
    let slots = Slots(
        (0..SLOTS)
            .map(|_| ViewportResources::new(render_state))
            .collect(),
    );
    render_state
        .renderer
        .write()
        .callback_resources
        .insert(slots);
}

/// What one frame of the viewport needs on the GPU side.
struct ViewportCallback {
    slot: usize,
    uniforms: FrameUniforms,
    scene: Option<Arc<Scene>>,
    version: u64,
    size_px: [u32; 2],
    too_large: Arc<AtomicBool>,
}

impl CallbackTrait for ViewportCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen_descriptor: &ScreenDescriptor,
        egui_encoder: &mut wgpu::CommandEncoder,
        callback_resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(res) = callback_resources
            .get_mut::<Slots>()
            .and_then(|s| s.0.get_mut(self.slot))
        {
            res.ensure_target(device, self.size_px);
            if res.uploaded_version != Some(self.version) {
                let fits = res.upload(device, queue, self.scene.as_deref());
                self.too_large.store(!fits, Ordering::Relaxed);
                res.uploaded_version = Some(self.version);
            }
            // The same scene through the same camera into the same target: the
            // last image stands (frames that only change the panels, such as a
            // build's progress, cost no 3D rendering).
            let frame = (self.uniforms, self.version, self.size_px);
            let unchanged = res.rendered.is_some_and(|(u, v, s)| {
                bytemuck::bytes_of(&u) == bytemuck::bytes_of(&frame.0)
                    && (v, s) == (frame.1, frame.2)
            });
            if !unchanged {
                queue.write_buffer(&res.uniform_buffer, 0, bytemuck::bytes_of(&self.uniforms));
                res.render(egui_encoder);
                res.rendered = Some(frame);
            }
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        callback_resources: &CallbackResources,
    ) {
        let Some(res) = callback_resources
            .get::<Slots>()
            .and_then(|s| s.0.get(self.slot))
        else {
            return;
        };
        let Some(target) = &res.target else {
            return;
        };
        // egui has set the viewport to our rect: one triangle covers it.
        render_pass.set_pipeline(&res.blit_pipeline);
        render_pass.set_bind_group(0, &target.blit_bind_group, &[]);
        render_pass.draw(0..3, 0..1);
    }
}

/// A GPU buffer that is reused and only reallocated when data outgrows it.
struct GrowBuffer {
    buffer: Option<wgpu::Buffer>,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl GrowBuffer {
    fn new(label: &'static str, usage: wgpu::BufferUsages) -> Self {
        GrowBuffer {
            buffer: None,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            label,
        }
    }

    /// Writes `data` at the start; false when it exceeds the device's buffer limit.
    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &[u8]) -> bool {
        let len = data.len() as u64;
        if len == 0 {
            return true;
        }
        if self.buffer.as_ref().is_none_or(|b| b.size() < len) {
            let max = device.limits().max_buffer_size;
            if len > max {
                return false;
            }
            let size = len
                .checked_next_power_of_two()
                .unwrap_or(len)
                .min(max)
                .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
            self.buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size,
                usage: self.usage,
                mapped_at_creation: false,
            }));
        }
        if let Some(buffer) = &self.buffer {
            queue.write_buffer(buffer, 0, data);
        }
        true
    }
}

/// What is uploaded and how to draw it.
#[derive(Clone, Copy)]
enum Drawn {
    Triangles { indices: u32 },
    Points { instances: u32 },
    Lines { vertices: u32 },
    Translucent { indices: u32 },
    Splats { indices: u32 },
}

/// One uploaded part of the scene.
struct PartGpu {
    vertices: GrowBuffer,
    indices: GrowBuffer,
    drawn: Option<Drawn>,
}

impl PartGpu {
    fn new() -> Self {
        PartGpu {
            vertices: GrowBuffer::new("viewport vertices", wgpu::BufferUsages::VERTEX),
            indices: GrowBuffer::new("viewport indices", wgpu::BufferUsages::INDEX),
            drawn: None,
        }
    }
}

/// The offscreen image the scene is rendered into, at the viewport's pixel size.
struct Target {
    size: [u32; 2],
    /// Resolved (or single-sample) colour, read by the blit.
    color: wgpu::TextureView,
    /// Multisampled colour, when MSAA is on.
    msaa: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
    blit_bind_group: wgpu::BindGroup,
}

struct ViewportResources {
    mesh_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    point_pipeline: wgpu::RenderPipeline,
    translucent_pipeline: wgpu::RenderPipeline,
    /// AMG §4 on the GPU: a depth pre-pass locks the nearest surface, then
    /// every splat adds colour·Ψ where it lies on that surface, so the
    /// overlapping neighbours of a domain blend into their partition of unity.
    splat_depth_pipeline: wgpu::RenderPipeline,
    splat_pipeline: wgpu::RenderPipeline,
    atlas_layout: wgpu::BindGroupLayout,
    atlas_sampler: wgpu::Sampler,
    atlas_bind_group: Option<wgpu::BindGroup>,
    blit_pipeline: wgpu::RenderPipeline,
    blit_layout: wgpu::BindGroupLayout,
    uniform_buffer: wgpu::Buffer,
    frame_bind_group: wgpu::BindGroup,
    parts: Vec<PartGpu>,
    uploaded_version: Option<u64>,
    /// What the target holds: the uniforms, scene version and size it was drawn with.
    rendered: Option<(FrameUniforms, u64, [u32; 2])>,
    sample_count: u32,
    target: Option<Target>,
}

impl ViewportResources {
    fn new(rs: &egui_wgpu::RenderState) -> Self {
        let device = &rs.device;
        // 4× MSAA where the GPU has it; a software renderer (lavapipe,
        // llvmpipe) would spend most of a frame on it, so it draws single-sampled.
        let software = rs.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let sample_count =
            if !software && supports_4x(rs, COLOR_FORMAT) && supports_4x(rs, DEPTH_FORMAT) {
                4
            } else {
                1
            };
        let scene_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("viewport scene"),
            source: wgpu::ShaderSource::Wgsl(SCENE_SHADER.into()),
        });
        let blit_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("viewport blit"),
            source: wgpu::ShaderSource::Wgsl(BLIT_SHADER.into()),
        });

        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(
                        std::mem::size_of::<FrameUniforms>() as u64
                    ),
                },
                count: None,
            }],
        });
        let uniform_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewport frame"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewport frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform_buffer.as_entire_binding(),
            }],
        });
        let scene_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport scene"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });

        const MESH_ATTRS: [wgpu::VertexAttribute; 3] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
        const POINT_ATTRS: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32, 2 => Float32x3, 3 => Float32x3
        ];
        let mesh_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &MESH_ATTRS,
        })];
        let point_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<PointInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &POINT_ATTRS,
        })];
        let atlas_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport splat atlas"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let splat_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport splats"),
            bind_group_layouts: &[Some(&frame_layout), Some(&atlas_layout)],
            immediate_size: 0,
        });
        let atlas_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("viewport splat atlas"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        const BLEND_ATTRS: [wgpu::VertexAttribute; 3] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];
        const SPLAT_ATTRS: [wgpu::VertexAttribute; 3] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];
        let blend_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<BlendVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &BLEND_ATTRS,
        })];
        let splat_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SplatVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &SPLAT_ATTRS,
        })];
        let additive = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent::OVER,
        };
        // Opaque by default; `Some(blend)` draws without writing depth.
        struct Style<'a> {
            layout: &'a wgpu::PipelineLayout,
            blend: Option<wgpu::BlendState>,
            depth_bias: i32,
        }
        let opaque = Style {
            layout: &scene_layout,
            blend: None,
            depth_bias: 0,
        };
        let scene_pipeline = |label: &str,
                              vs: &str,
                              fs: &str,
                              buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                              topology: wgpu::PrimitiveTopology,
                              style: &Style| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(style.layout),
                vertex: wgpu::VertexState {
                    module: &scene_module,
                    entry_point: Some(vs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(style.blend.is_none()),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState {
                        constant: style.depth_bias,
                        slope_scale: if style.depth_bias != 0 { 1.0 } else { 0.0 },
                        clamp: 0.0,
                    },
                }),
                multisample: wgpu::MultisampleState {
                    count: sample_count,
                    mask: !0,
                    alpha_to_coverage_enabled: false,
                },
                fragment: Some(wgpu::FragmentState {
                    module: &scene_module,
                    entry_point: Some(fs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend: style.blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let mesh_pipeline = scene_pipeline(
            "viewport mesh",
            "vs_mesh",
            "fs_mesh",
            &mesh_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &opaque,
        );
        let line_pipeline = scene_pipeline(
            "viewport lines",
            "vs_mesh",
            "fs_unlit",
            &mesh_buffers,
            wgpu::PrimitiveTopology::LineList,
            &opaque,
        );
        let point_pipeline = scene_pipeline(
            "viewport points",
            "vs_points",
            "fs_points",
            &point_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &opaque,
        );
        let translucent_pipeline = scene_pipeline(
            "viewport translucent layers",
            "vs_blend",
            "fs_blend",
            &blend_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &Style {
                layout: &scene_layout,
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                depth_bias: 0,
            },
        );
        // The pre-pass writes depth slightly behind the splats (a positive
        // bias), so splats on the same surface pass the test and blend.
        let splat_depth_pipeline = scene_pipeline(
            "viewport splat depth",
            "vs_splat",
            "fs_splat_depth",
            &splat_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &Style {
                layout: &splat_layout,
                blend: None,
                depth_bias: 2000,
            },
        );
        let splat_pipeline = scene_pipeline(
            "viewport splats",
            "vs_splat",
            "fs_splat",
            &splat_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &Style {
                layout: &splat_layout,
                blend: Some(additive),
                depth_bias: 0,
            },
        );

        let blit_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport blit"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let blit_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport blit"),
            bind_group_layouts: &[Some(&blit_layout)],
            immediate_size: 0,
        });
        // egui's pass (as run_studio and the tests configure it) has one sample
        // and no depth; its target may or may not be sRGB-encoding.
        let blit_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("viewport blit"),
            layout: Some(&blit_pipeline_layout),
            vertex: wgpu::VertexState {
                module: &blit_module,
                entry_point: Some("vs_blit"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &blit_module,
                entry_point: Some(if rs.target_format.is_srgb() {
                    "fs_blit_linear"
                } else {
                    "fs_blit_gamma"
                }),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                targets: &[Some(rs.target_format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });

        ViewportResources {
            mesh_pipeline,
            line_pipeline,
            point_pipeline,
            translucent_pipeline,
            splat_depth_pipeline,
            splat_pipeline,
            atlas_layout,
            atlas_sampler,
            atlas_bind_group: None,
            blit_pipeline,
            blit_layout,
            uniform_buffer,
            frame_bind_group,
            parts: Vec::new(),
            uploaded_version: None,
            rendered: None,
            sample_count,
            target: None,
        }
    }

    /// (Re)creates the offscreen target when the viewport's pixel size changed.
    fn ensure_target(&mut self, device: &wgpu::Device, size: [u32; 2]) {
        let max = device.limits().max_texture_dimension_2d.max(1);
        let size = size.map(|s| s.clamp(1, max));
        if self.target.as_ref().is_some_and(|t| t.size == size) {
            return;
        }
        let texture = |label: &str, format, samples, usage| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size[0],
                        height: size[1],
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let color = texture(
            "viewport colour",
            COLOR_FORMAT,
            1,
            attach | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let msaa = (self.sample_count > 1).then(|| {
            texture(
                "viewport colour (msaa)",
                COLOR_FORMAT,
                self.sample_count,
                attach,
            )
        });
        let depth = texture("viewport depth", DEPTH_FORMAT, self.sample_count, attach);
        let blit_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewport blit"),
            layout: &self.blit_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&color),
            }],
        });
        self.target = Some(Target {
            size,
            color,
            msaa,
            depth,
            blit_bind_group,
        });
    }

    /// Uploads the scene's geometry; false (and that part not drawn) when a
    /// part does not fit.
    fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: Option<&Scene>,
    ) -> bool {
        let parts = scene.map_or(&[][..], |s| &s.parts[..]);
        while self.parts.len() < parts.len() {
            self.parts.push(PartGpu::new());
        }
        let count = |n: usize| u32::try_from(n).ok();
        let mut fits = true;
        for (gpu, part) in self.parts.iter_mut().zip(parts) {
            let PartGpu {
                vertices: vb,
                indices: ib,
                ..
            } = gpu;
            let mut indexed = |vertices: &[u8], indices: &[u32]| {
                count(indices.len()).filter(|_| {
                    vb.write(device, queue, vertices)
                        && ib.write(device, queue, bytemuck::cast_slice(indices))
                })
            };
            gpu.drawn = match part {
                Geometry::Triangles { vertices, indices } => {
                    indexed(bytemuck::cast_slice(vertices), indices)
                        .map(|indices| Drawn::Triangles { indices })
                }
                Geometry::Translucent { vertices, indices } => {
                    indexed(bytemuck::cast_slice(vertices), indices)
                        .map(|indices| Drawn::Translucent { indices })
                }
                Geometry::Splats {
                    vertices,
                    indices,
                    atlas,
                } => {
                    self.atlas_bind_group = Some(upload_atlas(
                        device,
                        queue,
                        &self.atlas_layout,
                        &self.atlas_sampler,
                        atlas,
                    ));
                    indexed(bytemuck::cast_slice(vertices), indices)
                        .map(|indices| Drawn::Splats { indices })
                }
                Geometry::Points(points) => count(points.len())
                    .filter(|_| vb.write(device, queue, bytemuck::cast_slice(points)))
                    .map(|instances| Drawn::Points { instances }),
                Geometry::Lines(lines) => count(lines.len())
                    .filter(|_| vb.write(device, queue, bytemuck::cast_slice(lines)))
                    .map(|vertices| Drawn::Lines { vertices }),
            };
            fits &= gpu.drawn.is_some();
        }
        for gpu in self.parts.iter_mut().skip(parts.len()) {
            gpu.drawn = None;
        }
        fits
    }

    /// Clears the offscreen target and draws the uploaded geometry into it.
    fn render(&self, encoder: &mut wgpu::CommandEncoder) {
        let Some(target) = &self.target else {
            return;
        };
        let (view, resolve_target, store) = match &target.msaa {
            Some(msaa) => (msaa, Some(&target.color), wgpu::StoreOp::Discard),
            None => (&target.color, None, wgpu::StoreOp::Store),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("viewport scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                resolve_target,
                depth_slice: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(BACKGROUND),
                    store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_bind_group(0, &self.frame_bind_group, &[]);
        for part in &self.parts {
            let (Some(drawn), Some(vertices)) = (part.drawn, &part.vertices.buffer) else {
                continue;
            };
            pass.set_vertex_buffer(0, vertices.slice(..));
            let index_buffer = part.indices.buffer.as_ref();
            let indexed = |pass: &mut wgpu::RenderPass, pipeline: &wgpu::RenderPipeline, n: u32| {
                if let Some(ib) = index_buffer {
                    pass.set_pipeline(pipeline);
                    pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..n, 0, 0..1);
                }
            };
            match drawn {
                Drawn::Triangles { indices } => indexed(&mut pass, &self.mesh_pipeline, indices),
                Drawn::Translucent { indices } => {
                    indexed(&mut pass, &self.translucent_pipeline, indices)
                }
                Drawn::Splats { indices } => {
                    if let Some(atlas) = &self.atlas_bind_group {
                        pass.set_bind_group(1, atlas, &[]);
                        indexed(&mut pass, &self.splat_depth_pipeline, indices);
                        indexed(&mut pass, &self.splat_pipeline, indices);
                    }
                }
                Drawn::Points { instances } => {
                    pass.set_pipeline(&self.point_pipeline);
                    pass.draw(0..6, 0..instances);
                }
                Drawn::Lines { vertices: n } => {
                    pass.set_pipeline(&self.line_pipeline);
                    pass.draw(0..n, 0..1);
                }
            }
        }
    }
}

/// Uploads the splat atlas and binds it with its sampler.
fn upload_atlas(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    layout: &wgpu::BindGroupLayout,
    sampler: &wgpu::Sampler,
    atlas: &Atlas,
) -> wgpu::BindGroup {
    let max = device.limits().max_texture_dimension_2d;
    let size = wgpu::Extent3d {
        width: atlas.width.clamp(1, max),
        height: atlas.height.clamp(1, max),
        depth_or_array_layers: 1,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("viewport splat atlas"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let rows = (atlas.rgba.len() as u32 / atlas.width.max(1)).min(size.height);
    if rows > 0 && atlas.width <= max {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&atlas.rgba[..(rows * atlas.width) as usize]),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * atlas.width),
                rows_per_image: Some(rows),
            },
            wgpu::Extent3d {
                height: rows,
                ..size
            },
        );
    }
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("viewport splat atlas"),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(sampler),
            },
        ],
    })
}

/// Whether `format` can be rendered with 4x MSAA on this device.
fn supports_4x(rs: &egui_wgpu::RenderState, format: wgpu::TextureFormat) -> bool {
    let features = rs.device.features();
    let flags = if features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
        rs.adapter.get_texture_format_features(format).flags
    } else {
        format.guaranteed_format_features(features).flags
    };
    flags.sample_count_supported(4)
}

/// Every scene pipeline's shaders, one module: the frame's uniforms and
/// shading written once (`frame.wgsl`), lit meshes, lines and point discs
/// (`scene.wgsl`), translucent layers and textured splats (`blend.wgsl`).
const SCENE_SHADER: &str = concat!(
    include_str!("shaders/frame.wgsl"),
    include_str!("shaders/scene.wgsl"),
    include_str!("shaders/blend.wgsl"),
);

/// Copies the offscreen image 1:1 into egui's pass, encoding to sRGB when the
/// target does not do it itself.
const BLIT_SHADER: &str = include_str!("shaders/blit.wgsl");
