//! View-dependent simplification with merge trees (Xia & Varshney, merge-tree
//! paper).
//!
//! Paper: J. C. Xia, A. Varshney, "Dynamic View-Dependent Simplification for
//! Polygonal Models", Proc. IEEE Visualization '96 (the "merge-tree paper" in
//! this tree's docs).
//!
//! Offline, [`build`] collapses edges level by level into a merge tree over the
//! mesh's vertices (§4.1), stores switch distances and attribute ranges at its
//! nodes (§4.2, §5.1) and the dependencies between collapses that keep the
//! run-time mesh from folding (§4.3). At run time a [`MergeTreeView`] walks the
//! tree up and down from the previous frame's display vertices and swaps the
//! display triangles fan by fan (§5).

mod criteria;
mod dependencies;
mod selection;
mod tree;

pub use criteria::{Criteria, NormalCone};
pub use selection::{MergeTreeView, UpdateStats};
pub use tree::Merge;

use glam::Vec3;

use crate::geom::TriMesh;
use crate::progress::{Cancelled, Progress};
use crate::simplify::CollapseOptions;

/// Marks "no node" (a leaf vertex, or no merge).
pub const NONE: u32 = u32::MAX;

/// Default sliver guard (eq. 3 quality) for the merges of a tree: off. On the
/// bunny and horse a guard of 0.2 changed the depth by at most 2 levels, but
/// on the scanned dragon (many slivers to begin with) guards of 0.05, 0.1 and
/// 0.2 stalled the tree at 12k, 25k and 42k of its 436k vertices.
pub const DEFAULT_MIN_QUALITY: f32 = 0.0;

/// How few vertices a tree may stop at (§4.1 (a)): a tetrahedron's four up
/// to the point where a deeper tree is no longer worth its levels.
pub const MIN_VERTICES_RANGE: std::ops::RangeInclusive<usize> = 4..=100_000;

/// How the tree is built.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct MergeTreeOptions {
    /// §4.1 (a): stop once this few vertices are left.
    pub min_vertices: usize,
    /// Legality of each collapse: fold guard, and the §6 sliver guard
    /// (`min_quality`, eq. 3) on the triangles it makes.
    #[serde(flatten)]
    pub collapse: CollapseOptions,
}

impl MergeTreeOptions {
    pub fn validate(&self) -> Result<(), crate::lod::ParamError> {
        crate::lod::in_range("min_vertices", self.min_vertices, &MIN_VERTICES_RANGE)?;
        self.collapse.validate()
    }
}

impl Default for MergeTreeOptions {
    fn default() -> Self {
        Self {
            min_vertices: 8,
            collapse: CollapseOptions {
                min_quality: DEFAULT_MIN_QUALITY,
                ..CollapseOptions::default()
            },
        }
    }
}

/// A node of the merge tree: a parent vertex after it absorbed a child (one
/// [`Merge`]), with the ranges of everything below it (§4.2).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Node {
    /// The parent vertex's position: where the node is displayed.
    pub center: Vec3,
    /// A sphere about `center` holding every original vertex below the node.
    pub radius: f32,
    /// §5.1 downswitch distance: refine the node (split the child off) when its
    /// projection exceeds the threshold. Bounds how far any original vertex
    /// below moved; never smaller than that of a node below.
    pub downswitch: f32,
    /// §5.1 upswitch distance: the downswitch distance of the next merge of the
    /// same parent vertex (infinite at a root).
    pub upswitch: f32,
    /// Range of the normals of every triangle below the node (§4.2).
    pub cone: NormalCone,
}

/// Rows of `u32` packed in one vector (per-merge triangle fans and
/// dependencies).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Csr {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Default for Csr {
    fn default() -> Self {
        Self {
            start: vec![0],
            items: Vec::new(),
        }
    }
}

impl Csr {
    pub(crate) fn push_row(&mut self, row: impl IntoIterator<Item = u32>) {
        self.items.extend(row);
        self.start.push(self.items.len() as u32);
    }

