//! Progressive edge collapse: the collapse sequence recorded once, down to a
//! floor, as a progressive mesh (Hoppe 1996) whose every prefix carries a
//! certified two-sided Hausdorff bound. The step API's bounds give each
//! collapse's new triangles a guaranteed bound, at least that of every
//! triangle it removed (`step_bounds`), so the mesh after k collapses is
//! within the largest bound among the collapses that made its triangles.
//!
//! A cut is the coarsest prefix within the tolerance (object space, or
//! pixels through the view, projected from the model's bounding sphere);
//! moving from one cut to the next replays or undoes only the collapses in
//! between. A prefix's mesh is what [`super::simplify`] makes when run to
//! its triangle count: the same collapses, gathered the same way.

use std::collections::BinaryHeap;
use std::sync::Arc;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::collapse::{CollapseOptions, EdgeCollapser};
use super::prune::TopologyMode;
use super::step_bounds::run_bounded;
use crate::geom::TriMesh;
use crate::lod::{DrawSet, Hierarchy, PrefixTarget};
use crate::progress::{Cancelled, Progress};
use crate::view::{Tolerance, View};

/// The saved part: what the collapses made, in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Every vertex and triangle the collapses made, the input's first, with
    /// a part per triangle and the wedge corners of every triangle.
    pub history: TriMesh,
    pub input_triangles: u32,
    /// Collapse i removed `removed[removed_end[i-1]..removed_end[i]]` ...
    pub removed: Vec<u32>,
    pub removed_end: Vec<u32>,
    /// ... and made `added[added_end[i-1]..added_end[i]]`.
    pub added: Vec<u32>,
    pub added_end: Vec<u32>,
    /// The certified bound of each collapse's new triangles.
    pub step_bound: Vec<f32>,
    /// Bounding-box diagonal of the input.
    pub diagonal: f32,
}

/// A recorded collapse sequence, ready to cut.
#[derive(Debug, Clone, PartialEq)]
pub struct Progressive {
    record: Record,
    /// Triangles after k collapses, k = 0..=collapses (decreasing).
    prefix_triangles: Vec<u32>,
    /// The certified bound after k collapses (0 for the input).
    prefix_bound: Vec<f32>,
    /// `suffix_min[k]`: the least bound of prefixes k and later (for finding
    /// the coarsest prefix within a tolerance by bisection).
    suffix_min: Vec<f32>,
    /// The collapse that made each triangle (`u32::MAX`: the input's).
    producer: Vec<u32>,
    /// The input's bounding sphere, for pixel tolerances.
    center: Vec3,
    radius: f32,
}

const INPUT: u32 = u32::MAX;

/// The share of the input a record collapses down to unless told otherwise:
/// 0.1 %, past every budget users ask of a progressive mesh.
pub const FLOOR_RATIO: f32 = 0.001;

/// What an edge-collapse hierarchy is built with: the collapses' legality
/// and how far the record goes.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct ProgressiveOptions {
    #[serde(flatten)]
    pub collapse: CollapseOptions,
    /// Record down to this many triangles; `None`: [`FLOOR_RATIO`] of the input.
    pub floor: Option<usize>,
    /// `free`: the record reaches the floor as `simplify_free` does, through
    /// a topology step where pieces or handles stop the collapse
    /// (`prune::record_free`).
    #[serde(skip_serializing_if = "TopologyMode::is_keep")]
    pub topology: TopologyMode,
}

impl ProgressiveOptions {
    pub fn validate(&self) -> Result<(), crate::lod::ParamError> {
        self.collapse.validate()
    }

    /// The triangles a record of `input` triangles stops at.
    pub fn floor(&self, input: usize) -> usize {
        self.floor
            .unwrap_or((f64::from(FLOOR_RATIO) * input as f64) as usize)
    }

