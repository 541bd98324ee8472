//! Geometry: triangle meshes, point sets, volumes, bounds, adjacency, topology
//! (components, boundary loops, genus) and load-time repair.

pub mod adjacency;
pub mod gather;
pub mod material;
pub mod normals;
pub mod payload;
pub mod repair;
pub mod tangents;
pub mod topology;
pub mod wedges;

use glam::{Vec2, Vec3};

pub use adjacency::Adjacency;
pub use gather::MeshArrays;
pub use material::{
    AlphaMode, Image, Material, Materials, UNTEXTURED_TEXELS, VertexAttributes, declared_size,
};
pub use payload::Payload;
pub use repair::{RepairOptions, RepairReport, Weld};
pub use topology::{ComponentTopology, Topology};
pub use wedges::Wedges;

/// Refuses an index of `what` at or past `len` (a structure read from a
/// file is checked before anything indexes with it).
pub fn check_indices(
    what: &str,
    ids: impl IntoIterator<Item = u32>,
    len: usize,
) -> Result<(), String> {
    match ids.into_iter().find(|&i| i as usize >= len) {
        Some(i) => Err(format!("{what} {i} out of range (only {len})")),
        None => Ok(()),
    }
}

/// Refuses per-item attributes whose count is not `len`.
pub fn check_len<T>(what: &str, items: Option<&Vec<T>>, len: usize) -> Result<(), String> {
    match items {
        Some(v) if v.len() != len => Err(format!("{} {what} for {len} items", v.len())),
        _ => Ok(()),
    }
}

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (min > max); growing it by any point gives that point.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.grow(*p))
    }

    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// The box around this one's eight corners under `m` (empty stays empty).
    pub fn transformed(&self, m: glam::Mat4) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        (0..8).fold(Aabb::EMPTY, |b, k| {
            let pick = |bit: usize, lo: f32, hi: f32| if k >> bit & 1 == 0 { lo } else { hi };
            let corner = Vec3::new(
                pick(0, self.min.x, self.max.x),
                pick(1, self.min.y, self.max.y),
                pick(2, self.min.z, self.max.z),
            );
            b.grow(m.transform_point3(corner))
        })
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// Length of the diagonal; object-space tolerances are fractions of it.
    pub fn diagonal(&self) -> f32 {
        self.extent().length()
    }

    /// Distance from `p` to the box (0 inside): a lower bound for anything inside it.
    pub fn distance(&self, p: Vec3) -> f32 {
        self.distance_squared(p).sqrt()
    }

    /// Its square, for comparisons that need no root.
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        (self.min - p)
            .max(p - self.max)
            .max(Vec3::ZERO)
            .length_squared()
    }
}

/// What a model is: a triangle mesh, a point set or a volume (what a file
/// or a built-in holds).
#[derive(Debug, Clone, PartialEq)]
// One per load, moved rather than copied: boxing the mesh buys nothing.
#[allow(clippy::large_enum_variant)]
pub enum Model {
    Mesh(TriMesh),
    Points(PointSet),
    Volume(Volume),
}

impl Model {
    pub fn kind(&self) -> &'static str {
        match self {
            Model::Mesh(_) => "mesh",
            Model::Points(_) => "points",
            Model::Volume(_) => "volume",
        }
    }

    pub fn bounds(&self) -> Aabb {
        match self {
            Model::Mesh(m) => m.bounds(),
            Model::Points(p) => p.bounds(),
            Model::Volume(v) => v.bounds(),
        }
    }
}

/// A triangle mesh with optional per-vertex attributes and a per-triangle part id
/// (OBJ objects, glTF mesh instances, builtin sub-shapes).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub normals: Option<Vec<Vec3>>,
    /// Linear RGB in 0..=1.
    pub colors: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    /// One id per triangle; `None` means a single part.
    pub parts: Option<Vec<u32>>,
    /// The input's materials, one per part; `None` when it had none.
    pub materials: Option<Materials>,
    /// Each corner's own attributes where welded vertices' corners differ
    /// (UV and normal seams, parts' colours); `None`: the per-vertex ones hold.
    pub wedges: Option<Wedges>,
    /// What the vertices carry for their asset (skin, morph deltas), per
    /// vertex; per wedge in `wedges` where those exist.
    pub payload: Option<Payload>,
}

