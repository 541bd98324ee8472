//! Cuts through the MRG (§4, §6): the arcs between the nodes above (refined
//! away, the source among them) and the nodes below (the drain among them).
//!
//! A node must be refined when its error, seen in its sphere, exceeds the
//! tolerance: object space compares the error with a fraction of the bounding-
//! box diagonal; screen space projects it conservatively
//! ([`View::pixels_f64`], via [`SphereTest`]) anywhere in the node's sphere
//! grown by the error (the deviation may reach that far), and a node whose
//! grown sphere is outside the view frustum needs no refinement. Node spheres contain their children's and
//! errors never decrease upwards, so "must be refined" is monotone: the cut is
//! exactly {nodes that must be refined} ∪ {source}, found fresh by a traversal
//! from the source, or incrementally (§4, §6) by moving the frontier nodes up
//! (coarsening: an above node whose children are all below and that need not
//! be refined drops below) and down (refining: a below node with all parents
//! above that must be refined goes above). Both give the same cut.

use std::sync::Arc;

use glam::Vec3;

use super::mrg::{DRAIN, Mrg, NodeKind};
use crate::geom::{TriMesh, Wedges};
use crate::id_set::{Columns, IdSet};
use crate::lod::{CutPoint, DrawSet, Hierarchy};
use crate::view::{NarrowTest, SphereTest, Tolerance, View};

/// What the refinement test reads of a node.
#[derive(Debug, Clone, Copy)]
struct Probe {
    kind: NodeKind,
    center: Vec3,
    /// The sphere's radius plus the error: how far the deviation may reach.
    reach: f32,
    error: f32,
}

impl Probe {
    fn of(mrg: &Mrg, n: u32) -> Probe {
        let node = &mrg.nodes[n as usize];
        Probe {
            kind: node.kind,
            center: node.sphere.center,
            reach: node.sphere.radius + node.error,
            error: node.error,
        }
    }

    /// The exact test (double precision, [`SphereTest`]).
    #[inline(always)]
    fn must_refine(&self, test: &SphereTest, tolerance: Tolerance, diagonal: f32) -> bool {
        let refines = match tolerance {
            Tolerance::Relative(f) => self.error > f * diagonal,
            Tolerance::Pixels(p) => {
                test.sees(self.center, self.reach)
                    & test.exceeds(self.error as f64, self.center, self.reach as f64, p as f64)
            }
        };
        self.settled(refines)
    }

    /// The source is always refined, the drain never.
    #[inline(always)]
    fn settled(&self, refines: bool) -> bool {
        (self.kind == NodeKind::Source) | (refines & (self.kind != NodeKind::Drain))
    }
}

/// The front's or bottom's copies of their probes, a column per number, so
/// that one pass over a set loads eight nodes per instruction.
#[derive(Debug, Clone, Default)]
struct Probes {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    reach: Vec<f32>,
    error: Vec<f32>,
    kind: Vec<NodeKind>,
}

impl Probes {
    fn row(&self, i: usize) -> Probe {
        Probe {
            kind: self.kind[i],
            center: Vec3::new(self.x[i], self.y[i], self.z[i]),
            reach: self.reach[i],
            error: self.error[i],
        }
    }
}

impl Columns for Probes {
    type Row = Probe;
    fn push(&mut self, p: Probe) {
        self.x.push(p.center.x);
        self.y.push(p.center.y);
        self.z.push(p.center.z);
        self.reach.push(p.reach);
        self.error.push(p.error);
        self.kind.push(p.kind);
    }
    fn swap_remove(&mut self, i: usize) {
        self.x.swap_remove(i);
        self.y.swap_remove(i);
        self.z.swap_remove(i);
        self.reach.swap_remove(i);
        self.error.swap_remove(i);
        self.kind.swap_remove(i);
    }
    fn clear(&mut self) {
        for c in [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.reach,
            &mut self.error,
        ] {
            c.clear();
        }
        self.kind.clear();
    }
}