    pub(crate) fn row(&self, i: usize) -> &[u32] {
        &self.items[self.start[i] as usize..self.start[i + 1] as usize]
    }

    pub(crate) fn total(&self) -> usize {
        self.items.len()
    }

    /// `rows` rows with items below `len`, offsets rising to the item count.
    fn check(&self, what: &str, rows: usize, len: usize) -> Result<(), String> {
        let offsets_fit = self.start.len() == rows + 1
            && self.start.first() == Some(&0)
            && self.start.windows(2).all(|w| w[0] <= w[1])
            && self.start.last().map(|&e| e as usize) == Some(self.items.len());
        if !offsets_fit {
            return Err(format!("{what}: rows do not match the merges"));
        }
        crate::geom::check_indices(what, self.items.iter().copied(), len)
    }

    /// Rows `0..rows` from `(row, item)` pairs.
    pub(crate) fn from_pairs(rows: usize, pairs: &mut [(u32, u32)]) -> Csr {
        pairs.sort_unstable();
        let mut csr = Csr {
            start: Vec::with_capacity(rows + 1),
            items: Vec::with_capacity(pairs.len()),
        };
        csr.start.push(0);
        let mut i = 0;
        for r in 0..rows as u32 {
            while i < pairs.len() && pairs[i].0 == r {
                csr.items.push(pairs[i].1);
                i += 1;
            }
            csr.start.push(csr.items.len() as u32);
        }
        csr
    }
}

/// The merge tree of a mesh, with its dependencies (built once, offline).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct MergeTree {
    /// The input mesh (display vertices keep their original positions and
    /// attributes).
    pub(crate) mesh: TriMesh,
    /// Every triangle the build made, the input's first: the display triangles
    /// are always some of these.
    pub(crate) triangles: Vec<[u32; 3]>,
    /// The input triangle each one stands for (its orientation and part).
    pub(crate) origin: Vec<u32>,
    /// Each one's corner wedges, on its input triangle's side of every seam
    /// (`geom::wedges`); `None` when the input has no wedges.
    pub(crate) corner_wedges: Option<Vec<[u32; 3]>>,
    pub(crate) merges: Vec<Merge>,
    pub(crate) nodes: Vec<Node>,
    /// Per merge, the node its parent vertex had before it ([`NONE`]: leaf).
    pub(crate) previous: Vec<u32>,
    /// Per merge, the triangles around the child before (removed) and after
    /// (added) it: the fans swapped at run time (§5.2, Fig. 6).
    pub(crate) removed: Csr,
    pub(crate) added: Csr,
    /// §4.3: merges that must be in place before a merge (requires) and that
    /// must be undone before it is (dependents).
    pub(crate) requires: Csr,
    pub(crate) dependents: Csr,
    levels: Vec<usize>,
    diagonal: f32,
}

/// Builds the merge tree of `mesh` (expected repaired: no degenerate
/// triangles), reporting progress level by level.
pub fn build(
    mesh: &TriMesh,
    opts: &MergeTreeOptions,
    progress: &Progress,
) -> Result<MergeTree, Cancelled> {
    progress.stage("merge tree levels");
    let built = tree::build_levels(mesh, opts, progress)?;
    progress.stage("merge tree dependencies");
    let deps = dependencies::dependencies(&built.merges, &built.region, mesh.positions.len());
    progress.check()?;
    let (nodes, previous) = dependencies::nodes(mesh, &built.merges, &built.cones);
    progress.set_fraction(1.0);
    Ok(MergeTree {
        // Display vertices are input vertices: their input normals (area-weighted
        // when the input has none) shade every cut without recomputing any.
        mesh: TriMesh {
            normals: Some(
                mesh.normals
                    .clone()
                    .unwrap_or_else(|| mesh.vertex_normals()),
            ),
            ..mesh.clone()
        },
        corner_wedges: crate::geom::wedges::WedgeSides::new(mesh).map(|sides| {
            (built.triangles.iter().zip(&built.origin))
                .map(|(tri, o)| tri.map(|v| sides.wedge(mesh, *o as usize, v)))
                .collect()
        }),
        triangles: built.triangles,
        origin: built.origin,
        merges: built.merges,
        nodes,
        previous,
        removed: built.removed,
        added: built.added,
        requires: deps.requires,
        dependents: deps.dependents,
        levels: built.levels,
        diagonal: mesh.bounds().diagonal(),
    })
}