impl TriMesh {
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
            ..Self::default()
        }
    }

    /// Every index in range and every attribute the size of what it
    /// describes (for a mesh read from a saved file, before any use).
    pub fn check(&self) -> Result<(), String> {
        let (nv, nt) = (self.positions.len(), self.triangles.len());
        check_indices("vertex", self.triangles.iter().flatten().copied(), nv)?;
        check_len("normals", self.normals.as_ref(), nv)?;
        check_len("colours", self.colors.as_ref(), nv)?;
        check_len("UVs", self.uvs.as_ref(), nv)?;
        check_len("parts", self.parts.as_ref(), nt)?;
        if let Some(m) = &self.materials {
            m.check(self.parts.as_deref().unwrap_or(&[0]))?;
        }
        if let Some(w) = &self.wedges {
            w.check(nt, nv)?;
        }
        if let Some(p) = &self.payload {
            p.check("payload", nv)?;
        }
        Ok(())
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }

    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|v| self.positions[v as usize])
    }

    pub fn triangle_area(&self, t: usize) -> f32 {
        let [a, b, c] = self.triangle(t);
        0.5 * (b - a).cross(c - a).length()
    }

    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| self.triangle_area(t) as f64)
            .sum()
    }

    pub fn part(&self, t: usize) -> u32 {
        self.parts.as_ref().map_or(0, |p| p[t])
    }

    /// Area-weighted vertex normals, for shading meshes that came without normals.
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut n = vec![Vec3::ZERO; self.positions.len()];
        for tri in &self.triangles {
            let [a, b, c] = tri.map(|v| self.positions[v as usize]);
            let face = (b - a).cross(c - a);
            for v in tri {
                n[*v as usize] += face;
            }
        }
        n.iter().map(|v| v.normalize_or_zero()).collect()
    }

    /// Number of vertices referenced by at least one triangle.
    pub fn used_vertex_count(&self) -> usize {
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for v in t {
                used[*v as usize] = true;
            }
        }
        used.iter().filter(|u| **u).count()
    }

    /// Appends `other`, offsetting its indices; its parts are renumbered after ours.
    pub fn append(&mut self, other: &TriMesh) {
        self.append_after(other, self.part_count());
    }

    /// Appends `other`, a mesh of our parts and materials (both gathered
    /// from one mesh), keeping its part ids.
    pub fn append_same_parts(&mut self, other: &TriMesh) {
        let materials = self.materials.take().or_else(|| other.materials.clone());
        self.append_after(other, 0);
        self.materials = materials;
    }

    /// `pieces` one after the other, as [`TriMesh::append`] would join them,
    /// in time linear in their size (the part count is kept as it grows, not
    /// recounted per piece).
    pub fn concat(pieces: &[TriMesh]) -> TriMesh {
        let mut out = TriMesh::default();
        let mut parts = 0;
        for piece in pieces {
            out.append_after(piece, parts);
            parts += piece.part_count();
        }
        out
    }

    /// [`TriMesh::append`] with our part count given.
    fn append_after(&mut self, other: &TriMesh, part_base: u32) {
        let base = self.positions.len() as u32;
        let n_self_v = self.positions.len();
        let n_self_t = self.triangles.len();
        if self.wedges.is_some() || other.wedges.is_some() {
            let mut w = self
                .wedges
                .take()
                .unwrap_or_else(|| Wedges::per_vertex(self));
            let theirs = other
                .wedges
                .clone()
                .unwrap_or_else(|| Wedges::per_vertex(other));
            w.append(&theirs, base);
            self.wedges = Some(w);
        }
        merge_attr(
            &mut self.normals,
            n_self_v,
            &other.normals,
            other.positions.len(),
            Vec3::Z,
        );
        merge_attr(
            &mut self.colors,
            n_self_v,
            &other.colors,
            other.positions.len(),
            Vec3::ONE,
        );
        merge_attr(
            &mut self.uvs,
            n_self_v,
            &other.uvs,
            other.positions.len(),
            Vec2::ZERO,
        );
        self.payload = match (&self.payload, &other.payload) {
            (Some(a), Some(b)) => a.joined(b),
            (None, Some(b)) if n_self_v == 0 => Some(b.clone()),
            _ => None,
        };
        if self.materials.is_some() || other.materials.is_some() {
            let mut m = self.materials.take().unwrap_or_else(|| {
                let mut m = Materials::default();
                m.append(0, None, part_base);
                m
            });
            m.append(part_base, other.materials.as_ref(), other.part_count());
            self.materials = Some(m);
        }
        if self.parts.is_some() || other.parts.is_some() || n_self_t > 0 {
            let parts = self.parts.get_or_insert_with(|| vec![0; n_self_t]);
            parts.extend((0..other.triangles.len()).map(|t| part_base + other.part(t)));
        }
        self.positions.extend_from_slice(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|v| v + base)));
    }

    /// The triangles `keep` (in that order) with only the vertices and
    /// wedges they use, and their attributes; a single part, no materials.
    pub fn subset(&self, keep: &[u32]) -> TriMesh {
        TriMesh {
            parts: None,
            materials: None,
            ..self.arrays().gather(keep.iter().copied())
        }
    }

    /// Number of distinct part ids (max + 1).
    pub fn part_count(&self) -> u32 {
        match &self.parts {
            Some(p) => p.iter().copied().max().map_or(0, |m| m + 1),
            None => u32::from(!self.triangles.is_empty()),
        }
    }
}

