//! §5: real-time triangulation. The display vertices of a frame come from the
//! previous frame's by walking the tree down (splits) from each display vertex
//! and up (merges) from the merges that could happen next, honouring the
//! dependencies recursively; the display
//! triangles change with each split or merge by swapping the fan it was built
//! from (§5.2, Fig. 6). A cold start begins with every vertex and triangle of
//! the input, as the paper's frame 0 does.

use std::sync::Arc;

use fixedbitset::FixedBitSet;

use super::criteria::Frame;
use super::{Criteria, MergeTree, NONE, Node};
use crate::geom::{TriMesh, Wedges};
use crate::id_set::IdSet;
use crate::lod::{DrawSet, Hierarchy};
use crate::view::{Tolerance, View};

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

/// Per merge, what the run time knows of it, in one record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct MergeState {
    merged: bool,
    /// How many of its requirements are not in place.
    missing: u32,
}

impl MergeState {
    const NEW: MergeState = MergeState {
        merged: false,
        missing: 0,
    };
}

/// The two lists of merges a frame tests, each with a copy of their nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum List {
    /// Merges not in place whose requirements all are: may merge next.
    Mergeable,
    /// The nodes of the display vertices that have one.
    Active,
}

/// The run-time state of a merge tree: the merges in place, the display
/// vertices and triangles, and the frontier the next frame's walk up starts from.
#[derive(Debug, Clone)]
pub struct MergeTreeView {
    tree: Arc<MergeTree>,
    pub criteria: Criteria,
    /// Per merge: in place, requirements missing.
    state: Vec<MergeState>,
    /// Merges not in place whose requirements all are: may merge next.
    mergeable: IdSet<Vec<Node>>,
    /// The display vertices and triangles, as bits: a fan swap touches a few
    /// words of a small array instead of a dense list's slots.
    shown: FixedBitSet,
    display: FixedBitSet,
    displayed: usize,
    /// Per vertex, its node now ([`NONE`]: the vertex itself, a leaf).
    node: Vec<u32>,
    /// The nodes of the display vertices that have one: the walk down
    /// starts from them.
    active: IdSet<Vec<Node>>,
    work: Vec<u32>,
    /// Per-frame scratch of the batched tests.
    flags: Vec<u8>,
    pending: Vec<u32>,
    remap: Vec<u32>,
}

impl MergeTreeView {
    /// Starts with every input vertex and triangle displayed (§5.1, §5.2 frame 0).
    pub fn new(tree: Arc<MergeTree>, criteria: Criteria) -> Self {
        let m = tree.merges.len();
        let n = tree.mesh.positions.len();
        let mut view = MergeTreeView {
            criteria,
            state: vec![MergeState::NEW; m],
            mergeable: IdSet::new(m),
            shown: FixedBitSet::with_capacity(n),
            display: FixedBitSet::with_capacity(tree.triangles.len()),
            displayed: 0,
            node: vec![NONE; n],
            active: IdSet::new(m),
            work: Vec::with_capacity(m),
            flags: Vec::with_capacity(m),
            pending: Vec::with_capacity(m),
            remap: vec![NONE; n],
            tree,
        };
        view.reset();
        view
    }

    /// Back to every input vertex and triangle: a cold start.
    pub fn reset(&mut self) {
        self.state.fill(MergeState::NEW);
        self.node.fill(NONE);
        self.mergeable.clear();
        self.active.clear();
        self.shown.clear();
        self.display.clear();
        for k in 0..self.tree.merges.len() {
            self.state[k].missing = self.tree.requires.row(k).len() as u32;
            if self.state[k].missing == 0 {
                self.insert(List::Mergeable, k as u32);
            }
        }
        let input = self.tree.mesh.triangles.len();
        self.display.insert_range(..input);
        self.displayed = input;
        for tri in &self.tree.triangles[..input] {
            for v in tri {
                self.shown.insert(*v as usize);
            }
        }
    }

    pub fn tree(&self) -> &Arc<MergeTree> {
        &self.tree
    }