impl MergeTree {
    /// Vertices present at each level, finest first; its length is the tree's
    /// depth (§6, Table 1).
    /// Every index in range and every per-merge table one row per merge
    /// (a tree read from a saved file is checked before any cut).
    pub fn check(&self) -> Result<(), String> {
        use crate::geom::{check_indices, check_len};
        self.mesh.check()?;
        let (nv, nm, nt) = (
            self.mesh.positions.len(),
            self.merges.len(),
            self.triangles.len(),
        );
        check_indices("vertex", self.triangles.iter().flatten().copied(), nv)?;
        check_len("origins", Some(&self.origin), nt)?;
        check_indices(
            "input triangle",
            self.origin.iter().copied(),
            self.mesh.triangles.len(),
        )?;
        if let Some(c) = &self.corner_wedges {
            let wedges = self.mesh.wedges.as_ref().map_or(0, |w| w.vertex.len());
            check_len("corner wedges", Some(c), nt)?;
            check_indices("wedge", c.iter().flatten().copied(), wedges)?;
        }
        check_indices(
            "merge vertex",
            self.merges.iter().flat_map(|m| [m.child, m.parent]),
            nv,
        )?;
        check_len("nodes", Some(&self.nodes), nm)?;
        check_len("previous nodes", Some(&self.previous), nm)?;
        let previous = self.previous.iter().copied().filter(|&p| p != NONE);
        check_indices("previous node", previous, nm)?;
        self.removed.check("removed triangle", nm, nt)?;
        self.added.check("added triangle", nm, nt)?;
        self.requires.check("required merge", nm, nm)?;
        self.dependents.check("dependent merge", nm, nm)?;
        if !(self.diagonal.is_finite() && self.diagonal >= 0.0) {
            return Err("diagonal not finite".into());
        }
        Ok(())
    }

    pub fn levels(&self) -> &[usize] {
        &self.levels
    }

    pub fn merges(&self) -> &[Merge] {
        &self.merges
    }

    /// The node made by each merge.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Merges that must be in place before merge `k` is made (§4.3).
    pub fn requires(&self, k: usize) -> &[u32] {
        self.requires.row(k)
    }

    /// Number of dependency links stored.
    pub fn dependency_count(&self) -> usize {
        self.requires.total()
    }

    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    pub fn diagonal(&self) -> f32 {
        self.diagonal
    }

    /// Vertices of build triangle `t` (input vertex ids).
    pub fn triangle(&self, t: u32) -> [u32; 3] {
        self.triangles[t as usize]
    }

    /// The input triangle build triangle `t` stands for.
    pub fn origin(&self, t: u32) -> u32 {
        self.origin[t as usize]
    }

