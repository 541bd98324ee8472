//! The guaranteed bound of every collapse, for the step API: after collapse
//! i, each of its new triangles is within `bounds[i]` (two-sided Hausdorff)
//! of the part of the original surface it stands for, and `bounds[i]` is at
//! least the bound of every collapse that made a triangle it removed. So the
//! mesh after any number of steps is within the largest bound of the
//! collapses that made its triangles (originals are exact). The hybrid MRG
//! stores these as its collapse nodes' errors (§4, §5.2).
//!
//! Each direction is bounded directly against the original O, not
//! accumulated step by step (a triangle-inequality bound, H(new star, old
//! star) + the old star's bound, adds up along every chain of collapses: on
//! an icosphere it passed 70% of the diagonal before the triangles ran out):
//! - new triangle → O: the branch and bound of `bound::max_distance_bound`
//!   (Cohen et al.'s planar projection, else O's BVH);
//! - O → new triangle: every piece of O belongs to one triangle of each mesh
//!   it passes through, which bounds its distance (module `attribution`).
//!
//! A collapse's bound only needs what it and the collapses before it made, so
//! [`run_bounded`] bounds each finished wave of [`WAVE`] collapses on a
//! worker (its triangles in parallel, and the pieces of collapses that do
//! not build on each other) while the collapser makes the next.
//! A triangle's branch and bound stops once it cannot raise its collapse's
//! bound (below the largest exact distance found under the collapse, or a
//! bound of an earlier wave it builds on): every bound is still a true upper
//! bound, and refining further could not lower any collapse's.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::attribution::{Attribution, Handover};
use super::bound::{BoundOptions, Original, max_distance_bound};
use super::collapse::{Collapse, EdgeCollapser};
use super::projection::Projection;
use crate::distance::MeshDistance;
use crate::geom::TriMesh;
use crate::progress::{Cancelled, Progress};

/// Collapses per wave. A triangle's refinement stops below the bound of a
/// collapse from an earlier wave, so the waves' size is part of the result.
pub const WAVE: usize = 1024;

/// Made by no collapse: a triangle of the input.
const INPUT: u32 = u32::MAX;

/// One collapse as the bounds need it.
struct Recorded {
    removed: Vec<u32>,
    added: Vec<u32>,
    /// The collapses that made `removed` (its dependencies), deduplicated.
    kids: Vec<u32>,
}

/// Up to [`WAVE`] collapses in order, with the vertices and triangles made
/// since the previous wave (the first wave brings the input's too).
struct Wave {
    collapses: Vec<Recorded>,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

/// A bounded run: every collapse's bound, and the original's search
/// structures (for more measurements against it).
pub struct BoundedRun<'a> {
    pub bounds: Vec<f32>,
    pub original: Original<'a>,
}