/// A cut of an MRG that adapts from frame to frame.
#[derive(Debug, Clone)]
pub struct HybridCut {
    mrg: Arc<Mrg>,
    above: Vec<bool>,
    /// Below nodes with an above parent (producers of the cut's arcs).
    front: IdSet<Probes>,
    /// Above nodes whose children are all below.
    bottom: IdSet<Probes>,
    /// Per-frame scratch: the walk's stack, the nodes that moved, one pass's
    /// tests and the nodes they picked.
    stack: Vec<u32>,
    moved: Vec<u32>,
    flags: Vec<u8>,
    pending: Vec<u32>,
    primed: bool,
    /// The draw set's scratch: each MRG vertex's number in the cut (or
    /// `u32::MAX`), and the vertices numbered.
    remap: Vec<u32>,
    order: Vec<u32>,
    /// The same for the cut's wedges.
    wedge_remap: Vec<u32>,
    wedge_order: Vec<u32>,
    /// The last frame's view constants, whose projection part the next frame
    /// reuses when the lens is the same.
    last_test: Option<SphereTest>,
}

/// Tests every node of `set` and puts those whose answer is `want` (0 or 1)
/// into `picked`: one vector pass ([`crate::simd::wide`]) in single
/// precision ([`NarrowTest`]), then the exact test for the few it leaves
/// unsure. Few nodes change their answer in a frame, so the flags are
/// scanned eight at a time. The flags' buffer only grows: the pass writes
/// every one it reads.
fn tested(
    set: &IdSet<Probes>,
    (test, narrow, tolerance, diagonal): (&SphereTest, &NarrowTest, Tolerance, f32),
    (flags, picked): (&mut Vec<u8>, &mut Vec<u32>),
    want: u8,
) {
    let p = &set.values;
    let n = set.items.len();
    if flags.len() < n {
        flags.resize(n, 0);
    }
    let flags = &mut flags[..n];
    let columns = (
        &p.x[..n],
        &p.y[..n],
        &p.z[..n],
        &p.reach[..n],
        &p.error[..n],
        &p.kind[..n],
    );
    crate::simd::wide(
        &columns,
        flags,
        #[inline(always)]
        |&(x, y, z, reach, error, kind), flags| {
            // Slices of one length, so that the loops run without bounds
            // checks.
            let n = flags.len();
            let (x, y, z, reach, error, kind) = (
                &x[..n],
                &y[..n],
                &z[..n],
                &reach[..n],
                &error[..n],
                &kind[..n],
            );
            // 1 where the answer is `want`, UNSURE where the exact test must
            // decide, 0 elsewhere; the source and drain are settled.
            let flag = |i: usize, answer: u8| {
                let (source, drain) = (kind[i] == NodeKind::Source, kind[i] == NodeKind::Drain);
                let answer = if source | drain {
                    u8::from(source)
                } else {
                    answer
                };
                (answer & NarrowTest::UNSURE) | u8::from(answer == want)
            };
            match tolerance {
                Tolerance::Relative(f) => {
                    for i in 0..n {
                        flags[i] = flag(i, u8::from(error[i] > f * diagonal));
                    }
                }
                Tolerance::Pixels(px) => {
                    for i in 0..n {
                        let answer = narrow.refines([x[i], y[i], z[i]], reach[i], error[i], px);
                        flags[i] = flag(i, answer);
                    }
                }
            }
        },
    );
    picked.clear();
    let mut pick = |i: usize, f: u8| {
        if f == 1 || u8::from(p.row(i).must_refine(test, tolerance, diagonal)) == want {
            picked.push(set.items[i]);
        }
    };
    let words = flags.chunks_exact(8);
    let tail = 8 * words.len();
    for (k, word) in words.enumerate() {
        if u64::from_ne_bytes(word.try_into().expect("8 flags")) != 0 {
            let flagged = word.iter().enumerate().filter(|(_, f)| **f != 0);
            flagged.for_each(|(j, f)| pick(8 * k + j, *f));
        }
    }
    let flagged = flags[tail..].iter().enumerate().filter(|(_, f)| **f != 0);
    flagged.for_each(|(j, f)| pick(tail + j, *f));
}

/// Whether node `n` must be refined for the view of `test` and `tolerance`.
pub fn must_refine(mrg: &Mrg, n: u32, test: &SphereTest, tolerance: Tolerance) -> bool {
    Probe::of(mrg, n).must_refine(test, tolerance, mrg.diagonal)
}