    /// Whether build triangle `t` faces against the input triangle it stands
    /// for: a fold (never expected; measured independently of the build's guard).
    pub fn is_folded(&self, t: u32) -> bool {
        let p = |v: u32| self.mesh.positions[v as usize];
        let [a, b, c] = self.triangles[t as usize].map(p);
        let [oa, ob, oc] = self.mesh.triangle(self.origin[t as usize] as usize);
        (b - a).cross(c - a).dot((ob - oa).cross(oc - oa)) <= 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::{icosphere, torus};
    use crate::geom::Topology;
    use crate::lod::Hierarchy;
    use crate::view::{Tolerance, View};
    use std::sync::Arc;

    fn orbit(i: usize, frames: usize, distance: f32) -> View {
        let a = i as f32 / frames as f32 * std::f32::consts::TAU;
        View::orbit(Vec3::ZERO, distance, a, 0.3)
    }

    /// Every merge in place has its requirements in place.
    fn dependencies_hold(view: &MergeTreeView) -> bool {
        let tree = view.tree();
        (0..tree.merges().len()).all(|k| {
            !view.is_merged(k) || tree.requires(k).iter().all(|j| view.is_merged(*j as usize))
        })
    }

    /// A built tree passes the reopen check; each kind of damage a file can
    /// carry is refused by it.
    #[test]
    fn check_accepts_built_trees_and_refuses_broken_indices() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 2);
        let tree = build(&mesh, &MergeTreeOptions::default(), &Progress::new()).unwrap();
        assert_eq!(tree.check(), Ok(()));
        let damaged: [fn(&mut MergeTree); 5] = [
            |t| t.merges[0].child = u32::MAX,
            |t| t.triangles[3][1] = t.mesh.positions.len() as u32,
            |t| t.previous.pop().map(drop).unwrap_or(()),
            |t| t.added.start[1] = u32::MAX,
            |t| t.requires.items.push(t.merges.len() as u32),
        ];
        for (k, damage) in damaged.iter().enumerate() {
            let mut t = tree.clone();
            damage(&mut t);
            assert!(t.check().is_err(), "damage {k} passed the check");
        }
    }

    #[test]
    fn levels_shrink_to_the_minimum_with_a_shallow_tree() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 4);
        let tree = build(&mesh, &MergeTreeOptions::default(), &Progress::new()).unwrap();
        let levels = tree.levels();
        assert_eq!(levels[0], mesh.positions.len());
        assert!(levels.windows(2).all(|w| w[1] < w[0]), "{levels:?}");
        assert!(*levels.last().unwrap() <= 8, "{levels:?}");
        let bound = 3.0 * (mesh.positions.len() as f32).log2();
        assert!(
            (levels.len() as f32) <= bound,
            "{} levels: {levels:?}",
            levels.len()
        );
        // Each vertex merges at most once, and the children of one level are
        // as many as its drop in vertices.
        let mut seen = vec![false; mesh.positions.len()];
        for m in tree.merges() {
            assert!(!std::mem::replace(&mut seen[m.child as usize], true));
        }
        for (l, w) in levels.windows(2).enumerate() {
            let children = tree.merges().iter().filter(|m| m.level == l as u32).count();
            assert_eq!(children, w[0] - w[1]);
        }
    }

    #[test]
    fn switch_distances_bound_the_vertices_below_and_grow_up_the_tree() {
        let mesh = torus(1.0, 0.3, 40, 16);
        let tree = build(&mesh, &MergeTreeOptions::default(), &Progress::new()).unwrap();
        // Original vertices below each node, by following child links.
        let mut below: Vec<Vec<u32>> = (0..mesh.positions.len() as u32).map(|v| vec![v]).collect();
        for (k, m) in tree.merges().iter().enumerate() {
            let moved = std::mem::take(&mut below[m.child as usize]);
            below[m.parent as usize].extend(moved);
            let node = &tree.nodes()[k];
            for v in &below[m.parent as usize] {
                let d = mesh.positions[*v as usize].distance(node.center);
                assert!(d <= node.downswitch * 1.0001 + 1e-6);
                assert!(d <= node.radius);
            }
            assert!(node.upswitch >= node.downswitch);
        }
    }

    #[test]
    fn incremental_and_cold_selections_agree_without_folds() {
        let mesh = torus(1.0, 0.35, 60, 24);
        let before = Topology::of(&mesh);
        let tree = Arc::new(build(&mesh, &MergeTreeOptions::default(), &Progress::new()).unwrap());
        // Every §4.3 link, also those the stored dependencies leave implied.
        let built = tree::build_levels(&mesh, &MergeTreeOptions::default(), &Progress::new());
        let built = built.unwrap();
        let all = dependencies::links(&built.merges, &built.region, mesh.positions.len());
        assert!(all.len() > tree.dependency_count());
        let mut warm = MergeTreeView::new(tree.clone(), Criteria::default());
        let mut cold = MergeTreeView::new(tree.clone(), Criteria::default());
        let frames = 40;
        for i in 0..frames {
            let view = orbit(i, frames, 2.5 + (i % 7) as f32 * 0.3);
            let stats = warm.update(&view, Tolerance::Pixels(4.0));
            assert_eq!(stats.fan_mismatches, 0, "frame {i}");
            cold.reset();
            assert_eq!(cold.update(&view, Tolerance::Pixels(4.0)).fan_mismatches, 0);
            assert!(dependencies_hold(&warm), "frame {i}");
            let implied =
                |(r, j): &(u32, u32)| !warm.is_merged(*r as usize) || warm.is_merged(*j as usize);
            assert!(all.iter().all(implied), "frame {i}");
            assert!(warm.active_follows_display() && cold.active_follows_display());
            for k in 0..tree.merges().len() {
                assert_eq!(warm.is_merged(k), cold.is_merged(k), "frame {i} merge {k}");
            }
            assert!(
                warm.display_triangles().eq(cold.display_triangles()),
                "frame {i}"
            );
            assert_eq!(warm.folds(), 0);
            let set = warm.select(&view, Tolerance::Pixels(4.0));
            assert!(set.mesh.triangles.len() < mesh.triangles.len());
            let after = Topology::of(&set.mesh);
            assert_eq!(after.components.len(), before.components.len());
            assert_eq!(after.is_manifold(), before.is_manifold());
            assert_eq!(
                after.components.iter().map(|c| c.genus).collect::<Vec<_>>(),
                before
                    .components
                    .iter()
                    .map(|c| c.genus)
                    .collect::<Vec<_>>()
            );
        }
    }

    #[test]
    fn sliver_guard_keeps_every_triangle_at_least_as_good_as_asked_or_as_its_original() {
        let mesh = torus(1.0, 0.3, 48, 16);
        let q = |p: [Vec3; 3]| crate::simplify::collapse::quality(p);
        for min_quality in [0.0, 0.5] {
            let opts = MergeTreeOptions {
                collapse: CollapseOptions {
                    min_quality,
                    ..Default::default()
                },
                ..Default::default()
            };
            let tree = build(&mesh, &opts, &Progress::new()).unwrap();
            let mut worst = f32::INFINITY;
            for t in 0..tree.triangles.len() as u32 {
                let quality = q(tree.triangle(t).map(|v| mesh.positions[v as usize]));
                let original = q(mesh.triangle(tree.origin(t) as usize));
                assert!(quality >= min_quality.min(original) - 1e-6, "{quality}");
                worst = worst.min(quality);
            }
            if min_quality == 0.0 {
                assert!(worst < 0.5, "the guard is what keeps slivers out");
            }
        }
    }

    #[test]
    fn relative_tolerance_zero_keeps_every_triangle_and_coarse_keeps_few() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 3);
        let tree = Arc::new(build(&mesh, &MergeTreeOptions::default(), &Progress::new()).unwrap());
        let mut v = MergeTreeView::new(tree, Criteria::default());
        let view = orbit(0, 1, 3.0);
        let fine = v.select(&view, Tolerance::Relative(0.0));
        assert_eq!(fine.mesh.triangles.len(), mesh.triangles.len());
        assert_eq!(fine.error_bound, 0.0);
        let coarse = v.select(&view, Tolerance::Relative(10.0));
        assert!(
            coarse.mesh.triangles.len() <= 2 * 8 + 4,
            "{}",
            coarse.mesh.triangles.len()
        );
        assert!(coarse.error_bound > 0.5);
    }
}
