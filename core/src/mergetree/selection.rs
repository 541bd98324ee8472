//! §5: real-time triangulation. The display vertices of a frame come from the
//! previous frame's by walking the tree down (splits) from each display vertex
//! and up (merges) from the merges that could happen next, honouring the
//! dependencies recursively; the display
//! triangles change with each split or merge by swapping the fan it was built
//! from (§5.2, Fig. 6). A cold start begins with every vertex and triangle of
//! the input, as the paper's frame 0 does.

use std::sync::Arc;

use super::{Criteria, MergeTree, NONE};
use crate::cut::{DrawSet, Hierarchy};
use crate::geom::TriMesh;
use crate::view::{Tolerance, View};

/// A set of small ids with O(1) insert, remove and membership, and a dense
/// list to walk.
#[derive(Debug, Clone)]
struct IdSet {
    items: Vec<u32>,
    slot: Vec<u32>,
}

impl IdSet {
    fn new(capacity: usize) -> Self {
        Self {
            items: Vec::with_capacity(capacity),
            slot: vec![NONE; capacity],
        }
    }

    fn clear(&mut self) {
        for &i in &self.items {
            self.slot[i as usize] = NONE;
        }
        self.items.clear();
    }

    fn contains(&self, i: u32) -> bool {
        self.slot[i as usize] != NONE
    }

    fn insert(&mut self, i: u32) {
        if !self.contains(i) {
            self.slot[i as usize] = self.items.len() as u32;
            self.items.push(i);
        }
    }

    /// False when `i` was not there.
    fn remove(&mut self, i: u32) -> bool {
        let s = self.slot[i as usize];
        if s == NONE {
            return false;
        }
        self.items.swap_remove(s as usize);
        if let Some(&moved) = self.items.get(s as usize) {
            self.slot[moved as usize] = s;
        }
        self.slot[i as usize] = NONE;
        true
    }
}

/// What one update did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UpdateStats {
    /// Nodes whose criteria were evaluated.
    pub evaluated: usize,
    pub splits: usize,
    pub merges: usize,
    /// Swaps that did not find their fan among the display triangles (a broken
    /// dependency; never expected).
    pub fan_mismatches: usize,
}

/// The run-time state of a merge tree: the merges in place, the display
/// vertices and triangles, and the frontier the next frame's walk up starts from.
#[derive(Debug, Clone)]
pub struct MergeTreeView {
    tree: Arc<MergeTree>,
    pub criteria: Criteria,
    merged: Vec<bool>,
    /// Per merge, how many of its requirements are not in place.
    missing: Vec<u32>,
    /// Merges not in place whose requirements all are: may merge next.
    mergeable: IdSet,
    /// The display vertices and triangles.
    shown: IdSet,
    display: IdSet,
    /// Per vertex, its node now ([`NONE`]: the vertex itself, a leaf).
    node: Vec<u32>,
    work: Vec<u32>,
    remap: Vec<u32>,
}

impl MergeTreeView {
    /// Starts with every input vertex and triangle displayed (§5.1, §5.2 frame 0).
    pub fn new(tree: Arc<MergeTree>, criteria: Criteria) -> Self {
        let m = tree.merges.len();
        let n = tree.mesh.positions.len();
        let mut view = MergeTreeView {
            criteria,
            merged: vec![false; m],
            missing: vec![0; m],
            mergeable: IdSet::new(m),
            shown: IdSet::new(n),
            display: IdSet::new(tree.triangles.len()),
            node: vec![NONE; n],
            work: Vec::with_capacity(m),
            remap: vec![NONE; n],
            tree,
        };
        view.reset();
        view
    }