    /// Records `mesh`'s collapses down to the floor, cut live.
    pub fn build(&self, mesh: &TriMesh, progress: &Progress) -> Result<ProgressiveCut, Cancelled> {
        let floor = self.floor(mesh.triangles.len());
        let recorded = match self.topology {
            TopologyMode::Keep => record(mesh, self.collapse, floor, progress)?,
            TopologyMode::Free => super::prune::record_free(mesh, self.collapse, floor, progress)?,
        };
        Ok(ProgressiveCut::new(Arc::new(recorded)))
    }
}

/// Collapses `mesh` down to `floor` triangles (or as far as collapses go)
/// with `opts`, as `simplify` would, and bounds every collapse.
pub fn record(
    mesh: &TriMesh,
    opts: CollapseOptions,
    floor: usize,
    progress: &Progress,
) -> Result<Progressive, Cancelled> {
    let n = mesh.triangles.len();
    let mut col = EdgeCollapser::new(mesh, opts);
    let (mut removed, mut removed_end) = (Vec::new(), Vec::new());
    let (mut added, mut added_end) = (Vec::new(), Vec::new());
    progress.stage("collapsing edges");
    let run = run_bounded(
        &mut col,
        mesh,
        floor,
        progress,
        "bounding collapses",
        |s, c| {
            removed.extend_from_slice(&c.removed);
            removed_end.push(removed.len() as u32);
            added.extend_from_slice(&c.added);
            added_end.push(added.len() as u32);
            if s.collapses().is_multiple_of(512) {
                let done = (n - s.triangle_count()) as f32 / n.saturating_sub(floor).max(1) as f32;
                progress.set_fraction(done);
                // The studio shows the mesh as it is simplified.
                if progress.wants_preview() {
                    progress.publish(crate::lod::DrawSet {
                        mesh: s.mesh().0,
                        ..Default::default()
                    });
                }
            }
            true
        },
    )?;
    progress.stage("indexing the record");
    let record = Record {
        history: col.arrays().gather(0..col.triangle_total() as u32),
        input_triangles: n as u32,
        removed,
        removed_end,
        added,
        added_end,
        step_bound: run.bounds,
        diagonal: mesh.bounds().diagonal(),
    };
    Ok(Progressive::new(record).expect("a recorded run is consistent"))
}

impl Progressive {
    /// `mesh` as a record of no collapse.
    pub fn of(mesh: &TriMesh) -> Progressive {
        let record = Record {
            history: mesh.clone(),
            input_triangles: mesh.triangles.len() as u32,
            removed: Vec::new(),
            removed_end: Vec::new(),
            added: Vec::new(),
            added_end: Vec::new(),
            step_bound: Vec::new(),
            diagonal: mesh.bounds().diagonal(),
        };
        Progressive::new(record).expect("a mesh is a consistent record")
    }

    /// This record, then a topology step to `next`'s input (a mesh of the
    /// same parts: pieces pruned, pairs contracted, or the same triangles
    /// recertified), then `next`'s collapses. The step removes every
    /// triangle alive at our last prefix and adds `next`'s input, certified
    /// within `jump` of our input O directly; every triangle after it is
    /// then within `jump` plus its own bound against `next`'s input N of O
    /// (d_H(S, O) ≤ d_H(S, N) + d_H(N, O)), so each of `next`'s step bounds
    /// is raised by `jump`. The step adds every triangle alive after it, so
    /// the prefix bound (the largest among the steps that made the
    /// triangles alive) is `jump` there and the sums after it.
    pub fn then(self, jump: f32, next: Progressive) -> Progressive {
        let last = self.alive_at(self.collapses());
        let mut r = self.record;
        let n = next.record;
        let base = r.history.triangles.len() as u32;
        r.history.append_same_parts(&n.history);
        r.removed
            .extend((0..last.len() as u32).filter(|t| last[*t as usize]));
        r.removed_end.push(r.removed.len() as u32);
        r.added.extend(base..base + n.input_triangles);
        r.added_end.push(r.added.len() as u32);
        r.step_bound.push(jump);
        let (removed, added) = (r.removed.len() as u32, r.added.len() as u32);
        r.removed_end
            .extend(n.removed_end.iter().map(|e| e + removed));
        r.added_end.extend(n.added_end.iter().map(|e| e + added));
        r.removed.extend(n.removed.iter().map(|t| t + base));
        r.added.extend(n.added.iter().map(|t| t + base));
        // Rounded up: a sum of floats may round below the real one.
        let raised = |b: f32| (jump + b) * (1.0 + super::bound::ROUNDING);
        r.step_bound.extend(n.step_bound.iter().map(|b| raised(*b)));
        Progressive::new(r).expect("two consistent records join into one")
    }