/// Screen radius of a point primitive in pixels (§6: the same scale as errors).
pub fn point_pixels(view: &View, p: &CutPoint) -> f32 {
    view.pixels(p.radius, p.center, p.radius)
}

impl HybridCut {
    pub fn new(mrg: Arc<Mrg>) -> Self {
        let n = mrg.nodes.len();
        HybridCut {
            mrg,
            above: vec![false; n],
            front: IdSet::new(n),
            bottom: IdSet::new(n),
            stack: Vec::new(),
            moved: Vec::new(),
            flags: Vec::new(),
            pending: Vec::new(),
            primed: false,
            remap: Vec::new(),
            order: Vec::new(),
            wedge_remap: Vec::new(),
            wedge_order: Vec::new(),
            last_test: None,
        }
    }

    pub fn mrg(&self) -> &Arc<Mrg> {
        &self.mrg
    }

    /// Which nodes are above the cut.
    pub fn above(&self) -> &[bool] {
        &self.above
    }

    /// The cut from scratch: a traversal down from the source.
    pub fn select_fresh(&mut self, view: &View, tolerance: Tolerance) {
        let mrg = Arc::clone(&self.mrg);
        self.above.fill(false);
        self.front.clear();
        self.bottom.clear();
        if mrg.nodes.len() < 2 {
            return;
        }
        let source = mrg.source();
        self.above[source as usize] = true;
        let test = view.sphere_test_after(self.last_test.as_ref());
        // Every node the traversal raises, in `moved`; children it reaches
        // that stay below are the front.
        self.moved.clear();
        self.moved.push(source);
        self.stack.clear();
        self.stack.push(source);
        while let Some(n) = self.stack.pop() {
            for c in mrg.child_nodes(n) {
                if self.above[c as usize] {
                    continue;
                }
                if c != DRAIN && must_refine(&mrg, c, &test, tolerance) {
                    self.above[c as usize] = true;
                    self.moved.push(c);
                    self.stack.push(c);
                } else {
                    self.front.set(c, true, || Probe::of(&mrg, c));
                }
            }
        }
        for i in 0..self.moved.len() {
            let n = self.moved[i];
            self.bottom.set(n, self.in_bottom(n), || Probe::of(&mrg, n));
        }
        self.primed = true;
        self.last_test = Some(test);
    }

    /// Moves the previous cut to `view` and `tolerance` (§4, §6).
    pub fn adapt(&mut self, view: &View, tolerance: Tolerance) {
        if !self.primed {
            return self.select_fresh(view, tolerance);
        }
        let mrg = Arc::clone(&self.mrg);
        let source = mrg.source();
        let test = view.sphere_test_after(self.last_test.as_ref());
        let refine = |n: u32| must_refine(&mrg, n, &test, tolerance);
        self.moved.clear();
        self.stack.clear();
        // Coarsen: above nodes with all children below that need no
        // refinement. The bottom's tests run in one pass over its copies (its
        // nodes have no above child), the parents they uncover one by one.
        let narrow = test.narrow();
        let at = (&test, &narrow, tolerance, mrg.diagonal);
        tested(&self.bottom, at, (&mut self.flags, &mut self.pending), 0);
        for i in 0..self.pending.len() {
            let n = self.pending[i];
            if n != source {
                self.lower(n);
            }
        }
        while let Some(n) = self.stack.pop() {
            if self.above[n as usize]
                && n != source
                && !mrg.child_nodes(n).any(|c| self.above[c as usize])
                && !refine(n)
            {
                self.lower(n);
            }
        }
        // Refine: below nodes with all parents above that must be refined;
        // likewise the front in one pass, the rest one by one.
        let lowered = self.moved.len();
        tested(&self.front, at, (&mut self.flags, &mut self.pending), 1);
        for i in 0..self.pending.len() {
            self.raise(self.pending[i]);
        }
        self.stack.extend_from_slice(&self.moved[..lowered]);
        while let Some(n) = self.stack.pop() {
            if !self.above[n as usize] && n != DRAIN && refine(n) {
                self.raise(n);
            }
        }
        // A node's place in the front depends on it and its parents, in the
        // bottom on it and its children: only those around a moved node change.
        for i in 0..self.moved.len() {
            let n = self.moved[i];
            let around = std::iter::once(n)
                .chain(mrg.child_nodes(n))
                .chain(mrg.parent_nodes(n));
            for m in around {
                self.front.set(m, self.in_front(m), || Probe::of(&mrg, m));
                self.bottom.set(m, self.in_bottom(m), || Probe::of(&mrg, m));
            }
        }
        self.last_test = Some(test);
    }