    /// §5.1: adapts the cut from the previous frame's to `view`; no allocation
    /// once the work lists have grown. Every display vertex's node and every
    /// mergeable merge is tested in one batched pass; only the nodes a split
    /// or merge uncovers are tested one by one.
    pub fn update(&mut self, view: &View, tolerance: Tolerance) -> UpdateStats {
        let tree = Arc::clone(&self.tree);
        let frame = self.criteria.frame(view, tolerance, tree.diagonal);
        let refine = |k: u32| frame.must_refine(&tree.nodes[k as usize]);
        let mut stats = UpdateStats::default();
        self.work.clear();
        // Down the tree from every display vertex whose node is too coarse,
        // splitting what depends on it first (§4.3).
        stats.evaluated += self.pick(&frame, List::Active, true);
        for i in 0..self.pending.len() {
            let k = self.pending[i];
            if self.state[k as usize].merged {
                self.split(k, &mut stats);
            }
        }
        while let Some(k) = self.work.pop() {
            if !self.state[k as usize].merged {
                continue;
            }
            stats.evaluated += 1;
            if refine(k) {
                self.split(k, &mut stats);
            }
        }
        // Up the tree: merge children wherever the view and the dependencies
        // allow it.
        stats.evaluated += self.pick(&frame, List::Mergeable, false);
        for i in 0..self.pending.len() {
            let k = self.pending[i];
            if !self.state[k as usize].merged && self.state[k as usize].missing == 0 {
                self.merge(k, &mut stats);
            }
        }
        while let Some(k) = self.work.pop() {
            if self.state[k as usize].merged || self.state[k as usize].missing != 0 {
                continue;
            }
            stats.evaluated += 1;
            if !refine(k) {
                self.merge(k, &mut stats);
            }
        }
        stats
    }

    /// Tests every node of list `which` in one pass and puts the merges whose
    /// answer is `refine` into `pending`; returns how many were tested.
    fn pick(&mut self, frame: &Frame, which: List, refine: bool) -> usize {
        let list = match which {
            List::Mergeable => &self.mergeable,
            List::Active => &self.active,
        };
        frame.refine_flags(&list.values, &mut self.flags);
        self.pending.clear();
        let flagged = list.items.iter().zip(&self.flags);
        let picked = flagged.filter(|(_, f)| (**f == 1) == refine);
        self.pending.extend(picked.map(|(k, _)| *k));
        list.len()
    }

    fn list(&mut self, which: List) -> &mut IdSet<Vec<Node>> {
        match which {
            List::Mergeable => &mut self.mergeable,
            List::Active => &mut self.active,
        }
    }

    fn insert(&mut self, which: List, k: u32) {
        let node = self.tree.nodes[k as usize];
        self.list(which).insert(k, || node);
    }

    fn remove(&mut self, which: List, k: u32) {
        self.list(which).remove(k);
    }

    /// Sets vertex `v`'s node, keeping the display vertices' nodes in step.
    fn set_node(&mut self, v: u32, k: u32) {
        let old = std::mem::replace(&mut self.node[v as usize], k);
        if old != NONE {
            self.remove(List::Active, old);
        }
        if k != NONE {
            self.insert(List::Active, k);
        }
    }

    /// Shows or hides vertex `v` (with its node).
    fn show(&mut self, v: u32, shown: bool) {
        let k = self.node[v as usize];
        self.shown.set(v as usize, shown);
        match (k != NONE, shown) {
            (true, true) => self.insert(List::Active, k),
            (true, false) => self.remove(List::Active, k),
            _ => {}
        }
    }

    /// Swaps fan `from` for fan `to` in the display triangles.
    fn swap(&mut self, from: &[u32], to: &[u32], stats: &mut UpdateStats) {
        for &t in from {
            if self.display.contains(t as usize) {
                self.display.remove(t as usize);
                self.displayed -= 1;
            } else {
                stats.fan_mismatches += 1;
            }
        }
        for &t in to {
            if !self.display.put(t as usize) {
                self.displayed += 1;
            }
        }
    }

    /// Splits merge `k` (in place), after the merges in place that depend on
    /// it; the nodes it uncovers join the walk.
    fn split(&mut self, k: u32, stats: &mut UpdateStats) {
        let tree = Arc::clone(&self.tree);
        let ku = k as usize;
        for &r in tree.dependents.row(ku) {
            if self.state[r as usize].merged {
                self.split(r, stats);
            }
        }
        let m = tree.merges[ku];
        self.swap(tree.added.row(ku), tree.removed.row(ku), stats);
        self.state[ku].merged = false;
        self.show(m.child, true);
        self.set_node(m.parent, tree.previous[ku]);
        for v in [m.parent, m.child] {
            if self.node[v as usize] != NONE {
                self.work.push(self.node[v as usize]);
            }
        }
        // Everything k requires is in place, so k may merge again.
        self.insert(List::Mergeable, k);
        for &r in tree.dependents.row(ku) {
            self.state[r as usize].missing += 1;
            self.remove(List::Mergeable, r);
        }
        stats.splits += 1;
    }

    fn merge(&mut self, k: u32, stats: &mut UpdateStats) {
        let tree = Arc::clone(&self.tree);
        let ku = k as usize;
        let m = tree.merges[ku];
        self.swap(tree.removed.row(ku), tree.added.row(ku), stats);
        self.state[ku].merged = true;
        self.show(m.child, false);
        self.set_node(m.parent, k);
        self.remove(List::Mergeable, k);
        for &r in tree.dependents.row(ku) {
            self.state[r as usize].missing -= 1;
            if self.state[r as usize].missing == 0 {
                self.insert(List::Mergeable, r);
                self.work.push(r);
            }
        }
        stats.merges += 1;
    }

