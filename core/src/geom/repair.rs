//! Repair on load, reported not hidden: every fix is counted in a
//! [`RepairReport`] that `info` prints and the studio shows.
//!
//! Order matters: non-finite vertices go first (their triangles with them), then
//! welding (which can make triangles degenerate), then repeated-index and
//! zero-area triangles, then vertices nothing uses. Non-manifold edges are
//! counted, not changed: splitting them would change the model's topology.

use std::collections::HashMap;

use glam::Vec3;

use super::adjacency::Adjacency;
use super::topology::UnionFind;
use super::{PointSet, TriMesh, Wedges};

/// How coincident vertices are merged.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Weld {
    /// Keep every vertex record as it is.
    Off,
    /// Merge vertices with bit-identical coordinates (after -0 = +0).
    #[default]
    Exact,
    /// Merge vertices closer than this distance (transitively).
    Tolerance(f32),
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RepairOptions {
    pub weld: Weld,
}

/// Each fix with its count, in the order applied.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RepairReport {
    pub fixes: Vec<(&'static str, usize)>,
}

impl RepairReport {
    fn add(&mut self, what: &'static str, count: usize) {
        self.fixes.push((what, count));
    }

    pub fn get(&self, what: &str) -> usize {
        self.fixes
            .iter()
            .filter(|(w, _)| *w == what)
            .map(|(_, n)| n)
            .sum()
    }

    /// Fixes that changed something.
    pub fn applied(&self) -> impl Iterator<Item = (&'static str, usize)> + '_ {
        self.fixes.iter().copied().filter(|(_, n)| *n > 0)
    }

    pub fn to_json(&self) -> serde_json::Value {
        serde_json::Value::Object(
            self.fixes
                .iter()
                .map(|(k, v)| ((*k).to_string(), (*v).into()))
                .collect(),
        )
    }
}

pub const NON_FINITE_VERTICES: &str = "non_finite_vertices_dropped";
pub const NON_FINITE_TRIANGLES: &str = "triangles_on_non_finite_vertices_dropped";
pub const OUT_OF_RANGE_TRIANGLES: &str = "out_of_range_triangles_dropped";
pub const WELDED_VERTICES: &str = "vertices_welded";
pub const REPEATED_INDEX_TRIANGLES: &str = "repeated_index_triangles_dropped";
pub const ZERO_AREA_TRIANGLES: &str = "zero_area_triangles_dropped";
pub const UNUSED_VERTICES: &str = "unused_vertices_dropped";
pub const NON_MANIFOLD_EDGES: &str = "non_manifold_edges_reported";
pub const NON_FINITE_POINTS: &str = "non_finite_points_dropped";

/// Repairs a mesh; see the module doc for the order of fixes.
pub fn repair_mesh(mut mesh: TriMesh, opts: &RepairOptions) -> (TriMesh, RepairReport) {
    let mut report = RepairReport::default();
    let nv = mesh.positions.len();

    let bad: Vec<bool> = mesh.positions.iter().map(|p| !p.is_finite()).collect();
    report.add(NON_FINITE_VERTICES, bad.iter().filter(|b| **b).count());
    let before = mesh.triangles.len();
    retain_triangles(&mut mesh, |t| t.iter().all(|v| (*v as usize) < nv));
    report.add(OUT_OF_RANGE_TRIANGLES, before - mesh.triangles.len());
    let before = mesh.triangles.len();
    retain_triangles(&mut mesh, |t| t.iter().all(|v| !bad[*v as usize]));
    report.add(NON_FINITE_TRIANGLES, before - mesh.triangles.len());

    let remap = match opts.weld {
        Weld::Off => None,
        Weld::Exact => Some(weld_exact(&mesh.positions, &bad)),
        Weld::Tolerance(tol) => Some(weld_tolerance(&mesh.positions, &bad, tol)),
    };
    if let Some(remap) = remap {
        let merged = remap
            .iter()
            .enumerate()
            .filter(|(i, r)| **r as usize != *i && !bad[*i])
            .count();
        report.add(WELDED_VERTICES, merged);
        // Corners welded across a seam keep their own attributes as wedges.
        mesh.wedges = match mesh.wedges.take() {
            Some(mut w) => {
                for v in &mut w.vertex {
                    *v = remap[*v as usize];
                }
                Some(w)
            }
            None => Wedges::of_welded(&mesh, &remap),
        };
        for t in &mut mesh.triangles {
            *t = t.map(|v| remap[v as usize]);
        }
    }

    let before = mesh.triangles.len();
    retain_triangles(&mut mesh, |t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    report.add(REPEATED_INDEX_TRIANGLES, before - mesh.triangles.len());

    let before = mesh.triangles.len();
    let pos = mesh.positions.clone();
    retain_triangles(&mut mesh, |t| !is_zero_area(&pos, t));
    report.add(ZERO_AREA_TRIANGLES, before - mesh.triangles.len());

    report.add(UNUSED_VERTICES, drop_unused_vertices(&mut mesh));
    report.add(
        NON_MANIFOLD_EDGES,
        Adjacency::new(&mesh.triangles).non_manifold_edge_count(),
    );
    (mesh, report)
}

/// Drops non-finite points.
pub fn repair_points(mut points: PointSet) -> (PointSet, RepairReport) {
    let keep: Vec<bool> = points
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| p.is_finite() && points.radii.as_ref().is_none_or(|r| r[i].is_finite()))
        .collect();
    let dropped = keep.iter().filter(|k| !**k).count();
    if dropped > 0 {
        filter_by(&mut points.positions, &keep);
        if let Some(v) = &mut points.normals {
            filter_by(v, &keep);
        }
        if let Some(v) = &mut points.colors {
            filter_by(v, &keep);
        }
        if let Some(v) = &mut points.radii {
            filter_by(v, &keep);
        }
    }
    let mut report = RepairReport::default();
    report.add(NON_FINITE_POINTS, dropped);
    (points, report)
}

fn filter_by<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
    let mut i = 0;
    v.retain(|_| {
        i += 1;
        keep[i - 1]
    });
}

