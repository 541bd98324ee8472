//! Wedges (Hoppe, "Efficient implementation of progressive meshes", 1998, §3):
//! the attribute sets of a welded vertex's corners where they differ — the
//! two sides of a UV seam, a crease's two normals, two parts' own colours.
//! Welding joins the surface for topology and the certificate; wedges keep
//! every face's own side of each seam, so LODs and exports never take a UV
//! or a normal from across one.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::TriMesh;

/// Per-corner attribute sets of a welded mesh. The mesh's own per-vertex
/// attributes stay one representative per vertex (for methods that shade
/// by vertex); these are what exports write.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Wedges {
    /// Per triangle, the wedge of each corner.
    pub corners: Vec<[u32; 3]>,
    /// Per wedge, its vertex.
    pub vertex: Vec<u32>,
    pub normals: Option<Vec<Vec3>>,
    pub colors: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    /// Per wedge, what it carries for the asset ([`super::Payload`]).
    pub payload: Option<super::Payload>,
}

/// A wedge's attributes as bits, for finding equal ones.
type Key = (u32, [u32; 3], [u32; 3], [u32; 2], Vec<u32>);

fn bits<const N: usize>(v: [f32; N]) -> [u32; N] {
    // +0.0 and -0.0 are the same value.
    v.map(|x| (x + 0.0).to_bits())
}

impl Wedges {
    /// Index ranges and sizes against a mesh of `triangles` on `vertices`
    /// vertices (for wedges read from a saved file).
    pub fn check(&self, triangles: usize, vertices: usize) -> Result<(), String> {
        if self.corners.len() != triangles {
            return Err(format!(
                "{} wedge corners for {triangles} triangles",
                self.corners.len()
            ));
        }
        let n = self.vertex.len();
        super::check_indices("wedge", self.corners.iter().flatten().copied(), n)?;
        super::check_indices("wedge vertex", self.vertex.iter().copied(), vertices)?;
        super::check_len("wedge normals", self.normals.as_ref(), n)?;
        super::check_len("wedge colours", self.colors.as_ref(), n)?;
        super::check_len("wedge UVs", self.uvs.as_ref(), n)?;
        match &self.payload {
            Some(p) => p.check("wedge payload", n),
            None => Ok(()),
        }
    }

    /// The wedges of `records` (one attribute set per vertex record, as read)
    /// once records are welded by `remap` (record → vertex): equal attribute
    /// sets of one vertex share a wedge. `None` when every vertex keeps a
    /// single set (nothing welded across a seam).
    pub fn of_welded(records: &TriMesh, remap: &[u32]) -> Option<Wedges> {
        if records.normals.is_none()
            && records.colors.is_none()
            && records.uvs.is_none()
            && records.payload.is_none()
        {
            return None;
        }
        let key = |i: usize| -> Key {
            (
                remap[i],
                bits(
                    records
                        .normals
                        .as_ref()
                        .map_or([0.0; 3], |n| n[i].to_array()),
                ),
                bits(
                    records
                        .colors
                        .as_ref()
                        .map_or([0.0; 3], |c| c[i].to_array()),
                ),
                bits(records.uvs.as_ref().map_or([0.0; 2], |u| u[i].to_array())),
                records.payload.as_ref().map_or(Vec::new(), |p| p.bits(i)),
            )
        };
        let mut ids: HashMap<Key, u32> = HashMap::new();
        let mut first = Vec::new();
        let mut wedge_of = vec![u32::MAX; records.positions.len()];
        let corners: Vec<[u32; 3]> = records
            .triangles
            .iter()
            .map(|t| {
                t.map(|r| {
                    let r = r as usize;
                    if wedge_of[r] == u32::MAX {
                        wedge_of[r] = *ids.entry(key(r)).or_insert_with(|| {
                            first.push(r);
                            first.len() as u32 - 1
                        });
                    }
                    wedge_of[r]
                })
            })
            .collect();
        let mut vertices: Vec<u32> = first.iter().map(|r| remap[*r]).collect();
        vertices.sort_unstable();
        vertices.dedup();
        if vertices.len() == first.len() {
            return None;
        }
        let gather = |a: &[_]| first.iter().map(|&r| a[r]).collect::<Vec<_>>();
        Some(Wedges {
            corners,
            vertex: first.iter().map(|r| remap[*r]).collect(),
            normals: records.normals.as_deref().map(gather),
            colors: records.colors.as_deref().map(gather),
            uvs: records
                .uvs
                .as_ref()
                .map(|u| first.iter().map(|&r| u[r]).collect()),
            payload: records
                .payload
                .as_ref()
                .map(|p| p.pick(first.iter().copied())),
        })
    }

