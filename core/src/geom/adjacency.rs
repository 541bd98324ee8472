//! Corner table: for every corner of every triangle, the opposite corner across
//! the edge facing it. This is the adjacency that edge collapse walks (one-rings,
//! link condition) and that topology counts edges and borders from.
//!
//! Corner `c = 3t + i` sits at vertex `triangles[t][i]`; the edge it faces runs
//! from the vertex of `next(c)` to the vertex of `prev(c)`.

use rayon::prelude::*;

/// Marks a corner whose facing edge is a border or non-manifold edge.
pub const NONE: u32 = u32::MAX;

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Adjacency {
    /// Opposite corner per corner, or [`NONE`] on a border or non-manifold edge.
    pub opposite: Vec<u32>,
    /// Undirected edges, each once, as (smaller, larger) vertex index.
    pub edges: Vec<[u32; 2]>,
    /// Number of triangles using each entry of `edges`.
    pub edge_valence: Vec<u32>,
    /// Edges shared by two triangles that traverse them in the same direction
    /// (the neighbours disagree on orientation).
    pub inconsistent_edges: usize,
}

#[inline]
pub fn next(c: u32) -> u32 {
    if c % 3 == 2 { c - 2 } else { c + 1 }
}

#[inline]
pub fn prev(c: u32) -> u32 {
    if c.is_multiple_of(3) { c + 2 } else { c - 1 }
}

impl Adjacency {
    pub fn new(triangles: &[[u32; 3]]) -> Adjacency {
        let vert = |c: u32| triangles[(c / 3) as usize][(c % 3) as usize];
        let n = triangles.len() as u32 * 3;
        // (edge key, corner) sorted by key groups the corners that face one edge.
        let mut keyed: Vec<(u64, u32)> = (0..n)
            .into_par_iter()
            .map(|c| {
                let (a, b) = (vert(next(c)), vert(prev(c)));
                ((a.min(b) as u64) << 32 | a.max(b) as u64, c)
            })
            .collect();
        keyed.par_sort_unstable();
        let mut opposite = vec![NONE; n as usize];
        let mut edges = Vec::with_capacity(keyed.len() / 2 + 1);
        let mut edge_valence = Vec::with_capacity(keyed.len() / 2 + 1);
        let mut inconsistent_edges = 0;
        for group in keyed.chunk_by(|x, y| x.0 == y.0) {
            let key = group[0].0;
            edges.push([(key >> 32) as u32, key as u32]);
            edge_valence.push(group.len() as u32);
            if let [(_, c0), (_, c1)] = group {
                opposite[*c0 as usize] = *c1;
                opposite[*c1 as usize] = *c0;
                if vert(next(*c0)) == vert(next(*c1)) {
                    inconsistent_edges += 1;
                }
            }
        }
        Adjacency {
            opposite,
            edges,
            edge_valence,
            inconsistent_edges,
        }
    }

    pub fn border_edges(&self) -> impl Iterator<Item = [u32; 2]> + '_ {
        self.edges
            .iter()
            .zip(&self.edge_valence)
            .filter(|(_, n)| **n == 1)
            .map(|(e, _)| *e)
    }

    /// Edges used by more than two triangles.
    pub fn non_manifold_edge_count(&self) -> usize {
        self.edge_valence.iter().filter(|n| **n > 2).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tetrahedron_is_closed_and_consistent() {
        let tris = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        let adj = Adjacency::new(&tris);
        assert_eq!(adj.edges.len(), 6);
        assert!(adj.opposite.iter().all(|o| *o != NONE));
        assert_eq!(adj.inconsistent_edges, 0);
        for (c, o) in adj.opposite.iter().enumerate() {
            assert_eq!(
                adj.opposite[*o as usize], c as u32,
                "opposite is an involution"
            );
        }
    }

    #[test]
    fn fin_is_non_manifold_and_flip_is_inconsistent() {
        let fin = [[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let adj = Adjacency::new(&fin);
        assert_eq!(adj.non_manifold_edge_count(), 1);
        let flipped = [[0, 1, 2], [0, 1, 3]];
        assert_eq!(Adjacency::new(&flipped).inconsistent_edges, 1);
        assert_eq!(Adjacency::new(&flipped).border_edges().count(), 4);
    }
}
