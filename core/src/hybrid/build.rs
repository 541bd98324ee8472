//! Hybrid simplification (§5): edge collapses, point replacement and point
//! simplification, recorded bottom-up as a multi-resolution graph.
//!
//! Queue (§5.1): every operation's optimisation value is cost / benefit, the
//! cost being the increase in error and the benefit the decrease in
//! primitives (triangles + points/κ). An edge collapse costs its deviation
//! from the star it replaces (estimated for the queue as the largest distance
//! of the new star's vertex, edge midpoints and centroids to the old star and
//! of the old endpoints to the new star) and gains the triangles it removes;
//! its value is scaled by the transition factor τ. A point replacement of a
//! triangle costs its point radius and gains 1 − s/κ (§5.3). After a collapse's
//! value is computed, the replacement of each of its triangles is evaluated;
//! if one takes precedence, the collapse leaves the queue (§5). When the queue
//! is empty every remaining triangle is point-replaced (κ > 1), and the points
//! are merged through an octree (§5.4).
//!
//! Guaranteed node bounds. A collapse node's error is the bound the step API
//! gives its collapse (`simplify::step_bounds`: both directions directly
//! against the original O, at least its dependencies' bounds). A point's is
//! r + d(c, O) for its ball of radius r around c (exact distance) and at least
//! its triangle's: a replaced triangle is covered by its balls, and merged
//! balls contain their children, so originals stay within that distance of
//! the points. Errors never decrease upwards.
//! For a cut, every point of a drawn primitive is within its bound of O, and
//! every original point follows its attribution up to the first triangle on
//! the cut, or to a triangle replaced below the cut whose balls (or their
//! merged parents) are on it: so the two-sided Hausdorff distance of any cut
//! is at most its largest node error.

use std::ops::RangeInclusive;
use std::sync::Mutex;

use glam::Vec3;
use rayon::prelude::*;

use super::mrg::{DRAIN, Mrg, NodeKind, Point, Sphere};
use super::{point_replacement, point_simplification};
use crate::distance::facets::Facets;
use crate::geom::TriMesh;
use crate::progress::{Cancelled, Progress};
use crate::simplify::step_bounds::{BoundedRun, run_bounded};
use crate::simplify::{CollapseOptions, EdgeCollapser};

/// The performance ratios κ a build accepts (κ ≤ 1 never replaces triangles
/// by points; each replacement makes at most ⌊κ⌋ points).
pub const KAPPA_RANGE: RangeInclusive<f32> = 0.0..=64.0;
/// The transition factors τ a build accepts: both ends are far past where
/// the curve stops changing (all triangles, or points at once).
pub const TAU_RANGE: RangeInclusive<f32> = 0.01..=100.0;

/// Parameters of the hybrid build (§5.1, §5.3).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct HybridOptions {
    /// Performance ratio κ of points to triangles; κ ≤ 1 never replaces.
    pub kappa: f32,
    /// Transition factor τ scaling the triangle operations' values (≥ 1 introduces points sooner).
    pub tau: f32,
    #[serde(flatten)]
    pub collapse: CollapseOptions,
}

impl Default for HybridOptions {
    /// The paper's κ = 3 (§7) and τ = 1.
    fn default() -> Self {
        Self {
            kappa: 3.0,
            tau: 1.0,
            collapse: CollapseOptions::default(),
        }
    }
}

impl HybridOptions {
    /// Triangle-only simplification with the same collapses and bounds.
    pub fn triangles_only(self) -> Self {
        Self { kappa: 1.0, ..self }
    }

    pub fn validate(&self) -> Result<(), crate::lod::ParamError> {
        use crate::lod::in_range;
        in_range("kappa", self.kappa, &KAPPA_RANGE)?;
        in_range("tau", self.tau, &TAU_RANGE)?;
        self.collapse.validate()
    }
}

/// What the build has made so far (for a live view of the build).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snapshot {
    pub stage: &'static str,
    /// Triangles of the current (coarsest so far) model.
    pub triangles: usize,
    pub points: usize,
    pub nodes: usize,
}

/// Builds the MRG of `mesh` (repaired, as `io::load` returns it).
pub fn build(mesh: &TriMesh, opts: &HybridOptions, progress: &Progress) -> Result<Mrg, Cancelled> {
    build_observed(mesh, opts, progress, |_| {})
}