/// Zero area in f64: the cross product of two edges is exactly the zero vector.
pub(crate) fn is_zero_area(pos: &[Vec3], t: &[u32; 3]) -> bool {
    let [a, b, c] = t.map(|v| pos[v as usize].as_dvec3());
    (b - a).cross(c - a) == glam::DVec3::ZERO
}

fn retain_triangles(mesh: &mut TriMesh, keep: impl Fn(&[u32; 3]) -> bool) {
    let flags: Vec<bool> = mesh.triangles.iter().map(&keep).collect();
    if flags.iter().all(|f| *f) {
        return;
    }
    filter_by(&mut mesh.triangles, &flags);
    if let Some(p) = &mut mesh.parts {
        filter_by(p, &flags);
    }
    if let Some(w) = &mut mesh.wedges {
        filter_by(&mut w.corners, &flags);
    }
}

fn position_key(p: Vec3) -> [u32; 3] {
    // +0.0 and -0.0 are the same point.
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Each vertex maps to the first vertex with identical coordinates.
pub(crate) fn weld_exact(pos: &[Vec3], bad: &[bool]) -> Vec<u32> {
    let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(pos.len());
    (0..pos.len())
        .map(|i| {
            if bad[i] {
                return i as u32;
            }
            *first.entry(position_key(pos[i])).or_insert(i as u32)
        })
        .collect()
}

/// Union of vertices closer than `tol`, found through a hash grid of cell `tol`.
fn weld_tolerance(pos: &[Vec3], bad: &[bool], tol: f32) -> Vec<u32> {
    if !(tol > 0.0 && tol.is_finite()) {
        return weld_exact(pos, bad);
    }
    let cell = |p: Vec3| (p / tol).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    for (i, p) in pos.iter().enumerate() {
        if !bad[i] {
            grid.entry(cell(*p)).or_default().push(i as u32);
        }
    }
    let mut uf = UnionFind::new(pos.len());
    for (i, p) in pos.iter().enumerate() {
        if bad[i] {
            continue;
        }
        let c = cell(*p);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(list) = grid.get(&(c + glam::IVec3::new(dx, dy, dz))) else {
                        continue;
                    };
                    for &j in list {
                        if (j as usize) < i && pos[j as usize].distance(*p) <= tol {
                            uf.union(i as u32, j);
                        }
                    }
                }
            }
        }
    }
    (0..pos.len() as u32).map(|i| uf.find(i)).collect()
}