    /// Lowers above node `n`, which need not be refined and has no above
    /// child; its parents join the walk.
    fn lower(&mut self, n: u32) {
        self.above[n as usize] = false;
        self.moved.push(n);
        self.stack.extend(self.mrg.parent_nodes(n));
    }

    /// Raises below node `n`, which must be refined, if all its parents are
    /// above; its children join the walk.
    fn raise(&mut self, n: u32) {
        let mrg = &*self.mrg;
        if self.above[n as usize] || mrg.parent_nodes(n).any(|m| !self.above[m as usize]) {
            return;
        }
        self.above[n as usize] = true;
        self.moved.push(n);
        self.stack.extend(mrg.child_nodes(n));
    }

    fn in_front(&self, n: u32) -> bool {
        !self.above[n as usize] && self.mrg.parent_nodes(n).any(|m| self.above[m as usize])
    }

    fn in_bottom(&self, n: u32) -> bool {
        self.above[n as usize] && !self.mrg.child_nodes(n).any(|c| self.above[c as usize])
    }

    /// The arcs on the cut.
    pub fn arcs(&self) -> Vec<u32> {
        let mut out: Vec<u32> = (self.front.items.iter())
            .flat_map(|n| self.mrg.nodes[*n as usize].parents.iter().copied())
            .filter(|a| self.above[self.mrg.arcs[*a as usize].consumer as usize])
            .collect();
        out.sort_unstable();
        out
    }

    /// Triangles and points on the cut.
    pub fn counts(&self) -> (usize, usize) {
        self.arcs().iter().fold((0, 0), |(t, p), a| {
            let a = &self.mrg.arcs[*a as usize];
            (t + a.triangles.len(), p + a.points.len())
        })
    }