/// Keeps an optional attribute array aligned with the positions when appending.
fn merge_attr<T: Copy>(
    mine: &mut Option<Vec<T>>,
    n_mine: usize,
    theirs: &Option<Vec<T>>,
    n_theirs: usize,
    fill: T,
) {
    if mine.is_none() && theirs.is_none() {
        return;
    }
    let m = mine.get_or_insert_with(|| vec![fill; n_mine]);
    match theirs {
        Some(t) => m.extend_from_slice(t),
        None => m.extend(std::iter::repeat_n(fill, n_theirs)),
    }
}

/// A point set with optional per-point attributes.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointSet {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    /// Linear RGB in 0..=1.
    pub colors: Option<Vec<Vec3>>,
    pub radii: Option<Vec<f32>>,
}

impl PointSet {
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
}

/// A scalar volume on a regular grid, x fastest, then y, then z.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Volume {
    pub dims: [usize; 3],
    /// Voxel size along x, y, z (may be anisotropic).
    pub spacing: Vec3,
    pub origin: Vec3,
    pub data: Vec<f32>,
}

impl Volume {
    pub fn value(&self, x: usize, y: usize, z: usize) -> f32 {
        self.data[x + self.dims[0] * (y + self.dims[1] * z)]
    }

    /// Physical bounds of the sample points.
    pub fn bounds(&self) -> Aabb {
        let ext = Vec3::new(
            self.dims[0].saturating_sub(1) as f32,
            self.dims[1].saturating_sub(1) as f32,
            self.dims[2].saturating_sub(1) as f32,
        ) * self.spacing;
        Aabb {
            min: self.origin,
            max: self.origin + ext,
        }
    }

    /// (min, max) of the finite samples.
    pub fn value_range(&self) -> (f32, f32) {
        self.data
            .iter()
            .filter(|v| v.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(*v), hi.max(*v))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A subset keeps only the wedges its corners use, naming its own
    /// vertices (it kept every wedge, those of vertices left out naming
    /// u32::MAX, and joining two subsets overflowed).
    #[test]
    fn a_subset_keeps_the_wedges_it_uses() {
        let mut mesh = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::ONE, Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        mesh.wedges = Some(Wedges {
            corners: vec![[0, 1, 2], [3, 4, 5]],
            vertex: vec![0, 1, 2, 0, 2, 3],
            normals: None,
            colors: None,
            uvs: Some((0..6).map(|i| Vec2::splat(i as f32)).collect()),
            payload: None,
        });
        let second = mesh.subset(&[1]);
        second.check().unwrap();
        let w = second.wedges.as_ref().unwrap();
        assert_eq!(w.corners, vec![[0, 1, 2]]);
        assert_eq!(w.vertex, vec![0, 1, 2]);
        assert_eq!(w.uvs.as_ref().unwrap()[0], Vec2::splat(3.0));
        let both = TriMesh::concat(&[mesh.subset(&[0]), second]);
        both.check().unwrap();
        assert_eq!(both.unwelded().uvs, mesh.unwelded().uvs);
    }
}