/// Compacts vertices to those used by triangles; returns how many were dropped.
fn drop_unused_vertices(mesh: &mut TriMesh) -> usize {
    let n = mesh.positions.len();
    let mut used = vec![false; n];
    for t in &mesh.triangles {
        for v in t {
            used[*v as usize] = true;
        }
    }
    let dropped = used.iter().filter(|u| !**u).count();
    if dropped == 0 {
        return 0;
    }
    let mut new_index = vec![u32::MAX; n];
    let mut next = 0u32;
    for (i, u) in used.iter().enumerate() {
        if *u {
            new_index[i] = next;
            next += 1;
        }
    }
    for t in &mut mesh.triangles {
        *t = t.map(|v| new_index[v as usize]);
    }
    if let Some(w) = &mut mesh.wedges {
        for v in &mut w.vertex {
            *v = new_index[*v as usize];
        }
    }
    filter_by(&mut mesh.positions, &used);
    if let Some(v) = &mut mesh.normals {
        filter_by(v, &used);
    }
    if let Some(v) = &mut mesh.colors {
        filter_by(v, &used);
    }
    if let Some(v) = &mut mesh.uvs {
        filter_by(v, &used);
    }
    if let Some(p) = &mut mesh.payload {
        p.retain(&used);
    }
    dropped
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_with_seam() -> TriMesh {
        // Two triangles sharing an edge, but the shared vertices are duplicated.
        TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::X,
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, -0.0),
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        )
    }

    #[test]
    fn exact_weld_merges_duplicates_and_reports() {
        let (m, r) = repair_mesh(quad_with_seam(), &RepairOptions::default());
        assert_eq!(r.get(WELDED_VERTICES), 2);
        assert_eq!(r.get(UNUSED_VERTICES), 2);
        assert_eq!(m.positions.len(), 4);
        assert_eq!(Adjacency::new(&m.triangles).edges.len(), 5);
    }

    #[test]
    fn tolerance_weld_merges_near_vertices() {
        let mut m = quad_with_seam();
        m.positions[3] += Vec3::splat(1e-4);
        let (_, exact) = repair_mesh(m.clone(), &RepairOptions::default());
        assert_eq!(exact.get(WELDED_VERTICES), 1);
        let opts = RepairOptions {
            weld: Weld::Tolerance(1e-3),
        };
        let (m2, r) = repair_mesh(m, &opts);
        assert_eq!(r.get(WELDED_VERTICES), 2);
        assert_eq!(m2.positions.len(), 4);
    }

    #[test]
    fn drops_nan_degenerate_and_zero_area() {
        let mesh = TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::new(f32::NAN, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 1, 3], [0, 0, 2], [0, 1, 4], [0, 1, 9]],
        );
        let (m, r) = repair_mesh(mesh, &RepairOptions::default());
        assert_eq!(r.get(NON_FINITE_VERTICES), 1);
        assert_eq!(r.get(NON_FINITE_TRIANGLES), 1);
        assert_eq!(r.get(OUT_OF_RANGE_TRIANGLES), 1);
        assert_eq!(r.get(REPEATED_INDEX_TRIANGLES), 1);
        assert_eq!(r.get(ZERO_AREA_TRIANGLES), 1);
        assert_eq!(m.triangles.len(), 1);
        assert_eq!(m.positions.len(), 3);
        assert!(m.positions.iter().all(|p| p.is_finite()));
    }

    #[test]
    fn non_manifold_edges_are_reported_not_changed() {
        let mesh = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::NEG_Y, Vec3::Z],
            vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
        );
        let (m, r) = repair_mesh(mesh, &RepairOptions::default());
        assert_eq!(r.get(NON_MANIFOLD_EDGES), 1);
        assert_eq!(m.triangles.len(), 3);
    }
}