/// Runs `col`, made from `mesh`, down to `target` triangles (as
/// [`EdgeCollapser::run`]; `on_step` sees every collapse and may stop the
/// run by returning false) and bounds every collapse (module doc) on a
/// worker a wave behind. Once the collapses are done, the stage becomes
/// `finishing` while the worker catches up; cancelling `progress` stops both.
pub fn run_bounded<'a>(
    col: &mut EdgeCollapser,
    mesh: &'a TriMesh,
    target: usize,
    progress: &Progress,
    finishing: &'static str,
    mut on_step: impl FnMut(&EdgeCollapser, &Collapse) -> bool,
) -> Result<BoundedRun<'a>, Cancelled> {
    let diagonal = mesh.bounds().diagonal();
    // Waves sent; all sent once the collapses are done (the worker then reports progress).
    let sent = AtomicUsize::new(0);
    let all_sent = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let (to_worker, waves) = std::sync::mpsc::channel::<Wave>();
        let (sent, all_sent) = (&sent, &all_sent);
        let worker = scope.spawn(move || {
            // The original's search structures are built here, beside the first collapses.
            let original = Original::new(mesh);
            let mut bounds = StepBounds::new(&original, diagonal);
            for (k, wave) in waves.into_iter().enumerate() {
                if progress.is_cancelled() {
                    break;
                }
                bounds.wave(wave);
                if all_sent.load(Ordering::Acquire) {
                    progress.set_fraction((k + 1) as f32 / sent.load(Ordering::Relaxed) as f32);
                }
            }
            BoundedRun {
                bounds: bounds.error,
                original,
            }
        });
        let (mut sent_v, mut sent_t) = (0, 0);
        let mut send = move |col: &EdgeCollapser, collapses: Vec<Recorded>| {
            let (nv, nt) = (col.vertex_count() as u32, col.triangle_total() as u32);
            // A closed channel means the worker stopped: cancelled.
            let _ = to_worker.send(Wave {
                collapses,
                positions: (sent_v..nv).map(|v| col.position(v)).collect(),
                triangles: (sent_t..nt).map(|t| col.triangle(t)).collect(),
            });
            (sent_v, sent_t) = (nv, nt);
            sent.fetch_add(1, Ordering::Relaxed);
        };
        let mut producer: Vec<u32> = vec![INPUT; col.triangle_total()];
        let mut collapses = Vec::with_capacity(WAVE);
        let mut index = 0u32;
        while col.triangle_count() > target {
            let Some(c) = col.step() else { break };
            let mut kids: Vec<u32> = c
                .removed
                .iter()
                .map(|t| producer[*t as usize])
                .filter(|k| *k != INPUT)
                .collect();
            kids.sort_unstable();
            kids.dedup();
            producer.resize(col.triangle_total(), INPUT);
            for t in &c.added {
                producer[*t as usize] = index;
            }
            index += 1;
            let stopped = !on_step(col, &c);
            collapses.push(Recorded {
                removed: c.removed,
                added: c.added,
                kids,
            });
            if collapses.len() == WAVE {
                send(
                    col,
                    std::mem::replace(&mut collapses, Vec::with_capacity(WAVE)),
                );
            }
            if stopped || progress.is_cancelled() {
                break;
            }
        }
        let cancelled = progress.is_cancelled();
        if !cancelled {
            send(col, collapses);
            progress.stage(finishing);
            all_sent.store(true, Ordering::Release);
        }
        drop(send);
        let run = worker
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p));
        progress.check()?;
        Ok(run)
    })
}

/// The bounding worker's state: its own copy of the collapser's geometry,
/// the attribution of the original triangles and the bounds found so far.
struct StepBounds<'a> {
    original: &'a MeshDistance<'a>,
    projection: &'a Projection<'a>,
    opts: BoundOptions,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Nearest original distance (and triangle) of every vertex.
    nearest: Vec<(f32, u32)>,
    /// The original's side of every triangle's bound.
    attribution: Attribution<'a>,
    /// Per collapse: the largest exact distance found under it, and its bound.
    floor: Vec<f32>,
    error: Vec<f32>,
}

impl<'a> StepBounds<'a> {
    fn new(original: &'a Original<'a>, diagonal: f32) -> Self {
        Self {
            original: original.distance(),
            projection: original.projection(),
            // Looser than the simplifier's certificate (there are ~3 bounds per
            // collapse): still a true upper bound, within 25% of the lower one or 8 splits.
            opts: BoundOptions {
                rel_tol: 0.25,
                max_splits: 8,
                ..BoundOptions::for_diagonal(diagonal)
            },
            positions: Vec::new(),
            triangles: Vec::new(),
            nearest: Vec::new(),
            attribution: Attribution::new(original.mesh()),
            floor: Vec::new(),
            error: Vec::new(),
        }
    }