    /// Checks a record (one read from a file, say) and derives what cuts need.
    pub fn new(record: Record) -> Result<Self, String> {
        let r = &record;
        let h = &r.history;
        h.check()?;
        let collapses = r.step_bound.len();
        let total = h.triangles.len();
        if r.removed_end.len() != collapses || r.added_end.len() != collapses {
            return Err("collapse lists and bounds differ in length".into());
        }
        if r.input_triangles as usize > total {
            return Err("more input triangles than triangles".into());
        }
        if !(r.diagonal.is_finite() && r.diagonal >= 0.0) {
            return Err("diagonal not finite".into());
        }
        if r.step_bound.iter().any(|b| !(b.is_finite() && *b >= 0.0)) {
            return Err("a collapse bound is not a finite distance".into());
        }
        let ranges = |ends: &[u32], len: usize| -> Result<(), String> {
            let ordered = ends.windows(2).all(|w| w[0] <= w[1]);
            if !ordered || ends.last().map_or(0, |e| *e as usize) != len {
                return Err("collapse lists out of order".into());
            }
            Ok(())
        };
        ranges(&r.removed_end, r.removed.len())?;
        ranges(&r.added_end, r.added.len())?;
        crate::geom::check_indices("triangle", r.removed.iter().copied(), total)?;
        crate::geom::check_indices("triangle", r.added.iter().copied(), total)?;
        // Replay: every removed triangle alive, every added one new, and the
        // alive triangles' bound after each prefix (a lazy max-heap over the
        // collapses that still have triangles alive).
        let mut alive = vec![false; total];
        alive[..r.input_triangles as usize].fill(true);
        let mut born = alive.clone();
        let mut producer = vec![INPUT; total];
        let mut count = vec![0u32; collapses];
        let mut heap: BinaryHeap<(u32, u32)> = BinaryHeap::new();
        let mut prefix_triangles = vec![r.input_triangles];
        let mut prefix_bound = vec![0.0f32];
        let mut triangles = r.input_triangles as i64;
        for i in 0..collapses {
            for &t in range(&r.removed, &r.removed_end, i) {
                if !std::mem::take(&mut alive[t as usize]) {
                    return Err(format!("collapse {i} removes triangle {t}, not alive"));
                }
                if let Some(p) = count.get_mut(producer[t as usize] as usize) {
                    *p -= 1;
                }
            }
            for &t in range(&r.added, &r.added_end, i) {
                if std::mem::replace(&mut born[t as usize], true) {
                    return Err(format!("collapse {i} makes triangle {t} again"));
                }
                alive[t as usize] = true;
                producer[t as usize] = i as u32;
                count[i] += 1;
            }
            triangles += range(&r.added, &r.added_end, i).len() as i64
                - range(&r.removed, &r.removed_end, i).len() as i64;
            // Bounds are non-negative, so their bits order as they do.
            heap.push((r.step_bound[i].to_bits(), i as u32));
            while heap.peek().is_some_and(|(_, j)| count[*j as usize] == 0) {
                heap.pop();
            }
            prefix_triangles.push(triangles as u32);
            prefix_bound.push(heap.peek().map_or(0.0, |(b, _)| f32::from_bits(*b)));
        }
        let mut suffix_min = prefix_bound.clone();
        for k in (0..collapses).rev() {
            suffix_min[k] = suffix_min[k].min(suffix_min[k + 1]);
        }
        let bounds = crate::geom::Aabb::from_points(&h.positions[..]);
        Ok(Progressive {
            prefix_triangles,
            prefix_bound,
            suffix_min,
            producer,
            center: bounds.center(),
            radius: 0.5 * bounds.diagonal(),
            record,
        })
    }