/// [`build`], calling `observe` with the current counts every so often.
pub fn build_observed(
    mesh: &TriMesh,
    opts: &HybridOptions,
    progress: &Progress,
    mut observe: impl FnMut(&Snapshot),
) -> Result<Mrg, Cancelled> {
    let kappa = if opts.kappa.is_finite() {
        opts.kappa
    } else {
        1.0
    };
    let tau = if opts.tau.is_finite() && opts.tau > 0.0 {
        opts.tau
    } else {
        1.0
    } as f64;
    let n = mesh.triangles.len();
    let mut mrg = Mrg {
        input_triangles: n,
        diagonal: mesh.bounds().diagonal(),
        kappa,
        ..Mrg::default()
    };
    mrg.add_node(NodeKind::Drain, 0.0, Sphere::default());

    // §5.1–5.2: edge collapses in cost/benefit order.
    progress.stage("hybrid: collapsing edges");
    let queue = Mutex::new(QueueScratch::default());
    let cost = move |cand: &crate::simplify::Candidate, col: &EdgeCollapser| {
        let mut guard = queue.lock().unwrap_or_else(|e| e.into_inner());
        let q = &mut *guard;
        col.star_into(cand.edge, &mut q.star);
        // A collapse that removes its whole star (a closed pillow of two
        // triangles) would make a node that produces nothing: the piece stays
        // for point replacement or the source instead of vanishing.
        if q.star.len() <= cand.triangles_removed {
            return f64::INFINITY;
        }
        let value = tau * q.deviation(col, cand) / cand.triangles_removed.max(1) as f64;
        if kappa > 1.0 {
            if q.replacement.len() < col.triangle_total() {
                q.replacement.resize(col.triangle_total(), f64::NAN);
            }
            for t in &q.star {
                let v = &mut q.replacement[*t as usize];
                if v.is_nan() {
                    *v = point_replacement::value(&col.triangle_positions(*t), kappa);
                }
                if *v < value {
                    return f64::INFINITY;
                }
            }
        }
        value
    };
    let mut col = EdgeCollapser::with_star_cost(mesh, opts.collapse, Box::new(cost));
    let mut tri_producer: Vec<u32> = vec![DRAIN; n];
    // The collapse nodes, in collapse order.
    let mut collapse_nodes: Vec<u32> = Vec::new();
    let BoundedRun { bounds, original } = run_bounded(
        &mut col,
        mesh,
        0,
        progress,
        "hybrid: bounding errors",
        |col, c| {
            sync(&mut mrg, col);
            let balls = mrg.balls(&c.added, &[]);
            let mut kids: Vec<u32> = c
                .removed
                .iter()
                .map(|t| tri_producer[*t as usize])
                .collect();
            kids.sort_unstable();
            kids.dedup();
            let sphere = spheres_of(&mrg, balls, &mut kids.iter().copied());
            let node = mrg.add_node(NodeKind::TriangleSimplification, 0.0, sphere);
            tri_producer.resize(col.triangle_total(), DRAIN);
            mrg.consume(node, &c.removed, &[], &tri_producer, &[]);
            for t in &c.added {
                tri_producer[*t as usize] = node;
            }
            collapse_nodes.push(node);
            let count = collapse_nodes.len();
            if count.is_multiple_of(256) && progress.wants_preview() {
                // Watching the build: the triangles left and the points made so far.
                progress.publish(crate::lod::DrawSet {
                    mesh: col.mesh().0,
                    points: mrg
                        .points
                        .iter()
                        .map(|p| crate::lod::CutPoint {
                            center: p.center,
                            radius: p.radius,
                            color: p.color,
                            normal: p.normal,
                            error: p.center_error,
                        })
                        .collect(),
                    ..Default::default()
                });
            }
            if count.is_multiple_of(1024) {
                progress.set_fraction((n - col.triangle_count()) as f32 / n.max(1) as f32);
                observe(&Snapshot {
                    stage: "collapsing edges",
                    triangles: col.triangle_count(),
                    points: 0,
                    nodes: mrg.nodes.len(),
                });
            }
            true
        },
    )?;
    sync(&mut mrg, &col);
    for (node, error) in collapse_nodes.iter().zip(bounds) {
        mrg.nodes[*node as usize].error = error;
    }
    mrg.colors = vertex_attribute(&col, |v| col.color(v));
    mrg.normals = vertex_attribute(&col, |v| col.normal(v));
    mrg.uvs = vertex_attribute(&col, |v| col.uv(v));
    mrg.payload = col.arrays().payload.cloned();
    mrg.materials = col.materials().cloned();
    mrg.wedges = col.wedges().cloned();

    // §5.3: every remaining triangle is point-replaced.
    let remaining: Vec<u32> = col.alive_triangles().collect();
    drop(col);
    let mut point_producer: Vec<u32> = Vec::new();
    let mut point_errors: Vec<f32> = Vec::new();
    let mut top_triangles = Vec::new();
    if kappa > 1.0 {
        progress.stage("hybrid: replacing triangles by points");
        let replacements: Vec<_> = remaining
            .par_iter()
            .map(|t| point_replacement::best(&mrg.triangle_positions(*t), kappa))
            .collect();
        for (k, (t, rep)) in remaining.iter().zip(replacements).enumerate() {
            let Some(rep) = rep else {
                top_triangles.push(*t);
                continue;
            };
            let producer = tri_producer[*t as usize];
            let p = mrg.triangle_positions(*t);
            let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            let colors = mrg
                .colors
                .as_ref()
                .map(|c| mrg.triangles[*t as usize].map(|v| c[v as usize]));
            let first = mrg.points.len() as u32;
            let mut error = mrg.nodes[producer as usize].error;
            for s in &rep.samples {
                let center_error = original.distance().distance(s.center);
                error = error.max((s.radius + center_error) * (1.0 + 1e-5));
                let color = colors.map_or(Vec3::splat(0.8), |c| {
                    c[0] * s.weights[0] + c[1] * s.weights[1] + c[2] * s.weights[2]
                });
                mrg.points.push(Point {
                    center: s.center,
                    radius: s.radius,
                    color,
                    normal,
                    area: s.area,
                    center_error,
                });
            }
            let ids: Vec<u32> = (first..mrg.points.len() as u32).collect();
            let balls = mrg.balls(&[], &ids);
            let sphere = spheres_of(&mrg, balls, &mut std::iter::once(producer));
            let node = mrg.add_node(NodeKind::PointReplacement, error, sphere);
            mrg.consume(node, &[*t], &[], &tri_producer, &[]);
            point_producer.resize(mrg.points.len(), node);
            point_errors.resize(mrg.points.len(), error);
            if k % 4096 == 0 {
                progress.set_fraction(k as f32 / remaining.len() as f32);
                progress.check()?;
                observe(&Snapshot {
                    stage: "replacing triangles by points",
                    triangles: remaining.len() - k,
                    points: mrg.points.len(),
                    nodes: mrg.nodes.len(),
                });
            }
        }
    } else {
        top_triangles = remaining;
    }

    // §5.4: octree merges of the points.
    progress.stage("hybrid: merging points");
    let samples = mrg.points.len();
    let merges = point_simplification::simplify(&mrg.points, &point_errors, &|c| {
        original.distance().distance(c)
    });
    for m in merges {
        let mut balls = vec![Sphere {
            center: m.parent.center,
            radius: m.parent.radius,
        }];
        balls.extend(
            m.children
                .iter()
                .map(|c| mrg.nodes[point_producer[*c as usize] as usize].sphere),
        );
        let node = mrg.add_node(
            NodeKind::PointSimplification,
            m.error,
            Sphere::bounding(&balls),
        );
        mrg.consume(node, &[], &m.children, &tri_producer, &point_producer);
        mrg.points.push(m.parent);
        point_producer.push(node);
    }
    progress.check()?;

    // The source consumes whatever is left: the root point and/or triangles.
    let mut top_points = Vec::new();
    if mrg.points.len() > samples || samples == 1 {
        top_points.push(mrg.points.len() as u32 - 1);
    }
    let mut kids: Vec<u32> = top_triangles
        .iter()
        .map(|t| tri_producer[*t as usize])
        .collect();
    kids.extend(top_points.iter().map(|p| point_producer[*p as usize]));
    kids.sort_unstable();
    kids.dedup();
    let balls = mrg.balls(&top_triangles, &top_points);
    let sphere = spheres_of(&mrg, balls, &mut kids.into_iter());
    let source = mrg.add_node(NodeKind::Source, f32::INFINITY, sphere);
    if !top_triangles.is_empty() || !top_points.is_empty() {
        mrg.consume(
            source,
            &top_triangles,
            &top_points,
            &tri_producer,
            &point_producer,
        );
    }
    observe(&Snapshot {
        stage: "done",
        triangles: top_triangles.len(),
        points: top_points.len(),
        nodes: mrg.nodes.len(),
    });
    debug_assert!(n == 0 || mrg.check().is_ok(), "{:?}", mrg.check());
    Ok(mrg)
}