    /// Bounds one wave's collapses.
    fn wave(&mut self, wave: Wave) {
        let first = self.positions.len();
        self.positions.extend(wave.positions);
        let nearest: Vec<(f32, u32)> = self.positions[first..]
            .par_iter()
            .map(|p| self.original.nearest(*p))
            .collect();
        self.nearest.extend(nearest);
        self.triangles.extend(wave.triangles);
        self.attribution.grow(self.triangles.len());
        let c0 = self.error.len();
        self.floor.resize(c0 + wave.collapses.len(), 0.0);
        self.error.resize(c0 + wave.collapses.len(), 0.0);
        // A collapse's pieces come from triangles of earlier collapses: the
        // collapses of one level (their dependencies in earlier levels) hand
        // over their pieces at the same time.
        let mut level = vec![0u32; wave.collapses.len()];
        for (i, c) in wave.collapses.iter().enumerate() {
            level[i] = c
                .kids
                .iter()
                .filter(|k| **k as usize >= c0)
                .map(|k| level[*k as usize - c0] + 1)
                .max()
                .unwrap_or(0);
        }
        let mut order: Vec<usize> = (0..level.len()).collect();
        order.sort_by_key(|i| level[*i]);
        for same in order.chunk_by(|a, b| level[*a] == level[*b]) {
            let mut handovers: Vec<(usize, Handover)> = same
                .iter()
                .map(|i| (*i, self.attribution.take(&wave.collapses[*i].removed)))
                .collect();
            let this = &*self;
            let floors: Vec<f32> = handovers
                .par_iter_mut()
                .map(|(i, handover)| {
                    let c = &wave.collapses[*i];
                    // Exact distances bound each triangle's error from below,
                    // and a collapse's bound is at least its dependencies'
                    // (final from earlier waves): the attribution need not
                    // refine below that.
                    let floor = c
                        .kids
                        .iter()
                        .map(|k| this.floor[*k as usize])
                        .chain(c.added.iter().map(|t| this.low(*t)))
                        .fold(this.kids_error(c), f32::max);
                    let made: Vec<[Vec3; 3]> = c
                        .added
                        .iter()
                        .map(|t| this.triangles[*t as usize].map(|v| this.positions[v as usize]))
                        .collect();
                    let tolerance = (this.opts.rel_tol, this.opts.abs_tol, floor);
                    this.attribution.hand_over(handover, &made, tolerance);
                    floor
                })
                .collect();
            for ((i, handover), floor) in handovers.into_iter().zip(floors) {
                let c = &wave.collapses[i];
                self.attribution.give(handover, &c.added);
                self.floor[c0 + i] = c.added.iter().map(|t| self.low(*t)).fold(floor, f32::max);
            }
        }
        // A triangle's refinement stops at what cannot raise its collapse's
        // bound: the floor, or the bound of a dependency from an earlier wave.
        let jobs: Vec<(u32, f32)> = wave
            .collapses
            .iter()
            .enumerate()
            .flat_map(|(i, c)| {
                let below = self.kids_error(c).max(self.floor[c0 + i]);
                c.added.iter().map(move |t| (*t, below))
            })
            .collect();
        let tri_error: Vec<f32> = jobs
            .par_iter()
            .map(|&(t, below)| self.triangle_bound(t, below))
            .collect();
        let mut errors = tri_error.into_iter();
        for (i, c) in wave.collapses.iter().enumerate() {
            let own = errors.by_ref().take(c.added.len()).fold(0.0, f32::max);
            self.error[c0 + i] = own.max(self.kids_error(c));
        }
    }

    fn kids_error(&self, c: &Recorded) -> f32 {
        c.kids
            .iter()
            .map(|k| self.error[*k as usize])
            .fold(0.0, f32::max)
    }

    /// The largest exact distance known on triangle `t`: its vertices' and its originals'.
    fn low(&self, t: u32) -> f32 {
        self.triangles[t as usize]
            .iter()
            .map(|v| self.nearest[*v as usize].0)
            .fold(self.attribution.forward(t), f32::max)
    }