    /// Whether the batched walk's node list is exactly the display vertices'
    /// nodes.
    #[cfg(test)]
    pub(crate) fn active_follows_display(&self) -> bool {
        let mut want: Vec<u32> = (self.shown.ones())
            .map(|v| self.node[v])
            .filter(|k| *k != NONE)
            .collect();
        let mut have = self.active.items.clone();
        want.sort_unstable();
        have.sort_unstable();
        let copies = (self.active.items.iter().zip(&self.active.values))
            .all(|(k, n)| self.tree.nodes[*k as usize] == *n);
        want == have && copies
    }

    /// Whether merge `k` is in place (its child is not displayed).
    pub fn is_merged(&self, k: usize) -> bool {
        self.state[k].merged
    }

    /// The display triangles, as build-triangle ids in ascending order.
    pub fn display_triangles(&self) -> impl Iterator<Item = u32> + '_ {
        self.display.ones().map(|t| t as u32)
    }

    /// How many triangles are displayed.
    pub fn display_count(&self) -> usize {
        self.displayed
    }

    /// A display vertex's node ([`NONE`]: a leaf).
    pub fn node_of(&self, v: u32) -> u32 {
        self.node[v as usize]
    }

    /// Display triangles facing against the input triangle they stand for.
    pub fn folds(&self) -> usize {
        self.display_triangles()
            .filter(|t| self.tree.is_folded(*t))
            .count()
    }

    /// The display mesh: display vertices at their input positions with their
    /// input attributes; per-triangle errors are the largest downswitch
    /// distance of its vertices' nodes.
    pub fn draw_set(&mut self) -> DrawSet {
        let tree = &self.tree;
        let src = &tree.mesh;
        let mut order: Vec<u32> = Vec::new();
        let mut triangles = Vec::with_capacity(self.displayed);
        let mut errors = Vec::with_capacity(self.displayed);
        let mut levels = Vec::with_capacity(self.displayed);
        let error = |v: u32| match self.node[v as usize] {
            NONE => 0.0,
            k => tree.nodes[k as usize].downswitch,
        };
        // Node k stands for merge k, made at its tree level (leaves: level 0).
        let level = |v: u32| match self.node[v as usize] {
            NONE => 0,
            k => tree.merges[k as usize].level + 1,
        };
        for t in self.display.ones() {
            let tri = tree.triangles[t];
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
        // The display triangles' wedges, numbered in order of use.
        let wedges = src
            .wedges
            .as_ref()
            .zip(tree.corner_wedges.as_ref())
            .map(|(w, cw)| {
                let mut wremap = vec![NONE; w.len()];
                let mut worder = Vec::new();
                let corners = (self.display.ones())
                    .map(|t| {
                        cw[t].map(|x| {
                            if wremap[x as usize] == NONE {
                                wremap[x as usize] = worder.len() as u32;
                                worder.push(x);
                            }
                            wremap[x as usize]
                        })
                    })
                    .collect();
                Wedges::gathered(w, &worder, corners, |v| self.remap[v as usize])
            });
        for &v in &order {
            self.remap[v as usize] = NONE;
        }
        let mesh = TriMesh {
            positions: order.iter().map(|v| src.positions[*v as usize]).collect(),
            normals: gather(&src.normals, &order),
            colors: gather(&src.colors, &order),
            uvs: gather(&src.uvs, &order),
            parts: src.parts.as_ref().map(|p| {
                (self.display.ones())
                    .map(|t| p[tree.origin[t] as usize])
                    .collect()
            }),
            materials: src.materials.clone(),
            wedges,
            payload: src
                .payload
                .as_ref()
                .map(|p| p.pick(order.iter().map(|&v| v as usize))),
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
    fn diagonal(&self) -> f32 {
        self.tree.diagonal
    }

    fn method(&self) -> crate::lod::Method {
        crate::lod::Method::MergeTree
    }

    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet {
        self.update(view, tolerance);
        self.draw_set()
    }

    fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        Some(crate::io::hierarchy_file::save(
            crate::lod::Method::MergeTree.tag(),
            params,
            self.tree().as_ref(),
        ))
    }

    /// The criteria scale the tolerance per node (§3); they never replace it.
    fn controls(&self) -> crate::lod::Controls {
        crate::lod::Controls {
            knobs: &[crate::lod::Knob::Criteria],
            overridden_by: None,
            has_levels: true,
        }
    }

    fn set_knobs(&mut self, knobs: &crate::lod::Knobs) -> bool {
        let changed = self.criteria != knobs.criteria;
        self.criteria = knobs.criteria;
        changed
    }
}