    /// The cut's primitives (§6). Per frame: the cut's vertices are numbered
    /// through a table kept from frame to frame (reset where it was written),
    /// not a hash map, and the outputs are sized once.
    pub fn draw_set(&mut self) -> DrawSet {
        let mrg = &*self.mrg;
        let arcs = self.arcs();
        let (nt, np) = arcs.iter().fold((0, 0), |(t, p), a| {
            let a = &mrg.arcs[*a as usize];
            (t + a.triangles.len(), p + a.points.len())
        });
        let mut out = DrawSet::default();
        let mut mesh = TriMesh::default();
        mesh.triangles.reserve(nt);
        out.triangle_errors.reserve(nt);
        out.points.reserve(np);
        let mut parts = Vec::with_capacity(nt);
        let remap = &mut self.remap;
        remap.resize(mrg.positions.len(), u32::MAX);
        // Its wedges the same way, when the input has seams.
        let (wedge_remap, wedge_order) = (&mut self.wedge_remap, &mut self.wedge_order);
        wedge_order.clear();
        let mut corners = Vec::new();
        if let Some(w) = &mrg.wedges {
            wedge_remap.resize(w.len(), u32::MAX);
            corners.reserve(nt);
        }
        // The cut's vertices: the MRG's, each taken once.
        let order = &mut self.order;
        order.clear();
        for a in arcs {
            let arc = &mrg.arcs[a as usize];
            let error = mrg.nodes[arc.producer as usize].error;
            out.error_bound = out.error_bound.max(error);
            for t in &arc.triangles {
                let tri = mrg.triangles[*t as usize].map(|v| {
                    let slot = &mut remap[v as usize];
                    if *slot == u32::MAX {
                        *slot = order.len() as u32;
                        order.push(v);
                    }
                    *slot
                });
                mesh.triangles.push(tri);
                if let Some(w) = &mrg.wedges {
                    corners.push(w.corners[*t as usize].map(|x| {
                        let slot = &mut wedge_remap[x as usize];
                        if *slot == u32::MAX {
                            *slot = wedge_order.len() as u32;
                            wedge_order.push(x);
                        }
                        *slot
                    }));
                }
                parts.push(mrg.parts.get(*t as usize).copied().unwrap_or(0));
                out.triangle_errors.push(error);
            }
            out.points.extend(arc.points.iter().map(|p| {
                let p = &mrg.points[*p as usize];
                CutPoint {
                    center: p.center,
                    radius: p.radius,
                    color: p.color,
                    normal: p.normal,
                    error,
                }
            }));
        }
        mesh.wedges = mrg
            .wedges
            .as_ref()
            .map(|w| Wedges::gathered(w, wedge_order, corners, |v| remap[v as usize]));
        for &v in order.iter() {
            remap[v as usize] = u32::MAX;
        }
        for &x in wedge_order.iter() {
            wedge_remap[x as usize] = u32::MAX;
        }
        let gather = |a: &[Vec3]| order.iter().map(|&v| a[v as usize]).collect::<Vec<_>>();
        mesh.positions = order.iter().map(|&v| mrg.positions[v as usize]).collect();
        mesh.colors = mrg.colors.as_deref().map(gather);
        mesh.normals = mrg.normals.as_deref().map(gather);
        mesh.uvs = mrg
            .uvs
            .as_ref()
            .map(|u| order.iter().map(|&v| u[v as usize]).collect());
        mesh.payload = mrg
            .payload
            .as_ref()
            .map(|p| p.pick(order.iter().map(|&v| v as usize)));
        mesh.parts = parts.iter().any(|p| *p != 0).then_some(parts);
        mesh.materials = mrg.materials.clone();
        out.mesh = mesh;
        out
    }

    /// The point centres and radii of a draw set (for distance measurement).
    pub fn spheres(points: &[CutPoint]) -> (Vec<Vec3>, Vec<f32>) {
        points.iter().map(|p| (p.center, p.radius)).unzip()
    }
}

impl Hierarchy for HybridCut {
    fn diagonal(&self) -> f32 {
        self.mrg.diagonal
    }

    fn method(&self) -> crate::lod::Method {
        crate::lod::Method::Hybrid
    }

    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet {
        self.adapt(view, tolerance);
        self.draw_set()
    }

    fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        Some(crate::io::hierarchy_file::save(
            crate::lod::Method::Hybrid.tag(),
            params,
            self.mrg().as_ref(),
        ))
    }

    /// Object-space cuts do not depend on the view.
    fn view_key(&self, _view: &View, tolerance: Tolerance) -> Option<u64> {
        matches!(tolerance, Tolerance::Relative(_)).then_some(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::{icosphere, torus};
    use crate::distance::{SamplingOptions, hausdorff_mesh_spheres};
    use crate::hybrid::{HybridOptions, build};
    use crate::progress::Progress;
    use crate::rng::Rng;

    fn random_view(rng: &mut Rng, center: Vec3, diag: f32) -> (View, Tolerance) {
        let dist = diag * (0.05 + 20.0 * rng.f32() * rng.f32());
        let mut view = View::orbit(center, dist, rng.f32() * 6.3, rng.f32() * 3.0 - 1.5);
        view.target = center + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * diag;
        let tol = if rng.below(3) == 0 {
            Tolerance::Relative(0.4 * rng.f32() * rng.f32())
        } else {
            Tolerance::Pixels(0.5 + 100.0 * rng.f32() * rng.f32())
        };
        (view, tol)
    }

    fn models() -> Vec<TriMesh> {
        let mut bumpy = icosphere(Vec3::ZERO, 1.0, 3);
        for p in &mut bumpy.positions {
            *p *= 1.0 + 0.15 * (5.0 * p.x).sin() * (4.0 * p.y).cos();
        }
        vec![
            crate::hybrid::build::tests::two_parts(),
            torus(1.0, 0.4, 24, 12),
            bumpy,
        ]
    }

    /// 1,000 random views and tolerances per model: the cut is upward closed,
    /// covers the surface exactly once (random weights per original triangle
    /// add up), and adapting incrementally gives the cut of a fresh traversal.
    #[test]
    fn cuts_cover_once_and_incremental_equals_fresh() {
        let mut rng = Rng::new(21);
        for (k, mesh) in models().into_iter().enumerate() {
            let opts = HybridOptions {
                tau: [1.0, 5.0, 1.0][k],
                ..Default::default()
            };
            let mrg = Arc::new(build(&mesh, &opts, &Progress::new()).unwrap());
            let weights: Vec<f64> = (0..mesh.triangles.len())
                .map(|_| 0.5 + rng.f32() as f64)
                .collect();
            let total: f64 = weights.iter().sum();
            let (tri_w, pt_w) = mrg.represented(&weights);
            let (center, diag) = (mesh.bounds().center(), mrg.diagonal);
            let mut moving = HybridCut::new(Arc::clone(&mrg));
            let mut fresh = HybridCut::new(Arc::clone(&mrg));
            let mut kinds = [0usize; 3];
            for _ in 0..1000 {
                let (view, tol) = random_view(&mut rng, center, diag);
                moving.adapt(&view, tol);
                fresh.select_fresh(&view, tol);
                assert_eq!(
                    moving.above(),
                    fresh.above(),
                    "incremental differs from fresh"
                );
                assert_eq!(moving.arcs(), fresh.arcs());
                for (i, a) in mrg.arcs.iter().enumerate() {
                    if moving.above()[a.producer as usize] {
                        assert!(
                            moving.above()[a.consumer as usize],
                            "not upward closed at arc {i}"
                        );
                    }
                }
                let mut covered = 0.0;
                for a in moving.arcs() {
                    let a = &mrg.arcs[a as usize];
                    covered += a.triangles.iter().map(|t| tri_w[*t as usize]).sum::<f64>();
                    covered += a.points.iter().map(|p| pt_w[*p as usize]).sum::<f64>();
                }
                assert!(
                    (covered - total).abs() <= 1e-9 * total,
                    "{covered} vs {total}"
                );
                let (t, p) = moving.counts();
                kinds[usize::from(t > 0) + usize::from(p > 0 && t > 0)] += 1;
                // Within tolerance: every drawn primitive's error passes (Relative).
                if let Tolerance::Relative(f) = tol {
                    let set = moving.draw_set();
                    assert!(set.error_bound <= f * diag || set.primitive_count() <= 1);
                }
            }
            assert!(
                kinds[2] > 0,
                "some cuts mix triangles and points: {kinds:?}"
            );
        }
    }

    /// The cut's bound holds against an independent two-sided Hausdorff
    /// measurement (points as solid balls).
    #[test]
    fn cut_bound_holds_against_measured_hausdorff() {
        let mesh = crate::hybrid::build::tests::two_parts();
        let mrg = Arc::new(build(&mesh, &HybridOptions::default(), &Progress::new()).unwrap());
        let mut cut = HybridCut::new(Arc::clone(&mrg));
        let sampling = SamplingOptions {
            samples: 40_000,
            seed: 3,
        };
        let mut mixed = 0;
        for f in [0.0, 0.002, 0.005, 0.01, 0.02, 0.04, 0.08, 0.2] {
            let view = View::orbit(Vec3::ZERO, 5.0, 0.0, 0.0);
            let set = cut.select(&view, Tolerance::Relative(f));
            let (centers, radii) = HybridCut::spheres(&set.points);
            let measured =
                hausdorff_mesh_spheres(&mesh, &set.mesh, &centers, &radii, &sampling).two_sided();
            // The measurement's own f32 round-off (the f = 0 cut is the input).
            let noise = 1e-6 * mrg.diagonal;
            assert!(
                measured <= set.error_bound + noise,
                "f {f}: measured {measured} > bound {}",
                set.error_bound
            );
            assert!(set.error_bound <= f * mrg.diagonal || f == 0.2);
            mixed += usize::from(!set.points.is_empty() && !set.mesh.triangles.is_empty());
        }
        assert!(mixed > 0);
    }
}