/// Copies the vertices and triangles the collapser has made since the last call.
fn sync(mrg: &mut Mrg, col: &EdgeCollapser) {
    let (v0, t0) = (mrg.positions.len() as u32, mrg.triangles.len() as u32);
    mrg.positions
        .extend((v0..col.vertex_count() as u32).map(|v| col.position(v)));
    mrg.triangles
        .extend((t0..col.triangle_total() as u32).map(|t| col.triangle(t)));
    mrg.parts
        .extend((t0..col.triangle_total() as u32).map(|t| col.triangle_part(t)));
}

/// One vertex attribute of every vertex the collapser made, if it has it.
fn vertex_attribute<T>(col: &EdgeCollapser, get: impl Fn(u32) -> Option<T>) -> Option<Vec<T>> {
    if col.vertex_count() == 0 {
        return None;
    }
    get(0)?;
    (0..col.vertex_count() as u32).map(get).collect()
}

/// A node's sphere: its own primitives' balls and its non-drain children's spheres.
fn spheres_of(mrg: &Mrg, own: Vec<Sphere>, children: &mut dyn Iterator<Item = u32>) -> Sphere {
    let mut balls = own;
    balls.extend(
        children
            .filter(|c| *c != DRAIN)
            .map(|c| mrg.nodes[c as usize].sphere),
    );
    Sphere::bounding(&balls)
}

