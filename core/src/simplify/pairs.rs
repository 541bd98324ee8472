//! Pair contraction across gaps (issue 48, item 2: "virtual edges between
//! close vertices of different components or across holes are contracted").
//! Garland and Heckbert (1997, §3 "pair selection") contract any pair of
//! vertices closer than a threshold t, not only edges, so that pieces merge
//! and holes close where the edge collapse alone must keep them: a handle
//! or a piece costs at least four triangles however far the collapse goes.
//!
//! **Which pairs.** Every pair within one cell of a grid of spacing t is
//! contracted, as vertex clustering does (Rossignac and Borrel 1993;
//! meshoptimizer's sloppy mode): the cell's vertices become the one of them
//! whose position the cell's summed quadric likes best, which keeps that
//! vertex's attributes (wedges stay per corner), placed at the quadric's
//! optimum where that lies within the members' box (Lindstrom 2000). A
//! triangle left with two corners in one cell, a second copy of a triangle
//! and one of zero area go. This is run on a mesh the certified collapse
//! has already taken to its topology's floor (for a count) or to half the
//! error (for an error), and the collapse then goes on from it.
//!
//! **The bound.** Nothing is composed: what comes out of contraction and
//! the collapse after it is certified directly against the input, two-sided
//! (`bound::certify_against`), by the branch and bound every certificate
//! here uses. A two-sided distance between surfaces does not care about
//! their connectivity, so merged pieces and closed holes cost exactly what
//! the certificate says. Which t is best is not known beforehand; the
//! caller tries a few and keeps the best certified result.

use std::collections::{HashMap, HashSet};

use glam::Vec3;

use super::quadric::Quadric;
use crate::geom::repair::is_zero_area;
use crate::geom::{Aabb, TriMesh};

/// `mesh` with the vertices of each cell of a grid of spacing `cell`
/// contracted to one (module doc), and the number of vertices contracted
/// into another.
pub fn contract(mesh: &TriMesh, cell: f32, shift: f32) -> (TriMesh, usize) {
    let origin = mesh.bounds().min - Vec3::splat(shift * cell);
    let key = |p: Vec3| ((p - origin) / cell).floor().as_ivec3().to_array();
    // Each vertex's quadric: its triangles' planes, weighted by area.
    let mut quadric = vec![Quadric::default(); mesh.positions.len()];
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let n = (b - a).cross(c - a);
        let area = 0.5 * n.length();
        if area > 0.0 {
            let q = Quadric::plane(a, n.normalize(), area as f64);
            for &v in t {
                quadric[v as usize].add(&q);
            }
        }
        for &v in t {
            used[v as usize] = true;
        }
    }
    // Cells in order of their first vertex, so the result depends on the
    // mesh alone.
    let mut cell_of = HashMap::new();
    let mut members: Vec<Vec<u32>> = Vec::new();
    let mut cluster = vec![u32::MAX; mesh.positions.len()];
    for (v, p) in mesh.positions.iter().enumerate() {
        if !used[v] {
            continue;
        }
        let c = *cell_of.entry(key(*p)).or_insert_with(|| {
            members.push(Vec::new());
            members.len() as u32 - 1
        });
        members[c as usize].push(v as u32);
        cluster[v] = c;
    }
    // Each cell's vertex: the member its summed quadric likes best (whose
    // attributes it keeps), moved to the quadric's optimum where that lies
    // within the members' box and is better still (Lindstrom 2000).
    let mut out = mesh.clone();
    let representative: Vec<u32> = members
        .iter()
        .map(|m| {
            let mut q = Quadric::default();
            let mut reach = Aabb::EMPTY;
            for &v in m {
                q.add(&quadric[v as usize]);
                reach = reach.grow(mesh.positions[v as usize]);
            }
            let cost = |v: u32| q.error(mesh.positions[v as usize]);
            let best = *m
                .iter()
                .min_by(|&&a, &&b| cost(a).total_cmp(&cost(b)).then(a.cmp(&b)))
                .expect("a cell has a vertex");
            let within = |p: Vec3| p.cmpge(reach.min).all() && p.cmple(reach.max).all();
            if let Some(p) = q
                .optimum()
                .filter(|&p| within(p) && q.error(p) < cost(best))
            {
                out.positions[best as usize] = p;
            }
            best
        })
        .collect();
    let contracted = members.iter().map(|m| m.len() - 1).sum();
    let to = |v: u32| representative[cluster[v as usize] as usize];
    let mut seen = HashSet::new();
    let mut kept = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let new = tri.map(to);
        let mut sorted = new;
        sorted.sort_unstable();
        let distinct = sorted[0] != sorted[1] && sorted[1] != sorted[2];
        if distinct && !is_zero_area(&out.positions, &new) && seen.insert(sorted) {
            kept.push(t as u32);
        }
        out.triangles[t] = new;
    }
    if let Some(w) = &mut out.wedges {
        for v in &mut w.vertex {
            if used[*v as usize] {
                *v = to(*v);
            }
        }
    }
    (out.arrays().gather(kept), contracted)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::icosphere;
    use crate::geom::Topology;

    /// Two spheres closer than a cell become one piece; a cell finer than
    /// their gap leaves two, and a cell finer than every edge changes
    /// nothing.
    #[test]
    fn pieces_closer_than_a_cell_merge() {
        let a = icosphere(Vec3::ZERO, 1.0, 2);
        let b = icosphere(Vec3::new(2.05, 0.0, 0.0), 1.0, 2);
        let mesh = TriMesh::concat(&[a, b]);
        let pieces = |m: &TriMesh| Topology::of(m).components.len();
        assert_eq!(pieces(&mesh), 2);
        let (same, contracted) = contract(&mesh, 1e-3, 0.0);
        assert_eq!(
            (same.triangles.len(), contracted),
            (mesh.triangles.len(), 0)
        );
        let (merged, contracted) = contract(&mesh, 0.6, 0.0);
        assert_eq!(pieces(&merged), 1, "{}", merged.triangles.len());
        assert!(contracted > 0 && merged.triangles.len() < mesh.triangles.len());
        // Every vertex left is one of the input's, or within the box of
        // the input's vertices of its cell.
        let o = mesh.bounds().min;
        let near = |p: &Vec3| {
            let cell = |q: &Vec3| ((*q - o) / 0.6).floor() == ((*p - o) / 0.6).floor();
            let box_ = Aabb::from_points(mesh.positions.iter().filter(|q| cell(q)));
            p.cmpge(box_.min).all() && p.cmple(box_.max).all()
        };
        assert!(merged.positions.iter().all(near));
    }
}