    pub fn record(&self) -> &Record {
        &self.record
    }

    pub fn collapses(&self) -> usize {
        self.record.step_bound.len()
    }

    pub fn diagonal(&self) -> f32 {
        self.record.diagonal
    }

    /// Triangles after `k` collapses.
    pub fn triangles_at(&self, k: usize) -> usize {
        self.prefix_triangles[k] as usize
    }

    /// The certified bound after `k` collapses.
    pub fn bound_at(&self, k: usize) -> f32 {
        self.prefix_bound[k]
    }

    /// The first prefix with at most `n` triangles (where `simplify` run to
    /// `n` stops), or the floor.
    pub fn prefix_for_triangles(&self, n: usize) -> usize {
        let mut k = self
            .prefix_triangles
            .partition_point(|&c| c as usize > n)
            .min(self.collapses());
        // A step that keeps the count (the same triangles recertified,
        // `then`) is taken where it lowers the bound.
        while k < self.collapses()
            && self.prefix_triangles[k + 1] == self.prefix_triangles[k]
            && self.prefix_bound[k + 1] < self.prefix_bound[k]
        {
            k += 1;
        }
        k
    }

    /// The coarsest prefix whose bound `tolerance` accepts for `view`.
    pub fn prefix_within(&self, view: &View, tolerance: Tolerance) -> usize {
        let accepts =
            |e: f32| tolerance.accepts(view, self.record.diagonal, e, self.center, self.radius);
        // `suffix_min` grows with k; the last k it accepts is the last
        // prefix whose own bound is accepted.
        self.suffix_min.partition_point(|e| accepts(*e)).max(1) - 1
    }

    /// The mesh after `k` collapses, as `simplify` makes it.
    pub fn mesh_at(&self, k: usize) -> TriMesh {
        self.gather(&self.alive_at(k))
    }

    fn alive_at(&self, k: usize) -> Vec<bool> {
        let mut alive = vec![false; self.record.history.triangles.len()];
        alive[..self.record.input_triangles as usize].fill(true);
        self.replay(&mut alive, 0, k);
        alive
    }

    /// Moves `alive` from prefix `from` to prefix `to`, replaying collapses
    /// forwards or undoing them backwards.
    fn replay(&self, alive: &mut [bool], from: usize, to: usize) {
        let r = &self.record;
        let mut set = |list: &[u32], ends: &[u32], i: usize, value: bool| {
            for &t in range(list, ends, i) {
                alive[t as usize] = value;
            }
        };
        for i in from..to {
            set(&r.removed, &r.removed_end, i, false);
            set(&r.added, &r.added_end, i, true);
        }
        for i in (to..from).rev() {
            set(&r.added, &r.added_end, i, false);
            set(&r.removed, &r.removed_end, i, true);
        }
    }

    fn gather(&self, alive: &[bool]) -> TriMesh {
        let ids = (0..alive.len() as u32).filter(|t| alive[*t as usize]);
        self.record.history.arrays().gather(ids)
    }

    /// The bound of each triangle's collapse (0 for the input's).
    fn triangle_bound(&self, t: u32) -> f32 {
        self.record
            .step_bound
            .get(self.producer[t as usize] as usize)
            .copied()
            .unwrap_or(0.0)
    }
}