    /// One wedge per vertex, holding its attributes (a mesh without seams).
    pub fn per_vertex(mesh: &TriMesh) -> Wedges {
        Wedges {
            corners: mesh.triangles.clone(),
            vertex: (0..mesh.positions.len() as u32).collect(),
            normals: mesh.normals.clone(),
            colors: mesh.colors.clone(),
            uvs: mesh.uvs.clone(),
            payload: mesh.payload.clone(),
        }
    }

    pub fn len(&self) -> usize {
        self.vertex.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vertex.is_empty()
    }

    /// Appends a wedge at `vertex` with the attributes of `from` interpolated
    /// towards `to` by `s` (normals renormalised); returns its id.
    pub fn push_lerp(&mut self, vertex: u32, from: u32, to: u32, s: f32) -> u32 {
        // The ends exactly: a wedge that stays where it was keeps its bits.
        let (f, t, s) = match s {
            0.0 => (from as usize, from as usize, 0.0),
            1.0 => (to as usize, to as usize, 0.0),
            _ => (from as usize, to as usize, s),
        };
        if let Some(n) = &mut self.normals {
            let v = n[f].lerp(n[t], s).normalize_or(n[f]);
            n.push(v);
        }
        if let Some(c) = &mut self.colors {
            c.push(c[f].lerp(c[t], s));
        }
        if let Some(u) = &mut self.uvs {
            u.push(u[f].lerp(u[t], s));
        }
        if let Some(p) = &mut self.payload {
            p.push_lerp(f, t, s);
        }
        self.vertex.push(vertex);
        self.vertex.len() as u32 - 1
    }

    /// Drops the last wedge (one just pushed that turned out to be a copy).
    pub fn pop(&mut self) {
        self.vertex.pop();
        for a in [&mut self.normals, &mut self.colors].into_iter().flatten() {
            a.pop();
        }
        if let Some(u) = &mut self.uvs {
            u.pop();
        }
        if let Some(p) = &mut self.payload {
            p.pop();
        }
    }

    /// The wedges `order` of `w` (in that order) with `corners` indexing
    /// them and their vertices renumbered by `vertex`.
    pub fn gathered(
        w: &Wedges,
        order: &[u32],
        corners: Vec<[u32; 3]>,
        vertex: impl Fn(u32) -> u32,
    ) -> Wedges {
        let gather = |a: &[Vec3]| order.iter().map(|&x| a[x as usize]).collect::<Vec<_>>();
        Wedges {
            corners,
            vertex: order
                .iter()
                .map(|&x| vertex(w.vertex[x as usize]))
                .collect(),
            normals: w.normals.as_deref().map(gather),
            colors: w.colors.as_deref().map(gather),
            uvs: w
                .uvs
                .as_ref()
                .map(|u| order.iter().map(|&x| u[x as usize]).collect()),
            payload: w
                .payload
                .as_ref()
                .map(|p| p.pick(order.iter().map(|&x| x as usize))),
        }
    }

    /// Whether wedges `a` and `b` show the same surface: equal UVs,
    /// colours and hard payload (skin weights, target deltas). Only those
    /// seams constrain collapses: a texture or colour taken from across one
    /// is plainly wrong, while a normal is carried softly (interpolated, or
    /// kept, then oriented on export), so a faceted model, whose every edge
    /// is a normal seam, still simplifies.
    pub fn same_surface(&self, a: u32, b: u32) -> bool {
        a == b
            || self.same_but_uv(a, b)
                && self
                    .uvs
                    .as_ref()
                    .is_none_or(|u| u[a as usize] == u[b as usize])
    }

    /// [`Wedges::same_surface`] but for their UVs: a UV seam, the only one
    /// a collapse may cross (within a tolerance, `simplify::collapse`).
    pub fn same_but_uv(&self, a: u32, b: u32) -> bool {
        let (a, b) = (a as usize, b as usize);
        a == b
            || self.colors.as_ref().is_none_or(|c| c[a] == c[b])
                && self.payload.as_ref().is_none_or(|p| p.same_hard(a, b))
    }

    /// Whether wedges `a` and `b` hold the same attributes.
    pub fn same_attributes(&self, a: u32, b: u32) -> bool {
        let (a, b) = (a as usize, b as usize);
        self.normals.as_ref().is_none_or(|n| n[a] == n[b])
            && self.colors.as_ref().is_none_or(|c| c[a] == c[b])
            && self.uvs.as_ref().is_none_or(|u| u[a] == u[b])
            && self.payload.as_ref().is_none_or(|p| p.same(a, b))
    }

