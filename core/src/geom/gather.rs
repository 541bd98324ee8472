//! A subset of a mesh's triangles as a mesh of its own: what an edge
//! collapser's working mesh (every vertex and triangle it ever made) and a
//! progressive mesh's prefixes (`simplify::progressive`) show. Written once
//! so both give the same mesh, vertex for vertex.

use glam::{Vec2, Vec3};

use super::{Materials, Payload, TriMesh, Wedges};

/// A mesh's arrays, borrowed. `parts` and wedge corners have one entry per
/// triangle of `triangles`.
#[derive(Clone, Copy)]
pub struct MeshArrays<'a> {
    pub positions: &'a [Vec3],
    pub triangles: &'a [[u32; 3]],
    pub normals: Option<&'a [Vec3]>,
    pub colors: Option<&'a [Vec3]>,
    pub uvs: Option<&'a [Vec2]>,
    pub parts: Option<&'a [u32]>,
    pub materials: Option<&'a Materials>,
    pub wedges: Option<&'a Wedges>,
    pub payload: Option<&'a Payload>,
}

impl TriMesh {
    pub fn arrays(&self) -> MeshArrays<'_> {
        MeshArrays {
            positions: &self.positions,
            triangles: &self.triangles,
            normals: self.normals.as_deref(),
            colors: self.colors.as_deref(),
            uvs: self.uvs.as_deref(),
            parts: self.parts.as_deref(),
            materials: self.materials.as_ref(),
            wedges: self.wedges.as_ref(),
            payload: self.payload.as_ref(),
        }
    }
}

impl MeshArrays<'_> {
    /// The triangles `ids` in that order, with the vertices (and wedges) they
    /// use numbered in order of first use; parts only where one is not 0.
    pub fn gather(&self, ids: impl IntoIterator<Item = u32>) -> TriMesh {
        let ids = ids.into_iter();
        let mut remap = Remap::for_subset(ids.size_hint().0, self.positions.len());
        let mut out = TriMesh::default();
        let mut kept = Vec::new();
        let mut order = Vec::new();
        for t in ids {
            let tri = self.triangles[t as usize].map(|v| {
                let slot = remap.slot(v);
                if *slot == u32::MAX {
                    *slot = order.len() as u32;
                    order.push(v);
                }
                *slot
            });
            out.triangles.push(tri);
            kept.push(t);
        }
        out.positions = pick(self.positions, &order);
        out.normals = self.normals.map(|a| pick(a, &order));
        out.colors = self.colors.map(|a| pick(a, &order));
        out.uvs = self.uvs.map(|a| pick(a, &order));
        out.payload = self
            .payload
            .map(|p| p.pick(order.iter().map(|&v| v as usize)));
        if let Some(p) = self.parts {
            let parts: Vec<u32> = kept.iter().map(|t| p[*t as usize]).collect();
            if parts.iter().any(|p| *p != 0) {
                out.parts = Some(parts);
            }
        }
        out.materials = self.materials.cloned();
        out.wedges = self.wedges.map(|w| {
            let mut wremap = vec![u32::MAX; w.len()];
            let mut worder = Vec::new();
            let corners = kept
                .iter()
                .map(|&t| {
                    w.corners[t as usize].map(|x| {
                        let slot = &mut wremap[x as usize];
                        if *slot == u32::MAX {
                            *slot = worder.len() as u32;
                            worder.push(x);
                        }
                        *slot
                    })
                })
                .collect();
            Wedges::gathered(w, &worder, corners, |v| remap.get(v))
        });
        out
    }
}

/// Old vertex index to new: an array over every vertex, or a map where the
/// subset is small beside the mesh (a tile of a scan of 10⁸ triangles must
/// not clear 200 MB to gather its 64k).
enum Remap {
    Dense(Vec<u32>),
    Sparse(std::collections::HashMap<u32, u32>),
}

impl Remap {
    fn for_subset(triangles: usize, vertices: usize) -> Remap {
        if triangles.saturating_mul(16) < vertices {
            Remap::Sparse(std::collections::HashMap::with_capacity(triangles * 3))
        } else {
            Remap::Dense(vec![u32::MAX; vertices])
        }
    }

    /// Vertex `v`'s new index (`u32::MAX`: not in the subset).
    fn get(&self, v: u32) -> u32 {
        match self {
            Remap::Dense(r) => r[v as usize],
            Remap::Sparse(m) => m.get(&v).copied().unwrap_or(u32::MAX),
        }
    }

    /// Vertex `v`'s new index, `u32::MAX` until set.
    fn slot(&mut self, v: u32) -> &mut u32 {
        match self {
            Remap::Dense(r) => &mut r[v as usize],
            Remap::Sparse(m) => m.entry(v).or_insert(u32::MAX),
        }
    }
}

/// `items` at `order`.
fn pick<T: Copy>(items: &[T], order: &[u32]) -> Vec<T> {
    order.iter().map(|i| items[*i as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gathering_renumbers_in_order_of_first_use() {
        let mut mesh = TriMesh::new(
            (0..5).map(|i| Vec3::splat(i as f32)).collect(),
            vec![[0, 1, 2], [2, 3, 4], [4, 1, 0]],
        );
        mesh.parts = Some(vec![0, 3, 0]);
        let sub = mesh.arrays().gather([1, 2]);
        assert_eq!(sub.triangles, vec![[0, 1, 2], [2, 3, 4]]);
        let want: Vec<Vec3> = [2.0, 3.0, 4.0, 1.0, 0.0].map(Vec3::splat).to_vec();
        assert_eq!(sub.positions, want);
        assert_eq!(sub.parts, Some(vec![3, 0]));
        assert_eq!(mesh.arrays().gather([2]).parts, None, "part 0 only");
        assert_eq!(mesh.arrays().gather(0..3), mesh, "all of it, as it was");
    }
}