    /// Back to every input vertex and triangle: a cold start.
    pub fn reset(&mut self) {
        self.merged.fill(false);
        self.node.fill(NONE);
        self.mergeable.clear();
        self.shown.clear();
        self.display.clear();
        for k in 0..self.tree.merges.len() {
            self.missing[k] = self.tree.requires.row(k).len() as u32;
            if self.missing[k] == 0 {
                self.mergeable.insert(k as u32);
            }
        }
        for t in 0..self.tree.mesh.triangles.len() as u32 {
            self.display.insert(t);
            for v in self.tree.triangles[t as usize] {
                self.shown.insert(v);
            }
        }
    }

    pub fn tree(&self) -> &Arc<MergeTree> {
        &self.tree
    }

    /// §5.1: adapts the cut from the previous frame's to `view`; no allocation
    /// once the work list has grown.
    pub fn update(&mut self, view: &View, tolerance: Tolerance) -> UpdateStats {
        let tree = Arc::clone(&self.tree);
        let frame = self.criteria.frame(view, tolerance, tree.diagonal);
        let refine = |k: u32| frame.must_refine(&tree.nodes[k as usize]);
        let mut stats = UpdateStats::default();
        // Down the tree from every display vertex whose node is too coarse,
        // splitting what depends on it first (§4.3).
        self.work.clear();
        for &v in &self.shown.items {
            if self.node[v as usize] != NONE {
                self.work.push(self.node[v as usize]);
            }
        }
        while let Some(k) = self.work.pop() {
            if !self.merged[k as usize] {
                continue;
            }
            stats.evaluated += 1;
            if refine(k) {
                self.split(k, &mut stats);
            }
        }
        // Up the tree: merge children wherever the view and the dependencies
        // allow it.
        self.work.extend_from_slice(&self.mergeable.items);
        while let Some(k) = self.work.pop() {
            if self.merged[k as usize] || self.missing[k as usize] != 0 {
                continue;
            }
            stats.evaluated += 1;
            if !refine(k) {
                self.merge(k, &mut stats);
            }
        }
        stats
    }

    /// Swaps fan `from` for fan `to` in the display triangles.
    fn swap(&mut self, from: &[u32], to: &[u32], stats: &mut UpdateStats) {
        for &t in from {
            if !self.display.remove(t) {
                stats.fan_mismatches += 1;
            }
        }
        for &t in to {
            self.display.insert(t);
        }
    }

    /// Splits merge `k` (in place), after the merges in place that depend on
    /// it; the nodes it uncovers join the walk.
    fn split(&mut self, k: u32, stats: &mut UpdateStats) {
        let tree = Arc::clone(&self.tree);
        let ku = k as usize;
        for &r in tree.dependents.row(ku) {
            if self.merged[r as usize] {
                self.split(r, stats);
            }
        }
        let m = tree.merges[ku];
        self.swap(tree.added.row(ku), tree.removed.row(ku), stats);
        self.merged[ku] = false;
        self.shown.insert(m.child);
        self.node[m.parent as usize] = tree.previous[ku];
        for v in [m.parent, m.child] {
            if self.node[v as usize] != NONE {
                self.work.push(self.node[v as usize]);
            }
        }
        // Everything k requires is in place, so k may merge again.
        self.mergeable.insert(k);
        for &r in tree.dependents.row(ku) {
            self.missing[r as usize] += 1;
            self.mergeable.remove(r);
        }
        stats.splits += 1;
    }

    fn merge(&mut self, k: u32, stats: &mut UpdateStats) {
        let tree = Arc::clone(&self.tree);
        let ku = k as usize;
        let m = tree.merges[ku];
        self.swap(tree.removed.row(ku), tree.added.row(ku), stats);
        self.merged[ku] = true;
        self.shown.remove(m.child);
        self.node[m.parent as usize] = k;
        self.mergeable.remove(k);
        for &r in tree.dependents.row(ku) {
            self.missing[r as usize] -= 1;
            if self.missing[r as usize] == 0 {
                self.mergeable.insert(r);
                self.work.push(r);
            }
        }
        stats.merges += 1;
    }