    /// Appends `other` (its vertices offset by `vertex_base`); an attribute
    /// only one side has is filled with `fill`'s for the other.
    pub fn append(&mut self, other: &Wedges, vertex_base: u32) {
        let base = self.len() as u32;
        let (n_self, n_other) = (self.len(), other.len());
        super::merge_attr(&mut self.normals, n_self, &other.normals, n_other, Vec3::Z);
        super::merge_attr(&mut self.colors, n_self, &other.colors, n_other, Vec3::ONE);
        super::merge_attr(&mut self.uvs, n_self, &other.uvs, n_other, Vec2::ZERO);
        self.payload = match (&self.payload, &other.payload) {
            (Some(a), Some(b)) => a.joined(b),
            (None, Some(b)) if n_self == 0 => Some(b.clone()),
            _ => None,
        };
        self.vertex
            .extend(other.vertex.iter().map(|v| v + vertex_base));
        self.corners
            .extend(other.corners.iter().map(|c| c.map(|w| w + base)));
    }
}

/// Which wedge of a vertex a face takes when the face stands for an input
/// triangle that did not have that vertex (a merge moved one of its corners
/// onto it, merge-tree paper §4): the vertex's wedge in the input triangle's
/// chart (triangles joined across edges without a UV or colour seam), the one
/// nearest in UV where a chart meets itself along a seam.
pub struct WedgeSides {
    chart: Vec<u32>,
    /// Per vertex, its wedges with their charts.
    of_vertex: Vec<Vec<(u32, u32)>>,
}

impl WedgeSides {
    pub fn new(mesh: &TriMesh) -> Option<WedgeSides> {
        let w = mesh.wedges.as_ref()?;
        let adj = super::Adjacency::new(&mesh.triangles);
        let mut uf = super::topology::UnionFind::new(mesh.triangles.len());
        for (c, &o) in adj.opposite.iter().enumerate() {
            if o == super::adjacency::NONE {
                continue;
            }
            let (t, u) = (c / 3, o as usize / 3);
            let tri = mesh.triangles[t];
            let same = [tri[(c + 1) % 3], tri[(c + 2) % 3]].iter().all(|&v| {
                let k = mesh.triangles[u].iter().position(|x| *x == v);
                let j = tri.iter().position(|x| *x == v).unwrap_or(0);
                k.is_some_and(|k| w.same_surface(w.corners[t][j], w.corners[u][k]))
            });
            if same {
                uf.union(t as u32, u as u32);
            }
        }
        let chart: Vec<u32> = (0..mesh.triangles.len() as u32)
            .map(|t| uf.find(t))
            .collect();
        let mut of_vertex = vec![Vec::new(); mesh.positions.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let entry = (w.corners[t][k], chart[t]);
                let list: &mut Vec<(u32, u32)> = &mut of_vertex[tri[k] as usize];
                if !list.contains(&entry) {
                    list.push(entry);
                }
            }
        }
        Some(WedgeSides { chart, of_vertex })
    }

    /// The wedge of vertex `v` for a face standing for input triangle `t`.
    pub fn wedge(&self, mesh: &TriMesh, t: usize, v: u32) -> u32 {
        let w = mesh.wedges.as_ref().expect("WedgeSides::new had wedges");
        if let Some(k) = mesh.triangles[t].iter().position(|x| *x == v) {
            return w.corners[t][k];
        }
        let list = &self.of_vertex[v as usize];
        let centre = w
            .uvs
            .as_ref()
            .map(|u| w.corners[t].iter().map(|c| u[*c as usize]).sum::<Vec2>() / 3.0);
        let far = |x: u32| match (centre, &w.uvs) {
            (Some(c), Some(u)) => u[x as usize].distance_squared(c),
            _ => 0.0,
        };
        let in_chart = list.iter().filter(|(_, c)| *c == self.chart[t]);
        let pick = |it: &mut dyn Iterator<Item = &(u32, u32)>| {
            it.map(|(x, _)| *x)
                .min_by(|a, b| far(*a).total_cmp(&far(*b)))
        };
        pick(&mut in_chart.clone())
            .or_else(|| pick(&mut list.iter()))
            .unwrap_or(w.corners[t][0])
    }
}

impl TriMesh {
    /// The corner wedges of triangle `t` (its vertices when the mesh has no wedges).
    pub fn corner_wedges(&self, t: usize) -> [u32; 3] {
        match &self.wedges {
            Some(w) => w.corners[t],
            None => self.triangles[t],
        }
    }