    /// Both directions of triangle `t`'s bound, refined no further than `below`.
    fn triangle_bound(&self, t: u32, below: f32) -> f32 {
        let tri = self.triangles[t as usize];
        let p = tri.map(|v| self.positions[v as usize]);
        let at = tri.map(|v| self.nearest[v as usize]);
        let forward = self.attribution.forward(t);
        let enough = forward.max(below);
        let to = (self.original, Some(self.projection));
        let (reverse, _, _) = max_distance_bound(p, at, to, &self.opts, enough, 0.0);
        // f32 round-off of the coordinates (flat collapses bound to 0).
        let scale = p.iter().map(|v| v.abs().max_element()).fold(0.0, f32::max);
        reverse.max(forward) + 8.0 * f32::EPSILON * scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::{icosphere, torus};
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};
    use crate::simplify::CollapseOptions;

    /// The mesh after any step is within the largest bound of the collapses
    /// that made its triangles, measured by dense two-sided sampling; a
    /// bound is never below those it builds on; a run stopped by the caller
    /// bounds exactly the collapses it made; every bound is within 1.5× of
    /// the measurement (whole original triangles attributed to one new
    /// triangle were 10–14× on the finest steps).
    #[test]
    fn every_step_is_within_its_bounds() {
        let mut bumpy = icosphere(Vec3::ZERO, 1.0, 4);
        for p in &mut bumpy.positions {
            *p *= 1.0 + 0.15 * (5.0 * p.x).sin() * (4.0 * p.y).cos();
        }
        for mesh in [bumpy, torus(1.0, 0.3, 48, 16)] {
            let n = mesh.triangles.len();
            let mut col = EdgeCollapser::new(&mesh, CollapseOptions::default());
            // Per triangle id, the collapse that made it.
            let mut producer: Vec<u32> = vec![INPUT; n];
            let mut deps: Vec<Vec<u32>> = Vec::new();
            let mut snapshots = Vec::new();
            let marks = [n / 2, n / 5, n / 20, 60];
            let progress = Progress::new();
            let run = run_bounded(&mut col, &mesh, 0, &progress, "done", |col, c| {
                let mut kids: Vec<u32> = c.removed.iter().map(|t| producer[*t as usize]).collect();
                kids.retain(|k| *k != INPUT);
                deps.push(kids);
                producer.resize(col.triangle_total(), INPUT);
                for t in &c.added {
                    producer[*t as usize] = deps.len() as u32 - 1;
                }
                if marks.contains(&col.triangle_count())
                    || marks.iter().any(|m| col.triangle_count() + 1 == *m)
                {
                    let (out, ids) = col.mesh();
                    let made: Vec<u32> = ids.iter().map(|t| producer[*t as usize]).collect();
                    snapshots.push((out, made));
                }
                col.triangle_count() > 40
            })
            .unwrap();
            assert_eq!(run.bounds.len(), deps.len());
            assert!(col.triangle_count() <= 40 && col.triangle_count() >= 38);
            for (i, kids) in deps.iter().enumerate() {
                for k in kids {
                    assert!(run.bounds[i] >= run.bounds[*k as usize]);
                }
            }
            assert!(snapshots.len() >= 3, "{}", snapshots.len());
            let sampling = SamplingOptions {
                samples: 60_000,
                seed: 5,
            };
            for (out, made) in &snapshots {
                let bound = made
                    .iter()
                    .filter(|k| **k != INPUT)
                    .map(|k| run.bounds[*k as usize])
                    .fold(0.0, f32::max);
                let measured = hausdorff_mesh_mesh(&mesh, out, &sampling).two_sided();
                assert!(
                    measured <= bound,
                    "{} triangles: measured {measured} > bound {bound}",
                    out.triangles.len()
                );
                assert!(bound <= 1.5 * measured + 1e-4, "{bound} vs {measured}");
            }
        }
    }
}