/// Buffers of the queue's cost, reused across its calls (about a dozen per
/// collapse).
#[derive(Default)]
struct QueueScratch {
    star: Vec<u32>,
    old: Facets,
    new: Facets,
    /// New triangles' positions.
    made: Vec<[Vec3; 3]>,
    /// Far ends of the new vertex's edges seen so far.
    spokes: Vec<Vec3>,
    /// Point-replacement value per triangle id (NaN until needed; a triangle's
    /// value never changes).
    replacement: Vec<f64>,
}

impl QueueScratch {
    /// Queue estimate of H(new star, old star) for the collapse of `cand`
    /// (the star in `self.star`): a lower bound from the new vertex, the
    /// midpoints of its edges and the centroids of the new triangles against
    /// the old star, and the old endpoints against the new star.
    fn deviation(&mut self, col: &EdgeCollapser, cand: &crate::simplify::Candidate) -> f64 {
        let [a, b] = cand.edge;
        let p = cand.position;
        self.old.clear();
        self.new.clear();
        self.made.clear();
        for &t in &self.star {
            let tri = col.triangle(t);
            let pos = col.triangle_positions(t);
            self.old.push(&pos);
            if !(tri.contains(&a) && tri.contains(&b)) {
                let moved = std::array::from_fn(|k| {
                    if tri[k] == a || tri[k] == b {
                        p
                    } else {
                        pos[k]
                    }
                });
                self.new.push(&moved);
                self.made.push(moved);
            }
        }
        // Each spoke from p is shared by two new triangles: its midpoint once.
        self.spokes.clear();
        let mut worst = self.old.nearest_squared(p);
        for t in &self.made {
            for v in t.iter().filter(|v| **v != p) {
                if !self.spokes.contains(v) {
                    self.spokes.push(*v);
                    worst = worst.max(self.old.nearest_squared((*v + p) * 0.5));
                }
            }
            worst = worst.max(self.old.nearest_squared((t[0] + t[1] + t[2]) / 3.0));
        }
        // The collapsed edge's endpoints are the old vertices that moved.
        for v in [col.position(a), col.position(b)] {
            worst = worst.max(self.new.nearest_squared(v));
        }
        (worst as f64).sqrt()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::builtins::{icosphere, torus};

    /// A sphere and a torus as two parts, with colours.
    pub(crate) fn two_parts() -> TriMesh {
        let mut mesh = icosphere(Vec3::new(3.0, 0.0, 0.0), 1.0, 3);
        mesh.append(&torus(1.0, 0.3, 32, 12));
        mesh.colors = Some(
            mesh.positions
                .iter()
                .map(|p| (p.normalize() + 1.0) * 0.5)
                .collect(),
        );
        mesh
    }

    #[test]
    fn build_makes_a_valid_graph_with_all_three_operations() {
        let mesh = two_parts();
        let mut seen = Vec::new();
        let mrg = build_observed(&mesh, &HybridOptions::default(), &Progress::new(), |s| {
            seen.push(*s)
        })
        .unwrap();
        assert_eq!(mrg.check(), Ok(()));
        assert!(mrg.count(NodeKind::TriangleSimplification) > 100);
        assert!(mrg.count(NodeKind::PointReplacement) > 0);
        assert!(mrg.count(NodeKind::PointSimplification) > 0);
        // One root point at the top: everything ends as points.
        let top = &mrg.nodes[mrg.source() as usize];
        assert_eq!(top.children.len(), 1);
        assert_eq!(mrg.arcs[top.children[0] as usize].points.len(), 1);
        assert_eq!(seen.last().map(|s| s.points), Some(1));
        // Point replacement never makes more than ⌊κ⌋ points from a triangle.
        for n in mrg
            .nodes
            .iter()
            .filter(|n| n.kind == NodeKind::PointReplacement)
        {
            let pts: usize = n
                .parents
                .iter()
                .map(|a| mrg.arcs[*a as usize].points.len())
                .sum();
            assert!((1..=3).contains(&pts));
        }
        // Colours are interpolated into the points.
        assert!(mrg.points.iter().any(|p| p.color != Vec3::splat(0.8)));
    }

    /// Fig. 9 trend: κ ≤ 1 never replaces; a larger κ allows more, finer
    /// samples, so points appear on cuts at smaller errors, and with τ = 5 point
    /// replacement takes precedence over more collapses.
    #[test]
    fn kappa_at_most_one_makes_no_points_and_larger_kappa_switches_sooner() {
        let mesh = two_parts();
        let run = |kappa, tau| {
            let opts = HybridOptions {
                kappa,
                tau,
                ..Default::default()
            };
            let mrg = build(&mesh, &opts, &Progress::new()).unwrap();
            assert_eq!(mrg.check(), Ok(()));
            let first_points = mrg
                .nodes
                .iter()
                .filter(|n| n.kind == NodeKind::PointReplacement)
                .map(|n| n.error)
                .fold(f32::INFINITY, f32::min);
            (
                mrg.count(NodeKind::PointReplacement),
                first_points,
                mrg.points.len(),
            )
        };
        let (pr, _, points) = run(1.0, 1.0);
        assert_eq!((pr, points), (0, 0));
        let (_, e2, _) = run(2.0, 1.0);
        let (_, e3, _) = run(3.0, 1.0);
        let (_, e8, _) = run(8.0, 1.0);
        assert!(
            e2 >= e3 && e3 >= e8 && e2 > e8,
            "first point errors {e2} {e3} {e8}"
        );
        let (p2, _, _) = run(2.0, 5.0);
        let (p8, _, _) = run(8.0, 5.0);
        assert!(p2 < p8, "replaced triangles {p2} {p8}");
    }

    /// Cancelling mid-collapse, with waves still queued for the bounding
    /// worker, stops the build (the worker must not be left waiting).
    #[test]
    fn cancel_while_the_bounds_run_behind_stops_the_build() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 5);
        let progress = std::sync::Arc::new(Progress::new());
        let watcher = {
            let p = progress.clone();
            std::thread::spawn(move || {
                while p.fraction() < 0.3 {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                }
                p.cancel();
            })
        };
        let r = build(&mesh, &HybridOptions::default(), &progress);
        watcher.join().unwrap();
        assert!(r.is_err());
        assert_eq!(progress.stage_name(), "hybrid: collapsing edges");
    }

    /// Two triangles on the same three vertices (a closed "pillow", the
    /// smallest closed surface; fuzz find) still make a valid graph.
    #[test]
    fn a_pillow_of_two_triangles_makes_a_valid_graph() {
        for scale in [1.0, 2.2e18] {
            let p = [Vec3::ZERO, Vec3::X * scale, Vec3::Y * scale];
            let mesh = TriMesh::new(p.to_vec(), vec![[0, 1, 2], [0, 2, 1]]);
            let mrg = build(&mesh, &HybridOptions::default(), &Progress::new()).unwrap();
            assert_eq!(mrg.check(), Ok(()), "scale {scale}");
        }
    }

    #[test]
    fn cancel_stops_the_build() {
        let progress = Progress::new();
        progress.cancel();
        assert!(
            build(
                &icosphere(Vec3::ZERO, 1.0, 4),
                &HybridOptions::default(),
                &progress
            )
            .is_err()
        );
    }
}

#[cfg(test)]
mod watched {
    use super::*;

    /// A watched build publishes its primitives as they appear.
    #[test]
    fn watched_builds_publish_triangles_and_points() {
        let mesh = crate::builtins::torus(1.0, 0.3, 48, 24);
        let progress = Progress::new();
        progress.watch();
        let opts = HybridOptions {
            kappa: 8.0,
            tau: 5.0,
            ..Default::default()
        };
        build(&mesh, &opts, &progress).unwrap();
        let state = progress.take_preview().expect("an intermediate state");
        let n = state.mesh.triangles.len();
        assert!(n > 0 && n < mesh.triangles.len(), "{n}");
    }
}
