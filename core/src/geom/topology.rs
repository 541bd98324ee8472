//! Connected components, boundary loops, Euler characteristic and genus.
//!
//! Components connect through shared vertices. Per component,
//! χ = V − E + F and genus g = (2 − χ − b) / 2 with b boundary loops; the
//! mesh's genus is the sum. It is meaningful only without non-manifold edges.

use super::TriMesh;
use super::adjacency::Adjacency;

/// Union-find with path halving.
#[derive(Debug, Clone)]
pub struct UnionFind(Vec<u32>);

impl UnionFind {
    pub fn new(n: usize) -> Self {
        Self((0..n as u32).collect())
    }
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = p;
            x = p;
        }
        x
    }
    pub fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb) as usize] = ra.min(rb);
        }
    }
}

/// Counts of one connected component.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ComponentTopology {
    pub vertices: usize,
    pub edges: usize,
    pub triangles: usize,
    pub boundary_loops: usize,
    pub euler: i64,
    pub genus: i64,
}

/// Topology of a whole mesh.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Topology {
    pub vertices: usize,
    pub edges: usize,
    pub triangles: usize,
    pub components: Vec<ComponentTopology>,
    pub boundary_loops: usize,
    pub non_manifold_edges: usize,
    /// Edges whose two triangles disagree on orientation.
    pub inconsistent_edges: usize,
    pub euler: i64,
    pub genus: i64,
    /// Component id per vertex (`u32::MAX` for vertices no triangle uses).
    #[serde(skip)]
    pub vertex_component: Vec<u32>,
}

impl Topology {
    pub fn of(mesh: &TriMesh) -> Topology {
        Self::with_adjacency(mesh, &Adjacency::new(&mesh.triangles))
    }

    pub fn with_adjacency(mesh: &TriMesh, adj: &Adjacency) -> Topology {
        let nv = mesh.positions.len();
        let mut uf = UnionFind::new(nv);
        let mut used = vec![false; nv];
        for t in &mesh.triangles {
            uf.union(t[0], t[1]);
            uf.union(t[1], t[2]);
            for v in t {
                used[*v as usize] = true;
            }
        }
        // Dense component ids in order of first vertex.
        let mut root_id = vec![u32::MAX; nv];
        let mut vertex_component = vec![u32::MAX; nv];
        let mut comps: Vec<ComponentTopology> = Vec::new();
        for v in 0..nv {
            if !used[v] {
                continue;
            }
            let r = uf.find(v as u32) as usize;
            if root_id[r] == u32::MAX {
                root_id[r] = comps.len() as u32;
                comps.push(ComponentTopology {
                    vertices: 0,
                    edges: 0,
                    triangles: 0,
                    boundary_loops: 0,
                    euler: 0,
                    genus: 0,
                });
            }
            vertex_component[v] = root_id[r];
            comps[root_id[r] as usize].vertices += 1;
        }
        for t in &mesh.triangles {
            comps[vertex_component[t[0] as usize] as usize].triangles += 1;
        }
        for e in &adj.edges {
            comps[vertex_component[e[0] as usize] as usize].edges += 1;
        }
        // Boundary loops: connected pieces of the border-edge graph.
        let mut border_uf = UnionFind::new(nv);
        let mut on_border = vec![false; nv];
        for [a, b] in adj.border_edges() {
            border_uf.union(a, b);
            on_border[a as usize] = true;
            on_border[b as usize] = true;
        }
        for v in 0..nv {
            if on_border[v] && border_uf.find(v as u32) == v as u32 {
                comps[vertex_component[v] as usize].boundary_loops += 1;
            }
        }
        for c in &mut comps {
            c.euler = c.vertices as i64 - c.edges as i64 + c.triangles as i64;
            c.genus = (2 - c.euler - c.boundary_loops as i64).div_euclid(2);
        }
        Topology {
            vertices: comps.iter().map(|c| c.vertices).sum(),
            edges: adj.edges.len(),
            triangles: mesh.triangles.len(),
            boundary_loops: comps.iter().map(|c| c.boundary_loops).sum(),
            non_manifold_edges: adj.non_manifold_edge_count(),
            inconsistent_edges: adj.inconsistent_edges,
            euler: comps.iter().map(|c| c.euler).sum(),
            genus: comps.iter().map(|c| c.genus).sum(),
            components: comps,
            vertex_component,
        }
    }

    pub fn is_closed(&self) -> bool {
        self.boundary_loops == 0
    }

    pub fn is_manifold(&self) -> bool {
        self.non_manifold_edges == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A square torus made of a `n × m` grid wrapped both ways: genus 1, χ = 0.
    fn grid_torus(n: u32, m: u32) -> TriMesh {
        let mut pos = Vec::new();
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..m {
                pos.push(Vec3::new(i as f32, j as f32, 0.0));
                let a = i * m + j;
                let b = ((i + 1) % n) * m + j;
                let c = ((i + 1) % n) * m + (j + 1) % m;
                let d = i * m + (j + 1) % m;
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
        TriMesh::new(pos, tris)
    }

    #[test]
    fn torus_has_genus_one() {
        let t = Topology::of(&grid_torus(6, 5));
        assert_eq!(t.components.len(), 1);
        assert_eq!(t.euler, 0);
        assert_eq!(t.genus, 1);
        assert!(t.is_closed() && t.is_manifold());
    }

    #[test]
    fn two_components_and_a_border() {
        let mut m = grid_torus(4, 4);
        let square = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::ONE, Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        m.append(&square);
        let t = Topology::of(&m);
        assert_eq!(t.components.len(), 2);
        assert_eq!(t.boundary_loops, 1);
        assert_eq!(t.components[1].euler, 1);
        assert_eq!(t.components[1].genus, 0);
        assert_eq!(t.genus, 1);
    }
}
