//! Cuts through the MRG (§4, §6): the arcs between the nodes above (refined
//! away, the source among them) and the nodes below (the drain among them).
//!
//! A node must be refined when its error, seen in its sphere, exceeds the
//! tolerance: object space compares the error with a fraction of the bounding-
//! box diagonal; screen space projects it conservatively with
//! [`View::pixels_f64`] anywhere in the node's sphere grown by the error (the
//! deviation may reach that far), and a node whose grown sphere is outside the
//! view frustum needs no refinement. Node spheres contain their children's and
//! errors never decrease upwards, so "must be refined" is monotone: the cut is
//! exactly {nodes that must be refined} ∪ {source}, found fresh by a traversal
//! from the source, or incrementally (§4, §6) by moving the frontier nodes up
//! (coarsening: an above node whose children are all below and that need not
//! be refined drops below) and down (refining: a below node with all parents
//! above that must be refined goes above). Both give the same cut.

use std::sync::Arc;

use glam::Vec3;

use super::mrg::{DRAIN, Mrg, NodeKind};
use crate::cut::{CutPoint, DrawSet, Hierarchy};
use crate::geom::TriMesh;
use crate::view::{Tolerance, View};

/// A cut of an MRG that adapts from frame to frame.
#[derive(Debug, Clone)]
pub struct HybridCut {
    mrg: Arc<Mrg>,
    above: Vec<bool>,
    /// Below nodes with an above parent (producers of the cut's arcs).
    front: Vec<u32>,
    /// Above nodes whose children are all below.
    bottom: Vec<u32>,
    stamp: Vec<u32>,
    generation: u32,
    primed: bool,
}

/// Whether node `n` must be refined for `view` and `tolerance`.
pub fn must_refine(mrg: &Mrg, n: u32, view: &View, tolerance: Tolerance) -> bool {
    let node = &mrg.nodes[n as usize];
    match node.kind {
        NodeKind::Drain => false,
        NodeKind::Source => true,
        _ => match tolerance {
            Tolerance::Relative(f) => node.error > f * mrg.diagonal,
            Tolerance::Pixels(p) => {
                let reach = node.sphere.radius + node.error;
                view.sees_sphere(node.sphere.center, reach)
                    && view.pixels_f64(node.error as f64, node.sphere.center, reach as f64)
                        > p as f64
            }
        },
    }
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
            front: Vec::new(),
            bottom: Vec::new(),
            stamp: vec![0; n],
            generation: 0,
            primed: false,
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
        let mrg = &*self.mrg;
        self.above.fill(false);
        if mrg.nodes.len() < 2 {
            return;
        }
        let source = mrg.source();
        self.above[source as usize] = true;
        let mut stack = vec![source];
        let mut reached = Vec::new();
        while let Some(n) = stack.pop() {
            for c in mrg.child_nodes(n) {
                if self.above[c as usize] || c == DRAIN {
                    reached.push(c);
                } else if must_refine(mrg, c, view, tolerance) {
                    self.above[c as usize] = true;
                    stack.push(c);
                } else {
                    reached.push(c);
                }
            }
        }
        let all_above: Vec<u32> = (0..mrg.nodes.len() as u32)
            .filter(|n| self.above[*n as usize])
            .collect();
        self.front = reached;
        self.bottom = all_above;
        self.tidy();
        self.primed = true;
    }

    /// Moves the previous cut to `view` and `tolerance` (§4, §6).
    pub fn adapt(&mut self, view: &View, tolerance: Tolerance) {
        if !self.primed {
            return self.select_fresh(view, tolerance);
        }
        let mrg = Arc::clone(&self.mrg);
        let source = mrg.source();
        let refine = |n: u32| must_refine(&mrg, n, view, tolerance);
        // Coarsen: above nodes with all children below that need no refinement.
        let mut lowered = Vec::new();
        let mut stack = self.bottom.clone();
        while let Some(n) = stack.pop() {
            if !self.above[n as usize] || n == source {
                continue;
            }
            if mrg.child_nodes(n).any(|c| self.above[c as usize]) || refine(n) {
                continue;
            }
            self.above[n as usize] = false;
            lowered.push(n);
            stack.extend(mrg.parent_nodes(n));
        }
        // Refine: below nodes with all parents above that must be refined.
        let mut raised = Vec::new();
        let mut stack = self.front.clone();
        stack.extend(&lowered);
        while let Some(n) = stack.pop() {
            if self.above[n as usize] || n == DRAIN || !refine(n) {
                continue;
            }
            if mrg.parent_nodes(n).any(|m| !self.above[m as usize]) {
                continue;
            }
            self.above[n as usize] = true;
            raised.push(n);
            stack.extend(mrg.child_nodes(n));
        }
        if raised.is_empty() && lowered.is_empty() {
            return;
        }
        self.front.extend(&lowered);
        for n in &raised {
            self.front.extend(mrg.child_nodes(*n));
        }
        self.bottom.extend(&raised);
        for n in &lowered {
            self.bottom.extend(mrg.parent_nodes(*n));
        }
        self.tidy();
    }

    /// Keeps only true frontier nodes, once each.
    fn tidy(&mut self) {
        let mrg = &*self.mrg;
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
        let g = self.generation;
        let (above, stamp) = (&self.above, &mut self.stamp);
        self.front.retain(|n| {
            let keep = !above[*n as usize]
                && stamp[*n as usize] != g
                && mrg.parent_nodes(*n).any(|m| above[m as usize]);
            if keep {
                stamp[*n as usize] = g;
            }
            keep
        });
        self.bottom.retain(|n| {
            let keep = above[*n as usize]
                && stamp[*n as usize] != g
                && !mrg.child_nodes(*n).any(|c| above[c as usize]);
            if keep {
                stamp[*n as usize] = g;
            }
            keep
        });
    }

    /// The arcs on the cut.
    pub fn arcs(&self) -> Vec<u32> {
        let mut out: Vec<u32> = self
            .front
            .iter()
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

    /// The cut's primitives (§6).
    pub fn draw_set(&self) -> DrawSet {
        let mrg = &*self.mrg;
        let mut out = DrawSet::default();
        let mut remap = std::collections::HashMap::new();
        let mut mesh = TriMesh::default();
        // The cut's vertices: the MRG's, each taken once.
        let mut order = Vec::new();
        let mut parts = Vec::new();
        for a in self.arcs() {
            let arc = &mrg.arcs[a as usize];
            let error = mrg.nodes[arc.producer as usize].error;
            out.error_bound = out.error_bound.max(error);
            for t in &arc.triangles {
                let tri = mrg.triangles[*t as usize].map(|v| {
                    *remap.entry(v).or_insert_with(|| {
                        order.push(v as usize);
                        order.len() as u32 - 1
                    })
                });
                mesh.triangles.push(tri);
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
        let gather = |a: &[Vec3]| order.iter().map(|&v| a[v]).collect::<Vec<_>>();
        mesh.positions = order.iter().map(|&v| mrg.positions[v]).collect();
        mesh.colors = mrg.colors.as_deref().map(gather);
        mesh.normals = mrg.normals.as_deref().map(gather);
        mesh.uvs = mrg
            .uvs
            .as_ref()
            .map(|u| order.iter().map(|&v| u[v]).collect());
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
    fn method(&self) -> &'static str {
        "hybrid"
    }

    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet {
        self.adapt(view, tolerance);
        self.draw_set()
    }

    fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        Some(crate::io::hierarchy_file::save(
            "hybrid",
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