    /// Whether merge `k` is in place (its child is not displayed).
    pub fn is_merged(&self, k: usize) -> bool {
        self.merged[k]
    }

    /// The display triangles, as build-triangle ids.
    pub fn display_triangles(&self) -> &[u32] {
        &self.display.items
    }

    /// A display vertex's node ([`NONE`]: a leaf).
    pub fn node_of(&self, v: u32) -> u32 {
        self.node[v as usize]
    }

    /// Display triangles facing against the input triangle they stand for.
    pub fn folds(&self) -> usize {
        self.display
            .items
            .iter()
            .filter(|t| self.tree.is_folded(**t))
            .count()
    }

    /// The display mesh: display vertices at their input positions with their
    /// input attributes; per-triangle errors are the largest downswitch
    /// distance of its vertices' nodes.
    pub fn draw_set(&mut self) -> DrawSet {
        let tree = &self.tree;
        let src = &tree.mesh;
        let mut order: Vec<u32> = Vec::new();
        let mut triangles = Vec::with_capacity(self.display.items.len());
        let mut errors = Vec::with_capacity(self.display.items.len());
        let mut levels = Vec::with_capacity(self.display.items.len());
        let error = |v: u32| match self.node[v as usize] {
            NONE => 0.0,
            k => tree.nodes[k as usize].downswitch,
        };
        // Node k stands for merge k, made at its tree level (leaves: level 0).
        let level = |v: u32| match self.node[v as usize] {
            NONE => 0,
            k => tree.merges[k as usize].level + 1,
        };
        for &t in &self.display.items {
            let tri = tree.triangles[t as usize];
            errors.push(tri.iter().map(|v| error(*v)).fold(0.0, f32::max));
            levels.push(tri.iter().map(|v| level(*v)).max().unwrap_or(0));
            triangles.push(tri.map(|v| {
                if self.remap[v as usize] == NONE {
                    self.remap[v as usize] = order.len() as u32;
                    order.push(v);
                }
                self.remap[v as usize]
            }));
        }
        for &v in &order {
            self.remap[v as usize] = NONE;
        }
        let mesh = TriMesh {
            positions: order.iter().map(|v| src.positions[*v as usize]).collect(),
            normals: gather(&src.normals, &order),
            colors: gather(&src.colors, &order),
            uvs: gather(&src.uvs, &order),
            parts: src.parts.as_ref().map(|p| {
                self.display
                    .items
                    .iter()
                    .map(|t| p[tree.origin[*t as usize] as usize])
                    .collect()
            }),
            materials: src.materials.clone(),
            triangles,
        };
        DrawSet {
            mesh,
            error_bound: errors.iter().copied().fold(0.0, f32::max),
            triangle_errors: errors,
            triangle_levels: levels,
            ..DrawSet::default()
        }
    }
}

/// The per-vertex attribute of `order`'s vertices, where there is one.
fn gather<T: Copy>(attribute: &Option<Vec<T>>, order: &[u32]) -> Option<Vec<T>> {
    attribute
        .as_ref()
        .map(|a| order.iter().map(|v| a[*v as usize]).collect())
}

impl Hierarchy for MergeTreeView {
    fn method(&self) -> &'static str {
        "mergetree"
    }

    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet {
        self.update(view, tolerance);
        self.draw_set()
    }

    fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        Some(crate::io::hierarchy_file::save(
            "mergetree",
            params,
            self.tree().as_ref(),
        ))
    }

    /// The criteria switches `backface`, `silhouette` and `lighting` (§3).
    fn set_runtime(&mut self, params: &serde_json::Value) {
        let flag =
            |key: &str, current: bool| params.get(key).and_then(|v| v.as_bool()).unwrap_or(current);
        self.criteria = Criteria {
            backface: flag("backface", self.criteria.backface),
            silhouette: flag("silhouette", self.criteria.silhouette),
            lighting: flag("lighting", self.criteria.lighting),
        };
    }
}