/// Item `i`'s slice of a list stored with its end offsets.
fn range<'a>(list: &'a [u32], ends: &[u32], i: usize) -> &'a [u32] {
    let start = if i == 0 { 0 } else { ends[i - 1] as usize };
    &list[start..ends[i] as usize]
}

/// A progressive mesh cut live: the selected prefix and its alive triangles.
pub struct ProgressiveCut {
    progressive: Arc<Progressive>,
    /// `None`: the view's tolerance chooses.
    pub target: Option<PrefixTarget>,
    at: usize,
    alive: Vec<bool>,
}

impl ProgressiveCut {
    pub fn new(progressive: Arc<Progressive>) -> Self {
        let alive = progressive.alive_at(0);
        ProgressiveCut {
            progressive,
            target: None,
            at: 0,
            alive,
        }
    }

    pub fn progressive(&self) -> &Arc<Progressive> {
        &self.progressive
    }

    /// The prefix a cut for `view` within `tolerance` shows.
    fn prefix_for(&self, view: &View, tolerance: Tolerance) -> usize {
        let p = &self.progressive;
        match self.target {
            Some(PrefixTarget::Triangles(n)) => p.prefix_for_triangles(n),
            None => p.prefix_within(view, tolerance),
        }
    }

    /// The cut after `k` collapses, moved to from the previous one.
    pub fn select_prefix(&mut self, k: usize) -> DrawSet {
        self.move_to(k);
        self.draw_set()
    }

    /// Replays or undoes the collapses between the current prefix and `k`.
    pub fn move_to(&mut self, k: usize) {
        let k = k.min(self.progressive.collapses());
        self.progressive.replay(&mut self.alive, self.at, k);
        self.at = k;
    }

    /// The current prefix's triangles (as `simplify` makes them), each with
    /// the bound of the collapse that made it.
    pub fn draw_set(&self) -> DrawSet {
        let p = &self.progressive;
        let ids: Vec<u32> = (0..self.alive.len() as u32)
            .filter(|t| self.alive[*t as usize])
            .collect();
        DrawSet {
            triangle_errors: ids.iter().map(|t| p.triangle_bound(*t)).collect(),
            mesh: p.record.history.arrays().gather(ids),
            error_bound: p.bound_at(self.at),
            ..Default::default()
        }
    }
}

impl Hierarchy for ProgressiveCut {
    fn method(&self) -> crate::lod::Method {
        crate::lod::Method::EdgeCollapse
    }

    fn diagonal(&self) -> f32 {
        self.progressive.diagonal()
    }

    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet {
        let k = self.prefix_for(view, tolerance);
        self.select_prefix(k)
    }

    /// The selected prefix.
    fn view_key(&self, view: &View, tolerance: Tolerance) -> Option<u64> {
        Some(self.prefix_for(view, tolerance) as u64)
    }

    /// The prefix target, or `None` to follow the tolerance.
    /// A prefix target (ratio, triangles, error) chooses the cut instead of
    /// the tolerance.
    fn controls(&self) -> crate::lod::Controls {
        use crate::lod::Knob;
        crate::lod::Controls {
            knobs: &[Knob::CollapseTarget],
            overridden_by: self.target.map(|_| Knob::CollapseTarget),
            has_levels: true,
        }
    }

    fn set_knobs(&mut self, knobs: &crate::lod::Knobs) -> bool {
        let changed = self.target != knobs.collapse;
        self.target = knobs.collapse;
        changed
    }

    fn select_triangles(&mut self, n: usize) -> Option<DrawSet> {
        let k = self.progressive.prefix_for_triangles(n);
        Some(self.select_prefix(k))
    }

    fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        Some(crate::io::hierarchy_file::save(
            crate::lod::Method::EdgeCollapse.tag(),
            params,
            self.progressive.record(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};
    use crate::simplify::{SimplifyOptions, Target, simplify};

    /// Every prefix is a fresh run to its count, and cuts move both ways.
    #[test]
    fn prefixes_are_fresh_runs_and_cuts_move_both_ways() {
        let mesh = crate::builtins::torus(1.0, 0.3, 24, 12);
        let p = Arc::new(record(&mesh, CollapseOptions::default(), 40, &Progress::new()).unwrap());
        assert!(p.triangles_at(p.collapses()) <= 40);
        let mut cut = ProgressiveCut::new(p.clone());
        for n in [400, 100, 300, 41] {
            let fresh = simplify(
                &mesh,
                &SimplifyOptions {
                    target: Target::Triangles(n),
                    collapse: CollapseOptions::default(),
                    per_triangle_bounds: false,
                },
                &Progress::new(),
            )
            .unwrap();
            let set = cut.select_triangles(n).unwrap();
            assert_eq!(set.mesh, fresh.mesh, "{n} triangles");
            assert_eq!(set.mesh, p.mesh_at(p.prefix_for_triangles(n)));
            let measured = hausdorff_mesh_mesh(&mesh, &set.mesh, &SamplingOptions::default());
            assert!(measured.two_sided() <= set.error_bound, "{n}");
        }
    }

    /// A tolerance selects the coarsest prefix within it, and a tighter one
    /// never a larger bound.
    #[test]
    fn a_tolerance_selects_the_coarsest_prefix_within_it() {
        let mesh = crate::builtins::icosphere(Vec3::ZERO, 1.0, 3);
        let p = record(&mesh, CollapseOptions::default(), 10, &Progress::new()).unwrap();
        let view = View::orbit(Vec3::ZERO, 4.0, 0.3, 0.2);
        let mut last = f32::INFINITY;
        for f in [0.2, 0.05, 0.01, 0.002, 0.0] {
            let k = p.prefix_within(&view, Tolerance::Relative(f));
            let e = f * p.diagonal();
            assert!(p.bound_at(k) <= e, "{f}");
            assert!((k + 1..=p.collapses()).all(|j| p.bound_at(j) > e), "{f}");
            assert!(p.bound_at(k) <= last);
            last = p.bound_at(k);
        }
        assert_eq!(p.prefix_within(&view, Tolerance::Relative(0.0)), 0);
        // Pixels: a farther view allows a coarser prefix.
        let near = p.prefix_within(&view, Tolerance::Pixels(1.0));
        let far = View::orbit(Vec3::ZERO, 40.0, 0.3, 0.2);
        assert!(p.prefix_within(&far, Tolerance::Pixels(1.0)) > near);
    }

    /// A watched record shows the mesh as it is simplified (the studio's
    /// edge-collapse build draws it): a state between the input and the floor.
    #[test]
    fn a_watched_record_publishes_the_mesh_being_simplified() {
        let mesh = crate::builtins::torus(1.0, 0.3, 96, 48);
        let progress = Progress::new();
        progress.watch();
        record(&mesh, CollapseOptions::default(), 100, &progress).unwrap();
        let shown = progress.take_preview().expect("an intermediate mesh");
        let t = shown.mesh.triangles.len();
        assert!(t < mesh.triangles.len() && t >= 100, "{t}");
    }

    /// Hostile records are refused, never replayed.
    #[test]
    fn inconsistent_records_are_refused() {
        let mesh = crate::builtins::torus(1.0, 0.3, 12, 8);
        let p = record(&mesh, CollapseOptions::default(), 20, &Progress::new()).unwrap();
        let mut twice = p.record().clone();
        twice.added[1] = twice.added[0];
        assert!(Progressive::new(twice).is_err());
        let mut dead = p.record().clone();
        dead.removed[0] = dead.added[0];
        assert!(Progressive::new(dead).is_err());
        let mut nan = p.record().clone();
        nan.step_bound[0] = f32::NAN;
        assert!(Progressive::new(nan).is_err());
        let mut short = p.record().clone();
        short.added_end.pop();
        assert!(Progressive::new(short).is_err());
    }
}
