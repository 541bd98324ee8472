//! Tangent frames for normal maps. glTF 2.0 (§3.7.2.1) says a client that
//! finds no `TANGENT` computes MikkTSpace tangents (Mikkelsen, "Simulation
//! of wrinkled surfaces revisited", 2008) from the written positions,
//! normals and UVs; a normal map baked in that same frame therefore shades
//! alike in every client, with the tangents written or not. Bakes, exports
//! and the studio's renderer all take their frames from here.

use bevy_mikktspace::{Geometry, TangentSpace, generate_tangents};
use glam::{Vec3, Vec4};

use super::TriMesh;

/// A vertex-attribute mesh as MikkTSpace reads it, with a tangent per corner.
struct Corners<'a> {
    mesh: &'a TriMesh,
    normals: &'a [Vec3],
    tangents: Vec<Vec4>,
}

impl Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.mesh.triangles[face][vert] as usize].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.mesh.triangles[face][vert] as usize].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uvs = self.mesh.uvs.as_deref().unwrap_or_default();
        uvs[self.mesh.triangles[face][vert] as usize].to_array()
    }
    fn set_tangent(&mut self, space: Option<TangentSpace>, face: usize, vert: usize) {
        let t = space.unwrap_or_default().tangent_encoded();
        self.tangents[3 * face + vert] = Vec4::from_array(t);
    }
}

impl TriMesh {
    /// The mesh with a MikkTSpace tangent (xyz, and the bitangent's sign in
    /// w) per vertex, vertices split where their corners' tangents differ
    /// (a UV mirror, a chart's fold); `None` without UVs. Meant for
    /// vertex-attribute meshes ([`TriMesh::unwelded`]); one without normals
    /// gets area-weighted ones.
    pub fn with_tangents(&self) -> Option<(TriMesh, Vec<Vec4>)> {
        self.uvs.as_ref()?;
        let mut mesh = self.clone();
        let normals = mesh.normals.take().unwrap_or_else(|| self.vertex_normals());
        let mut corners = Corners {
            mesh: self,
            normals: &normals,
            tangents: vec![Vec4::new(1.0, 0.0, 0.0, 1.0); 3 * self.triangles.len()],
        };
        // No error variant exists: degenerate faces borrow a neighbour's frame.
        let _ = generate_tangents(&mut corners);
        let corner_tangents = corners.tangents;
        mesh.normals = Some(normals);
        let mut tangents: Vec<Option<Vec4>> = vec![None; mesh.positions.len()];
        for (t, tri) in mesh.triangles.iter_mut().enumerate() {
            for (k, v) in tri.iter_mut().enumerate() {
                let want = corner_tangents[3 * t + k];
                match tangents[*v as usize] {
                    None => tangents[*v as usize] = Some(want),
                    Some(have) if have == want => {}
                    Some(_) => {
                        let i = *v as usize;
                        let own = mesh.positions.len() as u32;
                        mesh.positions.push(mesh.positions[i]);
                        for a in [&mut mesh.normals, &mut mesh.colors].into_iter().flatten() {
                            a.push(a[i]);
                        }
                        if let Some(u) = &mut mesh.uvs {
                            u.push(u[i]);
                        }
                        if let Some(p) = &mut mesh.payload {
                            p.push_copy(i);
                        }
                        tangents.push(Some(want));
                        *v = own;
                    }
                }
            }
        }
        let tangents = tangents
            .into_iter()
            .map(|t| t.unwrap_or(Vec4::new(1.0, 0.0, 0.0, 1.0)))
            .collect();
        Some((mesh, tangents))
    }
}

/// The tangent frame a fragment shader rebuilds at a point of a triangle
/// from its corners' (normal, MikkTSpace tangent): interpolated, the
/// tangent made orthogonal to the normal, the bitangent `w · N × T`. A
/// normal map's texel is a direction in this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TangentFrame {
    pub tangent: Vec3,
    pub bitangent: Vec3,
    pub normal: Vec3,
}

impl TangentFrame {
    /// The frame at barycentric `b` of a triangle whose corners have
    /// `corners`; `None` where the normals cancel.
    pub fn at(corners: [(Vec3, Vec4); 3], b: [f32; 3]) -> Option<TangentFrame> {
        let normal: Vec3 = (0..3).map(|k| corners[k].0 * b[k]).sum();
        let tangent: Vec3 = (0..3).map(|k| corners[k].1.truncate() * b[k]).sum();
        let normal = normal.try_normalize()?;
        let tangent = (tangent - normal * normal.dot(tangent))
            .try_normalize()
            .unwrap_or_else(|| normal.any_orthonormal_vector());
        let bitangent = normal.cross(tangent) * corners[0].1.w.signum();
        Some(TangentFrame {
            tangent,
            bitangent,
            normal,
        })
    }

    /// World direction `n` in this frame.
    pub fn local(&self, n: Vec3) -> Vec3 {
        Vec3::new(
            n.dot(self.tangent),
            n.dot(self.bitangent),
            n.dot(self.normal),
        )
    }

    /// Direction `m` of this frame in the world.
    pub fn world(&self, m: Vec3) -> Vec3 {
        self.tangent * m.x + self.bitangent * m.y + self.normal * m.z
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::*;

    /// A flat square whose UVs run along x and y has the tangent +x and a
    /// right-handed frame; UVs folded over on one triangle split the
    /// vertices the two halves share and flip that half's sign.
    #[test]
    fn tangents_follow_the_uvs_and_mirrors_split_vertices() {
        let square = || {
            let mut m = TriMesh::new(
                vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
                vec![[0, 1, 2], [0, 2, 3]],
            );
            m.normals = Some(vec![Vec3::Z; 4]);
            m.uvs = Some(m.positions.iter().map(|p| p.truncate()).collect());
            m
        };
        let (m, t) = square().with_tangents().unwrap();
        assert_eq!(m.positions.len(), 4);
        for t in &t {
            assert!(t.truncate().abs_diff_eq(Vec3::X, 1e-5), "{t}");
            assert_eq!(t.w, 1.0);
        }
        // A fold: the second triangle's UVs turn the other way round the
        // two vertices it shares with the first.
        let mut mirrored = square();
        mirrored.uvs.as_mut().unwrap()[3] = Vec2::new(1.0, 0.0);
        let (m, t) = mirrored.with_tangents().unwrap();
        assert_eq!(m.positions.len(), 6);
        let signs: Vec<f32> = m.triangles.iter().map(|tri| t[tri[0] as usize].w).collect();
        assert_eq!(signs, [1.0, -1.0]);
        assert!(square().uvs.is_some() && TriMesh::new(vec![], vec![]).with_tangents().is_none());
    }
}