    /// The mesh with one vertex per wedge its triangles use (positions
    /// repeated along seams), as vertex-attribute formats (glTF, PLY) store
    /// it: every corner gets its own side's attributes. Parts and materials
    /// are kept; a mesh without wedges comes back as it is.
    pub fn unwelded(&self) -> TriMesh {
        let Some(w) = &self.wedges else {
            return self.clone();
        };
        let mut remap = vec![u32::MAX; w.len()];
        let mut order = Vec::new();
        let triangles = w
            .corners
            .iter()
            .map(|c| {
                c.map(|x| {
                    let slot = &mut remap[x as usize];
                    if *slot == u32::MAX {
                        *slot = order.len() as u32;
                        order.push(x as usize);
                    }
                    *slot
                })
            })
            .collect();
        let gather = |a: &[_]| order.iter().map(|&x| a[x]).collect::<Vec<_>>();
        TriMesh {
            positions: order
                .iter()
                .map(|&x| self.positions[w.vertex[x] as usize])
                .collect(),
            triangles,
            normals: w.normals.as_deref().map(gather),
            colors: w.colors.as_deref().map(gather),
            uvs: w
                .uvs
                .as_ref()
                .map(|u| order.iter().map(|&x| u[x]).collect()),
            parts: self.parts.clone(),
            materials: self.materials.clone(),
            wedges: None,
            payload: w.payload.as_ref().map(|p| p.pick(order.iter().copied())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{RepairOptions, repair::repair_mesh};

    /// A unit square of two triangles whose diagonal is a UV seam: the two
    /// records of each diagonal vertex share a position but not a UV.
    pub(crate) fn square_with_uv_seam() -> TriMesh {
        let mut m = TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::ZERO,
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::Y,
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        );
        m.uvs = Some(vec![
            Vec2::ZERO,
            Vec2::X,
            Vec2::ONE,
            Vec2::new(0.5, 0.0),
            Vec2::new(0.5, 0.5),
            Vec2::new(0.0, 0.5),
        ]);
        m
    }

    /// A payload that differs across the diagonal (a morph target that
    /// opens the square like lips) makes a seam as UVs do: both sides keep
    /// their own floats through welding, and unwelding gives them back.
    #[test]
    fn a_payload_seam_keeps_both_sides() {
        let mut records = square_with_uv_seam();
        records.uvs = None;
        let mut payload = crate::geom::Payload::new(1, 1, 0);
        payload.values = vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        records.payload = Some(payload);
        let (m, _) = repair_mesh(records.clone(), &RepairOptions::default());
        assert_eq!(m.positions.len(), 4);
        let w = m.wedges.as_ref().expect("the payload seam needs wedges");
        assert_eq!(w.len(), 6);
        assert!(!w.same_surface(w.corners[0][0], w.corners[1][0]));
        let back = m.unwelded();
        let (read, written) = (records.payload.unwrap(), back.payload.unwrap());
        for t in 0..2 {
            for k in 0..3 {
                let r = records.triangles[t][k] as usize;
                let b = back.triangles[t][k] as usize;
                assert_eq!(read.get(r), written.get(b), "triangle {t} corner {k}");
            }
        }
    }

    #[test]
    fn welding_keeps_each_side_of_a_seam_and_unwelding_restores_it() {
        let records = square_with_uv_seam();
        let (m, _) = repair_mesh(records.clone(), &RepairOptions::default());
        assert_eq!(m.positions.len(), 4, "the diagonal's vertices are welded");
        let w = m.wedges.as_ref().expect("the seam needs wedges");
        assert_eq!(w.len(), 6);
        let back = m.unwelded();
        // Every corner has the UV it was read with.
        for t in 0..2 {
            for k in 0..3 {
                let read = records.uvs.as_ref().unwrap()[records.triangles[t][k] as usize];
                let written = back.uvs.as_ref().unwrap()[back.triangles[t][k] as usize];
                assert_eq!(read, written, "triangle {t} corner {k}");
                assert_eq!(
                    records.positions[records.triangles[t][k] as usize],
                    back.positions[back.triangles[t][k] as usize]
                );
            }
        }
        // Without a seam, no wedges.
        let mut plain = records;
        plain.uvs = Some(plain.positions.iter().map(|p| p.truncate()).collect());
        let (m, _) = repair_mesh(plain, &RepairOptions::default());
        assert!(m.wedges.is_none());
    }
}
