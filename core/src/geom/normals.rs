//! Vertex normals that agree with the winding. A normal carried through
//! simplification (interpolated, or taken from a welded neighbour) can end up
//! pointing away from a face it shades, which a real-time client lights from
//! behind; exports make every corner's normal face its triangle's front.

use glam::Vec3;

use super::TriMesh;

impl TriMesh {
    /// Gives every corner a normal on its triangle's front side (a positive dot
    /// product with the face normal), changing as little as it can: a vertex
    /// whose normal is against one of its faces takes the area-weighted normal
    /// of all its faces; a corner still against its face (a fan folded past
    /// 180°) gets a vertex of its own with the face's normal. A mesh without
    /// normals gets area-weighted ones first. Returns the corners changed.
    /// Meant for vertex-attribute meshes ([`TriMesh::unwelded`]).
    pub fn orient_normals_to_winding(&mut self) -> usize {
        let mut normals = self.normals.take().unwrap_or_else(|| self.vertex_normals());
        let face: Vec<Vec3> = (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                (b - a).cross(c - a)
            })
            .collect();
        let against = |n: Vec3, f: Vec3| f != Vec3::ZERO && n.dot(f) <= 0.0;
        let mut sum = vec![Vec3::ZERO; self.positions.len()];
        let mut bad = vec![false; self.positions.len()];
        for (tri, f) in self.triangles.iter().zip(&face) {
            for &v in tri {
                sum[v as usize] += *f;
                bad[v as usize] |= against(normals[v as usize], *f);
            }
        }
        let mut changed = 0;
        for (v, n) in normals.iter_mut().enumerate() {
            if bad[v] {
                *n = sum[v].try_normalize().unwrap_or(*n);
            }
        }
        for (tri, f) in self.triangles.iter_mut().zip(&face) {
            for corner in tri.iter_mut() {
                let v = *corner as usize;
                changed += usize::from(bad[v]);
                if !against(normals[v], *f) {
                    continue;
                }
                let own = self.positions.len() as u32;
                self.positions.push(self.positions[v]);
                normals.push(f.normalize());
                if let Some(c) = &mut self.colors {
                    c.push(c[v]);
                }
                if let Some(u) = &mut self.uvs {
                    u.push(u[v]);
                }
                if let Some(p) = &mut self.payload {
                    p.push_copy(v);
                }
                *corner = own;
            }
        }
        self.normals = Some(normals);
        changed
    }

    /// Area of the triangles with a corner whose normal points against the
    /// face (behind it), as a fraction of the total area; 0 without normals.
    pub fn area_with_normals_against_winding(&self) -> f64 {
        let Some(normals) = &self.normals else {
            return 0.0;
        };
        let (mut bad, mut total) = (0.0, 0.0);
        for (t, tri) in self.triangles.iter().enumerate() {
            let [a, b, c] = self.triangle(t);
            let f = (b - a).cross(c - a);
            let area = 0.5 * f.length() as f64;
            total += area;
            if tri.iter().any(|v| normals[*v as usize].dot(f) < 0.0) {
                bad += area;
            }
        }
        if total > 0.0 { bad / total } else { 0.0 }
    }
}

/// A mesh's shading normals as a renderer interpolates them: per corner,
/// its wedge's (or vertex's) normal, area-weighted vertex normals where it
/// has none (what bakes and impostors transfer).
pub struct ShadingNormals<'a> {
    mesh: &'a TriMesh,
    normals: std::borrow::Cow<'a, [Vec3]>,
}

impl<'a> ShadingNormals<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let normals = match (&mesh.wedges, &mesh.normals) {
            (Some(w), _) if w.normals.is_some() => w.normals.as_deref().unwrap_or_default().into(),
            (None, Some(n)) => n.as_slice().into(),
            _ => mesh.vertex_normals().into(),
        };
        ShadingNormals { mesh, normals }
    }

    /// The unit normal interpolated over triangle `t` at barycentric `b`.
    pub fn at(&self, t: usize, b: [f32; 3]) -> Vec3 {
        let c = match &self.mesh.wedges {
            Some(w) if w.normals.is_some() => w.corners[t],
            _ => self.mesh.triangles[t],
        };
        let n: Vec3 = (0..3).map(|k| self.normals[c[k] as usize] * b[k]).sum();
        n.try_normalize().unwrap_or_else(|| {
            let [a, bb, cc] = self.mesh.triangle(t);
            (bb - a).cross(cc - a).normalize_or(Vec3::Z)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_against_their_faces_are_turned_and_folds_split() {
        // A flat square of two triangles facing +z whose normals point down.
        let mut m = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        m.normals = Some(vec![Vec3::NEG_Z; 4]);
        assert_eq!(m.area_with_normals_against_winding(), 1.0);
        assert_eq!(m.orient_normals_to_winding(), 6);
        assert_eq!(m.area_with_normals_against_winding(), 0.0);
        assert!(m.normals.as_ref().unwrap().iter().all(|n| *n == Vec3::Z));
        assert_eq!(m.positions.len(), 4, "no corner needed its own vertex");

        // Two triangles folded onto each other around a shared edge: no single
        // normal at the edge's vertices faces both, so those corners split.
        let mut fold = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.0, 1.0, 1e-3)],
            vec![[0, 1, 2], [1, 0, 3]],
        );
        fold.normals = Some(vec![Vec3::Z; 4]);
        fold.orient_normals_to_winding();
        assert_eq!(fold.area_with_normals_against_winding(), 0.0);
        assert!(fold.positions.len() > 4);
        // A mesh that agrees is left as it is.
        let mut good = m.clone();
        assert_eq!(good.orient_normals_to_winding(), 0);
        assert_eq!(good, m);
    }
}
